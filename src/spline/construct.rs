//! Level-0 construction: each element's 4x4x4 Bézier points as combinations of
//! control vertices (the rules of DESIGN.md, with boundary and sharp-feature rules).
//!
//! * body points (no index 0 or 3): the element's corners with weights
//!   (2/3, 1/3) per direction;
//! * points on an interior face / edge / vertex: the mean of the body points
//!   next to that position of every element sharing the face / edge / vertex;
//! * points on the boundary follow the same rules one dimension lower on the
//!   boundary quadrilaterals (quad "body points" with (2/3, 1/3) weights, means
//!   over the quads sharing a boundary edge or vertex), so the boundary surface
//!   of the spline depends on boundary vertices only;
//! * sharp edges use the curve rule ((2/3, 1/3) along the edge, (1, 4, 1)/6 at a
//!   vertex the sharp curve passes through) and sharp corners are interpolated.
//!
//! On a regular grid this is the uniform tricubic B-spline in the interior and,
//! at a flat boundary, the cubic B-spline with the "natural" end condition (the
//! boundary control points are interpolated in the normal direction).

use super::bernstein::bidx;
use super::topology::{vtk_of_bits, Topology, VertexKind, BITS_OF_VTK};
use super::SparseOp;

/// A sparse linear combination of control vertices.
type Combo = Vec<(u32, f64)>;

fn push_scaled(out: &mut Combo, src: &[(u32, f64)], s: f64) {
    for &(v, w) in src {
        out.push((v, w * s));
    }
}

/// Body point of element e next to its vertex v (8 weights).
fn body(topo: &Topology, e: u32, v: u32) -> [(u32, f64); 8] {
    let el = &topo.elements[e as usize];
    let n = el.iter().position(|&x| x == v).expect("vertex of element");
    let vb = BITS_OF_VTK[n];
    let mut out = [(0u32, 0.0); 8];
    for (c, o) in out.iter_mut().enumerate() {
        let cb = BITS_OF_VTK[c];
        let mut w = 1.0;
        for d in 0..3 {
            w *= if cb[d] == vb[d] { 2.0 / 3.0 } else { 1.0 / 3.0 };
        }
        *o = (el[c], w);
    }
    out
}

/// The combination for Bézier node (a, b, c) of root element e.
fn node_combo(topo: &Topology, e: u32, idx: [usize; 3]) -> Combo {
    let el = &topo.elements[e as usize];
    let vb = [(idx[0] >= 2) as usize, (idx[1] >= 2) as usize, (idx[2] >= 2) as usize];
    let v = el[vtk_of_bits(vb)];
    let on: Vec<usize> = (0..3).filter(|&d| idx[d] == 0 || idx[d] == 3).collect();
    let mut out: Combo = Vec::with_capacity(64);
    match on.len() {
        0 => push_scaled(&mut out, &body(topo, e, v), 1.0),
        1 => {
            let d = on[0];
            let s = (idx[d] == 3) as usize;
            let f = &topo.faces[topo.elem_faces[e as usize][d * 2 + s] as usize];
            if f.elems.len() == 2 {
                for &(g, _, _) in &f.elems {
                    push_scaled(&mut out, &body(topo, g, v), 0.5);
                }
            } else {
                let fi = topo.elem_faces[e as usize][d * 2 + s];
                let q = topo.face_bquad[fi as usize] as usize;
                push_scaled(&mut out, &topo.bquads[q].body_weights(v), 1.0);
            }
        }
        2 => {
            let d = (0..3).find(|x| !on.contains(x)).unwrap();
            let mut wb = vb;
            wb[d] = 1 - vb[d];
            let w = el[vtk_of_bits(wb)];
            let ed = topo.edge(v, w).expect("edge of element");
            if !ed.is_boundary() {
                let s = 1.0 / ed.elems.len() as f64;
                for &g in &ed.elems {
                    push_scaled(&mut out, &body(topo, g, v), s);
                }
            } else if ed.sharp {
                out.push((v, 2.0 / 3.0));
                out.push((w, 1.0 / 3.0));
            } else {
                let s = 1.0 / ed.bquads.len() as f64;
                for &q in &ed.bquads {
                    push_scaled(&mut out, &topo.bquads[q as usize].body_weights(v), s);
                }
            }
        }
        _ => match topo.vertex_kind[v as usize] {
            VertexKind::Interior => {
                let st = &topo.star[v as usize];
                let s = 1.0 / st.len() as f64;
                for &g in st {
                    push_scaled(&mut out, &body(topo, g, v), s);
                }
            }
            VertexKind::Smooth => {
                let qs = &topo.vertex_bquads[v as usize];
                let s = 1.0 / qs.len() as f64;
                for &q in qs {
                    push_scaled(&mut out, &topo.bquads[q as usize].body_weights(v), s);
                }
            }
            VertexKind::Crease(a, b) => {
                out.push((v, 4.0 / 6.0));
                out.push((a, 1.0 / 6.0));
                out.push((b, 1.0 / 6.0));
            }
            VertexKind::Corner => out.push((v, 1.0)),
        },
    }
    out
}

/// Basis ids (vertex ids, sorted) and extraction operator of root element e.
pub fn element_operator(topo: &Topology, e: u32) -> (Vec<u32>, SparseOp) {
    let mut cols: Vec<Combo> = Vec::with_capacity(64);
    for k in 0..4 {
        for j in 0..4 {
            for i in 0..4 {
                debug_assert_eq!(cols.len(), bidx(i, j, k));
                cols.push(node_combo(topo, e, [i, j, k]));
            }
        }
    }
    let mut ids: Vec<u32> = cols.iter().flat_map(|c| c.iter().map(|x| x.0)).collect();
    ids.sort_unstable();
    ids.dedup();
    let mut dense = vec![0.0; ids.len() * 64];
    for (k, c) in cols.iter().enumerate() {
        for &(v, w) in c {
            let r = ids.binary_search(&v).unwrap();
            dense[r * 64 + k] += w;
        }
    }
    let op = SparseOp::from_dense(&dense, ids.len());
    (ids, op)
}

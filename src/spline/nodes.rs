//! Canonical keys of Bézier node positions on the (unstructured) parameter
//! domain, so that the same position seen from different elements, possibly of
//! different root elements and levels, gets one key.
//!
//! Each root element's parameter cube is an integer grid of `R = 3 * 2^LMAX`
//! steps per direction; a leaf of level L spans `3 * 2^(LMAX-L)` steps and its
//! Bézier node (a, b, c) sits `a * 2^(LMAX-L)` steps from its origin. Positions
//! on a root vertex, edge or face are keyed by that entity with coordinates in a
//! frame that depends only on the vertex ids, never on the element.

use super::topology::{edge_local, face_corners_local, other_dims, vtk_of_bits, Topology, BITS_OF_VTK};

/// Deepest refinement level.
pub const LMAX: u8 = 10;
/// Grid steps per root element and direction.
pub const R: u32 = 3 << LMAX;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NodeKey {
    Vertex(u32),
    /// Edge (smaller vertex id, larger vertex id), position from the smaller one.
    Edge(u32, u32, u32),
    /// Face index, coordinates in the face's canonical frame.
    Face(u32, u32, u32),
    /// Root element, coordinates inside it.
    Cell(u32, [u32; 3]),
}

/// Canonical frame of a local face: origin corner (0..4 in the cyclic order of
/// `face_corners_local`) and direction (+1 / -1 = 3).
fn face_frame(c: [u32; 4]) -> (usize, usize) {
    let m = (0..4).min_by_key(|&i| c[i]).unwrap();
    let dir = if c[(m + 1) % 4] < c[(m + 3) % 4] { 1 } else { 3 };
    (m, dir)
}

const SQ: [[i64; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];

/// Key of the position p (grid units) of root element e.
pub fn key_of(topo: &Topology, e: u32, p: [u32; 3]) -> NodeKey {
    let el = &topo.elements[e as usize];
    let on: Vec<usize> = (0..3).filter(|&d| p[d] == 0 || p[d] == R).collect();
    match on.len() {
        0 => NodeKey::Cell(e, p),
        3 => {
            let b = [(p[0] == R) as usize, (p[1] == R) as usize, (p[2] == R) as usize];
            NodeKey::Vertex(el[vtk_of_bits(b)])
        }
        2 => {
            let d = (0..3).find(|d| !on.contains(d)).unwrap();
            let mut lo = [0usize; 3];
            for &o in &on {
                lo[o] = (p[o] == R) as usize;
            }
            let mut hi = lo;
            hi[d] = 1;
            let (a, b) = (el[vtk_of_bits(lo)], el[vtk_of_bits(hi)]);
            if a < b {
                NodeKey::Edge(a, b, p[d])
            } else {
                NodeKey::Edge(b, a, R - p[d])
            }
        }
        _ => {
            let d = on[0];
            let s = (p[d] == R) as usize;
            let fi = topo.elem_faces[e as usize][d * 2 + s];
            let lc = face_corners_local(d, s);
            let c = lc.map(|i| el[i]);
            let (m, dir) = face_frame(c);
            let [d1, d2] = other_dims(d);
            let r = R as i64;
            let q = [p[d1] as i64 - SQ[m][0] * r, p[d2] as i64 - SQ[m][1] * r];
            let es = [SQ[(m + dir) % 4][0] - SQ[m][0], SQ[(m + dir) % 4][1] - SQ[m][1]];
            let et = [SQ[(m + 4 - dir) % 4][0] - SQ[m][0], SQ[(m + 4 - dir) % 4][1] - SQ[m][1]];
            let s1 = q[0] * es[0] + q[1] * es[1];
            let t1 = q[0] * et[0] + q[1] * et[1];
            NodeKey::Face(fi, s1 as u32, t1 as u32)
        }
    }
}

/// Every (root element, position) at which the keyed position lies.
pub fn locate(topo: &Topology, key: NodeKey) -> Vec<(u32, [u32; 3])> {
    match key {
        NodeKey::Cell(e, p) => vec![(e, p)],
        NodeKey::Vertex(v) => topo.star[v as usize]
            .iter()
            .map(|&e| {
                let el = &topo.elements[e as usize];
                let n = el.iter().position(|&x| x == v).unwrap();
                let b = BITS_OF_VTK[n];
                (e, [b[0] as u32 * R, b[1] as u32 * R, b[2] as u32 * R])
            })
            .collect(),
        NodeKey::Edge(a, b, pos) => {
            let id = topo.edge_index[&(a, b)];
            let ed = &topo.edges[id as usize];
            ed.elems
                .iter()
                .map(|&e| {
                    let el = &topo.elements[e as usize];
                    let li = (0..12).find(|&i| topo.elem_edges[e as usize][i] == id).unwrap();
                    let d = li / 4;
                    let [d1, d2] = other_dims(d);
                    let (b1, b2) = ((li % 4) % 2, (li % 4) / 2);
                    let mut lo = [0usize; 3];
                    lo[d1] = b1;
                    lo[d2] = b2;
                    let mut p = [0u32; 3];
                    p[d1] = b1 as u32 * R;
                    p[d2] = b2 as u32 * R;
                    p[d] = if el[vtk_of_bits(lo)] == a { pos } else { R - pos };
                    (e, p)
                })
                .collect()
        }
        NodeKey::Face(fi, s1, t1) => topo.faces[fi as usize]
            .elems
            .iter()
            .map(|&(e, d, s)| {
                let (d, s) = (d as usize, s as usize);
                let el = &topo.elements[e as usize];
                let c = face_corners_local(d, s).map(|i| el[i]);
                let (m, dir) = face_frame(c);
                let r = R as i64;
                let es = [SQ[(m + dir) % 4][0] - SQ[m][0], SQ[(m + dir) % 4][1] - SQ[m][1]];
                let et = [SQ[(m + 4 - dir) % 4][0] - SQ[m][0], SQ[(m + 4 - dir) % 4][1] - SQ[m][1]];
                let q0 = SQ[m][0] * r + s1 as i64 * es[0] + t1 as i64 * et[0];
                let q1 = SQ[m][1] * r + s1 as i64 * es[1] + t1 as i64 * et[1];
                let [d1, d2] = other_dims(d);
                let mut p = [0u32; 3];
                p[d] = s as u32 * R;
                p[d1] = q0 as u32;
                p[d2] = q1 as u32;
                (e, p)
            })
            .collect(),
    }
}

/// Local edge index helper re-exported for callers that walk edges.
#[allow(dead_code)]
pub fn local_edge(d: usize, b1: usize, b2: usize) -> usize {
    edge_local(d, b1, b2)
}

/// Map a point given in root element `e`'s parameters (floating point, [0,1]^3) on the
/// shared face with root element `f` into `f`'s parameters. Used by continuity checks.
pub fn map_face_point(topo: &Topology, e: u32, p: [f64; 3], f: u32) -> Option<[f64; 3]> {
    // exact on the integer grid: scale, key, locate
    let scaled = p.map(|x| (x * R as f64).round().clamp(0.0, R as f64) as u32);
    let key = key_of(topo, e, scaled);
    locate(topo, key)
        .into_iter()
        .find(|&(g, _)| g == f)
        .map(|(_, q)| q.map(|x| x as f64 / R as f64))
}

//! Local 3-refinement of a voxel lattice's hex mesh with conforming transition
//! elements (docs/hex.md "Local refinement").
//!
//! The lattice nodes inside a box are marked. An edge is split in three when both
//! its ends are marked, so a lattice element has 0, 1, 2 (one edge), 4 (one face) or
//! 8 marked corners and takes one of four templates:
//! - 0 or 1 marked corner: kept as it is (no edge of it is split);
//! - 8: the 27 elements of the 3 x 3 x 3 split;
//! - 4 (a face): 13 elements, the marked face split 3 x 3, the opposite face whole;
//! - 2 (an edge): 5 elements, that edge split in three.
//!
//! Every face of every template is one of three patterns decided by the face's own
//! marked corners (whole; one edge split, with two inner nodes two thirds of the
//! way to the opposite edge; 3 x 3), so two elements that share a face agree on it
//! and the result is conforming. The inner nodes' places were chosen on a grid of
//! 24ths for the largest least plus mean scaled Jacobian on a unit lattice: the face
//! template's least is 0.50 (mean 0.63), the edge template's 0.58 (mean 0.66); the
//! side nodes at half height gave 0.31 and 0.43. The unit tests check this and
//! conformity.
//!
//! Coordinates are lattice units (one voxel = 1); template points lie on a grid of
//! twelfths, so shared nodes are found by their exact position.

use crate::geometry::vec3::{cross, dot, sub};
use std::collections::HashMap;

/// Template points in twelfths of a lattice cell.
type P = [i32; 3];

const THIRD: i32 = 4;
const ONE: i32 = 12;

/// The eight corners of a VTK hexahedron over the unit cell, in twelfths.
const CORNERS: [P; 8] = [[0, 0, 0], [ONE, 0, 0], [ONE, ONE, 0], [0, ONE, 0], [0, 0, ONE], [ONE, 0, ONE], [ONE, ONE, ONE], [0, ONE, ONE]];

/// The 27-element split.
fn full_template() -> Vec<[P; 8]> {
    let mut out = Vec::with_capacity(27);
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                out.push(CORNERS.map(|c| [i * THIRD + c[0] / 3, j * THIRD + c[1] / 3, k * THIRD + c[2] / 3]));
            }
        }
    }
    out
}

/// The face template: the face z = 0 split 3 x 3, the face z = 1 whole, each side face
/// with its bottom edge split in three and two inner nodes at two thirds of the height.
fn face_template() -> Vec<[P; 8]> {
    let g = |i: i32, j: i32| [i * THIRD, j * THIRD, 0];
    // the upper ends of the first layer, indexed like the 4 x 4 grid of the bottom face
    let u = |i: i32, j: i32| -> P {
        let side = |k: i32| k == 0 || k == 3;
        match (side(i), side(j)) {
            (true, true) => [i / 3 * ONE, j / 3 * ONE, ONE], // top corners
            (true, false) | (false, true) => [i * THIRD, j * THIRD, 2 * THIRD], // side-face nodes
            (false, false) => [i * THIRD, j * THIRD, THIRD], // inner nodes
        }
    };
    let mut out = Vec::with_capacity(13);
    for j in 0..3 {
        for i in 0..3 {
            out.push([g(i, j), g(i + 1, j), g(i + 1, j + 1), g(i, j + 1), u(i, j), u(i + 1, j), u(i + 1, j + 1), u(i, j + 1)]);
        }
    }
    let (a0, a1, c1, c0) = (u(1, 0), u(2, 0), u(1, 3), u(2, 3));
    let (d1, d0, b0, b1) = (u(0, 1), u(0, 2), u(3, 1), u(3, 2));
    let (p11, p21, p22, p12) = (u(1, 1), u(2, 1), u(2, 2), u(1, 2));
    let (t00, t10, t11, t01) = (u(0, 0), u(3, 0), u(3, 3), u(0, 3));
    out.push([a0, a1, p21, p11, t00, t10, b0, d1]);
    out.push([p12, p22, c0, c1, d0, b1, t11, t01]);
    out.push([p11, p21, p22, p12, d1, b0, b1, d0]);
    out.push([d1, b0, b1, d0, t00, t10, t11, t01]);
    out
}

/// The edge template: the edge y = z = 0 split in three; the faces z = 0 and y = 0
/// carry the one-edge pattern, the other four faces are whole.
fn edge_template() -> Vec<[P; 8]> {
    let b = |k: i32| [k * THIRD, 0, 0];
    let (i1, i2) = ([THIRD, 2 * THIRD, 0], [2 * THIRD, 2 * THIRD, 0]); // on z = 0
    let (j1, j2) = ([THIRD, 0, 2 * THIRD], [2 * THIRD, 0, 2 * THIRD]); // on y = 0
    let (t0, t1, u0, u1) = ([0, ONE, 0], [ONE, ONE, 0], [0, 0, ONE], [ONE, 0, ONE]);
    let (c0, c1) = ([0, ONE, ONE], [ONE, ONE, ONE]);
    let (p1, p2) = ([THIRD, 2 * THIRD, 2 * THIRD], [2 * THIRD, 2 * THIRD, 2 * THIRD]);
    vec![
        [b(0), b(1), i1, t0, u0, j1, p1, c0],
        [b(1), b(2), i2, i1, j1, j2, p2, p1],
        [b(2), b(3), t1, i2, j2, u1, c1, p2],
        [t0, i1, i2, t1, c0, p1, p2, c1],
        [u0, u1, j2, j1, c0, c1, p2, p1],
    ]
}

/// A symmetry of the unit cell: output axis a reads input axis `perm[a]`, mirrored when `flip[a]`.
#[derive(Clone, Copy)]
struct Sym {
    perm: [usize; 3],
    flip: [bool; 3],
}

impl Sym {
    fn apply(&self, p: P) -> P {
        std::array::from_fn(|a| if self.flip[a] { ONE - p[self.perm[a]] } else { p[self.perm[a]] })
    }

    fn all() -> Vec<Sym> {
        const PERMS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        let mut out = Vec::with_capacity(48);
        for perm in PERMS {
            for f in 0..8u8 {
                out.push(Sym { perm, flip: [f & 1 != 0, f & 2 != 0, f & 4 != 0] });
            }
        }
        out
    }
}

/// The result of a refinement ([`refine_boxes`], [`refine_marked`]): node positions in lattice units (the first nodes are
/// the input's, in its order) and elements in VTK order.
#[derive(Debug, Clone)]
pub struct Refined {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[u32; 8]>,
    /// Elements refined (27-split), and transition elements replaced by a template.
    pub split: usize,
    pub transitions: usize,
}

/// Refine the lattice elements whose corners lie in the box of lattice nodes
/// `lo..=hi` (inclusive, per axis) three times along each axis, with transition
/// elements around them. `nodes` are lattice coordinates; every element must be one
/// lattice cell in VTK order. (Test-only: the pipeline refines several boxes, [`refine_boxes`].)
#[cfg(test)]
pub fn refine_box(nodes: &[[u32; 3]], elements: &[[u32; 8]], lo: [u32; 3], hi: [u32; 3]) -> Refined {
    refine_boxes(nodes, elements, &[(lo, hi)])
}


/// Whether marked corners `m` (VTK order) are a pattern with a template: none, one,
/// the two ends of an edge, the four corners of a face, or all eight.
fn has_template(m: [bool; 8]) -> bool {
    let on: Vec<usize> = (0..8).filter(|&k| m[k]).collect();
    let corner = |k: usize| CORNERS[k];
    match on.len() {
        0 | 1 | 8 => true,
        2 => (0..3).filter(|&a| corner(on[0])[a] != corner(on[1])[a]).count() == 1,
        4 => (0..3).any(|a| on.iter().all(|&k| corner(k)[a] == corner(on[0])[a])),
        _ => false,
    }
}

/// The refinement of `refine_box` for the lattice nodes marked in `marked` (one flag per node):
/// first every element whose marked corners have no template gets all its corners
/// marked, until none is left (two boxes a cell apart are bridged there, not
/// merged into their bounding box); returns the refined mesh and how many nodes
/// that marked.
pub fn refine_marked(nodes: &[[u32; 3]], elements: &[[u32; 8]], mut marked: Vec<bool>) -> (Refined, usize) {
    let added = close_marks(elements, &mut marked);
    (refine_flags(nodes, elements, &marked), added)
}

/// The closure of [`refine_marked`]: every element whose marked corners have no
/// template gets all its corners marked, until none is left; returns how many
/// nodes that marked.
pub fn close_marks(elements: &[[u32; 8]], marked: &mut [bool]) -> usize {
    let mut added = 0;
    loop {
        let mut changed = false;
        for el in elements {
            let m = el.map(|v| marked[v as usize]);
            if !has_template(m) {
                for &v in el {
                    if !marked[v as usize] {
                        marked[v as usize] = true;
                        added += 1;
                    }
                }
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    added
}

/// Boxes of lattice nodes (inclusive) merged into their bounding boxes until every
/// two are at least two lattice steps apart along some axis: then no cell has
/// corners in two boxes, every cell's marked corners are a corner, an edge, a face
/// or all of one box's, and [`refine_marked`]'s closure has nothing to mark (which
/// around overlapping boxes can spread over a whole lattice plane: each corner it
/// marks past a box face gives the cells beside it five marked corners).
pub fn merge_boxes(boxes: &[([u32; 3], [u32; 3])]) -> Vec<([u32; 3], [u32; 3])> {
    let mut out: Vec<([u32; 3], [u32; 3])> = boxes.to_vec();
    loop {
        let mut merged = false;
        'pairs: for i in 0..out.len() {
            for j in i + 1..out.len() {
                let (a, b) = (out[i], out[j]);
                // apart when some axis has a gap of two or more lattice steps
                let apart = (0..3).any(|k| a.0[k] >= b.1[k] + 2 || b.0[k] >= a.1[k] + 2);
                if !apart {
                    out[i] = (std::array::from_fn(|k| a.0[k].min(b.0[k])), std::array::from_fn(|k| a.1[k].max(b.1[k])));
                    out.swap_remove(j);
                    merged = true;
                    break 'pairs;
                }
            }
        }
        if !merged {
            break;
        }
    }
    out.sort_unstable();
    out
}

/// Whether lattice node `p` lies in one of the boxes of lattice nodes (inclusive).
pub fn in_boxes(p: [u32; 3], boxes: &[([u32; 3], [u32; 3])]) -> bool {
    boxes.iter().any(|(lo, hi)| (0..3).all(|a| p[a] >= lo[a] && p[a] <= hi[a]))
}

/// The refinement of `refine_box` for several boxes (see [`refine_marked`]).
pub fn refine_boxes(nodes: &[[u32; 3]], elements: &[[u32; 8]], boxes: &[([u32; 3], [u32; 3])]) -> Refined {
    let marked = nodes.iter().map(|&p| in_boxes(p, boxes)).collect();
    refine_marked(nodes, elements, marked).0
}

/// Positions of a refinement's new nodes (`r.nodes[lattice.len()..]`, lattice
/// units) from those of the lattice's nodes (`pos`): each new node at the
/// trilinear map of the corners of a lattice cell that holds it (on a face or an
/// edge, any of the cells there). `cells` are the lattice's elements and
/// `cell_lattice` their lowest corners. Err names a node in no cell.
pub fn interpolate_new_nodes(r: &Refined, lattice: &[[u32; 3]], elements: &[[u32; 8]], cell_lattice: &[[u32; 3]], pos: &[[f64; 3]]) -> Result<Vec<[f64; 3]>, String> {
    let cell: HashMap<[u32; 3], usize> = cell_lattice.iter().enumerate().map(|(e, c)| (*c, e)).collect();
    let mut out = pos.to_vec();
    for x in &r.nodes[lattice.len()..] {
        let base = (0..8u32).find_map(|k| {
            let c: [u32; 3] = std::array::from_fn(|a| {
                let f = x[a].floor();
                (if k >> a & 1 == 1 && f == x[a] { f - 1.0 } else { f }).max(0.0) as u32
            });
            cell.get(&c).map(|&e| (c, e))
        });
        let Some((c, e)) = base else {
            return Err(format!("node {x:?} lies in no cell of the lattice"));
        };
        let mut p = [0.0; 3];
        for &v in &elements[e] {
            let o = lattice[v as usize];
            let w: f64 = (0..3).map(|a| if o[a] > c[a] { x[a] - c[a] as f64 } else { 1.0 - (x[a] - c[a] as f64) }).product();
            for a in 0..3 {
                p[a] += w * pos[v as usize][a];
            }
        }
        out.push(p);
    }
    Ok(out)
}

/// The refinement itself: every element's marked corners must have a template.
pub fn refine_flags(nodes: &[[u32; 3]], elements: &[[u32; 8]], flags: &[bool]) -> Refined {
    let marked = |v: u32| flags[v as usize];
    let syms = Sym::all();
    let templates: [(Vec<[P; 8]>, Vec<usize>); 3] = [
        (full_template(), (0..8).collect()),
        (face_template(), vec![0, 1, 2, 3]),
        (edge_template(), vec![0, 1]),
    ];
    let mut index: HashMap<[i64; 3], u32> = HashMap::with_capacity(nodes.len() * 2);
    let mut out_nodes: Vec<[f64; 3]> = Vec::with_capacity(nodes.len() * 2);
    for (i, p) in nodes.iter().enumerate() {
        index.insert(p.map(|c| c as i64 * ONE as i64), i as u32);
        out_nodes.push(p.map(|c| c as f64));
    }
    let mut out_elements = Vec::with_capacity(elements.len());
    let (mut split, mut transitions) = (0, 0);
    for el in elements {
        let base: [u32; 3] = std::array::from_fn(|a| el.iter().map(|&v| nodes[v as usize][a]).min().unwrap_or(0));
        // the element's marked corners as points of the unit cell
        let mut mk: Vec<P> = el
            .iter()
            .filter(|&&v| marked(v))
            .map(|&v| std::array::from_fn(|a| (nodes[v as usize][a] - base[a]) as i32 * ONE))
            .collect();
        let which = match mk.len() {
            8 => 0,
            4 => 1,
            2 => 2,
            _ => {
                out_elements.push(*el);
                continue;
            }
        };
        mk.sort_unstable();
        let (tmpl, refc) = &templates[which];
        // the symmetry taking the template's marked corners onto this element's
        let sym = syms.iter().find(|s| {
            let mut m: Vec<P> = refc.iter().map(|&c| s.apply(CORNERS[c])).collect();
            m.sort_unstable();
            m == mk
        });
        let Some(sym) = sym else {
            // two corners not on an edge, four not on a face: refine_marked closes
            // the marks so that this does not happen
            out_elements.push(*el);
            continue;
        };
        if which == 0 {
            split += 1;
        } else {
            transitions += 1;
        }
        for hex in tmpl {
            let pts = hex.map(|p| {
                let q = sym.apply(p);
                let key: [i64; 3] = std::array::from_fn(|a| base[a] as i64 * ONE as i64 + q[a] as i64);
                *index.entry(key).or_insert_with(|| {
                    out_nodes.push(key.map(|k| k as f64 / ONE as f64));
                    (out_nodes.len() - 1) as u32
                })
            });
            // a mirror turns the element inside out: read it from the other face
            let e = |k: usize| sub(out_nodes[pts[k] as usize], out_nodes[pts[0] as usize]);
            let det = dot(e(1), cross(e(3), e(4)));
            out_elements.push(if det > 0.0 { pts } else { [pts[4], pts[5], pts[6], pts[7], pts[0], pts[1], pts[2], pts[3]] });
        }
    }
    Refined { nodes: out_nodes, elements: out_elements, split, transitions }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex::quality::scaled_jacobian;
    use crate::hex::topology::{boundary_quads, hex_volume as volume};
    use crate::hex::HexMesh;

    fn lattice(n: u32) -> (Vec<[u32; 3]>, Vec<[u32; 8]>) {
        let id = |i: u32, j: u32, k: u32| (k * (n + 1) + j) * (n + 1) + i;
        let mut nodes = Vec::new();
        for k in 0..=n {
            for j in 0..=n {
                for i in 0..=n {
                    nodes.push([i, j, k]);
                }
            }
        }
        let mut els = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    els.push(CORNERS.map(|c| id(i + (c[0] / ONE) as u32, j + (c[1] / ONE) as u32, k + (c[2] / ONE) as u32)));
                }
            }
        }
        (nodes, els)
    }

    /// Faces used once are on the outside of the n-cell lattice, none is used
    /// more than twice (conforming).
    fn assert_conforming(r: &Refined, n: f64, what: &str) {
        let bq = boundary_quads(&HexMesh { nodes: r.nodes.clone(), elements: r.elements.clone() }).unwrap_or_else(|e| panic!("{what}: {e}"));
        for q in bq {
            let p = q.nodes.map(|i| r.nodes[i as usize]);
            assert!((0..3).any(|a| p.iter().all(|x| x[a] == 0.0) || p.iter().all(|x| x[a] == n)), "{what}: face {p:?} used once");
        }
    }

    #[test]
    fn templates_have_positive_scaled_jacobians() {
        for (name, t, least) in [("full", full_template(), 1.0), ("face", face_template(), 0.5), ("edge", edge_template(), 0.57)] {
            for hex in &t {
                let p = hex.map(|q| q.map(|c| c as f64 / ONE as f64));
                let sj = scaled_jacobian(&p);
                assert!(sj >= least - 1e-9, "{name}: {sj} {hex:?}");
            }
            let v: f64 = t.iter().map(|h| volume(&h.map(|q| q.map(|c| c as f64 / ONE as f64)))).sum();
            assert!((v - 1.0).abs() < 1e-12, "{name} fills the cell: {v}");
        }
    }

    #[test]
    fn a_refined_box_is_conforming_and_valid() {
        let (nodes, els) = lattice(5);
        for (lo, hi) in [([1, 1, 1], [3, 3, 3]), ([0, 0, 0], [2, 5, 1]), ([2, 2, 2], [2, 3, 4]), ([1, 2, 3], [4, 3, 5])] {
            let r = refine_box(&nodes, &els, lo, hi);
            // every face is used once (on the outside of the lattice) or twice
            assert_conforming(&r, 5.0, &format!("box {lo:?}-{hi:?}"));
            let mut vol = 0.0;
            for el in &r.elements {
                let p = el.map(|i| r.nodes[i as usize]);
                assert!(scaled_jacobian(&p) > 0.49, "box {lo:?}-{hi:?}: {p:?}");
                vol += volume(&p);
            }
            assert!((vol - 125.0).abs() < 1e-9, "{vol}");
            let inside: u32 = (0..3).map(|a| hi[a] - lo[a]).product();
            assert_eq!(r.split as u32, inside, "box {lo:?}-{hi:?}");
        }
    }

    #[test]
    fn boxes_a_cell_apart_are_bridged_and_stay_conforming() {
        let (nodes, els) = lattice(6);
        // two boxes touching one cell diagonally, and a third far away: the cells
        // between the first two get all their corners marked, the rest is as marked
        for boxes in [vec![([0, 0, 0], [1, 1, 1]), ([2, 2, 2], [3, 3, 3]), ([5, 0, 5], [6, 1, 6])], vec![([0, 0, 0], [2, 1, 1]), ([1, 2, 0], [2, 3, 1])], vec![([1, 1, 1], [2, 2, 2]), ([3, 1, 1], [4, 2, 2])]] {
            let r = refine_boxes(&nodes, &els, &boxes);
            assert_conforming(&r, 6.0, &format!("{boxes:?}"));
            assert!(r.elements.iter().all(|el| scaled_jacobian(&el.map(|i| r.nodes[i as usize])) > 0.49));
            let vol: f64 = r.elements.iter().map(|el| volume(&el.map(|i| r.nodes[i as usize]))).sum();
            assert!((vol - 216.0).abs() < 1e-9, "{vol}");
            // far less than the bounding box of the boxes (6 x 6 x 6 cells)
            assert!(r.split < 100, "{boxes:?}: {} split", r.split);
        }
        let marked: Vec<bool> = nodes.iter().map(|p| *p == [1, 1, 1] || *p == [2, 2, 2]).collect();
        let (_, added) = refine_marked(&nodes, &els, marked);
        assert_eq!(added, 6, "the cell between two diagonal nodes");
    }

    #[test]
    fn merged_boxes_are_apart_and_need_no_closure() {
        let (nodes, els) = lattice(8);
        // two overlapping, one touching them, two a step apart; the first three
        // and the last two become one box each
        let boxes = [([1, 1, 1], [2, 2, 2]), ([2, 2, 1], [3, 3, 2]), ([3, 1, 1], [4, 2, 2]), ([6, 6, 6], [7, 7, 7]), ([4, 4, 4], [5, 5, 5])];
        let m = merge_boxes(&boxes);
        assert_eq!(m, vec![([1, 1, 1], [4, 3, 2]), ([4, 4, 4], [7, 7, 7])]);
        for b in &boxes {
            assert!(m.iter().any(|(lo, hi)| (0..3).all(|a| lo[a] <= b.0[a] && b.1[a] <= hi[a])), "{b:?} in a merged box");
        }
        let marked: Vec<bool> = nodes.iter().map(|&p| in_boxes(p, &m)).collect();
        let (r, added) = refine_marked(&nodes, &els, marked);
        assert_eq!(added, 0, "every cell's marks have a template");
        assert_conforming(&r, 8.0, "merged");
        assert_eq!(r.split, 3 * 2 * 1 + 27);
        // unmerged, the closure spreads past the boxes' bounding box
        let marked: Vec<bool> = nodes.iter().map(|&p| in_boxes(p, &boxes)).collect();
        assert!(refine_marked(&nodes, &els, marked).1 > 0);
    }
}

//! The polycube's boundary faces: maximal connected planar regions of boundary quads
//! with the same outward axis direction and the same plane, with their boundary
//! loops, corners (points where three or more faces meet) and edges (the straight
//! runs between corners where two faces meet). Positions are in the normalised
//! frame of the context (the occupied cells' box, longest edge 2, centred).

use crate::context::{context_frame, Context};
use crate::error::{Error, Result};
use crate::polycube::assembly::boundary;
use crate::geometry::StableHashMap;
use std::collections::BTreeSet;

/// Axis-direction code of a face: 0..6 = +X, -X, +Y, -Y, +Z, -Z.
pub type Dir = u8;

/// Name of a direction code ("+X" .. "-Z").
pub fn dir_name(d: Dir) -> &'static str {
    ["+X", "-X", "+Y", "-Y", "+Z", "-Z"][d as usize % 6]
}

/// Unit outward normal of a direction code.
pub fn dir_normal(d: Dir) -> [f64; 3] {
    let mut n = [0.0; 3];
    n[d as usize / 2] = if d % 2 == 0 { 1.0 } else { -1.0 };
    n
}

/// Coordinates of a point in a face's plane, oriented so that a loop that runs
/// counter-clockwise seen from outside has positive signed area.
pub fn plane_coords(d: Dir, p: [f64; 3]) -> [f64; 2] {
    let a = d as usize / 2;
    let (u, w) = ((a + 1) % 3, (a + 2) % 3);
    if d % 2 == 0 {
        [p[u], p[w]]
    } else {
        [p[w], p[u]]
    }
}

/// One boundary face of the polycube.
#[derive(Debug, Clone)]
pub struct PolyFace {
    /// Outward axis direction.
    pub dir: Dir,
    /// Coordinate of the face's plane along its axis (normalised frame).
    pub plane: f64,
    /// The boundary quads of the face (indices into [`PolycubeFaces::quads`]).
    pub quads: Vec<usize>,
    /// Boundary loops as vertex ids, counter-clockwise seen from outside; the outer
    /// loop first, then the holes (clockwise seen from outside has negative area:
    /// holes are stored in their own traversal order, which is clockwise).
    pub loops: Vec<Vec<usize>>,
    /// Corners on the face's loops (ids into [`PolycubeFaces::corners`]), in loop order.
    pub corners: Vec<usize>,
    /// Edges on the face's boundary (ids into [`PolycubeFaces::edges`]).
    pub edges: Vec<usize>,
    /// Face area (normalised units).
    pub area: f64,
}

/// A polycube corner: a boundary vertex where three or more faces meet.
#[derive(Debug, Clone)]
pub struct PolyCorner {
    pub vertex: usize,
    pub position: [f64; 3],
    /// The faces that meet there, sorted.
    pub faces: Vec<usize>,
}

/// A polycube edge: the straight run between two corners where two faces meet.
#[derive(Debug, Clone)]
pub struct PolyEdge {
    /// The two faces, sorted.
    pub faces: [usize; 2],
    /// The end corners (ids into [`PolycubeFaces::corners`]).
    pub corners: [usize; 2],
    /// End positions (normalised frame).
    pub ends: [[f64; 3]; 2],
}

/// The face structure of a polycube's boundary.
#[derive(Debug, Clone)]
pub struct PolycubeFaces {
    /// Boundary lattice vertices (normalised frame).
    pub vertices: Vec<[f64; 3]>,
    /// Boundary quads (vertex ids, counter-clockwise seen from outside) and their direction.
    pub quads: Vec<([u32; 4], Dir)>,
    pub faces: Vec<PolyFace>,
    pub corners: Vec<PolyCorner>,
    pub edges: Vec<PolyEdge>,
    /// Pairs of faces that share an edge (smaller id first).
    pub adjacency: BTreeSet<(usize, usize)>,
}

impl PolycubeFaces {
    /// A readable name of face `f`: its direction, its plane and, where several
    /// faces share the direction, which one it is (e.g. "+Z at z=1.00").
    pub fn name(&self, f: usize) -> String {
        let face = &self.faces[f];
        let axis = ["x", "y", "z"][face.dir as usize / 2];
        let same = self.faces.iter().filter(|g| g.dir == face.dir && (g.plane - face.plane).abs() < 1e-9).count();
        let mut s = format!("{} at {axis}={:.2}", dir_name(face.dir), face.plane);
        if same > 1 {
            let k = self.faces[..f].iter().filter(|g| g.dir == face.dir && (g.plane - face.plane).abs() < 1e-9).count();
            s.push_str(&format!(" (part {})", k + 1));
        }
        s
    }

    /// Faces that share a direction code.
    pub fn faces_with_dir(&self, d: Dir) -> impl Iterator<Item = usize> + '_ {
        (0..self.faces.len()).filter(move |&f| self.faces[f].dir == d)
    }

    /// Distance from `p` to face `f` (to the union of its quads).
    pub fn distance(&self, f: usize, p: [f64; 3]) -> f64 {
        self.faces[f]
            .quads
            .iter()
            .map(|&q| {
                let vs = self.quads[q].0.map(|i| self.vertices[i as usize]);
                let mut d2 = 0.0;
                for a in 0..3 {
                    let lo = vs.iter().map(|v| v[a]).fold(f64::INFINITY, f64::min);
                    let hi = vs.iter().map(|v| v[a]).fold(f64::NEG_INFINITY, f64::max);
                    let e = if p[a] < lo { lo - p[a] } else if p[a] > hi { p[a] - hi } else { 0.0 };
                    d2 += e * e;
                }
                d2
            })
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }

    /// Is `p` on a polycube edge (within `tol`)?
    pub fn on_edge(&self, p: [f64; 3], tol: f64) -> bool {
        self.edges.iter().any(|e| segment_distance(p, e.ends[0], e.ends[1]) <= tol)
    }
}

fn segment_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    use crate::geometry::vec3::*;
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 { (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    norm(sub(p, add(a, scale(ab, t))))
}

/// The boundary faces of the context's polycube (see the module docs).
pub fn polycube_faces(ctx: &Context) -> Result<PolycubeFaces> {
    let frame = context_frame(ctx).ok_or_else(|| Error::InvalidContext("the context has no occupied cell".into()))?;
    let qm = boundary(&ctx.assemble());
    let vertices: Vec<[f64; 3]> = qm.vertices.iter().map(|&p| frame.to_normalised(p)).collect();
    let quads: Vec<([u32; 4], Dir)> = qm.quads.iter().zip(&qm.quad_voxel).map(|(q, (_, d))| (*q, *d)).collect();
    // plane key in sub-voxel units
    let plane_key = |q: &([u32; 4], Dir)| -> (Dir, i64) {
        let a = q.1 as usize / 2;
        (q.1, (qm.vertices[q.0[0] as usize][a] * 3.0).round() as i64)
    };
    // directed edge -> quad
    let mut directed: StableHashMap<(u32, u32), usize> = StableHashMap::default();
    for (i, q) in quads.iter().enumerate() {
        for k in 0..4 {
            directed.insert((q.0[k], q.0[(k + 1) % 4]), i);
        }
    }
    // union of quads across shared edges within one plane and direction
    let mut parent: Vec<usize> = (0..quads.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for (i, q) in quads.iter().enumerate() {
        for k in 0..4 {
            if let Some(&j) = directed.get(&(q.0[(k + 1) % 4], q.0[k])) {
                if plane_key(&quads[j]) == plane_key(q) {
                    let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                    parent[a] = b;
                }
            }
        }
    }
    let mut face_of_root: StableHashMap<usize, usize> = StableHashMap::default();
    let mut quad_face = vec![0usize; quads.len()];
    let mut faces: Vec<PolyFace> = Vec::new();
    for i in 0..quads.len() {
        let r = find(&mut parent, i);
        let f = *face_of_root.entry(r).or_insert_with(|| {
            let a = quads[i].1 as usize / 2;
            faces.push(PolyFace {
                dir: quads[i].1,
                plane: vertices[quads[i].0[0] as usize][a],
                quads: Vec::new(),
                loops: Vec::new(),
                corners: Vec::new(),
                edges: Vec::new(),
                area: 0.0,
            });
            faces.len() - 1
        });
        quad_face[i] = f;
        faces[f].quads.push(i);
    }
    for (f, face) in faces.iter_mut().enumerate() {
        face.loops = face_loops(&quads, &quad_face, &directed, f, face);
        let areas: Vec<f64> = face.loops.iter().map(|l| loop_area(face.dir, l, &vertices)).collect();
        let outer = (0..areas.len()).max_by(|&a, &b| areas[a].total_cmp(&areas[b])).unwrap_or(0);
        face.loops.swap(0, outer);
        face.area = areas.iter().sum();
    }
    // the faces around each vertex
    let mut vertex_faces: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); vertices.len()];
    for (i, q) in quads.iter().enumerate() {
        for v in q.0 {
            vertex_faces[v as usize].insert(quad_face[i]);
        }
    }
    let mut corner_of: StableHashMap<usize, usize> = StableHashMap::default();
    let mut corners: Vec<PolyCorner> = Vec::new();
    for (v, fs) in vertex_faces.iter().enumerate() {
        if fs.len() >= 3 {
            corner_of.insert(v, corners.len());
            corners.push(PolyCorner { vertex: v, position: vertices[v], faces: fs.iter().copied().collect() });
        }
    }
    let mut edges: Vec<PolyEdge> = Vec::new();
    let mut adjacency = BTreeSet::new();
    for f in 0..faces.len() {
        let loops = faces[f].loops.clone();
        for l in &loops {
            let cs: Vec<usize> = (0..l.len()).filter(|&k| corner_of.contains_key(&l[k])).collect();
            if cs.is_empty() {
                return Err(Error::InvalidContext(format!(
                    "face {} of the polycube has a boundary loop without a corner",
                    dir_name(faces[f].dir)
                )));
            }
            for (ci, &k0) in cs.iter().enumerate() {
                let k1 = cs[(ci + 1) % cs.len()];
                let (a, b) = (l[k0], l[(k0 + 1) % l.len()]);
                // the face across the first step of the run
                let g = directed.get(&(b as u32, a as u32)).map(|&j| quad_face[j]).unwrap_or(f);
                faces[f].corners.push(corner_of[&a]);
                if g == f {
                    continue;
                }
                adjacency.insert((f.min(g), f.max(g)));
                if f < g {
                    let (c0, c1) = (corner_of[&l[k0]], corner_of[&l[k1]]);
                    edges.push(PolyEdge { faces: [f, g], corners: [c0, c1], ends: [vertices[l[k0]], vertices[l[k1]]] });
                }
            }
        }
    }
    for (e, edge) in edges.iter().enumerate() {
        faces[edge.faces[0]].edges.push(e);
        faces[edge.faces[1]].edges.push(e);
    }
    Ok(PolycubeFaces { vertices, quads, faces, corners, edges, adjacency })
}

/// The boundary loops of face `f`: its directed quad edges whose reverse is not in the face.
fn face_loops(
    quads: &[([u32; 4], Dir)],
    quad_face: &[usize],
    directed: &StableHashMap<(u32, u32), usize>,
    f: usize,
    face: &PolyFace,
) -> Vec<Vec<usize>> {
    let mut next: StableHashMap<u32, Vec<u32>> = StableHashMap::default();
    for &q in &face.quads {
        let vs = quads[q].0;
        for k in 0..4 {
            let (a, b) = (vs[k], vs[(k + 1) % 4]);
            let inside = directed.get(&(b, a)).is_some_and(|&j| quad_face[j] == f);
            if !inside {
                next.entry(a).or_default().push(b);
            }
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut loops = Vec::new();
    for s in starts {
        while next.get(&s).is_some_and(|v| !v.is_empty()) {
            let mut l = vec![s as usize];
            let mut cur = s;
            loop {
                let Some(n) = next.get_mut(&cur).and_then(|v| v.pop()) else { break };
                if n == s {
                    break;
                }
                l.push(n as usize);
                cur = n;
            }
            loops.push(l);
        }
    }
    loops
}

/// Signed area of a loop in the face's plane coordinates.
fn loop_area(d: Dir, l: &[usize], vertices: &[[f64; 3]]) -> f64 {
    let mut a = 0.0;
    for k in 0..l.len() {
        let p = plane_coords(d, vertices[l[k]]);
        let q = plane_coords(d, vertices[l[(k + 1) % l.len()]]);
        a += p[0] * q[1] - p[1] * q[0];
    }
    a / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_has_six_faces_eight_corners_twelve_edges() {
        let pf = polycube_faces(&Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap()).unwrap();
        assert_eq!((pf.faces.len(), pf.corners.len(), pf.edges.len(), pf.adjacency.len()), (6, 8, 12, 12));
        for f in &pf.faces {
            assert_eq!(f.loops.len(), 1);
            assert_eq!(f.corners.len(), 4);
            assert!((f.area - 4.0).abs() < 1e-9);
        }
    }

    #[test]
    fn a_through_hole_cube_has_ten_faces_and_two_annuli() {
        let pf = polycube_faces(&Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()).unwrap();
        assert_eq!(pf.faces.len(), 10);
        assert_eq!(pf.corners.len(), 16);
        assert_eq!(pf.edges.len(), 24);
        let annuli = pf.faces.iter().filter(|f| f.loops.len() == 2).count();
        assert_eq!(annuli, 2);
        // Euler characteristic of the torus: V - E + F over corners, edges, faces with
        // one cut per annulus (an annulus counts as a face with Euler characteristic 0)
        let chi: i64 = pf.corners.len() as i64 - pf.edges.len() as i64
            + pf.faces.iter().map(|f| 2 - f.loops.len() as i64).sum::<i64>();
        assert_eq!(chi, 0);
    }

    #[test]
    fn an_l_shape_has_l_shaped_faces() {
        let pf = polycube_faces(&Context::parse("cube,cube,0,cube,0,0,0,0,0,0,0,0").unwrap()).unwrap();
        assert_eq!(pf.faces.len(), 8);
        let six = pf.faces.iter().filter(|f| f.corners.len() == 6).count();
        assert_eq!(six, 2);
    }
}

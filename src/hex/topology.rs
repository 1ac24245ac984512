//! Connectivity of an all-hex mesh: faces, boundary quads, edges, node rings.

use super::HexMesh;
use std::collections::HashMap;

/// The six faces of a VTK hexahedron, each counter-clockwise seen from outside.
pub const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// The twelve edges of a VTK hexahedron.
pub const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// A boundary quad: nodes counter-clockwise seen from outside, with its element and local face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoundaryQuad {
    pub nodes: [u32; 4],
    pub element: u32,
    pub face: u8,
}

fn face_key(f: [u32; 4]) -> [u32; 4] {
    let mut k = f;
    k.sort_unstable();
    k
}

/// Faces used by exactly one element, oriented outward. Faces used by more than two
/// elements (a non-conforming or non-manifold mesh) are reported as an error string.
pub fn boundary_quads(m: &HexMesh) -> Result<Vec<BoundaryQuad>, String> {
    let mut count: HashMap<[u32; 4], (u32, BoundaryQuad)> = HashMap::with_capacity(m.elements.len() * 3);
    for (e, el) in m.elements.iter().enumerate() {
        for (f, lf) in HEX_FACES.iter().enumerate() {
            let nodes = lf.map(|i| el[i]);
            let q = BoundaryQuad { nodes, element: e as u32, face: f as u8 };
            count.entry(face_key(nodes)).and_modify(|c| c.0 += 1).or_insert((1, q));
        }
    }
    if let Some((k, _)) = count.iter().find(|(_, c)| c.0 > 2) {
        return Err(format!("face {k:?} is shared by more than two elements"));
    }
    let mut out: Vec<BoundaryQuad> = count.into_values().filter(|c| c.0 == 1).map(|c| c.1).collect();
    out.sort_by_key(|q| (q.element, q.face));
    Ok(out)
}

/// Unique undirected edges (sorted node pairs) of the mesh.
pub fn edges(m: &HexMesh) -> Vec<[u32; 2]> {
    let mut v: Vec<[u32; 2]> = Vec::with_capacity(m.elements.len() * 3);
    for el in &m.elements {
        for e in HEX_EDGES {
            let (a, b) = (el[e[0]], el[e[1]]);
            v.push(if a < b { [a, b] } else { [b, a] });
        }
    }
    v.sort_unstable();
    v.dedup();
    v
}

/// Edges where the mesh is not a regular grid, which is where a TH-spline on it is
/// only C0: interior edges shared by other than four elements, and boundary edges
/// (on a boundary quad) shared by other than two.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct IrregularEdges {
    pub interior: usize,
    pub boundary: usize,
}

impl IrregularEdges {
    pub fn total(&self) -> usize {
        self.interior + self.boundary
    }
}

/// Count the irregular edges of a mesh (see [`IrregularEdges`]); an edge is on the
/// boundary when a boundary quad has it.
pub fn irregular_edges(m: &HexMesh) -> IrregularEdges {
    let key = |a: u32, b: u32| if a < b { [a, b] } else { [b, a] };
    let mut valence: HashMap<[u32; 2], u32> = HashMap::with_capacity(m.elements.len() * 3);
    for el in &m.elements {
        for e in HEX_EDGES {
            *valence.entry(key(el[e[0]], el[e[1]])).or_insert(0) += 1;
        }
    }
    let mut on_boundary: std::collections::HashSet<[u32; 2]> = std::collections::HashSet::new();
    if let Ok(quads) = boundary_quads(m) {
        for q in quads {
            for i in 0..4 {
                on_boundary.insert(key(q.nodes[i], q.nodes[(i + 1) % 4]));
            }
        }
    }
    let mut out = IrregularEdges::default();
    for (e, v) in valence {
        if on_boundary.contains(&e) {
            out.boundary += (v != 2) as usize;
        } else {
            out.interior += (v != 4) as usize;
        }
    }
    out
}

/// Compressed adjacency lists (CSR): `start[i]..start[i+1]` indexes `list`.
#[derive(Debug, Clone, Default)]
pub struct Csr {
    pub start: Vec<u32>,
    pub list: Vec<u32>,
}

impl Csr {
    pub fn of(&self, i: usize) -> &[u32] {
        &self.list[self.start[i] as usize..self.start[i + 1] as usize]
    }

    pub fn from_pairs(n: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Csr {
        let mut start = vec![0u32; n + 1];
        for (a, _) in pairs.clone() {
            start[a as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; start[n] as usize];
        for (a, b) in pairs {
            list[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
        }
        Csr { start, list }
    }
}

/// Node -> neighbouring nodes along mesh edges.
pub fn node_neighbours(n: usize, edges: &[[u32; 2]]) -> Csr {
    Csr::from_pairs(n, edges.iter().flat_map(|e| [(e[0], e[1]), (e[1], e[0])]))
}

/// Node -> incident elements.
pub fn node_elements(m: &HexMesh) -> Csr {
    Csr::from_pairs(
        m.nodes.len(),
        m.elements.iter().enumerate().flat_map(|(e, el)| el.iter().map(move |&v| (v, e as u32))),
    )
}

/// Signed volume of a hexahedron: 24 tetrahedra formed by the element centroid, each
/// face centroid and each face edge (faces counter-clockwise from outside, so a
/// positively oriented element has positive volume).
pub fn hex_volume(p: &[[f64; 3]; 8]) -> f64 {
    let triple = |u: [f64; 3], v: [f64; 3], w: [f64; 3]| {
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])
    };
    let mut c = [0.0; 3];
    for q in p {
        for a in 0..3 {
            c[a] += q[a] / 8.0;
        }
    }
    let mut v = 0.0;
    for f in HEX_FACES {
        let q = f.map(|i| p[i]);
        let fc: [f64; 3] = std::array::from_fn(|a| (q[0][a] + q[1][a] + q[2][a] + q[3][a]) / 4.0 - c[a]);
        for k in 0..4 {
            let u: [f64; 3] = std::array::from_fn(|a| q[k][a] - c[a]);
            let w: [f64; 3] = std::array::from_fn(|a| q[(k + 1) % 4][a] - c[a]);
            v += triple(u, w, fc) / 6.0;
        }
    }
    v
}

/// Total signed volume of a hex mesh.
pub fn mesh_volume(m: &HexMesh) -> f64 {
    (0..m.elements.len()).map(|e| hex_volume(&m.element_corners(e))).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_cube_faces_volume() {
        let m = HexMesh::unit_cube();
        assert!((mesh_volume(&m) - 1.0).abs() < 1e-14);
        let b = boundary_quads(&m).unwrap();
        assert_eq!(b.len(), 6);
        // each face's normal points away from the centre
        for q in b {
            let p = q.nodes.map(|i| m.nodes[i as usize]);
            let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let e2 = [p[3][0] - p[0][0], p[3][1] - p[0][1], p[3][2] - p[0][2]];
            let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
            let fc = (0..4).fold([0.0; 3], |a, k| [a[0] + p[k][0] / 4.0, a[1] + p[k][1] / 4.0, a[2] + p[k][2] / 4.0]);
            let d = [fc[0] - 0.5, fc[1] - 0.5, fc[2] - 0.5];
            assert!(n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0);
        }
        assert_eq!(edges(&m).len(), 12);
    }

    /// An n x n x n grid of unit hexes.
    fn grid(n: usize) -> HexMesh {
        let id = |i: usize, j: usize, k: usize| (i + (n + 1) * (j + (n + 1) * k)) as u32;
        let mut nodes = Vec::new();
        for k in 0..=n {
            for j in 0..=n {
                for i in 0..=n {
                    nodes.push([i as f64, j as f64, k as f64]);
                }
            }
        }
        let mut elements = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    elements.push([id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k), id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)]);
                }
            }
        }
        HexMesh { nodes, elements }
    }

    #[test]
    fn a_grid_is_irregular_only_along_the_box_edges() {
        for n in [1, 2, 4] {
            let r = irregular_edges(&grid(n));
            // the twelve box edges' n segments each lie on one element
            assert_eq!(r, IrregularEdges { interior: 0, boundary: 12 * n }, "n = {n}");
        }
        // an L of three grids' worth: the re-entrant edge lies on three elements
        let mut m = grid(2);
        m.elements.retain(|el| {
            let c = el.iter().fold([0.0; 3], |a, &v| {
                let p = m.nodes[v as usize];
                [a[0] + p[0] / 8.0, a[1] + p[1] / 8.0, a[2] + p[2] / 8.0]
            });
            !(c[0] > 1.0 && c[1] > 1.0)
        });
        let r = irregular_edges(&m);
        // vertical: the plan's five convex corners (valence 1) and its re-entrant
        // corner (valence 3), two segments each; horizontal: the plan's 8-unit outline
        // on the top and the bottom face (valence 1); the rest lie on two or four
        assert_eq!(r, IrregularEdges { interior: 0, boundary: 5 * 2 + 2 + 2 * 8 });
    }
}

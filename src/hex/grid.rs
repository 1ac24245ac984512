//! The parametric domain: the polycube's sub-voxel hexes (level 0) and their
//! uniform octree subdivisions (level L: every sub-voxel split into 2^L per edge).
//!
//! Nodes live on a regular lattice of spacing 1 / (3 * 2^L) grid units; a node is
//! created only where an element uses it. Elements are in VTK_HEXAHEDRON order and
//! positively oriented (right-handed), so in grid units every element has scaled
//! Jacobian exactly 1.

use super::topology::HEX_FACES;
use super::HexMesh;
use crate::polycube::primitive::SUB;
use crate::geometry::VoxelGrid;
use std::collections::HashMap;

/// A polycube hex mesh at one subdivision level, with its lattice bookkeeping.
#[derive(Debug, Clone)]
pub struct LatticeHex {
    pub level: u32,
    /// Elements per sub-voxel edge (2^level).
    pub subdiv: usize,
    /// Node lattice dimensions (points per axis).
    pub dims: [usize; 3],
    /// Nodes in grid units (one cell = 1).
    pub mesh: HexMesh,
    /// Lattice coordinates of each node.
    pub node_lattice: Vec<[u32; 3]>,
    /// Lattice coordinates of each element's lowest corner.
    pub elem_lattice: Vec<[u32; 3]>,
    /// Dense lattice point -> node id (u32::MAX where unused).
    index: Vec<u32>,
}

impl LatticeHex {
    /// Node id at lattice point p, if used.
    pub fn node_at(&self, p: [usize; 3]) -> Option<u32> {
        if p[0] >= self.dims[0] || p[1] >= self.dims[1] || p[2] >= self.dims[2] {
            return None;
        }
        let id = self.index[p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])];
        (id != u32::MAX).then_some(id)
    }
}

/// Build the level-`level` hex mesh of a voxel set (sub-voxels of the polycube lattice).
pub fn lattice_hex(g: &VoxelGrid, level: u32) -> LatticeHex {
    let n = 1usize << level;
    let [vx, vy, vz] = g.dims;
    let dims = [vx * n + 1, vy * n + 1, vz * n + 1];
    let mut index = vec![u32::MAX; dims[0] * dims[1] * dims[2]];
    let h = 1.0 / (SUB * n) as f64;
    let mut mesh = HexMesh::default();
    let mut node_lattice = Vec::new();
    let mut elem_lattice = Vec::new();
    let lid = |p: [usize; 3]| p[0] + dims[0] * (p[1] + dims[1] * p[2]);
    for z in 0..vz * n {
        for y in 0..vy * n {
            for x in 0..vx * n {
                if !g.occ[g.idx(x / n, y / n, z / n)] {
                    continue;
                }
                let corners = [
                    [x, y, z],
                    [x + 1, y, z],
                    [x + 1, y + 1, z],
                    [x, y + 1, z],
                    [x, y, z + 1],
                    [x + 1, y, z + 1],
                    [x + 1, y + 1, z + 1],
                    [x, y + 1, z + 1],
                ];
                let mut e = [0u32; 8];
                for (k, c) in corners.iter().enumerate() {
                    let i = lid(*c);
                    if index[i] == u32::MAX {
                        index[i] = mesh.nodes.len() as u32;
                        mesh.nodes.push([c[0] as f64 * h, c[1] as f64 * h, c[2] as f64 * h]);
                        node_lattice.push([c[0] as u32, c[1] as u32, c[2] as u32]);
                    }
                    e[k] = index[i];
                }
                mesh.elements.push(e);
                elem_lattice.push([x as u32, y as u32, z as u32]);
            }
        }
    }
    LatticeHex { level, subdiv: n, dims, mesh, node_lattice, elem_lattice, index }
}

/// Positions for the nodes of `fine` (level L + 1) interpolated from the positions
/// `coarse_pos` of the nodes of `coarse` (level L): a fine node at an even lattice
/// point is the coarse node; otherwise the average of the coarse nodes at the floor
/// and ceiling of its odd coordinates (the trilinear midpoint of an edge, face or element).
pub fn prolong(coarse: &LatticeHex, coarse_pos: &[[f64; 3]], fine: &LatticeHex) -> Vec<[f64; 3]> {
    assert_eq!(fine.subdiv, 2 * coarse.subdiv);
    fine.node_lattice
        .iter()
        .map(|l| {
            let mut lo = [0usize; 3];
            let mut odd = [false; 3];
            for a in 0..3 {
                lo[a] = l[a] as usize / 2;
                odd[a] = l[a] % 2 == 1;
            }
            let mut acc = [0.0; 3];
            let mut cnt = 0.0;
            for dz in 0..=(odd[2] as usize) {
                for dy in 0..=(odd[1] as usize) {
                    for dx in 0..=(odd[0] as usize) {
                        let p = [lo[0] + dx, lo[1] + dy, lo[2] + dz];
                        let id = coarse.node_at(p).expect("a fine node lies in the closure of a coarse element") as usize;
                        for a in 0..3 {
                            acc[a] += coarse_pos[id][a];
                        }
                        cnt += 1.0;
                    }
                }
            }
            acc.map(|v| v / cnt)
        })
        .collect()
}

/// Bitmask of outward axis directions (+X,-X,+Y,-Y,+Z,-Z -> bits 0..5) of the boundary
/// quads around each node of a lattice hex mesh (0 for interior nodes).
pub fn normal_masks(h: &LatticeHex) -> Vec<u8> {
    let mut mask = vec![0u8; h.mesh.nodes.len()];
    let faces = boundary_faces_lattice(h);
    for (q, dir) in faces {
        for v in q {
            mask[v as usize] |= 1 << dir;
        }
    }
    mask
}

/// Boundary quads of a lattice hex mesh with their outward axis direction code.
pub fn boundary_faces_lattice(h: &LatticeHex) -> Vec<([u32; 4], u8)> {
    // face f of an element at lattice cell c is on the boundary when the element
    // across it does not exist
    let mut occupied: HashMap<[u32; 3], ()> = HashMap::with_capacity(h.elem_lattice.len());
    for c in &h.elem_lattice {
        occupied.insert(*c, ());
    }
    // HEX_FACES order: -Z, +Z, -Y, +X, +Y, -X
    const DIRS: [(i64, i64, i64, u8); 6] = [(0, 0, -1, 5), (0, 0, 1, 4), (0, -1, 0, 3), (1, 0, 0, 0), (0, 1, 0, 2), (-1, 0, 0, 1)];
    let mut out = Vec::new();
    for (e, c) in h.elem_lattice.iter().enumerate() {
        for (f, d) in DIRS.iter().enumerate() {
            let n = [c[0] as i64 + d.0, c[1] as i64 + d.1, c[2] as i64 + d.2];
            let inside = n.iter().all(|&v| v >= 0) && occupied.contains_key(&[n[0] as u32, n[1] as u32, n[2] as u32]);
            if !inside {
                let el = h.mesh.elements[e];
                out.push((HEX_FACES[f].map(|i| el[i]), d.3));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex::quality::element_qualities;
    use crate::polycube::{assemble, Primitive};

    #[test]
    fn thc_levels_and_prolongation() {
        let mut l = [Primitive::Null; 12];
        l[0] = Primitive::ThcZ;
        let g = assemble(&l);
        let h0 = lattice_hex(&g, 0);
        assert_eq!(h0.mesh.elements.len(), 24);
        assert_eq!(h0.mesh.nodes.len(), 64);
        let h1 = lattice_hex(&g, 1);
        assert_eq!(h1.mesh.elements.len(), 24 * 8);
        assert!(element_qualities(&h1.mesh).iter().all(|&q| (q - 1.0).abs() < 1e-12));
        let p = prolong(&h0, &h0.mesh.nodes, &h1);
        for (a, b) in p.iter().zip(&h1.mesh.nodes) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-12);
            }
        }
    }
}

//! The boundary of a voxel set as a quad mesh.

use super::{NB6, SUB};
use crate::geometry::VoxelGrid;
use crate::mesh::TriMesh;

/// A quad surface: vertices in grid units (one cell = 1), quads counter-clockwise seen from outside.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuadMesh {
    pub vertices: Vec<[f64; 3]>,
    pub quads: Vec<[u32; 4]>,
    /// For each quad: the voxel it bounds (lattice coordinates) and its outward axis (0..6: +X,-X,+Y,-Y,+Z,-Z).
    pub quad_voxel: Vec<([usize; 3], u8)>,
}

impl QuadMesh {
    /// Split every quad into two triangles (diagonal 0-2).
    pub fn to_trimesh(&self) -> TriMesh {
        let mut triangles = Vec::with_capacity(self.quads.len() * 2);
        for q in &self.quads {
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
        TriMesh { vertices: self.vertices.clone(), triangles }
    }

    pub fn area(&self) -> f64 {
        // Every quad is an axis-aligned square of the lattice.
        let s = self
            .quads
            .first()
            .map(|q| {
                let a = self.vertices[q[0] as usize];
                let b = self.vertices[q[1] as usize];
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .unwrap_or(0.0);
        self.quads.len() as f64 * s * s
    }
}

/// The boundary of a voxel set as a quad mesh in grid units (voxel edge = 1/3).
/// Lattice points are shared, so the mesh is closed wherever the solid is; at a
/// non-manifold edge or vertex it is non-manifold (as the solid is).
pub fn boundary(g: &VoxelGrid) -> QuadMesh {
    let [nx, ny, nz] = g.dims;
    let (lx, ly) = (nx + 1, ny + 1);
    let mut id = vec![u32::MAX; (nx + 1) * (ny + 1) * (nz + 1)];
    let mut m = QuadMesh::default();
    let h = 1.0 / SUB as f64;
    let mut vid = |m: &mut QuadMesh, p: [usize; 3]| -> u32 {
        let k = p[0] + lx * (p[1] + ly * p[2]);
        if id[k] == u32::MAX {
            id[k] = m.vertices.len() as u32;
            m.vertices.push([p[0] as f64 * h, p[1] as f64 * h, p[2] as f64 * h]);
        }
        id[k]
    };
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if !g.occ[g.idx(x, y, z)] {
                    continue;
                }
                for (dir, d) in NB6.iter().enumerate() {
                    if g.at(x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]) {
                        continue;
                    }
                    let ax = dir / 2;
                    let positive = dir % 2 == 0;
                    let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
                    let mut base = [x, y, z];
                    if positive {
                        base[ax] += 1;
                    }
                    let corner = |du: usize, dw: usize| {
                        let mut p = base;
                        p[u] += du;
                        p[w] += dw;
                        p
                    };
                    let cs = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                    let mut q = [0u32; 4];
                    for (t, c) in cs.iter().enumerate() {
                        q[t] = vid(&mut m, *c);
                    }
                    if !positive {
                        q = [q[0], q[3], q[2], q[1]];
                    }
                    m.quads.push(q);
                    m.quad_voxel.push(([x, y, z], dir as u8));
                }
            }
        }
    }
    m
}

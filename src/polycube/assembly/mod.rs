//! Assembly of a labelled grid into a solid on the 9x6x6 sub-voxel lattice, its
//! boundary surface, its genus and its validity. Everything here is computed from
//! the voxel set, never from label arithmetic.
//!
//! By concern: the assembly and the cell-level measures (here), the validity
//! check ([`check`], validity.rs), the Euler characteristics from the lattice
//! points' 2x2x2 patterns ([`euler_solid`], [`boundary_euler`], euler.rs) and the
//! boundary quad mesh ([`boundary`], boundary.rs).

mod boundary;
mod euler;
mod validity;

pub use boundary::{boundary, QuadMesh};
pub use euler::{boundary_euler, euler_solid};
pub use validity::{check, Validity};

use super::primitive::{cell_coords, cell_index, Primitive, GRID, LATTICE, NUM_CELLS, SUB};
use crate::geometry::VoxelGrid;

/// The six face neighbours of a voxel.
const NB6: [[i64; 3]; 6] = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];

/// The voxel set of a labelling of the 12 cells on the 9x6x6 lattice.
pub fn assemble(labels: &[Primitive; NUM_CELLS]) -> VoxelGrid {
    let mut g = VoxelGrid::empty(LATTICE);
    for (n, p) in labels.iter().enumerate() {
        if *p == Primitive::Null {
            continue;
        }
        let [i, j, k] = cell_coords(n);
        let sv = p.subvoxels();
        for c in 0..SUB {
            for b in 0..SUB {
                for a in 0..SUB {
                    if sv[a + 3 * b + 9 * c] {
                        let ix = g.idx(i * SUB + a, j * SUB + b, k * SUB + c);
                        g.occ[ix] = true;
                    }
                }
            }
        }
    }
    g
}

/// One primitive alone on a 3x3x3 lattice (the template solid of TCV).
pub fn single(p: Primitive) -> VoxelGrid {
    VoxelGrid { dims: [SUB; 3], occ: p.subvoxels().to_vec() }
}

/// The faces of cell `n` that touch an occupied neighbour in `labels`: bit 2a is the
/// face at the low end of axis a, bit 2a + 1 the face at its high end.
pub fn shared_faces(labels: &[Primitive; NUM_CELLS], n: usize) -> u8 {
    let c = cell_coords(n);
    let mut bits = 0u8;
    for a in 0..3 {
        for (side, step) in [(0u8, -1i64), (1, 1)] {
            let mut d = c.map(|v| v as i64);
            d[a] += step;
            let limit = GRID[a] as i64;
            if d[a] >= 0 && d[a] < limit {
                let m = cell_index(d[0] as usize, d[1] as usize, d[2] as usize);
                if labels[m] != Primitive::Null {
                    bits |= 1 << (2 * a as u8 + side);
                }
            }
        }
    }
    bits
}

/// Bounding box of the occupied cells of a labelling, in grid units: (min, max) corners.
pub fn occupied_cell_box(labels: &[Primitive; NUM_CELLS]) -> Option<([usize; 3], [usize; 3])> {
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    let mut any = false;
    for (n, p) in labels.iter().enumerate() {
        if *p == Primitive::Null {
            continue;
        }
        any = true;
        let c = cell_coords(n);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a] + 1);
        }
    }
    any.then_some((lo, hi))
}

/// The occupied voxels cropped to their bounding box, as (dims, sorted coordinates).
fn cropped(g: &VoxelGrid) -> ([usize; 3], Vec<[usize; 3]>) {
    let pts: Vec<[usize; 3]> = (0..g.occ.len()).filter(|&i| g.occ[i]).map(|i| g.coords(i)).collect();
    if pts.is_empty() {
        return ([0; 3], pts);
    }
    let lo: [usize; 3] = std::array::from_fn(|a| pts.iter().map(|p| p[a]).min().unwrap());
    let hi: [usize; 3] = std::array::from_fn(|a| pts.iter().map(|p| p[a]).max().unwrap());
    let mut v: Vec<[usize; 3]> = pts.iter().map(|p| std::array::from_fn(|a| p[a] - lo[a])).collect();
    v.sort();
    (std::array::from_fn(|a| hi[a] - lo[a] + 1), v)
}

/// Are two voxel sets the same solid up to a translation and one of the 24 rotations
/// of the cube? (The criterion for "the same polycube" in the context search.)
pub fn congruent(a: &VoxelGrid, b: &VoxelGrid) -> bool {
    let (da, va) = cropped(a);
    let (db, vb) = cropped(b);
    if va.len() != vb.len() {
        return false;
    }
    for r in super::orientation::rotations() {
        // rotate a's cropped coordinates: new axis k = sign * old axis perm[k]
        let dims: [usize; 3] = std::array::from_fn(|k| da[r.perm[k]]);
        if dims != db {
            continue;
        }
        let mut w: Vec<[usize; 3]> = va
            .iter()
            .map(|p| {
                std::array::from_fn(|k| {
                    let v = p[r.perm[k]];
                    if r.sign[k] > 0 {
                        v
                    } else {
                        da[r.perm[k]] - 1 - v
                    }
                })
            })
            .collect();
        w.sort();
        if w == vb {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests;

//! The openings of a subregion, read from its voxels: which axes a hole runs
//! through and on which faces a blind hole opens. They say which labels a
//! subregion's shape can carry without comparing it with a template, so that a
//! label is not lost because the cell is twisted, tapered, rounded or holed off
//! its centre (the in-context fit scores such a cell against a template it no
//! longer lines up with).
//!
//! Along each axis, every column of voxels through the subregion is read once:
//! it is *through* when it holds no solid voxel, and its *depth* from each end is
//! the number of empty voxels before the first solid one. In the plane across the
//! axis, the 4-connected components of columns that do not touch the plane's
//! border are enclosed by solid:
//! - an enclosed component of through columns is a hole through the subregion
//!   along the axis (THC);
//! - an enclosed component of columns at least [`PIT_DEPTH`] of the axis deep
//!   from one end, none of them through, is a blind hole opening on that face
//!   (BHC of that face).
//!
//! Columns outside a rounded or tapered outline are through as well, but they
//! reach the border, so they never count. A component of fewer than
//! [`MIN_COLUMNS`] columns is noise.

use crate::geometry::VoxelGrid;
use crate::polycube::Primitive;
use serde::Serialize;

/// Depth (fraction of the subregion along the axis) from which an enclosed
/// column is a blind hole: the primitives' blind holes are 2/3 deep, and a
/// neighbour's hole reaching over a split that is off by a tenth of a cell stays
/// below it.
pub const PIT_DEPTH: f64 = 0.3;

/// Fewest columns of an enclosed component that counts as an opening.
pub const MIN_COLUMNS: usize = 2;

/// The openings of one subregion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Openings {
    /// A hole runs through along X, Y, Z.
    pub through: [bool; 3],
    /// A blind hole opens on the low / high face of X, Y, Z.
    pub blind: [[bool; 2]; 3],
}

impl Openings {
    /// The subregion shows no opening at all.
    pub fn none(&self) -> bool {
        !self.through.iter().any(|&t| t) && !self.blind.iter().flatten().any(|&b| b)
    }

    /// The label's hole (or its absence, for the cube) is among the openings.
    pub fn carries(&self, p: Primitive) -> bool {
        match p.hole() {
            None => p == Primitive::Cube && self.none(),
            Some((a, 0)) => self.through[a],
            Some((a, s)) => self.blind[a][usize::from(s > 0)],
        }
    }
}

/// The openings of the solid voxels of `g` (the subregion alone).
pub fn openings(g: &VoxelGrid) -> Openings {
    let mut o = Openings::default();
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        let (na, nu, nv) = (g.dims[a], g.dims[u], g.dims[v]);
        if na == 0 || nu < 3 || nv < 3 {
            continue;
        }
        // depth from the low and the high end of every column (na when through)
        let mut depth = vec![[na; 2]; nu * nv];
        for iv in 0..nv {
            for iu in 0..nu {
                let solid = |k: usize| {
                    let mut c = [0usize; 3];
                    c[a] = k;
                    c[u] = iu;
                    c[v] = iv;
                    g.occ[g.idx(c[0], c[1], c[2])]
                };
                let d = &mut depth[iu + nu * iv];
                d[0] = (0..na).find(|&k| solid(k)).unwrap_or(na);
                d[1] = (0..na).rev().find(|&k| solid(k)).map_or(na, |k| na - 1 - k);
            }
        }
        let through: Vec<bool> = depth.iter().map(|d| d[0] == na).collect();
        o.through[a] = enclosed(&through, nu, nv).iter().any(|c| c.len() >= MIN_COLUMNS);
        let deep = ((PIT_DEPTH * na as f64).ceil() as usize).max(2);
        for s in 0..2 {
            let pit: Vec<bool> = depth.iter().map(|d| d[s] >= deep).collect();
            o.blind[a][s] = enclosed(&pit, nu, nv).iter().any(|c| c.len() >= MIN_COLUMNS && c.iter().all(|&i| !through[i]));
        }
    }
    o
}

/// The 4-connected components of the set cells of an `nu` x `nv` mask that touch
/// no border of the mask, each as its cell indices.
fn enclosed(mask: &[bool], nu: usize, nv: usize) -> Vec<Vec<usize>> {
    let mut seen = vec![false; mask.len()];
    let mut out = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut comp = vec![start];
        let mut open = false;
        let mut k = 0;
        while k < comp.len() {
            let i = comp[k];
            k += 1;
            let (iu, iv) = (i % nu, i / nu);
            if iu == 0 || iv == 0 || iu + 1 == nu || iv + 1 == nv {
                open = true;
            }
            let mut push = |j: usize| {
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    comp.push(j);
                }
            };
            if iu > 0 {
                push(i - 1);
            }
            if iu + 1 < nu {
                push(i + 1);
            }
            if iv > 0 {
                push(i - nu);
            }
            if iv + 1 < nv {
                push(i + nu);
            }
        }
        if !open {
            out.push(comp);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 9x9x9 cell with the primitive's sub-voxels removed (each sub-voxel 3^3 voxels).
    fn cell(p: Primitive) -> VoxelGrid {
        let mut g = VoxelGrid::empty([9, 9, 9]);
        for z in 0..9 {
            for y in 0..9 {
                for x in 0..9 {
                    let s = [x / 3, y / 3, z / 3];
                    let removed = match p.hole() {
                        None => false,
                        Some((a, dir)) => {
                            let (u, v) = ((a + 1) % 3, (a + 2) % 3);
                            s[u] == 1 && s[v] == 1 && (dir == 0 || s[a] == 1 || (dir > 0 && s[a] == 2) || (dir < 0 && s[a] == 0))
                        }
                    };
                    let i = g.idx(x, y, z);
                    g.occ[i] = !removed;
                }
            }
        }
        g
    }

    #[test]
    fn every_primitive_carries_its_own_label_and_no_other() {
        for p in Primitive::solids() {
            let o = openings(&cell(p));
            for q in Primitive::solids() {
                assert_eq!(o.carries(q), p == q, "{p} cell, label {q}: {o:?}");
            }
        }
    }

    #[test]
    fn a_round_outline_does_not_open_a_hole() {
        // a cylinder along Z with a small hole along Z: the empty corners reach the border
        let n = 16;
        let mut g = VoxelGrid::empty([n, n, n]);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let (dx, dy) = (x as f64 + 0.5 - 8.0, y as f64 + 0.5 - 8.0);
                    let r = (dx * dx + dy * dy).sqrt();
                    let i = g.idx(x, y, z);
                    g.occ[i] = r < 8.0 && r > 2.0;
                }
            }
        }
        let o = openings(&g);
        assert!(o.through[2] && !o.through[0] && !o.through[1], "{o:?}");
        assert!(o.carries(Primitive::ThcZ) && !o.carries(Primitive::Cube));
        assert!(!o.blind.iter().flatten().any(|&b| b), "{o:?}");
    }

    #[test]
    fn a_shallow_dent_is_no_blind_hole() {
        let mut g = cell(Primitive::Cube);
        for y in 3..6 {
            for x in 3..6 {
                let i = g.idx(x, y, 8);
                g.occ[i] = false; // one voxel of nine deep
            }
        }
        assert!(openings(&g).carries(Primitive::Cube));
    }
}

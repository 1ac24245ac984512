//! `hex.target_size` ([`crate::hex::HexOptions::target_size`], `sddpm run --size
//! H`): the hex stage's level and lattice from a target element size in model
//! units.
//!
//! * A polycube mesh at level L has E0 x 8^L elements, E0 the polycube's
//!   sub-voxels (level 0). The level is the one whose count is nearest (on a log
//!   scale) N = V / H^3, V the input's volume: elements of volume H^3, edges about
//!   H long for elements near cubes. Levels 0 to 6, and at most `max_elements`
//!   elements.
//! * The fallback's lattice has voxels of edge `longest bounding-box edge /
//!   resolution`: the resolution is that edge over H (2 to 192), with no finer
//!   lattice after it (the size is the caller's choice, not the quality goals'),
//!   and voxels no smaller than (V / `max_elements`)^(1/3).

use crate::context::Context;
use crate::hex::voxel::VOXEL_MAX_RESOLUTION;
use crate::hex::HexOptions;
use crate::mesh::TriMesh;

/// `o` with the level for a polycube of `context` meshing `mesh` fixed by
/// `o.target_size` (unchanged without one).
pub fn for_polycube(o: &HexOptions, context: &Context, mesh: &TriMesh) -> HexOptions {
    let mut o = o.clone();
    if let Some(h) = o.target_size {
        let e0 = context.assemble().count().max(1) as f64;
        let mut l = level_for(e0, mesh.signed_volume().abs(), h);
        // never past `max_elements` (the automatic level's cap too)
        while l > 0 && e0 * 8f64.powi(l as i32) > o.max_elements as f64 {
            l -= 1;
        }
        o.map.level = Some(l);
    }
    o
}

/// The level 0..=6 whose E0 x 8^L elements are nearest V / H^3 (log scale).
pub fn level_for(e0: f64, volume: f64, h: f64) -> u32 {
    let target = volume / (h * h * h);
    let l = (target / e0).log2() / 3.0;
    if l.is_finite() { l.round().clamp(0.0, crate::hex::options::MAX_LEVEL as f64) as u32 } else { 0 }
}

/// `o` with the fallback's first lattice set by `o.target_size` and no finer
/// lattice after it (unchanged without one).
pub fn for_lattice(o: &HexOptions, mesh: &TriMesh) -> HexOptions {
    let mut o = o.clone();
    if let Some(h) = o.target_size {
        // at most about `max_elements` voxels inside the input
        let (edge, volume) = (longest_edge(mesh), mesh.signed_volume().abs());
        let h_min = (volume / o.max_elements as f64).cbrt();
        o.fallback.resolution = resolution_for(edge, h.max(h_min));
        o.fallback.refinements = 0;
    }
    o
}

/// Voxels along an edge of `length` at voxel size `h` (2 to 192).
pub fn resolution_for(length: f64, h: f64) -> usize {
    let r = (length / h).round();
    if r.is_finite() { (r as usize).clamp(2, VOXEL_MAX_RESOLUTION) } else { 2 }
}

fn longest_edge(mesh: &TriMesh) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &mesh.vertices {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_and_resolutions_follow_the_size() {
        // a 2 x 2 x 2 cube meshed from one polycube cell (27 sub-voxels)
        assert_eq!(level_for(27.0, 8.0, 2.0 / 3.0), 0);
        assert_eq!(level_for(27.0, 8.0, 1.0 / 3.0), 1);
        assert_eq!(level_for(27.0, 8.0, 1.0 / 6.0), 2);
        assert_eq!(level_for(27.0, 8.0, 1e-6), 6);
        assert_eq!(level_for(27.0, 8.0, 100.0), 0);
        assert_eq!(resolution_for(10.0, 0.5), 20);
        assert_eq!(resolution_for(10.0, 100.0), 2);
        assert_eq!(resolution_for(10.0, 1e-6), VOXEL_MAX_RESOLUTION);
    }
}

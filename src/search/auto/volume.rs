//! The temporary volume of the aligned input and its subregions (step 1 of the
//! automated mode): the voxel volume, refined until it holds the surface's volume,
//! the subregions of a box split with their fill and genus, and the splitting
//! ratios an error message suggests.

use super::super::generate::PreparedInput;
use super::AutoOptions;
use crate::error::{Error, Result};
use crate::geometry::voxel::{betti, majority, voxelize, VoxelVolume};
use crate::geometry::{Aabb, VoxelGrid};
use crate::mesh::TriMesh;
use serde::Serialize;

/// The temporary volume of the aligned input, with the volume it is measured against.
pub(super) struct TemporaryVolume {
    pub vol: VoxelVolume,
    /// `vol`'s voxels majority-filtered ([`majority`]), computed once for every
    /// box: the subregions' genus is read from them (see [`subregions`]).
    pub clean: VoxelGrid,
    /// Voxels along the longest side.
    pub resolution: usize,
    /// The enclosed volume of the aligned input surface.
    pub surface_volume: f64,
    /// The aligned input's bounding box, which the boxes split.
    pub bb: Aabb,
}

/// The temporary volume of the aligned input; a part thinner than a voxel at the
/// finest resolution allowed is refused with the reason.
pub(super) fn measure(input: &PreparedInput, aopts: &AutoOptions) -> Result<TemporaryVolume> {
    let surface_volume = input.alignment.mesh.check().volume.abs();
    let (vol, resolution) = temporary_volume(&input.alignment.mesh, aopts.resolution, surface_volume)?;
    let bb = Aabb::of_points(&input.alignment.mesh.vertices);
    let ratio = vol.volume() / surface_volume.max(f64::MIN_POSITIVE);
    if !(THIN_PART_FRACTION..=1.0 / THIN_PART_FRACTION).contains(&ratio) {
        // The finest lattice still misses most of the solid, or a wall thinner than
        // a voxel fills whole voxels: the subregions' fills and genera would
        // describe the lattice, not the part. Say why instead.
        let e = bb.size();
        let (thin, long) = (e.iter().copied().fold(f64::INFINITY, f64::min), e.iter().copied().fold(0.0, f64::max));
        return Err(Error::VerificationFailed(format!(
            "automated mode: the temporary volume at {resolution} voxels along the longest side holds {:.3e} of the surface's volume {:.3e} ({:.1} %): the part is thinner than a voxel (thinnest bounding-box extent {:.3e}, {:.1e} of the longest {:.3e}), so its subregions cannot be measured; give a context (--labels) or constraints instead",
            vol.volume(),
            surface_volume,
            100.0 * ratio,
            thin,
            thin / long.max(f64::MIN_POSITIVE),
            long
        )));
    }
    let clean = majority(&vol.grid);
    Ok(TemporaryVolume { vol, clean, resolution, surface_volume, bb })
}

/// The temporary volume misses the surface's volume by at most this fraction, or
/// its resolution is doubled (the test meshes are within 5 % at 48 voxels; a thin
/// wall, like the 12:1 tube of trimesh_round at 48, holds no voxel centre at all).
pub const VOLUME_TOLERANCE: f64 = 0.1;
/// A temporary volume holding less than this fraction of the surface's volume, or
/// more than its inverse, at the finest resolution allowed means walls thinner
/// than a voxel: the automated mode refuses with the reason instead of measuring
/// subregions of a lattice that does not describe the part.
pub const THIN_PART_FRACTION: f64 = 0.5;
/// The doubling stops at this many voxels along the longest side ...
pub const MAX_RESOLUTION: usize = 384;
/// ... or at this many voxels in the bounding grid.
pub const MAX_VOXELS: usize = 4_000_000;

/// The voxel volume at `resolution`, refined by doubling while it misses the
/// surface volume by more than [`VOLUME_TOLERANCE`] (within [`MAX_RESOLUTION`] and
/// [`MAX_VOXELS`]); returns the volume and the resolution used.
pub(super) fn temporary_volume(mesh: &TriMesh, resolution: usize, surface_volume: f64) -> Result<(VoxelVolume, usize)> {
    let mut res = resolution;
    let mut vol = voxelize(mesh, res)?;
    let size = Aabb::of_points(&mesh.vertices).size();
    let longest = size[0].max(size[1]).max(size[2]);
    let voxels = |r: usize| -> f64 { size.iter().map(|s| (s / longest * r as f64).ceil().max(1.0)).product() };
    while (vol.volume() - surface_volume).abs() > VOLUME_TOLERANCE * surface_volume && res * 2 <= MAX_RESOLUTION && voxels(res * 2) <= MAX_VOXELS as f64 {
        res *= 2;
        vol = voxelize(mesh, res)?;
    }
    Ok((vol, res))
}

/// What the automated mode measured for one subregion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Subregion {
    /// Cell index of the subregion in the grid.
    pub cell: usize,
    /// Box in the aligned frame.
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// Fraction of the subregion box that is solid.
    pub fill: f64,
    /// Solid components (26-connected), sealed cavities, tunnels (genus).
    pub components: usize,
    pub cavities: usize,
    pub genus: i64,
    /// The subregion is (almost) empty: label null.
    pub empty: bool,
    /// Its through and blind holes, read from its voxels.
    pub openings: super::openings::Openings,
}

/// Split points of one axis from ratios (fractions summing to 1).
pub fn split_points(lo: f64, hi: f64, ratios: &[f64]) -> Vec<f64> {
    let total: f64 = ratios.iter().sum();
    let mut v = vec![lo];
    let mut acc = 0.0;
    for r in ratios {
        acc += r / total;
        v.push(lo + acc * (hi - lo));
    }
    *v.last_mut().unwrap() = hi;
    v
}

/// Analyse the subregions of a volume split at `xs`, `ys`, `zs` (split points along
/// each axis). The genus is read from `clean`, the volume's majority-filtered voxels:
/// surface noise leaves one-voxel bridges that count as tunnels (a noisy cube
/// measured genus 3). The fill and the openings come from the raw voxels (the
/// filter also opens a wall one voxel thin, like the ring around a small eye,
/// which an opening must keep).
pub fn subregions(vol: &VoxelVolume, clean: &VoxelGrid, xs: &[f64], ys: &[f64], zs: &[f64], min_fill: f64) -> Vec<Subregion> {
    let mut out = Vec::new();
    let [nx, ny, nz] = vol.grid.dims;
    for (k, zw) in zs.windows(2).enumerate() {
        for (j, yw) in ys.windows(2).enumerate() {
            for (i, xw) in xs.windows(2).enumerate() {
                let lo = [xw[0], yw[0], zw[0]];
                let hi = [xw[1], yw[1], zw[1]];
                let r = |a: usize, v: f64, n: usize| (((v - vol.lo[a]) / vol.h).round().max(0.0) as usize).min(n);
                let (x0, x1) = (r(0, lo[0], nx), r(0, hi[0], nx));
                let (y0, y1) = (r(1, lo[1], ny), r(1, hi[1], ny));
                let (z0, z1) = (r(2, lo[2], nz), r(2, hi[2], nz));
                let dims = [x1.saturating_sub(x0).max(1), y1.saturating_sub(y0).max(1), z1.saturating_sub(z0).max(1)];
                let mut g = VoxelGrid::empty(dims);
                let mut gc = VoxelGrid::empty(dims);
                for z in z0..z1 {
                    for y in y0..y1 {
                        for x in x0..x1 {
                            let v = vol.grid.occ[vol.grid.idx(x, y, z)];
                            let ix = g.idx(x - x0, y - y0, z - z0);
                            g.occ[ix] = v;
                            gc.occ[ix] = clean.occ[clean.idx(x, y, z)];
                        }
                    }
                }
                let fill = g.count() as f64 / g.occ.len() as f64;
                let (b0, b2, b1) = betti(&gc);
                out.push(Subregion {
                    cell: crate::polycube::cell_index(i, j, k),
                    lo,
                    hi,
                    fill,
                    components: b0,
                    cavities: b2,
                    genus: b1,
                    empty: fill < min_fill,
                    openings: super::openings::openings(&g),
                });
            }
        }
    }
    out
}

/// Ratios that split the solid where it is thinnest along X (a heuristic for the error message).
pub fn suggest_ratios(vol: &VoxelVolume, lo: [f64; 3], hi: [f64; 3]) -> String {
    let g = &vol.grid;
    let nx = g.dims[0];
    let mut col = vec![0usize; nx];
    for z in 0..g.dims[2] {
        for y in 0..g.dims[1] {
            for x in 0..nx {
                if g.occ[g.idx(x, y, z)] {
                    col[x] += 1;
                }
            }
        }
    }
    // two cuts at the thinnest slabs in the middle thirds
    let thin = |a: usize, b: usize| (a..b.max(a + 1)).min_by_key(|&i| col[i.min(nx - 1)]).unwrap_or(a);
    let c1 = thin(nx / 6, nx / 2);
    let c2 = thin(nx / 2, 5 * nx / 6);
    let w = hi[0] - lo[0];
    let x1 = ((c1 as f64 + 0.5) * vol.h + vol.lo[0] - lo[0]) / w;
    let x2 = ((c2 as f64 + 0.5) * vol.h + vol.lo[0] - lo[0]) / w;
    format!("{:.2},{:.2},{:.2}:1,1:1,1", x1, (x2 - x1).max(0.05), (1.0 - x2).max(0.05))
}

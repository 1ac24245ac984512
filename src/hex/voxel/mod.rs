//! Grid-based all-hex meshing: the fallback of the hex stage when every polycube
//! candidate's mesh keeps inverted elements.
//!
//! The input is filled on a regular voxel lattice in the working frame (the
//! voxelisation of the automated mode's temporary volume), the voxel set is made
//! well-composed (no two voxels that share only an edge or a vertex, so that its
//! boundary is a 2-manifold), and the resolution is doubled until the voxel solid
//! has the input's topology (one component, no cavity, the input's genus; a solid
//! in one piece with extra tunnels, where a wall thinner than a voxel passes
//! between the voxel centres, first gets the voxels that are mostly or partly
//! inside, [`crate::geometry::voxel::solid_fractions`]). The
//! voxels become the hex elements; their boundary nodes are pulled onto the input
//! surface in validity-preserving steps (as the polycube map's nodes are), and the
//! usual quality steps follow: pillowing (which gives every boundary element one
//! face on the surface, as the staircase leaves elements with two or three),
//! smoothing and optimisation.
//!
//! This is the classical grid-based method (octree / voxel meshing with a
//! boundary layer), not the polycube structure: its elements are not aligned
//! with the part's features and sharp edges are followed only as closely as the
//! element size allows. The main job uses it only when the polycube meshes fold,
//!
//! [`build_voxel_hex_mesh`] searches the lattices ([`lattices`]), meshes each
//! ([`mesh`], with the feature-sheet variants of [`sheets`]) and refines the best
//! locally when asked ([`local`]); [`composed`] makes a voxel set well-composed.

mod composed;
mod lattices;
mod local;
mod mesh;
mod sheets;
#[cfg(test)]
mod tests;

pub use composed::{make_well_composed, make_well_composed_where};

use crate::error::{check_progress, Error, Progress, Result, SubProgress};
use crate::hex::frames::working_frames;
use crate::hex::{Affine, HexOptions, HexResult};
use crate::mesh::TriMesh;
use lattices::{first_lattice, meshed, Search};
use std::time::Instant;

/// Lowest voxel resolution (voxels along the longest bounding-box edge) the
/// fallback tries; it doubles from there while the topology is wrong.
pub const VOXEL_START_RESOLUTION: usize = 24;
/// Highest voxel resolution the fallback tries.
pub const VOXEL_MAX_RESOLUTION: usize = 192;


/// The all-hex mesh of `surface` (mapped to user coordinates by `to_user`) from a
/// voxel lattice; `genus` is the input's. The first lattice is the coarsest from
/// `opts.fallback.resolution` (doubling) with the input's topology; while the mesh
/// misses `opts.goals`, up to `opts.fallback.refinements` finer lattices follow
/// (`Search::refine`); when the best meets every goal with room to spare and a
/// coarser lattice missed the distance goal, coarser resolutions predicted from
/// the two are meshed and kept when they meet every goal too
/// (`Search::coarser`); the kept lattice is meshed again with its planes on the
/// input's faces (`Search::planes_on_faces`) and refined locally when asked
/// (`Search::refine_locally`). The best mesh is returned (its details list
/// every lattice tried). Errors (MESHING_FAILED) when no resolution up to
/// [`VOXEL_MAX_RESOLUTION`] within `opts.max_elements` elements has the input's topology.
pub fn build_voxel_hex_mesh(surface: &TriMesh, to_user: &Affine, genus: i64, opts: &HexOptions, progress: &mut dyn Progress) -> Result<HexResult> {
    let t_all = Instant::now();
    if surface.triangles.is_empty() {
        return Err(Error::InvalidArgument("the input surface has no triangles".into()));
    }
    if surface.vertices.iter().flatten().any(|v| !v.is_finite()) || !to_user.is_finite() || to_user.inverse().is_none() {
        return Err(Error::InvalidArgument("non-finite coordinate or singular frame in the hex stage input".into()));
    }
    opts.validate()?;
    check_progress(progress, 0.0, "hex: voxel lattice")?;
    let (fr, _) = working_frames(surface, to_user, opts)?;
    let mut tried = Vec::new();
    let (lattice, res) = first_lattice(&fr, genus, opts, &mut tried)?;
    // the share of the progress range each mesh gets: the first and its refinements
    // (and the predicted coarser lattice)
    let share = 1.0 / (2 + opts.fallback.refinements) as f64;
    let mut sub = SubProgress { inner: progress, lo: 0.0, hi: share };
    let best = mesh::mesh_lattice(lattice, res, None, &fr, opts, t_all, &mut sub)?;
    let meshed = vec![meshed(res, &best)];
    let mut search = Search { fr: &fr, opts, genus, t_all, tried, meshed, best, best_res: res, share };
    search.refine(progress)?;
    search.coarser(progress)?;
    let planes = search.planes_on_faces(progress)?;
    let carve_failed = search.refine_locally(planes, progress)?;
    let Search { mut best, tried, meshed, .. } = search;
    if let Some(d) = best.lattice_mut() {
        d.resolutions_tried = Some(tried);
        d.lattices_meshed = Some(meshed);
        // local refinement rounds whose split voxels could not be voxelised again
        d.revoxelisation_skipped = (!carve_failed.is_empty()).then_some(carve_failed);
    }
    best.seconds_total = t_all.elapsed().as_secs_f64();
    check_progress(progress, 1.0, "hex: done")?;
    Ok(best)
}

//! Feature sheets: one sheet of hexahedra inserted under each surface patch of a
//! pillowed lattice mesh, so that its boundary can follow the input's sharp curves
//! where they run diagonally across the lattice.
//!
//! The boundary quads of a lattice mesh meet a sharp curve along a staircase path:
//! seen on one face of the curve, a quad at a convex step has two consecutive path
//! edges, and with its three path nodes on a straight curve it is flat (the
//! capture steps therefore leave such nodes off the curve, and the mesh rounds the
//! edge). Labelling every boundary quad with the input patch it lies on (patches:
//! the input's triangles split by its sharp curves) and inserting, under each
//! patch's quads, a sheet of hexahedra (the pillowing of that patch's layer
//! elements against the rest of the mesh) gives every node on the path between
//! two labels exactly one edge into each patch, like a pillow layer does for every
//! boundary node; the path's nodes then go onto the curve between the two patches
//! (or onto the feature corner where three labels meet) and are held there, and
//! the elements along the curve share its dihedral angle two by two.
//!
//! The node copies of a sheet are made per face-connected group of the patch's
//! elements around the node, so that patches touching only along an edge or at a
//! node still give a conforming mesh; the result is checked (every face on one or
//! two elements) and the step is undone when it is not.
//!
//! [`feature_sheets`] runs the parts in order: the patches ([`patches`]), the
//! quads' labels and the paths between them ([`labels`]), the sheets ([`insert`]),
//! the path nodes onto the curves and corners and the settling ([`place`]).

mod insert;
mod labels;
mod patches;
mod place;
#[cfg(test)]
mod tests;

use super::measure::summary;
use super::step::stage_report;
use super::untangle::smoothing;
use crate::error::{check_progress, Error, Progress, Result};
use crate::hex::options::QualityOptions;
use crate::hex::stages::{SheetsDetails, Stage, StageDetails, StageReport};
use crate::hex::surface::{edge_triangles, Surface};
use crate::hex::topology::boundary_quads;
use crate::hex::work::{mean_boundary_edge, Role, Work};
use std::time::Instant;

/// The sheets go under the quads within this many rings of a path (one ring:
/// hexgen_rod at 28 voxels 1,927 elements at 0.68 %; the whole patch: 2,495 at
/// 0.67 %; BENCHMARKS.md "Feature sheets").
pub(super) const SHEET_BAND: usize = 1;

/// Laplacian passes that give the sheets a thickness before the smoothing, over
/// the new nodes and the old ones within SETTLE_RING edges of a path (hexgen_hepta
/// at 12 voxels: 8 elements inverted after the smoothing with the new nodes only,
/// 1 with the first ring).
pub(super) const SETTLE_ITERATIONS: usize = 10;
pub(super) const SETTLE_RING: usize = 1;

/// How near its sharp curve or corner (in mean boundary edge lengths) a node where
/// two patch labels meet must be for the feature sheets to put it there.
pub const SHEET_REACH: f64 = 1.5;

/// What the feature sheets did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SheetReport {
    /// Input patches (triangles split by the sharp curves).
    pub patches: usize,
    /// Boundary quads whose label the clean-up changed (isolated quads and islands).
    pub labels_changed: usize,
    /// Patches that got a sheet (those whose quads border another label).
    pub sheets: usize,
    /// Boundary nodes where labels meet (the paths), and those put on a feature
    /// curve / a feature corner; the rest stay free on the surface (a path between
    /// two patches no sharp curve separates, or too far from it).
    pub path_nodes: usize,
    pub curve_nodes: usize,
    pub corner_nodes: usize,
    pub nodes_added: usize,
    pub elements_added: usize,
    /// The nodes held at feature corners: (node, index of the corner in the
    /// surface's feature corners); node numbers of the mesh this stage returns,
    /// which the later stages keep.
    pub corners_held: Vec<[u32; 2]>,
    /// Feature corners the caller asked not to hold a node at.
    pub corners_released: usize,
    /// Corners where a face narrower than the option's angle kept the lattice's
    /// quads out of its sheet.
    pub narrow_corners: usize,
    /// Input patches narrower than the lattice merged into a neighbour.
    pub narrow_patches_merged: usize,
    /// New elements with a negative signed volume right after the insertion (zero
    /// thickness counts as neither): the smoothing that follows untangles them.
    pub negative_volume: usize,
}

/// The feature sheets step (with `QualityOptions::feature_sheets` on a pillowed
/// lattice mesh whose boundary nodes are all free, when the input has sharp
/// curves): [`feature_sheets`] within [`SHEET_REACH`] boundary edges, smoothed
/// at once when inserted. Kept even when the smoothing leaves inverted elements
/// (faces narrower than the voxels): the steps after it untangle most of them,
/// and the fallback compares the result with the mesh without the sheets
/// (`voxel::sheets`). Returns the step's report (None when it does not apply)
/// and the smoothing's (None when no sheet was inserted).
pub fn sheets_step(work: &mut Work, sw: &Surface, released: &[u32], opts: &QualityOptions, progress: &mut dyn Progress) -> Result<(Option<StageReport>, Option<StageReport>)> {
    if !(opts.feature_sheets && opts.pillow && work.role.iter().all(|r| matches!(r, Role::Free | Role::Interior)) && !sw.features.curves.is_empty()) {
        return Ok((None, None));
    }
    check_progress(progress, 0.58, "hex: feature sheets")?;
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let elements_before = work.mesh.elements.len();
    let edge = mean_boundary_edge(work);
    let (report, error) = match feature_sheets(work, sw, SHEET_REACH * edge, released, opts.narrow_corner_faces, opts.narrow_patch_width * edge) {
        Ok(rep) => (Some(rep), None),
        Err(e) => (None, Some(e.to_string())),
    };
    let inserted = work.mesh.elements.len() > elements_before;
    let mut details = SheetsDetails { report, error, kept: inserted, inverted_after_smoothing: None };
    let mut smoothed = None;
    if inserted {
        let st = smoothing(work, sw, opts.smooth_iterations);
        details.inverted_after_smoothing = Some(st.after.inverted);
        smoothed = Some(st);
    }
    Ok((Some(stage_report(Stage::FeatureSheets, before, &work.mesh, t0, StageDetails::FeatureSheets(details))), smoothed))
}

/// Insert the feature sheets into a pillowed mesh (every boundary quad on its own
/// element) whose boundary nodes lie on the surface, and put the nodes of the
/// paths between patch labels onto the curves between them. `reach`: how far (in
/// the working frame) a path node may be from its curve or corner to be put on it.
/// No node is held at the feature corners listed in `released` (indices into
/// `sw.features.corners`; the nodes there go onto one of the corner's curves).
/// A face whose angle at a held corner is below `narrow_deg` degrees keeps the
/// lattice's quads there, out of its sheet (0: none). A patch narrower than
/// `narrow_width` (a length in the working frame) is merged into a neighbour
/// first ([`patches::merge_narrow_patches`]; 0: none).
/// Leaves `w` unchanged and returns an error when the mesh is not pillowed or
/// the result would not be conforming.
pub fn feature_sheets(w: &mut Work, sw: &Surface, reach: f64, released: &[u32], narrow_deg: f64, narrow_width: f64) -> Result<SheetReport> {
    let mut rep = SheetReport::default();
    let edge_tris = edge_triangles(&sw.mesh);
    let patches = patches::patches(sw, &edge_tris, narrow_width);
    rep.patches = patches.count;
    rep.narrow_patches_merged = patches.merged;
    if patches.count < 2 {
        return Ok(rep);
    }
    let bq = boundary_quads(&w.mesh).map_err(Error::MeshingFailed)?;
    let ne0 = w.mesh.elements.len();
    // every boundary quad on its own element (a pillowed mesh)
    let mut owner = vec![u32::MAX; ne0];
    for (k, q) in bq.iter().enumerate() {
        if owner[q.element as usize] != u32::MAX {
            return Err(Error::MeshingFailed(format!("feature sheets: element {} has two boundary faces (pillow first)", q.element)));
        }
        owner[q.element as usize] = k as u32;
    }
    // ---- labels: the patch of the input the quad faces and is nearest to ----
    let labels = labels::label_quads(w, sw, &bq, &patches.tri_patch);
    rep.labels_changed = labels.changed;
    // ---- the paths: boundary nodes whose quads carry two labels or more ----
    let n0 = w.mesh.nodes.len();
    let paths = labels::paths(&bq, &labels, n0);
    rep.path_nodes = paths.nodes.len();
    if paths.nodes.is_empty() {
        return Ok(rep);
    }
    let saved = w.clone();
    // ---- one sheet per patch that borders another label ----
    let mut el_label = insert::sheet_elements(&bq, &labels, &paths, ne0);
    if narrow_deg > 0.0 {
        rep.narrow_corners += insert::narrow_corner_faces(&mut el_label, w, sw, &bq, &labels, &paths, &patches, reach, released, narrow_deg);
    }
    let copy_patch = insert::insert_sheets(w, &el_label, &paths, n0, &mut rep);
    if let Err(e) = boundary_quads(&w.mesh) {
        *w = saved;
        return Err(Error::MeshingFailed(format!("feature sheets: {e}")));
    }
    // ---- the path nodes onto the curves and corners ----
    place::onto_features(w, sw, &edge_tris, &patches, &paths, reach, released, &mut rep);
    w.rebuild();
    place::settle(w, sw, &patches.tri_patch, &paths, &copy_patch, n0);
    Ok(rep)
}

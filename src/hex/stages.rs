//! Typed reports of the hex stage's steps: which step ([`Stage`]), the quality
//! before and after it, and what it did ([`StageDetails`], one type per step).
//! They serialise to report.json's "hex.stages" entries (the keys and strings
//! docs/hex.md lists); the stage itself reads them as types, never as JSON.

use super::fit::FitStats;
use super::quality::capture::CaptureStats;
use super::quality::coverage::CoverStats;
use super::quality::pillow::PillowReport;
use super::quality::sheets::SheetReport;
use super::quality::QualitySummary;
use super::work::MoveStats;
use serde::{Serialize, Serializer};

/// A step of the hex stage, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// The mapped mesh (the polycube map's chosen level, or a voxel lattice fitted to the surface).
    Mapping,
    Pillowing,
    FeatureSheets,
    Smoothing,
    Capture,
    Coverage,
    Optimisation,
    Recapture,
    BoundaryAscent,
}

impl Stage {
    /// The name in report.json ("feature sheets").
    pub fn name(self) -> &'static str {
        match self {
            Stage::Mapping => "mapping",
            Stage::Pillowing => "pillowing",
            Stage::FeatureSheets => "feature sheets",
            Stage::Smoothing => "smoothing",
            Stage::Capture => "capture",
            Stage::Coverage => "coverage",
            Stage::Optimisation => "optimisation",
            Stage::Recapture => "recapture",
            Stage::BoundaryAscent => "boundary ascent",
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

impl Serialize for Stage {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// One quality step: what it started from and what it produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageReport {
    pub stage: Stage,
    pub before: QualitySummary,
    pub after: QualitySummary,
    pub nodes: usize,
    pub elements: usize,
    pub seconds: f64,
    pub details: StageDetails,
}

impl StageReport {
    /// The details as report.json has them.
    pub fn details_json(&self) -> serde_json::Value {
        serde_json::to_value(&self.details).unwrap_or_default()
    }
}

/// What a step did, one type per step.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum StageDetails {
    Mapping(MappingDetails),
    Pillowing(PillowReport),
    FeatureSheets(SheetsDetails),
    /// The smoothing's moves.
    Smoothing(MoveStats),
    /// The capture and the recapture.
    Capture(Guarded<CaptureDetails>),
    Coverage(Guarded<CoverStats>),
    Optimisation(OptimisationDetails),
    BoundaryAscent(Guarded<AscentDetails>),
}

/// The mapped mesh: its level, its flipped boundary quads, the fits that put its
/// boundary on the surface, and for a voxel lattice what the fallback did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MappingDetails {
    pub level: u32,
    pub flipped_boundary_quads: usize,
    pub fit: Vec<FitStats>,
    #[serde(flatten)]
    pub lattice: Option<LatticeDetails>,
}

/// The grid-based fallback's lattice of a mesh (and, on the mesh it returns,
/// every lattice it tried and meshed).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LatticeDetails {
    pub voxel_resolution: usize,
    /// Voxel edge in user units.
    pub voxel_size: f64,
    pub voxels_filled_for_manifold: usize,
    /// Boundary nodes held on the input's sharp features from the start.
    pub feature_nodes_held: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub local_refinement: Option<RefinementDetails>,
    /// The lattice planes moved onto the input's faces, per axis (`FallbackOptions::lattice_planes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub planes_on_faces: Option<Vec<usize>>,
    /// The lattice was repaired for a porous thin wall.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub voxels_added_for_thin_walls: Option<ThinWall>,
    /// Which of the feature-sheet variants was kept.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feature_sheets: Option<SheetsChoice>,
    /// On the returned mesh: every resolution whose topology was checked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resolutions_tried: Option<Vec<String>>,
    /// On the returned mesh: every lattice meshed, in order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lattices_meshed: Option<Vec<LatticeMeshed>>,
    /// Local refinement rounds whose split voxels could not be voxelised again.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revoxelisation_skipped: Option<Vec<String>>,
}

/// The voxels added to close the extra tunnels of a porous thin wall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ThinWall {
    pub voxels: usize,
    pub min_solid_fraction: f32,
}

/// A locally refined lattice: the boxes split, the elements split and the
/// transition elements, where its mesh started.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RefinementDetails {
    pub boxes: Vec<([u32; 3], [u32; 3])>,
    pub elements_split: usize,
    pub transition_elements: usize,
    pub start: RefineStart,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revoxelised: Option<Revoxelised>,
}

/// Where a locally refined lattice's mesh started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefineStart {
    /// Every node on the lattice.
    Lattice,
    /// The new nodes on the fitted coarse mesh.
    FittedCoarseMesh,
    /// The split voxels voxelised again at the fine size.
    Revoxelised,
}

impl RefineStart {
    pub fn name(self) -> &'static str {
        match self {
            RefineStart::Lattice => "lattice",
            RefineStart::FittedCoarseMesh => "fitted coarse mesh",
            RefineStart::Revoxelised => "re-voxelised lattice",
        }
    }
}

impl Serialize for RefineStart {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// What the re-voxelisation of the split voxels did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Revoxelised {
    pub empty_voxels_split: usize,
    pub fine_voxels_removed: usize,
    pub fine_voxels_filled: usize,
}

/// A lattice the fallback meshed and the figures its mesh is ranked by.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LatticeMeshed {
    pub resolution: usize,
    pub elements: usize,
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    pub hausdorff_relative: f64,
    /// The lattice with its planes on the input's faces.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub planes_on_faces: Option<bool>,
    /// A local refinement round: the start of its kept mesh, and every start's mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub local_refinement_start: Option<RefineStart>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub local_refinement_starts: Option<Vec<MeshFigures>>,
}

/// The figures a mesh is ranked by (and, for a local refinement round's mesh, its start).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeshFigures {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<RefineStart>,
    pub elements: usize,
    pub inverted: usize,
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    pub hausdorff_relative: f64,
}

/// Which mesh of a lattice with the feature sheets was kept: the one with the
/// sheets, with the corners at fault released, with every corner released, or
/// the one without the sheets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SheetsVariant {
    With,
    Released,
    ReleasedAll,
    Without,
}

impl Serialize for SheetsVariant {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(match self {
            SheetsVariant::With => "with",
            SheetsVariant::Released => "released",
            SheetsVariant::ReleasedAll => "released_all",
            SheetsVariant::Without => "without",
        })
    }
}

/// The feature-sheet variants of a lattice: whether they were compared, whether
/// the kept mesh has the sheets, and the figures of each variant meshed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SheetsChoice {
    pub compared: bool,
    pub kept: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub with: Option<MeshFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corners_released: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub released: Option<MeshFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corners_released_all: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub released_all: Option<MeshFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub without: Option<MeshFigures>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chosen: Option<SheetsVariant>,
}

/// The feature sheets: what they did (or why they could not be inserted),
/// whether they were inserted, and the inverted elements the smoothing right
/// after them left.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SheetsDetails {
    #[serde(flatten)]
    pub report: Option<SheetReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub kept: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inverted_after_smoothing: Option<usize>,
}

/// A step that moves boundary nodes towards the input, undone unless it brings
/// the mesh closer with the quality held: its own details, the two-sided
/// Hausdorff distances before and after, and whether it was kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Guarded<T> {
    #[serde(flatten)]
    pub step: T,
    pub hausdorff_relative_before: f64,
    pub hausdorff_relative_after: f64,
    pub kept: bool,
}

/// The capture (and the recapture, which re-optimises when it moved a node).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaptureDetails {
    #[serde(flatten)]
    pub capture: CaptureStats,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moves: Option<MoveStats>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_ascent: Option<MoveStats>,
}

/// The optimisation: the max-min moves (with the polish), the mean ascent, and
/// the folded boundary's nodes released.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OptimisationDetails {
    pub moves: MoveStats,
    pub mean_ascent: MoveStats,
    pub mean_before_ascent: f64,
    pub released_boundary_nodes: usize,
}

/// The boundary mean ascent.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AscentDetails {
    #[serde(flatten)]
    pub moves: MoveStats,
    pub mean_after_ascent: f64,
    pub pins_released: usize,
}

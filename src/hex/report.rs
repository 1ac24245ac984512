//! The result of the hex stage ([`HexResult`]) and what it hands to `sddpm run`:
//! the names of its files in the output folder (written by
//! `export::hexfmt::write_hex_files`) and the "hex" object of report.json
//! (DESIGN.md "Command line").

use super::distance::Hausdorff;
use super::quality::QualitySummary;
use super::stages::{LatticeDetails, MappingDetails, SheetsDetails, StageDetails, StageReport};
use super::HexMesh;
use serde::{Serialize, Serializer};

/// File names of the hex stage inside the output folder.
pub const HEX_VTU: &str = "hex.vtu";
pub const HEX_VTK: &str = "hex.vtk";
pub const HEX_MESH: &str = "hex.mesh";
pub const HEX_K: &str = "hex.k";

/// How a mesh's boundary went onto the input (report.json `surface_map.method`:
/// "charts", "projection" or "lattice").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MapMethod {
    /// The inverse chart maps of the polycube path.
    Charts,
    /// Closest facing point and relaxation on the surface (the polycube path).
    #[default]
    Projection,
    /// The grid-based fallback's fit of its lattice.
    Lattice,
}

impl MapMethod {
    /// The name report.json and the benchmarks print.
    pub fn name(self) -> &'static str {
        match self {
            MapMethod::Charts => "charts",
            MapMethod::Projection => "projection",
            MapMethod::Lattice => "lattice",
        }
    }
}

impl std::fmt::Display for MapMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where the elements come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Domain {
    /// The parametric domain of the polycube, the method of this library.
    Polycube,
    /// The grid-based fallback ([`super::voxel`]) at this many voxels along the
    /// longest bounding-box edge.
    Voxel { resolution: usize },
}

impl std::fmt::Display for Domain {
    /// "polycube" or "voxel N" (report.json's "hex.domain").
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Domain::Polycube => f.pad("polycube"),
            Domain::Voxel { resolution } => f.pad(&format!("voxel {resolution}")),
        }
    }
}

impl Serialize for Domain {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Which mesh the hex stage returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Returned {
    /// The mesh after the quality steps.
    Optimised,
    /// The mapped mesh, when the quality steps did not reach its minimum scaled
    /// Jacobian (`QualityOptions::keep_better_mapped`).
    Mapped,
}

impl std::fmt::Display for Returned {
    /// "optimised" or "mapped" (report.json's "hex.returned").
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(match self {
            Returned::Optimised => "optimised",
            Returned::Mapped => "mapped",
        })
    }
}

impl Serialize for Returned {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// One level of the mapping and the stopping rule's measurement on it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LevelReport {
    pub level: u32,
    pub nodes: usize,
    pub elements: usize,
    /// The stopping rule's measure: the largest distance between a boundary midpoint
    /// linearly interpolated from this level and the input surface on which the next
    /// level maps it, relative to the bounding-box diagonal (None when the next level
    /// was not computed).
    pub deviation: Option<f64>,
    /// Boundary quads whose normal opposes the input's, and inverted elements, of
    /// this level's map.
    pub flipped_quads: usize,
    pub inverted: usize,
    pub seconds: f64,
}

/// How the surface map was set up.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SurfaceMapReport {
    /// How the boundary went onto the input.
    pub method: MapMethod,
    /// Why the projection was used where the charts were asked for (None otherwise).
    pub why: Option<String>,
    pub feature_curves: usize,
    pub feature_corners: usize,
    pub matched_corners: usize,
    pub matched_chains: usize,
    pub correspondence_pairs: usize,
    /// Sub-voxel planes moved towards the input before mapping, and the largest move (normalised units).
    pub planes_fitted: usize,
    pub max_plane_shift: f64,
    /// Boundary quads of the mapped mesh whose normal opposes the surface normal.
    pub flipped_quads: usize,
    /// Every surface map and level meshed, in the order tried, with the figures
    /// of its finished mesh: the charts and the projection under
    /// [`crate::hex::SurfaceMap::Best`], and the level one finer when a mesh
    /// missed the distance goal alone (empty when one mesh was built under
    /// another setting).
    pub tried: Vec<SurfaceMapTry>,
}

/// One mesh of the polycube path (a surface map at a level) and its figures.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SurfaceMapTry {
    /// [`MapMethod::Charts`] or [`MapMethod::Projection`].
    pub method: MapMethod,
    pub level: u32,
    pub elements: usize,
    pub inverted: usize,
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    pub hausdorff_relative: f64,
    /// Quality goals the mesh misses.
    pub goals_missed: usize,
    pub seconds: f64,
    /// Whether this mesh is the one returned.
    pub kept: bool,
    /// Elements of the level split 3 x 3 x 3 by local refinement (0: the level as mapped).
    pub split_elements: usize,
}

/// The result of the hex stage.
#[derive(Debug, Clone, Serialize)]
pub struct HexResult {
    /// The all-hex mesh in user coordinates (VTK_HEXAHEDRON order, positively oriented).
    #[serde(skip)]
    pub mesh: HexMesh,
    /// The mapped mesh (before pillowing, smoothing and optimisation), user coordinates.
    #[serde(skip)]
    pub mapped: HexMesh,
    pub level: u32,
    #[serde(skip)]
    pub scaled_jacobian: Vec<f64>,
    pub quality: QualitySummary,
    /// Counts of scaled Jacobians in 20 equal bins of [-1, 1].
    pub histogram: Vec<usize>,
    pub hausdorff: Hausdorff,
    pub hausdorff_relative: f64,
    pub volume: f64,
    pub input_volume: f64,
    pub levels: Vec<LevelReport>,
    pub surface_map: SurfaceMapReport,
    /// One report per step; the first is always the mapping.
    pub stages: Vec<StageReport>,
    /// Which mesh was returned.
    pub returned: Returned,
    /// Where the elements come from.
    pub domain: Domain,
    pub seconds_total: f64,
}

impl HexResult {
    /// Did the elements come from the polycube (not from the grid-based fallback)?
    pub fn from_polycube(&self) -> bool {
        self.domain == Domain::Polycube
    }

    /// The mapping step's details (the first stage).
    pub fn mapping(&self) -> Option<&MappingDetails> {
        match self.stages.first().map(|s| &s.details) {
            Some(StageDetails::Mapping(d)) => Some(d),
            _ => None,
        }
    }

    /// The voxel lattice's details of a fallback mesh (None for a polycube mesh).
    pub fn lattice(&self) -> Option<&LatticeDetails> {
        self.mapping().and_then(|d| d.lattice.as_ref())
    }

    /// [`HexResult::lattice`], to record more on it.
    pub fn lattice_mut(&mut self) -> Option<&mut LatticeDetails> {
        match self.stages.first_mut().map(|s| &mut s.details) {
            Some(StageDetails::Mapping(d)) => d.lattice.as_mut(),
            _ => None,
        }
    }

    /// The feature sheets' details when they were inserted (kept).
    pub fn kept_sheets(&self) -> Option<&SheetsDetails> {
        self.stages.iter().find_map(|s| match &s.details {
            StageDetails::FeatureSheets(d) if d.kept => Some(d),
            _ => None,
        })
    }
}

/// The "hex" object of report.json: the keys DESIGN.md fixes (vertices, elements,
/// min_scaled_jacobian, mean_scaled_jacobian, inverted, hausdorff_relative, file)
/// and more: level, histogram, volumes, per-level and per-stage reports.
pub fn report_json(r: &HexResult) -> serde_json::Value {
    let irregular = super::topology::irregular_edges(&r.mesh);
    serde_json::json!({
        "vertices": r.mesh.nodes.len(),
        "elements": r.mesh.elements.len(),
        "min_scaled_jacobian": r.quality.min,
        "mean_scaled_jacobian": r.quality.mean,
        "inverted": r.quality.inverted,
        "hausdorff_relative": r.hausdorff_relative,
        // interior edges on other than four elements plus boundary edges on other
        // than two: where the spline is only C0
        "irregular_edges": irregular.total(),
        "irregular_edges_interior": irregular.interior,
        "irregular_edges_boundary": irregular.boundary,
        "file": HEX_VTU,
        "files": [HEX_VTU, HEX_VTK, HEX_MESH, HEX_K],
        "level": r.level,
        "scaled_jacobian_measure": "Verdict hex scaled Jacobian (8 corners + centre principal axes, VTK node order)",
        "histogram": { "bins": r.histogram.len(), "range": [-1.0, 1.0], "counts": r.histogram },
        "hausdorff": r.hausdorff,
        "volume": r.volume,
        "input_volume": r.input_volume,
        "returned": r.returned,
        "domain": r.domain,
        "levels": r.levels,
        "surface_map": r.surface_map,
        "stages": r.stages,
        "seconds": r.seconds_total,
    })
}

/// Seconds per hex stage, for report.json's "seconds" object ("hex_mapping", ...).
pub fn stage_seconds(r: &HexResult) -> Vec<(String, f64)> {
    r.stages.iter().map(|s| (format!("hex_{}", s.stage), s.seconds)).collect()
}

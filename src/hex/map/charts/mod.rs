//! Charts and chart maps: the polycube map in the sense of the literature (a
//! segmentation of the input surface into one chart per polycube face, each chart
//! mapped onto its face). docs/hex.md "Charts and chart maps" has the same in prose.
//!
//! One step a file:
//! 1. [`faces`]: the polycube's boundary faces, corners and edges;
//! 2. [`segment`]: the seed labelling and its optimisation, the removal of ears
//!    (triangles that would map without area) and of islands (so that every
//!    chart is connected);
//! 3. [`topology`]: the check of the charts against the faces (connected, disc or
//!    annulus as the face is, adjacency, corners) with a diagnostic per mismatch;
//! 4. [`chart_map`]: each chart onto its face (boundary by arc length between the
//!    corners, interior by a Tutte embedding) with a count of flipped triangles;
//! 5. [`inverse`]: the inverse of the chart maps, a polycube boundary point onto
//!    the input (the surface map of [`crate::hex::SurfaceMap::Charts`]).
//!
//! [`segment_and_map`] runs them all on a [`HexInput`].

pub mod chart_map;
pub mod faces;
pub mod inverse;
pub mod segment;
pub mod topology;

pub use chart_map::{map_chart, ChartMap};
pub use inverse::{ChartInverse, Located};
pub use faces::{polycube_faces, PolyCorner, PolyEdge, PolyFace, PolycubeFaces};
pub use topology::{ChartStats, ChartTopology, Diagnostic};

use super::HexInput;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;

/// Weights of the Tutte embedding of a chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TutteWeights {
    /// Every edge weight 1.
    Uniform,
    /// Floater's mean-value weights (positive; closer to the chart's own shape).
    MeanValue,
}

/// Options of the segmentation and the chart maps.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChartOptions {
    /// Weight of the distance from a triangle to a face in the data term, per
    /// normalised unit (default 1.0; range [0, 100]). The normal term is 1 - n.d.
    pub distance_weight: f64,
    /// Weight of the boundary term per mean edge length of chart boundary (default
    /// 0.3; range [0, 100]; 0 keeps the seed where the data term agrees).
    pub smoothness: f64,
    /// Dihedral angle scale (degrees) of the boundary term: an edge with dihedral
    /// angle a costs exp(-(a/sharp_angle)^2) per length, so chart boundaries follow
    /// sharp input edges (default 30; range (0, 180]).
    pub sharp_angle: f64,
    /// Most sweeps of iterated conditional modes (default 30; range 0..=10 000).
    pub iterations: usize,
    /// Weights of the Tutte embedding (default mean value).
    pub weights: TutteWeights,
}

impl Default for ChartOptions {
    fn default() -> Self {
        ChartOptions { distance_weight: 1.0, smoothness: 0.3, sharp_angle: 30.0, iterations: 30, weights: TutteWeights::MeanValue }
    }
}

impl ChartOptions {
    /// Check every option against its range.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidArgument(m));
        if !(0.0..=100.0).contains(&self.distance_weight) {
            return bad(format!("charts: distance_weight {} is outside [0, 100]", self.distance_weight));
        }
        if !(0.0..=100.0).contains(&self.smoothness) {
            return bad(format!("charts: smoothness {} is outside [0, 100]", self.smoothness));
        }
        if !(self.sharp_angle > 0.0 && self.sharp_angle <= 180.0) {
            return bad(format!("charts: sharp_angle {} is outside (0, 180]", self.sharp_angle));
        }
        if self.iterations > 10_000 {
            return bad(format!("charts: iterations {} is above 10 000", self.iterations));
        }
        Ok(())
    }
}

/// The segmentation of the input into charts.
#[derive(Debug, Clone)]
pub struct Segmentation {
    /// Per input triangle: the polycube face it maps to.
    pub face_of: Vec<u32>,
    /// Per face: its chart's measures.
    pub charts: Vec<ChartStats>,
    /// Per polycube corner: the input vertex where its faces' charts meet.
    pub corners: Vec<Option<u32>>,
    /// Islands moved to a neighbouring chart to make the charts connected.
    pub islands_moved: usize,
    /// Ears (triangles bordering one other chart across two edges) moved to that chart.
    pub ears_moved: usize,
    /// Sweeps of the optimisation.
    pub sweeps: usize,
    /// What does not match the polycube (empty when the charts are as the faces are).
    pub diagnostics: Vec<Diagnostic>,
    pub(crate) topology: ChartTopology,
}

impl Segmentation {
    /// Do the charts have the polycube's topology?
    pub fn is_valid(&self) -> bool {
        self.diagnostics.is_empty()
    }

    /// The diagnostics as one typed error (Ok when there are none).
    pub fn check(&self) -> Result<()> {
        if self.diagnostics.is_empty() {
            return Ok(());
        }
        let v: Vec<String> = self.diagnostics.iter().map(|d| d.to_string()).collect();
        Err(Error::MeshingFailed(format!("the charts do not match the polycube's faces: {}", v.join("; "))))
    }
}

/// Segment `surface` (normalised frame) into the charts of the faces `pf`.
/// `corr` is the diffusion correspondence (polycube point, input point); may be empty.
pub fn segment(surface: &TriMesh, pf: &PolycubeFaces, corr: &[([f64; 3], [f64; 3])], opts: &ChartOptions) -> Result<Segmentation> {
    opts.validate()?;
    if surface.triangles.is_empty() {
        return Err(Error::InvalidArgument("charts: the surface has no triangles".into()));
    }
    if surface.triangles.iter().flatten().any(|&i| i as usize >= surface.vertices.len()) {
        return Err(Error::InvalidArgument("charts: a triangle refers to a vertex that does not exist".into()));
    }
    if surface.vertices.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::InvalidArgument("charts: non-finite vertex coordinate".into()));
    }
    let g = segment::TriGraph::new(surface, opts.sharp_angle);
    let mut labels = segment::seed(&g, pf, corr);
    let sweeps = segment::optimise(&g, pf, opts, &mut labels);
    let mut ears_moved = segment::remove_ears(&g, &mut labels, pf.faces.len());
    let islands_moved = segment::remove_islands(&g, &mut labels, pf.faces.len());
    ears_moved += segment::remove_ears(&g, &mut labels, pf.faces.len());
    let topology = topology::check_topology(surface, &g, pf, &labels);
    Ok(Segmentation {
        face_of: labels,
        charts: topology.charts.clone(),
        corners: topology.corners.clone(),
        islands_moved,
        ears_moved,
        sweeps,
        diagnostics: topology.diagnostics.clone(),
        topology,
    })
}

/// Faces, segmentation and chart maps of a hex-stage input.
#[derive(Debug, Clone)]
pub struct Charts {
    pub faces: PolycubeFaces,
    pub segmentation: Segmentation,
    /// Per face: its chart map, or why there is none (a face with a hole, a chart
    /// that is not a disc, a corner that is missing).
    pub maps: Vec<Result<ChartMap>>,
}

/// The polycube faces of `input.context`, the segmentation of `input.surface` into
/// their charts and each chart's map onto its face.
pub fn segment_and_map(input: &HexInput, opts: &ChartOptions) -> Result<Charts> {
    let validity = input.context.validity();
    if !validity.valid {
        return Err(Error::InvalidContext(format!(
            "the polycube is not a valid solid: {}",
            validity.reason.unwrap_or_default()
        )));
    }
    let faces = polycube_faces(&input.context)?;
    let segmentation = segment(&input.surface, &faces, &input.correspondence, opts)?;
    let maps = (0..faces.faces.len())
        .map(|f| map_chart(&input.surface, &faces, &segmentation.topology, &segmentation.face_of, f, opts.weights))
        .collect();
    Ok(Charts { faces, segmentation, maps })
}

//! Options of the hex stage: one struct per concern (the polycube map, the input
//! surface and its features, the quality steps, the grid-based fallback, the
//! quality goals), each with its documented defaults, and the one check of them
//! all ([`HexOptions::validate`]) that the library, the command line and the C API
//! share. docs/hex.md explains every default.

use super::goals::QualityGoals;
use super::voxel::{VOXEL_MAX_RESOLUTION, VOXEL_START_RESOLUTION};
use crate::error::Error;
use serde::{Deserialize, Serialize};

/// Options of the hex stage (defaults in [`HexOptions::default`], docs/hex.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HexOptions {
    /// The polycube map: levels and the stopping rule, the start embedding.
    pub map: MapOptions,
    /// The input surface: its sharp features and the fit of the boundary nodes to it.
    pub surface: SurfaceOptions,
    /// The quality steps after the mapping.
    pub quality: QualityOptions,
    /// The grid-based fallback ([`super::voxel`]).
    pub fallback: FallbackOptions,
    /// The quality a mesh should reach. Meshes are ranked by
    /// inverted elements, then by how many goals they miss, then by minimum scaled
    /// Jacobian; when the polycube meshes miss one (and the level is automatic), the
    /// voxel fallback is tried too.
    pub goals: QualityGoals,
    /// Most elements before pillowing (default 200 000): the stopping rule's level is
    /// capped by it (but not below `map.min_level`), and the fallback's lattices have
    /// at most this many voxels (none within it: the fallback fails, MESHING_FAILED).
    pub max_elements: usize,
    /// Extra random surface samples for the Hausdorff distance (default 20 000).
    pub hausdorff_samples: usize,
    /// Target element size in model units (default None: the level by the
    /// stopping rule, the fallback's lattices by `fallback.resolution`; finite,
    /// > 0). When set, the main job fixes each polycube mesh's level to the one
    /// whose element count is nearest the input's volume over size^3, and the
    /// fallback's first lattice to `longest bounding-box edge / size` voxels with no
    /// finer lattice after it (`crate::pipeline::size`); a fixed `map.level` or
    /// the caller's own `fallback.resolution` is replaced.
    #[serde(default)]
    pub target_size: Option<f64>,
}

impl Default for HexOptions {
    fn default() -> Self {
        HexOptions {
            map: MapOptions::default(),
            surface: SurfaceOptions::default(),
            quality: QualityOptions::default(),
            fallback: FallbackOptions::default(),
            goals: QualityGoals::default(),
            max_elements: 200_000,
            hausdorff_samples: 20_000,
            target_size: None,
        }
    }
}

/// Options of the polycube map ([`super::build_hex_mesh`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapOptions {
    /// Fix the subdivision level instead of choosing it by the stopping rule (default
    /// None; at most [`MAX_LEVEL`]).
    pub level: Option<u32>,
    /// Smallest level the stopping rule may choose (default 2).
    pub min_level: u32,
    /// Largest level (default 4; at most [`MAX_LEVEL`]).
    pub max_level: u32,
    /// Stopping rule threshold: largest distance between a mapped midpoint and its
    /// linear interpolation, relative to the input's bounding-box diagonal (default 0.005).
    pub threshold: f64,
    /// The stopping rule also stops when the measure of a level is above this fraction
    /// of the previous level's (refining no longer helps; default 0.75).
    pub stall_ratio: f64,
    /// Use the diffusion correspondence as the seed of the surface map (default
    /// false: with the template-attention default the decoded points sit on the
    /// template in rank order, and seeding the map from them folded cgal_hole at
    /// level 1 — 2 inverted elements, Hausdorff 12.7 % — where the plane fit gives a
    /// valid mesh within 1 %; BENCHMARKS.md "Main job").
    pub use_correspondence: bool,
    /// Without a correspondence, fit the polycube's sub-voxel planes to the input
    /// before mapping (default true).
    pub fit_planes: bool,
    /// How the boundary of the polycube's lattice mesh goes onto the input (default
    /// [`SurfaceMap::Best`]; docs/hex.md "Surface map from the charts").
    pub surface_map: SurfaceMap,
    /// Rounds of local refinement of the chosen level when its mesh misses the
    /// distance goal alone (default 0 = none): each round splits the level's
    /// elements around the points farthest from the last mesh 3 x 3 x 3, with
    /// conforming transitions, and runs the quality steps again; the level one
    /// finer is still meshed after them when a goal is missed, and the best mesh
    /// by the goals is kept (docs/hex.md "Local refinement of the polycube map").
    /// A round whose mesh would have as many elements as the finer level (eight
    /// times the level's) ends the rounds.
    /// Off by default: on cgal_dragknob it meets the goals with fewer elements
    /// than the finer level but a lower minimum and mean (BENCHMARKS.md). Not
    /// with a fixed `level`.
    pub local_refinement: usize,
}

/// The surface map of the polycube path ([`MapOptions::surface_map`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum SurfaceMap {
    /// Closest facing point on the input, matched feature curves and corners,
    /// relaxation on the surface.
    Projection,
    /// The inverse of the chart maps (one chart of the input per polycube face,
    /// mapped bijectively onto it); the projection where a chart does not map.
    Charts,
    /// The charts first; when their mesh misses a quality goal, the projection
    /// too, and the mesh that ranks better by the goals is kept
    /// ([`crate::hex::QualityGoals::beats`]; report.json `surface_map.tried`).
    /// The default: neither map wins on every part (BENCHMARKS.md "Surface map:
    /// charts and projection").
    #[default]
    Best,
}

/// Highest subdivision level of the polycube map.
pub const MAX_LEVEL: u32 = 6;

impl Default for MapOptions {
    fn default() -> Self {
        MapOptions { level: None, min_level: 2, max_level: 4, threshold: 0.005, stall_ratio: 0.75, use_correspondence: false, fit_planes: true, surface_map: SurfaceMap::Best, local_refinement: 0 }
    }
}

/// The input surface's sharp features and the fit of the boundary nodes to it
/// (the polycube map and the fallback alike).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceOptions {
    /// Dihedral angle (degrees) above which an input edge is a sharp feature (default 40).
    pub feature_angle: f64,
    /// Feature curves shorter than this fraction of the bounding-box diagonal are
    /// ignored (default 0.03).
    pub min_feature_length: f64,
    /// Feature curves whose median dihedral angle (degrees) is below this are ignored
    /// (default 60: creases of CAD parts, not facets of a coarse smooth surface).
    pub feature_median_angle: f64,
    /// Turning angle (degrees) that makes a feature-curve vertex a corner (default 45).
    pub corner_angle: f64,
    /// Rounds of the boundary fit and relaxation iterations of the surface map on
    /// level 0 (later levels use a half and a third; default 30); also the rounds
    /// of the capture and coverage steps' pulls.
    pub relax_iterations: usize,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions { feature_angle: 40.0, min_feature_length: 0.03, feature_median_angle: 60.0, corner_angle: 45.0, relax_iterations: 30 }
    }
}

/// The quality steps after the mapping ([`super::quality`]), in their order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QualityOptions {
    /// One pillow layer under the boundary (default true).
    pub pillow: bool,
    /// Feature sheets (after pillowing; the fallback's lattices and the polycube
    /// map's mesh alike): the boundary quads
    /// labelled with the input patch they lie on (patches: the input split by its
    /// sharp curves), a sheet of elements inserted under each patch's quads within
    /// one ring of another label, and the nodes where labels meet put on the sharp
    /// curve (or the feature corner) between their patches and held there
    /// ([`super::quality::sheets`]); kept even when the smoothing that follows leaves
    /// inverted elements (a face narrower than the voxels), which the later
    /// steps untangle. The elements along a curve share its dihedral angle two
    /// by two and six meet at a corner of three faces, so when the mesh misses
    /// the minimum goal alone at elements of corner nodes the fallback meshes the
    /// lattice again with no node held at those corners, when that misses a goal
    /// (the distance too), with no node held at any corner, when the best misses
    /// a scaled-Jacobian goal still, without the sheets, and keeps the best
    /// (docs/hex.md "Feature sheets"). Default true: at 24 voxels cgal_joint 1.92 -> 0.30 % and
    /// mambo_B0 1.46 -> 0.21 %, both meeting every goal (the main job needed 48
    /// and 39 voxels); hexgen_hepta at 28 voxels 1.41 -> 0.83 %, every goal met
    /// (BENCHMARKS.md "Feature sheets", "Feature sheets through the inversions").
    pub feature_sheets: bool,
    /// With the feature sheets: at a node held at a feature corner, a face whose
    /// angle at the corner is below this many degrees keeps the lattice's quads
    /// there instead of getting two of half its angle from its sheet (0: off).
    /// Default 70: hexgen_rod's four concave corners (faces of 52-60 degrees)
    /// are then held within the minimum goal (0.24-0.28 -> 0.37-0.40), and at 33
    /// voxels it comes to 0.75 % with every corner held, where releasing them
    /// gave 0.93 % (BENCHMARKS.md "One quad for a narrow face at a corner").
    pub narrow_corner_faces: f64,
    /// With the feature sheets: an input patch (a face between sharp curves)
    /// narrower than this fraction of the lattice's boundary edge (width: twice
    /// its area over its perimeter) is merged into its neighbour before the
    /// labelling; its curves and the corners no longer between three patches are
    /// then not held (0: off). A strip that narrow gets a label region of one
    /// quad or none, whose two sheets meet and fold. Default 0.75: hexgen_hepta's
    /// chamfers and ledges (0.59-0.70 of the spacing at 12 voxels) merged, the
    /// sheets hold there (2.14 -> 0.94 %); hexgen_rod's narrow faces at its
    /// concave corners (0.79-0.90) keep their corners (BENCHMARKS.md "Narrow
    /// patches merged").
    pub narrow_patch_width: f64,
    /// Passes of mean-ratio smoothing (untangling) over all nodes (default 20).
    pub smooth_iterations: usize,
    /// Sharp-edge capture (after smoothing, before the coverage step): a boundary
    /// node within 0.75 boundary edge lengths of a sharp feature curve whose quads
    /// face both of the curve's faces goes onto the curve (two or more quads on
    /// each side) or half that distance off it onto its majority face (one quad on
    /// the minority side: a staircase step's convex corner), in steps that keep
    /// every element above min(before, goal + 0.05)
    /// ([`super::quality::capture::capture_features`]); undone unless it lowers the
    /// two-sided Hausdorff distance with no inverted element. Again after the
    /// optimisation, followed by a re-optimisation, on the same terms
    /// ("recapture"). Default true (false: neither step).
    pub capture_features: bool,
    /// Coverage step (after smoothing): every input vertex the mesh boundary misses
    /// by more than this fraction of [`QualityGoals::hausdorff`] gets its nearest
    /// free boundary node facing like it, pulled there in steps that keep every
    /// element above min(before, goal + 0.05) and kept there
    /// ([`super::quality::coverage::cover_uncovered_vertices`]); the step is undone unless it
    /// lowers the two-sided Hausdorff distance with no inverted element and a
    /// minimum scaled Jacobian no lower than before or above the goal. Default 0
    /// (off): on the 24-voxel meshes of eight fallback parts at 0.6 it brought
    /// hepta from 2.23 to 1.29 %, spool 2.44 -> 2.30 %, bust 3.12 -> 2.62 % (its
    /// minimum 0.547 -> 0.217), rod 1.92 -> 2.09 %, and was undone on rockerarm,
    /// pinion, dragknob and mambo (BENCHMARKS.md "Coverage").
    pub pin_uncovered: f64,
    /// Optimisation visits the nodes of elements below this scaled Jacobian (default 0.8).
    pub optimise_target: f64,
    /// Passes of the optimisation (default 30; 0: no optimisation, mean ascent,
    /// recapture or boundary ascent).
    pub optimise_passes: usize,
    /// Where elements stay inverted after optimisation, the surface nodes around them
    /// may leave the input by this fraction of the bounding-box diagonal (default 0.002).
    pub release_distance: f64,
    /// Boundary mean ascent (last quality step): the mean ascent again with the
    /// boundary nodes sliding on the input surface (curve nodes along their
    /// curves, corner nodes fixed), each boundary move kept only when no input
    /// point near the node's quads comes to lie farther from them than before
    /// or than 3/4 of the largest such distance
    /// ([`super::quality::ascent::boundary_mean_ascent`]); the step is kept when the
    /// mean rises with no inverted element, no lower minimum and a two-sided
    /// Hausdorff distance no larger than before. Default true: at one lattice
    /// each with the coverage step, hexgen_rod at 28 voxels mean 0.823 -> 0.832
    /// and 0.69 -> 0.63 %, hexgen_hepta at 12 0.871 -> 0.877 at the same 1.49 %
    /// (BENCHMARKS.md "Boundary mean ascent").
    pub boundary_ascent: bool,
    /// Return the mapped mesh when the quality steps end below its minimum scaled
    /// Jacobian (default true; false only to inspect the quality steps).
    pub keep_better_mapped: bool,
}

impl Default for QualityOptions {
    fn default() -> Self {
        QualityOptions {
            pillow: true,
            feature_sheets: true,
            narrow_corner_faces: 70.0,
            narrow_patch_width: 0.75,
            smooth_iterations: 20,
            capture_features: true,
            pin_uncovered: 0.0,
            optimise_target: 0.8,
            optimise_passes: 30,
            release_distance: 0.002,
            boundary_ascent: true,
            keep_better_mapped: true,
        }
    }
}

/// The grid-based fallback ([`super::voxel`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FallbackOptions {
    /// When no polycube candidate's mesh meets [`HexOptions::goals`] (with a fixed
    /// `map.level`: when every one keeps inverted elements), also mesh the input on a
    /// voxel lattice ([`super::voxel`]) and keep that mesh when it ranks better
    /// (default true: on the 16 test parts it gave valid meshes where the
    /// polycube meshes of 6 folded, and meshes within the goals where single-cube
    /// polycubes missed the surface; BENCHMARKS.md "Main job"). The result says so
    /// (`HexResult::domain`). Used by the main job and by sddpm_hex_mesh_build.
    pub enabled: bool,
    /// Voxels along the longest bounding-box edge of the fallback's first lattice
    /// (default [`VOXEL_START_RESOLUTION`], 24; 2 to [`VOXEL_MAX_RESOLUTION`]);
    /// doubled while the lattice's topology differs from the input's.
    pub resolution: usize,
    /// Finer lattices the fallback may try after its first when the mesh misses
    /// [`HexOptions::goals`] (default 2; each within `max_elements`); when one
    /// meets the goals with room to spare, one more at the coarser resolution
    /// predicted to just meet the distance goal (kept when it meets every goal).
    /// 0: the first lattice only.
    pub refinements: usize,
    /// The kept lattice is meshed again with its planes moved onto the input's
    /// axis-parallel planar faces of at least this share of the input's area
    /// ([`super::lattice::LatticePlanes::aligned`]), and that mesh kept when it
    /// ranks better ([`QualityGoals::rank`]); in [0, 1), 0: the uniform lattice
    /// alone. Default [`LATTICE_PLANES_SHARE`].
    pub lattice_planes: f64,
    /// Local refinement rounds: after the lattices, the best lattice is meshed
    /// again up to this many times, each time with the voxels around the points
    /// farthest from the last mesh (input vertices and boundary nodes at least 0.8
    /// times the largest distance away) added to the voxels split 3 x 3 x 3 with
    /// conforming transition elements ([`super::refine`]); a round's mesh is kept
    /// when it ranks better by [`QualityGoals::rank`]; the rounds stop at
    /// `max_elements` or once the best meets every goal. Each round meshes the
    /// refined lattice three times (new nodes started on the lattice, on the fitted
    /// coarse mesh, and the split voxels voxelised again at the fine size) and keeps
    /// the best. Default 0 (off): on hexgen_rod at 28 voxels, 1,519 elements at
    /// 1.27 % -> 1,777 at 0.84 % in one round (the default fallback needs 48
    /// voxels, 5,723 elements), but the mean scaled Jacobian drops below its goal
    /// (0.833) and on hexgen_hepta at 12 voxels no round beats the plain lattice
    /// (BENCHMARKS.md "Local refinement").
    pub local_refinement: usize,
}

/// Default [`FallbackOptions::lattice_planes`]: a face of 2 % of the area or more
/// (hexgen_hepta's base, ledge and top: 21 / 8 / 7 %, its flat side 5 %, its
/// lugs' faces 0.8 %; hexgen_rod's two sides 11 / 10 %, its steps 1 % and less).
pub const LATTICE_PLANES_SHARE: f64 = 0.02;

impl Default for FallbackOptions {
    fn default() -> Self {
        FallbackOptions { enabled: true, resolution: VOXEL_START_RESOLUTION, refinements: 2, lattice_planes: LATTICE_PLANES_SHARE, local_refinement: 0 }
    }
}

/// An option of [`HexOptions`] that [`HexOptions::validate`] checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HexOption {
    Level,
    MinLevel,
    MaxLevel,
    Threshold,
    StallRatio,
    FeatureAngle,
    FeatureMedianAngle,
    CornerAngle,
    MinFeatureLength,
    NarrowCornerFaces,
    NarrowPatchWidth,
    PinUncovered,
    OptimiseTarget,
    ReleaseDistance,
    VoxelResolution,
    LatticePlanes,
    GoalMinScaledJacobian,
    GoalMeanScaledJacobian,
    GoalHausdorff,
    MaxElements,
    TargetSize,
}

impl HexOption {
    /// The option's path in [`HexOptions`] ("fallback.resolution").
    pub fn path(self) -> &'static str {
        match self {
            HexOption::Level => "map.level",
            HexOption::MinLevel => "map.min_level",
            HexOption::MaxLevel => "map.max_level",
            HexOption::Threshold => "map.threshold",
            HexOption::StallRatio => "map.stall_ratio",
            HexOption::FeatureAngle => "surface.feature_angle",
            HexOption::FeatureMedianAngle => "surface.feature_median_angle",
            HexOption::CornerAngle => "surface.corner_angle",
            HexOption::MinFeatureLength => "surface.min_feature_length",
            HexOption::NarrowCornerFaces => "quality.narrow_corner_faces",
            HexOption::NarrowPatchWidth => "quality.narrow_patch_width",
            HexOption::PinUncovered => "quality.pin_uncovered",
            HexOption::OptimiseTarget => "quality.optimise_target",
            HexOption::ReleaseDistance => "quality.release_distance",
            HexOption::VoxelResolution => "fallback.resolution",
            HexOption::LatticePlanes => "fallback.lattice_planes",
            HexOption::GoalMinScaledJacobian => "goals.min_scaled_jacobian",
            HexOption::GoalMeanScaledJacobian => "goals.mean_scaled_jacobian",
            HexOption::GoalHausdorff => "goals.hausdorff",
            HexOption::MaxElements => "max_elements",
            HexOption::TargetSize => "target_size",
        }
    }
}

/// A hex option out of its range: which option, its value, and what it must be.
/// Each interface names the option its own way ([`HexOption::path`] here, the
/// flag on the command line, the struct field in the C API).
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidHexOption {
    pub option: HexOption,
    /// The value given, as text.
    pub value: String,
    /// What it must be ("between 2 and 192").
    pub expected: String,
}

impl std::fmt::Display for InvalidHexOption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "hex option {} must be {}, got {}", self.option.path(), self.expected, self.value)
    }
}

impl std::error::Error for InvalidHexOption {}

impl From<InvalidHexOption> for Error {
    fn from(e: InvalidHexOption) -> Error {
        Error::InvalidArgument(e.to_string())
    }
}

impl HexOptions {
    /// Check every option against its range; the first one out of it is the error.
    /// The hex stage calls it ([`super::build_hex_mesh`], [`super::build_voxel_hex_mesh`]),
    /// and so do the main job, the command line and the C API before any work.
    pub fn validate(&self) -> Result<(), InvalidHexOption> {
        let bad = |option: HexOption, value: String, expected: &str| Err(InvalidHexOption { option, value, expected: expected.to_string() });
        let finite = |option: HexOption, x: f64| if x.is_finite() { Ok(()) } else { bad(option, x.to_string(), "finite") };
        let m = &self.map;
        if let Some(l) = m.level.filter(|&l| l > MAX_LEVEL) {
            return bad(HexOption::Level, l.to_string(), "a subdivision level in 0..=6");
        }
        if m.max_level > MAX_LEVEL {
            return bad(HexOption::MaxLevel, m.max_level.to_string(), "a subdivision level in 0..=6");
        }
        if m.min_level > m.max_level {
            return bad(HexOption::MinLevel, m.min_level.to_string(), &format!("at most map.max_level ({})", m.max_level));
        }
        if !(m.threshold > 0.0 && m.threshold.is_finite()) {
            return bad(HexOption::Threshold, m.threshold.to_string(), "a finite fraction of the bounding-box diagonal > 0");
        }
        finite(HexOption::StallRatio, m.stall_ratio)?;
        let s = &self.surface;
        finite(HexOption::FeatureAngle, s.feature_angle)?;
        finite(HexOption::CornerAngle, s.corner_angle)?;
        finite(HexOption::MinFeatureLength, s.min_feature_length)?;
        if !(0.0..=180.0).contains(&s.feature_median_angle) {
            return bad(HexOption::FeatureMedianAngle, s.feature_median_angle.to_string(), "an angle in degrees in [0, 180]");
        }
        let q = &self.quality;
        finite(HexOption::NarrowCornerFaces, q.narrow_corner_faces)?;
        finite(HexOption::NarrowPatchWidth, q.narrow_patch_width)?;
        if !(q.pin_uncovered.is_finite() && q.pin_uncovered >= 0.0) {
            return bad(HexOption::PinUncovered, q.pin_uncovered.to_string(), "a finite number >= 0");
        }
        finite(HexOption::OptimiseTarget, q.optimise_target)?;
        finite(HexOption::ReleaseDistance, q.release_distance)?;
        let f = &self.fallback;
        if !(2..=VOXEL_MAX_RESOLUTION).contains(&f.resolution) {
            return bad(HexOption::VoxelResolution, f.resolution.to_string(), &format!("between 2 and {VOXEL_MAX_RESOLUTION}"));
        }
        if !(0.0..1.0).contains(&f.lattice_planes) {
            return bad(HexOption::LatticePlanes, f.lattice_planes.to_string(), "a share of the area in [0, 1)");
        }
        let g = &self.goals;
        for (option, s) in [(HexOption::GoalMinScaledJacobian, g.min_scaled_jacobian), (HexOption::GoalMeanScaledJacobian, g.mean_scaled_jacobian)] {
            if !(s > -1.0 && s <= 1.0) {
                return bad(option, s.to_string(), "a scaled Jacobian in (-1, 1]");
            }
        }
        if !(g.hausdorff > 0.0 && g.hausdorff.is_finite()) {
            return bad(HexOption::GoalHausdorff, g.hausdorff.to_string(), "a finite fraction of the bounding-box diagonal > 0");
        }
        if self.max_elements == 0 {
            return bad(HexOption::MaxElements, "0".into(), "at least 1");
        }
        if let Some(h) = self.target_size.filter(|h| !(h.is_finite() && *h > 0.0)) {
            return bad(HexOption::TargetSize, h.to_string(), "a finite size > 0 in model units");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_valid_and_a_bad_option_is_named() {
        assert_eq!(HexOptions::default().validate(), Ok(()));
        let mut o = HexOptions::default();
        o.fallback.resolution = 1;
        let e = o.validate().unwrap_err();
        assert_eq!((e.option, e.value.as_str()), (HexOption::VoxelResolution, "1"));
        assert!(e.to_string().contains("fallback.resolution"), "{e}");
        let mut o = HexOptions::default();
        o.goals.hausdorff = f64::NAN;
        assert_eq!(o.validate().unwrap_err().option, HexOption::GoalHausdorff);
        let mut o = HexOptions::default();
        o.map.level = Some(7);
        assert_eq!(o.validate().unwrap_err().option, HexOption::Level);
        let mut o = HexOptions::default();
        o.map.min_level = 5;
        assert_eq!(o.validate().unwrap_err().option, HexOption::MinLevel);
        let mut o = HexOptions::default();
        o.quality.pin_uncovered = -0.1;
        assert_eq!(o.validate().unwrap_err().option, HexOption::PinUncovered);
    }
}

//! The hex stage end to end: accepted polycube + input surface -> mapped mesh at the
//! level the stopping rule picks -> pillowing -> smoothing -> optimisation, with a
//! before / after report for every step, in the user's coordinates.

use super::distance::{hausdorff, Hausdorff};
use super::frame::Affine;
use super::grid::{lattice_hex, prolong, LatticeHex};
use super::map::{self, Correspondence, FeatureMatch, Role};
use super::optimize::{self, MoveStats, Work};
use super::pillow::{pillow, PillowReport};
use super::quality::{element_qualities, histogram, summarize, QualitySummary};
use super::surface::{detect_features, prune_features, Surface};
use super::topology::{self, mesh_volume};
use super::HexMesh;
use crate::context::Context;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::vec3::*;
use crate::geometry::{Aabb, Alignment};
use crate::mesh::TriMesh;
use crate::polycube::assembly::occupied_cell_box;
use crate::context::context_frame;
use crate::polycube::tensor::BoxFrame;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// What the hex stage needs from the pipeline.
#[derive(Debug, Clone)]
pub struct HexInput {
    /// The input surface in the context's normalised frame (its aligned bounding box
    /// scaled per axis onto the box of the occupied cells, longest edge 2, centred).
    pub surface: TriMesh,
    /// The accepted polycube.
    pub context: Context,
    /// Diffusion correspondence: (point on the polycube surface, point on the input
    /// surface), both in the normalised frame. May be empty; used as a seed only.
    pub correspondence: Vec<([f64; 3], [f64; 3])>,
    /// Normalised frame -> user coordinates.
    pub to_user: Affine,
}

impl HexInput {
    /// The mapping DESIGN.md "Inference" fixes: the PCA-aligned input's bounding box
    /// scaled per axis onto the normalised box of the context's occupied cells.
    /// Returns the input and the affine map aligned frame -> normalised frame.
    pub fn from_alignment(al: &Alignment, context: Context) -> Result<(HexInput, Affine)> {
        let frame = context_frame(&context)
            .ok_or_else(|| Error::InvalidContext("the context has no occupied cell".into()))?;
        let (lo, hi) = occupied_cell_box(&context.labels).expect("occupied");
        let blo = frame.to_normalised(lo.map(|v| v as f64));
        let bhi = frame.to_normalised(hi.map(|v| v as f64));
        let bb = Aabb::of_points(&al.mesh.vertices);
        let size = bb.size();
        if size.iter().any(|s| !(*s > 0.0)) {
            return Err(Error::InvalidMesh(format!("the aligned input is flat (bounding box {size:?})")));
        }
        let s: [f64; 3] = std::array::from_fn(|a| (bhi[a] - blo[a]) / size[a]);
        let t: [f64; 3] = std::array::from_fn(|a| blo[a] - s[a] * bb.min[a]);
        let a_to_n = Affine::diagonal(s, t);
        let n_to_a = a_to_n.inverse().expect("positive scales");
        let a_to_u = Affine::from_transform(&al.transform.inverse());
        let surface = TriMesh { vertices: al.mesh.vertices.iter().map(|&p| a_to_n.apply(p)).collect(), triangles: al.mesh.triangles.clone() };
        Ok((HexInput { surface, context, correspondence: Vec::new(), to_user: a_to_u.after(&n_to_a) }, a_to_n))
    }

    /// PCA-align a user mesh (geometry::align) and map it as [`HexInput::from_alignment`] does.
    pub fn from_user_mesh(mesh: &TriMesh, context: Context) -> Result<HexInput> {
        let al = crate::geometry::align(mesh)?;
        Ok(Self::from_alignment(&al, context)?.0)
    }
}

/// Options of the hex stage (defaults in [`HexOptions::default`], docs/hex.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HexOptions {
    /// Fix the subdivision level instead of choosing it by the stopping rule.
    pub level: Option<u32>,
    /// Smallest level the stopping rule may choose (default 2).
    pub min_level: u32,
    /// Largest level (default 4).
    pub max_level: u32,
    /// Stopping rule threshold: largest distance between a mapped midpoint and its
    /// linear interpolation, relative to the input's bounding-box diagonal (default 0.005).
    pub threshold: f64,
    /// The stopping rule also stops when the measure of a level is above this fraction
    /// of the previous level's (refining no longer helps; default 0.75).
    pub stall_ratio: f64,
    /// Most elements before pillowing (default 200 000): the stopping rule's level is
    /// capped by it (but not below `min_level`), and the fallback's lattices have at
    /// most this many voxels (none within it: the fallback fails, MESHING_FAILED).
    pub max_elements: usize,
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
    /// Relaxation iterations of the surface map on level 0 (later levels use a third).
    pub surface_relax_iterations: usize,
    /// Use the diffusion correspondence as the seed of the surface map (default
    /// false: with the template-attention default the decoded points sit on the
    /// template in rank order, and seeding the map from them folded cgal_hole at
    /// level 1 — 2 inverted elements, Hausdorff 12.7 % — where the plane fit gives a
    /// valid mesh within 1 %; BENCHMARKS.md "Main job").
    pub use_correspondence: bool,
    /// Without a correspondence, fit the polycube's sub-voxel planes to the input
    /// before mapping (default true).
    pub fit_planes: bool,
    pub pillow: bool,
    /// Passes of mean-ratio smoothing (untangling) over all nodes (default 20).
    pub smooth_iterations: usize,
    /// Optimisation visits the nodes of elements below this scaled Jacobian.
    pub optimise_target: f64,
    pub optimise_passes: usize,
    /// Where elements stay inverted after optimisation, the surface nodes around them
    /// may leave the input by this fraction of the bounding-box diagonal (default 0.002).
    pub release_distance: f64,
    /// Extra random surface samples for the Hausdorff distance.
    pub hausdorff_samples: usize,
    /// When no polycube candidate's mesh meets [`HexOptions::goals`] (with a fixed
    /// `level`: when every one keeps inverted elements), also mesh the input on a
    /// voxel lattice ([`super::voxel`]) and keep that mesh when it ranks better
    /// (default true: on the 16 test parts it gave valid meshes where the
    /// polycube meshes of 6 folded, and meshes within the goals where single-cube
    /// polycubes missed the surface; BENCHMARKS.md "Main job"). The result says so
    /// (`HexResult::domain`). Used by the main job and by sddpm_hex_mesh_build.
    pub voxel_fallback: bool,
    /// Voxels along the longest bounding-box edge of the fallback's first lattice
    /// (default [`super::voxel::VOXEL_START_RESOLUTION`], 24); doubled while the
    /// lattice's topology differs from the input's.
    pub voxel_resolution: usize,
    /// Finer lattices the fallback may try after its first when the mesh misses
    /// [`HexOptions::goals`] (default 2; each within `max_elements`); when one
    /// meets the goals with room to spare, one more at the coarser resolution
    /// predicted to just meet the distance goal (kept when it meets every goal).
    /// 0: the first lattice only.
    pub voxel_refinements: usize,
    /// The quality a mesh should reach (issue 6's goals). Meshes are ranked by
    /// inverted elements, then by how many goals they miss, then by minimum scaled
    /// Jacobian; when the polycube meshes miss one (and the level is automatic), the
    /// voxel fallback is tried too.
    pub goals: QualityGoals,
    /// Return the mapped mesh when the quality steps end below its minimum scaled
    /// Jacobian (default true; false only to inspect the quality steps).
    pub keep_better_mapped: bool,
    /// Coverage step (after smoothing): every input vertex the mesh boundary misses
    /// by more than this fraction of [`QualityGoals::hausdorff`] gets its nearest
    /// free boundary node facing like it, pulled there in steps that keep every
    /// element above min(before, goal + 0.05) and kept there
    /// ([`super::optimize::cover_uncovered_vertices`]); the step is undone unless it
    /// lowers the two-sided Hausdorff distance with no inverted element and a
    /// minimum scaled Jacobian no lower than before or above the goal. Default 0
    /// (off): on the 24-voxel meshes of eight fallback parts at 0.6 it brought
    /// hepta from 2.23 to 1.29 %, spool 2.44 -> 2.30 %, bust 3.12 -> 2.62 % (its
    /// minimum 0.547 -> 0.217), rod 1.92 -> 2.09 %, and was undone on rockerarm,
    /// pinion, dragknob and mambo (BENCHMARKS.md "Coverage").
    pub pin_uncovered: f64,
    /// Sharp-edge capture (after smoothing, before the coverage step): a boundary
    /// node within 0.75 boundary edge lengths of a sharp feature curve whose quads
    /// face both of the curve's faces goes onto the curve (two or more quads on
    /// each side) or half that distance off it onto its majority face (one quad on
    /// the minority side: a staircase step's convex corner), in steps that keep
    /// every element above min(before, goal + 0.05)
    /// ([`super::optimize::capture_features`]); undone unless it lowers the
    /// two-sided Hausdorff distance with no inverted element. Again after the
    /// optimisation, followed by a re-optimisation, on the same terms
    /// ("recapture"). Default true (false: neither step).
    pub capture_features: bool,
    /// Grid-based fallback, local refinement rounds: after the lattices, the best
    /// lattice is meshed again up to this many times, each time with the voxels
    /// around the points farthest from the last mesh (input vertices and boundary
    /// nodes at least 0.8 times the largest distance away) added to the voxels split
    /// 3 x 3 x 3 with conforming transition elements ([`super::refine`]); a round's
    /// mesh is kept when it ranks better by [`QualityGoals::rank`]; the rounds stop
    /// at `max_elements` or once the best meets every goal. Each round meshes the
    /// refined lattice three times (new nodes started on the lattice, on the fitted
    /// coarse mesh, and the split voxels voxelised again at the fine size) and keeps
    /// the best. Default 0 (off): on hexgen_rod at 28 voxels, 1,519 elements at
    /// 1.27 % -> 1,777 at 0.84 % in one round (the default fallback needs 48
    /// voxels, 5,723 elements), but the mean scaled Jacobian drops below its goal
    /// (0.833) and on hexgen_hepta at 12 voxels no round beats the plain lattice
    /// (BENCHMARKS.md "Local refinement").
    pub local_refinement: usize,
    /// Feature sheets (lattice meshes, after pillowing): the boundary quads
    /// labelled with the input patch they lie on (patches: the input split by its
    /// sharp curves), a sheet of elements inserted under each patch's quads within
    /// one ring of another label, and the nodes where labels meet put on the sharp
    /// curve (or the feature corner) between their patches and held there
    /// ([`super::sheets`]); kept even when the smoothing that follows leaves
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
    /// Boundary mean ascent (last quality step): the mean ascent again with the
    /// boundary nodes sliding on the input surface (curve nodes along their
    /// curves, corner nodes fixed), each boundary move kept only when no input
    /// point near the node's quads comes to lie farther from them than before
    /// or than 3/4 of the largest such distance
    /// ([`super::optimize::boundary_mean_ascent`]); the step is kept when the
    /// mean rises with no inverted element, no lower minimum and a two-sided
    /// Hausdorff distance no larger than before. Default true: at one lattice
    /// each with the coverage step, hexgen_rod at 28 voxels mean 0.823 -> 0.832
    /// and 0.69 -> 0.63 %, hexgen_hepta at 12 0.871 -> 0.877 at the same 1.49 %
    /// (BENCHMARKS.md "Boundary mean ascent").
    pub boundary_ascent: bool,
    /// Voxel fallback: the kept lattice is meshed again with its planes moved
    /// onto the input's axis-parallel planar faces of at least this share of
    /// the input's area ([`super::lattice::LatticePlanes::aligned`]), and that
    /// mesh kept when it ranks better ([`QualityGoals::rank`]); 0: the uniform
    /// lattice alone. Default [`LATTICE_PLANES_SHARE`].
    pub lattice_planes: f64,
}

/// Default [`HexOptions::lattice_planes`]: a face of 2 % of the area or more
/// (hexgen_hepta's base, ledge and top: 21 / 8 / 7 %, its flat side 5 %, its
/// lugs' faces 0.8 %; hexgen_rod's two sides 11 / 10 %, its steps 1 % and less).
pub const LATTICE_PLANES_SHARE: f64 = 0.02;

impl Default for HexOptions {
    fn default() -> Self {
        HexOptions {
            level: None,
            min_level: 2,
            max_level: 4,
            threshold: 0.005,
            max_elements: 200_000,
            stall_ratio: 0.75,
            feature_angle: 40.0,
            min_feature_length: 0.03,
            feature_median_angle: 60.0,
            corner_angle: 45.0,
            surface_relax_iterations: 30,
            use_correspondence: false,
            fit_planes: true,
            pillow: true,
            smooth_iterations: 20,
            optimise_target: 0.8,
            optimise_passes: 30,
            release_distance: 0.002,
            hausdorff_samples: 20_000,
            keep_better_mapped: true,
            pin_uncovered: 0.0,
            capture_features: true,
            feature_sheets: true,
            narrow_corner_faces: 70.0,
            narrow_patch_width: 0.75,
            boundary_ascent: true,
            lattice_planes: LATTICE_PLANES_SHARE,
            local_refinement: 0,
            voxel_fallback: true,
            voxel_resolution: super::voxel::VOXEL_START_RESOLUTION,
            voxel_refinements: 2,
            goals: QualityGoals::default(),
        }
    }
}

/// Quality targets of a finished mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct QualityGoals {
    /// Smallest acceptable minimum scaled Jacobian (default 0.3).
    pub min_scaled_jacobian: f64,
    /// Smallest acceptable mean scaled Jacobian (default 0.85).
    pub mean_scaled_jacobian: f64,
    /// Largest acceptable two-sided Hausdorff distance between the mesh boundary and
    /// the input, relative to the bounding-box diagonal (default 0.01).
    pub hausdorff: f64,
}

impl Default for QualityGoals {
    fn default() -> Self {
        QualityGoals { min_scaled_jacobian: 0.3, mean_scaled_jacobian: 0.85, hausdorff: 0.01 }
    }
}

impl QualityGoals {
    /// How many of the three goals `r` misses (a mesh with inverted elements misses
    /// the minimum one whatever the threshold).
    pub fn missed(&self, r: &HexResult) -> usize {
        let q = &r.quality;
        [q.inverted > 0 || !(q.min >= self.min_scaled_jacobian), !(q.mean >= self.mean_scaled_jacobian), !(r.hausdorff_relative <= self.hausdorff)]
            .iter()
            .filter(|&&m| m)
            .count()
    }

    /// Does `r` miss a scaled-Jacobian goal (an inverted element, the minimum or
    /// the mean), whatever its distance?
    pub fn misses_scaled_jacobian(&self, r: &HexResult) -> bool {
        r.quality.inverted > 0 || r.quality.min < self.min_scaled_jacobian || r.quality.mean < self.mean_scaled_jacobian
    }

    /// How far a mesh with these figures falls short of the goals: the sum over the
    /// three of the miss relative to the goal (0 for a goal met): (goal - min) /
    /// goal, (goal - mean) / goal, (distance - goal) / goal. A mesh with inverted
    /// elements falls short of the minimum goal by at least 1.
    pub fn shortfall_of(&self, inverted: usize, min: f64, mean: f64, hausdorff: f64) -> f64 {
        // a NaN figure misses by the most; a goal that is not positive counts nothing
        let rel = |miss: f64, goal: f64| {
            if !(goal > 0.0) {
                0.0
            } else if miss.is_nan() {
                f64::INFINITY
            } else {
                (miss / goal).max(0.0)
            }
        };
        let mut m = rel(self.min_scaled_jacobian - min, self.min_scaled_jacobian);
        if inverted > 0 {
            m = m.max(1.0);
        }
        m + rel(self.mean_scaled_jacobian - mean, self.mean_scaled_jacobian) + rel(hausdorff - self.hausdorff, self.hausdorff)
    }

    /// [`QualityGoals::shortfall_of`] of a mesh.
    pub fn shortfall(&self, r: &HexResult) -> f64 {
        self.shortfall_of(r.quality.inverted, r.quality.min, r.quality.mean, r.hausdorff_relative)
    }

    /// Ranking key of a mesh, smaller is better: inverted elements, goals missed,
    /// how far it falls short of them ([`QualityGoals::shortfall`]; a mesh at 2.4 %
    /// of a 1.5 % distance goal ranks below one at 0.94 % with a minimum of 0.28
    /// for a 0.3 goal), then the minimum scaled Jacobian (higher first).
    pub fn rank(&self, r: &HexResult) -> (usize, usize, f64, f64) {
        (r.quality.inverted, self.missed(r), self.shortfall(r), -r.quality.min)
    }

    /// Is `r` better than `best` by [`QualityGoals::rank`]?
    pub fn beats(&self, r: &HexResult, best: Option<&HexResult>) -> bool {
        best.is_none_or(|b| self.rank(r).partial_cmp(&self.rank(b)) == Some(std::cmp::Ordering::Less))
    }
}

/// One quality step: what it started from and what it produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageReport {
    pub stage: String,
    pub before: QualitySummary,
    pub after: QualitySummary,
    pub nodes: usize,
    pub elements: usize,
    pub seconds: f64,
    pub details: serde_json::Value,
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
    pub stages: Vec<StageReport>,
    /// Which mesh was returned: "optimised" or "mapped" (when the quality steps did not
    /// beat the mapped mesh's minimum scaled Jacobian).
    pub returned: String,
    /// Where the elements come from: "polycube" (the parametric domain of the
    /// polycube, the method of this library) or "voxel N" (the grid-based fallback
    /// of [`super::voxel`] at N voxels along the longest edge).
    pub domain: String,
    pub seconds_total: f64,
}

impl HexResult {
    /// Did the elements come from the polycube (not from the grid-based fallback)?
    pub fn from_polycube(&self) -> bool {
        self.domain == "polycube"
    }
}

pub(crate) fn summary(m: &HexMesh) -> QualitySummary {
    summarize(&element_qualities(m))
}

/// Spread the boundary nodes on the surface (plain tangential Laplacian), take the
/// harmonic interior when it is better than the current one, and fit again.
pub(crate) fn relax_and_refit(work: &mut Work, sw: &Surface, bquads: &[[u32; 4]], opts: &HexOptions, fit_stats: &mut Vec<optimize::FitStats>) {
    let before = work.mesh.nodes.clone();
    let before_attach = work.attach.clone();
    let q0 = summary(&work.mesh);
    map::relax_boundary(sw, &work.role, &work.curve_nb, &work.bgraph, &mut work.mesh.nodes, &mut work.attach, opts.surface_relax_iterations * 2, 0.5);
    let mut harm = work.mesh.nodes.clone();
    map::harmonic_interior(&work.nbr, &work.role, &mut harm, 1e-9, 5000);
    let q_keep = summary(&work.mesh);
    let keep = std::mem::replace(&mut work.mesh.nodes, harm);
    let q_harm = summary(&work.mesh);
    if (q_keep.inverted, -q_keep.min) < (q_harm.inverted, -q_harm.min) {
        work.mesh.nodes = keep;
    }
    let f = optimize::fit_to_surface(work, sw, bquads, opts.surface_relax_iterations, 0.2);
    fit_stats.push(f);
    let q1 = summary(&work.mesh);
    if (q1.inverted, -q1.min) > (q0.inverted, -q0.min) {
        work.mesh.nodes = before;
        work.attach = before_attach;
    }
}

/// Target boxes of the elements of a lattice mesh: their start shape (the warped
/// lattice) in the working frame, as edge lengths along the element axes.
fn element_targets(h: &LatticeHex, warp: &map::Warp, to_w: &Affine) -> Vec<[f64; 3]> {
    let col: [f64; 3] = std::array::from_fn(|a| (0..3).map(|i| to_w.m[i][a] * to_w.m[i][a]).sum::<f64>().sqrt());
    h.elem_lattice
        .iter()
        .map(|&c| {
            let ext = warp.element_extent(c, h.subdiv);
            std::array::from_fn(|a| (ext[a] * col[a]).max(1e-12))
        })
        .collect()
}

/// Boundary quads whose normal opposes the normal of the input at their centre.
fn flipped_quads(sw: &Surface, pos: &[[f64; 3]], quads: &[[u32; 4]]) -> usize {
    quads
        .par_iter()
        .filter(|q| {
            let p = q.map(|i| pos[i as usize]);
            let nq = cross(sub(p[2], p[0]), sub(p[3], p[1]));
            let c = scale(p.iter().fold([0.0; 3], |a, x| add(a, *x)), 0.25);
            let (_, t, _) = sw.closest(c);
            dot(nq, sw.normal(t)) < 0.0
        })
        .count()
}

#[derive(Clone)]
pub(crate) struct Level {
    pub h: LatticeHex,
    pub pos: Vec<[f64; 3]>,
    pub attach: Vec<u32>,
    pub role: Vec<Role>,
    pub curve_nb: Vec<Vec<u32>>,
    pub bquads: Vec<[u32; 4]>,
    /// With the feature sheets, the feature corners (indices into the surface's
    /// feature corners) at which no node is held: the nodes there go onto one of
    /// their curves. Empty: a node at every corner the sheets reach.
    pub released_corners: Vec<u32>,
}

/// Build the all-hex mesh of `input` (see the module docs and docs/hex.md).
pub fn build_hex_mesh(input: &HexInput, opts: &HexOptions, progress: &mut dyn Progress) -> Result<HexResult> {
    let t_all = Instant::now();
    // ---- checks ----
    let validity = input.context.validity();
    if !validity.valid {
        return Err(Error::InvalidContext(format!(
            "the polycube is not a valid solid: {}",
            validity.reason.unwrap_or_default()
        )));
    }
    if input.surface.triangles.is_empty() {
        return Err(Error::InvalidArgument("the input surface has no triangles".into()));
    }
    if input.surface.vertices.iter().flatten().any(|v| !v.is_finite()) || !input.to_user.is_finite() {
        return Err(Error::InvalidArgument("non-finite coordinate in the hex stage input".into()));
    }
    if input.surface.triangles.iter().flatten().any(|&i| i as usize >= input.surface.vertices.len()) {
        return Err(Error::InvalidArgument("a triangle refers to a vertex that does not exist".into()));
    }
    if opts.max_level > 6 || opts.level.is_some_and(|l| l > 6) {
        return Err(Error::InvalidArgument("subdivision levels above 6 are not supported".into()));
    }
    if !(opts.threshold > 0.0) {
        return Err(Error::InvalidArgument(format!("threshold must be positive, got {}", opts.threshold)));
    }
    if input.to_user.inverse().is_none() {
        return Err(Error::InvalidArgument("the map to user coordinates is singular".into()));
    }
    check_progress(progress, 0.0, "hex: setup")?;

    // ---- frames ----
    let frame: BoxFrame = context_frame(&input.context).expect("valid context has cells");
    let grid = input.context.assemble();
    let (fr, mesh_n) = working_frames(&input.surface, &input.to_user, opts)?;
    // the surface in the caller's (normalised) frame, with the same features, for
    // the polycube's plane fit and feature matching
    let sn = Surface::new(mesh_n, fr.sw.features.clone());
    let (sw, to_w, diag_w) = (&fr.sw, fr.to_w, fr.diag_w);
    let corr = if opts.use_correspondence { Correspondence::new(&input.correspondence) } else { None };

    // ---- levels ----
    // start embedding of the polycube: its sub-voxel planes fitted to the input
    // (or the uniform lattice when the correspondence seeds the map)
    let (warp, warp_report) = if opts.fit_planes && corr.is_none() {
        let h0 = lattice_hex(&grid, 0);
        let cells = occupied_cell_box(&input.context.labels).expect("occupied");
        map::fit_warp(&h0, &frame, cells, &sn)
    } else {
        (map::Warp::uniform(&frame), map::WarpReport::default())
    };
    // features are matched on level 1, where every polycube edge has an inner node
    let h1 = lattice_hex(&grid, 1);
    let pos_n1: Vec<[f64; 3]> = h1.mesh.nodes.iter().map(|&g| warp.apply(g)).collect();
    let radius = 0.5 * frame.scale / 3.0;
    let fm: FeatureMatch = map::match_features(&h1, &pos_n1, &sn, radius);
    drop(h1);
    let smap = SurfaceMapReport {
        feature_curves: sw.features.curves.len(),
        feature_corners: sw.features.corners.len(),
        matched_corners: fm.corners.len(),
        matched_chains: fm.chains.len(),
        correspondence_pairs: corr.as_ref().map(|_| input.correspondence.len()).unwrap_or(0),
        planes_fitted: warp_report.planes_fitted,
        max_plane_shift: warp_report.max_shift,
        flipped_quads: 0,
    };
    let max_level = opts.level.unwrap_or(opts.max_level);
    let min_level = opts.level.unwrap_or(opts.min_level.min(max_level));
    let mut levels: Vec<LevelReport> = Vec::new();
    let mut fit_stats: Vec<optimize::FitStats> = Vec::new();
    let mut prev: Option<Level> = None;
    let mut chosen: Option<Level> = None;
    for l in 0..=max_level {
        let t0 = Instant::now();
        check_progress(progress, 0.05 + 0.45 * l as f64 / (max_level + 1) as f64, &format!("hex: mapping level {l}"))?;
        let h = lattice_hex(&grid, l);
        let (role, curve_nb) = map::roles(&h, &fm);
        let masks = map::normal_masks(&h);
        let bquads: Vec<[u32; 4]> = map::boundary_faces_lattice(&h).into_iter().map(|(q, _)| q).collect();
        let bgraph = map::boundary_graph(h.mesh.nodes.len(), &bquads);
        let n = h.mesh.nodes.len();
        let mut work = Work {
            mesh: HexMesh { nodes: Vec::new(), elements: h.mesh.elements.clone() },
            role: role.clone(),
            attach: vec![u32::MAX; n],
            curve_nb: curve_nb.clone(),
            bgraph,
            nbr: Default::default(),
            n2e: Default::default(),
            target: element_targets(&h, &warp, &to_w),
        };
        let e = topology::edges(&h.mesh);
        work.nbr = topology::node_neighbours(n, &e);
        work.n2e = topology::node_elements(&h.mesh);
        let interp = match &prev {
            None => {
                // the polycube itself (plus the correspondence seed) in the working frame
                work.mesh.nodes = h
                    .mesh
                    .nodes
                    .iter()
                    .map(|&g| match corr.as_ref() {
                        Some(c) => {
                            let u = frame.to_normalised(g);
                            to_w.apply(add(u, c.displacement(u, 8)))
                        }
                        None => to_w.apply(warp.apply(g)),
                    })
                    .collect();
                let _ = &masks;
                let f = optimize::fit_to_surface(&mut work, &sw, &bquads, opts.surface_relax_iterations, 0.2);
                fit_stats.push(f);
                relax_and_refit(&mut work, &sw, &bquads, opts, &mut fit_stats);
                None
            }
            Some(pv) => {
                let interp = prolong(&pv.h, &pv.pos, &h);
                let nrm = map::quad_normals(n, &bquads, &interp);
                let mut pos = interp.clone();
                for v in 0..n {
                    match role[v] {
                        Role::Interior => {}
                        Role::Corner(c) => pos[v] = sw.mesh.vertices[c as usize],
                        Role::Curve(c) => pos[v] = sw.closest_on_curve(c as usize, interp[v]).point,
                        Role::Free => {
                            let (q, t, _) = sw.closest_facing(interp[v], nrm[v], 0.0);
                            pos[v] = q;
                            work.attach[v] = t;
                        }
                    }
                }
                // interior: the prolonged positions or the harmonic map, whichever is better
                let mut harm = pos.clone();
                map::harmonic_interior(&work.nbr, &role, &mut harm, 1e-9, 5000);
                work.mesh.nodes = pos;
                let q_pro = summary(&work.mesh);
                let keep = std::mem::replace(&mut work.mesh.nodes, harm);
                let q_harm = summary(&work.mesh);
                if (q_pro.inverted, -q_pro.min) < (q_harm.inverted, -q_harm.min) {
                    work.mesh.nodes = keep;
                }
                if l <= 1 {
                    // the coarse levels define the surface map: fit and spread
                    let f = optimize::fit_to_surface(&mut work, &sw, &bquads, opts.surface_relax_iterations / 2, 0.2);
                    fit_stats.push(f);
                    relax_and_refit(&mut work, &sw, &bquads, opts, &mut fit_stats);
                } else {
                    // finer levels inherit it: only the interior is evened out
                    optimize::untangle(&mut work, &sw, 3, |v| role[v] == Role::Interior);
                }
                Some(interp)
            }
        };
        let pos = work.mesh.nodes;
        let attach = work.attach;
        let cur = Level { h, pos, attach, role, curve_nb, bquads, released_corners: Vec::new() };
        let flipped = flipped_quads(&sw, &cur.pos, &cur.bquads);
        let inverted = summary(&HexMesh { nodes: cur.pos.clone(), elements: cur.h.mesh.elements.clone() }).inverted;
        let rep = LevelReport {
            level: l,
            nodes: cur.pos.len(),
            elements: cur.h.mesh.elements.len(),
            deviation: None,
            flipped_quads: flipped,
            inverted,
            seconds: t0.elapsed().as_secs_f64(),
        };
        // the stopping rule for the previous level
        if let (Some(pv), Some(interp)) = (prev.as_ref(), interp.as_ref()) {
            // chord height: how far the linearly interpolated boundary midpoints are from
            // the surface their mapped counterparts lie on
            let dev: f64 = cur
                .h
                .node_lattice
                .par_iter()
                .enumerate()
                .filter(|(v, lat)| cur.role[*v].on_boundary() && lat.iter().any(|c| c % 2 == 1))
                .map(|(v, _)| sw.closest(interp[v]).2)
                .reduce(|| 0.0, f64::max);
            let dev = dev / diag_w;
            let k = levels.len() - 1;
            levels[k].deviation = Some(dev);
            // a measure that no longer shrinks means refining does not resolve what is
            // left (sharp features no polycube edge follows): stop there as well
            let stalled = k >= 1 && levels[k - 1].deviation.is_some_and(|d0| dev > opts.stall_ratio * d0);
            // refining must not fold the map: a finer level whose share of flipped
            // boundary quads is above twice this one's plus 0.2 % is not taken
            let frac = |f: usize, q: usize| f as f64 / q.max(1) as f64;
            let folds = frac(rep.flipped_quads, cur.bquads.len()) > 2.0 * frac(levels[k].flipped_quads, pv.bquads.len()) + 0.002;
            if opts.level.is_none() && pv.h.level >= min_level && (dev <= opts.threshold || stalled || folds) {
                levels.push(rep);
                chosen = prev.take();
                break;
            }
        }
        levels.push(rep);
        let next_elements = cur.h.mesh.elements.len() * 8;
        let last = l == max_level || (opts.level.is_none() && l >= min_level && next_elements > opts.max_elements);
        if last {
            chosen = Some(cur);
            break;
        }
        prev = Some(cur);
    }
    let lv = chosen.expect("a level is chosen");
    let targets = element_targets(&lv.h, &warp, &to_w);
    // the feature sheets are for lattice meshes (the polycube map puts nodes on the curves itself)
    let opts = &HexOptions { feature_sheets: false, ..opts.clone() };
    finish(lv, targets, smap, levels, serde_json::json!({ "fit": fit_stats }), &fr, opts, t_all, progress)
}

/// The input surface in the working frame W (the user frame centred, scaled to a
/// longest bounding-box edge of 2, mirrored when the map to the user frame reverses
/// orientation), with its sharp features.
pub(crate) struct Frames {
    /// The surface in W, with features.
    pub sw: Surface,
    pub to_w: Affine,
    pub w_to_u: Affine,
    pub mirror: bool,
    pub sw_scale: f64,
    pub diag_w: f64,
}

/// Also returns the surface in the caller's frame, outward oriented.
pub(crate) fn working_frames(surface: &TriMesh, to_user: &Affine, opts: &HexOptions) -> Result<(Frames, TriMesh)> {
    let mut mesh_n = surface.clone();
    if mesh_n.signed_volume() < 0.0 {
        for t in mesh_n.triangles.iter_mut() {
            t.swap(1, 2);
        }
    }
    let user_pts: Vec<[f64; 3]> = mesh_n.vertices.iter().map(|&p| to_user.apply(p)).collect();
    let ubox = Aabb::of_points(&user_pts);
    let longest = ubox.size().iter().copied().fold(0.0, f64::max);
    if !(longest > 0.0) {
        return Err(Error::InvalidArgument("the input surface has no extent".into()));
    }
    let sw_scale = 2.0 / longest;
    // W is U centred and scaled, and mirrored in x when the map to U reverses
    // orientation, so that the lattice's positive elements stay positive in W.
    let mirror = to_user.det() < 0.0;
    let sx = if mirror { -sw_scale } else { sw_scale };
    let c = ubox.centre();
    let u_to_w = Affine::diagonal([sx, sw_scale, sw_scale], [-sx * c[0], -sw_scale * c[1], -sw_scale * c[2]]);
    let to_w = u_to_w.after(to_user);
    let w_to_u = u_to_w.inverse().expect("similarity");
    let mesh_w = TriMesh { vertices: mesh_n.vertices.iter().map(|&p| to_w.apply(p)).collect(), triangles: mesh_n.triangles.clone() };
    let features = detect_features(&mesh_w, opts.feature_angle, opts.corner_angle);
    let diag0 = Aabb::of_points(&mesh_w.vertices).diagonal();
    let features = prune_features(&mesh_w, features, opts.min_feature_length * diag0, opts.feature_median_angle);
    let sw = Surface::new(mesh_w, features);
    let diag_w = sw.bbox.diagonal();
    Ok((Frames { sw, to_w, w_to_u, mirror, sw_scale, diag_w }, mesh_n))
}

/// The per-pass callback of an optimisation loop: reports progress from `lo` over
/// `span` of the range and records a cancel in `cancelled` (true stops the loop).
fn pass_reporter<'a, P: Progress + ?Sized>(progress: &'a mut P, lo: f64, span: f64, passes: usize, cancelled: &'a mut bool) -> impl FnMut(usize) -> bool + 'a {
    move |p| {
        let ok = progress.report(lo + span * p as f64 / passes.max(1) as f64, "hex: optimisation");
        if !ok {
            *cancelled = true;
        }
        !ok
    }
}

/// How near a sharp curve (in mean boundary edge lengths) a boundary node must be
/// for the capture step to move it (0.5 / 0.75 / 1.0 / 1.5 measured on hepta and
/// rod at HexGen-like counts: BENCHMARKS.md "Sharp-edge capture").
const CAPTURE_REACH: f64 = 0.75;

/// How near its sharp curve or corner (in mean boundary edge lengths) a node where
/// two patch labels meet must be for the feature sheets to put it there.
const SHEET_REACH: f64 = 1.5;

/// Mean length of the boundary edges of a mesh (0 without a boundary).
fn mean_boundary_edge(w: &Work) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in 0..w.mesh.nodes.len() {
        for &u in w.bgraph.of(v) {
            sum += norm(sub(w.mesh.nodes[u as usize], w.mesh.nodes[v]));
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// A step that moves boundary nodes (capture, coverage, the boundary mean ascent),
/// undone unless `keep(before, after, h0, h1)` holds for the quality before and
/// after and the two-sided Hausdorff distances before and after; for the steps
/// towards the input [`fit_step_kept`]: closer to it without an inverted element or
/// a minimum below both the one before and the goal (with `hold_mean`, nor a mean
/// below both the one before and its goal: for a step after the optimisation,
/// whose mesh is the result). `step` gets
/// the floor no element may go below (min(before, goal + 0.05)) and says whether it
/// had anything to do (else no stage is reported), whether it moved a node, and its
/// details.
fn guarded_fit_step(
    work: &mut Work,
    sw: &Surface,
    opts: &HexOptions,
    name: &str,
    keep: impl FnOnce(&QualitySummary, &QualitySummary, f64, f64) -> bool,
    stages: &mut Vec<StageReport>,
    step: impl FnOnce(&mut Work, f64) -> (bool, bool, serde_json::Value),
) {
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let saved = (work.mesh.nodes.clone(), work.role.clone(), work.attach.clone());
    let floor = before.min.min(opts.goals.min_scaled_jacobian + 0.05).max(0.0);
    let (attempted, moved, mut details) = step(work, floor);
    if !attempted {
        return;
    }
    let after = summary(&work.mesh);
    let h0 = hausdorff(&HexMesh { nodes: saved.0.clone(), elements: work.mesh.elements.clone() }, &sw.mesh, opts.hausdorff_samples).relative;
    let h1 = if moved { hausdorff(&work.mesh, &sw.mesh, opts.hausdorff_samples).relative } else { h0 };
    let kept = moved && keep(&before, &after, h0, h1);
    if !kept {
        (work.mesh.nodes, work.role, work.attach) = saved;
    }
    if let Some(d) = details.as_object_mut() {
        d.insert("hausdorff_relative_before".into(), serde_json::json!(h0));
        d.insert("hausdorff_relative_after".into(), serde_json::json!(h1));
        d.insert("kept".into(), serde_json::json!(kept));
    }
    stages.push(stage_report(name, before, &work.mesh, t0, details));
}

/// Whether a fit step that moved nodes is kept ([`guarded_fit_step`]): the distance
/// falls (`h1 < h0`), nothing is inverted, the minimum is at least the one before or
/// meets its goal, and with `hold_mean` so is the mean.
fn fit_step_kept(before: &QualitySummary, after: &QualitySummary, h0: f64, h1: f64, goals: &QualityGoals, hold_mean: bool) -> bool {
    h1 < h0
        && after.inverted == 0
        && (after.min >= before.min || after.min >= goals.min_scaled_jacobian)
        && (!hold_mean || after.mean >= before.mean || after.mean >= goals.mean_scaled_jacobian)
}

/// The report of a quality step that started at `t0` from `before` and left `mesh`.
fn stage_report(stage: &str, before: QualitySummary, mesh: &HexMesh, t0: Instant, details: serde_json::Value) -> StageReport {
    StageReport { stage: stage.into(), before, after: summary(mesh), nodes: mesh.nodes.len(), elements: mesh.elements.len(), seconds: t0.elapsed().as_secs_f64(), details }
}

/// The quality steps and the result, from the mapped mesh of the chosen level:
/// pillowing, smoothing, the capture and coverage steps when asked for,
/// optimisation, the release of folded boundary nodes, the recapture (with the
/// capture), the Hausdorff distance, and the mesh back in user coordinates.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish(
    lv: Level,
    targets: Vec<[f64; 3]>,
    mut smap: SurfaceMapReport,
    levels: Vec<LevelReport>,
    map_details: serde_json::Value,
    fr: &Frames,
    opts: &HexOptions,
    t_all: Instant,
    progress: &mut dyn Progress,
) -> Result<HexResult> {
    let (sw, w_to_u, mirror, sw_scale, diag_w) = (&fr.sw, fr.w_to_u, fr.mirror, fr.sw_scale, fr.diag_w);
    let level = lv.h.level;
    // ---- mapped mesh ----
    let mut work = Work {
        mesh: HexMesh { nodes: lv.pos.clone(), elements: lv.h.mesh.elements.clone() },
        role: lv.role.clone(),
        attach: lv.attach.clone(),
        curve_nb: lv.curve_nb.clone(),
        bgraph: Default::default(),
        nbr: Default::default(),
        n2e: Default::default(),
        target: targets,
    };
    work.rebuild();
    smap.flipped_quads = flipped_quads(&sw, &work.mesh.nodes, &lv.bquads);
    let mapped = work.mesh.clone();
    let q_mapped = summary(&mapped);
    let mut stages = vec![StageReport {
        stage: "mapping".into(),
        before: QualitySummary::default(),
        after: q_mapped,
        nodes: mapped.nodes.len(),
        elements: mapped.elements.len(),
        seconds: levels.iter().map(|l| l.seconds).sum(),
        details: {
            let mut d = serde_json::json!({ "level": level, "flipped_boundary_quads": smap.flipped_quads });
            if let (Some(d), serde_json::Value::Object(extra)) = (d.as_object_mut(), map_details) {
                d.extend(extra);
            }
            d
        },
    }];

    // ---- pillowing ----
    if opts.pillow {
        check_progress(progress, 0.55, "hex: pillowing")?;
        let t0 = Instant::now();
        let before = q_mapped;
        let rep: PillowReport = pillow(&mut work)?;
        stages.push(stage_report("pillowing", before, &work.mesh, t0, serde_json::to_value(&rep).unwrap_or_default()));
    }

    // ---- feature sheets: a sheet under each surface patch, the paths between
    // them onto the sharp curves (lattice meshes, whose nodes are not on curves
    // yet); smoothed at once. Kept even when the smoothing leaves inverted
    // elements (faces narrower than the voxels): the steps below untangle most of
    // them, and the fallback compares the result with the mesh without the
    // sheets (voxel::mesh_lattice) ----
    let mut smoothed = None;
    if opts.feature_sheets && opts.pillow && work.role.iter().all(|r| matches!(r, Role::Free | Role::Interior)) && !sw.features.curves.is_empty() {
        check_progress(progress, 0.58, "hex: feature sheets")?;
        let t0 = Instant::now();
        let before = summary(&work.mesh);
        let elements_before = work.mesh.elements.len();
        let edge = mean_boundary_edge(&work);
        let mut details = match super::sheets::feature_sheets(&mut work, sw, SHEET_REACH * edge, &lv.released_corners, opts.narrow_corner_faces, opts.narrow_patch_width * edge) {
            Ok(rep) => serde_json::to_value(&rep).unwrap_or_default(),
            Err(e) => serde_json::json!({ "error": e.to_string() }),
        };
        let inserted = work.mesh.elements.len() > elements_before;
        if let Some(d) = details.as_object_mut() {
            d.insert("kept".into(), serde_json::json!(inserted));
        }
        if inserted {
            let before_smooth = summary(&work.mesh);
            let t1 = Instant::now();
            let st: MoveStats = optimize::untangle(&mut work, sw, opts.smooth_iterations, |_| true);
            let after = summary(&work.mesh);
            if let Some(d) = details.as_object_mut() {
                d.insert("inverted_after_smoothing".into(), serde_json::json!(after.inverted));
            }
            smoothed = Some(stage_report("smoothing", before_smooth, &work.mesh, t1, serde_json::to_value(st).unwrap_or_default()));
        }
        stages.push(stage_report("feature sheets", before, &work.mesh, t0, details));
    }
    // ---- smoothing: mean-ratio energy of the corners (untangles, then evens out) ----
    check_progress(progress, 0.6, "hex: smoothing")?;
    match smoothed {
        Some(st) => stages.push(st),
        None => {
            let t0 = Instant::now();
            let before = summary(&work.mesh);
            let st: MoveStats = optimize::untangle(&mut work, &sw, opts.smooth_iterations, |_| true);
            stages.push(stage_report("smoothing", before, &work.mesh, t0, serde_json::to_value(st).unwrap_or_default()));
        }
    }
    // ---- sharp-edge capture: boundary nodes onto the feature curves near them ----
    if opts.capture_features {
        let reach = CAPTURE_REACH * mean_boundary_edge(&work);
        guarded_fit_step(&mut work, sw, opts, "capture", |b, a, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, false), &mut stages, |w, floor| {
            let st = optimize::capture_features(w, sw, reach, opts.surface_relax_iterations, floor);
            (st.candidates > 0, st.snapped + st.lifted > 0, serde_json::to_value(st).unwrap_or_default())
        });
    }

    // ---- coverage: boundary nodes pinned to the input vertices the boundary misses ----
    if opts.pin_uncovered > 0.0 && opts.goals.hausdorff > 0.0 {
        let tol = opts.pin_uncovered * opts.goals.hausdorff * sw.bbox.diagonal();
        guarded_fit_step(&mut work, sw, opts, "coverage", |b, a, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, false), &mut stages, |w, floor| {
            let st = optimize::cover_uncovered_vertices(w, sw, tol, opts.surface_relax_iterations, floor);
            (st.uncovered > 0, st.pinned > 0, serde_json::to_value(st).unwrap_or_default())
        });
    }

    // ---- optimisation ----
    check_progress(progress, 0.65, "hex: optimisation")?;
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let passes = opts.optimise_passes;
    let mut cancelled = false;
    let mut st = optimize::optimise(&mut work, &sw, opts.optimise_target, passes, pass_reporter(progress, 0.65, 0.2, passes, &mut cancelled));
    if cancelled {
        return Err(Error::Cancelled("hex: optimisation".into()));
    }
    // polish: the mean-ratio energy again, now never below the minimum reached
    if passes > 0 {
        check_progress(progress, 0.88, "hex: optimisation")?;
        let floor = summary(&work.mesh).min;
        let p = optimize::mean_ratio_smooth(&mut work, &sw, opts.smooth_iterations, Some(floor.max(0.0)), |_| true);
        let p2 = optimize::optimise(&mut work, &sw, opts.optimise_target, passes / 2, |_| false);
        st.passes += p.passes + p2.passes;
        st.moves_tried += p.moves_tried + p2.moves_tried;
        st.moves_accepted += p.moves_accepted + p2.moves_accepted;
    }
    // mean ascent of the interior nodes: raise the mean scaled Jacobian, never below
    // the minimum reached
    let mut ascent = MoveStats::default();
    let q = summary(&work.mesh);
    let mean_before_ascent = q.mean;
    if passes > 0 && q.inverted == 0 {
        check_progress(progress, 0.9, "hex: optimisation")?;
        ascent = optimize::mean_ascent(&mut work, passes, q.min, pass_reporter(progress, 0.9, 0.05, passes, &mut cancelled));
        if cancelled {
            return Err(Error::Cancelled("hex: optimisation".into()));
        }
    }
    // where elements are still inverted, the boundary itself is folded: let the
    // boundary nodes of the bad elements (and their ring) leave the input by a little
    // (mean ascent runs only without them and cannot invert one: `q` still counts them)
    let mut released_nodes = 0usize;
    if opts.release_distance > 0.0 && q.inverted > 0 {
        let sj = element_qualities(&work.mesh);
        let mut rel = vec![false; work.mesh.nodes.len()];
        for (e, el) in work.mesh.elements.iter().enumerate() {
            if sj[e] <= 0.05 || sj[e] == super::quality::DEGENERATE {
                for &v in el {
                    rel[v as usize] = true;
                    for &u in work.nbr.of(v as usize) {
                        rel[u as usize] = true;
                    }
                }
            }
        }
        for v in 0..rel.len() {
            rel[v] &= work.role[v].on_boundary();
        }
        released_nodes = rel.iter().filter(|&&b| b).count();
        let leave = opts.release_distance * diag_w;
        let keep = (work.mesh.nodes.clone(), work.attach.clone());
        optimize::mean_ratio_smooth_released(&mut work, &sw, opts.smooth_iterations, None, |_| true, &rel, leave);
        optimize::optimise(&mut work, &sw, opts.optimise_target, passes / 2, |_| false);
        let q1 = summary(&work.mesh);
        if (q1.inverted, -q1.min) > (q.inverted, -q.min) {
            work.mesh.nodes = keep.0;
            work.attach = keep.1;
            released_nodes = 0;
        }
    }
    stages.push(stage_report("optimisation", before, &work.mesh, t0, serde_json::json!({ "moves": st, "mean_ascent": ascent, "mean_before_ascent": mean_before_ascent, "released_boundary_nodes": released_nodes })));

    // ---- sharp-edge capture again on the optimised mesh, then re-optimised ----
    // The optimisation slides boundary nodes along the surface, off the curves the
    // first capture put them on or nearer to: capture once more, optimise and
    // raise the mean again, keep it all only when the distance falls and the
    // minimum and the mean hold (each at least as before or meeting its goal:
    // the mesh is final now; hexgen_hepta at 36 voxels: 1.67 -> 1.31 %, at 12: 1.77 ->
    // 1.49 % with the coverage step; undone on hexgen_rod at 28 and 36).
    if opts.capture_features && passes > 0 && summary(&work.mesh).inverted == 0 {
        check_progress(progress, 0.95, "hex: recapture")?;
        let reach = CAPTURE_REACH * mean_boundary_edge(&work);
        guarded_fit_step(&mut work, sw, opts, "recapture", |b, a, h0, h1| fit_step_kept(b, a, h0, h1, &opts.goals, true), &mut stages, |w, floor| {
            let st = optimize::capture_features(w, sw, reach, opts.surface_relax_iterations, floor);
            let moved = st.snapped + st.lifted > 0;
            let mut details = serde_json::to_value(st).unwrap_or_default();
            if moved {
                let o = optimize::optimise(w, sw, opts.optimise_target, passes, pass_reporter(progress, 0.95, 0.005, passes, &mut cancelled));
                let m = summary(&w.mesh).min;
                let a = optimize::mean_ascent(w, passes, m, pass_reporter(progress, 0.955, 0.005, passes, &mut cancelled));
                if let Some(d) = details.as_object_mut() {
                    d.insert("moves".into(), serde_json::to_value(o).unwrap_or_default());
                    d.insert("mean_ascent".into(), serde_json::to_value(a).unwrap_or_default());
                }
            }
            (st.candidates > 0, moved, details)
        });
        if cancelled {
            return Err(Error::Cancelled("hex: recapture".into()));
        }
    }
    // ---- boundary mean ascent: the boundary nodes slide too, kept when the fit holds ----
    if opts.boundary_ascent && passes > 0 && summary(&work.mesh).inverted == 0 {
        check_progress(progress, 0.958, "hex: boundary ascent")?;
        let keep = |before: &QualitySummary, after: &QualitySummary, h0: f64, h1: f64| {
            after.mean > before.mean && after.inverted == 0 && after.min >= before.min && h1 <= h0
        };
        guarded_fit_step(&mut work, sw, opts, "boundary ascent", keep, &mut stages, |w, _| {
            let m = summary(&w.mesh).min;
            let released = optimize::release_pins(w, sw);
            let st = optimize::boundary_mean_ascent(w, sw, passes, m, pass_reporter(progress, 0.958, 0.002, passes, &mut cancelled));
            let mut details = serde_json::to_value(st).unwrap_or_default();
            if let Some(d) = details.as_object_mut() {
                d.insert("mean_after_ascent".into(), serde_json::json!(summary(&w.mesh).mean));
                d.insert("pins_released".into(), serde_json::json!(released));
            }
            (true, st.moves_accepted > 0, details)
        });
        if cancelled {
            return Err(Error::Cancelled("hex: boundary ascent".into()));
        }
    }
    let q_final = summary(&work.mesh);

    // ---- never worse than the mapped mesh ----
    let mut mapped_u = mapped.clone();
    for p in mapped_u.nodes.iter_mut() {
        *p = w_to_u.apply(*p);
    }
    if mirror {
        for e in mapped_u.elements.iter_mut() {
            *e = [e[4], e[5], e[6], e[7], e[0], e[1], e[2], e[3]];
        }
    }
    let (mut out, returned) = if q_final.min >= q_mapped.min || !opts.keep_better_mapped { (work.mesh, "optimised") } else { (mapped, "mapped") };
    check_progress(progress, 0.96, "hex: distances")?;
    let haus_w = hausdorff(&out, &sw.mesh, opts.hausdorff_samples);
    let s_inv = 1.0 / sw_scale;
    let haus = Hausdorff {
        hex_to_surface: haus_w.hex_to_surface * s_inv,
        surface_to_hex: haus_w.surface_to_hex * s_inv,
        distance: haus_w.distance * s_inv,
        ..haus_w
    };
    for p in out.nodes.iter_mut() {
        *p = w_to_u.apply(*p);
    }
    if mirror {
        for e in out.elements.iter_mut() {
            *e = [e[4], e[5], e[6], e[7], e[0], e[1], e[2], e[3]];
        }
    }
    let input_volume = sw.mesh.signed_volume() * s_inv.powi(3);
    let volume = mesh_volume(&out);
    let sj = element_qualities(&out);
    let quality = summarize(&sj);
    check_progress(progress, 1.0, "hex: done")?;
    Ok(HexResult {
        mesh: out,
        mapped: mapped_u,
        level,
        histogram: histogram(&sj, 20),
        scaled_jacobian: sj,
        quality,
        hausdorff: haus,
        hausdorff_relative: haus.relative,
        volume,
        input_volume,
        levels,
        surface_map: smap,
        stages,
        returned: returned.into(),
        domain: "polycube".into(),
        seconds_total: t_all.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::trimesh::tests::box_mesh;

    #[test]
    fn unit_box_maps_to_a_perfect_grid() {
        let ctx = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
        let input = HexInput {
            surface: box_mesh([-1.0; 3], [1.0; 3]),
            context: ctx,
            correspondence: vec![],
            to_user: Affine::similarity(0.5, [0.5; 3]),
        };
        let opts = HexOptions { level: Some(1), pillow: true, ..Default::default() };
        let r = build_hex_mesh(&input, &opts, &mut crate::error::NoProgress).unwrap();
        assert!((r.stages[0].after.min - 1.0).abs() < 1e-12);
        assert!(r.quality.min >= r.stages[0].after.min);
    }

    #[test]
    fn a_fit_step_is_kept_only_when_closer_and_the_quality_holds() {
        let g = QualityGoals::default();
        let q = |min: f64, mean: f64, inverted: usize| QualitySummary { elements: 10, min, mean, max: 1.0, inverted };
        let before = q(0.5, 0.9, 0);
        // closer, quality as before: kept; not closer: undone
        assert!(fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, 0.01, &g, true));
        assert!(!fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, 0.02, &g, true));
        assert!(!fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, f64::NAN, &g, true));
        // an inverted element: undone
        assert!(!fit_step_kept(&before, &q(-0.1, 0.9, 1), 0.02, 0.01, &g, false));
        // the minimum may fall as long as it meets its goal (0.3)
        assert!(fit_step_kept(&before, &q(0.31, 0.9, 0), 0.02, 0.01, &g, false));
        assert!(!fit_step_kept(&before, &q(0.29, 0.9, 0), 0.02, 0.01, &g, false));
        assert!(fit_step_kept(&q(0.2, 0.9, 0), &q(0.25, 0.9, 0), 0.02, 0.01, &g, false));
        // the mean (goal 0.85) counts only for a step on the final mesh
        assert!(fit_step_kept(&before, &q(0.5, 0.84, 0), 0.02, 0.01, &g, false));
        assert!(!fit_step_kept(&before, &q(0.5, 0.84, 0), 0.02, 0.01, &g, true));
        assert!(fit_step_kept(&before, &q(0.5, 0.86, 0), 0.02, 0.01, &g, true));
        assert!(fit_step_kept(&q(0.5, 0.8, 0), &q(0.5, 0.81, 0), 0.02, 0.01, &g, true));
    }

    #[test]
    fn meshes_missing_as_many_goals_rank_by_how_far_they_miss() {
        let input = HexInput {
            surface: box_mesh([-1.0; 3], [1.0; 3]),
            context: Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap(),
            correspondence: vec![],
            to_user: Affine::similarity(1.0, [0.0; 3]),
        };
        let r = build_hex_mesh(&input, &HexOptions { level: Some(1), ..Default::default() }, &mut crate::error::NoProgress).unwrap();
        let with = |min: f64, mean: f64, inverted: usize, h: f64| {
            let mut m = r.clone();
            (m.quality.min, m.quality.mean, m.quality.inverted, m.hausdorff_relative) = (min, mean, inverted, h);
            m
        };
        // cgal_spool's lattices with a 1.5 % distance goal (measured): 24 voxels at
        // 2.44 % with min 0.389, 65 voxels at 0.94 % with min 0.281; each misses one
        let goals = QualityGoals { hausdorff: 0.015, ..Default::default() };
        let (coarse, fine) = (with(0.389, 0.95, 0, 0.0244), with(0.281, 0.95, 0, 0.0094));
        assert_eq!((goals.missed(&coarse), goals.missed(&fine)), (1, 1));
        assert!((goals.shortfall(&coarse) - (0.0244 - 0.015) / 0.015).abs() < 1e-12);
        assert!((goals.shortfall(&fine) - (0.3 - 0.281) / 0.3).abs() < 1e-12);
        assert!(goals.beats(&fine, Some(&coarse)) && !goals.beats(&coarse, Some(&fine)));
        // meeting every goal: the higher minimum wins, as before
        let (a, b) = (with(0.5, 0.9, 0, 0.009), with(0.6, 0.86, 0, 0.0099));
        assert_eq!(goals.shortfall(&a), 0.0);
        assert!(goals.beats(&b, Some(&a)));
        // inverted elements first, however close the rest; then goals missed
        let inverted = with(-0.01, 0.95, 1, 0.001);
        assert!(goals.shortfall(&inverted) >= 1.0);
        assert!(goals.beats(&with(0.1, 0.5, 0, 0.5), Some(&inverted)));
        assert!(goals.beats(&with(0.29, 0.9, 0, 0.001), Some(&with(0.31, 0.84, 0, 0.02))));
        // a NaN figure ranks last among meshes missing as many goals
        assert!(goals.shortfall(&with(0.5, 0.9, 0, f64::NAN)).is_infinite());
        assert!(goals.beats(&with(0.5, 0.9, 0, 0.9), Some(&with(0.5, 0.9, 0, f64::NAN))));
    }
}

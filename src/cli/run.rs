//! `sddpm run MESH -o DIR [polycube options] [--level N] [--no-spline] [fallback options] [quality goals]`: the main job.

use super::common::{load_checked, Loaded};
use super::polycube::{load_generator, options_of, request_of, PolycubeArgs};
use sddpm::error::{Error, Progress};
use sddpm::hex::{HexOption, HexOptions, SurfaceMap};
use sddpm::pipeline::report::{write_run_folder, InputInfo};
use sddpm::pipeline::{run as run_job, RunOptions, RunResult};
use sddpm::Result;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub polycube: PolycubeArgs,
    /// Stop after the hex mesh (no spline.bext / model.k).
    #[arg(long)]
    pub no_spline: bool,
    /// Write an output folder that is not empty: first remove the files sddpm writes
    /// (report.json, hex.*, spline.*, ...; other files are kept). Without it a
    /// non-empty folder is refused.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub spline_files: SplineFileArgs,
    /// Refuse (exit 2) when no candidate passes verification instead of meshing the
    /// best-fitting unverified one, and when the hex mesh keeps inverted elements.
    #[arg(long)]
    pub strict: bool,
    /// How many candidates are meshed (verified ones, else unverified ones by fit); the best mesh is kept (default 4).
    #[arg(long)]
    pub hex_candidates: Option<usize>,
    #[command(flatten)]
    pub hex: HexArgs,
}

/// How spline.bext is written, shared by `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct SplineFileArgs {
    /// Dense BEXT operator rows (64 entries each, as Hex2Spline writes them) instead of the default sparse rows.
    #[arg(long)]
    pub dense_bext: bool,
    /// Absolute tolerance of the BEXT operator entries: each is written with the fewest decimals that read back within it (default 1e-8; 0: exact).
    #[arg(long, value_name = "T")]
    pub bext_tolerance: Option<f64>,
}

/// Apply the spline-file arguments to the run's spline options (none without a spline).
pub fn spline_file_options(a: &SplineFileArgs, opts: &mut RunOptions) -> Result<()> {
    if let Some(t) = a.bext_tolerance {
        if !(t.is_finite() && t >= 0.0) {
            return Err(Error::InvalidArgument(format!("--bext-tolerance must be a finite number >= 0, got {t}")));
        }
    }
    if let Some(so) = opts.spline.as_mut() {
        if a.dense_bext {
            so.sparse_bext = false;
        }
        if let Some(t) = a.bext_tolerance {
            so.bext_tolerance = t;
        }
    }
    Ok(())
}

/// The hex stage's options, shared by `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct HexArgs {
    /// Fix the octree subdivision level (default: chosen by the stopping rule).
    #[arg(long)]
    pub level: Option<u32>,
    /// Surface map of the polycube path: projection (closest facing point and relaxation, the default) or charts (inverse chart maps; the projection where a chart does not map; docs/hex.md).
    #[arg(long, value_name = "METHOD")]
    pub surface_map: Option<String>,
    /// The grid-based fallback's first lattice: voxels along the longest bounding-box edge (default 24).
    #[arg(long)]
    pub voxel_resolution: Option<usize>,
    /// How many finer lattices the fallback may try after the first (default 2; 0: that lattice only).
    #[arg(long)]
    pub voxel_refinements: Option<usize>,
    /// No sharp-edge capture (by default boundary nodes near the input's sharp edges go onto them; docs/hex.md).
    #[arg(long)]
    pub no_capture_features: bool,
    /// No feature sheets (by default the fallback's lattice meshes get a sheet of elements under each surface patch so that their boundary follows the sharp curves; docs/hex.md).
    #[arg(long)]
    pub no_feature_sheets: bool,
    /// Feature curves whose median dihedral angle is below DEG degrees are ignored (default 60: creases of CAD parts, not facets of a coarse tessellation; e.g. 40 to follow 45-degree chamfers; docs/hex.md "Surface map").
    #[arg(long, value_name = "DEG")]
    pub feature_median_angle: Option<f64>,
    /// The fallback's kept lattice is meshed again with its planes on the input's axis-parallel planar faces of at least F of its area, and kept when it ranks better (default 0.02; 0: off; docs/hex.md "Lattice planes on the faces").
    #[arg(long, value_name = "F")]
    pub lattice_planes: Option<f64>,
    /// Coverage step: pin nodes to input vertices farther than F times the distance goal (e.g. 0.6; off by default).
    #[arg(long, value_name = "F")]
    pub pin_uncovered: Option<f64>,
    /// Local refinement: up to N rounds that split the fallback's voxels around the points farthest from its mesh 3 x 3 x 3, with conforming transition elements (off by default; docs/hex.md).
    #[arg(long, value_name = "N")]
    pub local_refinement: Option<usize>,
    /// Quality goal: smallest acceptable minimum scaled Jacobian, in (-1, 1] (default 0.3). Meshes are ranked by the goals they miss; the fallback refines its lattice while the best misses one.
    #[arg(long, value_name = "S")]
    pub goal_min_sj: Option<f64>,
    /// Quality goal: smallest acceptable mean scaled Jacobian, in (-1, 1] (default 0.85).
    #[arg(long, value_name = "S")]
    pub goal_mean_sj: Option<f64>,
    /// Quality goal: largest acceptable two-sided Hausdorff distance between the mesh boundary and the input, relative to the bounding-box diagonal, > 0 (default 0.01; e.g. 0.02 for a coarser control mesh).
    #[arg(long, value_name = "D")]
    pub goal_hausdorff: Option<f64>,
    /// Most elements a mesh may have before pillowing: caps the automatic octree level (not below its minimum, 2) and the fallback's lattices (default 200000).
    #[arg(long, value_name = "N")]
    pub max_elements: Option<usize>,
}

/// The hex-stage options of the arguments on top of `hex`, checked by
/// [`HexOptions::validate`] (an out-of-range value is an error naming its flag).
pub fn hex_options(a: &HexArgs, hex: &mut HexOptions) -> Result<()> {
    hex.map.level = a.level;
    match a.surface_map.as_deref() {
        None => {}
        Some("projection") => hex.map.surface_map = SurfaceMap::Projection,
        Some("charts") => hex.map.surface_map = SurfaceMap::Charts,
        Some(o) => return Err(Error::InvalidArgument(format!("--surface-map must be projection or charts, got {o:?}"))),
    }
    if let Some(n) = a.voxel_resolution {
        hex.fallback.resolution = n;
    }
    if let Some(n) = a.voxel_refinements {
        hex.fallback.refinements = n;
    }
    hex.quality.capture_features = !a.no_capture_features;
    hex.quality.feature_sheets = !a.no_feature_sheets;
    if let Some(n) = a.local_refinement {
        hex.fallback.local_refinement = n;
    }
    if let Some(d) = a.feature_median_angle {
        hex.surface.feature_median_angle = d;
    }
    if let Some(f) = a.lattice_planes {
        hex.fallback.lattice_planes = f;
    }
    if let Some(f) = a.pin_uncovered {
        hex.quality.pin_uncovered = f;
    }
    if let Some(s) = a.goal_min_sj {
        hex.goals.min_scaled_jacobian = s;
    }
    if let Some(s) = a.goal_mean_sj {
        hex.goals.mean_scaled_jacobian = s;
    }
    if let Some(d) = a.goal_hausdorff {
        hex.goals.hausdorff = d;
    }
    if let Some(n) = a.max_elements {
        hex.max_elements = n;
    }
    hex.validate().map_err(|e| Error::InvalidArgument(format!("{} must be {}, got {}", flag(e.option), e.expected, e.value)))
}

/// The flag of `sddpm run` that sets a hex option (the core's path for the
/// options no flag sets, whose defaults are valid).
fn flag(o: HexOption) -> &'static str {
    match o {
        HexOption::Level => "--level",
        HexOption::VoxelResolution => "--voxel-resolution",
        HexOption::FeatureMedianAngle => "--feature-median-angle",
        HexOption::LatticePlanes => "--lattice-planes",
        HexOption::PinUncovered => "--pin-uncovered",
        HexOption::GoalMinScaledJacobian => "--goal-min-sj",
        HexOption::GoalMeanScaledJacobian => "--goal-mean-sj",
        HexOption::GoalHausdorff => "--goal-hausdorff",
        HexOption::MaxElements => "--max-elements",
        other => other.path(),
    }
}

/// What the main job wrote: report.json's content and the run's result.
pub struct RunDone {
    pub report: serde_json::Value,
    pub result: RunResult,
    pub seconds: f64,
}

/// The main job of `sddpm run` into its output folder: every check, the pipeline
/// and every file the command writes, with progress through `progress` and
/// `command` as report.json's "command". Prints nothing (the command and the C
/// ABI's sddpm_run both call it).
pub fn run_folder(a: &RunArgs, progress: &mut dyn Progress, command: &str) -> Result<RunDone> {
    let t0 = std::time::Instant::now();
    let p = &a.polycube;
    let mut opts = RunOptions::default();
    hex_options(&a.hex, &mut opts.hex)?;
    let Loaded { mesh, report, path } = load_checked(&p.mesh, p.weld_tolerance)?;
    let genus = report.genus.ok_or_else(|| Error::InvalidMesh("the genus of the input is undefined".into()))?;
    let request = request_of(p)?;
    let model = load_generator(p)?;
    opts.polycube = options_of(p)?;
    if a.no_spline {
        opts.spline = None;
    }
    spline_file_options(&a.spline_files, &mut opts)?;
    opts.validate()?;
    super::common::prepare_output(&p.output, a.force)?;
    opts.accept_unverified = !a.strict;
    opts.require_valid_hex = a.strict;
    if let Some(n) = a.hex_candidates {
        opts.hex_candidates = n;
    }
    let r = run_job(&model, &mesh, genus, &request, &opts, progress)?;
    let input = InputInfo { path: &path, mesh: &mesh, report: &report, command: Some(command) };
    let j = write_run_folder(&p.output, &input, &r, t0.elapsed().as_secs_f64())?;
    Ok(RunDone { report: j, result: r, seconds: t0.elapsed().as_secs_f64() })
}

/// The warnings of a finished run (also in report.json: `polycube.verification_error`
/// and the hex attempts).
pub fn warnings(r: &RunResult) -> Vec<String> {
    let mut w = Vec::new();
    if let Some(e) = &r.verification_error {
        if r.hex.from_polycube() {
            w.push(format!("no candidate passed verification; meshed the best-fitting unverified candidate ({e})"));
        } else {
            w.push(format!("the mesh comes from the grid-based fallback, not from a polycube: {e}"));
        }
    }
    if let Some(e) = r.hex_attempts.iter().filter(|t| t.candidate.is_none()).find_map(|t| t.error.as_ref()) {
        w.push(format!("the grid-based fallback was tried and failed ({e}); the hex mesh is the best polycube mesh, which misses the quality goals"));
    }
    w
}

pub fn run(a: &RunArgs) -> Result<i32> {
    let p = &a.polycube;
    let mut progress = super::common::progress_bar(p.quiet);
    let RunDone { report: j, result: r, seconds } = run_folder(a, &mut progress, &super::common::command_line())?;
    if !p.quiet || p.json {
        for w in warnings(&r) {
            eprintln!("warning: {w}");
        }
    }
    if p.json {
        println!("{j}");
    } else if !p.quiet {
        let h = &j["hex"];
        eprintln!(
            "polycube {} ({} of {} candidates verified); hex ({}): {} elements, min scaled Jacobian {:.3}, mean {:.3}, {} inverted, Hausdorff {:.2} % of the diagonal; {}wrote {} in {:.1} s",
            j["polycube"]["description"].as_str().unwrap_or("none"),
            j["polycube"]["verified"],
            j["polycube"]["candidates"],
            r.hex.domain,
            h["elements"],
            h["min_scaled_jacobian"].as_f64().unwrap_or(f64::NAN),
            h["mean_scaled_jacobian"].as_f64().unwrap_or(f64::NAN),
            h["inverted"],
            100.0 * r.hex.hausdorff_relative,
            if j["spline"].is_null() { String::new() } else { format!("spline: {} basis functions; ", j["spline"]["basis_functions"]) },
            p.output.display(),
            seconds
        );
    }
    Ok(0)
}

//! `sddpm run MESH -o DIR [polycube options] [--size H | --level N] [--no-spline] [fallback options] [quality goals] [file and deck options]`: the main job.
//! `sddpm run --help` groups the options under headings; the developer knobs come last ("Developer").

use super::common::{load_checked, Loaded};
use super::polycube::{load_generator, options_of, request_of, GeneratorArgs, PolycubeArgs};
use sddpm::error::{Error, Progress};
use sddpm::export::lsdyna::{Analysis, DeckOptions, Material, Units};
use sddpm::export::spline_files::{OutputOptions, MAX_SAMPLES};
use sddpm::hex::{HexOption, HexOptions, SurfaceMap};
use sddpm::pipeline::report::{write_run_folder, InputInfo};
use sddpm::pipeline::{run as run_job, RunOptions, RunResult};
use sddpm::Result;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub polycube: PolycubeArgs,
    /// Write an output folder that is not empty: first remove the files sddpm writes
    /// (report.json, hex.*, spline.*, ...; other files are kept). Without it a
    /// non-empty folder is refused.
    #[arg(long, help_heading = "Input and output")]
    pub force: bool,
    /// Refuse (exit 2) when no candidate passes verification instead of meshing the
    /// best-fitting unverified one, and when the hex mesh keeps inverted elements.
    #[arg(long, help_heading = "Mesh size and quality goals")]
    pub strict: bool,
    #[command(flatten)]
    pub hex: HexArgs,
    /// Stop after the hex mesh (no spline.bext / model.k / spline.vtu).
    #[arg(long, help_heading = "Spline and files")]
    pub no_spline: bool,
    #[command(flatten)]
    pub spline_files: SplineFileArgs,
    #[command(flatten)]
    pub deck: DeckArgs,
    /// How many candidates are meshed (verified ones, else unverified ones by fit); the best mesh is kept (default 4).
    #[arg(long, help_heading = "Developer")]
    pub hex_candidates: Option<usize>,
    #[command(flatten)]
    pub hex_dev: HexDevArgs,
    #[command(flatten)]
    pub generator: GeneratorArgs,
}

/// The LS-DYNA decks' part, material and analysis (hex.k and model.k), shared by
/// `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct DeckArgs {
    /// Unit system of the decks: mm-t-s (MPa, t/mm^3), m-kg-s (Pa, kg/m^3) or mm-kg-ms (GPa, kg/mm^3); the mesh's coordinates are taken in its length unit (default mm-t-s).
    #[arg(long, value_name = "U", default_value = "mm-t-s", help_heading = "LS-DYNA decks")]
    pub units: String,
    /// Material of *MAT_ELASTIC: steel (210 GPa, 0.3, 7850 kg/m^3), aluminium (70 GPa, 0.33, 2700 kg/m^3) or E,nu,rho in SI units (Pa, -, kg/m^3), scaled into --units (default steel).
    #[arg(long, value_name = "M", default_value = "steel", help_heading = "LS-DYNA decks")]
    pub material: String,
    /// Analysis of the decks: none (the model alone, to include in another deck), modal (10 free-free eigenmodes) or static (one implicit step; add loads and constraints) (default modal).
    #[arg(long, value_name = "A", default_value = "modal", help_heading = "LS-DYNA decks")]
    pub analysis: String,
}

/// The spline files' and the decks' options of the arguments.
pub fn output_options(s: &SplineFileArgs, d: &DeckArgs) -> Result<OutputOptions> {
    let units = Units::parse(&d.units)?;
    let material = Material::parse(&d.material).map_err(|e| Error::InvalidArgument(format!("--material: {e}")))?;
    let deck = DeckOptions { analysis: Analysis::parse(&d.analysis)?, ..DeckOptions::default() }.with_material(material, units)?;
    let mut o = OutputOptions { deck, ..OutputOptions::default() };
    match s.spline_sample {
        0 => o.vtu = None,
        n if n <= MAX_SAMPLES => o.vtk_samples = n,
        n => return Err(Error::InvalidArgument(format!("--spline-sample must be 0 to {MAX_SAMPLES}, got {n}"))),
    }
    Ok(o)
}

/// How spline.bext is written, shared by `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct SplineFileArgs {
    /// spline.vtu, the spline sampled for ParaView: N sub-cells along each element edge (N^3 cells and (N+1)^3 points per element; 0 to 8, 0: no spline.vtu), lowered where the file would pass 500,000 cells (default 2).
    #[arg(long, value_name = "N", default_value_t = sddpm::export::spline_files::DEFAULT_SAMPLES, help_heading = "Spline and files")]
    pub spline_sample: usize,
    /// Dense BEXT operator rows (64 entries each, as Hex2Spline writes them) instead of the default sparse rows.
    #[arg(long, help_heading = "Spline and files")]
    pub dense_bext: bool,
    /// Absolute tolerance of the BEXT operator entries: each is written with the fewest decimals that read back within it (default 1e-8; 0: exact).
    #[arg(long, value_name = "T", help_heading = "Spline and files")]
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

/// The hex stage's developer knobs (`--help`'s "Developer" heading), shared by
/// `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct HexDevArgs {
    /// No sharp-edge capture (by default boundary nodes near the input's sharp edges go onto them; docs/hex.md).
    #[arg(long, help_heading = "Developer")]
    pub no_capture_features: bool,
    /// No feature sheets (by default the fallback's lattice meshes get a sheet of elements under each surface patch so that their boundary follows the sharp curves; docs/hex.md).
    #[arg(long, help_heading = "Developer")]
    pub no_feature_sheets: bool,
    /// Feature curves whose median dihedral angle is below DEG degrees are ignored (default 60: creases of CAD parts, not facets of a coarse tessellation; e.g. 40 to follow 45-degree chamfers; docs/hex.md "Surface map").
    #[arg(long, value_name = "DEG", help_heading = "Developer")]
    pub feature_median_angle: Option<f64>,
}

/// The hex stage's options, shared by `sddpm run` and `sddpm batch`.
#[derive(clap::Args, Debug)]
pub struct HexArgs {
    /// Target element size H in model units: the polycube mesh's level is the one whose element count is nearest the input's volume / H^3, the fallback's lattice has voxels of edge H with no finer lattice; replaces --level and --voxel-resolution (report.json "hex.mean_edge_length" gives the result).
    #[arg(long, value_name = "H", help_heading = "Mesh size and quality goals", conflicts_with_all = ["level", "voxel_resolution"])]
    pub size: Option<f64>,
    /// Fix the octree subdivision level (default: chosen by the stopping rule).
    #[arg(long, help_heading = "Mesh size and quality goals")]
    pub level: Option<u32>,
    /// Surface map of the polycube path: best (the default: the charts, and the projection too when their mesh misses a quality goal; the better mesh kept), charts (inverse chart maps; the projection where a chart does not map) or projection (closest facing point and relaxation); docs/hex.md.
    #[arg(long, value_name = "METHOD", help_heading = "Polycube")]
    pub surface_map: Option<String>,
    /// The grid-based fallback's first lattice: voxels along the longest bounding-box edge (default 24).
    #[arg(long, help_heading = "Grid-based fallback")]
    pub voxel_resolution: Option<usize>,
    /// How many finer lattices the fallback may try after the first (default 2; 0: that lattice only).
    #[arg(long, help_heading = "Grid-based fallback")]
    pub voxel_refinements: Option<usize>,
    /// The fallback's kept lattice is meshed again with its planes on the input's axis-parallel planar faces of at least F of its area, and kept when it ranks better (default 0.02; 0: off; docs/hex.md "Lattice planes on the faces").
    #[arg(long, value_name = "F", help_heading = "Grid-based fallback")]
    pub lattice_planes: Option<f64>,
    /// Coverage step: pin nodes to input vertices farther than F times the distance goal (e.g. 0.6; off by default).
    #[arg(long, value_name = "F", help_heading = "Grid-based fallback")]
    pub pin_uncovered: Option<f64>,
    /// Local refinement: up to N rounds that split the fallback's voxels around the points farthest from its mesh 3 x 3 x 3, with conforming transition elements (off by default; docs/hex.md).
    #[arg(long, value_name = "N", help_heading = "Grid-based fallback")]
    pub local_refinement: Option<usize>,
    /// Local refinement of the polycube map: up to N rounds that split the chosen level's elements around the points farthest from its mesh 3 x 3 x 3, with conforming transition elements, when it misses the distance goal alone (off by default; docs/hex.md "Local refinement of the polycube map").
    #[arg(long, value_name = "N", help_heading = "Mesh size and quality goals")]
    pub map_local_refinement: Option<usize>,
    /// Quality goal: smallest acceptable minimum scaled Jacobian, in (-1, 1] (default 0.3). Meshes are ranked by the goals they miss; the fallback refines its lattice while the best misses one.
    #[arg(long, value_name = "S", help_heading = "Mesh size and quality goals")]
    pub goal_min_sj: Option<f64>,
    /// Quality goal: smallest acceptable mean scaled Jacobian, in (-1, 1] (default 0.85).
    #[arg(long, value_name = "S", help_heading = "Mesh size and quality goals")]
    pub goal_mean_sj: Option<f64>,
    /// Quality goal: largest acceptable two-sided Hausdorff distance between the mesh boundary and the input, relative to the bounding-box diagonal, > 0 (default 0.01; e.g. 0.02 for a coarser control mesh).
    #[arg(long, value_name = "D", help_heading = "Mesh size and quality goals")]
    pub goal_hausdorff: Option<f64>,
    /// Most elements a mesh may have before pillowing: caps the automatic octree level (not below its minimum, 2) and the fallback's lattices (default 200000).
    #[arg(long, value_name = "N", help_heading = "Mesh size and quality goals")]
    pub max_elements: Option<usize>,
}

/// The hex-stage options of the arguments on top of `hex`, checked by
/// [`HexOptions::validate`] (an out-of-range value is an error naming its flag).
pub fn hex_options(a: &HexArgs, d: &HexDevArgs, hex: &mut HexOptions) -> Result<()> {
    hex.map.level = a.level;
    hex.target_size = a.size;
    match a.surface_map.as_deref() {
        None => {}
        Some("projection") => hex.map.surface_map = SurfaceMap::Projection,
        Some("charts") => hex.map.surface_map = SurfaceMap::Charts,
        Some("best") => hex.map.surface_map = SurfaceMap::Best,
        Some(o) => return Err(Error::InvalidArgument(format!("--surface-map must be projection, charts or best, got {o:?}"))),
    }
    if let Some(n) = a.voxel_resolution {
        hex.fallback.resolution = n;
    }
    if let Some(n) = a.voxel_refinements {
        hex.fallback.refinements = n;
    }
    hex.quality.capture_features = !d.no_capture_features;
    hex.quality.feature_sheets = !d.no_feature_sheets;
    if let Some(n) = a.local_refinement {
        hex.fallback.local_refinement = n;
    }
    if let Some(n) = a.map_local_refinement {
        hex.map.local_refinement = n;
    }
    if let Some(deg) = d.feature_median_angle {
        hex.surface.feature_median_angle = deg;
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
        HexOption::TargetSize => "--size",
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
    hex_options(&a.hex, &a.hex_dev, &mut opts.hex)?;
    let Loaded { mesh, report, path } = load_checked(&p.mesh, p.weld_tolerance)?;
    let genus = report.genus.ok_or_else(|| Error::InvalidMesh("the genus of the input is undefined".into()))?;
    let request = request_of(p)?;
    let model = load_generator(&a.generator)?;
    opts.polycube = options_of(p, &a.generator)?;
    if a.no_spline {
        opts.spline = None;
    }
    spline_file_options(&a.spline_files, &mut opts)?;
    let files = output_options(&a.spline_files, &a.deck)?;
    opts.validate()?;
    super::common::prepare_output(&p.output, a.force)?;
    opts.accept_unverified = !a.strict;
    opts.require_valid_hex = a.strict;
    if let Some(n) = a.hex_candidates {
        opts.hex_candidates = n;
    }
    let r = run_job(&model, &mesh, genus, &request, &opts, progress)?;
    let input = InputInfo { path: &path, mesh: &mesh, report: &report, command: Some(command) };
    let j = write_run_folder(&p.output, &input, &r, &files, t0.elapsed().as_secs_f64())?;
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
            "polycube {} ({} of {} candidates verified); hex ({}): {} elements, min scaled Jacobian {:.3}, mean {:.3}, {} inverted, Hausdorff {:.2} % of the diagonal; {}wrote {} ({} files, {:.1} MB) in {:.1} s",
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
            j["files"].as_array().map_or(0, |f| f.len()),
            j["files_bytes"].as_u64().unwrap_or(0) as f64 / 1e6,
            seconds
        );
    }
    Ok(0)
}

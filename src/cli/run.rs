//! `sddpm run MESH -o DIR [polycube options] [--level N] [--no-spline] [fallback options]`: the main job.

use super::common::{load_checked, Loaded};
use super::polycube::{load_model, options_of, request_of, PolycubeArgs};
use sddpm::error::Error;
use sddpm::export::report::{write_run_folder, InputInfo};
use sddpm::pipeline::{run as run_job, RunOptions};
use sddpm::Result;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub polycube: PolycubeArgs,
    /// Fix the octree subdivision level (default: chosen by the stopping rule).
    #[arg(long)]
    pub level: Option<u32>,
    /// Stop after the hex mesh (no spline.bext / model.k).
    #[arg(long)]
    pub no_spline: bool,
    /// Refuse (exit 2) when no candidate passes verification instead of meshing the
    /// best-fitting unverified one, and when the hex mesh keeps inverted elements.
    #[arg(long)]
    pub strict: bool,
    /// How many candidates are meshed (verified ones, else unverified ones by fit); the best mesh is kept (default 4).
    #[arg(long)]
    pub hex_candidates: Option<usize>,
    /// The grid-based fallback's first lattice: voxels along the longest bounding-box edge (default 24).
    #[arg(long)]
    pub voxel_resolution: Option<usize>,
    /// How many finer lattices the fallback may try after the first (default 2; 0: that lattice only).
    #[arg(long)]
    pub voxel_refinements: Option<usize>,
    /// No sharp-edge capture (by default boundary nodes near the input's sharp edges go onto them; docs/hex.md).
    #[arg(long)]
    pub no_capture_features: bool,
    /// Coverage step: pin nodes to input vertices farther than F times the distance goal (e.g. 0.6; off by default).
    #[arg(long, value_name = "F")]
    pub pin_uncovered: Option<f64>,
}

pub fn run(a: &RunArgs) -> Result<i32> {
    let t0 = std::time::Instant::now();
    let p = &a.polycube;
    let Loaded { mesh, report, path } = load_checked(&p.mesh, p.weld_tolerance)?;
    let genus = report.genus.ok_or_else(|| Error::InvalidMesh("the genus of the input is undefined".into()))?;
    let request = request_of(p)?;
    let model = load_model(&p.weights)?;
    std::fs::create_dir_all(&p.output).map_err(|e| Error::io(p.output.display(), e))?;
    let mut opts = RunOptions { polycube: options_of(p), ..Default::default() };
    opts.hex.level = a.level;
    if a.no_spline {
        opts.spline = None;
    }
    opts.accept_unverified = !a.strict;
    opts.require_valid_hex = a.strict;
    if let Some(n) = a.hex_candidates {
        opts.hex_candidates = n;
    }
    if let Some(n) = a.voxel_resolution {
        if !(2..=sddpm::hex::voxel::VOXEL_MAX_RESOLUTION).contains(&n) {
            return Err(Error::InvalidArgument(format!("--voxel-resolution must be between 2 and {}, got {n}", sddpm::hex::voxel::VOXEL_MAX_RESOLUTION)));
        }
        opts.hex.voxel_resolution = n;
    }
    if let Some(n) = a.voxel_refinements {
        opts.hex.voxel_refinements = n;
    }
    opts.hex.capture_features = !a.no_capture_features;
    if let Some(f) = a.pin_uncovered {
        if !(f.is_finite() && f >= 0.0) {
            return Err(Error::InvalidArgument(format!("--pin-uncovered must be a finite number >= 0, got {f}")));
        }
        opts.hex.pin_uncovered = f;
    }
    let mut progress = super::common::progress_bar(p.quiet);
    let r = run_job(&model, &mesh, genus, &request, &opts, &mut progress)?;
    let j = write_run_folder(&p.output, &InputInfo { path: &path, mesh: &mesh, report: &report }, &r, t0.elapsed().as_secs_f64())?;
    if let Some(e) = &r.verification_error {
        if !p.quiet || p.json {
            eprintln!("warning: no candidate passed verification; meshed the best-fitting unverified candidate ({e})");
        }
    }
    if p.json {
        println!("{j}");
    } else if !p.quiet {
        let h = &j["hex"];
        eprintln!(
            "polycube {} ({} of {} candidates verified); hex: {} elements, min scaled Jacobian {:.3}, {} inverted; {}wrote {} in {:.1} s",
            j["polycube"]["names"].as_str().unwrap_or("?"),
            j["polycube"]["verified"],
            j["polycube"]["candidates"],
            h["elements"],
            h["min_scaled_jacobian"].as_f64().unwrap_or(f64::NAN),
            h["inverted"],
            if j["spline"].is_null() { String::new() } else { format!("spline: {} basis functions; ", j["spline"]["basis_functions"]) },
            p.output.display(),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(0)
}

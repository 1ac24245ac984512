//! `sddpm batch DIR -o OUT [-j N]`: the main job on every mesh file of a folder, with
//! all cores (one pipeline per file, files in parallel), each into OUT/<file stem>/,
//! and a summary (summary.md, summary.json) in OUT: every part's status, figures
//! and output files with their sizes.

use super::common::{load_checked, write_json, Loaded};
use super::polycube::load_model;
use sddpm::error::{Error, NoProgress};
use sddpm::pipeline::report::{write_run_folder, InputInfo};
use sddpm::export::spline_files::OutputOptions;
use sddpm::pipeline::{run as run_job, ContextRequest, RunOptions};
use sddpm::Result;
use rayon::prelude::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct BatchArgs {
    /// Folder of .obj / .stl / .off files (not recursive).
    pub dir: PathBuf,
    /// Output folder: one run folder per input plus summary.md and summary.json; absent or empty (a used one is refused unless --force).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Files meshed at once (default: the number of cores).
    #[arg(short = 'j', long)]
    pub jobs: Option<usize>,
    /// Stop after the hex mesh.
    #[arg(long)]
    pub no_spline: bool,
    /// Refuse unverified polycubes and inverted hex meshes (see `sddpm run --strict`).
    #[arg(long)]
    pub strict: bool,
    /// Seed of sampling and diffusion.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Reverse-diffusion steps (default: the library's default).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Model weights (default: the embedded model).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Write an output folder that is not empty: first remove the files sddpm writes
    /// there and in each input's run folder (other files are kept). Without it a
    /// non-empty folder is refused.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub spline_files: super::run::SplineFileArgs,
    #[command(flatten)]
    pub deck: super::run::DeckArgs,
    /// Print the summary as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// No per-file lines on stderr.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub hex: super::run::HexArgs,
    #[command(flatten)]
    pub hex_dev: super::run::HexDevArgs,
}

fn one(model: &sddpm::diffusion::Model, file: &Path, out: &Path, opts: &RunOptions, files: &OutputOptions, command: &str) -> Result<Value> {
    let t0 = std::time::Instant::now();
    let Loaded { mesh, report, path } = load_checked(file, sddpm::mesh::DEFAULT_WELD_TOLERANCE)?;
    let genus = report.genus.ok_or_else(|| Error::InvalidMesh("the genus of the input is undefined".into()))?;
    let r = run_job(model, &mesh, genus, &ContextRequest::Auto, opts, &mut NoProgress)?;
    write_run_folder(out, &InputInfo { path: &path, mesh: &mesh, report: &report, command: Some(command) }, &r, files, t0.elapsed().as_secs_f64())
}

pub fn run(a: &BatchArgs) -> Result<i32> {
    let t0 = std::time::Instant::now();
    let mut opts = RunOptions::default();
    super::run::hex_options(&a.hex, &a.hex_dev, &mut opts.hex)?;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&a.dir)
        .map_err(|e| Error::io(a.dir.display(), e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().and_then(|x| x.to_str()).is_some_and(|x| matches!(x.to_ascii_lowercase().as_str(), "obj" | "stl" | "off")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Error::InvalidArgument(format!("{}: no .obj, .stl or .off file", a.dir.display())));
    }
    let model = load_model(&a.weights)?;
    opts.polycube.seed = a.seed;
    opts.polycube.sampler.seed = a.seed;
    if let Some(st) = a.steps {
        opts.polycube.sampler.steps = st;
    }
    opts.accept_unverified = !a.strict;
    opts.require_valid_hex = a.strict;
    if a.no_spline {
        opts.spline = None;
    }
    super::run::spline_file_options(&a.spline_files, &mut opts)?;
    let outputs = super::run::output_options(&a.spline_files, &a.deck)?;
    opts.validate()?;
    super::common::prepare_output(&a.output, a.force)?;
    if a.force {
        // each input's run folder: the tool's files go, the caller's stay
        for f in &files {
            let sub = a.output.join(f.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh"));
            if sub.is_dir() {
                sddpm::pipeline::report::clear_outputs(&sub)?;
            }
        }
    }
    let command = super::common::command_line();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.jobs.unwrap_or(0))
        .build()
        .map_err(|e| Error::Internal(format!("thread pool: {e}")))?;
    let rows: Vec<Value> = pool.install(|| {
        files
            .par_iter()
            .map(|f| {
                let stem = f.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh").to_string();
                let t = std::time::Instant::now();
                let r = one(&model, f, &a.output.join(&stem), &opts, &outputs, &command);
                let secs = t.elapsed().as_secs_f64();
                let row = match &r {
                    Ok(j) => json!({
                        "file": f.display().to_string(), "folder": stem, "status": "OK",
                        "genus": j["input"]["genus"], "polycube": j["polycube"]["names"],
                        "verified": j["polycube"]["verified_choice"],
                        "elements": j["hex"]["elements"], "min_scaled_jacobian": j["hex"]["min_scaled_jacobian"],
                        "inverted": j["hex"]["inverted"], "hausdorff_relative": j["hex"]["hausdorff_relative"],
                        "basis_functions": j["spline"]["basis_functions"], "seconds": secs,
                        "files": part_files(&j), "files_bytes": j["files_bytes"],
                    }),
                    Err(e) => json!({ "file": f.display().to_string(), "folder": stem, "status": e.status().name(), "error": e.to_string(), "seconds": secs, "files": [], "files_bytes": 0 }),
                };
                if !a.quiet {
                    eprintln!("{:<28} {:<20} {:.1} s", stem, row["status"].as_str().unwrap_or("?"), secs);
                }
                row
            })
            .collect()
    });
    let ok = rows.iter().filter(|r| r["status"] == "OK").count();
    let total: u64 = rows.iter().filter_map(|r| r["files_bytes"].as_u64()).sum();
    let summary = json!({ "files": rows.len(), "ok": ok, "seconds": t0.elapsed().as_secs_f64(), "bytes": total, "runs": rows });
    write_json(&a.output.join("summary.json"), &summary)?;
    let md = summary_md(&rows, total);
    std::fs::write(a.output.join("summary.md"), &md).map_err(|e| Error::io(a.output.join("summary.md").display(), e))?;
    if a.json {
        println!("{summary}");
    } else if !a.quiet {
        eprintln!("{ok} of {} files meshed in {:.1} s; summary in {}", rows.len(), t0.elapsed().as_secs_f64(), a.output.join("summary.md").display());
    }
    Ok(if ok == rows.len() { 0 } else { super::EXIT_BAD_INPUT })
}

/// A part's files (report.json "files": name and bytes), paths relative to the
/// batch's output folder.
fn part_files(j: &Value) -> Value {
    Value::Array(j["files"].as_array().into_iter().flatten().map(|f| json!({ "name": f["name"], "bytes": f["bytes"] })).collect())
}

/// summary.md: one row per part, the failures with their errors, and every part's
/// files with their sizes.
fn summary_md(rows: &[Value], total: u64) -> String {
    let mut md = String::from("| file | status | genus | polycube | verified | elements | min SJ | inverted | Hausdorff | basis functions | files | MB | s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let f = |v: &Value| match v {
        Value::Number(n) if n.is_f64() => format!("{:.4}", n.as_f64().unwrap_or(f64::NAN)),
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        o => o.to_string(),
    };
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.1} |\n",
            f(&r["folder"]), f(&r["status"]), f(&r["genus"]), f(&r["polycube"]), f(&r["verified"]), f(&r["elements"]),
            f(&r["min_scaled_jacobian"]), f(&r["inverted"]), f(&r["hausdorff_relative"]), f(&r["basis_functions"]),
            r["files"].as_array().map_or(0, |v| v.len()), r["files_bytes"].as_u64().unwrap_or(0) as f64 / 1e6, r["seconds"].as_f64().unwrap_or(0.0)
        ));
    }
    md.push_str(&format!("\nAll parts: {:.2} MB.\n", total as f64 / 1e6));
    for r in rows.iter().filter(|r| r["status"] != "OK") {
        md.push_str(&format!("\n- {}: {}\n", f(&r["folder"]), f(&r["error"])));
    }
    md.push_str("\n## Files of each part\n");
    for r in rows {
        md.push_str(&format!("\n### {} ({})\n\n", f(&r["folder"]), f(&r["status"])));
        let files = r["files"].as_array().cloned().unwrap_or_default();
        if files.is_empty() {
            md.push_str("no file written\n");
        }
        for x in files {
            md.push_str(&format!("- [{0}/{1}]({0}/{1}) {2} bytes\n", f(&r["folder"]), f(&x["name"]), f(&x["bytes"])));
        }
    }
    md
}

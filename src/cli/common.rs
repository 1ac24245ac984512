//! Pieces shared by the commands: loading a checked mesh, progress on stderr, JSON files.

use sddpm::search::generate::{Candidate, PolycubeResult};
use sddpm::error::Error;
use sddpm::mesh::{LoadOptions, MeshReport, TriMesh};
use sddpm::Result;
use std::path::Path;

pub struct Loaded {
    pub mesh: TriMesh,
    pub report: MeshReport,
    pub path: String,
}

/// Load with the default options but `weld_tolerance` and refuse a mesh that cannot
/// go on to meshing.
pub fn load_checked(path: &Path, weld_tolerance: f64) -> Result<Loaded> {
    let mesh = TriMesh::load(path, &LoadOptions { weld_tolerance, ..LoadOptions::default() })?;
    let report = mesh.validate().map_err(|e| match e {
        Error::InvalidMesh(m) => Error::InvalidMesh(format!("{}: {m}", path.display())),
        o => o,
    })?;
    Ok(Loaded { mesh, report, path: path.display().to_string() })
}

pub fn write_json(path: &Path, v: &impl serde::Serialize) -> Result<()> {
    let s = serde_json::to_string_pretty(v).map_err(|e| Error::Internal(e.to_string()))?;
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

/// A progress sink printing one line per stage change (and nothing when quiet).
pub fn progress_bar(quiet: bool) -> impl FnMut(f64, &str) -> bool {
    let bar = if quiet { None } else { Some(indicatif::ProgressBar::new(1000)) };
    if let Some(b) = &bar {
        b.set_style(indicatif::ProgressStyle::with_template("{msg:>22} [{bar:40}] {percent:>3}% {elapsed}").unwrap().progress_chars("=> "));
    }
    // the bar never goes back (the library's stages may re-estimate their share)
    let mut best = 0.0f64;
    move |f: f64, stage: &str| {
        if f > best {
            best = f.min(1.0);
        }
        let f = best;
        if let Some(b) = &bar {
            b.set_message(stage.to_string());
            b.set_position((f * 1000.0) as u64);
            if f >= 1.0 {
                b.finish_and_clear();
            }
        }
        true
    }
}

/// The chosen polycube's surface in the user's coordinates.
pub fn to_user_polycube(result: &PolycubeResult, c: &Candidate) -> TriMesh {
    sddpm::pipeline::polycube_user_mesh(result, c)
}

/// The command line as typed (arguments with spaces or quotes single-quoted), for
/// report.json's "command".
pub fn command_line() -> String {
    std::env::args().map(|a| shell_quote(&a)).collect::<Vec<_>>().join(" ")
}

/// `a` as a shell word: as it is when it has no special character, else single-quoted.
pub fn shell_quote(a: &str) -> String {
    if !a.is_empty() && a.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c)) {
        a.to_string()
    } else {
        format!("'{}'", a.replace('\'', "'\\''"))
    }
}

/// Make `dir` ready for a command's files: a folder that does not exist or is
/// empty is used as it is; a non-empty one is refused (so that no file of another
/// run is mixed with this run's, and nothing the caller owns is overwritten)
/// unless `force`, which removes the files the tool writes there
/// (`pipeline::report::OUTPUT_FILES`, only those names) and keeps the rest.
pub fn prepare_output(dir: &Path, force: bool) -> Result<()> {
    let entries = sddpm::pipeline::report::folder_entries(dir)?;
    if !entries.is_empty() {
        if !force {
            let shown: Vec<&str> = entries.iter().take(4).map(|s| s.as_str()).collect();
            return Err(Error::InvalidArgument(format!(
                "the output folder {} is not empty ({} entr{}: {}{}); choose a new or empty folder, or pass --force to replace the files sddpm writes there (other files are kept)",
                dir.display(),
                entries.len(),
                if entries.len() == 1 { "y" } else { "ies" },
                shown.join(", "),
                if entries.len() > shown.len() { ", ..." } else { "" }
            )));
        }
        sddpm::pipeline::report::clear_outputs(dir)?;
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))
}

//! `sddpm polycube MESH -o DIR [--labels L | --constraints FILE | --auto] [--ratios R] [--seed N]`

use super::common::{load_checked, to_user_polycube, write_json, Loaded};
use sddpm::search::auto::{AutoOptions, SplitRatios};
use sddpm::search::generate::PolycubeOptions;
use sddpm::context::{Constraints, Context};
use sddpm::diffusion::sample::SamplerOptions;
use sddpm::diffusion::{Backend, Model};
use sddpm::error::Error;
use sddpm::pipeline::{generate_polycube, ContextRequest};
use sddpm::Result;
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args, Debug, Clone)]
pub struct PolycubeArgs {
    /// Input surface (.obj, .stl, .off).
    pub mesh: PathBuf,
    /// Output folder: absent or empty (a used one is refused unless --force).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Weld tolerance relative to the bounding-box diagonal (negative: no welding;
    /// lower it for parts thinner than 1e-9 of their size).
    #[arg(long, default_value_t = sddpm::mesh::DEFAULT_WELD_TOLERANCE, allow_negative_numbers = true, help_heading = "Input and output")]
    pub weld_tolerance: f64,
    /// A complete context: 12 labels in cell-index order (repeat for a stack).
    #[arg(long, allow_hyphen_values = true, conflicts_with_all = ["constraints", "auto"], help_heading = "Polycube")]
    pub labels: Vec<String>,
    /// Partial constraints (JSON: {"cube": n, "thc": n, "bhc": n, "labels": {...}, "allowed": [...], "required": [...]}).
    #[arg(long, conflicts_with = "auto", help_heading = "Polycube")]
    pub constraints: Option<PathBuf>,
    /// Automated context generation (the default when no context is given).
    #[arg(long, help_heading = "Polycube")]
    pub auto: bool,
    /// Splitting ratios X1,X2,X3:Y1,Y2:Z1,Z2 for the automated mode.
    #[arg(long, help_heading = "Polycube")]
    pub ratios: Option<String>,
    /// Seed of sampling and diffusion.
    #[arg(long, default_value_t = 0, help_heading = "Polycube")]
    pub seed: u64,
    /// Print the report as one JSON object on stdout.
    #[arg(long, help_heading = "Input and output")]
    pub json: bool,
    /// No progress on stderr.
    #[arg(short, long, help_heading = "Input and output")]
    pub quiet: bool,
}

/// The generator's and the sampler's knobs (`--help`'s "Developer" heading),
/// shared by `sddpm polycube` and `sddpm run`.
#[derive(clap::Args, Debug, Clone)]
pub struct GeneratorArgs {
    /// Reverse-diffusion steps (0 = the full T-step sampler; default: the library's default).
    #[arg(long, help_heading = "Developer")]
    pub steps: Option<usize>,
    /// Reverse diffusion starts at this step from the forward-noised input (0 = T; default: the library's default).
    #[arg(long, help_heading = "Developer")]
    pub start_step: Option<usize>,
    /// Start the reverse process at this noise level in cell units instead of a
    /// fixed step (SamplerOptions::start_noise).
    #[arg(long, help_heading = "Developer")]
    pub start_noise: Option<f64>,
    /// Classifier-free guidance weight (0 = off; default: the library's default).
    #[arg(long, help_heading = "Developer")]
    pub guidance: Option<f64>,
    /// Gate of the template attention (SamplerOptions::kernel_gate; 1 = its estimate alone, 0 = the U-Net alone, negative = the gate the weights learned; default: the library's default, 1).
    #[arg(long, allow_negative_numbers = true, help_heading = "Developer")]
    pub kernel_gate: Option<f64>,
    /// The template attention's prior and TCV's coverage without the template faces a
    /// cell shares with an occupied neighbour (SamplerOptions::visible_prior and
    /// VerifyOptions::visible_coverage): more true contexts pass in the user-guided
    /// mode, the automated search ranks worse (BENCHMARKS.md, "The visible prior";
    /// measured with --start-step 100).
    #[arg(long, help_heading = "Developer")]
    pub visible: bool,
    /// Do not diffuse a candidate that fails verification a second time with the
    /// visible prior (PolycubeOptions::visible_retry, on by default).
    #[arg(long, help_heading = "Developer")]
    pub no_visible_retry: bool,
    /// The generator: "learned" (the embedded point denoiser, or --weights) or
    /// "template" (the closed-form template estimate, the baseline; no weights).
    #[arg(long, default_value = "learned", help_heading = "Developer")]
    pub generator: String,
    /// The sampler: "strided" (the generator's default) or "paper" (the paper's
    /// reverse process from the input itself at T, all T ancestral steps).
    #[arg(long, help_heading = "Developer")]
    pub sampler: Option<String>,
    /// Model weights for the learned generator (default: the embedded model).
    #[arg(long, help_heading = "Developer")]
    pub weights: Option<PathBuf>,
}

/// `sddpm polycube`'s arguments: the polycube options and `--force`.
#[derive(clap::Args, Debug)]
pub struct PolycubeCommandArgs {
    #[command(flatten)]
    pub polycube: PolycubeArgs,
    /// Write an output folder that is not empty: first remove the files sddpm writes
    /// (report.json, polycube.obj, candidates.json, ...; other files are kept).
    /// Without it a non-empty folder is refused.
    #[arg(long, help_heading = "Input and output")]
    pub force: bool,
    #[command(flatten)]
    pub generator: GeneratorArgs,
}

pub fn request_of(a: &PolycubeArgs) -> Result<ContextRequest> {
    if !a.labels.is_empty() {
        let cs: Vec<Context> = a.labels.iter().map(|l| Context::parse(l)).collect::<Result<_>>()?;
        return Ok(ContextRequest::Contexts(cs));
    }
    if let Some(p) = &a.constraints {
        let text = std::fs::read_to_string(p).map_err(|e| Error::io(p.display(), e))?;
        let c: Constraints = serde_json::from_str(&text).map_err(|e| Error::parse(p.display(), e.to_string()))?;
        return Ok(ContextRequest::Constraints(c));
    }
    if let Some(r) = &a.ratios {
        return Ok(ContextRequest::Ratios(SplitRatios::parse(r)?));
    }
    Ok(ContextRequest::Auto)
}

/// `--kernel-gate G`: a fixed gate, or the learned one for a negative G.
pub fn kernel_gate_arg(g: f64) -> Option<f64> {
    if g < 0.0 { None } else { Some(g) }
}

pub fn options_of(p: &PolycubeArgs, a: &GeneratorArgs) -> Result<PolycubeOptions> {
    let mut o = match a.generator.as_str() {
        "template" => PolycubeOptions::template(),
        _ => PolycubeOptions::default(),
    };
    match a.sampler.as_deref() {
        None | Some("strided") => {}
        Some("paper") => o.sampler = SamplerOptions { kernel_gate: o.sampler.kernel_gate, ..SamplerOptions::paper() },
        Some(other) => return Err(Error::InvalidArgument(format!("--sampler must be strided or paper, got {other:?}"))),
    }
    o.seed = p.seed;
    o.sampler.seed = p.seed;
    if let Some(s) = a.steps {
        o.sampler.steps = s;
    }
    if let Some(s) = a.start_step {
        o.sampler.start_step = s;
    }
    if let Some(v) = a.start_noise {
        o.sampler.start_noise = Some(v);
    }
    if let Some(w) = a.guidance {
        o.sampler.guidance = w;
    }
    if let Some(g) = a.kernel_gate {
        o.sampler.kernel_gate = kernel_gate_arg(g);
    }
    if a.visible {
        o.sampler.visible_prior = true;
        o.verify.visible_coverage = true;
    }
    if a.no_visible_retry {
        o.visible_retry = false;
    }
    Ok(o)
}

pub fn load_model(weights: &Option<PathBuf>) -> Result<Model> {
    match weights {
        Some(p) => Model::from_file(p, Backend::default()),
        None => Model::default_model(),
    }
}

/// The model `--generator` and `--weights` name.
pub fn load_generator(a: &GeneratorArgs) -> Result<Model> {
    match a.generator.as_str() {
        "learned" => load_model(&a.weights),
        "template" if a.weights.is_none() => Ok(Model::template()),
        "template" => Err(Error::InvalidArgument("--weights is an option of --generator learned".into())),
        other => Err(Error::InvalidArgument(format!("--generator must be learned or template, got {other:?}"))),
    }
}

pub fn run(c: &PolycubeCommandArgs) -> Result<i32> {
    let a = &c.polycube;
    let t0 = std::time::Instant::now();
    let Loaded { mesh, report: mrep, path } = load_checked(&a.mesh, a.weld_tolerance)?;
    let genus = mrep.genus.ok_or_else(|| Error::InvalidMesh("the genus of the input is undefined".into()))?;
    let request = request_of(a)?;
    let model = load_generator(&c.generator)?;
    let opts = options_of(a, &c.generator)?;
    // every option is checked before the folder is touched
    sddpm::pipeline::RunOptions { polycube: opts.clone(), ..Default::default() }.validate()?;
    super::common::prepare_output(&a.output, c.force)?;
    let quiet = a.quiet;
    let mut progress = super::common::progress_bar(quiet);
    let (result, auto, err) = generate_polycube(&model, &mesh, genus, &request, &opts, &AutoOptions::default(), &mut progress)?;
    let chosen = result.chosen.map(|i| &result.candidates[i]);
    let mut written = Vec::new();
    if let Some(c) = chosen {
        let obj = to_user_polycube(&result, c);
        sddpm::export::obj::write_obj(&a.output.join("polycube.obj"), &obj, &format!("libsddpm polycube {} (user coordinates)", c.context))?;
        written.push("polycube.obj");
    }
    write_json(&a.output.join("candidates.json"), &json!({ "candidates": result.candidates, "auto": auto }))?;
    written.push("candidates.json");
    let mut report = json!({
        "version": env!("CARGO_PKG_VERSION"),
        "command": super::common::command_line(),
        "options": opts,
        "input": { "path": path, "vertices": mrep.vertices, "triangles": mrep.triangles, "genus": genus, "volume": mrep.volume },
        "polycube": {
            "labels": chosen.map(|c| c.labels.to_vec()),
            "names": chosen.map(|c| c.context.names()),
            "description": chosen.map(|c| c.context.describe()),
            "source": result.source,
            "generator": result.generator,
            "candidates": result.candidates.len(),
            "verified": result.verified().count(),
            "genus": chosen.and_then(|c| c.context.validity().genus),
            "rotation": chosen.map(|c| c.rotation.clone()),
            "frame": result.frame,
            "error": err.as_ref().map(|e| e.to_string()),
        },
        "seconds": { "total": t0.elapsed().as_secs_f64(), "polycube": result.timings },
    });
    let text = sddpm::pipeline::report::json_with_manifest(&a.output, &written, &mut report)?;
    std::fs::write(a.output.join("report.json"), text).map_err(|e| Error::io(a.output.join("report.json").display(), e))?;
    if a.json {
        println!("{report}");
    } else if !quiet {
        match chosen {
            Some(c) => eprintln!("polycube: {} (rotation {}, fit {:.4}); {} of {} candidates verified; wrote {}", c.context, c.rotation, c.fit, result.verified().count(), result.candidates.len(), a.output.display()),
            None => eprintln!("no polycube passed verification; candidates in {}", a.output.join("candidates.json").display()),
        }
    }
    match err {
        Some(e) => Err(e),
        None => Ok(0),
    }
}

//! `sddpm eval-model`: measure a model on held-in synthetic inputs (developer command).

use sddpm::search::generate::PolycubeOptions;
use sddpm::search::eval::evaluate;
use sddpm::diffusion::{Backend, Model};
use sddpm::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Weights file (default: the embedded model).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Number of synthetic cases.
    #[arg(long, default_value_t = 20)]
    pub cases: usize,
    /// Fewest occupied cells.
    #[arg(long, default_value_t = 1)]
    pub min: usize,
    /// Most occupied cells.
    #[arg(long, default_value_t = 3)]
    pub max: usize,
    /// Sampler steps (0 = full T-step sampler).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Seed of the synthetic cases (the training uses 42).
    #[arg(long, default_value_t = 1000)]
    pub seed: u64,
    /// Also try a wrong, genus-consistent context per case.
    #[arg(long)]
    pub wrong: bool,
    /// TCV threshold tau_CD (squared cell units).
    #[arg(long)]
    pub tau_cd: Option<f64>,
    /// Reverse diffusion starts at this step from the forward-noised input (0 = T).
    #[arg(long)]
    pub start_step: Option<usize>,
    /// Start the reverse process at this noise level in cell units instead of a
    /// fixed step (SamplerOptions::start_noise).
    #[arg(long)]
    pub start_noise: Option<f64>,
    /// Classifier-free guidance weight (SamplerOptions::guidance; 0 = off).
    #[arg(long)]
    pub guidance: Option<f64>,
    /// Gate of the template attention (SamplerOptions::kernel_gate; 1 = its estimate alone, 0 = the U-Net alone, negative = the gate the weights learned; default: the library's default, 1).
    #[arg(long, allow_negative_numbers = true)]
    pub kernel_gate: Option<f64>,
    /// Denoising passes after sampling (SamplerOptions::refine_passes).
    #[arg(long)]
    pub refine_passes: Option<usize>,
    /// Timestep of those passes (SamplerOptions::refine_t).
    #[arg(long)]
    pub refine_t: Option<usize>,
    /// Sweep TCV's tau_CD and p over a grid instead (true vs wrong contexts accepted).
    #[arg(long)]
    pub sweep: bool,
    /// With --sweep: also print to stderr each candidate's per-cell PCD between its
    /// output and its own laid-out input.
    #[arg(long)]
    pub sweep_fidelity: bool,
    /// TCV's coverage term without the template faces shared with occupied
    /// neighbours (VerifyOptions::visible_coverage; default: the library's).
    #[arg(long)]
    pub visible_coverage: Option<bool>,
    /// The template attention's prior without those faces
    /// (SamplerOptions::visible_prior; default: the library's).
    #[arg(long)]
    pub visible_prior: Option<bool>,
    /// A second diffusion with the visible prior for a candidate that fails
    /// (PolycubeOptions::visible_retry; default: the library's, on).
    #[arg(long)]
    pub visible_retry: Option<bool>,
}

pub fn run(a: &EvalArgs) -> Result<i32> {
    let model = match &a.weights {
        Some(p) => Model::from_file(p, Backend::default())?,
        None => Model::default_model()?,
    };
    let mut opts = PolycubeOptions::default();
    if let Some(s) = a.steps {
        opts.sampler.steps = s;
    }
    if let Some(t) = a.start_step {
        opts.sampler.start_step = t;
    }
    if let Some(v) = a.start_noise {
        opts.sampler.start_noise = Some(v);
    }
    if let Some(w) = a.guidance {
        opts.sampler.guidance = w;
    }
    if let Some(g) = a.kernel_gate {
        opts.sampler.kernel_gate = super::polycube::kernel_gate_arg(g);
    }
    if let Some(n) = a.refine_passes {
        opts.sampler.refine_passes = n;
    }
    if let Some(t) = a.refine_t {
        opts.sampler.refine_t = t;
    }
    if let Some(t) = a.tau_cd {
        opts.verify.tau_cd = t;
    }
    if let Some(v) = a.visible_coverage {
        opts.verify.visible_coverage = v;
    }
    if let Some(v) = a.visible_prior {
        opts.sampler.visible_prior = v;
    }
    if let Some(v) = a.visible_retry {
        opts.visible_retry = v;
    }
    if a.sweep {
        let taus = [0.005, 0.0075, 0.01, 0.0125, 0.015, 0.0175, 0.02, 0.03, 0.05];
        let ps = [1.0, 2.0];
        let (rows, gocc) = sddpm::search::eval::tcv_sweep(&model, a.seed, a.cases, a.min, a.max, &opts, &taus, &ps, a.sweep_fidelity)?;
        println!("| tau_CD | p | true accepted | target nearest (cells) | wrong accepted |");
        println!("|---|---|---|---|---|");
        for r in &rows {
            println!("| {} | {} | {}/{} | {}/{} | {}/{} |", r.tau_cd, r.penalty_p, r.true_accepted, r.true_cases, r.true_cells_nearest, r.true_cells, r.wrong_accepted, r.wrong_cases);
        }
        println!();
        println!("| contexts | diffused | GOCC passed | smallest occupied-cell span (cell units) | smallest fraction of a block in its cell | largest fraction in null cells' regions |");
        println!("|---|---:|---:|---:|---:|---:|");
        for (name, truth) in [("true", true), ("wrong", false)] {
            let g: Vec<_> = gocc.iter().filter(|s| s.truth == truth).collect();
            let lo = |f: fn(&sddpm::search::eval::GoccSample) -> f64| g.iter().map(|s| f(s)).fold(f64::INFINITY, f64::min);
            let hi = g.iter().map(|s| s.null_fraction).fold(0.0, f64::max);
            println!("| {name} | {} | {} | {:.3} | {:.3} | {:.4} |", g.len(), g.iter().filter(|s| s.gocc_pass).count(), lo(|s| s.min_span), lo(|s| s.min_inside), hi);
        }
        return Ok(0);
    }
    let s = evaluate(&model, a.seed, a.cases, a.min, a.max, &opts, a.wrong)?;
    println!("{}", serde_json::to_string_pretty(&s).unwrap());
    Ok(0)
}

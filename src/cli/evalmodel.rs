//! `sddpm eval-model`: measure a model on held-in synthetic inputs (developer command).

use sddpm::context::generate::PolycubeOptions;
use sddpm::diffusion::eval::evaluate;
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
    if let Some(t) = a.tau_cd {
        opts.verify.tau_cd = t;
    }
    let s = evaluate(&model, a.seed, a.cases, a.min, a.max, &opts, a.wrong)?;
    println!("{}", serde_json::to_string_pretty(&s).unwrap());
    Ok(0)
}

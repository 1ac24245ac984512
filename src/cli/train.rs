//! `sddpm train -o FILE [--epochs N] [--seed 42] [--resume CKPT]`

use sddpm::diffusion::train::{checkpoint_dir_for, train, TrainConfig, TrainEvent};
use sddpm::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct TrainArgs {
    /// Output weights file (written after every epoch; checkpoints go to FILE.ckpt/).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Number of epochs over the 5,000-sample set.
    #[arg(long)]
    pub epochs: Option<usize>,
    /// Seed of the data set and of the run.
    #[arg(long, default_value_t = 42)]
    pub seed: u64,
    /// Resume from a checkpoint folder (FILE.ckpt/ of an earlier run).
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Base width of the U-Net.
    #[arg(long)]
    pub width: Option<usize>,
    /// Width of the pointwise head (0 = none; see ModelConfig::point_width).
    #[arg(long)]
    pub point_width: Option<usize>,
    /// Batch size.
    #[arg(long)]
    pub batch: Option<usize>,
    /// Initial learning rate.
    #[arg(long)]
    pub lr: Option<f64>,
    /// Train on the first N samples only (quick experiments).
    #[arg(long)]
    pub limit: Option<usize>,
    /// Start from these weights (fine-tuning) instead of a seeded initialisation.
    #[arg(long)]
    pub init_from: Option<PathBuf>,
    /// Largest training timestep (0 = T).
    #[arg(long)]
    pub t_max: Option<usize>,
    /// Timestep density exponent p: t = 1 + floor(t_max u^p); 1 = uniform.
    #[arg(long)]
    pub t_power: Option<f64>,
    /// Heavier-tailed noise: probability that a point's noise is scaled by --outlier-scale.
    #[arg(long)]
    pub outlier_prob: Option<f64>,
    /// Scale of the outlier noise (with --outlier-prob).
    #[arg(long)]
    pub outlier_scale: Option<f64>,
    /// Template prior input (ModelConfig::prior); with --init-from on weights without it, a warm start.
    #[arg(long)]
    pub prior: bool,
    /// Template attention (ModelConfig::kernel); with --init-from on weights without it, a warm start.
    #[arg(long)]
    pub kernel: bool,
    /// Label dropout probability (classifier-free guidance; see TrainConfig::label_dropout).
    #[arg(long)]
    pub label_dropout: Option<f64>,
    /// Linear learning-rate warm-up over the first N steps (for --init-from).
    #[arg(long)]
    pub warmup: Option<usize>,
    /// Fraction of the learning rate left at the last step.
    #[arg(long)]
    pub final_lr: Option<f64>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: &TrainArgs) -> Result<i32> {
    let mut cfg = TrainConfig { seed: a.seed, limit_samples: a.limit, ..Default::default() };
    cfg.dataset.seed = a.seed;
    if let Some(e) = a.epochs {
        cfg.epochs = e;
    }
    if let Some(w) = a.width {
        cfg.model.base_width = w;
    }
    if let Some(p) = a.point_width {
        cfg.model.point_width = p;
    }
    if let Some(b) = a.batch {
        cfg.batch_size = b;
    }
    if let Some(lr) = a.lr {
        cfg.learning_rate = lr;
    }
    if let Some(t) = a.t_max {
        cfg.t_max = t;
    }
    if let Some(p) = a.t_power {
        cfg.t_power = p;
    }
    if let Some(p) = a.outlier_prob {
        if !(0.0..=1.0).contains(&p) {
            return Err(sddpm::Error::InvalidArgument(format!("--outlier-prob must be in [0, 1], got {p}")));
        }
        cfg.outlier_prob = p;
    }
    if let Some(k) = a.outlier_scale {
        if !(k.is_finite() && k > 0.0) {
            return Err(sddpm::Error::InvalidArgument(format!("--outlier-scale must be positive, got {k}")));
        }
        cfg.outlier_scale = k;
    }
    if let Some(w) = a.warmup {
        cfg.warmup_steps = w;
    }
    if a.kernel {
        cfg.model.kernel = true;
    }
    if a.prior {
        cfg.model.prior = true;
    }
    if let Some(p) = a.label_dropout {
        if !(0.0..1.0).contains(&p) {
            return Err(sddpm::Error::InvalidArgument(format!("--label-dropout must be in [0, 1), got {p}")));
        }
        cfg.label_dropout = p;
    }
    if let Some(f) = a.final_lr {
        cfg.final_lr_fraction = f;
    }
    cfg.init_from = a.init_from.clone();
    if !a.quiet {
        eprintln!(
            "training: {} epochs, batch {}, width {}, lr {:.1e}, seed {}; checkpoints in {}",
            cfg.epochs,
            cfg.batch_size,
            cfg.model.base_width,
            cfg.learning_rate,
            cfg.seed,
            a.resume.clone().unwrap_or_else(|| checkpoint_dir_for(&a.output)).display()
        );
    }
    let quiet = a.quiet;
    let meta = train(&cfg, &a.output, a.resume.as_deref(), &mut |ev| {
        if !quiet {
            match ev {
                TrainEvent::Log(r) => eprintln!(
                    "step {:>7}  epoch {:>7.3}  loss {:.5}  lr {:.2e}  {:.1} samples/s",
                    r.step, r.epoch, r.loss, r.lr, r.samples_per_second
                ),
                TrainEvent::EpochDone { epoch, seconds, checkpoint } => {
                    eprintln!("epoch {epoch} done after {:.0} s; checkpoint {}", seconds, checkpoint.display())
                }
            }
        }
        true
    })?;
    if !quiet {
        eprintln!("wrote {} ({} epochs, {} steps, final loss {:.5})", a.output.display(), meta.training.epochs, meta.training.steps, meta.training.final_loss);
    }
    Ok(0)
}

//! `sddpm train -o FILE [--epochs N] [--seed 42] [--resume CKPT]`

use sddpm::diffusion::train::{checkpoint_dir_for, train, TrainConfig, TrainEvent, LOSS_CSV};
use sddpm::export::plot::plot_loss;
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
    /// Architecture: "field" (the learned point denoiser, the default model) or
    /// "unet" (the paper's U-Net; with --kernel, template attention).
    #[arg(long, default_value = "field")]
    pub arch: String,
    /// Width: the point denoiser's hidden width (default 128) or the U-Net's base width (24).
    #[arg(long)]
    pub width: Option<usize>,
    /// Residual blocks of the point denoiser (default 4).
    #[arg(long)]
    pub blocks: Option<usize>,
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
    let base = match a.arch.as_str() {
        "field" => TrainConfig::field_default(),
        "unet" => TrainConfig::default(),
        o => return Err(sddpm::Error::InvalidArgument(format!("--arch must be field or unet, got {o:?}"))),
    };
    let mut cfg = TrainConfig { seed: a.seed, limit_samples: a.limit, ..base };
    cfg.dataset.seed = a.seed;
    if let Some(e) = a.epochs {
        cfg.epochs = e;
    }
    if let Some(w) = a.width {
        if w == 0 {
            return Err(sddpm::Error::InvalidArgument("--width must be positive".into()));
        }
        match cfg.model.field.as_mut() {
            Some(f) => f.width = w,
            None => cfg.model.base_width = w,
        }
    }
    if let Some(b) = a.blocks {
        match cfg.model.field.as_mut() {
            Some(f) if b > 0 => f.blocks = b,
            Some(_) => return Err(sddpm::Error::InvalidArgument("--blocks must be positive".into())),
            None => return Err(sddpm::Error::InvalidArgument("--blocks is an option of --arch field".into())),
        }
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
    if (a.kernel || a.prior || a.point_width.is_some() || a.init_from.is_some()) && cfg.model.field.is_some() {
        return Err(sddpm::Error::InvalidArgument("--kernel, --prior, --point-width and --init-from are options of --arch unet".into()));
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
            "training {}: {} epochs, batch {}, width {}, lr {:.1e}, seed {}; checkpoints in {}",
            a.arch,
            cfg.epochs,
            cfg.batch_size,
            cfg.model.field.as_ref().map_or(cfg.model.base_width, |f| f.width),
            cfg.learning_rate,
            cfg.seed,
            a.resume.clone().unwrap_or_else(|| checkpoint_dir_for(&a.output)).display()
        );
    }
    let quiet = a.quiet;
    let meta = train(&cfg, &a.output, a.resume.as_deref(), &mut |ev| {
        if let TrainEvent::EpochDone { checkpoint, .. } = &ev {
            // the loss curve next to its CSV at every checkpoint; a plotting failure
            // never stops a training run
            let _ = plot_loss(&checkpoint.join(LOSS_CSV), checkpoint, 20);
        }
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

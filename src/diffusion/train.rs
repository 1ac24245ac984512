//! Training: MSE on the noise, Adam, linear learning-rate decay, seeded, with a
//! checkpoint every epoch that a later run resumes from, and a loss log (CSV).
//!
//! Randomness (initial weights, epoch shuffles, timesteps and noise) all comes from
//! `seed`: the weights from burn's device seed, the rest from per-step ChaCha
//! generators, so a resumed run draws exactly what the uninterrupted run would have.

use super::model::{Denoiser, ModelConfig};

use super::schedule::{Schedule, ScheduleConfig};
use super::weights::{self, TrainingInfo, WeightsMeta};
use super::{device, load_net, net_bytes, Backend};
use crate::error::{Error, Result};
use crate::geometry::rng::seeded_rng;
use crate::diffusion::dataset::{generate, DatasetConfig, Sample};
use crate::polycube::tensor::{TENSOR_H, TENSOR_LEN, TENSOR_W};
use crate::polycube::CONTEXT_DIM;
use burn::optim::grad_clipping::GradientClippingConfig;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::{Tensor, TensorData};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seed mixers of the random streams of training: the epoch's shuffle (stream =
/// epoch) and the step's timesteps and noise (stream = step).
const SHUFFLE_STREAM: u64 = 0x5348_5546;
const NOISE_STREAM: u64 = 0x4e4f_4953;

/// Everything a training run depends on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrainConfig {
    pub epochs: usize,
    pub batch_size: usize,
    /// Initial learning rate.
    pub learning_rate: f64,
    /// The rate decays linearly to `learning_rate * final_lr_fraction` at the last step.
    pub final_lr_fraction: f64,
    /// Linear warm-up of the learning rate over this many first steps (0 = none).
    /// Fine-tuning with a fresh Adam needs it: Adam's first steps move every
    /// parameter by about the learning rate whatever its gradient, which was measured
    /// to raise the low-noise error of trained weights by half within two steps.
    #[serde(default)]
    pub warmup_steps: usize,
    pub seed: u64,
    /// Log the mean loss every this many steps.
    pub log_every: usize,
    /// Use only the first n samples (for quick tests); None = the whole set.
    pub limit_samples: Option<usize>,
    /// Average the loss over occupied cells only (null cells are known and held by
    /// replacement in the sampler, so the network need not learn them).
    pub mask_null_cells: bool,
    /// Largest training timestep (0 = T). Fine-tuning for the sampler's range: the
    /// default sampler starts at t = 200, so steps above it are never evaluated.
    pub t_max: usize,
    /// Timestep density: t = 1 + floor(t_max * u^p), u ~ U(0, 1). p = 1 is uniform;
    /// p = 2 has density proportional to 1 / sqrt(t), i.e. more low-noise steps, where
    /// the network must place points to a small fraction of the noise level.
    pub t_power: f64,
    /// Weights file to start from (fine-tuning) instead of a seeded initialisation;
    /// the architecture and schedule come from that file, the optimiser starts fresh.
    pub init_from: Option<std::path::PathBuf>,
    /// Heavier-tailed training noise: each point's noise vector is multiplied by
    /// `outlier_scale` with probability `outlier_prob` (0 = plain Gaussian noise). The
    /// target is still the noise actually added, so the loss stays MSE on the noise;
    /// it puts points far from the primitive at low t into the training distribution,
    /// where the reverse process strands them (BENCHMARKS.md, "Where the error is").
    pub outlier_prob: f64,
    pub outlier_scale: f64,
    /// Label dropout for classifier-free guidance: with this probability a sample's
    /// context is given with its labels withheld (`Context::one_hot_unlabelled`), so
    /// one network learns the conditional and the "labels unknown" predictions
    /// (`SamplerOptions::guidance` combines them). 0 = off.
    pub label_dropout: f64,
    /// Point denoiser only: the share of training cells whose slots' ranks are
    /// withheld (`FieldConfig::rank_flag`). 0 = always given.
    #[serde(default)]
    pub rank_dropout: f64,
    pub dataset: DatasetConfig,
    pub model: ModelConfig,
    pub schedule: ScheduleConfig,
}

impl TrainConfig {
    /// The default model's training run: the point denoiser ([`super::field`]) with
    /// 64 cells a step, Adam at 1e-3 after a 200-step warm-up, decaying linearly to
    /// 5 %, 5 % of the points with triple noise (points far from the surface at low
    /// noise, where the reverse process on a real part puts them), 10 % label
    /// dropout (the "label withheld" estimate for guidance) and the ranks withheld
    /// for half of the cells (the sampler's default denoises without them). Seed 42.
    pub fn field_default() -> Self {
        TrainConfig {
            epochs: 12,
            batch_size: 64,
            learning_rate: 1e-3,
            final_lr_fraction: 0.05,
            warmup_steps: 200,
            log_every: 25,
            outlier_prob: 0.05,
            outlier_scale: 3.0,
            label_dropout: 0.1,
            rank_dropout: 0.5,
            model: ModelConfig { field: Some(Default::default()), ..Default::default() },
            ..Default::default()
        }
    }
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            epochs: 40,
            batch_size: 16,
            learning_rate: 6e-4,
            final_lr_fraction: 0.05,
            warmup_steps: 0,
            seed: 42,
            log_every: 25,
            limit_samples: None,
            mask_null_cells: true,
            t_max: 0,
            t_power: 1.0,
            init_from: None,
            outlier_prob: 0.0,
            outlier_scale: 1.0,
            label_dropout: 0.0,
            rank_dropout: 0.0,
            dataset: DatasetConfig::default(),
            model: ModelConfig::default(),
            schedule: ScheduleConfig::default(),
        }
    }
}

/// What is saved after every epoch.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckpointState {
    pub config: TrainConfig,
    pub epochs_done: usize,
    pub steps_done: usize,
    pub seconds: f64,
    pub last_loss: f64,
}

/// One line of the loss log.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LossRecord {
    pub step: usize,
    pub epoch: f64,
    pub loss: f64,
    pub lr: f64,
    pub samples_per_second: f64,
}

/// Progress events of a run; the callback returns false to stop after the current step
/// (a checkpoint is written first).
pub enum TrainEvent<'a> {
    Log(&'a LossRecord),
    EpochDone { epoch: usize, seconds: f64, checkpoint: &'a Path },
}

pub(super) fn checkpoint_files(dir: &Path) -> (PathBuf, PathBuf, PathBuf, PathBuf) {
    (dir.join("state.json"), dir.join("net.bpk"), dir.join("optim.bpk"), dir.join(LOSS_CSV))
}

/// Adam with gradient-norm clipping at 1 (guards the first steps of a fresh network).
pub(super) fn adam() -> burn::optim::ModuleOptimizer {
    AdamConfig::new().with_grad_clipping(Some(GradientClippingConfig::Norm(1.0))).init()
}

/// The loss log of a checkpoint folder (step, epoch, loss; one row every 25 steps),
/// read by [`read_loss_csv`].
pub const LOSS_CSV: &str = "loss.csv";

/// The checkpoint folder used for an output weights path: `<out>.ckpt/`.
pub fn checkpoint_dir_for(out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".ckpt");
    PathBuf::from(s)
}

pub(super) fn io<E: std::fmt::Display>(p: &Path) -> impl FnOnce(E) -> Error + '_ {
    move |e| Error::io(p.display(), e)
}

/// Train (or resume) and write the weights file `out` after every epoch.
pub fn train(
    requested: &TrainConfig,
    out: &Path,
    resume: Option<&Path>,
    on_event: &mut dyn FnMut(TrainEvent) -> bool,
) -> Result<WeightsMeta> {
    let field = match resume {
        Some(dir) => {
            let st = checkpoint_files(dir).0;
            let state: CheckpointState = serde_json::from_slice(&std::fs::read(&st).map_err(io(&st))?)
                .map_err(|e| Error::parse(st.display(), e.to_string()))?;
            state.config.model.field.is_some()
        }
        None => requested.model.field.is_some(),
    };
    if field {
        return super::train_field::train_field(requested, out, resume, on_event);
    }
    let ad = device(Backend::Flex).autodiff();
    let (cfg, ckdir, mut net, mut opt, mut epoch0, mut step, mut seconds0, mut last_loss);
    match resume {
        Some(dir) => {
            let (st, netf, optf, _) = checkpoint_files(dir);
            let state: CheckpointState = serde_json::from_slice(&std::fs::read(&st).map_err(io(&st))?)
                .map_err(|e| Error::parse(st.display(), e.to_string()))?;
            // Everything but the number of epochs comes from the checkpoint.
            cfg = TrainConfig { epochs: requested.epochs, ..state.config.clone() };
            let rec = std::fs::read(&netf).map_err(io(&netf))?;
            net = load_net(&cfg.model, &rec, &ad)?;
            let o = adam();
            opt = o.load(&optf).map_err(|e| Error::Model(format!("{}: {e:?}", optf.display())))?;
            epoch0 = state.epochs_done;
            step = state.steps_done;
            seconds0 = state.seconds;
            last_loss = state.last_loss;
            ckdir = dir.to_path_buf();
        }
        None => {
            let mut c = requested.clone();
            let mut warm_partial = false;
            let init = match &c.init_from {
                Some(p) => {
                    let bytes = std::fs::read(p).map_err(io(p))?;
                    let (meta, rec) = super::weights::decode(&bytes)?;
                    // Warm start of a larger architecture: a point head requested on
                    // weights without one is added (zero output at first) and trained
                    // together with the loaded U-Net.
                    let head = c.model.point_width;
                    let prior = c.model.prior;
                    let kernel = c.model.kernel;
                    c.model = meta.model.clone();
                    if head > 0 && c.model.point_width == 0 {
                        c.model.point_width = head;
                        warm_partial = true;
                    }
                    // likewise the template prior's input convolution (zero at first)
                    if prior && !c.model.prior {
                        c.model.prior = true;
                        warm_partial = true;
                    }
                    // and the template attention (gate and input at zero at first)
                    if kernel && !c.model.kernel {
                        c.model.kernel = true;
                        warm_partial = true;
                    }
                    c.schedule = meta.schedule.clone();
                    Some(rec.to_vec())
                }
                None => None,
            };
            cfg = c;
            // burn's seed is one process-wide generator: the seeded construction
            // holds the lock every construction takes (super::fresh_net)
            net = match &init {
                Some(rec) => super::load_net_seeded(&cfg.model, rec, &ad, warm_partial, Some(cfg.seed))?,
                None => super::fresh_net(&cfg.model, &ad, Some(cfg.seed)),
            };
            opt = adam();
            epoch0 = 0;
            step = 0;
            seconds0 = 0.0;
            last_loss = f64::NAN;
            ckdir = checkpoint_dir_for(out);
            std::fs::create_dir_all(&ckdir).map_err(io(&ckdir))?;
            let (_, _, _, csv) = checkpoint_files(&ckdir);
            std::fs::write(&csv, "step,epoch,loss,lr,samples_per_second\n").map_err(io(&csv))?;
        }
    }
    train_loop(&cfg, out, &ckdir, &mut net, &mut opt, &mut epoch0, &mut step, &mut seconds0, &mut last_loss, on_event)
}

#[allow(clippy::too_many_arguments)]
fn train_loop(
    cfg: &TrainConfig,
    out: &Path,
    ckdir: &Path,
    net: &mut Denoiser,
    opt: &mut burn::optim::ModuleOptimizer,
    epoch0: &mut usize,
    step: &mut usize,
    seconds0: &mut f64,
    last_loss: &mut f64,
    on_event: &mut dyn FnMut(TrainEvent) -> bool,
) -> Result<WeightsMeta> {
    let ad = device(Backend::Flex).autodiff();
    let mut data: Vec<Sample> = generate(&cfg.dataset);
    if let Some(n) = cfg.limit_samples {
        data.truncate(n.max(1));
    }
    let sched = Schedule::new(cfg.schedule.clone());
    *net = net.clone().with_schedule(&sched);
    let bs = cfg.batch_size.max(1);
    let steps_per_epoch = data.len().div_ceil(bs);
    let t_max = if cfg.t_max == 0 { sched.steps() } else { cfg.t_max.min(sched.steps()) };
    let total_steps = steps_per_epoch * cfg.epochs;
    let (_, _, _, csv) = checkpoint_files(ckdir);
    let mut csv_file = std::fs::OpenOptions::new().append(true).create(true).open(&csv).map_err(io(&csv))?;
    let started = Instant::now();
    let mut window_loss = 0.0;
    let mut window_n = 0usize;
    let mut window_start = Instant::now();
    let mut stop = false;
    let mut meta = meta_for(cfg, *epoch0, *step, *last_loss, *seconds0);
    for epoch in *epoch0..cfg.epochs {
        let mut perm: Vec<usize> = (0..data.len()).collect();
        let mut rng = seeded_rng(cfg.seed ^ SHUFFLE_STREAM, epoch as u64);
        for i in (1..perm.len()).rev() {
            let j = rng.random_range(0..=i);
            perm.swap(i, j);
        }
        for chunk in perm.chunks(bs) {
            let b = chunk.len();
            let mut srng = seeded_rng(cfg.seed ^ NOISE_STREAM, *step as u64);
            let mut x0 = Vec::with_capacity(b * TENSOR_LEN);
            let mut ctx = Vec::with_capacity(b * CONTEXT_DIM);
            for &i in chunk {
                x0.extend_from_slice(&data[i].tensor);
                if cfg.label_dropout > 0.0 && srng.random_range(0.0..1.0) < cfg.label_dropout {
                    ctx.extend_from_slice(&data[i].context.one_hot_unlabelled());
                } else {
                    ctx.extend_from_slice(&data[i].context.one_hot());
                }
            }
            let ts: Vec<usize> = (0..b).map(|_| training_timestep(&mut srng, t_max, cfg.t_power)).collect();
            let mut z: Vec<f32> = (0..b * TENSOR_LEN).map(|_| StandardNormal.sample(&mut srng)).collect();
            if cfg.outlier_prob > 0.0 {
                let hw = TENSOR_H * TENSOR_W;
                for i in 0..b {
                    for px in 0..hw {
                        if srng.random_range(0.0..1.0) < cfg.outlier_prob {
                            for ch in 0..3 {
                                z[i * TENSOR_LEN + ch * hw + px] *= cfg.outlier_scale as f32;
                            }
                        }
                    }
                }
            }
            let mut xt = vec![0f32; b * TENSOR_LEN];
            for i in 0..b {
                let r = i * TENSOR_LEN..(i + 1) * TENSOR_LEN;
                sched.forward_sample(&x0[r.clone()], &z[r.clone()], ts[i], &mut xt[r]);
            }
            let xt = Tensor::<4>::from_data(TensorData::new(xt, [b, 3, TENSOR_H, TENSOR_W]), &ad);
            let zt = Tensor::<4>::from_data(TensorData::new(z, [b, 3, TENSOR_H, TENSOR_W]), &ad);
            let ct = Tensor::<2>::from_data(TensorData::new(ctx, [b, CONTEXT_DIM]), &ad);
            let pred = net.forward(xt, &ts, ct);
            let loss = if cfg.mask_null_cells {
                let mask = occupied_mask(chunk.iter().map(|&i| &data[i].context));
                let count = mask.iter().filter(|&&m| m > 0.0).count().max(1) as f32 * 3.0;
                let mt = Tensor::<4>::from_data(TensorData::new(mask, [b, 1, TENSOR_H, TENSOR_W]), &ad);
                ((pred - zt).powi_scalar(2) * mt).sum().div_scalar(count)
            } else {
                (pred - zt).powi_scalar(2).mean()
            };
            let lv: f32 = loss.clone().into_scalar();
            if !lv.is_finite() {
                return Err(Error::Model(format!("training diverged at step {} (loss {lv})", *step)));
            }
            let grads = GradientsParams::from_grads(loss.backward(), &*net);
            let frac = if total_steps > 1 { *step as f64 / (total_steps - 1) as f64 } else { 0.0 };
            let mut lr = cfg.learning_rate * (1.0 - (1.0 - cfg.final_lr_fraction) * frac.min(1.0));
            if *step < cfg.warmup_steps {
                lr *= (*step + 1) as f64 / cfg.warmup_steps as f64;
            }
            *net = opt.step(lr, net.clone(), grads);
            *step += 1;
            *last_loss = lv as f64;
            window_loss += lv as f64;
            window_n += 1;
            if window_n >= cfg.log_every.max(1) {
                let rec = LossRecord {
                    step: *step,
                    epoch: *step as f64 / steps_per_epoch as f64,
                    loss: window_loss / window_n as f64,
                    lr,
                    samples_per_second: (window_n * bs) as f64 / window_start.elapsed().as_secs_f64(),
                };
                writeln!(csv_file, "{},{:.4},{:.6},{:.6e},{:.2}", rec.step, rec.epoch, rec.loss, rec.lr, rec.samples_per_second)
                    .map_err(io(&csv))?;
                window_loss = 0.0;
                window_n = 0;
                window_start = Instant::now();
                if !on_event(TrainEvent::Log(&rec)) {
                    stop = true;
                    break;
                }
            }
        }
        let seconds = *seconds0 + started.elapsed().as_secs_f64();
        let done = if stop { epoch } else { epoch + 1 };
        meta = meta_for(cfg, done, *step, *last_loss, seconds);
        save_checkpoint(cfg, ckdir, net, opt, done, *step, seconds, *last_loss)?;
        let bytes = weights::encode(&meta, &net_bytes(net)?);
        let tmp = out.with_extension("tmp");
        std::fs::write(&tmp, &bytes).map_err(io(&tmp))?;
        std::fs::rename(&tmp, out).map_err(io(out))?;
        if stop || !on_event(TrainEvent::EpochDone { epoch: done, seconds, checkpoint: ckdir }) {
            break;
        }
    }
    Ok(meta)
}

/// A training timestep in 1..=t_max: t = 1 + floor(t_max * u^p).
fn training_timestep(rng: &mut impl rand::Rng, t_max: usize, p: f64) -> usize {
    if p == 1.0 {
        return rng.random_range(1..=t_max);
    }
    let u: f64 = rng.random_range(0.0..1.0);
    (1 + (t_max as f64 * u.powf(p.max(1e-3))) as usize).min(t_max)
}

/// 1 on the pixels of occupied cells, 0 on null cells: [B, 1, 64, 96].
fn occupied_mask<'a>(ctxs: impl Iterator<Item = &'a crate::context::Context>) -> Vec<f32> {
    use crate::polycube::tensor::{slot, POINTS_PER_CELL};
    let mut out = Vec::new();
    for c in ctxs {
        let mut m = vec![0f32; TENSOR_H * TENSOR_W];
        for n in c.occupied() {
            for p in 0..POINTS_PER_CELL {
                let (r, col) = slot(n, p);
                m[r * TENSOR_W + col] = 1.0;
            }
        }
        out.extend(m);
    }
    out
}

pub(super) fn meta_for(cfg: &TrainConfig, epochs: usize, steps: usize, loss: f64, seconds: f64) -> WeightsMeta {
    WeightsMeta {
        format_version: 1,
        library_version: env!("CARGO_PKG_VERSION").to_string(),
        model: cfg.model.clone(),
        schedule: cfg.schedule.clone(),
        dataset: cfg.dataset.clone(),
        training: TrainingInfo {
            seed: cfg.seed,
            epochs,
            steps,
            batch_size: cfg.batch_size,
            learning_rate: cfg.learning_rate,
            final_loss: loss,
            seconds,
            t_max: cfg.t_max,
            t_power: cfg.t_power,
            init_from: cfg.init_from.as_ref().map(|p| p.display().to_string()),
            outlier_prob: cfg.outlier_prob,
            outlier_scale: cfg.outlier_scale,
            label_dropout: cfg.label_dropout,
            rank_dropout: cfg.rank_dropout,
        },
        dtype: "f32".into(),
    }
}

#[allow(clippy::too_many_arguments)]
fn save_checkpoint(
    cfg: &TrainConfig,
    dir: &Path,
    net: &Denoiser,
    opt: &burn::optim::ModuleOptimizer,
    epochs_done: usize,
    steps_done: usize,
    seconds: f64,
    last_loss: f64,
) -> Result<()> {
    let (st, netf, optf, _) = checkpoint_files(dir);
    let nb = net_bytes(net)?;
    let tmp = netf.with_extension("tmp");
    std::fs::write(&tmp, nb).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &netf).map_err(io(&netf))?;
    let tmp = optf.with_extension("tmp");
    opt.save(&tmp).map_err(|e| Error::Model(format!("{}: {e:?}", tmp.display())))?;
    std::fs::rename(&tmp, &optf).map_err(io(&optf))?;
    let state = CheckpointState { config: cfg.clone(), epochs_done, steps_done, seconds, last_loss };
    let tmp = st.with_extension("tmp");
    std::fs::write(&tmp, serde_json::to_vec_pretty(&state).unwrap()).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &st).map_err(io(&st))
}

/// Read the loss log of a checkpoint folder: (step, epoch, loss).
pub fn read_loss_csv(path: &Path) -> Result<Vec<(usize, f64, f64)>> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    let mut v = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() >= 3 {
            if let (Ok(s), Ok(e), Ok(l)) = (f[0].parse(), f[1].parse(), f[2].parse()) {
                v.push((s, e, l));
            }
        }
    }
    Ok(v)
}

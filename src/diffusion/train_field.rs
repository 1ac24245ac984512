//! Training of the point denoiser ([`super::field`]) on the data set.
//!
//! A step draws `batch_size` occupied cells of the data set (shuffled per epoch),
//! for each a timestep and fresh noise, and regresses the network's preconditioned
//! output F on its target (x0 - c_skip u) / c_out: the x_0 error weighted by
//! 1 / c_out^2, which is EDM's weighting of the noise-prediction loss (it keeps every
//! noise level's loss of order one). Timesteps are drawn so that ln of the noise
//! level sqrt(1 - ab_t) / sqrt(ab_t) is uniform over the schedule's range: the
//! schedule's uniform-in-t density spends half of all steps above t = 250, where the
//! input is lost and the estimate is nearly the primitive's centroid, and little
//! where the label shapes the cross-section (t = 10..200, BENCHMARKS.md "Learned
//! denoiser").
//!
//! Everything random comes from the run's seed (initial weights through burn's
//! device seed; shuffles, timesteps, noise and label dropout from per-step ChaCha
//! generators), so a resumed run draws what the uninterrupted one would have. A
//! checkpoint (weights, optimiser, state, loss log) is written after every epoch, and
//! the epoch's weights are kept as `epoch-N.sddpmw` beside it for the
//! quality-against-epoch curves.

use super::field::{frames_of, precond, CellBatch, FieldConfig, FieldNet, LABELS};
use super::schedule::Schedule;
use super::train::{adam, checkpoint_files, io, meta_for, CheckpointState, LossRecord, TrainConfig, TrainEvent};
use super::weights::{self, WeightsMeta};
use super::{device, fresh_field, load_module, module_bytes, Backend};
use crate::error::{Error, Result};
use crate::geometry::rng::seeded_rng;
use crate::diffusion::dataset::generate;
use crate::polycube::tensor::{unlayout, POINTS_PER_CELL};
use crate::polycube::Primitive;
use burn::optim::GradientsParams;
use burn::tensor::{Tensor, TensorData};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Random streams of a field run (mixed with the seed).
const SHUFFLE_STREAM: u64 = 0x4649_454c_4453;
const STEP_STREAM: u64 = 0x4649_5354_4550;

/// One occupied cell of the data set in its own frame.
struct TrainCell {
    /// The 512 points in slot order, local coordinates (cell centre 0, edge 1).
    local: Vec<[f32; 3]>,
    /// Edge length in normalised units.
    h: f64,
    label: Primitive,
}

fn cells_of(cfg: &TrainConfig) -> Vec<TrainCell> {
    let mut data = generate(&cfg.dataset);
    if let Some(n) = cfg.limit_samples {
        data.truncate(n.max(1));
    }
    let mut out = Vec::new();
    for s in &data {
        let Some(frames) = frames_of(&s.context) else { continue };
        let pts = unlayout(&s.tensor);
        for (n, f) in frames.iter().enumerate() {
            let Some(f) = f else { continue };
            let local = pts[n].iter().map(|p| std::array::from_fn(|a| ((p[a] as f64 - f.centre[a]) / f.h) as f32)).collect();
            out.push(TrainCell { local, h: f.h, label: s.context.labels[n] });
        }
    }
    out
}

/// The noise level sqrt(1 - ab_t) / sqrt(ab_t) per timestep (normalised units).
pub fn noise_levels(sched: &Schedule) -> Vec<f64> {
    sched.alpha_bar.iter().map(|&ab| ((1.0 - ab) / ab).sqrt()).collect()
}

/// A timestep whose noise level is log-uniform over the schedule's range.
fn draw_timestep(rng: &mut impl rand::Rng, levels: &[f64]) -> usize {
    let t_max = levels.len() - 1;
    let (lo, hi) = (levels[1].ln(), levels[t_max].ln());
    let target = (lo + rng.random_range(0.0..1.0) * (hi - lo)).exp();
    levels[1..].partition_point(|&s| s < target).clamp(0, t_max - 1) + 1
}

/// Train (or resume) the point denoiser; writes `out` after every epoch.
pub fn train_field(requested: &TrainConfig, out: &Path, resume: Option<&Path>, on_event: &mut dyn FnMut(TrainEvent) -> bool) -> Result<WeightsMeta> {
    let ad = device(Backend::Flex).autodiff();
    let (cfg, ckdir, mut net, mut opt, epoch0, mut step, seconds0, mut last_loss);
    match resume {
        Some(dir) => {
            let (st, netf, optf, _) = checkpoint_files(dir);
            let state: CheckpointState = serde_json::from_slice(&std::fs::read(&st).map_err(io(&st))?).map_err(|e| Error::parse(st.display(), e.to_string()))?;
            cfg = TrainConfig { epochs: requested.epochs, ..state.config.clone() };
            let fc = cfg.model.field.clone().ok_or_else(|| Error::Model(format!("{}: not a point-denoiser checkpoint", st.display())))?;
            let rec = std::fs::read(&netf).map_err(io(&netf))?;
            net = load_module(fresh_field(&fc, &ad, None), &rec, false)?.with_rank(true);
            opt = adam().load(&optf).map_err(|e| Error::Model(format!("{}: {e:?}", optf.display())))?;
            epoch0 = state.epochs_done;
            step = state.steps_done;
            seconds0 = state.seconds;
            last_loss = state.last_loss;
            ckdir = dir.to_path_buf();
        }
        None => {
            cfg = requested.clone();
            let fc = cfg.model.field.clone().ok_or_else(|| Error::InvalidArgument("train_field needs a point-denoiser configuration".into()))?;
            net = fresh_field(&fc, &ad, Some(cfg.seed)).with_rank(true);
            opt = adam();
            epoch0 = 0;
            step = 0;
            seconds0 = 0.0;
            last_loss = f64::NAN;
            ckdir = super::train::checkpoint_dir_for(out);
            std::fs::create_dir_all(&ckdir).map_err(io(&ckdir))?;
            let (_, _, _, csv) = checkpoint_files(&ckdir);
            std::fs::write(&csv, "step,epoch,loss,lr,samples_per_second\n").map_err(io(&csv))?;
        }
    }
    let fc: FieldConfig = cfg.model.field.clone().expect("checked above");
    let cells = cells_of(&cfg);
    if cells.is_empty() {
        return Err(Error::InvalidArgument("the data set has no occupied cell".into()));
    }
    let sched = Schedule::new(cfg.schedule.clone());
    let levels = noise_levels(&sched);
    let bs = cfg.batch_size.max(1);
    let steps_per_epoch = cells.len().div_ceil(bs);
    let total_steps = steps_per_epoch * cfg.epochs;
    let (_, _, _, csv) = checkpoint_files(&ckdir);
    let mut csv_file = std::fs::OpenOptions::new().append(true).create(true).open(&csv).map_err(io(&csv))?;
    let started = Instant::now();
    let (mut window_loss, mut window_n, mut window_start) = (0.0, 0usize, Instant::now());
    let mut stop = false;
    let mut meta = meta_for(&cfg, epoch0, step, last_loss, seconds0);
    for epoch in epoch0..cfg.epochs {
        let mut perm: Vec<usize> = (0..cells.len()).collect();
        let mut rng = seeded_rng(cfg.seed ^ SHUFFLE_STREAM, epoch as u64);
        for i in (1..perm.len()).rev() {
            let j = rng.random_range(0..=i);
            perm.swap(i, j);
        }
        for chunk in perm.chunks(bs) {
            let mut srng = seeded_rng(cfg.seed ^ STEP_STREAM, step as u64);
            let (batch, target) = noisy_batch(chunk.iter().map(|&i| &cells[i]), &fc, &levels, &cfg, &mut srng);
            let c = batch.cells();
            let (f, nz, lb) = batch.tensors(&ad);
            let tgt = Tensor::<3>::from_data(TensorData::new(target, [c, POINTS_PER_CELL, 3]), &ad);
            let loss = (net.forward(f, nz, lb) - tgt).powi_scalar(2).mean();
            let lv: f32 = loss.clone().into_scalar();
            if !lv.is_finite() {
                return Err(Error::Model(format!("training diverged at step {step} (loss {lv})")));
            }
            let grads = GradientsParams::from_grads(loss.backward(), &net);
            let frac = if total_steps > 1 { step as f64 / (total_steps - 1) as f64 } else { 0.0 };
            let mut lr = cfg.learning_rate * (1.0 - (1.0 - cfg.final_lr_fraction) * frac.min(1.0));
            if step < cfg.warmup_steps {
                lr *= (step + 1) as f64 / cfg.warmup_steps as f64;
            }
            net = opt.step(lr, net, grads);
            step += 1;
            last_loss = lv as f64;
            window_loss += lv as f64;
            window_n += 1;
            if window_n >= cfg.log_every.max(1) {
                let rec = LossRecord {
                    step,
                    epoch: step as f64 / steps_per_epoch as f64,
                    loss: window_loss / window_n as f64,
                    lr,
                    samples_per_second: (window_n * bs) as f64 / window_start.elapsed().as_secs_f64(),
                };
                writeln!(csv_file, "{},{:.4},{:.6},{:.6e},{:.2}", rec.step, rec.epoch, rec.loss, rec.lr, rec.samples_per_second).map_err(io(&csv))?;
                (window_loss, window_n, window_start) = (0.0, 0, Instant::now());
                if !on_event(TrainEvent::Log(&rec)) {
                    stop = true;
                    break;
                }
            }
        }
        let seconds = seconds0 + started.elapsed().as_secs_f64();
        let done = if stop { epoch } else { epoch + 1 };
        meta = meta_for(&cfg, done, step, last_loss, seconds);
        save(&cfg, &ckdir, &net, &opt, done, step, seconds, last_loss)?;
        let bytes = weights::encode(&meta, &module_bytes(net.clone())?);
        let tmp = out.with_extension("tmp");
        std::fs::write(&tmp, &bytes).map_err(io(&tmp))?;
        std::fs::rename(&tmp, out).map_err(io(out))?;
        if !stop {
            let snap = ckdir.join(format!("epoch-{done}.sddpmw"));
            std::fs::write(&snap, &bytes).map_err(io(&snap))?;
        }
        if stop || !on_event(TrainEvent::EpochDone { epoch: done, seconds, checkpoint: &ckdir }) {
            break;
        }
    }
    Ok(meta)
}

/// The network inputs and targets of a batch of cells: per cell a timestep drawn
/// log-uniform in noise level, Gaussian noise (a point's noise scaled by
/// `outlier_scale` with probability `outlier_prob`), the label withheld with
/// probability `label_dropout` and the ranks with probability `rank_dropout`.
fn noisy_batch<'a>(
    cells: impl Iterator<Item = &'a TrainCell>,
    fc: &FieldConfig,
    levels: &[f64],
    cfg: &TrainConfig,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> (CellBatch, Vec<f32>) {
    let mut batch = CellBatch::new(fc.octaves, fc.sigma_data, fc.rank_flag);
    let mut target = Vec::new();
    let mut u = vec![[0f32; 3]; POINTS_PER_CELL];
    for cell in cells {
        let t = draw_timestep(rng, levels);
        let s = levels[t] / cell.h;
        for (p, x0) in cell.local.iter().enumerate() {
            let k = if cfg.outlier_prob > 0.0 && rng.random_range(0.0..1.0) < cfg.outlier_prob { cfg.outlier_scale } else { 1.0 };
            u[p] = std::array::from_fn(|a| {
                let z: f64 = StandardNormal.sample(rng);
                (x0[a] as f64 + s * k * z) as f32
            });
        }
        let mut row = [0f32; LABELS];
        if !(cfg.label_dropout > 0.0 && rng.random_range(0.0..1.0) < cfg.label_dropout) {
            row[cell.label.label() as usize] = 1.0;
        }
        let rank = !(cfg.rank_dropout > 0.0 && rng.random_range(0.0..1.0) < cfg.rank_dropout);
        batch.push(&u, s, &row, rank);
        let (_, c_skip, c_out) = precond(s, fc.sigma_data);
        for (x0, ui) in cell.local.iter().zip(&u) {
            for a in 0..3 {
                target.push(((x0[a] as f64 - c_skip * ui[a] as f64) / c_out) as f32);
            }
        }
    }
    (batch, target)
}

#[allow(clippy::too_many_arguments)]
fn save(cfg: &TrainConfig, dir: &Path, net: &FieldNet, opt: &burn::optim::ModuleOptimizer, epochs_done: usize, steps_done: usize, seconds: f64, last_loss: f64) -> Result<()> {
    let (st, netf, optf, _) = checkpoint_files(dir);
    let tmp = netf.with_extension("tmp");
    std::fs::write(&tmp, module_bytes(net.clone())?).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &netf).map_err(io(&netf))?;
    let tmp = optf.with_extension("tmp");
    opt.save(&tmp).map_err(|e| Error::Model(format!("{}: {e:?}", tmp.display())))?;
    std::fs::rename(&tmp, &optf).map_err(io(&optf))?;
    let state = CheckpointState { config: cfg.clone(), epochs_done, steps_done, seconds, last_loss };
    let tmp = st.with_extension("tmp");
    std::fs::write(&tmp, serde_json::to_vec_pretty(&state).unwrap_or_default()).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &st).map_err(io(&st))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timesteps_are_log_uniform_in_noise_level() {
        let sched = Schedule::new(Default::default());
        let levels = noise_levels(&sched);
        let mut rng = seeded_rng(1, 2);
        let ts: Vec<usize> = (0..20000).map(|_| draw_timestep(&mut rng, &levels)).collect();
        assert!(ts.iter().all(|&t| (1..=500).contains(&t)));
        // the median noise level is the geometric mean of the range's ends
        let mut l: Vec<f64> = ts.iter().map(|&t| levels[t].ln()).collect();
        l.sort_by(f64::total_cmp);
        let mid = 0.5 * (levels[1].ln() + levels[500].ln());
        assert!((l[10000] - mid).abs() < 0.1, "{} vs {mid}", l[10000]);
        // and far more low-noise steps than the uniform density gives
        let below_100 = ts.iter().filter(|&&t| t <= 100).count() as f64 / ts.len() as f64;
        assert!(below_100 > 0.5, "{below_100}");
    }
}

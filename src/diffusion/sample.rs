//! Reverse diffusion from the input geometry, batched over candidate contexts.
//!
//! Null cells are known: their x_0 is 512 copies of (0, 0, 0). After every step
//! their blocks are replaced by a fresh forward sample of that known x_0 at the new
//! timestep (conditioning by replacement, as in inpainting), and by exact zeros at
//! the end; the network therefore always sees null blocks as it saw them in
//! training, and the output's null cells are exactly the placeholders of DESIGN.md.
//!
//! Two samplers share one loop: the full ancestral sampler of DESIGN.md (all T
//! steps, noise sigma_t^2 = b_t) and a strided deterministic sampler (DDIM on the
//! mean-shifted variable) with fewer network evaluations. Every candidate has its
//! own noise generator seeded from (seed, candidate index), so a candidate's result
//! does not depend on which other candidates share its batch.

use super::Model;
use crate::context::Context;
use crate::error::{check_progress, Error, Progress, Result};
use crate::geometry::rng::seeded_rng;
use crate::polycube::tensor::{TENSOR_H, TENSOR_LEN, TENSOR_W};
use crate::polycube::tensor::{flat, slot, POINTS_PER_CELL};
use crate::polycube::{Primitive, CONTEXT_DIM, NUM_CELLS};
use burn::tensor::{Tensor, TensorData};
use rand_distr::{Distribution, StandardNormal};

/// Options of the reverse process.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SamplerOptions {
    /// Network evaluations: 0 or >= T runs the full T-step ancestral sampler;
    /// 1..T runs the strided deterministic sampler with that many steps.
    pub steps: usize,
    /// Seed of the sampler noise.
    pub seed: u64,
    /// Keep the state every `keep_every` steps (0 = keep nothing) for visualisation.
    pub keep_every: usize,
    /// Candidates per network call.
    pub max_batch: usize,
    /// The step the reverse process starts from (0 = T). The input geometry enters as
    /// the x_0 of the forward process at that step: x'_start = sqrt(ab) x_in +
    /// sqrt(1 - ab) z + Q q, so the network sees the kind of state it was trained on.
    pub start_step: usize,
    /// Start from the noise level instead of a fixed step: each candidate starts at
    /// the first step whose noise sqrt(1 - ab_t) / sqrt(ab_t), in its cells' units
    /// (normalised units over the cell edge), reaches this value; overrides
    /// `start_step`. The same step means three times the noise in cell units for a
    /// context three cells long as for one cell, and the denoiser works in cell
    /// units. None = use `start_step`.
    pub start_noise: Option<f64>,
    /// Use the raw input geometry as x'_T without forward noising (DESIGN.md's literal
    /// reading; measured to be worse, see BENCHMARKS.md).
    pub raw_start: bool,
    /// Denoising passes after the last step: the output x is taken as the x_0 of a
    /// noise-free forward state at `refine_t` (x_t = sqrt(ab) x + Q_t q), the network
    /// predicts the noise and x moves to the predicted x_0. Each pass pulls points that
    /// the reverse process left off the learned surface back onto it.
    pub refine_passes: usize,
    /// Timestep of the refinement passes.
    pub refine_t: usize,
    /// Strided sampler: clip each predicted x_0 point to its own cell's box (grown by
    /// this margin, in cell units) before stepping on; negative turns clipping off.
    /// The data of every occupied cell lie in that cell, as image diffusion clips x_0
    /// to the pixel range.
    pub clip_margin: f64,
    /// Factor applied to every predicted noise before the step (1 = off). Values
    /// below 1 counter a network whose noise estimates are too large along the
    /// reverse trajectory ("epsilon scaling" against exposure bias); BENCHMARKS.md
    /// records the sweep.
    pub eps_scale: f64,
    /// Classifier-free guidance weight w: the noise is predicted under the context
    /// and under its "labels unknown" form (every occupied cell's one-hot row zeroed,
    /// null cells kept; see `Context::one_hot_unlabelled`) and combined as
    /// e_c + w (e_c - e_u). 0 = off (one network call per step); w > 0 doubles the
    /// work per step. Meaningful for weights trained with label dropout.
    pub guidance: f64,
    /// Gate of the template attention (`ModelConfig::kernel`): 1 = its Bayes
    /// estimate alone (the default, `DEFAULT_KERNEL_GATE`), 0 = the U-Net alone;
    /// None = the gate the weights learned. Ignored by weights without template
    /// attention.
    pub kernel_gate: Option<f64>,
    /// The template attention attends to each cell's primitive sampled off the faces
    /// the context gives an occupied neighbour (`model::prior_image_visible`), the part
    /// of the assembled surface the cell's input can carry, instead of the whole
    /// primitive. The sorted layout ties slot i to the prior points near rank i, so a
    /// prior holding faces the input lacks shifts the correspondence of every point.
    /// Goes with `VerifyOptions::visible_coverage` (the output then has no points on
    /// those faces). Measured in BENCHMARKS.md ("The visible prior").
    pub visible_prior: bool,
    /// The point denoiser sees each slot's rank (`FieldConfig::rank_flag`). Default
    /// false: the rank ties a slot to the quantile the standalone primitive's area
    /// gives it, which a real part's cell does not follow. Ignored by other networks.
    pub use_rank: bool,
}

impl Default for SamplerOptions {
    /// The learned generator's sampler: the strided deterministic sampler over
    /// [`LEARNED_STEPS`] steps from the input noised to [`LEARNED_START_NOISE`] cell
    /// units, ranks withheld.
    fn default() -> Self {
        SamplerOptions {
            steps: LEARNED_STEPS,
            seed: 0,
            keep_every: 0,
            max_batch: 16,
            start_step: 0,
            start_noise: Some(LEARNED_START_NOISE),
            raw_start: LEARNED_RAW_START,
            refine_passes: DEFAULT_REFINE_PASSES,
            refine_t: DEFAULT_REFINE_T,
            clip_margin: DEFAULT_CLIP_MARGIN,
            eps_scale: 1.0,
            guidance: 0.0,
            kernel_gate: DEFAULT_KERNEL_GATE,
            visible_prior: DEFAULT_VISIBLE_PRIOR,
            use_rank: false,
        }
    }
}

impl SamplerOptions {
    /// The baseline generator's sampler (the closed-form template estimate): 50
    /// strided steps from the input forward-noised at t = 200 (BENCHMARKS.md, the
    /// template estimate's measurements).
    pub fn template() -> Self {
        SamplerOptions { steps: TEMPLATE_STEPS, start_step: TEMPLATE_START_STEP, start_noise: None, raw_start: false, ..Default::default() }
    }

    /// The paper's sampler as written: the reverse process from the input geometry
    /// itself as x'_T (no forward noising), all T ancestral steps with the
    /// nonzero-mean drift and sigma_t^2 = b_t.
    pub fn paper() -> Self {
        SamplerOptions { steps: 0, start_step: 0, start_noise: None, raw_start: true, ..Default::default() }
    }
}

/// Steps of the learned generator's strided sampler (BENCHMARKS.md, "Generator").
pub const LEARNED_STEPS: usize = 20;
/// Noise level, in cell units, the learned generator starts from (BENCHMARKS.md,
/// "Generator": on the tuning seed 8100, 0.02 refused 20/21 relabelled contexts
/// of 1-3 cells and 14/16 of 4-12 where 0.03 refused 15/21 and 9/16, both verifying
/// every true context).
pub const LEARNED_START_NOISE: f64 = 0.02;
/// Whether the learned generator starts from the input itself at that level (true)
/// or from the input forward-noised to it (false).
pub const LEARNED_RAW_START: bool = false;
/// Steps of the template estimate's sampler, chosen by measurement (docs/history/diffusion.md).
pub const TEMPLATE_STEPS: usize = 50;
/// Default gate of the template attention: its estimate alone. Measured in
/// BENCHMARKS.md ("Template attention"): the gate learned on the MSE loss stays near
/// the small least-squares blend and does not make the label's shape (TCV 1/16 on
/// held-in cases from t = 100, against 5/16 with the estimate alone, 0/12 for the
/// U-Net alone); on the real meshes of the main job the estimate alone verifies
/// where the U-Net verified none.
pub const DEFAULT_KERNEL_GATE: Option<f64> = Some(1.0);
/// Start step of the template estimate's sampler (0 = T), chosen by measurement
/// (docs/history/diffusion.md; with the visible prior, 100 measured better).
pub const TEMPLATE_START_STEP: usize = 200;
/// Default of `SamplerOptions::visible_prior`: off. It lets more true contexts pass
/// TCV in the user-guided mode but makes the automated mode's ranking pick wrong
/// verified candidates (docs/history/diffusion.md, "The visible prior").
pub const DEFAULT_VISIBLE_PRIOR: bool = false;
/// Default refinement passes and their timestep (BENCHMARKS.md).
pub const DEFAULT_REFINE_PASSES: usize = 0;
pub const DEFAULT_REFINE_T: usize = 20;
/// Default x_0 clipping margin: off (BENCHMARKS.md: clipping removes the overshoot
/// but not the interior points that make TCV fail, and it would make GOCC's
/// "points in their own cell" check pass by construction).
pub const DEFAULT_CLIP_MARGIN: f64 = -1.0;

/// The step a candidate's reverse process starts from (see
/// [`SamplerOptions::start_noise`]).
pub fn start_step_for(sched: &super::schedule::Schedule, opts: &SamplerOptions, ctx: &Context) -> usize {
    let t_max = sched.steps();
    if let (Some(sigma), Some(frame)) = (opts.start_noise, crate::context::context_frame(ctx)) {
        return (1..=t_max).find(|&t| ((1.0 - sched.alpha_bar[t]) / sched.alpha_bar[t]).sqrt() / frame.scale >= sigma).unwrap_or(t_max);
    }
    if opts.start_step == 0 {
        t_max
    } else {
        opts.start_step.min(t_max)
    }
}

/// Per-slot clipping boxes [lo, hi] (model frame) of one context: each occupied
/// cell's box grown by `margin` cell units; None for null cells.
fn clip_boxes(ctx: &Context, margin: f64) -> Vec<Option<([f64; 3], [f64; 3])>> {
    let Some(frame) = crate::context::context_frame(ctx) else { return vec![None; NUM_CELLS] };
    (0..NUM_CELLS)
        .map(|n| {
            if ctx.labels[n] == Primitive::Null {
                return None;
            }
            let [i, j, k] = crate::polycube::cell_coords(n);
            let lo = frame.to_normalised([i as f64 - margin, j as f64 - margin, k as f64 - margin]);
            let hi = frame.to_normalised([i as f64 + 1.0 + margin, j as f64 + 1.0 + margin, k as f64 + 1.0 + margin]);
            Some((lo, hi))
        })
        .collect()
}

/// Output of a batch: one [3, 64, 96] tensor per candidate, and the kept states.
#[derive(Debug, Clone, Default)]
pub struct SampleOutput {
    pub tensors: Vec<Vec<f32>>,
    /// Per candidate: (t, tensor) for every kept step, t = T first and 0 last.
    pub trajectory: Vec<Vec<(usize, Vec<f32>)>>,
}

/// The timesteps the sampler visits from `t_max` down: t_max, ..., 1 (full) or an
/// evenly strided subset of `steps` of them.
pub fn timesteps(t_max: usize, steps: usize) -> Vec<usize> {
    if steps == 0 || steps >= t_max {
        return (1..=t_max).rev().collect();
    }
    let mut v: Vec<usize> = (0..steps).map(|i| t_max - (i * t_max) / steps).collect();
    v.dedup();
    v
}

/// Run the reverse process. `inputs[i]` is x'_T of candidate i (the input geometry
/// laid out for context `contexts[i]`).
pub fn reverse_diffusion(
    model: &Model,
    inputs: &[Vec<f32>],
    contexts: &[Context],
    opts: &SamplerOptions,
    progress: &mut dyn Progress,
) -> Result<SampleOutput> {
    check_sampler_inputs(inputs, contexts, opts)?;
    let n = inputs.len();
    let configured = model.net.configured(opts.kernel_gate.map(|g| g as f32), opts.visible_prior, opts.use_rank);
    let net = &configured;
    let mut out = SampleOutput { tensors: vec![Vec::new(); n], trajectory: vec![Vec::new(); n] };
    let sched = &model.schedule;
    // each candidate's start step: fixed, or from its cells' noise level in cell units
    let starts: Vec<usize> = contexts.iter().map(|c| start_step_for(sched, opts, c)).collect();
    let batch = opts.max_batch.max(1);
    // candidates sharing a start step run together, in batches, in index order
    let groups = groups_by_start(&starts, batch);
    let total_calls: usize = groups.iter().map(|g| timesteps(starts[g[0]], opts.steps).len()).sum::<usize>().max(1);
    let mut calls = 0usize;
    for members in &groups {
        let t_start = starts[members[0]];
        let ts = timesteps(t_start, opts.steps);
        let ancestral = ts.len() == t_start;
        let b = members.len();
        let mut x: Vec<f32> = members.iter().flat_map(|&i| inputs[i].iter().copied()).collect();
        let mut rngs: Vec<_> = members.iter().map(|&i| seeded_rng(opts.seed, i as u64)).collect();
        if !opts.raw_start {
            let mut z = vec![0f32; TENSOR_LEN];
            for i in 0..b {
                for v in z.iter_mut() {
                    *v = StandardNormal.sample(&mut rngs[i]);
                }
                let r = i * TENSOR_LEN..(i + 1) * TENSOR_LEN;
                let x_in = x[r.clone()].to_vec();
                sched.forward_sample(&x_in, &z, t_start, &mut x[r]);
            }
        }
        let ctx: Vec<f32> = members.iter().flat_map(|&i| contexts[i].one_hot()).collect();
        let ctx_t = Tensor::<2>::from_data(TensorData::new(ctx.clone(), [b, CONTEXT_DIM]), &model.device);
        // guidance: one batch of 2b, conditional first, "labels unknown" second
        let ctx_g = (opts.guidance != 0.0).then(|| {
            let mut both = ctx;
            both.extend(members.iter().flat_map(|&i| contexts[i].one_hot_unlabelled()));
            Tensor::<2>::from_data(TensorData::new(both, [2 * b, CONTEXT_DIM]), &model.device)
        });
        if opts.keep_every > 0 {
            for i in 0..b {
                out.trajectory[members[i]].push((t_start, x[i * TENSOR_LEN..(i + 1) * TENSOR_LEN].to_vec()));
            }
        }
        let mut next = vec![0f32; x.len()];
        let mut z = vec![0f32; TENSOR_LEN];
        for (si, &t) in ts.iter().enumerate() {
            check_progress(progress, calls as f64 / total_calls as f64, "reverse diffusion")?;
            let eps = network_eps(model, net, &x, t, b, &ctx_t, ctx_g.as_ref(), opts)?;
            let s = ts.get(si + 1).copied().unwrap_or(0);
            for i in 0..b {
                let r = i * TENSOR_LEN..(i + 1) * TENSOR_LEN;
                if ancestral {
                    let noise = if t > 1 {
                        for v in z.iter_mut() {
                            *v = StandardNormal.sample(&mut rngs[i]);
                        }
                        Some(&z[..])
                    } else {
                        None
                    };
                    sched.reverse_step(&x[r.clone()], &eps[r.clone()], t, noise, &mut next[r.clone()]);
                } else if opts.clip_margin >= 0.0 {
                    let boxes = clip_boxes(&contexts[members[i]], opts.clip_margin);
                    ddim_step_clipped(sched, &x[r.clone()], &eps[r.clone()], t, s, &boxes, &mut next[r.clone()]);
                } else {
                    sched.ddim_step(&x[r.clone()], &eps[r.clone()], t, s, &mut next[r.clone()]);
                }
            }
            // known null blocks: a forward sample of x_0 = 0 at the new timestep s
            null_blocks_at(sched, s, contexts, members, &mut rngs, &mut next);
            std::mem::swap(&mut x, &mut next);
            calls += 1;
            if opts.keep_every > 0 && ((si + 1) % opts.keep_every == 0 || s == 0) {
                for i in 0..b {
                    out.trajectory[members[i]].push((s, x[i * TENSOR_LEN..(i + 1) * TENSOR_LEN].to_vec()));
                }
            }
        }
        if opts.refine_passes > 0 {
            refine_passes(model, net, opts, contexts, members, &ctx_t, &mut x)?;
        }
        for i in 0..b {
            out.tensors[members[i]] = x[i * TENSOR_LEN..(i + 1) * TENSOR_LEN].to_vec();
        }
    }
    check_progress(progress, 1.0, "reverse diffusion")?;
    Ok(out)
}

/// Every sampler option and input checked before any work.
fn check_sampler_inputs(inputs: &[Vec<f32>], contexts: &[Context], opts: &SamplerOptions) -> Result<()> {
    if opts.start_noise.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
        return Err(Error::InvalidArgument(format!("the sampler's start noise must be positive, got {:?}", opts.start_noise)));
    }
    if !opts.guidance.is_finite() || !opts.eps_scale.is_finite() || opts.kernel_gate.is_some_and(|g| !g.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "sampler weights must be finite (guidance {}, eps_scale {}, kernel_gate {:?})",
            opts.guidance, opts.eps_scale, opts.kernel_gate
        )));
    }
    if inputs.len() != contexts.len() {
        return Err(Error::InvalidArgument(format!(
            "{} input tensors for {} contexts",
            inputs.len(),
            contexts.len()
        )));
    }
    for (i, x) in inputs.iter().enumerate() {
        if x.len() != TENSOR_LEN {
            return Err(Error::InvalidArgument(format!("input tensor {i} has {} values, expected {TENSOR_LEN}", x.len())));
        }
        if x.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidArgument(format!("input tensor {i} holds a non-finite value")));
        }
    }
    Ok(())
}

/// Candidates sharing a start step run together, in batches of at most `batch`, in
/// index order; the latest start first.
fn groups_by_start(starts: &[usize], batch: usize) -> Vec<Vec<usize>> {
    let n = starts.len();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut distinct: Vec<usize> = starts.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    for &t0 in distinct.iter().rev() {
        let members: Vec<usize> = (0..n).filter(|&i| starts[i] == t0).collect();
        groups.extend(members.chunks(batch).map(|c| c.to_vec()));
    }
    groups
}

/// The network's noise estimate for the batch `x` (`b` candidates) at step `t`:
/// with guidance, one batch of 2b (conditional first, "labels unknown" second)
/// combined as c + w (c - u); then scaled by `opts.eps_scale`.
#[allow(clippy::too_many_arguments)]
fn network_eps(model: &Model, net: &super::Net, x: &[f32], t: usize, b: usize, ctx_t: &Tensor<2>, ctx_g: Option<&Tensor<2>>, opts: &SamplerOptions) -> Result<Vec<f32>> {
    let sched = &model.schedule;
    let (xin, bb, ct) = match ctx_g {
        Some(g) => ([x, x].concat(), 2 * b, g.clone()),
        None => (x.to_vec(), b, ctx_t.clone()),
    };
    let xt = Tensor::<4>::from_data(TensorData::new(xin, [bb, 3, TENSOR_H, TENSOR_W]), &model.device);
    let eps = net.forward(xt, &vec![t; bb], ct, sched);
    let mut eps: Vec<f32> = eps
        .into_data()
        .try_into_vec::<f32>()
        .map_err(|e| Error::Internal(format!("reading the network output: {e:?}")))?;
    if ctx_g.is_some() {
        let w = opts.guidance as f32;
        let (c, u) = eps.split_at(b * TENSOR_LEN);
        eps = c.iter().zip(u).map(|(c, u)| c + w * (c - u)).collect();
    }
    if opts.eps_scale != 1.0 {
        let f = opts.eps_scale as f32;
        eps.iter_mut().for_each(|v| *v *= f);
    }
    Ok(eps)
}

/// The null cells of every member's context set to a forward sample of x_0 = 0 at
/// step `s` (exactly 0 at s = 0).
fn null_blocks_at(sched: &super::schedule::Schedule, s: usize, contexts: &[Context], members: &[usize], rngs: &mut [impl rand::Rng], next: &mut [f32]) {
    for i in 0..members.len() {
        let ctx = &contexts[members[i]];
        let base = i * TENSOR_LEN;
        let (sd, shift) = ((1.0 - sched.alpha_bar[s]).sqrt(), sched.qcoef[s]);
        for n in (0..NUM_CELLS).filter(|&n| ctx.labels[n] == Primitive::Null) {
            for p in 0..POINTS_PER_CELL {
                let (r, col) = slot(n, p);
                for ch in 0..3 {
                    let v = if s == 0 {
                        0.0
                    } else {
                        let zv: f64 = StandardNormal.sample(&mut rngs[i]);
                        sd * zv + shift * sched.config.q[ch]
                    };
                    next[base + flat(ch, r, col)] = v as f32;
                }
            }
        }
    }
}

/// `opts.refine_passes` one-step refinements at `opts.refine_t`: noise x to that
/// step, subtract the predicted noise, null cells back to 0.
fn refine_passes(model: &Model, net: &super::Net, opts: &SamplerOptions, contexts: &[Context], members: &[usize], ctx_t: &Tensor<2>, x: &mut [f32]) -> Result<()> {
    let (sched, b) = (&model.schedule, members.len());
    let t = opts.refine_t.clamp(1, sched.steps());
    let (sa, sd, shift) = (sched.alpha_bar[t].sqrt(), (1.0 - sched.alpha_bar[t]).sqrt(), sched.qcoef[t]);
    for _ in 0..opts.refine_passes {
        let mut xt = x.to_vec();
        for (k, v) in xt.iter_mut().enumerate() {
            let ch = (k % TENSOR_LEN) / (TENSOR_H * TENSOR_W);
            *v = (sa * *v as f64 + shift * sched.config.q[ch]) as f32;
        }
        let xt_t = Tensor::<4>::from_data(TensorData::new(xt, [b, 3, TENSOR_H, TENSOR_W]), &model.device);
        let eps: Vec<f32> = net
            .forward(xt_t, &vec![t; b], ctx_t.clone(), sched)
            .into_data()
            .try_into_vec::<f32>()
            .map_err(|e| Error::Internal(format!("reading the network output: {e:?}")))?;
        for (k, v) in x.iter_mut().enumerate() {
            *v -= (sd / sa * eps[k] as f64) as f32;
        }
        for i in 0..b {
            let ctx = &contexts[members[i]];
            for n in (0..NUM_CELLS).filter(|&n| ctx.labels[n] == Primitive::Null) {
                for p in 0..POINTS_PER_CELL {
                    let (r, col) = slot(n, p);
                    for ch in 0..3 {
                        x[i * TENSOR_LEN + flat(ch, r, col)] = 0.0;
                    }
                }
            }
        }
    }
    Ok(())
}

/// The strided step with x_0 clipped per point to its cell's box: x_0 from (y_t, eps),
/// clipped, eps recomputed from the clipped x_0, then the DDIM step to s.
fn ddim_step_clipped(sched: &super::schedule::Schedule, xt: &[f32], eps: &[f32], t: usize, s: usize, boxes: &[Option<([f64; 3], [f64; 3])>], out: &mut [f32]) {
    let (abt, abs) = (sched.alpha_bar[t], sched.alpha_bar[s]);
    let q = sched.config.q;
    for (n, b) in boxes.iter().enumerate() {
        for p in 0..POINTS_PER_CELL {
            let (row, col) = slot(n, p);
            for ch in 0..3 {
                let k = flat(ch, row, col);
                let (qt, qs) = (sched.qcoef[t] * q[ch], sched.qcoef[s] * q[ch]);
                let y = xt[k] as f64 - qt;
                let mut x0 = (y - (1.0 - abt).sqrt() * eps[k] as f64) / abt.sqrt();
                let mut e = eps[k] as f64;
                if let Some((lo, hi)) = b {
                    let c = x0.clamp(lo[ch], hi[ch]);
                    if c != x0 {
                        x0 = c;
                        e = (y - abt.sqrt() * x0) / (1.0 - abt).sqrt();
                    }
                }
                out[k] = (abs.sqrt() * x0 + (1.0 - abs).sqrt() * e + qs) as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_timesteps() {
        assert_eq!(timesteps(500, 0).len(), 500);
        assert_eq!(timesteps(500, 500)[0], 500);
        let t = timesteps(500, 50);
        assert_eq!(t.len(), 50);
        assert_eq!(t[0], 500);
        assert_eq!(*t.last().unwrap(), 10);
        assert!(t.windows(2).all(|w| w[0] > w[1]));
    }
}

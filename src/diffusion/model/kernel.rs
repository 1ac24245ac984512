//! Template attention: the closed-form estimate of x_0 from the label's template
//! prior, blended into the network's output.

use super::*;
use super::prior::prior_image_of;

/// Template attention: each noisy point of a cell attends to the cell's 512
/// template-prior points p_j. Points are laid out in sorted (x, y, z) order in both,
/// so the point in slot i is a draw from the prior points near rank i, not from the
/// whole cell: the prior over j is a Gaussian in rank, exp(-(i - j)^2 / (2 rho^2)),
/// rho learned (a rank-blind estimate was measured worse than the network at every
/// t <= 200, one with rho = 12 as good as the network at t >= 60 and better at
/// t >= 300: the probe `probe_gate`, in git history at 19585e7). Modelling a training point as a prior point plus
/// isotropic jitter of learned size sigma, the forward process gives
/// y = x_t - qshift_t ~ N(sqrt(ab) p_j, v I) with v = ab sigma^2 + (1 - ab), so the
/// posterior weights are softmax_j(-|y - sqrt(ab) p_j|^2 / (2 v) - (i - j)^2 / (2 rho^2)) and
/// E[x_0 | y] = sum_j w_j (p_j + sqrt(ab) sigma^2 / v (y - sqrt(ab) p_j)); its noise is
/// (y - sqrt(ab) x0_hat) / sqrt(1 - ab). The label decides the p_j, so the estimate
/// uses the label by construction — the Bayes denoiser for data drawn from the
/// templates, which the probe `probe_kernel` (git history, 19585e7) measured to make
/// the label's shape.
#[derive(Module, Debug)]
pub struct KernelHead {
    /// Per-timestep blend of the network's output towards the estimate's noise.
    pub(super) gate: Linear,
    /// The estimate x0_hat into the first features.
    pub(super) input: Conv2d,
    /// ln sigma (jitter of the data around the template samples, in cell units).
    pub(super) log_sigma: burn::module::Param<Tensor<1>>,
    /// ln rho (width of the rank prior, in slots).
    pub(super) log_rho: burn::module::Param<Tensor<1>>,
    /// A fixed gate instead of the learned one (sampler option; None = learned).
    #[module(skip)]
    pub(super) gate_override: Option<f32>,
    /// Attend to each cell's primitive sampled off the faces it shares with occupied
    /// neighbours ([`prior_image_visible`]) instead of the whole primitive (sampler
    /// option `SamplerOptions::visible_prior`).
    #[module(skip)]
    pub(super) visible_prior: bool,
    /// Per timestep: sqrt(ab), sqrt(1 - ab), the mean shift per channel.
    #[module(skip)]
    pub(super) coef: Vec<[f32; 5]>,
    /// Squared rank distances (i - j)^2 of a cell's slots, [512 * 512] (built once).
    #[module(skip)]
    pub(super) rank_d2: Vec<f32>,
}

/// Initial jitter of the template attention, in cell units (the training loss is
/// flat in it between 0.005 and 0.04, the probe `probe_gate` (19585e7); generation is not:
/// with 0.01 the decoded points snap to the prior's 512 points and leave gaps, with
/// 0.03 they stay spread, the probe `probe_kernel` with SIGMA / RHO).
pub const KERNEL_SIGMA0: f32 = 0.03;
/// Initial width of the rank prior (slots; the best of 4 / 12 / 32 / none measured
/// by the probe `probe_gate`).
pub const KERNEL_RHO0: f32 = 12.0;

impl KernelHead {
    pub(super) fn new(c0: usize, emb_dim: usize, device: &Device) -> Self {
        KernelHead {
            gate: LinearConfig::new(emb_dim, 1).with_initializer(burn::nn::Initializer::Zeros).init(device),
            input: Conv2dConfig::new([3, c0], [3, 3])
                .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
                .with_initializer(burn::nn::Initializer::Zeros)
                .init(device),
            log_sigma: burn::module::Param::from_tensor(Tensor::<1>::from_floats([KERNEL_SIGMA0.ln()], device)),
            log_rho: burn::module::Param::from_tensor(Tensor::<1>::from_floats([KERNEL_RHO0.ln()], device)),
            gate_override: None,
            visible_prior: false,
            coef: Vec::new(),
            rank_d2: {
                let np = BLOCK_H * BLOCK_W;
                (0..np * np).map(|k| ((k / np) as f32 - (k % np) as f32).powi(2)).collect()
            },
        }
    }

    /// (x0_hat, eps_hat) for x_t [B, 3, 64, 96], timesteps t and the prior image.
    pub(super) fn estimate(&self, x: Tensor<4>, t: &[usize], prior: Tensor<4>) -> (Tensor<4>, Tensor<4>) {
        assert!(!self.coef.is_empty(), "template attention used before Denoiser::with_schedule");
        let device = x.device();
        let b = t.len();
        let nc = NUM_CELLS;
        let np = BLOCK_H * BLOCK_W;
        let co: Vec<[f32; 5]> = t.iter().map(|&tt| self.coef[tt.min(self.coef.len() - 1)]).collect();
        let shift = Tensor::<4>::from_data(TensorData::new(co.iter().flat_map(|c| [c[2], c[3], c[4]]).collect::<Vec<f32>>(), [b, 3, 1, 1]), &device);
        let per = |f: &dyn Fn(&[f32; 5]) -> f32| Tensor::<3>::from_data(TensorData::new(co.iter().map(f).collect::<Vec<f32>>(), [b, 1, 1]), &device)
            .reshape([b, 1, 1, 1]).expand([b, nc, 1, 1]).reshape([b * nc, 1, 1]);
        let sa = per(&|c| c[0]);
        let sd = per(&|c| c[1]);
        let var_data = (self.log_sigma.val() * 2.0).exp().reshape([1, 1, 1]);
        let v = sa.clone().powf_scalar(2.0) * var_data.clone() + sd.clone().powf_scalar(2.0);
        let y = to_cells(x - shift.clone()); // [B*12, 512, 3]
        let p = to_cells(prior);
        let psq = p.clone().powf_scalar(2.0).sum_dim(2).reshape([b * nc, 1, np]);
        let rank = Tensor::<2>::from_data(TensorData::new(self.rank_d2.clone(), [np, np]), &device).reshape([1, np, np]);
        let inv_rho2 = (self.log_rho.val() * -2.0).exp().reshape([1, 1, 1]);
        let logits = (y.clone().matmul(p.clone().swap_dims(1, 2)) * sa.clone() - psq * sa.clone().powf_scalar(2.0) * 0.5) / v.clone()
            - rank * inv_rho2 * 0.5;
        let w = burn::tensor::activation::softmax(logits, 2);
        let pbar = w.matmul(p);
        let x0 = pbar.clone() + (y.clone() - pbar * sa.clone()) * (sa.clone() * var_data / v);
        let eps = (y - x0.clone() * sa) / sd;
        (from_cells(x0, b), from_cells(eps, b))
    }
}

impl KernelHead {
    /// The closed-form template estimate on its own (the baseline generator): the
    /// attention with jitter `sigma` (cell units) and rank width `rho` (slots) over
    /// the label's fixed-seed template sample, for the forward process `schedule`.
    pub fn template_estimator(sigma: f64, rho: f64, schedule: &crate::diffusion::schedule::Schedule, device: &Device) -> KernelHead {
        let mut k = KernelHead::new(1, 1, device);
        k.log_sigma = burn::module::Param::from_tensor(Tensor::<1>::from_floats([sigma.ln() as f32], device));
        k.log_rho = burn::module::Param::from_tensor(Tensor::<1>::from_floats([rho.ln() as f32], device));
        k.gate_override = Some(1.0);
        k.coef = kernel_coefficients(schedule);
        k
    }

    /// The estimate's noise for a batch (see [`KernelHead::estimate_eps_direct`]).
    pub fn template_eps(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Tensor<4> {
        self.estimate_eps_direct(x, t, ctx)
    }

    /// Attend to each cell's visible primitive (see [`Denoiser::with_visible_prior`]).
    pub fn with_visible_prior(mut self, visible: bool) -> Self {
        self.visible_prior = visible;
        self
    }

    /// The noise of [`KernelHead::estimate`] computed per cell on the CPU, for the
    /// estimate alone (gate 1, the sampler's default). The same formula, but a cell
    /// whose prior is all zero (null or withheld) needs no attention (its prior mean
    /// is zero whatever the weights), and weights below e^-88 of the largest (which
    /// f32 rounds to zero or a denormal) are not evaluated: the dense version spent
    /// the reverse process on 12 x 512 x 512 attention weights per candidate and
    /// step, most of them for empty cells or underflowing (BENCHMARKS.md "Search
    /// speed"). Agrees with the tensor version to f32 rounding (checked in the test
    /// `template_attention_is_the_bayes_estimate_and_its_warm_start_changes_nothing`).
    pub(super) fn estimate_eps_direct(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Tensor<4> {
        use crate::polycube::tensor::{flat, slot, POINTS_PER_CELL, TENSOR_LEN};
        use rayon::prelude::*;
        assert!(!self.coef.is_empty(), "template attention used before Denoiser::with_schedule");
        let device = x.device();
        let b = t.len();
        let scalar = |v: Tensor<1>| v.into_data().convert::<f32>().try_into_vec::<f32>().ok().and_then(|v| v.first().copied()).unwrap_or(f32::NAN);
        let var_data = (2.0 * scalar(self.log_sigma.val())).exp();
        let inv_rho2 = (-2.0 * scalar(self.log_rho.val())).exp();
        let xs: Vec<f32> = x.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
        let oh: Vec<f32> = ctx.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
        let priors: Vec<Vec<f32>> = oh.chunks(CONTEXT_DIM).map(|o| prior_image_of(o, self.visible_prior)).collect();
        assert_eq!(xs.len(), b * TENSOR_LEN);
        let np = POINTS_PER_CELL;
        let blocks: Vec<Vec<f32>> = (0..b * NUM_CELLS)
            .into_par_iter()
            .map(|job| {
                let (bi, n) = (job / NUM_CELLS, job % NUM_CELLS);
                let c = self.coef[t[bi].min(self.coef.len() - 1)];
                let (sa, sd) = (c[0], c[1]);
                let v = sa * sa * var_data + sd * sd;
                let keep = sa * var_data / v;
                let (xb, pb) = (&xs[bi * TENSOR_LEN..(bi + 1) * TENSOR_LEN], &priors[bi]);
                let at = |img: &[f32], p: usize| -> [f32; 3] {
                    let (r, col) = slot(n, p);
                    std::array::from_fn(|ch| img[flat(ch, r, col)])
                };
                let pts: Vec<[f32; 3]> = (0..np).map(|j| at(pb, j)).collect();
                let empty = pts.iter().all(|p| p.iter().all(|&q| q == 0.0));
                // logit_ij = y_i . a_j + c_j - (i - j)^2 / (2 rho^2)
                let a: Vec<[f32; 3]> = pts.iter().map(|p| p.map(|q| q * sa / v)).collect();
                let cj: Vec<f32> = pts.iter().map(|p| -0.5 * sa * sa * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) / v).collect();
                let mut out = vec![0f32; 3 * np];
                let mut logit = vec![0f32; np];
                for i in 0..np {
                    let xi = at(xb, i);
                    let y: [f32; 3] = std::array::from_fn(|ch| xi[ch] - c[2 + ch]);
                    let pbar = if empty {
                        [0.0; 3]
                    } else {
                        let mut m = f32::NEG_INFINITY;
                        for j in 0..np {
                            let d = i as f32 - j as f32;
                            let l = y[0] * a[j][0] + y[1] * a[j][1] + y[2] * a[j][2] + cj[j] - 0.5 * d * d * inv_rho2;
                            logit[j] = l;
                            m = m.max(l);
                        }
                        let (mut sw, mut acc) = (0f32, [0f32; 3]);
                        for j in 0..np {
                            let e = logit[j] - m;
                            if e > -88.0 {
                                let w = e.exp();
                                sw += w;
                                for ch in 0..3 {
                                    acc[ch] += w * pts[j][ch];
                                }
                            }
                        }
                        acc.map(|q| q / sw)
                    };
                    for ch in 0..3 {
                        let x0 = pbar[ch] + (y[ch] - pbar[ch] * sa) * keep;
                        out[ch * np + i] = (y[ch] - x0 * sa) / sd;
                    }
                }
                out
            })
            .collect();
        let mut eps = vec![0f32; b * TENSOR_LEN];
        for (job, blk) in blocks.iter().enumerate() {
            let (bi, n) = (job / NUM_CELLS, job % NUM_CELLS);
            for p in 0..np {
                let (r, col) = slot(n, p);
                for ch in 0..3 {
                    eps[bi * TENSOR_LEN + flat(ch, r, col)] = blk[ch * np + p];
                }
            }
        }
        Tensor::<4>::from_data(TensorData::new(eps, [b, 3, TENSOR_H, TENSOR_W]), &device)
    }
}

/// Per timestep: sqrt(ab), sqrt(1 - ab) and the mean shift per channel.
pub(super) fn kernel_coefficients(s: &crate::diffusion::schedule::Schedule) -> Vec<[f32; 5]> {
    (0..=s.steps())
        .map(|t| {
            let ab = s.alpha_bar[t];
            let sh = s.config.q.map(|q| (s.qcoef[t] * q) as f32);
            [ab.sqrt() as f32, (1.0 - ab).sqrt().max(1e-6) as f32, sh[0], sh[1], sh[2]]
        })
        .collect()
}

/// [B, 3, 64, 96] -> [B * 12, 512, 3]: each cell block's points (block order).
fn to_cells(x: Tensor<4>) -> Tensor<3> {
    let b = x.dims()[0];
    let (rb, cb) = (TENSOR_H / BLOCK_H, TENSOR_W / BLOCK_W);
    x.reshape([b, 3, rb, BLOCK_H, cb, BLOCK_W]).permute([0, 2, 4, 3, 5, 1]).reshape([b * rb * cb, BLOCK_H * BLOCK_W, 3])
}

/// Inverse of [`to_cells`].
fn from_cells(x: Tensor<3>, b: usize) -> Tensor<4> {
    let (rb, cb) = (TENSOR_H / BLOCK_H, TENSOR_W / BLOCK_W);
    x.reshape([b, rb, cb, BLOCK_H, BLOCK_W, 3]).permute([0, 5, 1, 3, 2, 4]).reshape([b, 3, TENSOR_H, TENSOR_W])
}

//! The learned point denoiser ("field"): a per-point network conditioned per cell
//! on the cell's primitive label and the noise level, the default generator.
//!
//! Why this shape. The training set draws each occupied cell's 512 points
//! independently and uniformly on its standalone primitive, and the forward process
//! noises every coordinate independently. The minimum-MSE denoiser therefore
//! factorises: the clean position of the point in slot p of cell n depends only on
//! that point's noisy position, the noise level, the cell's label and its frame, and
//! the slot's rank p (the sort order ties rank to x). A network that sees exactly
//! those inputs can represent the optimum, and one that is trained on fresh noise
//! over 25,000 cells learns the primitives' continuous surfaces instead of a fixed
//! sample of them: the probability-flow trajectory then carries each input point to
//! a nearby point of the label's surface (keeping the correspondence and the input's
//! features the label does not explain), where the closed-form template estimate
//! snaps every point to its rank's template sample.
//!
//! Inputs, in the cell's own frame (centre c, edge h in normalised units): the noisy
//! point rescaled to the data scale, y = (x_t - Q_t q) / sqrt(ab_t), made local,
//! u = (y - c) / h, whose noise is s = sqrt(1 - ab_t) / (sqrt(ab_t) h) cell units.
//! Per point: c_in(s) u, sin / cos(pi 2^k u) for k < `octaves`, and the rank in
//! [-1, 1] with a flag saying whether it is given. The rank pins a training point's
//! x to its quantile of the primitive's x-distribution; a real part's cell does not
//! follow that distribution (its faces shared with neighbours carry no points, its
//! sampling is not uniform by the primitive's area), and a denoiser that trusts the
//! rank slides the points towards the quantiles it expects (measured: three times
//! the displacement on a cell without its shared faces). So the sampler withholds it
//! by default, and training withholds it for half of the cells. Per cell: the label one-hot (an all-zero row is "label withheld", trained
//! by label dropout for guidance) and the noise features of ln(s) / 4, fused into a
//! conditioning vector that modulates every residual block (FiLM, per cell).
//! Output: EDM's preconditioned estimate x0(u) = c_skip(s) u + c_out(s) F, with
//! sigma_data the per-coordinate spread of a primitive's surface points (Karras et
//! al., 2022); the predicted noise is (u - x0) / s. The loss is the MSE of F against
//! its target, i.e. the x_0 error weighted by 1 / c_out^2 (see `train_field`).

use burn::module::Module;
use burn::nn::{Initializer, LayerNorm, LayerNormConfig, Linear, LinearConfig};
use burn::tensor::activation::silu;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};

use crate::context::Context;
use crate::polycube::tensor::{flat, slot, POINTS_PER_CELL, TENSOR_H, TENSOR_LEN, TENSOR_W};
use crate::polycube::{cell_coords, Primitive, CONTEXT_DIM, NUM_CELLS};

/// Labels per cell in the one-hot context (null included).
pub const LABELS: usize = CONTEXT_DIM / NUM_CELLS;
/// Width of the noise-level features.
pub const NOISE_FEATURES: usize = 17;

/// Architecture of the point denoiser (stored in every weights file that has one).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FieldConfig {
    /// Hidden width per point (default 128).
    pub width: usize,
    /// Residual blocks (default 4).
    pub blocks: usize,
    /// Width of the per-cell conditioning vector (default 64).
    pub cond_dim: usize,
    /// Octaves of the sinusoidal position features (default 3: pi, 2 pi, 4 pi).
    pub octaves: usize,
    /// Per-coordinate spread of a primitive's surface points in cell units (default
    /// 0.37: on a unit cube's surface E[x^2] = 1/3 * 1/4 + 2/3 * 1/12).
    pub sigma_data: f64,
    /// The rank enters with a "rank known" flag, and training withholds it for a
    /// share of the cells (`TrainConfig::rank_dropout`), so one network serves both
    /// uses: with the rank, the estimate the sorted layout defines (the label probe's
    /// reference); without it, a denoiser of the point alone, which the sampler uses
    /// by default (`SamplerOptions::use_rank`). Weights without the flag (false) always
    /// see the rank.
    pub rank_flag: bool,
}

impl Default for FieldConfig {
    fn default() -> Self {
        FieldConfig { width: 128, blocks: 4, cond_dim: 64, octaves: 3, sigma_data: 0.37, rank_flag: true }
    }
}

impl FieldConfig {
    /// Features per point.
    pub fn point_features(&self) -> usize {
        3 + 6 * self.octaves + 1 + self.rank_flag as usize
    }
}

/// EDM preconditioning at noise s (cell units): (c_in, c_skip, c_out).
pub fn precond(s: f64, sigma_data: f64) -> (f64, f64, f64) {
    let d2 = sigma_data * sigma_data;
    let n = (s * s + d2).sqrt();
    (1.0 / n, d2 / (s * s + d2), s * sigma_data / n)
}

/// The per-point denoiser network.
#[derive(Module, Debug)]
pub struct FieldNet {
    input: Linear,
    label: Linear,
    noise1: Linear,
    noise2: Linear,
    film: Vec<Linear>,
    norm: Vec<LayerNorm>,
    lin1: Vec<Linear>,
    lin2: Vec<Linear>,
    norm_out: LayerNorm,
    out: Linear,
    #[module(skip)]
    width: usize,
    #[module(skip)]
    octaves: usize,
    #[module(skip)]
    sigma_data: f64,
    #[module(skip)]
    rank_flag: bool,
    /// Whether inference gives the network the slots' ranks (only meaningful with
    /// `rank_flag`; without it the rank is always given).
    #[module(skip)]
    use_rank: bool,
}

impl FieldNet {
    pub fn new(cfg: &FieldConfig, device: &Device) -> Self {
        let w = cfg.width;
        let e = cfg.cond_dim;
        FieldNet {
            input: LinearConfig::new(cfg.point_features(), w).init(device),
            label: LinearConfig::new(LABELS, e).init(device),
            noise1: LinearConfig::new(NOISE_FEATURES, e).init(device),
            noise2: LinearConfig::new(e, e).init(device),
            film: (0..cfg.blocks).map(|_| LinearConfig::new(e, 2 * w).init(device)).collect(),
            norm: (0..cfg.blocks).map(|_| LayerNormConfig::new(w).init(device)).collect(),
            lin1: (0..cfg.blocks).map(|_| LinearConfig::new(w, w).init(device)).collect(),
            lin2: (0..cfg.blocks).map(|_| LinearConfig::new(w, w).init(device)).collect(),
            norm_out: LayerNormConfig::new(w).init(device),
            // zero output at first: the estimate starts as c_skip u (shrink to the centre)
            out: LinearConfig::new(w, 3).with_initializer(Initializer::Zeros).init(device),
            width: w,
            octaves: cfg.octaves,
            sigma_data: cfg.sigma_data,
            rank_flag: cfg.rank_flag,
            use_rank: !cfg.rank_flag,
        }
    }

    /// The same network giving (true) or withholding (false) the slots' ranks at
    /// inference; a network trained without the flag always gets them.
    pub fn with_rank(mut self, rank: bool) -> Self {
        self.use_rank = rank || !self.rank_flag;
        self
    }

    /// Whether inference gives the ranks.
    pub fn uses_rank(&self) -> bool {
        self.use_rank
    }

    /// A fresh batch for this network.
    pub fn batch(&self) -> CellBatch {
        CellBatch::new(self.octaves, self.sigma_data, self.rank_flag)
    }

    pub fn sigma_data(&self) -> f64 {
        self.sigma_data
    }

    pub fn octaves(&self) -> usize {
        self.octaves
    }

    /// The network output F. `feats`: [C, P, point_features]; `noise`: [C, 17];
    /// `labels`: [C, 11]. Returns [C, P, 3].
    pub fn forward(&self, feats: Tensor<3>, noise: Tensor<2>, labels: Tensor<2>) -> Tensor<3> {
        let c = feats.dims()[0];
        let w = self.width;
        let cond = silu(self.noise2.forward(silu(self.noise1.forward(noise))) + self.label.forward(labels));
        let mut h = self.input.forward(feats);
        for i in 0..self.lin1.len() {
            let m = self.film[i].forward(cond.clone()).reshape([c, 1, 2 * w]);
            let gamma = m.clone().narrow(2, 0, w);
            let beta = m.narrow(2, w, w);
            let a = self.lin1[i].forward(silu(self.norm[i].forward(h.clone())));
            let a = silu(a * (gamma + 1.0) + beta);
            h = h + self.lin2[i].forward(a);
        }
        self.out.forward(silu(self.norm_out.forward(h)))
    }

    /// Predicted noise for a batch of noisy tensors x_t ([B, 3, 64, 96] flat), one
    /// timestep and one 132-vector per item (an all-zero cell row: label withheld).
    /// Null cells get zero noise (the sampler holds them by replacement).
    pub fn eps(&self, x: &[f32], t: &[usize], one_hot: &[f32], sched: &super::schedule::Schedule, device: &Device) -> Vec<f32> {
        let b = t.len();
        assert_eq!(x.len(), b * TENSOR_LEN);
        assert_eq!(one_hot.len(), b * CONTEXT_DIM);
        let mut batch = self.batch();
        let mut where_: Vec<(usize, usize)> = Vec::new();
        for bi in 0..b {
            let oh = &one_hot[bi * CONTEXT_DIM..(bi + 1) * CONTEXT_DIM];
            let Some(cells) = cell_frames(oh) else { continue };
            let tt = t[bi].min(sched.steps());
            let (sa, sd) = (sched.alpha_bar[tt].sqrt(), (1.0 - sched.alpha_bar[tt]).sqrt());
            let shift = sched.config.q.map(|q| sched.qcoef[tt] * q);
            let xb = &x[bi * TENSOR_LEN..(bi + 1) * TENSOR_LEN];
            for (n, cf) in cells.iter().enumerate() {
                let Some(cf) = cf else { continue };
                let s = sd / (sa * cf.h);
                let local: Vec<[f32; 3]> = (0..POINTS_PER_CELL)
                    .map(|p| {
                        let (r, col) = slot(n, p);
                        std::array::from_fn(|ch| (((xb[flat(ch, r, col)] as f64 - shift[ch]) / sa - cf.centre[ch]) / cf.h) as f32)
                    })
                    .collect();
                batch.push(&local, s, &oh[n * LABELS..(n + 1) * LABELS], self.use_rank);
                where_.push((bi, n));
            }
        }
        let mut out = vec![0f32; b * TENSOR_LEN];
        if batch.cells() == 0 {
            return out;
        }
        let x0 = batch.x0(self, device);
        for (ci, &(bi, n)) in where_.iter().enumerate() {
            let s = batch.s[ci];
            for p in 0..POINTS_PER_CELL {
                let (r, col) = slot(n, p);
                for ch in 0..3 {
                    let k = (ci * POINTS_PER_CELL + p) * 3 + ch;
                    out[bi * TENSOR_LEN + flat(ch, r, col)] = ((batch.local[k] as f64 - x0[k] as f64) / s) as f32;
                }
            }
        }
        out
    }
}

/// One occupied cell's frame in the model's normalised coordinates.
#[derive(Debug, Clone, Copy)]
pub struct CellFrame {
    pub centre: [f64; 3],
    /// Edge length in normalised units.
    pub h: f64,
}

/// The frames of a 132-vector's cells (None for null cells); a withheld row (all
/// zero) counts as occupied, as in the template prior. None when nothing is occupied.
pub fn cell_frames(one_hot: &[f32]) -> Option<[Option<CellFrame>; NUM_CELLS]> {
    let mut labels = [Primitive::Null; NUM_CELLS];
    for (n, l) in labels.iter_mut().enumerate() {
        let row = &one_hot[n * LABELS..(n + 1) * LABELS];
        *l = match row.iter().position(|&v| v > 0.5) {
            Some(k) => Primitive::from_label(k as u8).unwrap_or(Primitive::Null),
            None => Primitive::Cube,
        };
    }
    frames_of(&Context { labels })
}

/// The frames of a context's occupied cells.
pub fn frames_of(ctx: &Context) -> Option<[Option<CellFrame>; NUM_CELLS]> {
    let frame = crate::context::context_frame(ctx)?;
    Some(std::array::from_fn(|n| {
        (ctx.labels[n] != Primitive::Null).then(|| {
            let [i, j, k] = cell_coords(n);
            CellFrame { centre: frame.to_normalised([i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5]), h: frame.scale }
        })
    }))
}

/// Noise-level features of s (cell units): ln(s) / 4 and its sines and cosines.
pub fn noise_features(s: f64) -> [f32; NOISE_FEATURES] {
    let c = s.max(1e-8).ln() / 4.0;
    let mut f = [0f32; NOISE_FEATURES];
    f[0] = c as f32;
    for k in 0..8 {
        let a = c * (1u32 << k) as f64;
        f[1 + 2 * k] = a.sin() as f32;
        f[2 + 2 * k] = a.cos() as f32;
    }
    f
}

/// Cells prepared for the network: features, noise features, labels and the local
/// noisy points they came from.
#[derive(Debug, Clone, Default)]
pub struct CellBatch {
    octaves: usize,
    sigma_data: f64,
    rank_flag: bool,
    pub feats: Vec<f32>,
    pub noise: Vec<f32>,
    pub labels: Vec<f32>,
    /// Local noisy points u, [C, P, 3].
    pub local: Vec<f32>,
    /// Noise per cell, cell units.
    pub s: Vec<f64>,
}

impl CellBatch {
    pub fn new(octaves: usize, sigma_data: f64, rank_flag: bool) -> Self {
        CellBatch { octaves, sigma_data, rank_flag, ..Default::default() }
    }

    pub fn cells(&self) -> usize {
        self.s.len()
    }

    fn point_features(&self) -> usize {
        3 + 6 * self.octaves + 1 + self.rank_flag as usize
    }

    /// Add one cell: its 512 local noisy points in slot order, its noise s, its
    /// label row (11 values; all zero = withheld) and whether the slots' ranks are
    /// given (without the flag they always are).
    pub fn push(&mut self, local: &[[f32; 3]], s: f64, label_row: &[f32], rank: bool) {
        assert_eq!(local.len(), POINTS_PER_CELL);
        assert_eq!(label_row.len(), LABELS);
        let (c_in, _, _) = precond(s, self.sigma_data);
        let np = local.len();
        for (p, u) in local.iter().enumerate() {
            for &v in u {
                self.feats.push((c_in * v as f64) as f32);
            }
            for k in 0..self.octaves {
                let f = std::f32::consts::PI * (1u32 << k) as f32;
                for &v in u {
                    self.feats.push((f * v).sin());
                    self.feats.push((f * v).cos());
                }
            }
            if self.rank_flag {
                self.feats.push(if rank { 2.0 * p as f32 / (np - 1) as f32 - 1.0 } else { 0.0 });
                self.feats.push(rank as u8 as f32);
            } else {
                self.feats.push(2.0 * p as f32 / (np - 1) as f32 - 1.0);
            }
            self.local.extend_from_slice(u);
        }
        self.noise.extend_from_slice(&noise_features(s));
        self.labels.extend_from_slice(label_row);
        self.s.push(s);
    }

    /// The tensors of the batch on `device`: (features, noise, labels).
    pub fn tensors(&self, device: &Device) -> (Tensor<3>, Tensor<2>, Tensor<2>) {
        let c = self.cells();
        (
            Tensor::<3>::from_data(TensorData::new(self.feats.clone(), [c, POINTS_PER_CELL, self.point_features()]), device),
            Tensor::<2>::from_data(TensorData::new(self.noise.clone(), [c, NOISE_FEATURES]), device),
            Tensor::<2>::from_data(TensorData::new(self.labels.clone(), [c, LABELS]), device),
        )
    }

    /// Per point, c_skip and c_out as [C, P, 1]-broadcastable vectors ([C * P]).
    pub fn coefficients(&self) -> (Vec<f32>, Vec<f32>) {
        let mut skip = Vec::with_capacity(self.cells());
        let mut out = Vec::with_capacity(self.cells());
        for &s in &self.s {
            let (_, cs, co) = precond(s, self.sigma_data);
            skip.push(cs as f32);
            out.push(co as f32);
        }
        (skip, out)
    }

    /// The network's x_0 estimate in local coordinates, [C * P * 3].
    pub fn x0(&self, net: &FieldNet, device: &Device) -> Vec<f32> {
        let (f, nz, lb) = self.tensors(device);
        let out: Vec<f32> = net.forward(f, nz, lb).into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
        let (skip, cout) = self.coefficients();
        let per = POINTS_PER_CELL * 3;
        out.iter()
            .enumerate()
            .map(|(k, &o)| {
                let c = k / per;
                skip[c] * self.local[k] + cout[c] * o
            })
            .collect()
    }
}

/// [`FieldNet::eps`] on a [B, 3, 64, 96] tensor (the U-Net's calling convention).
pub fn eps_tensor(net: &FieldNet, x: Tensor<4>, t: &[usize], ctx: Tensor<2>, sched: &super::schedule::Schedule) -> Tensor<4> {
    let device = x.device();
    let b = t.len();
    let xs: Vec<f32> = x.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
    let oh: Vec<f32> = ctx.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
    let e = net.eps(&xs, t, &oh, sched, &device);
    Tensor::<4>::from_data(TensorData::new(e, [b, 3, TENSOR_H, TENSOR_W]), &device)
}

//! The context-conditioned U-Net noise predictor eps(x_t, t, c).
//!
//! Input and output [B, 3, 64, 96]. Two fixed coordinate channels (row and column
//! inside the cell's 16 x 32 block, in [-1, 1]) are appended to the input, because
//! a cell's points are laid out in sorted order and where a pixel sits in its block
//! says where its point is in that order.
//!
//! Conditioning: the sinusoidal timestep embedding and the 132-d context each go
//! through two fully connected layers; their sum modulates every residual block
//! (per channel: h * (1 + gamma) + beta). The context also goes through a second
//! pair of fully connected layers to a 12 x `cell_dim` per-cell code, which each
//! block turns into its own per-cell (gamma, beta), broadcast over the cell's block
//! at that resolution: the modulation is additive and multiplicative at every
//! resolution, globally and per cell.

use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::{GroupNorm, GroupNormConfig, Linear, LinearConfig, PaddingConfig2d};
use burn::tensor::activation::silu;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};

use crate::polycube::tensor::{BLOCK_H, BLOCK_W, TENSOR_H, TENSOR_W};
use crate::polycube::{CONTEXT_DIM, NUM_CELLS};

mod kernel;
mod prior;

pub use kernel::{KernelHead, KERNEL_RHO0, KERNEL_SIGMA0};
pub use prior::{prior_image, prior_image_visible, PRIOR_SEED};
use kernel::kernel_coefficients;
use prior::prior_tensor;

/// Architecture of the noise predictor (stored in every weights file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelConfig {
    /// Channels at full resolution.
    pub base_width: usize,
    /// Channel multipliers at 64x96, 32x48 and 16x24.
    pub mults: [usize; 3],
    /// Width of the sinusoidal timestep encoding.
    pub time_dim: usize,
    /// Width of the fused time / context embedding.
    pub emb_dim: usize,
    /// Per-cell context code width.
    pub cell_dim: usize,
    /// Groups of the group normalisations.
    pub groups: usize,
    /// Width of the pointwise head (0 = none). The head is a small per-point network
    /// at full resolution (1x1 convolutions) that sees the point's own coordinates,
    /// its rank channels, the U-Net's last features and their mean over the point's
    /// cell, modulated by the time / context embedding and the per-cell code; its
    /// output is added to the U-Net's. The noise a point carries at low noise levels
    /// is a nearly pointwise function of the point given the context (its offset from
    /// the primitive's surface over sigma), which 3x3 convolutions over the sorted
    /// layout's neighbours, which are not spatial neighbours, represent poorly.
    #[serde(default)]
    pub point_width: usize,
    /// Template prior input: a fixed-seed sample of the context's primitives, laid out
    /// exactly like x_0 ([`prior_image`]), enters through its own 3x3 convolution added
    /// to the input convolution. The label of a cell then reaches the network as the
    /// shape it stands for, pixel by pixel in the sorted layout, instead of only
    /// through the modulations: a network with only those was measured to ignore the
    /// primitive label entirely (BENCHMARKS.md, "Where the error is"). The convolution
    /// starts at zero, so a warm start from weights without it begins at those weights.
    #[serde(default)]
    pub prior: bool,
    /// Template attention ([`KernelHead`]): every noisy point attends to its cell's
    /// template-prior points with the Bayes posterior weights of the forward process,
    /// giving an estimate of x_0 that depends on the label by construction; the
    /// estimate enters the first features (zero-initialised convolution) and the
    /// output is blended towards the estimate's noise by a learned per-timestep gate
    /// (zero at first). A network with only the modulations and the prior image was
    /// measured to ignore the label (BENCHMARKS.md, "The root cause").
    #[serde(default)]
    pub kernel: bool,
    /// The learned point denoiser instead of the U-Net ([`super::field`]); when set,
    /// every U-Net field above is ignored.
    #[serde(default)]
    pub field: Option<super::field::FieldConfig>,
}

impl Default for ModelConfig {
    fn default() -> Self {
        ModelConfig { base_width: 24, mults: [1, 2, 2], time_dim: 64, emb_dim: 128, cell_dim: 16, groups: 8, point_width: 0, prior: false, kernel: false, field: None }
    }
}

fn conv3(cin: usize, cout: usize, stride: usize, device: &Device) -> Conv2d {
    Conv2dConfig::new([cin, cout], [3, 3])
        .with_stride([stride, stride])
        .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
        .init(device)
}

fn conv1(cin: usize, cout: usize, device: &Device) -> Conv2d {
    Conv2dConfig::new([cin, cout], [1, 1]).init(device)
}

fn group_norm(groups: usize, ch: usize, device: &Device) -> GroupNorm {
    let mut g = groups.min(ch);
    while ch % g != 0 {
        g -= 1;
    }
    GroupNormConfig::new(g, ch).init(device)
}

/// Nearest-neighbour upsampling of [B, C, H, W] by integer factors (fy, fx).
fn upsample(x: Tensor<4>, fy: usize, fx: usize) -> Tensor<4> {
    let [b, c, h, w] = x.dims();
    x.reshape([b, c, h, 1, w, 1]).expand([b, c, h, fy, w, fx]).reshape([b, c, h * fy, w * fx])
}

/// Residual block with FiLM-style modulation by the global embedding and the per-cell code.
#[derive(Module, Debug)]
pub struct ResBlock {
    norm1: GroupNorm,
    conv1: Conv2d,
    norm2: GroupNorm,
    conv2: Conv2d,
    emb: Linear,
    cell: Linear,
    skip: Option<Conv2d>,
    out_ch: usize,
}

impl ResBlock {
    fn new(cin: usize, cout: usize, cfg: &ModelConfig, device: &Device) -> Self {
        ResBlock {
            norm1: group_norm(cfg.groups, cin, device),
            conv1: conv3(cin, cout, 1, device),
            norm2: group_norm(cfg.groups, cout, device),
            conv2: conv3(cout, cout, 1, device),
            emb: LinearConfig::new(cfg.emb_dim, 2 * cout).init(device),
            cell: LinearConfig::new(cfg.cell_dim, 2 * cout).init(device),
            skip: (cin != cout).then(|| conv1(cin, cout, device)),
            out_ch: cout,
        }
    }

    /// `emb`: [B, emb_dim]; `cells`: [B, 12, cell_dim].
    fn forward(&self, x: Tensor<4>, emb: Tensor<2>, cells: Tensor<3>) -> Tensor<4> {
        let [b, _, h, w] = x.dims();
        let c = self.out_ch;
        let hid = self.conv1.forward(silu(self.norm1.forward(x.clone())));
        let hid = self.norm2.forward(hid);
        // Global modulation [B, 2C, 1, 1].
        let g = self.emb.forward(emb).reshape([b, 2 * c, 1, 1]);
        // Per-cell modulation: [B, 12, 2C] -> [B, 4, 3, 2C] -> [B, 2C, 4, 3] -> blocks.
        let pc = self.cell.forward(cells).reshape([b, 4, 3, 2 * c]).permute([0, 3, 1, 2]);
        let pc = upsample(pc, h / 4, w / 3);
        let m = pc + g;
        let gamma = m.clone().narrow(1, 0, c);
        let beta = m.narrow(1, c, c);
        let hid = hid.clone() * (gamma + 1.0) + beta;
        let hid = self.conv2.forward(silu(hid));
        let skip = match &self.skip {
            Some(s) => s.forward(x),
            None => x,
        };
        hid + skip
    }
}

/// Mean of [B, C, 64, 96] over each cell's 16 x 32 block, broadcast back to the block.
fn cell_mean(x: Tensor<4>) -> Tensor<4> {
    let [b, c, h, w] = x.dims();
    let (bh, bw) = (h / 4, w / 3);
    let m = x.reshape([b, c, 4, bh, 3, bw]).mean_dim(3).mean_dim(5).reshape([b, c, 4, 3]);
    upsample(m, bh, bw)
}

/// The pointwise head (see [`ModelConfig::point_width`]).
#[derive(Module, Debug)]
pub struct PointHead {
    inp: Conv2d,
    emb: Linear,
    cell: Linear,
    hid: Conv2d,
    out: Conv2d,
    width: usize,
}

impl PointHead {
    fn new(c0: usize, cfg: &ModelConfig, device: &Device) -> Self {
        let pw = cfg.point_width;
        PointHead {
            inp: conv1(5 + 2 * c0, pw, device),
            emb: LinearConfig::new(cfg.emb_dim, 2 * pw).init(device),
            cell: LinearConfig::new(cfg.cell_dim, 2 * pw).init(device),
            hid: conv1(pw, pw, device),
            // zero output at initialisation: the head starts as "no correction",
            // so a warm start from a U-Net without it begins at that U-Net
            out: Conv2dConfig::new([pw, 3], [1, 1]).with_initializer(burn::nn::Initializer::Zeros).init(device),
            width: pw,
        }
    }

    /// `xin`: [B, 5, H, W] (point + rank channels); `feats`: [B, c0, H, W].
    fn forward(&self, xin: Tensor<4>, feats: Tensor<4>, emb: Tensor<2>, cells: Tensor<3>) -> Tensor<4> {
        let [b, _, h, w] = xin.dims();
        let pw = self.width;
        let pooled = cell_mean(feats.clone());
        let hid = silu(self.inp.forward(Tensor::cat(vec![xin, feats, pooled], 1)));
        let g = self.emb.forward(emb).reshape([b, 2 * pw, 1, 1]);
        let pc = self.cell.forward(cells).reshape([b, 4, 3, 2 * pw]).permute([0, 3, 1, 2]);
        let m = upsample(pc, h / 4, w / 3) + g;
        let gamma = m.clone().narrow(1, 0, pw);
        let beta = m.narrow(1, pw, pw);
        let hid = hid * (gamma + 1.0) + beta;
        let hid = silu(self.hid.forward(hid));
        self.out.forward(hid)
    }
}

/// The U-Net.
#[derive(Module, Debug)]
pub struct Denoiser {
    time1: Linear,
    time2: Linear,
    ctx1: Linear,
    ctx2: Linear,
    cell1: Linear,
    cell2: Linear,
    conv_in: Conv2d,
    enc0: ResBlock,
    down0: Conv2d,
    enc1: ResBlock,
    down1: Conv2d,
    mid0: ResBlock,
    mid1: ResBlock,
    dec1: ResBlock,
    dec0: ResBlock,
    norm_out: GroupNorm,
    conv_out: Conv2d,
    point: Option<PointHead>,
    prior_in: Option<Conv2d>,
    kernel: Option<KernelHead>,
    time_dim: usize,
    cell_dim: usize,
}

impl Denoiser {
    pub fn new(cfg: &ModelConfig, device: &Device) -> Self {
        let c0 = cfg.base_width * cfg.mults[0];
        let c1 = cfg.base_width * cfg.mults[1];
        let c2 = cfg.base_width * cfg.mults[2];
        let e = cfg.emb_dim;
        Denoiser {
            time1: LinearConfig::new(cfg.time_dim, e).init(device),
            time2: LinearConfig::new(e, e).init(device),
            ctx1: LinearConfig::new(CONTEXT_DIM, e).init(device),
            ctx2: LinearConfig::new(e, e).init(device),
            cell1: LinearConfig::new(CONTEXT_DIM, e).init(device),
            cell2: LinearConfig::new(e, NUM_CELLS * cfg.cell_dim).init(device),
            conv_in: conv3(5, c0, 1, device),
            enc0: ResBlock::new(c0, c0, cfg, device),
            down0: conv3(c0, c0, 2, device),
            enc1: ResBlock::new(c0, c1, cfg, device),
            down1: conv3(c1, c1, 2, device),
            mid0: ResBlock::new(c1, c2, cfg, device),
            mid1: ResBlock::new(c2, c2, cfg, device),
            dec1: ResBlock::new(c2 + c1, c1, cfg, device),
            dec0: ResBlock::new(c1 + c0, c0, cfg, device),
            norm_out: group_norm(cfg.groups, c0, device),
            conv_out: conv3(c0, 3, 1, device),
            point: (cfg.point_width > 0).then(|| PointHead::new(c0, cfg, device)),
            prior_in: cfg.prior.then(|| {
                Conv2dConfig::new([3, c0], [3, 3])
                    .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
                    .with_initializer(burn::nn::Initializer::Zeros)
                    .init(device)
            }),
            kernel: cfg.kernel.then(|| KernelHead::new(c0, cfg.emb_dim, device)),
            time_dim: cfg.time_dim,
            cell_dim: cfg.cell_dim,
        }
    }

    /// Give the template attention the forward process's coefficients (a no-op for a
    /// network without it). Loading a weights file does this; a network built by hand
    /// with `kernel` must be given its schedule before `forward`.
    pub fn with_schedule(mut self, s: &super::schedule::Schedule) -> Self {
        if let Some(k) = self.kernel.as_mut() {
            k.coef = kernel_coefficients(s);
        }
        self
    }

    /// Fix the template attention's gate (1 = the estimate alone, 0 = the U-Net
    /// alone; None = the learned gate). A no-op without template attention.
    pub fn with_kernel_gate(mut self, gate: Option<f32>) -> Self {
        if let Some(k) = self.kernel.as_mut() {
            k.gate_override = gate;
        }
        self
    }

    /// Make the template attention attend to the visible part of each cell's
    /// primitive (true) or to the whole primitive (false, what training used). A
    /// no-op without template attention.
    pub fn with_visible_prior(mut self, visible: bool) -> Self {
        if let Some(k) = self.kernel.as_mut() {
            k.visible_prior = visible;
        }
        self
    }

    /// Whether the network has the template attention.
    pub fn has_kernel(&self) -> bool {
        self.kernel.is_some()
    }

    /// The template attention's trained (sigma, rho), if it has one.
    pub fn kernel_params(&self) -> Option<(f64, f64)> {
        let k = self.kernel.as_ref()?;
        let scalar = |v: Tensor<1>| v.into_data().convert::<f64>().try_into_vec::<f64>().ok().and_then(|v| v.first().copied()).unwrap_or(f64::NAN);
        Some((scalar(k.log_sigma.val()).exp(), scalar(k.log_rho.val()).exp()))
    }

    /// The template attention's estimate (x0_hat, eps_hat) for a batch, or None
    /// without it.
    pub fn kernel_estimate(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Option<(Tensor<4>, Tensor<4>)> {
        let k = self.kernel.as_ref()?;
        let prior = prior_tensor(ctx, &x.device(), k.visible_prior);
        Some(k.estimate(x, t, prior))
    }

    /// Predict the noise. `x`: [B, 3, 64, 96]; `t`: the B timesteps; `ctx`: [B, 132].
    pub fn forward(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Tensor<4> {
        let device = x.device();
        let [b, _, h, w] = x.dims();
        assert_eq!(t.len(), b);
        // A gate fixed at 1 is the estimate alone: the U-Net's output would be
        // multiplied by zero, so it is not computed.
        if let Some(k) = self.kernel.as_ref().filter(|k| k.gate_override == Some(1.0)) {
            return k.estimate_eps_direct(x, t, ctx);
        }
        let temb = Tensor::<2>::from_data(TensorData::new(timestep_encoding(t, self.time_dim), [b, self.time_dim]), &device);
        let temb = self.time2.forward(silu(self.time1.forward(temb)));
        let cemb = self.ctx2.forward(silu(self.ctx1.forward(ctx.clone())));
        let emb = silu(temb.clone() + cemb);
        // the template prior is read off the context before the context is consumed
        // (the U-Net's own prior input always sees whole primitives, as in training)
        let prior_img = (self.prior_in.is_some() || self.kernel.is_some()).then(|| prior_tensor(ctx.clone(), &device, false));
        let kernel_img = match self.kernel.as_ref() {
            Some(k) if k.visible_prior => Some(prior_tensor(ctx.clone(), &device, true)),
            _ => prior_img.clone(),
        };
        let prior = self.prior_in.as_ref().zip(prior_img).map(|(p, img)| p.forward(img));
        let kern = self.kernel.as_ref().zip(kernel_img).map(|(k, img)| {
            let (x0, eps) = k.estimate(x.clone(), t, img);
            let gate = match k.gate_override {
                Some(g) => Tensor::<4>::full([b, 1, 1, 1], g, &device),
                None => k.gate.forward(silu(temb.clone())).reshape([b, 1, 1, 1]),
            };
            (k.input.forward(x0), eps, gate)
        });
        let cells = self.cell2.forward(silu(self.cell1.forward(ctx))).reshape([b, NUM_CELLS, self.cell_dim]);

        let coords = Tensor::<4>::from_data(TensorData::new(coordinate_channels(), [1, 2, h, w]), &device).expand([b, 2, h, w]);
        let x = Tensor::cat(vec![x, coords], 1);
        let xin = self.point.as_ref().map(|_| x.clone());
        let mut h0 = self.conv_in.forward(x);
        if let Some(p) = prior {
            h0 = h0 + p;
        }
        if let Some((kin, _, _)) = &kern {
            h0 = h0 + kin.clone();
        }
        let h0 = self.enc0.forward(h0, emb.clone(), cells.clone());
        let h1 = self.down0.forward(h0.clone());
        let h1 = self.enc1.forward(h1, emb.clone(), cells.clone());
        let h2 = self.down1.forward(h1.clone());
        let h2 = self.mid0.forward(h2, emb.clone(), cells.clone());
        let h2 = self.mid1.forward(h2, emb.clone(), cells.clone());
        let u1 = upsample(h2, 2, 2);
        let u1 = self.dec1.forward(Tensor::cat(vec![u1, h1], 1), emb.clone(), cells.clone());
        let u0 = upsample(u1, 2, 2);
        let u0 = self.dec0.forward(Tensor::cat(vec![u0, h0], 1), emb.clone(), cells.clone());
        let out = self.conv_out.forward(silu(self.norm_out.forward(u0.clone())));
        let out = match (&self.point, xin) {
            (Some(p), Some(xin)) => out + p.forward(xin, u0, emb, cells),
            _ => out,
        };
        match kern {
            Some((_, eps, gate)) => out.clone() + (eps - out) * gate,
            None => out,
        }
    }
}

/// Sinusoidal encoding of integer timesteps, [B * dim] row-major.
pub fn timestep_encoding(t: &[usize], dim: usize) -> Vec<f32> {
    let half = dim / 2;
    let mut out = vec![0f32; t.len() * dim];
    for (bi, &tt) in t.iter().enumerate() {
        for i in 0..half {
            let freq = (-(10000f64.ln()) * i as f64 / half as f64).exp();
            let a = tt as f64 * freq;
            out[bi * dim + i] = a.sin() as f32;
            out[bi * dim + half + i] = a.cos() as f32;
        }
    }
    out
}

/// Row / column position inside each cell block, scaled to [-1, 1]: [2, 64, 96].
pub fn coordinate_channels() -> Vec<f32> {
    let mut v = vec![0f32; 2 * TENSOR_H * TENSOR_W];
    for r in 0..TENSOR_H {
        for c in 0..TENSOR_W {
            v[r * TENSOR_W + c] = 2.0 * (r % BLOCK_H) as f32 / (BLOCK_H - 1) as f32 - 1.0;
            v[TENSOR_H * TENSOR_W + r * TENSOR_W + c] = 2.0 * (c % BLOCK_W) as f32 / (BLOCK_W - 1) as f32 - 1.0;
        }
    }
    v
}

/// Number of trainable scalars.
pub fn parameter_count(m: &Denoiser) -> usize {
    m.num_params()
}

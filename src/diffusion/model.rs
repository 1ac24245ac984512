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

/// The template priors of a batch of contexts as a [B, 3, 64, 96] tensor (each
/// cell's visible part with `visible`, see [`prior_image_visible`]).
fn prior_tensor(ctx: Tensor<2>, device: &Device, visible: bool) -> Tensor<4> {
    let b = ctx.dims()[0];
    let oh: Vec<f32> = ctx.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
    let img: Vec<f32> = oh.chunks(CONTEXT_DIM).flat_map(|o| prior_image_of(o, visible)).collect();
    Tensor::<4>::from_data(TensorData::new(img, [b, 3, TENSOR_H, TENSOR_W]), device)
}

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
    gate: Linear,
    /// The estimate x0_hat into the first features.
    input: Conv2d,
    /// ln sigma (jitter of the data around the template samples, in cell units).
    log_sigma: burn::module::Param<Tensor<1>>,
    /// ln rho (width of the rank prior, in slots).
    log_rho: burn::module::Param<Tensor<1>>,
    /// A fixed gate instead of the learned one (sampler option; None = learned).
    #[module(skip)]
    gate_override: Option<f32>,
    /// Attend to each cell's primitive sampled off the faces it shares with occupied
    /// neighbours ([`prior_image_visible`]) instead of the whole primitive (sampler
    /// option `SamplerOptions::visible_prior`).
    #[module(skip)]
    visible_prior: bool,
    /// Per timestep: sqrt(ab), sqrt(1 - ab), the mean shift per channel.
    #[module(skip)]
    coef: Vec<[f32; 5]>,
    /// Squared rank distances (i - j)^2 of a cell's slots, [512 * 512] (built once).
    #[module(skip)]
    rank_d2: Vec<f32>,
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
    fn new(c0: usize, emb_dim: usize, device: &Device) -> Self {
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
    fn estimate(&self, x: Tensor<4>, t: &[usize], prior: Tensor<4>) -> (Tensor<4>, Tensor<4>) {
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
    pub fn template_estimator(sigma: f64, rho: f64, schedule: &super::schedule::Schedule, device: &Device) -> KernelHead {
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
    fn estimate_eps_direct(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Tensor<4> {
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
fn kernel_coefficients(s: &super::schedule::Schedule) -> Vec<[f32; 5]> {
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

/// Seed of the template prior's samples (fixed: the prior is a function of the context).
pub const PRIOR_SEED: u64 = 0x5052_494f_52;

/// The template prior of one 132-vector: [3, 64, 96] laid out like x_0, each occupied
/// cell holding 512 points of its primitive sampled with a fixed seed (scale 1, sorted);
/// null cells and occupied cells whose label is withheld (an all-zero row, see
/// `Context::one_hot_unlabelled`) hold zeros. The occupied box, hence the frame, counts
/// withheld cells as occupied.
pub fn prior_image(one_hot: &[f32]) -> Vec<f32> {
    prior_image_of(one_hot, false)
}

/// [`prior_image`] with each cell's primitive sampled off the faces it shares with
/// occupied neighbours (`dataset::sample_cells_visible`).
pub fn prior_image_visible(one_hot: &[f32]) -> Vec<f32> {
    prior_image_of(one_hot, true)
}

fn prior_image_of(one_hot: &[f32], visible: bool) -> Vec<f32> {
    use crate::polycube::Primitive;
    let nl = CONTEXT_DIM / NUM_CELLS;
    let mut labels = [Primitive::Null; NUM_CELLS];
    let mut withheld = [false; NUM_CELLS];
    for n in 0..NUM_CELLS {
        let row = &one_hot[n * nl..(n + 1) * nl];
        match row.iter().position(|&v| v > 0.5) {
            Some(l) => labels[n] = Primitive::from_label(l as u8).unwrap_or(Primitive::Null),
            None => {
                labels[n] = Primitive::Cube;
                withheld[n] = true;
            }
        }
    }
    let ctx = crate::context::Context { labels };
    let mut rng = crate::geometry::rng::seeded_rng(PRIOR_SEED, 0);
    let mut cells = if visible {
        crate::diffusion::dataset::sample_cells_visible(&ctx, 1.0, &mut rng)
    } else {
        crate::diffusion::dataset::sample_cells(&ctx, 1.0, &mut rng)
    };
    for n in 0..NUM_CELLS {
        if withheld[n] {
            cells[n].clear();
        }
    }
    crate::polycube::tensor::layout(&cells)
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

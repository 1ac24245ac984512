//! The generative core: the nonzero-mean diffusion schedule, the context-conditioned
//! U-Net, its training data set ([`dataset`]), training, the weights files and
//! reverse diffusion.
//!
//! The compute device is chosen here and only here ([`Backend`], [`device`]): burn's
//! pure-Rust `flex` CPU backend by default, burn-ndarray behind the `ndarray` cargo
//! feature, and GPU backends behind `wgpu` / `cuda`.

pub mod dataset;
pub mod field;
pub mod model;
pub mod sample;
pub mod schedule;
pub mod train;
pub mod train_field;
pub mod weights;

use crate::error::{Error, Result};
use burn::module::Module;
use burn::tensor::{Device, Tensor};
use field::FieldNet;
use model::{Denoiser, ModelConfig};
use schedule::Schedule;
use weights::WeightsMeta;

/// The compute backends a model can run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// burn-flex: pure-Rust CPU backend (default).
    #[default]
    Flex,
    /// burn-ndarray (feature `ndarray`).
    #[cfg(feature = "ndarray")]
    Ndarray,
    /// wgpu (feature `wgpu`).
    #[cfg(feature = "wgpu")]
    Wgpu,
    /// CUDA (feature `cuda`).
    #[cfg(feature = "cuda")]
    Cuda,
}

/// The one place a device is made.
pub fn device(backend: Backend) -> Device {
    match backend {
        Backend::Flex => Device::flex(),
        #[cfg(feature = "ndarray")]
        Backend::Ndarray => Device::ndarray(),
        #[cfg(feature = "wgpu")]
        Backend::Wgpu => Device::wgpu(Default::default()),
        #[cfg(feature = "cuda")]
        Backend::Cuda => Device::cuda(0),
    }
}

/// The default weights, trained by `sddpm train` from seed 42 and embedded in the library.
pub static DEFAULT_WEIGHTS: &[u8] = include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/models/default.sddpmw"));

/// The network of a model: the learned point denoiser (the default, [`field`]) or
/// the U-Net with its optional template attention ([`model`]).
#[derive(Debug, Clone)]
pub enum Net {
    UNet(Denoiser),
    Field(FieldNet),
    /// The closed-form template estimate alone (the baseline generator; no weights).
    Template(model::KernelHead),
}

impl Net {
    /// The U-Net, if this is one.
    pub fn unet(&self) -> Option<&Denoiser> {
        match self {
            Net::UNet(d) => Some(d),
            _ => None,
        }
    }

    /// The point denoiser, if this is one.
    pub fn field(&self) -> Option<&FieldNet> {
        match self {
            Net::Field(f) => Some(f),
            _ => None,
        }
    }

    pub fn num_params(&self) -> usize {
        match self {
            Net::UNet(d) => d.num_params(),
            Net::Field(f) => f.num_params(),
            Net::Template(_) => 0,
        }
    }

    /// Predict the noise. `x`: [B, 3, 64, 96]; `t`: the B timesteps; `ctx`: [B, 132].
    pub fn forward(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>, schedule: &Schedule) -> Tensor<4> {
        match self {
            Net::UNet(d) => d.forward(x, t, ctx),
            Net::Field(f) => field::eps_tensor(f, x, t, ctx, schedule),
            Net::Template(k) => k.template_eps(x, t, ctx),
        }
    }

    /// The same network with the sampler's options applied: the template
    /// attention's gate and prior, and whether the point denoiser sees the ranks.
    pub fn configured(&self, kernel_gate: Option<f32>, visible_prior: bool, use_rank: bool) -> Net {
        match self {
            Net::UNet(d) => Net::UNet(d.clone().with_kernel_gate(kernel_gate).with_visible_prior(visible_prior)),
            Net::Field(f) => Net::Field(f.clone().with_rank(use_rank)),
            Net::Template(k) => Net::Template(k.clone().with_visible_prior(visible_prior)),
        }
    }

    /// Whether sampling with this network (and the sampler's template-attention
    /// gate) evaluates the template estimate alone, i.e. is the baseline generator.
    pub fn is_template(&self, kernel_gate: Option<f64>) -> bool {
        match self {
            Net::Template(_) => true,
            Net::UNet(d) => d.has_kernel() && kernel_gate == Some(1.0),
            Net::Field(_) => false,
        }
    }
}

/// A loaded model: metadata, schedule and network on a device. Immutable once
/// loaded, so one `Model` may be shared by threads.
#[derive(Debug)]
pub struct Model {
    pub meta: WeightsMeta,
    pub schedule: Schedule,
    pub net: Net,
    pub device: Device,
}

impl Model {
    /// The embedded default model on the default backend.
    pub fn default_model() -> Result<Model> {
        Model::from_bytes(DEFAULT_WEIGHTS, Backend::default())
    }

    pub fn from_file(path: &std::path::Path, backend: Backend) -> Result<Model> {
        let meta = std::fs::metadata(path).map_err(|e| Error::io(path.display(), e))?;
        if meta.len() as usize > weights::MAX_WEIGHTS_BYTES {
            return Err(Error::Model(format!("{}: {} bytes is larger than the limit of {} bytes", path.display(), meta.len(), weights::MAX_WEIGHTS_BYTES)));
        }
        let bytes = std::fs::read(path).map_err(|e| Error::io(path.display(), e))?;
        Model::from_bytes(&bytes, backend).map_err(|e| match e {
            Error::Model(m) => Error::Model(format!("{}: {m}", path.display())),
            o => o,
        })
    }

    pub fn from_bytes(bytes: &[u8], backend: Backend) -> Result<Model> {
        let (meta, record) = weights::decode(bytes)?;
        let device = device(backend);
        let schedule = Schedule::new(meta.schedule.clone());
        let net = load_any_net(&meta.model, record, &device, &schedule)?;
        Ok(Model { meta, schedule, net, device })
    }

    /// Serialise (metadata + parameters) into the weights-file format.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        Ok(weights::encode(&self.meta, &any_net_bytes(&self.net, false)?))
    }

    /// The same model as a weights-file image with half-precision parameters.
    pub fn to_bytes_f16(&self) -> Result<Vec<u8>> {
        let meta = weights::WeightsMeta { dtype: "f16".into(), ..self.meta.clone() };
        Ok(weights::encode(&meta, &any_net_bytes(&self.net, true)?))
    }

    pub fn save(&self, path: &std::path::Path) -> Result<()> {
        let b = self.to_bytes()?;
        std::fs::write(path, b).map_err(|e| Error::io(path.display(), e))
    }

    pub fn parameter_count(&self) -> usize {
        self.net.num_params()
    }

    /// Predict the noise (see [`Net::forward`]).
    pub fn forward(&self, x: Tensor<4>, t: &[usize], ctx: Tensor<2>) -> Tensor<4> {
        self.net.forward(x, t, ctx, &self.schedule)
    }

    /// The name of the generator that sampling with these options runs: "template"
    /// for the closed-form template estimate (the baseline), otherwise the learned
    /// weights' name, "<arch>-<thousands of parameters>k-seed<S>-e<epochs>".
    pub fn generator_name(&self, kernel_gate: Option<f64>) -> String {
        if self.net.is_template(kernel_gate) {
            return TEMPLATE_GENERATOR.to_string();
        }
        let kind = match self.net {
            Net::Field(_) => "field",
            _ => "unet",
        };
        format!("{kind}-{}k-seed{}-e{}", self.parameter_count() / 1000, self.meta.training.seed, self.meta.training.epochs)
    }

    /// The baseline generator: the closed-form template estimate with the jitter and
    /// rank width the template-attention training reached ([`TEMPLATE_SIGMA`],
    /// [`TEMPLATE_RHO`]), on the reference schedule. Needs no weights.
    pub fn template() -> Model {
        let device = device(Backend::default());
        let schedule = Schedule::new(schedule::ScheduleConfig::default());
        let net = Net::Template(model::KernelHead::template_estimator(TEMPLATE_SIGMA, TEMPLATE_RHO, &schedule, &device));
        let meta = WeightsMeta {
            format_version: 1,
            library_version: env!("CARGO_PKG_VERSION").to_string(),
            model: ModelConfig::default(),
            schedule: schedule.config.clone(),
            dataset: Default::default(),
            training: Default::default(),
            dtype: "none".into(),
        };
        Model { meta, schedule, net, device }
    }
}

/// The generator name of the closed-form template estimate.
pub const TEMPLATE_GENERATOR: &str = "template";
/// Jitter of the baseline template estimate, cell units: the value the template
/// attention's one-epoch training reached from 0.03 (the U-Net with template
/// attention, `models/` history in docs/history.md).
pub const TEMPLATE_SIGMA: f64 = 0.029325528131659846;
/// Rank width of the baseline template estimate, slots (trained from 12).
pub const TEMPLATE_RHO: f64 = 12.230174893930755;

/// The record bytes of either network, optionally in half precision.
pub fn any_net_bytes(net: &Net, half: bool) -> Result<Vec<u8>> {
    match (net, half) {
        (Net::UNet(d), false) => net_bytes(d),
        (Net::UNet(d), true) => net_bytes_f16(d),
        (Net::Field(f), false) => module_bytes(f.clone()),
        (Net::Field(f), true) => module_bytes_f16(f.clone()),
        (Net::Template(_), _) => Err(Error::Model("the template estimate has no weights to save".into())),
    }
}

/// Build the network a configuration names and load a record into it.
pub fn load_any_net(cfg: &ModelConfig, record: &[u8], device: &Device, schedule: &Schedule) -> Result<Net> {
    match &cfg.field {
        Some(fc) => {
            let fresh = fresh_field(fc, device, None);
            Ok(Net::Field(load_module(fresh, record, false)?))
        }
        None => Ok(Net::UNet(load_net(cfg, record, device)?.with_schedule(schedule))),
    }
}

/// A freshly initialised point denoiser (seeded like [`fresh_net`]).
pub(crate) fn fresh_field(cfg: &field::FieldConfig, device: &Device, seed: Option<u64>) -> FieldNet {
    let _guard = INIT_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = seed {
        device.seed(s);
    }
    FieldNet::new(cfg, device)
}

/// Any module's parameters as a burnpack byte record.
pub fn module_bytes<M: Module>(m: M) -> Result<Vec<u8>> {
    let b = m.into_record().into_bytes().map_err(|e| Error::Model(format!("cannot serialise the parameters: {e:?}")))?;
    Ok(b.to_vec())
}

/// Any module's parameters as a burnpack byte record in half precision.
pub fn module_bytes_f16<M: Module>(m: M) -> Result<Vec<u8>> {
    use burn::module::{ModuleMapper, Param};
    use burn::tensor::FloatDType;
    struct ToF16;
    impl ModuleMapper for ToF16 {
        fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
            param.map(|t| t.cast(FloatDType::F16))
        }
    }
    module_bytes(m.map(&mut ToF16))
}

/// Load a burnpack record into a module (cast to the module's dtype); a corrupt or
/// mismatched record is an error, never a panic.
pub fn load_module<M: Module>(m: M, record: &[u8], partial: bool) -> Result<M> {
    let bytes = burn::tensor::Bytes::from_bytes_vec(record.to_vec());
    let rec = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| burn::store::ModuleRecord::from_bytes(bytes)))
        .map_err(|_| Error::Model("the parameter record is corrupt".into()))?
        .map_err(|e| Error::Model(format!("the parameter record cannot be read: {e:?}")))?;
    let rec = rec.cast_to_module_dtype().allow_partial(partial);
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| m.try_load_record(rec)))
        .map_err(|_| Error::Model("the parameter record does not match the architecture".into()))?
        .map_err(|e| Error::Model(format!("the parameter record does not match the architecture: {e:?}")))
}

static INIT_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Parameters of a network as a burnpack byte record in half precision (IEEE
/// binary16): half the size; loading casts back to f32 (`load_net`).
pub fn net_bytes_f16(net: &Denoiser) -> Result<Vec<u8>> {
    module_bytes_f16(net.clone())
}

/// Parameters of a network as a burnpack byte record.
pub fn net_bytes(net: &Denoiser) -> Result<Vec<u8>> {
    module_bytes(net.clone())
}

/// Build a network of the given architecture and load a burnpack record into it.
pub fn load_net(cfg: &ModelConfig, record: &[u8], device: &Device) -> Result<Denoiser> {
    load_net_with(cfg, record, device, false)
}

/// As [`load_net`]; `partial` accepts a record without some of the module's
/// parameters (a warm start of a larger architecture: those keep their
/// initialisation).
pub fn load_net_with(cfg: &ModelConfig, record: &[u8], device: &Device, partial: bool) -> Result<Denoiser> {
    load_net_seeded(cfg, record, device, partial, None)
}

/// A freshly initialised network, its weights drawn from burn's process-wide
/// generator (seeded first when `seed` is given). Every construction takes one lock,
/// so that a seeded initialisation (training from a seed) is not interleaved with
/// the draws of another thread's construction (a model loaded concurrently, tests
/// run in parallel): the same seed gives the same weights.
pub(crate) fn fresh_net(cfg: &ModelConfig, device: &Device, seed: Option<u64>) -> Denoiser {
    let _guard = INIT_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = seed {
        device.seed(s);
    }
    Denoiser::new(cfg, device)
}

/// As [`load_net_with`], the parameters missing from a partial record initialised
/// from `seed`.
pub(crate) fn load_net_seeded(cfg: &ModelConfig, record: &[u8], device: &Device, partial: bool, seed: Option<u64>) -> Result<Denoiser> {
    load_module(fresh_net(cfg, device, seed), record, partial)
}

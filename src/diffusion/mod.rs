//! The generative core: the nonzero-mean diffusion schedule, the context-conditioned
//! U-Net, training, the weights files and reverse diffusion.
//!
//! The compute device is chosen here and only here ([`Backend`], [`device`]): burn's
//! pure-Rust `flex` CPU backend by default, burn-ndarray behind the `ndarray` cargo
//! feature, and GPU backends behind `wgpu` / `cuda`.

pub mod eval;
pub mod model;
pub mod sample;
pub mod schedule;
pub mod train;
pub mod weights;

use crate::error::{Error, Result};
use burn::module::Module;
use burn::tensor::Device;
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

/// A loaded model: metadata, schedule and network on a device. Immutable once
/// loaded, so one `Model` may be shared by threads.
#[derive(Debug)]
pub struct Model {
    pub meta: WeightsMeta,
    pub schedule: Schedule,
    pub net: Denoiser,
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
        let net = load_net(&meta.model, record, &device)?.with_schedule(&schedule);
        Ok(Model { meta, schedule, net, device })
    }

    /// Serialise (metadata + parameters) into the weights-file format.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        Ok(weights::encode(&self.meta, &net_bytes(&self.net)?))
    }

    /// The same model as a weights-file image with half-precision parameters.
    pub fn to_bytes_f16(&self) -> Result<Vec<u8>> {
        let meta = weights::WeightsMeta { dtype: "f16".into(), ..self.meta.clone() };
        Ok(weights::encode(&meta, &net_bytes_f16(&self.net)?))
    }

    pub fn save(&self, path: &std::path::Path) -> Result<()> {
        let b = self.to_bytes()?;
        std::fs::write(path, b).map_err(|e| Error::io(path.display(), e))
    }

    pub fn parameter_count(&self) -> usize {
        self.net.num_params()
    }
}

/// Parameters of a network as a burnpack byte record in half precision (IEEE
/// binary16): half the size; loading casts back to f32 (`load_net`).
pub fn net_bytes_f16(net: &Denoiser) -> Result<Vec<u8>> {
    use burn::module::{ModuleMapper, Param};
    use burn::tensor::{FloatDType, Tensor};
    struct ToF16;
    impl ModuleMapper for ToF16 {
        fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
            param.map(|t| t.cast(FloatDType::F16))
        }
    }
    let half = net.clone().map(&mut ToF16);
    let b = half.into_record().into_bytes().map_err(|e| Error::Model(format!("cannot serialise the parameters: {e:?}")))?;
    Ok(b.to_vec())
}

/// Parameters of a network as a burnpack byte record.
pub fn net_bytes(net: &Denoiser) -> Result<Vec<u8>> {
    let rec = net.clone().into_record();
    let b = rec.into_bytes().map_err(|e| Error::Model(format!("cannot serialise the parameters: {e:?}")))?;
    Ok(b.to_vec())
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
    static INIT: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _guard = INIT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = seed {
        device.seed(s);
    }
    Denoiser::new(cfg, device)
}

/// As [`load_net_with`], the parameters missing from a partial record initialised
/// from `seed`.
pub(crate) fn load_net_seeded(cfg: &ModelConfig, record: &[u8], device: &Device, partial: bool, seed: Option<u64>) -> Result<Denoiser> {
    let bytes = burn::tensor::Bytes::from_bytes_vec(record.to_vec());
    // Parsing foreign bytes must never take the process down: catch a panic in the decoder.
    let rec = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| burn::store::ModuleRecord::from_bytes(bytes)))
        .map_err(|_| Error::Model("the parameter record is corrupt".into()))?
        .map_err(|e| Error::Model(format!("the parameter record cannot be read: {e:?}")))?;
    let net = fresh_net(cfg, device, seed);
    let rec = rec.cast_to_module_dtype().allow_partial(partial);
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| net.try_load_record(rec)))
        .map_err(|_| Error::Model("the parameter record does not match the architecture".into()))?
        .map_err(|e| Error::Model(format!("the parameter record does not match the architecture: {e:?}")))
}

//! Self-describing weights files: architecture, schedule, training-data seed and
//! library version travel with the parameters, so a file fully describes its model.
//!
//! Layout (little endian):
//! ```text
//! 8 bytes  magic "SDDPMW\0\x01"
//! u32      length of the JSON metadata
//! ...      JSON metadata (WeightsMeta)
//! u64      length of the parameter record
//! ...      burnpack record of the Denoiser's parameters (f32 or f16)
//! ```

use super::model::ModelConfig;
use super::schedule::ScheduleConfig;
use crate::error::{Error, Result};
use crate::diffusion::dataset::DatasetConfig;
use serde::{Deserialize, Serialize};

pub const MAGIC: &[u8; 8] = b"SDDPMW\0\x01";
/// Upper bound on a weights file (refused before parsing above this).
pub const MAX_WEIGHTS_BYTES: usize = 256 << 20;

/// How the weights were trained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct TrainingInfo {
    pub seed: u64,
    pub epochs: usize,
    pub steps: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
    pub final_loss: f64,
    pub seconds: f64,
    /// Largest training timestep (0 = all T) and the timestep density exponent.
    #[serde(default)]
    pub t_max: usize,
    #[serde(default = "one")]
    pub t_power: f64,
    /// The weights this run was fine-tuned from (None = seeded initialisation).
    #[serde(default)]
    pub init_from: Option<String>,
    /// Heavier-tailed training noise (probability, scale); (0, 1) = plain Gaussian.
    #[serde(default)]
    pub outlier_prob: f64,
    #[serde(default = "one")]
    pub outlier_scale: f64,
    /// Label dropout (classifier-free guidance training); 0 = off.
    #[serde(default)]
    pub label_dropout: f64,
    /// Rank dropout (point denoiser); 0 = off.
    #[serde(default)]
    pub rank_dropout: f64,
}

fn one() -> f64 {
    1.0
}

/// Metadata stored in front of the parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WeightsMeta {
    pub format_version: u32,
    pub library_version: String,
    pub model: ModelConfig,
    pub schedule: ScheduleConfig,
    pub dataset: DatasetConfig,
    pub training: TrainingInfo,
    /// "f32" or "f16".
    pub dtype: String,
}

/// Encode metadata + record bytes into one file image.
pub fn encode(meta: &WeightsMeta, record: &[u8]) -> Vec<u8> {
    let json = serde_json::to_vec(meta).expect("metadata serialises");
    let mut out = Vec::with_capacity(8 + 4 + json.len() + 8 + record.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(record.len() as u64).to_le_bytes());
    out.extend_from_slice(record);
    out
}

/// Split a file image into metadata and record bytes, checking every length.
pub fn decode(bytes: &[u8]) -> Result<(WeightsMeta, &[u8])> {
    let bad = |m: &str| Error::Model(format!("not a libsddpm weights file: {m}"));
    if bytes.len() > MAX_WEIGHTS_BYTES {
        return Err(Error::Model(format!(
            "weights file of {} bytes is larger than the limit of {MAX_WEIGHTS_BYTES}",
            bytes.len()
        )));
    }
    if bytes.len() < 12 || &bytes[..8] != MAGIC {
        return Err(bad("missing the SDDPMW header"));
    }
    let jlen = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
    let jend = 12usize.checked_add(jlen).filter(|&e| e + 8 <= bytes.len()).ok_or_else(|| bad("metadata length runs past the end"))?;
    let meta: WeightsMeta = serde_json::from_slice(&bytes[12..jend]).map_err(|e| bad(&format!("metadata: {e}")))?;
    let rlen = u64::from_le_bytes(bytes[jend..jend + 8].try_into().unwrap()) as usize;
    let rstart = jend + 8;
    if rlen != bytes.len() - rstart {
        return Err(bad(&format!("record length {rlen} does not match the {} bytes that follow", bytes.len() - rstart)));
    }
    if meta.format_version != 1 {
        return Err(Error::Model(format!("weights format version {} is not supported (expected 1)", meta.format_version)));
    }
    let m = &meta.model;
    if m.base_width == 0 || m.base_width > 512 || m.mults.iter().any(|&x| x == 0 || x > 8) || m.time_dim < 2 || m.time_dim > 4096
        || m.emb_dim == 0 || m.emb_dim > 4096 || m.cell_dim == 0 || m.cell_dim > 1024 || m.groups == 0 || m.point_width > 4096
    {
        return Err(bad("architecture fields are out of range"));
    }
    let s = &meta.schedule;
    if s.steps == 0 || s.steps > 100_000 || !(s.beta_start > 0.0 && s.beta_end < 1.0 && s.beta_start <= s.beta_end)
        || s.q.iter().any(|q| !q.is_finite())
    {
        return Err(bad("schedule fields are out of range"));
    }
    Ok((meta, &bytes[rstart..]))
}

//! `sddpm weights IN -o OUT [--half]`: rewrite a weights file, in half precision
//! with --half (the compact record the library embeds), and print its metadata.

use sddpm::diffusion::{Backend, Model};
use sddpm::Result;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct WeightsArgs {
    /// Weights file to read.
    pub input: PathBuf,
    /// Weights file to write.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Store the parameters as IEEE binary16 (half the size; loaded back as f32).
    #[arg(long)]
    pub half: bool,
}

pub fn run(a: &WeightsArgs) -> Result<i32> {
    let model = Model::from_file(&a.input, Backend::Flex)?;
    let bytes = if a.half { model.to_bytes_f16()? } else { model.to_bytes()? };
    std::fs::write(&a.output, &bytes).map_err(|e| sddpm::Error::io(a.output.display(), e))?;
    let arch = match &model.meta.model.field {
        Some(f) => format!("point denoiser, width {}, {} blocks", f.width, f.blocks),
        None => format!("U-Net, width {}, point head {}", model.meta.model.base_width, model.meta.model.point_width),
    };
    println!(
        "{}: {} ({} parameters), {} bytes ({}), {} epochs, seed {}",
        a.output.display(),
        arch,
        model.parameter_count(),
        bytes.len(),
        if a.half { "f16" } else { "f32" },
        model.meta.training.epochs,
        model.meta.training.seed
    );
    Ok(0)
}

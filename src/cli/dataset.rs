//! `sddpm dataset -o DIR [--seed 42]`: write the training set for inspection.

use sddpm::error::Error;
use sddpm::diffusion::dataset::{generate, DatasetConfig};
use sddpm::polycube::tensor::TENSOR_LEN;
use sddpm::Result;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct DatasetArgs {
    /// Output folder.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    #[arg(long, default_value_t = 42)]
    pub seed: u64,
    /// Number of random assemblies (the paper: 4,870).
    #[arg(long, default_value_t = 4870)]
    pub random: usize,
    /// Assemblies written as OBJ for a look.
    #[arg(long, default_value_t = 8)]
    pub obj: usize,
}

pub fn run(a: &DatasetArgs) -> Result<i32> {
    let cfg = DatasetConfig { seed: a.seed, random: a.random, ..Default::default() };
    std::fs::create_dir_all(&a.output).map_err(|e| Error::io(a.output.display(), e))?;
    let data = generate(&cfg);
    // tensors.npy: float32 [n, 3, 64, 96] (NumPy .npy v1.0).
    let path = a.output.join("tensors.npy");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).map_err(|e| Error::io(path.display(), e))?);
    let header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, 3, 64, 96), }}", data.len());
    let total = 10 + header.len() + 1;
    let pad = (64 - total % 64) % 64;
    let mut h = Vec::new();
    h.extend_from_slice(b"\x93NUMPY\x01\x00");
    h.extend_from_slice(&((header.len() + pad + 1) as u16).to_le_bytes());
    h.extend_from_slice(header.as_bytes());
    h.extend(std::iter::repeat_n(b' ', pad));
    h.push(b'\n');
    let io = |e: std::io::Error| Error::io(path.display(), e);
    f.write_all(&h).map_err(io)?;
    for s in &data {
        debug_assert_eq!(s.tensor.len(), TENSOR_LEN);
        for v in &s.tensor {
            f.write_all(&v.to_le_bytes()).map_err(io)?;
        }
    }
    f.flush().map_err(io)?;
    // contexts.csv: index, 12 labels, scale.
    let cpath = a.output.join("contexts.csv");
    let mut c = String::from("index,labels,scale\n");
    for (i, s) in data.iter().enumerate() {
        c.push_str(&format!("{i},{},{:.6}\n", s.context.label_values().map(|l| l.to_string()).join(" "), s.scale));
    }
    std::fs::write(&cpath, c).map_err(|e| Error::io(cpath.display(), e))?;
    for (k, i) in (0..data.len()).step_by((data.len() / a.obj.max(1)).max(1)).take(a.obj).enumerate() {
        let p = a.output.join(format!("assembly_{k}_{i}.obj"));
        sddpm::export::obj::write_polycube_obj(&p, &data[i].context)?;
    }
    let cfg_path = a.output.join("config.json");
    std::fs::write(&cfg_path, serde_json::to_string_pretty(&cfg).unwrap()).map_err(|e| Error::io(cfg_path.display(), e))?;
    eprintln!("wrote {} samples to {}", data.len(), a.output.display());
    Ok(0)
}

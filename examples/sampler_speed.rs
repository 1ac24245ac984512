//! Reverse-diffusion time of the embedded model for 1 and 16 candidates, strided
//! (the default 50 steps) and full (500 steps), with the default denoiser (the
//! template attention's estimate alone) and, strided only, with the U-Net and its
//! learned gate. `cargo run --release --example sampler_speed` (BENCHMARKS.md).
use sddpm::context::Context;
use sddpm::diffusion::sample::{reverse_diffusion, SamplerOptions};
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::layout;
use std::time::Instant;

fn main() -> sddpm::Result<()> {
    let model = Model::default_model()?;
    println!("| denoiser | context | candidates | steps | seconds | per candidate and step, ms |");
    println!("|---|---|---:|---:|---:|---:|");
    for (name, labels) in [("1 cell", "THC+Z,0,0,0,0,0,0,0,0,0,0,0"), ("3 cells", "BHC-X,THC+Z,BHC+X,0,0,0,0,0,0,0,0,0"), ("12 cells", "cube,THC+Z,cube,BHC+Y,cube,cube,cube,THC+X,cube,BHC-Z,cube,cube")] {
        let ctx = Context::parse(labels)?;
        for (den, gate) in [("estimate alone (default)", SamplerOptions::default().kernel_gate), ("U-Net, learned gate", None)] {
            for n in [1usize, 16] {
                for steps in [50usize, 0] {
                    if gate.is_none() && steps == 0 {
                        continue; // the U-Net's full sampler: 10x its strided time
                    }
                    let inputs: Vec<Vec<f32>> = (0..n).map(|i| layout(&sample_cells(&ctx, 1.0, &mut seeded_rng(9, i as u64)))).collect();
                    let ctxs = vec![ctx; n];
                    let d = SamplerOptions::default();
                    // the full sampler: every one of the T steps from T
                    let start_step = if steps == 0 { 0 } else { d.start_step };
                    let opts = SamplerOptions { steps, kernel_gate: gate, start_step, ..d };
                    let t0 = Instant::now();
                    let out = reverse_diffusion(&model, &inputs, &ctxs, &opts, &mut NoProgress)?;
                    let s = t0.elapsed().as_secs_f64();
                    assert_eq!(out.tensors.len(), n);
                    let visited = sddpm::diffusion::sample::timesteps(if start_step == 0 { model.schedule.steps() } else { start_step }, steps).len();
                    println!("| {den} | {name} | {n} | {} | {s:.2} | {:.2} |", visited, 1e3 * s / (n * visited) as f64);
                }
            }
        }
    }
    Ok(())
}

//! The paper's BHC ablation: a genus-0 input with a blind hole (a warped, rotated
//! BHC+Z cell from the project's synthetic generator, seed != 42), diffused with the
//! label BHC+Z and with the label cube. Reports, per label, the Chamfer distance
//! (mean squared, cell units) and the maximum deviation (largest distance from an
//! output point to the input's samples, cell units) between the decoded cell and the
//! input surface it came from. Args: [cases] [weights]
use sddpm::search::generate::{generate_from_contexts, PolycubeOptions};
use sddpm::context::Context;
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::search::synthetic::{synthetic_mesh, SyntheticOptions};
use sddpm::search::verify::{active_points, chamfer};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map(|v| v.parse().unwrap()).unwrap_or(8);
    let model = match args.get(2) {
        Some(p) => Model::from_file(std::path::Path::new(p), Backend::Flex).unwrap(),
        None => Model::default_model().unwrap(),
    };
    let truth = Context::parse("BHC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let labels = [("BHC+Z", truth), ("cube", Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap())];
    let mut sums = [[0.0f64; 2]; 2];
    let mut counts = [0usize; 2];
    for i in 0..n {
        let mut rng = seeded_rng(2024, i as u64);
        let mesh = synthetic_mesh(&truth, &SyntheticOptions::default(), &mut rng);
        for (k, (_, ctx)) in labels.iter().enumerate() {
            // diffuse whatever the pre-check thinks of the label (that is the ablation)
            let opts = PolycubeOptions { max_fit: f64::INFINITY, max_in_empty_fraction: 1.0, min_occupied_fraction: 0.0, ..Default::default() };
            let r = generate_from_contexts(&model, &mesh, 0, &[*ctx], &opts, &mut NoProgress).unwrap();
            let c = &r.candidates[0];
            let (Some(out), Some(inp)) = (&c.output, &c.input) else {
                println!("case {i} {}: refused by the pre-check", labels[k].0);
                continue;
            };
            let s = 1.0 / inp.frame.scale;
            let o: Vec<[f64; 3]> = active_points(out, 0, 1e-4).iter().map(|p| p.map(|v| v * s)).collect();
            let x: Vec<[f64; 3]> = active_points(&inp.tensor, 0, 1e-4).iter().map(|p| p.map(|v| v * s)).collect();
            let cd = chamfer(&o, &x);
            let maxdev = o
                .iter()
                .map(|p| x.iter().map(|q| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>()).fold(f64::INFINITY, f64::min).sqrt())
                .fold(0.0, f64::max);
            sums[k][0] += cd;
            sums[k][1] += maxdev;
            counts[k] += 1;
            println!("case {i} label {:6}: Chamfer {cd:.4}  max deviation {maxdev:.4}", labels[k].0);
        }
    }
    println!("\n| label | mean Chamfer | mean max deviation |\n|---|---|---|");
    for (k, (name, _)) in labels.iter().enumerate() {
        println!("| {name} | {:.4} | {:.4} |", sums[k][0] / counts[k].max(1) as f64, sums[k][1] / counts[k].max(1) as f64);
    }
}

use sddpm::context::Context;
use sddpm::diffusion::sample::{reverse_diffusion, SamplerOptions};
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::context::context_frame;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::{layout, unlayout, TENSOR_LEN};
use sddpm::search::verify::{chamfer, verify, VerifyOptions};
use rand_distr::{Distribution, StandardNormal};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let steps: usize = args[2].parse().unwrap();
    let start_step: usize = args.get(4).map(|v| v.parse().unwrap()).unwrap_or(0);
    let raw = args.get(5).is_some();
    let ctx = Context::parse(&args[3]).unwrap();
    let mut rng = seeded_rng(5, 5);
    let exact = sample_cells(&ctx, 1.0, &mut rng);
    let x0 = layout(&exact);
    let s = &model.schedule;
    let t = s.steps();
    let noise: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
    let mut xt = vec![0f32; TENSOR_LEN];
    s.forward_sample(&x0, &noise, t, &mut xt);
    let frame = context_frame(&ctx).unwrap();
    let _ = xt;
    for (name, start) in [("x0", x0.clone())] {
        let out = reverse_diffusion(&model, &[start], &[ctx], &SamplerOptions { steps, start_step, raw_start: raw, ..Default::default() }, &mut NoProgress).unwrap();
        let o = unlayout(&out.tensors[0]);
        let r = verify(&out.tensors[0], &ctx, &frame, &VerifyOptions::default());
        for n in ctx.occupied() {
            let a: Vec<[f64; 3]> = o[n].iter().map(|p| p.map(|v| v as f64 / frame.scale)).collect();
            let b: Vec<[f64; 3]> = exact[n].iter().map(|p| p.map(|v| v as f64 / frame.scale)).collect();
            println!("{name}: cell {n} chamfer {:.4} inside {:.2} pcd_target {:?} nearest {:?}", chamfer(&a, &b), r.cells[n].inside_fraction, r.cells[n].pcd.get(ctx.labels[n].label() as usize - 1), r.cells[n].nearest);
        }
        println!("{name}: passed {} reason {:?}", r.passed, r.reason);
    }
}

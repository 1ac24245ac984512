//! Developer probe: one-shot x_0 prediction from a forward-noised exact cell at
//! several t, against the eps = 0 baseline. Args: weights labels
use burn::tensor::{Tensor, TensorData};
use rand_distr::{Distribution, StandardNormal};
use sddpm::context::Context;
use sddpm::diffusion::{Backend, Model};
use sddpm::geometry::rng::seeded_rng;
use sddpm::context::context_frame;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::{layout, TENSOR_H, TENSOR_LEN, TENSOR_W};
use sddpm::search::verify::{active_points, cached_templates, chamfer, local_points};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let ctx = Context::parse(&args[2]).unwrap();
    let mut rng = seeded_rng(5, 5);
    let x0 = layout(&sample_cells(&ctx, 1.0, &mut rng));
    let frame = context_frame(&ctx).unwrap();
    let tpl = cached_templates(2048);
    let sched = &model.schedule;
    let n = ctx.occupied().next().unwrap();
    let lab = ctx.labels[n].label() as usize;
    for t in [2usize, 5, 10, 20, 40, 80, 120, 200] {
        let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut xt = vec![0f32; TENSOR_LEN];
        sched.forward_sample(&x0, &z, t, &mut xt);
        let ctx_t = Tensor::<2>::from_data(TensorData::new(ctx.one_hot().to_vec(), [1, 132]), &model.device);
        let eps: Vec<f32> = model.forward(Tensor::<4>::from_data(TensorData::new(xt.clone(), [1, 3, TENSOR_H, TENSOR_W]), &model.device), &[t], ctx_t).into_data().try_into_vec().unwrap();
        let (sa, sd) = (sched.alpha_bar[t].sqrt(), (1.0 - sched.alpha_bar[t]).sqrt());
        let hw = TENSOR_H * TENSOR_W;
        let mk = |e: &dyn Fn(usize) -> f64| -> Vec<f32> { (0..TENSOR_LEN).map(|k| ((xt[k] as f64 - sched.qcoef[t] * sched.config.q[k / hw] - sd * e(k)) / sa) as f32).collect() };
        let hat = mk(&|k| eps[k] as f64);
        let base = mk(&|_| 0.0);
        let mse: f64 = (0..512).flat_map(|p| { let (r, c) = sddpm::polycube::tensor::slot(n, p); (0..3).map(move |ch| sddpm::polycube::tensor::flat(ch, r, c)) }).map(|k| (eps[k] - z[k]).powi(2) as f64).sum::<f64>() / (3.0 * 512.0);
        // Bayes-optimal eps from K independent samplings of the same context (the p-th
        // sorted point of each is a draw from p(x0 | rank p)).
        let kdraws: Vec<Vec<f32>> = (0..300u64).map(|k| { let mut r = seeded_rng(77, k); layout(&sample_cells(&ctx, 1.0, &mut r)) }).collect();
        let mut bmse = 0.0;
        for p in 0..512 {
            let (r, c) = sddpm::polycube::tensor::slot(n, p);
            let ks: Vec<usize> = (0..3).map(|ch| sddpm::polycube::tensor::flat(ch, r, c)).collect();
            let y: Vec<f64> = ks.iter().map(|&k| xt[k] as f64 - sched.qcoef[t] * sched.config.q[k / hw]).collect();
            let mut ws = Vec::new();
            for d in &kdraws { let e: f64 = (0..3).map(|a| (y[a] - sa * d[ks[a]] as f64).powi(2)).sum(); ws.push(-e / (2.0 * sd * sd)); }
            let m = ws.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let w: Vec<f64> = ws.iter().map(|v| (v - m).exp()).collect();
            let tot: f64 = w.iter().sum();
            for a in 0..3 { let mx: f64 = kdraws.iter().zip(&w).map(|(d, wi)| wi * d[ks[a]] as f64).sum::<f64>() / tot; let e = (y[a] - sa * mx) / sd; bmse += (e - z[ks[a]] as f64).powi(2); }
        }
        let bmse = bmse / 1536.0;
        print!("bayes_mse={bmse:.3} ");
        let ch = |x: &Vec<f32>| chamfer(&local_points(&active_points(x, n, 1e-4), frame.scale), &tpl[lab]);
        println!("t={t:4} sigma/sa={:.3} eps_mse={mse:.3} chamfer: predicted x0 {:.4}  eps=0 {:.4}", sd / sa, ch(&hat), ch(&base));
    }
}

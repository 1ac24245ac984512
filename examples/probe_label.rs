//! Developer probe: how much the context changes the predicted noise. A cell is
//! sampled from context A, forward-noised at t, and the network predicts the noise
//! under context A and under context B; prints the RMS of the two predictions'
//! difference, the RMS error of each against the true noise (occupied cell only),
//! and the same for the Bayes-optimal predictors from 300 samplings of A and of B.
//! Args: weights labelsA labelsB
use burn::tensor::{Tensor, TensorData};
use rand_distr::{Distribution, StandardNormal};
use sddpm::context::Context;
use sddpm::diffusion::{Backend, Model};
use sddpm::geometry::rng::seeded_rng;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::{flat, layout, slot, TENSOR_H, TENSOR_LEN, TENSOR_W};

fn bayes(kdraws: &[Vec<f32>], xt: &[f32], n: usize, sa: f64, sd: f64, shift: &dyn Fn(usize) -> f64) -> Vec<f64> {
    let mut out = Vec::new();
    for p in 0..512 {
        let (r, c) = slot(n, p);
        let ks: Vec<usize> = (0..3).map(|ch| flat(ch, r, c)).collect();
        let y: Vec<f64> = ks.iter().map(|&k| xt[k] as f64 - shift(k)).collect();
        let ws: Vec<f64> = kdraws.iter().map(|d| -(0..3).map(|a| (y[a] - sa * d[ks[a]] as f64).powi(2)).sum::<f64>() / (2.0 * sd * sd)).collect();
        let m = ws.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let w: Vec<f64> = ws.iter().map(|v| (v - m).exp()).collect();
        let tot: f64 = w.iter().sum();
        for a in 0..3 {
            let mx: f64 = kdraws.iter().zip(&w).map(|(d, wi)| wi * d[ks[a]] as f64).sum::<f64>() / tot;
            out.push((y[a] - sa * mx) / sd);
        }
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let ca = Context::parse(&args[2]).unwrap();
    let cb = Context::parse(&args[3]).unwrap();
    let mut rng = seeded_rng(5, 5);
    let x0 = layout(&sample_cells(&ca, 1.0, &mut rng));
    let sched = &model.schedule;
    let n = ca.occupied().next().unwrap();
    let hw = TENSOR_H * TENSOR_W;
    let draws = |c: &Context| -> Vec<Vec<f32>> { (0..300u64).map(|k| { let mut r = seeded_rng(77, k); layout(&sample_cells(c, 1.0, &mut r)) }).collect() };
    let (da, db) = (draws(&ca), draws(&cb));
    let idx: Vec<usize> = (0..512).flat_map(|p| { let (r, c) = slot(n, p); (0..3).map(move |ch| flat(ch, r, c)) }).collect();
    println!("   t | net: |eA-eB| |eA-z| |eB-z| | bayes: |eA-eB| |eA-z| |eB-z| | cos(net diff, bayes diff)");
    for t in [10usize, 20, 40, 80, 120, 200, 300] {
        let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut xt = vec![0f32; TENSOR_LEN];
        sched.forward_sample(&x0, &z, t, &mut xt);
        let run = |c: &Context| -> Vec<f32> {
            let ct = Tensor::<2>::from_data(TensorData::new(c.one_hot().to_vec(), [1, 132]), &model.device);
            model.forward(Tensor::<4>::from_data(TensorData::new(xt.clone(), [1, 3, TENSOR_H, TENSOR_W]), &model.device), &[t], ct).into_data().try_into_vec().unwrap()
        };
        let (ea, eb) = (run(&ca), run(&cb));
        let (sa, sd) = (sched.alpha_bar[t].sqrt(), (1.0 - sched.alpha_bar[t]).sqrt());
        let shift = |k: usize| sched.qcoef[t] * sched.config.q[k / hw];
        let (ba, bb) = (bayes(&da, &xt, n, sa, sd, &shift), bayes(&db, &xt, n, sa, sd, &shift));
        let rms = |f: &dyn Fn(usize) -> f64| ((0..idx.len()).map(|i| f(i).powi(2)).sum::<f64>() / idx.len() as f64).sqrt();
        let dn: Vec<f64> = (0..idx.len()).map(|i| (ea[idx[i]] - eb[idx[i]]) as f64).collect();
        let dbay: Vec<f64> = (0..idx.len()).map(|i| ba[i] - bb[i]).collect();
        let dot: f64 = dn.iter().zip(&dbay).map(|(a, b)| a * b).sum();
        let cos = dot / (dn.iter().map(|a| a * a).sum::<f64>().sqrt() * dbay.iter().map(|a| a * a).sum::<f64>().sqrt());
        println!(
            "{t:4} | {:.3} {:.3} {:.3} | {:.3} {:.3} {:.3} | {cos:.3}",
            rms(&|i| (ea[idx[i]] - eb[idx[i]]) as f64),
            rms(&|i| (ea[idx[i]] - z[idx[i]]) as f64),
            rms(&|i| (eb[idx[i]] - z[idx[i]]) as f64),
            rms(&|i| ba[i] - bb[i]),
            rms(&|i| ba[i] - z[idx[i]] as f64),
            rms(&|i| bb[i] - z[idx[i]] as f64),
        );
    }
}

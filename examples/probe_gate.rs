//! Developer probe: how much the template attention's estimate (the Bayes posterior
//! mean over the template prior's points, jitter sigma) could lower the training
//! loss, per timestep: MSE of the network, of the estimate, and of the best blend
//! out + g (eps_k - out) with g fitted by least squares. Args: weights [samples]
use burn::tensor::{Tensor, TensorData};
use rand_distr::{Distribution, StandardNormal};
use sddpm::diffusion::model::prior_image;
use sddpm::diffusion::{Backend, Model};
use sddpm::geometry::rng::seeded_rng;
use sddpm::diffusion::dataset::{generate, DatasetConfig};
use sddpm::polycube::tensor::{flat, slot, POINTS_PER_CELL, TENSOR_H, TENSOR_LEN, TENSOR_W};
use sddpm::polycube::{Primitive, NUM_CELLS};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let n: usize = args.get(2).map(|v| v.parse().unwrap()).unwrap_or(8);
    let sigmas = [(0.01f64, 4.0f64), (0.01, 12.0), (0.01, 32.0), (0.01, 1e9)];
    let data = generate(&DatasetConfig::default());
    let mut rng = seeded_rng(78, 0);
    let idx: Vec<usize> = (0..n).map(|i| (i * 7919 + 13) % data.len()).collect();
    let sch = &model.schedule;
    println!("t  mse_net  | per sigma: mse_kernel g* mse_blend");
    for &t in &[2usize, 10, 30, 60, 100, 150, 200, 300, 400, 500] {
        let (sa, sd) = (sch.alpha_bar[t].sqrt(), (1.0 - sch.alpha_bar[t]).sqrt());
        let mut se_net = 0.0;
        let mut cnt = 0usize;
        // per sigma: sum (k-e)^2, sum (z-o)(k-o), sum (k-o)^2
        let mut acc = vec![[0.0f64; 3]; sigmas.len()];
        for &i in &idx {
            let x0 = &data[i].tensor;
            let ctx = &data[i].context;
            let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
            let mut xt = vec![0f32; TENSOR_LEN];
            sch.forward_sample(x0, &z, t, &mut xt);
            let xt_t = Tensor::<4>::from_data(TensorData::new(xt.clone(), [1, 3, TENSOR_H, TENSOR_W]), &model.device);
            let c = Tensor::<2>::from_data(TensorData::new(ctx.one_hot().to_vec(), [1, 132]), &model.device);
            let out: Vec<f32> = model.forward(xt_t, &[t], c).into_data().try_into_vec::<f32>().unwrap();
            let prior = prior_image(&ctx.one_hot());
            for cell in 0..NUM_CELLS {
                if ctx.labels[cell] == Primitive::Null {
                    continue;
                }
                let pj: Vec<[f64; 3]> = (0..POINTS_PER_CELL).map(|p| { let (r, c) = slot(cell, p); [0, 1, 2].map(|ch| prior[flat(ch, r, c)] as f64) }).collect();
                for p in 0..POINTS_PER_CELL {
                    let (r, col) = slot(cell, p);
                    let y: [f64; 3] = [0, 1, 2].map(|ch| xt[flat(ch, r, col)] as f64 - sch.qcoef[t] * sch.config.q[ch]);
                    let d2: Vec<f64> = pj.iter().map(|q| (0..3).map(|k| (y[k] - sa * q[k]).powi(2)).sum::<f64>()).collect();
                    for ch in 0..3 {
                        let k = flat(ch, r, col);
                        let (o, e) = (out[k] as f64, z[k] as f64);
                        se_net += (o - e).powi(2);
                        cnt += 1;
                    }
                    for (si, &(s, rho)) in sigmas.iter().enumerate() {
                        let v = sa * sa * s * s + sd * sd;
                        let mx = d2.iter().enumerate().map(|(j, d)| d + v * ((j as f64 - p as f64) / rho).powi(2)).fold(f64::INFINITY, f64::min);
                        let w: Vec<f64> = d2.iter().enumerate().map(|(j, d)| (-(d - mx) / (2.0 * v) - ((j as f64 - p as f64) / rho).powi(2) / 2.0).exp()).collect();
                        let tot: f64 = w.iter().sum();
                        for ch in 0..3 {
                            let pbar: f64 = pj.iter().zip(&w).map(|(q, wi)| wi * q[ch]).sum::<f64>() / tot;
                            let x0h = pbar + sa * s * s / v * (y[ch] - sa * pbar);
                            let ek = (y[ch] - sa * x0h) / sd;
                            let k = flat(ch, r, col);
                            let (o, e) = (out[k] as f64, z[k] as f64);
                            acc[si][0] += (ek - e).powi(2);
                            acc[si][1] += (e - o) * (ek - o);
                            acc[si][2] += (ek - o).powi(2);
                        }
                    }
                }
            }
        }
        let mut line = format!("{t:3}  {:.4}  |", se_net / cnt as f64);
        for (si, &(s, rho)) in sigmas.iter().enumerate() {
            let g = acc[si][1] / acc[si][2];
            let blend = se_net - acc[si][1] * acc[si][1] / acc[si][2];
            line += &format!("  s{s} r{rho}: {:.4} {:.2} {:.4}", acc[si][0] / cnt as f64, g, blend / cnt as f64);
        }
        println!("{line}");
    }
}

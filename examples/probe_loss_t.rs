//! Developer probe: noise-prediction MSE (occupied cells) per timestep on training
//! samples. Args: weights [samples]
use burn::tensor::{Tensor, TensorData};
use rand_distr::{Distribution, StandardNormal};
use sddpm::diffusion::{Backend, Model};
use sddpm::geometry::rng::seeded_rng;
use sddpm::diffusion::dataset::{generate, DatasetConfig};
use sddpm::polycube::tensor::{slot, flat, TENSOR_H, TENSOR_LEN, TENSOR_W, POINTS_PER_CELL};
use sddpm::polycube::{Primitive, NUM_CELLS};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let n: usize = args.get(2).map(|v| v.parse().unwrap()).unwrap_or(16);
    let data = generate(&DatasetConfig::default());
    let mut rng = seeded_rng(77, 0);
    let idx: Vec<usize> = (0..n).map(|i| (i * 7919) % data.len()).collect();
    for &t in &[2usize, 10, 30, 60, 120, 250, 400, 500] {
        let mut se = 0.0;
        let mut se_wrong = 0.0;
        let mut cnt = 0usize;
        for (ii, &i) in idx.iter().enumerate() {
            let x0 = &data[i].tensor;
            let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
            let mut xt = vec![0f32; TENSOR_LEN];
            model.schedule.forward_sample(x0, &z, t, &mut xt);
            let xt_t = Tensor::<4>::from_data(TensorData::new(xt, [1, 3, TENSOR_H, TENSOR_W]), &model.device);
            let c = Tensor::<2>::from_data(TensorData::new(data[i].context.one_hot().to_vec(), [1, 132]), &model.device);
            let eps: Vec<f32> = model.forward(xt_t.clone(), &[t], c).into_data().try_into_vec::<f32>().unwrap();
            // the same state with another sample's context: how much does the context matter?
            let other = &data[idx[(ii + 1) % idx.len()]].context;
            let cw = Tensor::<2>::from_data(TensorData::new(other.one_hot().to_vec(), [1, 132]), &model.device);
            let epsw: Vec<f32> = model.forward(xt_t, &[t], cw).into_data().try_into_vec::<f32>().unwrap();
            for cell in 0..NUM_CELLS {
                if data[i].context.labels[cell] == Primitive::Null { continue; }
                for p in 0..POINTS_PER_CELL {
                    let (r, col) = slot(cell, p);
                    for ch in 0..3 {
                        let k = flat(ch, r, col);
                        se += ((eps[k] - z[k]) as f64).powi(2);
                        se_wrong += ((epsw[k] - z[k]) as f64).powi(2);
                        cnt += 1;
                    }
                }
            }
        }
        println!("t {t:4}  eps MSE {:.4}   with another sample's context {:.4}", se / cnt as f64, se_wrong / cnt as f64);
    }
}

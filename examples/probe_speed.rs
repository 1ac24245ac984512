use sddpm::diffusion::model::{Denoiser, ModelConfig};
use sddpm::diffusion::{device, Backend};
use burn::module::Module;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::{Tensor, Distribution};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let width: usize = args[1].parse().unwrap();
    let bs: usize = args[2].parse().unwrap();
    let ad = device(Backend::Flex).autodiff();
    let cfg = ModelConfig { base_width: width, ..Default::default() };
    let mut net = Denoiser::new(&cfg, &ad);
    println!("params {}", net.num_params());
    let mut opt = AdamConfig::new().init();
    for i in 0..4 {
        let t0 = Instant::now();
        let x = Tensor::<4>::random([bs, 3, 64, 96], Distribution::Default, &ad);
        let z = Tensor::<4>::random([bs, 3, 64, 96], Distribution::Default, &ad);
        let c = Tensor::<2>::random([bs, 132], Distribution::Default, &ad);
        let ts: Vec<usize> = (0..bs).map(|i| 10 + i).collect();
        let p = net.forward(x, &ts, c);
        let loss = (p - z).powi_scalar(2).mean();
        let lv: f32 = loss.clone().into_scalar();
        let g = GradientsParams::from_grads(loss.backward(), &net);
        net = opt.step(1e-3, net.clone(), g);
        println!("step {i}: {:.3}s loss {lv}", t0.elapsed().as_secs_f64());
    }
    let dev = device(Backend::Flex);
    let inf = Denoiser::new(&cfg, &dev);
    for b in [1usize, 16] {
        let x = Tensor::<4>::random([b, 3, 64, 96], Distribution::Default, &dev);
        let c = Tensor::<2>::random([b, 132], Distribution::Default, &dev);
        let t0 = Instant::now();
        for _ in 0..3 { let _ = inf.forward(x.clone(), &vec![5; b], c.clone()).into_data(); }
        println!("forward b={b}: {:.3}s", t0.elapsed().as_secs_f64() / 3.0);
    }
}

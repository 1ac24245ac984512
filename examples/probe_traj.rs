//! Developer probe: Chamfer of the (rescaled) reverse-process state to the cell's
//! template along the trajectory, from an exact cell. Args: weights labels steps start
use sddpm::context::Context;
use sddpm::diffusion::sample::{reverse_diffusion, SamplerOptions};
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::context::context_frame;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::{layout, TENSOR_H, TENSOR_W};
use sddpm::search::verify::{active_points, cached_templates, chamfer, local_points};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let ctx = Context::parse(&args[2]).unwrap();
    let steps: usize = args[3].parse().unwrap();
    let start: usize = args[4].parse().unwrap();
    let mut rng = seeded_rng(5, 5);
    // X0CTX=labels: sample the start cloud from another context (label-use check)
    let x0ctx = std::env::var("X0CTX").ok().map(|c| Context::parse(&c).unwrap()).unwrap_or(ctx.clone());
    let x0 = layout(&sample_cells(&x0ctx, 1.0, &mut rng));
    let frame = context_frame(&ctx).unwrap();
    let tpl = cached_templates(2048);
    let sched = &model.schedule;
    let keep = if steps == 0 { 10 } else { 1 };
    let out = reverse_diffusion(&model, &[x0], &[ctx.clone()], &SamplerOptions { steps, start_step: start, keep_every: keep, guidance: std::env::var("GUIDANCE").ok().map(|v| v.parse().unwrap()).unwrap_or(0.0), eps_scale: std::env::var("EPS_SCALE").ok().map(|v| v.parse().unwrap()).unwrap_or(1.0), ..Default::default() }, &mut NoProgress).unwrap();
    let hw = TENSOR_H * TENSOR_W;
    // RESTART=t,k,steps: k restarts from the output, forward-noised to t, `steps` steps each
    let mut out = out;
    if let Ok(r) = std::env::var("RESTART") {
        let v: Vec<usize> = r.split(',').map(|x| x.parse().unwrap()).collect();
        for k in 0..v[1] {
            let x = out.tensors[0].clone();
            let o2 = reverse_diffusion(&model, &[x], &[ctx.clone()], &SamplerOptions { steps: v[2], start_step: v[0], keep_every: 0, seed: 100 + k as u64, ..Default::default() }, &mut NoProgress).unwrap();
            out.trajectory[0].push((0, o2.tensors[0].clone()));
            out.tensors = o2.tensors;
        }
    }
    for (t, x) in &out.trajectory[0] {
        let sa = sched.alpha_bar[*t].sqrt();
        let y: Vec<f32> = x.iter().enumerate().map(|(k, v)| ((*v as f64 - sched.qcoef[*t] * sched.config.q[k / hw]) / sa) as f32).collect();
        let mut s = format!("t={t:4}");
        for n in ctx.occupied() {
            let loc = local_points(&active_points(&y, n, 1e-4), frame.scale);
            let lab = ctx.labels[n].label() as usize;
            s += &format!(" cell{n}: own {:.4}", chamfer(&loc, &tpl[lab]));
            // L-infinity norm of the centred points (cell units): 0.5 on a cube's surface
            let mut li: Vec<f64> = loc.iter().map(|p| p[0].abs().max(p[1].abs()).max(p[2].abs())).collect();
            li.sort_by(f64::total_cmp);
            let q = |f: f64| li[((li.len() - 1) as f64 * f) as usize];
            s += &format!(" Linf q05 {:.3} q25 {:.3} q50 {:.3} q75 {:.3} q95 {:.3}", q(0.05), q(0.25), q(0.5), q(0.75), q(0.95));
        }
        println!("{s}");
    }
}

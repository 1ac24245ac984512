//! Developer probe: the reverse process with a *kernel* denoiser instead of the
//! network — the Bayes estimator of x_0 with the template prior's points as draws
//! (x0_hat = sum_j w_j p_j, w_j ~ exp(-|y - sqrt(ab) p_j|^2 / (2 (1 - ab)))), per
//! occupied cell (env SIGMA: the data's jitter around the prior points, RHO: the
//! width in slots of a Gaussian prior on rank distance; both 0 = off). It bounds what a denoiser that uses the label fully would give:
//! the output's PCD to every template (TCV: target nearest and <= tau_CD) for the
//! true label and for wrong ones. Args: labels_of_input start_step label...
use rand_distr::{Distribution, StandardNormal};
use sddpm::context::Context;
use sddpm::diffusion::model::prior_image;
use sddpm::diffusion::schedule::{Schedule, ScheduleConfig};
use sddpm::geometry::rng::seeded_rng;
use sddpm::context::context_frame;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::{flat, layout, slot, TENSOR_LEN};
use sddpm::search::verify::{active_points, cached_templates, local_points, pcd, pcd_labels};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let input_ctx = Context::parse(&args[1]).unwrap();
    let start: usize = args[2].parse().unwrap();
    let sched = Schedule::new(ScheduleConfig::default());
    let mut rng = seeded_rng(5, 5);
    // a warped input: x_0 of the input context with a smooth bend
    let warp: f64 = std::env::var("WARP").ok().map(|v| v.parse().unwrap()).unwrap_or(0.0);
    let mut x_in = layout(&sample_cells(&input_ctx, 1.0, &mut rng));
    let hw = 64 * 96;
    for k in 0..hw {
        let (x, y) = (x_in[k] as f64, x_in[hw + k] as f64);
        x_in[2 * hw + k] += (warp * (x * 1.7).sin() * (y * 1.3).cos()) as f32;
    }
    // jitter sigma of the data around the prior points and the rank prior's width
    // (slots; 0 = rank-blind), as in the network's template attention
    let env = |k: &str, d: f64| std::env::var(k).ok().map(|v| v.parse().unwrap()).unwrap_or(d);
    let (sigma, rho) = (env("SIGMA", 0.0), env("RHO", 0.0));
    let tpl = cached_templates(2048);
    let names = pcd_labels();
    for lab in &args[3..] {
        let ctx = Context::parse(lab).unwrap();
        let prior = prior_image(&ctx.one_hot());
        let frame = context_frame(&ctx).unwrap();
        let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut x = vec![0f32; TENSOR_LEN];
        sched.forward_sample(&x_in, &z, start, &mut x);
        let ts = sddpm::diffusion::sample::timesteps(start, 50);
        for (si, &t) in ts.iter().enumerate() {
            let s = ts.get(si + 1).copied().unwrap_or(0);
            let (sa, sd) = (sched.alpha_bar[t].sqrt(), (1.0 - sched.alpha_bar[t]).sqrt());
            let mut eps = vec![0f32; TENSOR_LEN];
            for n in ctx.occupied() {
                let pj: Vec<[f64; 3]> = (0..512).map(|p| { let (r, c) = slot(n, p); [0, 1, 2].map(|ch| prior[flat(ch, r, c)] as f64) }).collect();
                for p in 0..512 {
                    let (r, c) = slot(n, p);
                    let y: [f64; 3] = [0, 1, 2].map(|ch| x[flat(ch, r, c)] as f64 - sched.qcoef[t] * sched.config.q[ch]);
                    let v = sa * sa * sigma * sigma + sd * sd;
                    let lw: Vec<f64> = pj.iter().enumerate()
                        .map(|(j, q)| {
                            let r = if rho > 0.0 { ((j as f64 - p as f64) / rho).powi(2) / 2.0 } else { 0.0 };
                            -(0..3).map(|a| (y[a] - sa * q[a]).powi(2)).sum::<f64>() / (2.0 * v) - r
                        })
                        .collect();
                    let m = lw.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                    let w: Vec<f64> = lw.iter().map(|v| (v - m).exp()).collect();
                    let tot: f64 = w.iter().sum();
                    for ch in 0..3 {
                        let pbar: f64 = pj.iter().zip(&w).map(|(q, wi)| wi * q[ch]).sum::<f64>() / tot;
                        let x0 = pbar + sa * sigma * sigma / v * (y[ch] - sa * pbar);
                        eps[flat(ch, r, c)] = ((y[ch] - sa * x0) / sd) as f32;
                    }
                }
            }
            let mut next = vec![0f32; TENSOR_LEN];
            sched.ddim_step(&x, &eps, t, s, &mut next);
            x = next;
        }
        let mut line = format!("label {lab}:");
        for n in ctx.occupied() {
            let loc = local_points(&active_points(&x, n, 1e-4), frame.scale);
            let d: Vec<f64> = (1..tpl.len()).map(|l| pcd(&loc, &tpl[l], 0.01, 2.0)).collect();
            let best = (0..d.len()).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap();
            let target = ctx.labels[n].label() as usize - 1;
            let pass = best == target && d[target] <= 0.01;
            line += &format!(" cell {n}: target {} {:.4}, nearest {} {:.4} -> {}", names[target], d[target], names[best], d[best], if pass { "PASS" } else { "fail" });
        }
        println!("{line}");
    }
}

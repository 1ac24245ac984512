//! Developer probe of TCV on one held-in case: for each occupied cell, the two halves
//! of the PCD (accuracy: points to the whole template; coverage: the template's points
//! off the faces shared with occupied neighbours to the points, as
//! `VerifyOptions::visible_coverage` computes it) against every template, for the
//! diffused output and for the laid-out input. ZONES=1 also splits the sums by zone
//! (the hole's core by thirds along its axis, and the rest) for the labels on the
//! target's hole axis. Args: SEED N MIN MAX CASE (the case of `eval-model --cases N
//! --min MIN --max MAX --seed SEED`).
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use sddpm::search::generate::generate_from_contexts;
use sddpm::search::generate::PolycubeOptions;
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::search::synthetic::{cases, SyntheticOptions};
use sddpm::polycube::Primitive;
use sddpm::polycube::assembly::shared_faces;
use sddpm::search::verify::{active_points, cached_templates, local_points, visible_part};

fn half(from: &[[f64; 3]], to: &[[f64; 3]], tau: f64) -> f64 {
    let t = ImmutableKdTree::new_from_slice(to).unwrap();
    from.iter()
        .map(|x| {
            let d = t.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance;
            if d <= tau { d } else { d * (1.0 + (d / tau).powi(2)) }
        })
        .sum::<f64>()
        / from.len() as f64
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let p = |i: usize| a[i].parse::<u64>().unwrap();
    let (seed, n, min, max, case) = (p(1), p(2) as usize, p(3) as usize, p(4) as usize, p(5) as usize);
    let model = Model::default_model().unwrap();
    let opts = PolycubeOptions::default();
    let (ctx, mesh) = cases(seed, n, min, max, &SyntheticOptions::default()).swap_remove(case);
    let g = ctx.validity().genus.unwrap();
    let r = generate_from_contexts(&model, &mesh, g, &[ctx], &opts, &mut NoProgress).unwrap();
    let c = &r.candidates[0];
    println!("{ctx} stage {:?} {:?}", c.stage, c.report.as_ref().and_then(|r| r.reason.clone()));
    let (out, inp) = (c.output.as_ref().unwrap(), c.input.as_ref().unwrap());
    let tpl = cached_templates(2048);
    let tau = opts.verify.tau_cd;
    for k in ctx.occupied() {
        let sh = shared_faces(&ctx.labels, k);
        println!("cell {k} {} shared {sh:06b}", ctx.labels[k]);
        for (name, t) in [("out", out), ("inp", &inp.tensor)] {
            let loc = local_points(&active_points(t, k, 1e-4), inp.frame.scale);
            let b = sddpm::geometry::Aabb::of_points(&loc);
            print!("  {name} ext {:.2} {:.2} {:.2}:", b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]);
            for q in Primitive::solids() {
                let full = &tpl[q.label() as usize];
                let acc = half(&loc, full, tau);
                let cov = half(&visible_part(full, sh), &loc, tau);
                let mark = if q == ctx.labels[k] { "*" } else { "" };
                print!(" {mark}{}={:.4}+{:.4}", q.name(), acc, cov);
            }
            println!();
            if std::env::var_os("ZONES").is_some() {
                // per-zone sums (not means) of the two halves, for the target and the
                // same-axis twins: zone = core (|u|,|v| <= 0.2 about the label's hole axis) by
                // thirds along the axis, or "out"
                for q in Primitive::solids().filter(|q| *q != Primitive::Cube) {
                    let ax = match q.name().chars().nth(q.name().len() - 1).unwrap() { 'X' => 0, 'Y' => 1, _ => 2 };
                    let tgt_ax = match ctx.labels[k].name().chars().last().unwrap() { 'X' => 0, 'Y' => 1, 'Z' => 2, _ => 9 };
                    if ax != tgt_ax { continue; }
                    let full = &tpl[q.label() as usize];
                    let vis = visible_part(full, sh);
                    let zone = |p: &[f64; 3]| -> usize {
                        let (u, v) = ((ax + 1) % 3, (ax + 2) % 3);
                        if p[u].abs() <= 0.2 && p[v].abs() <= 0.2 { ((p[ax] + 0.5) * 3.0).floor().clamp(0.0, 2.0) as usize } else { 3 }
                    };
                    let tt = ImmutableKdTree::new_from_slice(&full[..]).unwrap();
                    let tl = ImmutableKdTree::new_from_slice(&loc[..]).unwrap();
                    let f = |d: f64| if d <= tau { d } else { d * (1.0 + (d / tau).powi(2)) };
                    let mut acc = [0.0; 4];
                    let mut nacc = [0usize; 4];
                    for x in &loc { let d = tt.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance; acc[zone(x)] += f(d) / loc.len() as f64; nacc[zone(x)] += 1; }
                    let mut cov = [0.0; 4];
                    let mut ncov = [0usize; 4];
                    for x in &vis { let d = tl.query(x).nearest_one::<SquaredEuclidean<f64>>().execute().distance; cov[zone(x)] += f(d) / vis.len() as f64; ncov[zone(x)] += 1; }
                    println!("    {:6} acc {:?} n {:?} | cov {:?} n {:?}", q.name(), acc.map(|v| (v * 1e4).round() / 1e4), nacc, cov.map(|v| (v * 1e4).round() / 1e4), ncov);
                }
            }
        }
    }
}

//! The generator benchmark: the learned point denoiser (the default) against the
//! closed-form template estimate (the baseline), measured in one run on synthetic
//! cases of a seed that neither training (seed 42) nor the sampler's tuning (seed
//! 8100) used.
//!
//! `cargo bench --bench generator -- [--seed 9100] [--cases 48] [--weights FILE] [--csv FILE] [--without-paper]`
//!
//! Quality against training epochs, from the per-epoch snapshots a training run
//! keeps (`epoch-N.sddpmw` in its checkpoint folder), on 24 cases per group of the
//! same unseen seed: true contexts verified and relabelled contexts refused with the
//! default sampler, and the label probe's ratio and cosine at t = 40 and 120:
//! `cargo bench --bench generator -- --epochs CKPT_DIR --out docs/figures [--seed 9100]`
//! (writes quality_vs_epoch.csv and quality_vs_epoch.png there).
//!
//! 1. The label probe (docs/history/diffusion.md, "The root cause"): e_A - e_B of
//!    the model against the Bayes-optimal difference, ratio and cosine per t.
//! 2. Per group (1-3 and 4-12 occupied cells): true contexts verified (GOCC + TCV,
//!    no retry), one-cell relabelled contexts refused by the verification of the
//!    output (pre-check off), the median displacement between an input point and
//!    its output point, the Chamfer distance to the exact polycube, seconds.
//! 3. The paper's BHC ablation: a warped blind-hole cell diffused with its label
//!    and with the cube label, Chamfer distance of the output to the input.

use sddpm::context::Context;
use sddpm::diffusion::sample::SamplerOptions;
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::search::eval::{generator_eval, label_probe};
use sddpm::search::generate::{generate_from_contexts, PolycubeOptions};
use sddpm::search::synthetic::{synthetic_mesh, SyntheticOptions};
use sddpm::search::verify::{active_points, chamfer};
use std::fmt::Write as _;

struct Generator {
    name: &'static str,
    model: Model,
    opts: PolycubeOptions,
    /// Whether the label probe gives the model the slots' ranks.
    rank: bool,
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok())
}

/// The quality-against-epoch curves of a checkpoint folder's snapshots.
fn epochs(dir: &std::path::Path, out: &std::path::Path, seed: u64) {
    use sddpm::export::plot::{line_png, Series};
    let mut snaps: Vec<(usize, std::path::PathBuf)> = std::fs::read_dir(dir)
        .expect("checkpoint folder")
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let n = name.strip_prefix("epoch-")?.strip_suffix(".sddpmw")?.parse().ok()?;
            Some((n, e.path()))
        })
        .collect();
    snaps.sort();
    let single = |l: &str| Context::parse(&format!("{l},0,0,0,0,0,0,0,0,0,0,0")).expect("label");
    let mut csv = String::from("epoch,true_1_3,true_4_12,refused_1_3,refused_4_12,probe_ratio_t40,probe_cos_t40,probe_ratio_t120,probe_cos_t120\n");
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 8];
    for (n, path) in &snaps {
        let model = Model::from_file(path, Backend::Flex).expect("snapshot");
        let opts = PolycubeOptions::default();
        let a = generator_eval(&model, seed, 24, 1, 3, &opts).expect("evaluation");
        let b = generator_eval(&model, seed, 24, 4, 12, &opts).expect("evaluation");
        let mut probe = [0.0f64; 4];
        let pairs = [("cube", "THC+Z"), ("BHC+Z", "cube"), ("THC+X", "THC+Z")];
        for (x, y) in pairs {
            let rows = label_probe(&model, &single(x), &single(y), &[40, 120], seed, 2, false).expect("probe");
            for (i, r) in rows.iter().enumerate() {
                probe[2 * i] += r.ratio / pairs.len() as f64;
                probe[2 * i + 1] += r.cosine / pairs.len() as f64;
            }
        }
        let v = [
            a.true_verified as f64 / a.cases as f64,
            b.true_verified as f64 / b.cases as f64,
            a.wrong_refused as f64 / a.wrong_trials.max(1) as f64,
            b.wrong_refused as f64 / b.wrong_trials.max(1) as f64,
            probe[0],
            probe[1],
            probe[2],
            probe[3],
        ];
        writeln!(csv, "{n},{}", v.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(",")).unwrap();
        println!("epoch {n}: {:?}", v.map(|x| (x * 1000.0).round() / 1000.0));
        for (k, x) in v.iter().enumerate() {
            series[k].push((*n as f64, *x));
        }
    }
    std::fs::create_dir_all(out).expect("output folder");
    std::fs::write(out.join("quality_vs_epoch.csv"), csv).expect("csv");
    let names = ["true verified, 1-3 cells", "true verified, 4-12 cells", "relabelled refused, 1-3", "relabelled refused, 4-12", "probe ratio, t = 40", "probe cosine, t = 40", "probe ratio, t = 120", "probe cosine, t = 120"];
    let s: Vec<Series> = names.iter().zip(&series).map(|(name, pts)| Series { name, points: pts.clone() }).collect();
    line_png(&out.join("quality_vs_epoch.png"), &s, "Learned generator against training epochs (unseen seed)", "epoch", "share / ratio / cosine", false).expect("plot");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = arg(&args, "--seed").unwrap_or(9100);
    if let Some(dir) = arg::<String>(&args, "--epochs") {
        let out: String = arg(&args, "--out").unwrap_or_else(|| "docs/figures".into());
        epochs(std::path::Path::new(&dir), std::path::Path::new(&out), seed);
        return;
    }
    let cases: usize = arg(&args, "--cases").unwrap_or(48);
    let weights: Option<String> = arg(&args, "--weights");
    let csv: Option<String> = arg(&args, "--csv");
    let learned = || match &weights {
        Some(p) => Model::from_file(std::path::Path::new(p), Backend::Flex).expect("weights"),
        None => Model::default_model().expect("the embedded model"),
    };
    let gens = [
        Generator { name: "learned (default sampler)", model: learned(), opts: PolycubeOptions::default(), rank: false },
        Generator { name: "learned (paper's sampler)", model: learned(), opts: PolycubeOptions { sampler: SamplerOptions::paper(), ..Default::default() }, rank: false },
        Generator { name: "template estimate (baseline)", model: Model::template(), opts: PolycubeOptions::template(), rank: true },
    ];
    // `--without-paper`: skip the paper's sampler (all 500 steps; most of the run's time)
    let without_paper = args.iter().any(|a| a == "--without-paper");
    let mut out = String::new();
    let mut rows_csv = String::from("section,generator,key,value\n");
    let t0 = std::time::Instant::now();
    writeln!(out, "Generator benchmark, seed {seed}, {cases} cases per group, weights {}\n", gens[0].model.generator_name(None)).unwrap();

    // 1. label probe
    let pairs = [("cube", "THC+Z"), ("THC+Z", "cube"), ("BHC+Z", "cube"), ("BHC+Z", "BHC-Z"), ("THC+X", "THC+Z")];
    let ts = [20usize, 40, 80, 120, 200];
    let single = |l: &str| Context::parse(&format!("{l},0,0,0,0,0,0,0,0,0,0,0")).expect("label");
    writeln!(out, "### Label probe (mean over {} label pairs, 3 noisy cells each)\n", pairs.len()).unwrap();
    writeln!(out, "| t | learned, point alone: ratio / cos | learned, with ranks: ratio / cos | template estimate: ratio / cos |\n|---:|---|---|---|").unwrap();
    let probes: Vec<Vec<(f64, f64)>> = [(&gens[0], false), (&gens[0], true), (&gens[2], true)]
        .iter()
        .map(|(g, rank)| {
            let mut acc = vec![(0.0, 0.0); ts.len()];
            for (a, b) in pairs {
                let rows = label_probe(&g.model, &single(a), &single(b), &ts, seed, 3, *rank).expect("probe");
                for (i, r) in rows.iter().enumerate() {
                    acc[i].0 += r.ratio / pairs.len() as f64;
                    acc[i].1 += r.cosine / pairs.len() as f64;
                }
            }
            acc
        })
        .collect();
    for (i, t) in ts.iter().enumerate() {
        writeln!(out, "| {t} | {:.2} / {:.2} | {:.2} / {:.2} | {:.2} / {:.2} |", probes[0][i].0, probes[0][i].1, probes[1][i].0, probes[1][i].1, probes[2][i].0, probes[2][i].1).unwrap();
        for (k, name) in ["learned point alone", "learned with ranks", "template"].iter().enumerate() {
            writeln!(rows_csv, "probe,{name},ratio_t{t},{:.4}", probes[k][i].0).unwrap();
            writeln!(rows_csv, "probe,{name},cos_t{t},{:.4}", probes[k][i].1).unwrap();
        }
    }
    let _ = gens[0].rank;

    // 2. verification, refusal, correspondence
    writeln!(out, "\n### Verification, refusal and correspondence\n").unwrap();
    writeln!(out, "| generator | cells | true verified | relabelled refused by GOCC + TCV | median displacement (cell units) | Chamfer to the truth | s |\n|---|---|---:|---:|---:|---:|---:|").unwrap();
    for (lo, hi) in [(1usize, 3usize), (4, 12)] {
        for g in gens.iter().filter(|g| !(without_paper && g.opts.sampler.raw_start)) {
            // the paper's sampler runs all 500 steps: a dozen cases per group
            let n = if g.opts.sampler.raw_start { cases.min(12) } else { cases };
            let e = generator_eval(&g.model, seed, n, lo, hi, &g.opts).expect("evaluation");
            writeln!(
                out,
                "| {} | {lo}-{hi} | {}/{} ({:.0} %) | {}/{} ({:.0} %) | {:.3} | {:.5} | {:.0} |",
                g.name,
                e.true_verified,
                e.cases,
                100.0 * e.true_verified as f64 / e.cases.max(1) as f64,
                e.wrong_refused,
                e.wrong_trials,
                100.0 * e.wrong_refused as f64 / e.wrong_trials.max(1) as f64,
                e.median_displacement,
                e.mean_chamfer,
                e.seconds
            )
            .unwrap();
            for (k, v) in [("true_verified", e.true_verified as f64 / e.cases.max(1) as f64), ("wrong_refused", e.wrong_refused as f64 / e.wrong_trials.max(1) as f64), ("median_displacement", e.median_displacement), ("chamfer", e.mean_chamfer), ("seconds", e.seconds)] {
                writeln!(rows_csv, "eval_{lo}_{hi},{},{k},{v:.5}", g.name).unwrap();
            }
        }
    }

    // 3. BHC ablation
    writeln!(out, "\n### BHC ablation ({} warped blind-hole cells; Chamfer of the output to the input, cell units squared)\n", cases.min(12)).unwrap();
    writeln!(out, "| generator | label BHC+Z | label cube | ratio |\n|---|---:|---:|---:|").unwrap();
    let truth = single("BHC+Z");
    for g in gens.iter().filter(|g| !(without_paper && g.opts.sampler.raw_start)) {
        let mut sums = [0.0f64; 2];
        let n = cases.min(12);
        for i in 0..n {
            let mesh = synthetic_mesh(&truth, &SyntheticOptions::default(), &mut seeded_rng(seed ^ 0xb4c, i as u64));
            for (k, label) in ["BHC+Z", "cube"].iter().enumerate() {
                let opts = PolycubeOptions { max_fit: f64::INFINITY, relative_fit: 0.0, neighbour_fit_ratio: 0.0, max_in_empty_fraction: 1.0, min_occupied_fraction: 0.0, ..g.opts.clone() };
                let r = generate_from_contexts(&g.model, &mesh, 0, &[single(label)], &opts, &mut NoProgress).expect("generation");
                let c = &r.candidates[0];
                let (Some(o), Some(inp)) = (&c.output, &c.input) else { continue };
                let s = 1.0 / inp.frame.scale;
                let a: Vec<[f64; 3]> = active_points(o, 0, 1e-4).iter().map(|p| p.map(|v| v * s)).collect();
                let b: Vec<[f64; 3]> = active_points(&inp.tensor, 0, 1e-4).iter().map(|p| p.map(|v| v * s)).collect();
                sums[k] += chamfer(&a, &b) / n as f64;
            }
        }
        writeln!(out, "| {} | {:.4} | {:.4} | {:.1}x |", g.name, sums[0], sums[1], sums[1] / sums[0]).unwrap();
        writeln!(rows_csv, "bhc,{},right,{:.5}\nbhc,{},cube,{:.5}", g.name, sums[0], g.name, sums[1]).unwrap();
    }
    writeln!(out, "\n{:.0} s in all", t0.elapsed().as_secs_f64()).unwrap();
    print!("{out}");
    if let Some(p) = csv {
        std::fs::write(&p, rows_csv).expect("csv");
    }
}

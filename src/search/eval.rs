//! Measuring a model on held-in synthetic inputs (assemblies the training never saw,
//! warped and rotated): TCV pass rate with the true context, Chamfer distance to the
//! exact polycube per category, and the rate at which a wrong but genus-consistent
//! context is rejected.

use super::generate::{generate_from_contexts, Candidate, PolycubeOptions, Stage};
use super::synthetic::{cases, SyntheticOptions};
use super::verify::chamfer;
use crate::context::Context;
use crate::diffusion::dataset::sample_cells;
use crate::diffusion::Model;
use crate::error::{NoProgress, Result};
use crate::geometry::rng::seeded_rng;
use crate::polycube::tensor::unlayout;
use crate::polycube::{Primitive, NUM_CELLS};
use serde::Serialize;

/// Seed mixer of the exact polycube's samples a case's output is compared with.
const EXACT_SAMPLES_STREAM: u64 = 0xc0ffee;

/// Per-category Chamfer statistics.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CategoryStat {
    pub label: String,
    pub cells: usize,
    pub mean_chamfer: f64,
}

/// Result of an evaluation run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct EvalSummary {
    pub cases: usize,
    pub precheck_passed: usize,
    pub gocc_passed: usize,
    pub tcv_passed: usize,
    /// Of those, verified by the second diffusion with the visible prior
    /// (`PolycubeOptions::visible_retry`).
    pub tcv_passed_on_retry: usize,
    /// Cases whose aligned input itself (the tensor before any noise) passes GOCC and
    /// TCV under the true context: what a denoiser that only kept the input would
    /// score, the reference for the threshold.
    pub input_tcv_passed: usize,
    /// Why the inputs that fail it do.
    pub input_failures: Vec<String>,
    pub pass_rate: f64,
    pub per_category: Vec<CategoryStat>,
    /// Wrong-context trials and how many were rejected.
    pub wrong_trials: usize,
    pub wrong_rejected: usize,
    /// Rejections of wrong contexts by the pre-check (occupancy, fit or the
    /// neighbour test) alone.
    pub wrong_rejected_precheck: usize,
    /// Of those, by the neighbour test (a one-cell alternative fits far better).
    pub wrong_rejected_neighbour: usize,
    /// True contexts the neighbour test refused.
    pub true_rejected_neighbour: usize,
    /// Geometric fit of the true context (squared cell units), per case.
    pub true_fit: Vec<f64>,
    /// Geometric fit of the wrong context, per trial.
    pub wrong_fit: Vec<f64>,
    pub seconds: f64,
    pub failures: Vec<String>,
}

/// A genus-consistent wrong context: one occupied cell's label replaced by another of
/// the same genus whose solid is not congruent to the truth's.
pub fn wrong_context(ctx: &Context, k: u64) -> Option<Context> {
    let g = ctx.validity().genus?;
    let occupied: Vec<usize> = ctx.occupied().collect();
    const WRONG_CONTEXT_SEED: u64 = 0xbad;
    let mut rng = seeded_rng(WRONG_CONTEXT_SEED, k);
    use rand::RngExt;
    for _ in 0..50 {
        let n = occupied[rng.random_range(0..occupied.len())];
        let mut w = *ctx;
        w.labels[n] = Primitive::ALL[rng.random_range(1..=10usize)];
        if w.labels[n] != ctx.labels[n] && w.validity().genus == Some(g) && !crate::polycube::assembly::congruent(&w.assemble(), &ctx.assemble()) {
            return Some(w);
        }
    }
    None
}

/// Evaluate with the true context on `n` cases with `min..=max` occupied cells.
pub fn evaluate(model: &Model, seed: u64, n: usize, min: usize, max: usize, opts: &PolycubeOptions, with_wrong: bool) -> Result<EvalSummary> {
    let t0 = std::time::Instant::now();
    let synth = SyntheticOptions::default();
    let mut s = EvalSummary { cases: n, ..Default::default() };
    let mut cat_sum = [0.0f64; 11];
    let mut cat_n = [0usize; 11];
    for (i, (ctx, mesh)) in cases(seed, n, min, max, &synth).into_iter().enumerate() {
        let g = ctx.validity().genus.unwrap();
        let r = generate_from_contexts(model, &mesh, g, &[ctx], opts, &mut NoProgress)?;
        let c: &Candidate = &r.candidates[0];
        s.true_fit.push(c.fit);
        if c.refusal.is_some() {
            s.true_rejected_neighbour += 1;
        }
        if c.stage != Stage::Occupancy {
            s.precheck_passed += 1;
        }
        if matches!(c.stage, Stage::Tcv | Stage::Verified) {
            s.gocc_passed += 1;
        }
        if c.stage == Stage::Verified {
            s.tcv_passed += 1;
            s.tcv_passed_on_retry += c.visible_retry as usize;
        } else {
            let why = c.report.as_ref().and_then(|r| r.reason.clone()).unwrap_or_else(|| format!("pre-check: {:.1}% in empty cells", 100.0 * c.occupancy.in_empty_cells));
            s.failures.push(format!("case {i} {ctx}: {why}"));
        }
        if let Some(inp) = &c.input {
            let rep = crate::search::verify::verify(&inp.tensor, &ctx, &inp.frame, &opts.verify);
            if rep.passed {
                s.input_tcv_passed += 1;
            } else {
                s.input_failures.push(format!("case {i}: {}", rep.reason.clone().unwrap_or_default()));
            }
        }
        if let (Some(out), Some(inp)) = (&c.output, &c.input) {
            let mut rng = seeded_rng(seed ^ EXACT_SAMPLES_STREAM, i as u64);
            // the exact polycube's surface per cell: with the visible prior (asked for,
            // or the retry's) the output carries no shared faces, and neither does the
            // assembled surface
            let exact = if opts.sampler.visible_prior || c.visible_retry {
                crate::diffusion::dataset::sample_cells_visible(&ctx, 1.0, &mut rng)
            } else {
                sample_cells(&ctx, 1.0, &mut rng)
            };
            let blocks = unlayout(out);
            let scale = 1.0 / inp.frame.scale; // cell units
            for k in 0..NUM_CELLS {
                let l = ctx.labels[k];
                if l == Primitive::Null {
                    continue;
                }
                let a: Vec<[f64; 3]> = blocks[k].iter().map(|p| p.map(|v| v as f64 * scale)).collect();
                let b: Vec<[f64; 3]> = exact[k].iter().map(|p| p.map(|v| v as f64 * scale)).collect();
                cat_sum[l.label() as usize] += chamfer(&a, &b);
                cat_n[l.label() as usize] += 1;
            }
        }
        if with_wrong {
            if let Some(w) = wrong_context(&ctx, i as u64) {
                let r = generate_from_contexts(model, &mesh, g, &[w], opts, &mut NoProgress)?;
                s.wrong_trials += 1;
                s.wrong_fit.push(r.candidates[0].fit);
                if r.chosen.is_none() {
                    s.wrong_rejected += 1;
                }
                if r.candidates[0].stage == Stage::Occupancy {
                    s.wrong_rejected_precheck += 1;
                }
                if r.candidates[0].refusal.is_some() {
                    s.wrong_rejected_neighbour += 1;
                }
            }
        }
    }
    s.pass_rate = s.tcv_passed as f64 / n.max(1) as f64;
    s.per_category = (1..11)
        .filter(|&l| cat_n[l] > 0)
        .map(|l| CategoryStat { label: Primitive::ALL[l].name().into(), cells: cat_n[l], mean_chamfer: cat_sum[l] / cat_n[l] as f64 })
        .collect();
    s.seconds = t0.elapsed().as_secs_f64();
    Ok(s)
}

/// One cell of a diffused case, for the TCV threshold sweep.
struct SweepCell {
    local: Vec<[f64; 3]>,
    target: Primitive,
    /// Faces shared with occupied neighbours (`polycube::assembly::shared_faces`) when the options
    /// ask for visible coverage, else 0 (coverage over the whole template).
    shared: u8,
}

/// TCV acceptance for one (tau_CD, p) pair.
#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
    pub tau_cd: f64,
    pub penalty_p: f64,
    /// True contexts whose every cell passes TCV (of those that passed GOCC).
    pub true_accepted: usize,
    pub true_cases: usize,
    /// Cells of true contexts whose target template is the nearest.
    pub true_cells_nearest: usize,
    pub true_cells: usize,
    /// Wrong contexts whose every cell passes TCV (false acceptances).
    pub wrong_accepted: usize,
    pub wrong_cases: usize,
}

/// GOCC's measurements on one diffused candidate (the sweep's evidence for
/// `VerifyOptions::tau_active`, `min_inside_fraction` and `max_null_region_fraction`).
#[derive(Debug, Clone, Serialize)]
pub struct GoccSample {
    /// The true context (else a wrong genus-consistent one).
    pub truth: bool,
    pub gocc_pass: bool,
    /// Smallest bounding-box span of an occupied cell's points (cell units).
    pub min_span: f64,
    /// Smallest fraction of an occupied block's points inside its own cell.
    pub min_inside: f64,
    /// Fraction of the active points in null cells' regions.
    pub null_fraction: f64,
}

fn gocc_sample(c: &Candidate, truth: bool) -> Option<GoccSample> {
    let r = c.report.as_ref()?;
    let occ: Vec<&crate::search::verify::CellReport> = r.cells.iter().filter(|cr| c.context.labels[cr.cell] != Primitive::Null).collect();
    Some(GoccSample {
        truth,
        gocc_pass: r.gocc_pass,
        min_span: occ.iter().map(|cr| cr.span).fold(f64::INFINITY, f64::min),
        min_inside: occ.iter().map(|cr| cr.inside_fraction).fold(f64::INFINITY, f64::min),
        null_fraction: r.null_region_fraction,
    })
}

/// The measurement behind `VerifyOptions::tau_cd` and `penalty_p`: diffuse `n` held-in
/// cases with their true context and with a wrong genus-consistent one, then count, for
/// every pair of the grid, how many true contexts TCV accepts and how many wrong ones
/// it accepts. GOCC failures and pre-check refusals are left out (TCV never sees them).
/// With `fidelity`, also prints to stderr each candidate's per-cell
/// PCD between its output and its own laid-out input (grid units, tau 0.01, p 2),
/// the output-against-input test measured in BENCHMARKS.md ("TCV threshold for the
/// template-attention model"). Also returns GOCC's measurements on every diffused
/// candidate, true and wrong.
#[allow(clippy::too_many_arguments)]
pub fn tcv_sweep(model: &Model, seed: u64, n: usize, min: usize, max: usize, opts: &PolycubeOptions, taus: &[f64], ps: &[f64], fidelity: bool) -> Result<(Vec<SweepRow>, Vec<GoccSample>)> {
    let mut gocc: Vec<GoccSample> = Vec::new();
    let synth = SyntheticOptions::default();
    let tpl = crate::search::verify::cached_templates(opts.verify.template_points);
    let mut truth: Vec<Vec<SweepCell>> = Vec::new();
    let mut wrong: Vec<Vec<SweepCell>> = Vec::new();
    let collect = |c: &Candidate| -> Option<Vec<SweepCell>> {
        let (out, inp) = (c.output.as_ref()?, c.input.as_ref()?);
        if !c.report.as_ref().is_some_and(|r| r.gocc_pass) {
            return None;
        }
        Some(
            c.context
                .occupied()
                .map(|k| SweepCell {
                    local: crate::search::verify::local_points(&crate::search::verify::active_points(out, k, opts.verify.zero_norm), inp.frame.scale),
                    target: c.context.labels[k],
                    shared: if opts.verify.visible_coverage { crate::polycube::assembly::shared_faces(&c.context.labels, k) } else { 0 },
                })
                .collect(),
        )
    };
    // `fidelity`: each occupied cell's PCD between the output and its own laid-out
    // input, printed as "max [per cell] stage" after `head` (and, for a wrong
    // context, the value of its relabelled cell)
    let show_fidelity = fidelity;
    let print_fidelity = |head: String, c: &Candidate, changed: Option<usize>| {
        let cells: Vec<usize> = c.context.occupied().collect();
        // no values for a candidate the pre-check refused (it has no output)
        let f: Vec<f64> = match (c.output.as_ref(), c.input.as_ref()) {
            (Some(out), Some(inp)) => {
                let s = inp.frame.scale;
                let scaled = |t: &[f32], k: usize| -> Vec<[f64; 3]> { crate::search::verify::active_points(t, k, opts.verify.zero_norm).iter().map(|p| p.map(|v| v / s)).collect() };
                cells.iter().map(|&k| crate::search::verify::pcd(&scaled(out, k), &scaled(&inp.tensor, k), 0.01, 2.0)).collect()
            }
            _ => Vec::new(),
        };
        let max = f.iter().cloned().fold(0.0, f64::max);
        let at = changed.map(|k| format!(" changed cell {k}: {:.4}", cells.iter().position(|&c| c == k).and_then(|j| f.get(j).copied()).unwrap_or(f64::NAN))).unwrap_or_default();
        eprintln!("{head} max {max:.4}{at} {:?} stage {:?}", f.iter().map(|x| (x * 1e4).round() / 1e4).collect::<Vec<_>>(), c.stage);
    };
    for (i, (ctx, mesh)) in cases(seed, n, min, max, &synth).into_iter().enumerate() {
        let g = ctx.validity().genus.unwrap();
        let r = generate_from_contexts(model, &mesh, g, &[ctx], opts, &mut NoProgress)?;
        if show_fidelity {
            print_fidelity(format!("FID true {i} {ctx}"), &r.candidates[0], None);
        }
        gocc.extend(gocc_sample(&r.candidates[0], true));
        if let Some(v) = collect(&r.candidates[0]) {
            truth.push(v);
        }
        if let Some(w) = wrong_context(&ctx, i as u64) {
            let r = generate_from_contexts(model, &mesh, g, &[w], opts, &mut NoProgress)?;
            if show_fidelity {
                let k = w.labels.iter().zip(ctx.labels.iter()).position(|(a, b)| a != b);
                print_fidelity(format!("FID wrong {i} {w}"), &r.candidates[0], k);
            }
            gocc.extend(gocc_sample(&r.candidates[0], false));
            if let Some(v) = collect(&r.candidates[0]) {
                wrong.push(v);
            }
        }
    }
    let mut rows = Vec::new();
    for &p in ps {
        for &tau in taus {
            let judge = |cells: &[SweepCell]| -> (bool, usize) {
                let mut all = true;
                let mut nearest = 0;
                for c in cells {
                    let d: Vec<f64> = Primitive::solids().map(|q| crate::search::verify::cell_pcd(&c.local, &tpl[q.label() as usize], c.shared, tau, p)).collect();
                    let dt = d[c.target.label() as usize - 1];
                    let best = d.iter().cloned().fold(f64::INFINITY, f64::min);
                    let near = dt <= best;
                    nearest += near as usize;
                    all &= near && dt <= tau;
                }
                (all, nearest)
            };
            let mut row = SweepRow { tau_cd: tau, penalty_p: p, true_accepted: 0, true_cases: truth.len(), true_cells_nearest: 0, true_cells: 0, wrong_accepted: 0, wrong_cases: wrong.len() };
            for t in &truth {
                let (a, k) = judge(t);
                row.true_accepted += a as usize;
                row.true_cells_nearest += k;
                row.true_cells += t.len();
            }
            row.wrong_accepted = wrong.iter().filter(|w| judge(w).0).count();
            rows.push(row);
        }
    }
    Ok((rows, gocc))
}

/// One timestep of the label probe ([`label_probe`]).
#[derive(Debug, Clone, Serialize)]
pub struct ProbeRow {
    pub t: usize,
    /// RMS over the cell's 512 x 3 values of the model's e_A - e_B.
    pub model_diff: f64,
    /// The same for the Bayes-optimal predictors of A and of B.
    pub bayes_diff: f64,
    /// model_diff / bayes_diff.
    pub ratio: f64,
    /// Cosine between the model's and the Bayes-optimal difference.
    pub cosine: f64,
    /// RMS error of the model's e_A against the noise actually added.
    pub model_err: f64,
    /// RMS error of the Bayes-optimal e_A against that noise.
    pub bayes_err: f64,
}

/// Bayes-optimal noise of one cell's slots given `draws` independent sorted samples
/// of its primitive: with `rank`, the p-th point of each draw is a draw from
/// p(x_0 | rank p), the estimate the sorted layout defines; without, every point of
/// every draw is a draw from the primitive, the estimate of a point alone.
fn bayes_eps(draws: &[Vec<f32>], xt: &[f32], n: usize, sa: f64, sd: f64, shift: [f64; 3], rank: bool) -> Vec<f64> {
    use crate::polycube::tensor::{flat, slot, POINTS_PER_CELL};
    let pts: Vec<Vec<[f64; 3]>> = (0..POINTS_PER_CELL)
        .map(|p| {
            let (r, c) = slot(n, p);
            draws.iter().map(|d| std::array::from_fn(|ch| d[flat(ch, r, c)] as f64)).collect()
        })
        .collect();
    // 96 draws pooled: 49,152 points, about 0.011 cell units apart on a cell's
    // surface, a fifth of the noise at t = 20 (0.05 cell units for one cell)
    let pooled: Vec<[f64; 3]> = if rank { Vec::new() } else { pts.iter().flat_map(|v| v.iter().take(96)).copied().collect() };
    let mut out = Vec::with_capacity(POINTS_PER_CELL * 3);
    for p in 0..POINTS_PER_CELL {
        let (r, c) = slot(n, p);
        let y: [f64; 3] = std::array::from_fn(|ch| xt[flat(ch, r, c)] as f64 - shift[ch]);
        let cand: &[[f64; 3]] = if rank { &pts[p] } else { &pooled };
        let w: Vec<f64> = cand.iter().map(|d| -(0..3).map(|ch| (y[ch] - sa * d[ch]).powi(2)).sum::<f64>() / (2.0 * sd * sd)).collect();
        let m = w.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let w: Vec<f64> = w.iter().map(|v| (v - m).exp()).collect();
        let tot: f64 = w.iter().sum();
        for ch in 0..3 {
            let mx: f64 = cand.iter().zip(&w).map(|(d, wi)| wi * d[ch]).sum::<f64>() / tot;
            out.push((y[ch] - sa * mx) / sd);
        }
    }
    out
}

/// The label probe (BENCHMARKS.md "The root cause"): a cell of single-cell context A
/// is sampled (seeded), forward-noised at t, and the model predicts the noise under
/// A and under B (same cell, another label); the Bayes-optimal predictors of A and B
/// (300 sorted samplings each) give the difference the label should make. Averaged
/// over `trials` fresh cells and noises per t (sums of squares pooled). With `rank`
/// the model sees the slots' ranks and the reference is the rank-conditioned
/// estimate; without, neither uses them (the point denoiser's default; a U-Net or
/// the template estimate always use the layout, so probe them with `rank`).
pub fn label_probe(model: &Model, a: &Context, b: &Context, ts: &[usize], seed: u64, trials: usize, rank: bool) -> Result<Vec<ProbeRow>> {
    use crate::polycube::tensor::{flat, layout, slot, POINTS_PER_CELL, TENSOR_H, TENSOR_LEN, TENSOR_W};
    use burn::tensor::{Tensor, TensorData};
    use rand_distr::{Distribution, StandardNormal};
    let n = a.occupied().next().ok_or_else(|| crate::error::Error::InvalidArgument("context A has no occupied cell".into()))?;
    if a.occupied().count() != 1 || b.occupied().collect::<Vec<_>>() != vec![n] {
        return Err(crate::error::Error::InvalidArgument("the label probe takes two single-cell contexts on the same cell".into()));
    }
    let draws = |c: &Context, s: u64| -> Vec<Vec<f32>> {
        (0..300u64).map(|k| layout(&sample_cells(c, 1.0, &mut seeded_rng(s, k)))).collect()
    };
    let (da, db) = (draws(a, seed ^ 0xa), draws(b, seed ^ 0xb));
    let sched = &model.schedule;
    let net = model.net.configured(Some(1.0), false, rank);
    let idx: Vec<usize> = (0..POINTS_PER_CELL).flat_map(|p| {
        let (r, c) = slot(n, p);
        (0..3).map(move |ch| flat(ch, r, c))
    }).collect();
    let predict = |xt: &[f32], t: usize, c: &Context| -> Vec<f32> {
        let ct = Tensor::<2>::from_data(TensorData::new(c.one_hot().to_vec(), [1, crate::polycube::CONTEXT_DIM]), &model.device);
        let x = Tensor::<4>::from_data(TensorData::new(xt.to_vec(), [1, 3, TENSOR_H, TENSOR_W]), &model.device);
        net.forward(x, &[t], ct, sched).into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default()
    };
    let mut rows = Vec::new();
    for &t in ts {
        let (mut dm, mut dbay, mut dot, mut em, mut eb) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for trial in 0..trials {
            const PROBE_STREAM: u64 = 0x9e0b;
            let mut rng = seeded_rng(seed ^ PROBE_STREAM, (t * 1000 + trial) as u64);
            let x0 = layout(&sample_cells(a, 1.0, &mut rng));
            let z: Vec<f32> = (0..TENSOR_LEN).map(|_| StandardNormal.sample(&mut rng)).collect();
            let mut xt = vec![0f32; TENSOR_LEN];
            sched.forward_sample(&x0, &z, t, &mut xt);
            let (ea, eb_) = (predict(&xt, t, a), predict(&xt, t, b));
            let (sa, sd) = (sched.alpha_bar[t].sqrt(), (1.0 - sched.alpha_bar[t]).sqrt());
            let shift = sched.config.q.map(|q| sched.qcoef[t] * q);
            let (ba, bb) = (bayes_eps(&da, &xt, n, sa, sd, shift, rank), bayes_eps(&db, &xt, n, sa, sd, shift, rank));
            for (i, &k) in idx.iter().enumerate() {
                let m = (ea[k] - eb_[k]) as f64;
                let y = ba[i] - bb[i];
                dm += m * m;
                dbay += y * y;
                dot += m * y;
                em += (ea[k] as f64 - z[k] as f64).powi(2);
                eb += (ba[i] - z[k] as f64).powi(2);
            }
        }
        let cnt = (trials * idx.len()) as f64;
        rows.push(ProbeRow {
            t,
            model_diff: (dm / cnt).sqrt(),
            bayes_diff: (dbay / cnt).sqrt(),
            ratio: (dm / dbay).sqrt(),
            cosine: dot / (dm.sqrt() * dbay.sqrt()).max(1e-30),
            model_err: (em / cnt).sqrt(),
            bayes_err: (eb / cnt).sqrt(),
        });
    }
    Ok(rows)
}

/// What [`generator_eval`] measures for one generator on one set of cases.
#[derive(Debug, Clone, Default, Serialize)]
pub struct GeneratorEval {
    pub cases: usize,
    /// True contexts verified (GOCC + TCV, the pre-check as configured; no retry
    /// unless the options ask for one).
    pub true_verified: usize,
    /// Of the true contexts that failed, those the pre-check refused.
    pub true_precheck_refused: usize,
    /// One-cell relabelled, genus-consistent, non-congruent contexts diffused with
    /// the geometric pre-check off ...
    pub wrong_trials: usize,
    /// ... and refused by GOCC or TCV on the output.
    pub wrong_refused: usize,
    /// Median over the true contexts' occupied slots of |output - input|, cell units.
    pub median_displacement: f64,
    /// Mean Chamfer distance of the true contexts' outputs to the exact polycube's
    /// cells (squared cell units).
    pub mean_chamfer: f64,
    pub seconds: f64,
    /// Failures of true contexts, naming the case.
    pub failures: Vec<String>,
}

/// The generator benchmark's measurement on `n` synthetic cases of `seed` with
/// `min..=max` occupied cells: true contexts verified, relabelled contexts refused by
/// the verification of the output (pre-check off for those), correspondence
/// displacement and Chamfer distance to the truth.
pub fn generator_eval(model: &Model, seed: u64, n: usize, min: usize, max: usize, opts: &PolycubeOptions) -> Result<GeneratorEval> {
    let t0 = std::time::Instant::now();
    let mut e = GeneratorEval { cases: n, ..Default::default() };
    let no_precheck = PolycubeOptions { max_fit: f64::INFINITY, relative_fit: 0.0, neighbour_fit_ratio: 0.0, max_in_empty_fraction: 1.0, min_occupied_fraction: 0.0, ..opts.clone() };
    let mut disp: Vec<f64> = Vec::new();
    let (mut ch_sum, mut ch_n) = (0.0, 0usize);
    for (i, (ctx, mesh)) in cases(seed, n, min, max, &SyntheticOptions::default()).into_iter().enumerate() {
        let g = ctx.validity().genus.unwrap_or(0);
        let r = generate_from_contexts(model, &mesh, g, &[ctx], opts, &mut NoProgress)?;
        let c = &r.candidates[0];
        if c.stage == Stage::Verified {
            e.true_verified += 1;
        } else {
            if c.stage == Stage::Occupancy {
                e.true_precheck_refused += 1;
            }
            let why = c.report.as_ref().and_then(|r| r.reason.clone()).unwrap_or_else(|| "refused by the pre-check".into());
            e.failures.push(format!("case {i} {ctx}: {why}"));
        }
        if let (Some(out), Some(inp)) = (&c.output, &c.input) {
            let (o, x) = (unlayout(out), unlayout(&inp.tensor));
            let mut rng = seeded_rng(seed ^ EXACT_SAMPLES_STREAM, i as u64);
            let exact = if opts.verify.visible_coverage { crate::diffusion::dataset::sample_cells_visible(&ctx, 1.0, &mut rng) } else { sample_cells(&ctx, 1.0, &mut rng) };
            let s = 1.0 / inp.frame.scale;
            for k in ctx.occupied() {
                for (a, b) in o[k].iter().zip(&x[k]) {
                    disp.push(((0..3).map(|ch| ((a[ch] - b[ch]) as f64).powi(2)).sum::<f64>()).sqrt() * s);
                }
                let a: Vec<[f64; 3]> = o[k].iter().map(|p| p.map(|v| v as f64 * s)).collect();
                let b: Vec<[f64; 3]> = exact[k].iter().map(|p| p.map(|v| v as f64 * s)).collect();
                ch_sum += chamfer(&a, &b);
                ch_n += 1;
            }
        }
        if let Some(w) = wrong_context(&ctx, i as u64) {
            let r = generate_from_contexts(model, &mesh, g, &[w], &no_precheck, &mut NoProgress)?;
            e.wrong_trials += 1;
            if r.candidates[0].stage != Stage::Verified {
                e.wrong_refused += 1;
            }
        }
    }
    disp.sort_by(f64::total_cmp);
    e.median_displacement = disp.get(disp.len() / 2).copied().unwrap_or(f64::NAN);
    e.mean_chamfer = ch_sum / ch_n.max(1) as f64;
    e.seconds = t0.elapsed().as_secs_f64();
    Ok(e)
}

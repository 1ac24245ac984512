//! The fits that rank the automated mode's labels, candidates and boxes: the
//! in-context fit of a subregion's labels, the joint label search on the global
//! fit, the global fit of every candidate and the order in which the boxes are
//! tried, in a length common to every box.

use super::super::generate::register::registered_fit;
use super::super::generate::{fit_points, fit_score_cells, fit_score_scaled, polycube_samples, worst_and_mean, FIT_SAMPLES};
use super::boxes::BoxWork;
use super::volume::{suggest_ratios, Subregion};
use super::{AutoReport, BoxResult, Run};
use crate::context::Context;
use crate::error::{Error, Result};
use crate::geometry::SurfaceSample;
use crate::polycube::orientation::AxisRotation;
use crate::polycube::{Primitive, NUM_CELLS};

/// The global fit of every candidate of every box from `from` on (cheap): each box's candidates
/// get their worst cell's fit and are put in ranking order (see below), with the
/// box's best fit in the box's cell units and in the common unit of
/// [`box_scale`]; with `joint_labels`, the joint label search adds its contexts.
pub(super) fn rank_candidates(runs: &[Run], boxes: &mut [BoxWork], from: usize, report: &mut AutoReport) {
    for (bi, work) in boxes.iter_mut().enumerate().skip(from) {
        let run = &runs[work.frame];
        let fit_sub = run.fit_sub;
        // Thousands of candidates for a genus-0 part (a box: 22,000 over the 12
        // boxes): the fits are independent, so they run on every core. (Ranking them
        // on a coarse fit first was tried and lost a complex part's true solid:
        // BENCHMARKS.md "Global fits in parallel".)
        use rayon::prelude::*;
        //
        // Each candidate keeps its worst cell's fit (the fit limits apply to it) and
        // the box's candidates are ordered by the mean cell fit, the ranking score of
        // `Candidate::score`: the worst cell ties candidates that differ in better-
        // fitting cells, and which of them made the `max_global` cut was arbitrary
        // (BENCHMARKS.md "Ranking verified candidates by the mean cell fit").
        let fits: Vec<(f64, f64)> = work.cands.par_iter().map(|(ctx, _)| worst_and_mean(&fit_score_cells(fit_sub, ctx, AxisRotation::IDENTITY, &polycube_samples(ctx, FIT_SAMPLES), [1.0; 3]))).collect();
        let mut keyed: Vec<((Context, f64), f64)> = work.cands.drain(..).zip(fits).map(|((ctx, _), (worst, mean))| ((ctx, worst), mean)).collect();
        if run.aopts.joint_labels {
            add_joint_candidates(run, work, &mut keyed, &mut report.boxes[bi]);
        }
        // Boxes are compared in a common unit: the best of the box's few best-fitting
        // candidates (worst cell), measured with the box's cell widths scaled to that unit.
        keyed.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1));
        let br = &mut report.boxes[bi];
        br.best_fit = keyed.first().map(|c| c.0 .1);
        let scale = box_scale(run.volume.bb.size(), br.dims);
        br.best_fit_common = keyed
            .iter()
            .take(run.aopts.local_keep.max(1) * 2)
            .map(|((ctx, _), _)| fit_score_scaled(fit_sub, ctx, AxisRotation::IDENTITY, &polycube_samples(ctx, FIT_SAMPLES), scale))
            .min_by(f64::total_cmp);
        // then the box's candidates in ranking order (stable: worst cell among equals)
        keyed.sort_by(|a, b| a.1.total_cmp(&b.1));
        work.cands.extend(keyed.into_iter().map(|(c, _)| c));
    }
}

/// Add the contexts of the joint label search ([`joint_labels`]) to a box's
/// candidates `keyed` ((context, worst cell fit), mean cell fit), once each; a box
/// they give candidates is no longer refused.
fn add_joint_candidates(run: &Run, work: &mut BoxWork, keyed: &mut Vec<((Context, f64), f64)>, br: &mut BoxResult) {
    let Some((cells, lists)) = &work.joint else { return };
    let found = joint_labels(run.fit_sub, cells, lists, run.genus, JOINT_SWEEPS);
    let before = keyed.len();
    for (ctx, _) in found {
        work.joint_found.insert(ctx.labels);
        if !keyed.iter().any(|((c, _), _)| c.labels == ctx.labels) {
            let (worst, mean) = worst_and_mean(&fit_score_cells(run.fit_sub, &ctx, AxisRotation::IDENTITY, &polycube_samples(&ctx, FIT_SAMPLES), [1.0; 3]));
            keyed.push(((ctx, worst), mean));
        }
    }
    br.joint_candidates = keyed.len() - before;
    if keyed.len() > before {
        br.refused = None;
    }
}

/// The order in which the boxes with candidates are tried: the coarsest box whose
/// best fit (common unit) is not beaten by a finer one by `finer_box_factor` (the
/// same box in another frame only needs a better fit), then the rest by that fit. No box with a candidate is an error naming why the boxes
/// were refused, with suggested splitting ratios.
pub(super) fn box_order(run: &Run, boxes: &[BoxWork], report: &AutoReport) -> Result<Vec<usize>> {
    let common = |bi: usize| report.boxes[bi].best_fit_common.unwrap_or(f64::INFINITY);
    let mut order: Vec<usize> = Vec::new();
    for (bi, work) in boxes.iter().enumerate() {
        if !work.cands.is_empty() {
            match order.first() {
                None => order.push(bi),
                Some(&c) => {
                    let factor = if report.boxes[bi].dims == report.boxes[c].dims { 1.0 } else { run.aopts.finer_box_factor };
                    if common(bi) < factor * common(c) {
                        order.insert(0, bi);
                    } else {
                        order.push(bi);
                    }
                }
            }
        }
    }
    if order.len() > 1 {
        let first = order[0];
        order[1..].sort_by(|&a, &b| common(a).total_cmp(&common(b)));
        debug_assert_eq!(order[0], first);
    }
    if order.is_empty() {
        let mut why: Vec<String> = report.boxes.iter().filter_map(|b| b.refused.as_ref().map(|r| format!("{}: {r}", b.name()))).collect();
        why.truncate(6);
        let bb = &run.volume.bb;
        return Err(Error::VerificationFailed(format!(
            "automated mode found no context of genus {}: {}; no candidate was formed. To go on, give the context you expect (--labels L), constraints you know (--constraints FILE: counts of cubes, THCs and BHCs, allowed cells), or splitting ratios that put each hole in its own cell, e.g. --ratios {}",
            run.genus,
            why.join("; "),
            suggest_ratios(&run.volume.vol, bb.min, bb.max)
        )));
    }
    Ok(order)
}

/// The in-context fit of every feasible label of every subregion: the input's
/// samples against the box's assembly with that label in the subregion's cell and
/// a cube in every other occupied cell, the subregion's own cell's term of
/// [`fit_score_cells`]. (The sum over all cells is worse: the other cells' missing
/// holes give large penalties that vary with the label next to them and drown the
/// cell's own difference.) Unlike a fit of the subregion alone, whose cut faces are
/// far from every single-cell template and leave the labels tied (BHC directions
/// within 10 %), it sees the subregion where the global stage will: on the medium
/// synthetic cases the true label ranks first in every cell (BHC directions 0.004
/// against 0.01 and more; BENCHMARKS.md "Context search").
/// `scores[i][k]` belongs to `labels[i][k]`; null labels get NaN.
pub fn in_context_fits(samples: &[SurfaceSample], subs: &[Subregion], labels: &[Vec<Primitive>], register: bool) -> Vec<Vec<f64>> {
    use rayon::prelude::*;
    // cells that may be null (thin subregions) are null in the others' assemblies
    let mut base = [Primitive::Null; NUM_CELLS];
    for (sub, l) in subs.iter().zip(labels) {
        if !l.contains(&Primitive::Null) {
            base[sub.cell] = Primitive::Cube;
        }
    }
    let jobs: Vec<(usize, usize)> = labels.iter().enumerate().flat_map(|(i, l)| l.iter().enumerate().filter(|(_, p)| **p != Primitive::Null).map(move |(k, _)| (i, k))).collect();
    let vals: Vec<f64> = jobs
        .par_iter()
        .map(|&(i, k)| {
            let mut l = base;
            l[subs[i].cell] = labels[i][k];
            let ctx = Context::new(l);
            let target = polycube_samples(&ctx, FIT_SAMPLES);
            if !register {
                return fit_score_cells(samples, &ctx, AxisRotation::IDENTITY, &target, [1.0; 3])[subs[i].cell];
            }
            let cell = subs[i].cell;
            let Some((pts, cells)) = fit_points(samples, &ctx, AxisRotation::IDENTITY, [1.0; 3]) else { return f64::INFINITY };
            let p: Vec<[f64; 3]> = pts.iter().zip(&cells).filter(|(_, c)| **c == cell).map(|(x, _)| *x).collect();
            let q: Vec<[f64; 3]> = target.iter().filter(|t| t.1 == cell).map(|t| t.0).collect();
            registered_fit(&p, &q)
        })
        .collect();
    let mut out: Vec<Vec<f64>> = labels.iter().map(|l| vec![f64::NAN; l.len()]).collect();
    for (&(i, k), v) in jobs.iter().zip(vals) {
        out[i][k] = v;
    }
    out
}

/// Most sweeps of [`joint_labels`] over the cells.
pub const JOINT_SWEEPS: usize = 4;

/// Joint choice of the subregions' labels on the global fit: starting from each
/// subregion's best local label, each sweep visits the cells in turn and gives each
/// the feasible label that lowers the sum of the per-cell fits (a sum, not the worst
/// cell, so that a change in any cell counts), the others fixed; stops when a sweep
/// changes nothing or after `sweeps`. Returns every visited context that is a
/// valid assembly of the input's genus, with its (worst-cell) fit. Unlike the
/// product of the locally kept labels, it does not depend on the local ranking of
/// labels whose local fits are tied (a cell cut out of an assembly is far from every
/// single-cell template; BENCHMARKS.md "Context search").
pub fn joint_labels(samples: &[SurfaceSample], cells: &[usize], lists: &[Vec<Primitive>], input_genus: i64, sweeps: usize) -> Vec<(Context, f64)> {
    let mut labels = [Primitive::Null; NUM_CELLS];
    for (c, l) in cells.iter().zip(lists) {
        labels[*c] = l.first().copied().unwrap_or(Primitive::Null);
    }
    let mut seen: std::collections::HashMap<[Primitive; NUM_CELLS], f64> = std::collections::HashMap::new();
    let mut found: Vec<(Context, f64)> = Vec::new();
    let mut eval = |l: [Primitive; NUM_CELLS], found: &mut Vec<(Context, f64)>| -> f64 {
        if let Some(&v) = seen.get(&l) {
            return v;
        }
        let ctx = Context::new(l);
        let v = if ctx.occupied().next().is_none() {
            f64::INFINITY
        } else {
            let per = fit_score_cells(samples, &ctx, AxisRotation::IDENTITY, &polycube_samples(&ctx, FIT_SAMPLES), [1.0; 3]);
            let sum: f64 = per.iter().filter(|c| !c.is_nan()).sum();
            let validity = ctx.validity();
            if sum.is_finite() && validity.valid && validity.genus == Some(input_genus) {
                found.push((ctx, per.iter().filter(|c| !c.is_nan()).fold(0.0, |w: f64, c| w.max(*c))));
            }
            sum
        };
        seen.insert(l, v);
        v
    };
    let mut current = eval(labels, &mut found);
    for _ in 0..sweeps {
        let mut changed = false;
        for (c, list) in cells.iter().zip(lists) {
            for &p in list {
                if p == labels[*c] {
                    continue;
                }
                let mut l = labels;
                l[*c] = p;
                let v = eval(l, &mut found);
                if v < current {
                    (current, labels) = (v, l);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    found
}

/// Per-axis factors that turn a box's grid (cell) units into a length common to
/// every box: the part's extent along an axis over the box's cell count there,
/// divided by the edge of a cube holding 1/12 of the bounding box's volume. A bar
/// three times as long as it is thick measures the same in a 1-cell box (one
/// stretched cell) and in a 3-cell box (three cube cells).
pub fn box_scale(size: [f64; 3], dims: [usize; 3]) -> [f64; 3] {
    let s = size.map(|x| x.max(1e-12));
    let h = (s[0] * s[1] * s[2] / NUM_CELLS as f64).cbrt();
    std::array::from_fn(|a| s[a] / dims[a] as f64 / h)
}

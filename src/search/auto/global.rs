//! The boxes of the automated mode tried in order (step 4): a box none of whose
//! candidates the occupancy pre-check and the fit limit admit is passed over; a
//! box tried runs its local stage, then its best global candidates are diffused
//! in one batch and verified, until a box yields a verified polycube or
//! `max_boxes` were tried.

use super::super::generate::{diffuse_and_verify, lay_out, limit_fit, precheck_in, without_fit_limit, Candidate, PolycubeTimings, Stage};
use super::boxes::BoxWork;
use super::openings::Openings;
use super::{local, AutoReport, LocalResult, Run};
use crate::context::Context;
use crate::diffusion::Model;
use crate::error::{Progress, Result};
use crate::polycube::NUM_CELLS;

/// Try the boxes in `order` (at most `max_boxes`) until one yields a verified
/// polycube; the candidates of the boxes tried, or, when every box was passed
/// over, theirs (the main job can still mesh the best-fitting of them, see
/// pipeline::fallback_order).
pub(super) fn try_boxes(runs: &[Run], model: &Model, boxes: &mut [BoxWork], order: &[usize], report: &mut AutoReport, progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<Vec<Candidate>> {
    // the best fit of every box in the length common to all boxes
    // ([`super::rank::box_scale`]): a stretched single cell shrinks the part's
    // features and fits best in its own cell units
    let best_common = report.boxes.iter().filter_map(|b| b.best_fit_common).fold(f64::INFINITY, f64::min);
    let max_boxes = runs[0].aopts.max_boxes.max(1);
    let mut all_global: Vec<Candidate> = Vec::new();
    let mut attempt = 0usize;
    let mut passed_over: Vec<Candidate> = Vec::new();
    for &cb in order.iter() {
        if attempt >= max_boxes {
            break;
        }
        let run = &runs[boxes[cb].frame];
        // A box none of whose candidates the fit limit would admit (they all fit far
        // worse than another box's best) is passed over without using up an attempt
        // or running its local stage.
        let best_overall = in_box_units(best_common, &report.boxes[cb]);
        let (prechecked, probe) = probe(run, &boxes[cb].cands, best_overall)?;
        if !probe.iter().any(|c| c.stage == Stage::Pending) {
            passed_over.extend(probe);
            let br = &mut report.boxes[cb];
            if br.refused.is_none() {
                br.refused = Some(format!("no candidate passes the occupancy pre-check and the fit limit (best fit {:.4}, best of all boxes {best_overall:.4} in this box's cell units)", br.best_fit.unwrap_or(f64::INFINITY)));
            }
            continue;
        }
        let span = 0.35 + 0.6 * attempt as f64 / max_boxes as f64;
        attempt += 1;
        report.chosen_box = Some(report.boxes[cb].dims);
        report.chosen_frame = Some(report.boxes[cb].frame.clone());
        report.chosen_fitted = report.boxes[cb].fitted;
        // Local single-cell diffusion + verification for this box's kept labels (one batch).
        local::local_stage(run, model, &mut boxes[cb], &mut report.boxes[cb].locals, &mut |f: f64, s: &str| progress.report(span + 0.2 * f, s), timings)?;
        let mut sub_progress = |f: f64, s: &str| progress.report(span + 0.2 + 0.4 * f / max_boxes as f64, s);
        let openings = cell_openings(&report.boxes[cb].locals);
        let global = global_stage(run, model, &boxes[cb].cands, &prechecked, &openings, best_overall, &mut sub_progress, timings)?;
        let done = global.iter().any(|c| c.stage == Stage::Verified);
        all_global.extend(global);
        if done {
            break;
        }
    }
    Ok(if attempt == 0 { passed_over } else { all_global })
}

/// A fit in the common length (`best_fit_common`'s) in the cell units of the box
/// `b`, by the ratio of its best candidate's two fits; infinite (no limit from
/// the other boxes) when the box has no fit.
fn in_box_units(common: f64, b: &super::BoxResult) -> f64 {
    match (b.best_fit, b.best_fit_common) {
        (Some(f), Some(c)) if c > 0.0 && f.is_finite() && c.is_finite() => common * f / c,
        _ => f64::INFINITY,
    }
}

/// The occupancy pre-check of a box's first `max_global` candidates without the
/// fit limit (the verdicts, reused by the global stage for the contexts the local
/// filter keeps), and the same with the fit limit applied. Candidates are checked
/// against the aligned input in the box's frame.
fn probe(run: &Run, cands: &[(Context, f64)], best_overall: f64) -> Result<(Vec<Candidate>, Vec<Candidate>)> {
    let mut probe: Vec<Candidate> = Vec::new();
    for (ctx, _) in cands.iter().take(run.aopts.max_global.max(1)) {
        probe.extend(precheck_in(run.aligned, ctx, &[run.frame], &without_fit_limit(&run.global))?);
    }
    let prechecked = probe.clone();
    limit_fit(&mut probe, &run.global, best_overall);
    Ok((prechecked, probe))
}

/// The openings of each cell's subregion in a box.
fn cell_openings(locals: &[LocalResult]) -> [Option<Openings>; NUM_CELLS] {
    let mut o = [None; NUM_CELLS];
    for l in locals {
        o[l.subregion.cell] = Some(l.subregion.openings);
    }
    o
}

/// The cells of `ctx` whose label has a hole that its subregion's openings show
/// (`Candidate::holes_shown`).
fn holes_shown(ctx: &Context, openings: &[Option<Openings>; NUM_CELLS]) -> u16 {
    let mut m = 0u16;
    for n in ctx.occupied() {
        let l = ctx.labels[n];
        if l.hole().is_some() && openings[n].is_some_and(|o| o.carries(l)) {
            m |= 1 << n;
        }
    }
    m
}

/// The occupied cells of `ctx` whose label their subregion's openings do not
/// carry (`Candidate::openings_missed`).
fn openings_missed(ctx: &Context, openings: &[Option<Openings>; NUM_CELLS]) -> u8 {
    ctx.occupied().filter(|&n| openings[n].is_some_and(|o| !o.carries(ctx.labels[n]))).count() as u8
}

/// The global stage of one box: its first `max_global` candidates (their
/// pre-check verdicts from `prechecked` where known) within the fit limit, laid
/// out, diffused in one batch and verified, each with the cells whose holes its
/// subregions show.
#[allow(clippy::too_many_arguments)]
fn global_stage(run: &Run, model: &Model, cands: &[(Context, f64)], prechecked: &[Candidate], openings: &[Option<Openings>; NUM_CELLS], best_overall: f64, progress: &mut dyn Progress, timings: &mut PolycubeTimings) -> Result<Vec<Candidate>> {
    let mut global: Vec<Candidate> = Vec::new();
    let o = &run.global;
    for (ctx, _) in cands.iter().take(run.aopts.max_global.max(1)) {
        let known: Vec<Candidate> = prechecked.iter().filter(|c| c.context.labels == ctx.labels).cloned().collect();
        if known.is_empty() {
            global.extend(precheck_in(run.aligned, ctx, &[run.frame], &without_fit_limit(o))?);
        } else {
            global.extend(known);
        }
    }
    limit_fit(&mut global, o, best_overall);
    for c in global.iter_mut() {
        c.holes_shown = holes_shown(&c.context, openings);
        if run.aopts.opening_labels {
            c.openings_missed = openings_missed(&c.context, openings);
        }
    }
    lay_out(run.aligned, &mut global, o)?;
    diffuse_and_verify(model, &mut global, run.opts, progress, timings)?;
    Ok(global)
}

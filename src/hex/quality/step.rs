//! What the quality steps share: the report of a step, the guard of the steps
//! that move boundary nodes towards the input (undone unless the mesh comes
//! closer with its quality held), and the per-pass progress callback.

use super::measure::{summary, QualitySummary};
use crate::error::Progress;
use crate::hex::distance::hausdorff;
use crate::hex::goals::QualityGoals;
use crate::hex::stages::{Guarded, Stage, StageDetails, StageReport};
use crate::hex::surface::Surface;
use crate::hex::work::Work;
use crate::hex::{HexMesh, HexOptions};
use std::time::Instant;

/// The report of a quality step that started at `t0` from `before` and left `mesh`.
pub fn stage_report(stage: Stage, before: QualitySummary, mesh: &HexMesh, t0: Instant, details: StageDetails) -> StageReport {
    StageReport { stage, before, after: summary(mesh), nodes: mesh.nodes.len(), elements: mesh.elements.len(), seconds: t0.elapsed().as_secs_f64(), details }
}

/// A step that moves boundary nodes (capture, coverage, the boundary mean ascent),
/// undone unless `keep(before, after, h0, h1)` holds for the quality before and
/// after and the two-sided Hausdorff distances before and after; for the steps
/// towards the input [`fit_step_kept`]: closer to it without an inverted element or
/// a minimum below both the one before and the goal (with `hold_mean`, nor a mean
/// below both the one before and its goal: for a step after the optimisation,
/// whose mesh is the result). `step` gets
/// the floor no element may go below (min(before, goal + 0.05)) and says whether it
/// had anything to do (else no stage is reported: None), whether it moved a node, and its
/// details, which `wrap` makes the stage's.
pub fn guarded_fit_step<T>(
    work: &mut Work,
    sw: &Surface,
    opts: &HexOptions,
    stage: Stage,
    keep: impl FnOnce(&QualitySummary, &QualitySummary, f64, f64) -> bool,
    wrap: impl FnOnce(Guarded<T>) -> StageDetails,
    step: impl FnOnce(&mut Work, f64) -> (bool, bool, T),
) -> Option<StageReport> {
    let t0 = Instant::now();
    let before = summary(&work.mesh);
    let saved = (work.mesh.nodes.clone(), work.role.clone(), work.attach.clone());
    let floor = before.min.min(opts.goals.min_scaled_jacobian + 0.05).max(0.0);
    let (attempted, moved, details) = step(work, floor);
    if !attempted {
        return None;
    }
    let after = summary(&work.mesh);
    let h0 = hausdorff(&HexMesh { nodes: saved.0.clone(), elements: work.mesh.elements.clone() }, &sw.mesh, opts.hausdorff_samples).relative;
    let h1 = if moved { hausdorff(&work.mesh, &sw.mesh, opts.hausdorff_samples).relative } else { h0 };
    let kept = moved && keep(&before, &after, h0, h1);
    if !kept {
        (work.mesh.nodes, work.role, work.attach) = saved;
    }
    let details = Guarded { step: details, hausdorff_relative_before: h0, hausdorff_relative_after: h1, kept };
    Some(stage_report(stage, before, &work.mesh, t0, wrap(details)))
}

/// Whether a fit step that moved nodes is kept ([`guarded_fit_step`]): the distance
/// falls (`h1 < h0`), nothing is inverted, the minimum is at least the one before or
/// meets its goal, and with `hold_mean` so is the mean.
pub fn fit_step_kept(before: &QualitySummary, after: &QualitySummary, h0: f64, h1: f64, goals: &QualityGoals, hold_mean: bool) -> bool {
    h1 < h0
        && after.inverted == 0
        && (after.min >= before.min || after.min >= goals.min_scaled_jacobian)
        && (!hold_mean || after.mean >= before.mean || after.mean >= goals.mean_scaled_jacobian)
}

/// The per-pass callback of an optimisation loop: reports progress from `lo` over
/// `span` of the range and records a cancel in `cancelled` (true stops the loop).
pub fn pass_reporter<'a, P: Progress + ?Sized>(progress: &'a mut P, lo: f64, span: f64, passes: usize, cancelled: &'a mut bool) -> impl FnMut(usize) -> bool + 'a {
    move |p| {
        let ok = progress.report(lo + span * p as f64 / passes.max(1) as f64, "hex: optimisation");
        if !ok {
            *cancelled = true;
        }
        !ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fit_step_is_kept_only_when_closer_and_the_quality_holds() {
        let g = QualityGoals::default();
        let q = |min: f64, mean: f64, inverted: usize| QualitySummary { elements: 10, min, mean, max: 1.0, inverted };
        let before = q(0.5, 0.9, 0);
        // closer, quality as before: kept; not closer: undone
        assert!(fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, 0.01, &g, true));
        assert!(!fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, 0.02, &g, true));
        assert!(!fit_step_kept(&before, &q(0.5, 0.9, 0), 0.02, f64::NAN, &g, true));
        // an inverted element: undone
        assert!(!fit_step_kept(&before, &q(-0.1, 0.9, 1), 0.02, 0.01, &g, false));
        // the minimum may fall as long as it meets its goal (0.3)
        assert!(fit_step_kept(&before, &q(0.31, 0.9, 0), 0.02, 0.01, &g, false));
        assert!(!fit_step_kept(&before, &q(0.29, 0.9, 0), 0.02, 0.01, &g, false));
        assert!(fit_step_kept(&q(0.2, 0.9, 0), &q(0.25, 0.9, 0), 0.02, 0.01, &g, false));
        // the mean (goal 0.85) counts only for a step on the final mesh
        assert!(fit_step_kept(&before, &q(0.5, 0.84, 0), 0.02, 0.01, &g, false));
        assert!(!fit_step_kept(&before, &q(0.5, 0.84, 0), 0.02, 0.01, &g, true));
        assert!(fit_step_kept(&before, &q(0.5, 0.86, 0), 0.02, 0.01, &g, true));
        assert!(fit_step_kept(&q(0.5, 0.8, 0), &q(0.5, 0.81, 0), 0.02, 0.01, &g, true));
    }
}

//! Where the automated mode lost a part's true polycube: given the truth (the
//! context the part was made from), the run's candidates ([`PolycubeResult`])
//! and its [`AutoReport`], the first stage of the search at which the truth
//! dropped out. "The truth" is any placement congruent to the true solid
//! ([`congruent`]: up to translation and the 24 rotations); among the placements
//! of the true context on the grid ([`Context::rotations`]), the one that got
//! furthest counts.
//!
//! | stage | lost when | reasons |
//! |---|---|---|
//! | 1 occupancy / box | the truth's occupied box was refused (a subregion of genus >= 2) or never tried (another box was chosen, or it was passed over), a subregion's occupancy disagrees with the truth's (empty where the truth has a cell, or solid where it has none), or the pre-check refused the true candidate (occupancy, or the fit limit) | `box refused`, `subregion occupancy`, `box passed over`, `box not tried`, `occupancy pre-check`, `fit limit`, `no candidate` (the run found no box at all) |
//! | 2 label ranking | a subregion did not keep the true label (not feasible for the subregion's measured genus, or ranked below `local_keep`), or every true label was kept but the true product was not among the `max_global` best-fitting candidates of its box | `label not feasible`, `label not kept`, `global ranking cut`, `too many combinations` |
//! | 3 local verification | a true label failed the local single-cell diffusion + verification, which removed the true product | `local verification` |
//! | 4 global verification | the true candidate was diffused and failed GOCC or TCV | `GOCC`, `TCV` |
//! | 5 final choice | the true candidate verified, and another verified candidate was chosen | `ranked below` |

use super::auto::{AutoReport, BoxResult};
use super::generate::{Candidate, PolycubeOptions, PolycubeResult, Stage};
use crate::context::Context;
use crate::error::Error;
use crate::polycube::assembly::{congruent, occupied_cell_box};
use crate::polycube::Primitive;
use serde::Serialize;

/// The stage at which the truth dropped out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LossStage {
    /// (1) Occupancy / box detection.
    Occupancy,
    /// (2) Per-cell label ranking (and the global ranking cut).
    LabelRanking,
    /// (3) Local diffusion + verification of a subregion's label.
    LocalVerification,
    /// (4) Global diffusion: GOCC or TCV.
    GlobalVerification,
    /// (5) Verified, not chosen.
    FinalChoice,
}

impl LossStage {
    pub const ALL: [LossStage; 5] = [LossStage::Occupancy, LossStage::LabelRanking, LossStage::LocalVerification, LossStage::GlobalVerification, LossStage::FinalChoice];

    /// 1..5, the numbering.
    pub fn number(self) -> usize {
        LossStage::ALL.iter().position(|s| *s == self).expect("listed") + 1
    }

    pub fn name(self) -> &'static str {
        match self {
            LossStage::Occupancy => "occupancy / box",
            LossStage::LabelRanking => "label ranking",
            LossStage::LocalVerification => "local verification",
            LossStage::GlobalVerification => "global verification",
            LossStage::FinalChoice => "final choice",
        }
    }
}

impl std::fmt::Display for LossStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.number(), self.name())
    }
}

/// Where and why the truth was lost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Loss {
    pub stage: LossStage,
    /// A short key (see the module's table).
    pub reason: &'static str,
    /// What the records say, naming cells, labels and fits.
    pub detail: String,
}

/// The funnel's verdict on one part.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// The chosen polycube's solid is congruent to the truth's.
    pub recovered: bool,
    /// None when recovered.
    pub loss: Option<Loss>,
}

impl Verdict {
    fn lost(stage: LossStage, reason: &'static str, detail: String) -> Verdict {
        Verdict { recovered: false, loss: Some(Loss { stage, reason, detail }) }
    }

    pub fn stage(&self) -> Option<LossStage> {
        self.loss.as_ref().map(|l| l.stage)
    }
}

/// The verdict on a run that returned an error instead of a result (the automated
/// mode found no box with a candidate of the input's genus): lost at the box stage.
pub fn classify_error(err: &Error) -> Verdict {
    Verdict::lost(LossStage::Occupancy, "no candidate", err.to_string())
}

/// The verdict on one automated run: `result` and `report` as the run returned them,
/// `opts` the polycube options it ran with (the pre-check's occupancy limits).
pub fn classify(truth: &Context, result: &PolycubeResult, report: Option<&AutoReport>, opts: &PolycubeOptions) -> Verdict {
    let solid = truth.assemble();
    let same = |c: &Candidate| congruent(&c.context.assemble(), &solid);
    let chosen = result.chosen.map(|k| &result.candidates[k]);
    if chosen.is_some_and(same) {
        return Verdict { recovered: true, loss: None };
    }
    let chosen_name = chosen.map(|c| format!("{} (score {:.4})", c.context, c.score.unwrap_or(c.fit_mean))).unwrap_or_else(|| "nothing verified".into());
    let truths: Vec<&Candidate> = result.candidates.iter().filter(|c| same(c)).collect();
    // the true candidate's furthest stage among the run's candidates
    let rank = |s: Stage| match s {
        Stage::Pending => 0,
        Stage::Occupancy => 1,
        Stage::Gocc => 2,
        Stage::Tcv => 3,
        Stage::Verified => 4,
    };
    if let Some(t) = truths.iter().max_by_key(|c| rank(c.stage)) {
        let why = || t.report.as_ref().and_then(|r| r.reason.clone()).unwrap_or_default();
        match t.stage {
            Stage::Verified => {
                return Verdict::lost(LossStage::FinalChoice, "ranked below", format!("true {} verified (score {:.4}); chosen {chosen_name}", t.context, t.score.unwrap_or(t.fit_mean)));
            }
            Stage::Tcv => return Verdict::lost(LossStage::GlobalVerification, "TCV", format!("true {} passed GOCC, failed TCV: {}", t.context, why())),
            Stage::Gocc => return Verdict::lost(LossStage::GlobalVerification, "GOCC", format!("true {} failed GOCC: {}", t.context, why())),
            Stage::Occupancy | Stage::Pending => {
                let o = &t.occupancy;
                let occupancy_ok = o.in_empty_cells <= opts.max_in_empty_fraction && o.starved_cells.is_empty();
                if !occupancy_ok {
                    return Verdict::lost(
                        LossStage::Occupancy,
                        "occupancy pre-check",
                        format!("true {} refused by the occupancy pre-check: {:.3} of the surface in its empty cells, starved cells {:?}", t.context, o.in_empty_cells, o.starved_cells),
                    );
                }
                if let Some(r) = &t.refusal {
                    return Verdict::lost(LossStage::Occupancy, "occupancy pre-check", format!("true {} refused by the pre-check: {r}", t.context));
                }
                let best = result.candidates.iter().filter(|c| rank(c.stage) >= 2).map(|c| c.fit).fold(f64::INFINITY, f64::min);
                return Verdict::lost(LossStage::Occupancy, "fit limit", format!("true {} refused by the fit limit: worst-cell fit {:.4}, best diffused {best:.4}", t.context, t.fit));
            }
        }
    }
    let Some(report) = report else {
        return Verdict::lost(LossStage::Occupancy, "no candidate", "the truth is not among the candidates and there is no automated report".into());
    };
    // The truth never became a candidate: follow each of its placements through the
    // boxes' records and keep the one that got furthest.
    let mut best: Option<(u8, Verdict)> = None;
    for (_, p) in truth.rotations() {
        let v = follow(&p, result, report);
        if best.as_ref().is_none_or(|(k, _)| v.0 > *k) {
            best = Some(v);
        }
    }
    best.map(|(_, v)| v).unwrap_or_else(|| Verdict::lost(LossStage::Occupancy, "box refused", format!("{truth} has no placement on the grid")))
}

/// Names of a candidate's labels in `b`'s cells agree with the box's kept labels
/// (and it has nothing outside them), in the box's frame: the candidate may have
/// come from `b`.
fn from_box(c: &Candidate, b: &BoxResult) -> bool {
    let cells: Vec<usize> = b.locals.iter().map(|l| l.subregion.cell).collect();
    c.rotation == b.frame && (0..c.context.labels.len()).all(|n| match cells.iter().position(|&x| x == n) {
        None => c.context.labels[n] == Primitive::Null,
        Some(i) => b.locals[i].kept.iter().any(|k| k == c.context.labels[n].name()),
    })
}

/// How far one placement `p` (at the grid's first cell) got through the boxes'
/// records, as (progress, verdict); higher progress is later in the search.
fn follow(p: &Context, result: &PolycubeResult, report: &AutoReport) -> (u8, Verdict) {
    let Some((lo, hi)) = occupied_cell_box(&p.labels) else {
        return (0, Verdict::lost(LossStage::Occupancy, "box refused", "nothing occupied".into()));
    };
    let dims: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
    // the box of these dims in each frame it was analysed in; the furthest counts
    let mut best: Option<(u8, Verdict)> = None;
    for b in report.boxes.iter().filter(|b| b.dims == dims) {
        let v = follow_box(p, b, result, report);
        if best.as_ref().is_none_or(|(k, _)| v.0 > *k) {
            best = Some(v);
        }
    }
    best.unwrap_or_else(|| (0, Verdict::lost(LossStage::Occupancy, "box not tried", format!("box {}x{}x{} of {p} was not analysed", dims[0], dims[1], dims[2]))))
}

/// How far the placement `p` got through one box's record `b` ([`follow`]).
fn follow_box(p: &Context, b: &BoxResult, result: &PolycubeResult, report: &AutoReport) -> (u8, Verdict) {
    let dn = b.name();
    if b.locals.is_empty() {
        return (1, Verdict::lost(LossStage::Occupancy, "box refused", format!("box {dn} of {p}: {}", b.refused.clone().unwrap_or_default())));
    }
    let mut occupancy = Vec::new();
    let mut labels = Vec::new();
    let mut not_feasible = false;
    for l in &b.locals {
        let t = p.labels[l.subregion.cell];
        let s = &l.subregion;
        if t == Primitive::Null {
            if !l.kept.iter().any(|k| k == "null") {
                occupancy.push(format!("cell {} solid (fill {:.2}) where the truth has none", s.cell, s.fill));
            }
        } else if s.empty {
            occupancy.push(format!("cell {} empty (fill {:.2}) where the truth has {}", s.cell, s.fill, t.name()));
        } else if let Some(r) = l.fits.iter().position(|f| f.0 == t.name()) {
            if !l.kept.iter().any(|k| k == t.name()) {
                labels.push(format!("cell {}: {} ranked {} of {} (kept {})", s.cell, t.name(), r + 1, l.fits.len(), l.kept.join(" ")));
            }
        } else {
            not_feasible = true;
            labels.push(format!("cell {}: {} not feasible at measured genus {}", s.cell, t.name(), s.genus));
        }
    }
    if !occupancy.is_empty() {
        return (2, Verdict::lost(LossStage::Occupancy, "subregion occupancy", format!("box {dn} of {p}: {}", occupancy.join("; "))));
    }
    if !labels.is_empty() {
        let reason = if not_feasible { "label not feasible" } else { "label not kept" };
        return (3, Verdict::lost(LossStage::LabelRanking, reason, format!("box {dn} of {p}: {}", labels.join("; "))));
    }
    if b.candidates == 0 || b.refused.as_deref().is_some_and(|r| r.contains("combinations")) {
        return (4, Verdict::lost(LossStage::LabelRanking, "too many combinations", format!("box {dn} of {p}: {}", b.refused.clone().unwrap_or_default())));
    }
    let diffused = |c: &&Candidate| matches!(c.stage, Stage::Gocc | Stage::Tcv | Stage::Verified);
    let chosen_box = report.chosen();
    let tried = chosen_box.is_some_and(|x| std::ptr::eq(x, b)) || result.candidates.iter().filter(diffused).any(|c| from_box(c, b));
    if !tried {
        let chosen = chosen_box.map(|x| x.name()).unwrap_or_else(|| "none".into());
        return match &b.refused {
            Some(r) => (5, Verdict::lost(LossStage::Occupancy, "box passed over", format!("box {dn} of {p} passed over: {r}"))),
            None => (5, Verdict::lost(LossStage::Occupancy, "box not tried", format!("box {dn} of {p} not tried (best fit {:.4}); last box tried {chosen}", b.best_fit_common.unwrap_or(f64::NAN)))),
        };
    }
    // the local filter: a kept label that failed where another passed, and that is
    // not the subregion's best fit, removes the product
    let failed: Vec<String> = b
        .locals
        .iter()
        .filter_map(|l| {
            let t = p.labels[l.subregion.cell];
            let kept_anyway = t == Primitive::Null || l.verified.is_empty() || l.verified.iter().any(|v| v == t.name()) || l.fits.first().is_some_and(|f| f.0 == t.name());
            (!kept_anyway).then(|| format!("cell {}: {} failed (passed: {})", l.subregion.cell, t.name(), l.verified.join(" ")))
        })
        .collect();
    if !failed.is_empty() {
        return (6, Verdict::lost(LossStage::LocalVerification, "local verification", format!("box {dn} of {p}: {}", failed.join("; "))));
    }
    (7, Verdict::lost(LossStage::LabelRanking, "global ranking cut", format!("box {dn} of {p}: every true label kept; the product is not among the box's max_global best-fitting candidates (of {})", b.candidates)))
}

/// Counts of a set of verdicts: recovered, then lost per stage (1..5).
pub fn counts(verdicts: &[Verdict]) -> (usize, [usize; 5]) {
    let mut per = [0usize; 5];
    let mut rec = 0;
    for v in verdicts {
        match v.stage() {
            None => rec += usize::from(v.recovered),
            Some(s) => per[s.number() - 1] += 1,
        }
    }
    (rec, per)
}

#[cfg(test)]
mod tests;

//! The funnel on hand-made records of a run: each stage's loss named where the
//! records put it.

use super::*;
use crate::geometry::orient::align_axes;
use crate::polycube::orientation::rotations;
use crate::search::auto::volume::Subregion;
use crate::search::auto::{LocalResult, SplitRatios};
use crate::search::generate::{finish, PolycubeTimings, PreparedInput};
use crate::search::inference::Occupancy;

/// THC+Z in cell 0 and a cube in cell 3 (a 1 x 2 x 1 box); on the 2 x 1 x 1 box
/// its placements are THC+Z,cube and cube,THC+Z.
fn truth() -> Context {
    Context::parse("THC+Z,null,null,cube,null,null,null,null,null,null,null,null").unwrap()
}

fn ctx(s: &str) -> Context {
    let mut v: Vec<&str> = s.split(',').collect();
    v.resize(12, "null");
    Context::parse(&v.join(",")).unwrap()
}

fn cand(c: Context, stage: Stage) -> Candidate {
    Candidate {
        context: c,
        labels: c.label_values(),
        rotation: String::new(),
        axis_rotation: rotations()[0],
        occupancy: Occupancy { area_fraction: [0.0; 12], in_empty_cells: 0.0, starved_cells: Vec::new() },
        fit: 0.01,
        fit_mean: 0.01,
        stage,
        refusal: None,
        report: None,
        fidelity: None,
        score: Some(0.01),
        visible_retry: false,
        warp: None,
        warped: false,
        holes_shown: 0,
        openings_missed: 0,
        input: None,
        output: None,
    }
}

fn result(cands: Vec<Candidate>, chosen: Option<usize>) -> PolycubeResult {
    let m = crate::polycube::boundary(&truth().assemble()).to_trimesh();
    let (alignment, frame) = align_axes(&m).unwrap();
    let mut r = finish(PreparedInput { alignment, frame, samples: Vec::new(), area: 1.0 }, 0, "auto", cands, PolycubeTimings::default(), "test".into());
    r.chosen = chosen;
    r
}

fn local(cell: usize, empty: bool, fits: &[&str], kept: &[&str], verified: &[&str]) -> LocalResult {
    let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    LocalResult {
        subregion: Subregion { cell, lo: [0.0; 3], hi: [1.0; 3], fill: if empty { 0.0 } else { 0.8 }, components: 1, cavities: 0, genus: 0, empty, openings: Default::default() },
        fits: fits.iter().enumerate().map(|(i, s)| (s.to_string(), 0.01 * (i + 1) as f64)).collect(),
        kept: names(kept),
        verified: names(verified),
    }
}

/// A report with one 2 x 1 x 1 box of these two subregions (cells 0 and 1).
fn report(a: LocalResult, b: LocalResult, chosen: bool) -> AutoReport {
    AutoReport {
        resolution: 48,
        volume_tetrahedra: 0,
        volume: 1.0,
        surface_volume: 1.0,
        volume_relative_error: 0.0,
        boxes: vec![BoxResult { dims: [2, 1, 1], frame: "+x+y+z".into(), ratios: SplitRatios::equal(2, 1, 1), fitted: false, locals: vec![a, b], candidates: 6, best_fit: Some(0.01), best_fit_common: Some(0.01), joint_candidates: 0, refused: None }],
        no_candidate: None,
        chosen_box: chosen.then_some([2, 1, 1]),
        chosen_frame: chosen.then(|| "+x+y+z".into()),
        chosen_fitted: false,
    }
}

const ALL: &[&str] = &["cube", "THC+Z", "THC+X", "THC+Y", "BHC+Z", "BHC-Z", "BHC+X", "BHC-X", "BHC+Y", "BHC-Y"];

fn verdict(r: &PolycubeResult, rep: &AutoReport) -> Verdict {
    classify(&truth(), r, Some(rep), &PolycubeOptions::default())
}

fn well_ranked(chosen: bool) -> AutoReport {
    report(local(0, false, ALL, &["cube", "THC+Z"], &[]), local(1, false, ALL, &["cube", "THC+Z"], &[]), chosen)
}

#[test]
fn a_chosen_placement_of_the_truth_is_recovered() {
    // the truth turned onto the X axis, as the aligned frame sees it
    let r = result(vec![cand(ctx("cube,THC+Z"), Stage::Verified)], Some(0));
    let v = verdict(&r, &well_ranked(true));
    assert!(v.recovered && v.loss.is_none(), "{v:?}");
}

#[test]
fn a_verified_truth_not_chosen_is_lost_at_the_final_choice() {
    let r = result(vec![cand(ctx("cube,BHC+Z"), Stage::Verified), cand(ctx("THC+Z,cube"), Stage::Verified)], Some(0));
    let v = verdict(&r, &well_ranked(true));
    assert_eq!(v.stage(), Some(LossStage::FinalChoice), "{v:?}");
    assert_eq!(v.loss.unwrap().reason, "ranked below");
}

#[test]
fn a_diffused_truth_that_failed_is_lost_at_global_verification() {
    let r = result(vec![cand(ctx("cube,BHC+Z"), Stage::Verified), cand(ctx("THC+Z,cube"), Stage::Tcv)], Some(0));
    let v = verdict(&r, &well_ranked(true));
    assert_eq!(v.stage(), Some(LossStage::GlobalVerification));
    assert_eq!(v.loss.unwrap().reason, "TCV");
    let r = result(vec![cand(ctx("THC+Z,cube"), Stage::Gocc)], None);
    assert_eq!(verdict(&r, &well_ranked(true)).loss.unwrap().reason, "GOCC");
}

#[test]
fn a_truth_refused_before_diffusion_is_lost_at_the_box_stage() {
    let mut t = cand(ctx("THC+Z,cube"), Stage::Occupancy);
    t.occupancy.in_empty_cells = 0.2;
    let v = verdict(&result(vec![t.clone()], None), &well_ranked(true));
    assert_eq!((v.stage(), v.loss.unwrap().reason), (Some(LossStage::Occupancy), "occupancy pre-check"));
    // occupancy passed: the fit limit refused it
    t.occupancy.in_empty_cells = 0.0;
    t.fit = 0.4;
    let v = verdict(&result(vec![t, cand(ctx("cube,BHC+Z"), Stage::Gocc)], None), &well_ranked(true));
    assert_eq!((v.stage(), v.loss.unwrap().reason), (Some(LossStage::Occupancy), "fit limit"));
}

#[test]
fn a_truth_never_a_candidate_is_followed_through_the_boxes() {
    let other = || vec![cand(ctx("cube,BHC+Z"), Stage::Verified)];
    // a subregion empty where the truth has a cell: occupancy
    let rep = report(local(0, false, ALL, &["cube", "THC+Z"], &[]), local(1, true, &[], &["null"], &[]), true);
    let v = verdict(&result(other(), Some(0)), &rep);
    assert_eq!((v.stage(), v.loss.unwrap().reason), (Some(LossStage::Occupancy), "subregion occupancy"));
    // THC+Z ranked below the kept labels in both cells: label ranking
    let rep = report(local(0, false, ALL, &["cube", "BHC+Z"], &[]), local(1, false, ALL, &["cube", "BHC-Z"], &[]), true);
    let v = verdict(&result(other(), Some(0)), &rep);
    let l = v.loss.unwrap();
    assert_eq!((l.stage, l.reason), (LossStage::LabelRanking, "label not kept"), "{}", l.detail);
    assert!(l.detail.contains("ranked") && l.detail.contains("(kept cube BHC"), "{}", l.detail);
    // kept, but failed locally where another label passed (and not the best fit)
    let rep = report(local(0, false, ALL, &["cube", "THC+Z"], &["cube"]), local(1, false, ALL, &["cube", "THC+Z"], &["cube"]), true);
    let v = verdict(&result(other(), Some(0)), &rep);
    assert_eq!(v.stage(), Some(LossStage::LocalVerification), "{v:?}");
    // every label kept and passed, the box tried: the global ranking cut
    let rep = report(local(0, false, ALL, &["cube", "THC+Z"], &["cube", "THC+Z"]), local(1, false, ALL, &["cube", "THC+Z"], &["cube"]), true);
    let v = verdict(&result(other(), Some(0)), &rep);
    assert_eq!((v.stage(), v.loss.unwrap().reason), (Some(LossStage::LabelRanking), "global ranking cut"));
    // the same box never tried (another box chosen, none of its candidates diffused)
    let mut rep = well_ranked(false);
    rep.chosen_box = Some([1, 1, 1]);
    let v = verdict(&result(vec![cand(ctx("cube"), Stage::Verified)], Some(0)), &rep);
    assert_eq!((v.stage(), v.loss.unwrap().reason), (Some(LossStage::Occupancy), "box not tried"));
    // a run that found no box at all
    let e = crate::error::Error::VerificationFailed("automated mode found no context of genus 1".into());
    assert_eq!(classify_error(&e).stage(), Some(LossStage::Occupancy));
}

#[test]
fn counts_are_per_stage() {
    let r = result(vec![cand(ctx("cube,THC+Z"), Stage::Verified)], Some(0));
    let rec = verdict(&r, &well_ranked(true));
    let lost = classify_error(&crate::error::Error::VerificationFailed("x".into()));
    let fin = verdict(&result(vec![cand(ctx("cube,BHC+Z"), Stage::Verified), cand(ctx("THC+Z,cube"), Stage::Verified)], Some(0)), &well_ranked(true));
    assert_eq!(counts(&[rec, lost.clone(), lost, fin]), (1, [2, 0, 0, 0, 1]));
}

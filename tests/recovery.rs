//! The automated mode on the independent evaluation set (`search::evalset`), run
//! as `sddpm polycube MESH --auto` runs it, with the funnel's verdict
//! (`search::funnel`):
//! - one generated part per complexity group, each deformed by a family the
//!   automated mode was not tuned on (`REPORTED_FAMILIES`), drawn from seed
//!   4700 (not the reported seed 9100) and recovered: the chosen polycube's
//!   solid is congruent to the truth's;
//! - the funnel's counts on a run whose loss stage is known beforehand: the
//!   automated mode held to one cell-box (`--ratios 1:1:1`) cannot analyse a
//!   two-cell part's box, so the truth is lost at the box stage;
//! - a bent part recovered because the candidates are fitted and laid out after
//!   the quadratic registration (`PolycubeOptions::warp_fit`), and lost
//!   without it;
//! - a part whose row of three cells is across its longest side, recovered in
//!   the frame with the grid's X along the input's Y (`AutoOptions::axis_frames`).

use sddpm::context::Context;
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::pipeline::{generate_polycube, ContextRequest};
use sddpm::search::auto::{AutoOptions, SplitRatios};
use sddpm::search::evalset::{case_seed, Deformation, EvalCase, Params, COMPLEXITY_GROUPS, REPORTED_FAMILIES};
use sddpm::search::funnel::{classify, classify_error, counts, LossStage, Verdict};
use sddpm::search::generate::PolycubeOptions;

/// The seed the test cases are drawn from (the reported measurement uses 9100).
const TEST_SEED: u64 = 4700;

/// The funnel's verdict on the automated run of `request` over `case`'s mesh,
/// with the command line's defaults.
fn verdict(case: &EvalCase, request: &ContextRequest) -> Verdict {
    verdict_with(case, request, &PolycubeOptions::default(), &AutoOptions::default())
}

/// [`verdict`] with the given options.
fn verdict_with(case: &EvalCase, request: &ContextRequest, opts: &PolycubeOptions, aopts: &AutoOptions) -> Verdict {
    let model = Model::default_model().expect("the embedded model");
    let genus = case.mesh.check().genus.expect("the mesh's genus");
    assert_eq!(genus, case.genus);
    match generate_polycube(&model, &case.mesh, genus, request, opts, aopts, &mut NoProgress) {
        Ok((pr, rep, _)) => classify(&case.context, &pr, rep.as_ref(), opts),
        Err(e) => classify_error(&e),
    }
}

/// Case `k` of group `gi` of [`TEST_SEED`], deformed by `family` (a reported one),
/// is recovered by the automated mode.
fn recovered(gi: usize, k: usize, family: Deformation) {
    assert!(REPORTED_FAMILIES.contains(&family), "{family} is a tuning family");
    let case = EvalCase::generate(case_seed(TEST_SEED, gi, k), COMPLEXITY_GROUPS[gi], family).expect("the case");
    let v = verdict(&case, &ContextRequest::Auto);
    assert!(v.recovered, "{} case {k} ({family}, seed {}): {} ({} cells, genus {}) not recovered: {:?}", case.group, case.seed, case.context, case.cells, case.genus, v.loss);
    assert_eq!(counts(&[v]), (1, [0; 5]));
}

/// Seed 4700, simple case 0: a cube beside a blind hole (2 cells, genus 0), twisted.
#[test]
fn a_simple_twisted_part_is_recovered() {
    recovered(0, 0, Deformation::Twist);
}

/// Seed 4700, medium case 4: a through hole and three blind holes (4 cells, genus 0),
/// remeshed with irregular triangles.
#[test]
fn a_medium_remeshed_part_is_recovered() {
    recovered(1, 4, Deformation::Remesh);
}

/// Seed 4700, complex case 3: seven cells of genus 1, edges rounded.
#[test]
fn a_complex_rounded_part_is_recovered() {
    recovered(2, 3, Deformation::Rounding);
}

#[test]
fn the_funnel_counts_a_truth_whose_box_was_never_analysed_at_the_box_stage() {
    // a through hole beside a cube: its box is 2 x 1 x 1 in every placement
    let truth = Context::parse("THC+Z,cube,null,null,null,null,null,null,null,null,null,null").unwrap();
    let case = EvalCase::of_context(TEST_SEED, "simple", &truth, Deformation::Rotation).expect("the case");
    // one cell only: the only box the automated mode analyses is 1 x 1 x 1
    let v = verdict(&case, &ContextRequest::Ratios(SplitRatios::parse("1:1:1").unwrap()));
    let loss = v.loss.clone().expect("lost");
    assert!(!v.recovered);
    assert_eq!(loss.stage, LossStage::Occupancy, "{loss:?}");
    assert!(matches!(loss.reason, "box not tried" | "no candidate"), "{loss:?}");
    assert_eq!(counts(&[v.clone(), v]), (0, [2, 0, 0, 0, 0]));
}

/// Seed 9300 (the tuning seed), simple case 3: three blind holes (3 cells,
/// genus 0), bent. Fitted and laid out after the quadratic registration it is
/// recovered; with the box map alone its truth reaches diffusion and fails TCV.
#[test]
fn a_bent_part_is_recovered_after_the_registration_and_lost_without_it() {
    let case = EvalCase::generate(case_seed(9300, 0, 3), COMPLEXITY_GROUPS[0], Deformation::Bend).expect("the case");
    let v = verdict(&case, &ContextRequest::Auto);
    assert!(v.recovered, "{} not recovered with the registration: {:?}", case.context, v.loss);
    let rigid = PolycubeOptions { warp_fit: false, ..PolycubeOptions::default() };
    let v = verdict_with(&case, &ContextRequest::Auto, &rigid, &AutoOptions::default());
    assert!(!v.recovered, "{} recovered without the registration", case.context);
}

/// A row of three through holes beside a row of three cubes (3 x 2 x 1 cells,
/// genus 3), scaled 0.6 along the row and 1.5 across it: its longest side is
/// across the row, so the aligned frame's three-cell boxes cut the wrong side;
/// with the other frames the row is found along the input's Y.
#[test]
fn a_row_across_the_longest_side_is_found_in_another_frame() {
    let truth = Context::parse("THC+Z,THC+Z,THC+Z,cube,cube,cube,null,null,null,null,null,null").unwrap();
    let mut mesh = sddpm::polycube::boundary(&truth.assemble()).to_trimesh();
    for v in mesh.vertices.iter_mut() {
        *v = [0.6 * v[0], 1.5 * v[1], v[2]];
    }
    let case = EvalCase { seed: 0, group: "medium", family: Deformation::Aniso, context: truth, genus: 3, cells: 6, params: Params(Vec::new()), attempts: 1, mesh };
    let with = AutoOptions { axis_frames: true, ..AutoOptions::default() };
    let v = verdict_with(&case, &ContextRequest::Auto, &PolycubeOptions::default(), &with);
    assert!(v.recovered, "not recovered with the other frames: {:?}", v.loss);
    let without = AutoOptions { axis_frames: false, ..AutoOptions::default() };
    let v = verdict_with(&case, &ContextRequest::Auto, &PolycubeOptions::default(), &without);
    // (the aligned frame's 3 x 2 x 1 box cuts the long side into thirds: its
    // subregions show no row of holes)
    assert!(!v.recovered, "recovered in the aligned frame alone");
}

/// A real part, cinolib_3holes (a block with three holes through it in a row):
/// the automated mode verifies three through-hole cubes along the row. Each
/// cell's output lies at a near tie between its own template and the blind hole
/// on the same axis (a real hole's rim is not a template's); the cell's input
/// shows the hole through it, and a blind hole would change the part's genus,
/// so TCV does not count that template as a rival
/// (`VerifyOptions::same_genus_rivals`); with every template a rival, no
/// candidate verifies.
#[test]
fn a_real_part_whose_holes_tie_with_blind_holes_is_verified_by_its_openings() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/cinolib_3holes.obj");
    let mesh = sddpm::mesh::TriMesh::load(path, &sddpm::mesh::LoadOptions::default()).unwrap();
    let model = Model::default_model().expect("the embedded model");
    let truth = Context::parse("THC+Z,THC+Z,THC+Z,null,null,null,null,null,null,null,null,null").unwrap();
    let run = |opts: &PolycubeOptions| generate_polycube(&model, &mesh, 3, &ContextRequest::Auto, opts, &AutoOptions::default(), &mut NoProgress).expect("the automated mode").0;
    let pr = run(&PolycubeOptions::default());
    let chosen = pr.chosen.map(|k| pr.candidates[k].context).expect("a verified polycube");
    assert!(sddpm::polycube::assembly::congruent(&chosen.assemble(), &truth.assemble()), "chose {}", chosen.names());
    let mut all_rivals = PolycubeOptions::default();
    all_rivals.verify.same_genus_rivals = false;
    let pr = run(&all_rivals);
    assert_eq!(pr.chosen, None, "verified with every template a rival: {:?}", pr.chosen.map(|k| pr.candidates[k].context.names()));
}

/// mambo_B0, a block with a round channel across its top, is an arch of five
/// cells. Its single stretched cell fits better in that box's own cell units (a
/// blind-hole cube, 0.026 against the arch's 0.12), which used to put the arch's
/// box past the fit limit; compared in the length common to all boxes
/// (`rank::box_scale`) the arch fits about a hundred times better, and it is
/// the verified choice.
#[test]
fn a_block_with_a_channel_is_an_arch_when_boxes_are_compared_in_one_length() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/mambo_B0.obj");
    let mesh = sddpm::mesh::TriMesh::load(path, &sddpm::mesh::LoadOptions::default()).unwrap();
    let model = Model::default_model().expect("the embedded model");
    let (pr, report, _) = generate_polycube(&model, &mesh, 0, &ContextRequest::Auto, &PolycubeOptions::default(), &AutoOptions::default(), &mut NoProgress).expect("the automated mode");
    let chosen = pr.chosen.map(|k| pr.candidates[k].context).expect("a verified polycube");
    let arch = Context::parse("cube,cube,cube,cube,null,cube,null,null,null,null,null,null").unwrap();
    assert!(sddpm::polycube::assembly::congruent(&chosen.assemble(), &arch.assemble()), "chose {}", chosen.names());
    let report = report.expect("the automated mode's report");
    let one = report.boxes.iter().find(|b| b.dims == [1, 1, 1]).expect("the one-cell box");
    let tried = report.chosen().expect("the box tried");
    // in their own cell units the single cell fits better, in the common length far worse
    assert!(one.best_fit.unwrap() < tried.best_fit.unwrap(), "{:?} {:?}", one.best_fit, tried.best_fit);
    assert!(one.best_fit_common.unwrap() > 10.0 * tried.best_fit_common.unwrap(), "{:?} {:?}", one.best_fit_common, tried.best_fit_common);
}

use super::boxes::{feasible, trim_to_budget, MAX_COMBINATIONS};
use super::rank::{box_scale, in_context_fits, joint_labels, JOINT_SWEEPS};
use super::volume::{temporary_volume, MAX_RESOLUTION, VOLUME_TOLERANCE};
use super::*;
use crate::context::Context;
use crate::geometry::voxel::voxelize;
use crate::polycube::{Family, Primitive, NUM_CELLS};
use crate::search::generate::{fit_score, fit_score_scaled, polycube_samples};

/// A closed box [0, a] x [0, b] x [0, c], 12 outward triangles.
fn box_mesh(a: f64, b: f64, c: f64) -> TriMesh {
    let vertices = (0..8).map(|i| [if i & 1 == 1 { a } else { 0.0 }, if i & 2 == 2 { b } else { 0.0 }, if i & 4 == 4 { c } else { 0.0 }]).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let triangles = quads.iter().flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    TriMesh { vertices, triangles }
}

#[test]
fn a_thin_part_gets_a_finer_temporary_volume() {
    // a 12 x 1 x 0.15 plate: at 48 voxels along 12 (h = 0.25) its thickness holds
    // no voxel centre; doubling reaches a volume within the tolerance
    let m = box_mesh(12.0, 1.0, 0.15);
    let exact = 12.0 * 0.15;
    assert!(m.check().volume.abs() > 0.99 * exact);
    let coarse = voxelize(&m, 48).unwrap();
    assert!((coarse.volume() - exact).abs() > VOLUME_TOLERANCE * exact, "coarse volume {}", coarse.volume());
    let (v, res) = temporary_volume(&m, 48, exact).unwrap();
    assert!(res > 48 && res <= MAX_RESOLUTION, "resolution {res}");
    assert!((v.volume() - exact).abs() <= VOLUME_TOLERANCE * exact, "volume {} at {res}", v.volume());
    // a cube is within the tolerance at once: no refinement
    let c = box_mesh(1.0, 1.0, 1.0);
    assert_eq!(temporary_volume(&c, 48, 1.0).unwrap().1, 48);
}

#[test]
fn a_part_thinner_than_a_voxel_is_refused_with_the_reason() {
    // 1 x 1 x 1e-4: thinner than a voxel even at MAX_RESOLUTION (1/384)
    let m = box_mesh(1.0, 1.0, 1e-4);
    let model = crate::diffusion::Model::default_model().unwrap();
    let e = generate_auto(&model, &m, 0, None, &PolycubeOptions::default(), &AutoOptions::default(), &mut crate::error::NoProgress).unwrap_err();
    assert_eq!(e.status(), crate::error::Status::VerificationFailed);
    let msg = e.to_string();
    assert!(msg.contains("thinner than a voxel") && msg.contains("--labels"), "{msg}");
}

#[test]
fn box_scale_measures_every_box_in_the_same_length() {
    // a 3 x 1 x 1 bar: one stretched cell and three cube cells both become
    // cells of the bar's thickness (12-cell volume cube edge = (3/12)^(1/3))
    let h = (3.0f64 / 12.0).cbrt();
    let one = box_scale([3.0, 1.0, 1.0], [1, 1, 1]);
    let three = box_scale([3.0, 1.0, 1.0], [3, 1, 1]);
    for a in 0..3 {
        assert!((three[a] - 1.0 / h).abs() < 1e-12, "{three:?}");
    }
    assert!((one[0] - 3.0 / h).abs() < 1e-12 && (one[1] - 1.0 / h).abs() < 1e-12, "{one:?}");
}

/// The fit samples of a context's exact surface, in the working frame.
fn exact_samples(ctx: &Context) -> Vec<SurfaceSample> {
    let mesh = crate::polycube::boundary(&ctx.assemble()).to_trimesh();
    let input = prepare_input(&mesh, &PolycubeOptions::default()).unwrap();
    input.samples[..input.samples.len().min(FIT_SAMPLES)].to_vec()
}

#[test]
fn a_three_cell_bar_fits_its_own_box_better_than_one_stretched_cell() {
    // BHC+Y, THC+Z, BHC+Y in a row: in cell units of each box, the single
    // stretched THC shrinks the blind holes below the fit's penalty threshold
    // and the comparison favoured it; in the common unit the true box wins
    let truth = Context::parse("BHC+Y,THC+Z,BHC+Y,0,0,0,0,0,0,0,0,0").unwrap();
    let samples = exact_samples(&truth);
    let fit_sub = &samples[..];
    let best = |ctx: &Context, dims: [usize; 3]| {
        crate::polycube::orientation::rotations()
            .iter()
            .map(|r| {
                let pts: Vec<[f64; 3]> = fit_sub.iter().map(|s| r.apply(s.point)).collect();
                let size = crate::geometry::Aabb::of_points(&pts).size();
                fit_score_scaled(fit_sub, ctx, *r, &polycube_samples(ctx, FIT_SAMPLES), box_scale(size, dims))
            })
            .fold(f64::INFINITY, f64::min)
    };
    let own = best(&truth, [3, 1, 1]);
    let stretched = ["THC+X", "THC+Y", "THC+Z"]
        .iter()
        .map(|l| best(&Context::parse(&format!("{l},0,0,0,0,0,0,0,0,0,0,0")).unwrap(), [1, 1, 1]))
        .fold(f64::INFINITY, f64::min);
    assert!(own < AutoOptions::default().finer_box_factor * stretched, "own box {own}, one stretched cell {stretched}");
}

#[test]
fn joint_labels_find_the_assembly_whatever_the_local_ranking() {
    // a 3 x 1 x 1 bar with a blind hole at each end and a through hole in the
    // middle; every cell's labels are listed worst first, as tied local fits can
    // order them, and the joint search still finds the assembly
    let truth = Context::parse("BHC-X,THC+Z,BHC+X,0,0,0,0,0,0,0,0,0").unwrap();
    let fit_sub = &exact_samples(&truth)[..];
    // put the samples in the grid's orientation (the working frame may permute axes)
    let tgt = polycube_samples(&truth, FIT_SAMPLES);
    let r = *crate::polycube::orientation::rotations().iter().min_by(|a, b| fit_score(fit_sub, &truth, **a, &tgt).total_cmp(&fit_score(fit_sub, &truth, **b, &tgt))).unwrap();
    let samples: Vec<SurfaceSample> = fit_sub.iter().map(|s| SurfaceSample { point: r.apply(s.point), ..*s }).collect();
    let solid: Vec<Primitive> = Primitive::solids().filter(|p| p.family() != Family::Thc).collect();
    let through: Vec<Primitive> = Primitive::solids().filter(|p| p.family() == Family::Thc).collect();
    let worst_first = |ps: &[Primitive], truth: Primitive| -> Vec<Primitive> {
        let mut v: Vec<Primitive> = ps.iter().copied().filter(|p| *p != truth).collect();
        v.push(truth);
        v
    };
    let lists = vec![worst_first(&solid, truth.labels[0]), worst_first(&through, truth.labels[1]), worst_first(&solid, truth.labels[2])];
    let found = joint_labels(&samples, &[0, 1, 2], &lists, 1, JOINT_SWEEPS);
    let best = found.iter().min_by(|a, b| a.1.total_cmp(&b.1)).expect("a genus-1 assembly");
    assert!(crate::polycube::assembly::congruent(&best.0.assemble(), &truth.assemble()), "best {} ({:.4}) of {}", best.0, best.1, found.len());
    assert!(best.1 < 0.01, "fit {}", best.1);
    // the product of the best 3 local labels per cell would not contain it
    assert!(lists.iter().any(|l| !l[..3].contains(l.last().unwrap())));
}

fn subregion(cell: usize, fill: f64, genus: i64) -> Subregion {
    Subregion { cell, lo: [0.0; 3], hi: [1.0; 3], fill, components: 1, cavities: 0, genus, empty: fill < AutoOptions::default().min_fill, openings: Default::default() }
}

#[test]
fn in_context_fits_rank_every_true_blind_hole_first() {
    // four blind holes opening four different ways in a 2 x 2 x 1 block: the
    // direction of each is what the subregion-alone fit could not tell apart
    let truth = Context::parse("BHC-X,BHC-Y,0,BHC+Z,BHC+X,0,0,0,0,0,0,0").unwrap();
    assert!(truth.validity().valid);
    let fit_sub = &exact_samples(&truth)[..];
    let tgt = polycube_samples(&truth, FIT_SAMPLES);
    let r = *crate::polycube::orientation::rotations().iter().min_by(|a, b| fit_score(fit_sub, &truth, **a, &tgt).total_cmp(&fit_score(fit_sub, &truth, **b, &tgt))).unwrap();
    let samples: Vec<SurfaceSample> = fit_sub.iter().map(|s| SurfaceSample { point: r.apply(s.point), ..*s }).collect();
    let subs: Vec<Subregion> = [0, 1, 3, 4].iter().map(|&c| subregion(c, 0.9, 0)).collect();
    let labels: Vec<Vec<Primitive>> = subs.iter().map(|s| feasible(s, 0.15).unwrap()).collect();
    // rigid, and after the cell registration (which must not turn one label into another)
    for register in [false, true] {
        let scores = in_context_fits(&samples, &subs, &labels, register);
        for (i, sub) in subs.iter().enumerate() {
            let best = (0..labels[i].len()).min_by(|&a, &b| scores[i][a].total_cmp(&scores[i][b])).unwrap();
            assert_eq!(labels[i][best], truth.labels[sub.cell], "register {register}, cell {}: {:?}", sub.cell, labels[i].iter().zip(&scores[i]).collect::<Vec<_>>());
        }
    }
}

#[test]
fn a_thin_subregion_may_be_null() {
    let o = AutoOptions::default();
    // thin: null is one of the labels, and a thin sliver of genus 2 is only null
    let thin = feasible(&subregion(5, 0.08, 0), o.null_fill).unwrap();
    assert!(thin.contains(&Primitive::Null) && thin.contains(&Primitive::Cube), "{thin:?}");
    assert_eq!(feasible(&subregion(5, 0.08, 2), o.null_fill).unwrap(), vec![Primitive::Null]);
    // filled: no null, and genus 2 refuses the box naming the cell
    let full = feasible(&subregion(5, 0.8, 1), o.null_fill).unwrap();
    assert!(!full.contains(&Primitive::Null) && full.len() == 3, "{full:?}");
    let e = feasible(&subregion(5, 0.8, 2), o.null_fill).unwrap_err();
    assert!(e.contains("cell 5") && e.contains("genus 2"), "{e}");
    // empty: null only
    assert_eq!(feasible(&subregion(5, 0.01, 1), o.null_fill).unwrap(), vec![Primitive::Null]);
}

#[test]
fn a_full_box_is_trimmed_to_the_budget_keeping_every_cells_best_label() {
    // twelve genus-0 cells with three kept labels each: 3^12 products
    let names = ["BHC+X", "BHC-Y", "cube"];
    let mut options: Vec<Vec<Primitive>> = Vec::new();
    let mut locals: Vec<LocalResult> = Vec::new();
    for c in 0..NUM_CELLS {
        // cell c's alternatives are (2 + c) and (3 + c) times worse than its best
        let fits: Vec<(String, f64)> = names.iter().enumerate().map(|(k, n)| (n.to_string(), if k == 0 { 0.01 } else { 0.01 * (k + 1 + c) as f64 })).collect();
        options.push(names.iter().map(|n| Primitive::parse(n).unwrap()).collect());
        locals.push(LocalResult { subregion: subregion(c, 0.9, 0), fits, kept: names.iter().map(|n| n.to_string()).collect(), verified: Vec::new() });
    }
    // one thin cell that may also be null
    options[0].push(Primitive::Null);
    locals[0].kept.push("null".into());
    trim_to_budget(&mut options, &mut locals, MAX_COMBINATIONS);
    let product: usize = options.iter().map(|o| o.len()).product();
    assert!(product <= MAX_COMBINATIONS && product > MAX_COMBINATIONS / 3, "{product}");
    for (o, l) in options.iter().zip(&locals) {
        assert_eq!(o[0], Primitive::BhcPx, "every cell keeps its best label");
        assert_eq!(o.len(), l.kept.len());
    }
    assert!(options[0].contains(&Primitive::Null));
    // the least plausible alternatives (the last cells') went first
    assert!(options[NUM_CELLS - 1].len() <= options[1].len(), "{:?}", options.iter().map(|o| o.len()).collect::<Vec<_>>());
}

/// A candidate of `names` (the first cells; null elsewhere) at `stage` with these fits.
fn refused_candidate(names: &str, stage: crate::search::generate::Stage, fit: f64, fit_mean: f64) -> crate::search::generate::Candidate {
    let mut v: Vec<&str> = names.split(',').collect();
    v.resize(NUM_CELLS, "null");
    let c = Context::parse(&v.join(",")).unwrap();
    crate::search::generate::Candidate {
        context: c,
        labels: c.label_values(),
        rotation: String::new(),
        axis_rotation: crate::polycube::orientation::rotations()[0],
        occupancy: crate::search::inference::Occupancy { area_fraction: [0.0; 12], in_empty_cells: 0.0, starved_cells: Vec::new() },
        fit,
        fit_mean,
        stage,
        refusal: None,
        report: None,
        fidelity: None,
        score: None,
        visible_retry: false,
        warp: None,
        warped: false,
        holes_shown: 0,
        openings_missed: 0,
        input: None,
        output: None,
    }
}

#[test]
fn a_refusal_names_the_nearest_candidates_and_what_the_user_could_give() {
    use crate::search::generate::{finish, Stage};
    let truth = Context::parse("THC+Z,cube,0,0,0,0,0,0,0,0,0,0").unwrap();
    let mesh = crate::polycube::boundary(&truth.assemble()).to_trimesh();
    let (alignment, frame) = crate::geometry::orient::align_axes(&mesh).unwrap();
    // nothing verified: a TCV failure, two GOCC failures (the better fit first) and
    // one refused before diffusion; the TCV failure is nearest though its fit is worst
    let cands = vec![
        refused_candidate("cube,cube", Stage::Occupancy, 0.001, 0.001),
        refused_candidate("BHC+Z,cube", Stage::Gocc, 0.03, 0.02),
        refused_candidate("THC+Z,cube", Stage::Tcv, 0.04, 0.03),
        refused_candidate("cube,BHC+X", Stage::Gocc, 0.02, 0.01),
    ];
    let r = finish(PreparedInput { alignment, frame, samples: Vec::new(), area: 1.0 }, 1, "auto", cands, PolycubeTimings::default(), "test".into());
    assert!(r.chosen.is_none());
    let near = nearest_candidates(&r, NEAREST_NAMED);
    assert_eq!(near.len(), 3, "{near:?}");
    assert!(near[0].starts_with("THC+Z,cube,null") && near[0].contains("fit 0.0400, mean 0.0300") && near[0].contains("failed TCV"), "{near:?}");
    assert!(near[1].starts_with("cube,BHC+X") && near[2].starts_with("BHC+Z,cube"), "{near:?}");
    // the one refused before diffusion with a clean occupancy: the fit limit
    let all = nearest_candidates(&r, 4);
    assert!(all[3].starts_with("cube,cube") && all[3].ends_with("refused before diffusion by the fit limit)"), "{all:?}");
    let local = |cell: usize, verified: &[&str]| LocalResult {
        subregion: subregion(cell, 0.9, if cell == 0 { 1 } else { 0 }),
        fits: vec![("THC+Z".into(), 0.01)],
        kept: vec!["THC+Z".into()],
        verified: verified.iter().map(|s| s.to_string()).collect(),
    };
    let bx = |refused: Option<&str>| BoxResult {
        dims: [2, 1, 1],
        frame: "+x+y+z".into(),
        ratios: SplitRatios::equal(2, 1, 1),
        fitted: false,
        locals: vec![local(0, &[]), local(1, &["cube"])],
        candidates: 4,
        best_fit: Some(0.02),
        best_fit_common: Some(0.02),
        joint_candidates: 0,
        refused: refused.map(str::to_string),
    };
    let report = |chosen: Option<[usize; 3]>, refused: Option<&str>| AutoReport {
        resolution: 48,
        volume_tetrahedra: 0,
        volume: 1.0,
        surface_volume: 1.0,
        volume_relative_error: 0.0,
        boxes: vec![bx(refused)],
        no_candidate: None,
        chosen_frame: chosen.map(|_| "+x+y+z".into()),
        chosen_box: chosen,
        chosen_fitted: false,
    };
    // the box was tried: its local failures, the nearest candidates, what to give
    let msg = auto_failure(&r, &report(Some([2, 1, 1]), None)).expect("a refusal").to_string();
    for want in ["local verification failed in cell 0", "nearest candidates: THC+Z,cube", "cube,BHC+X", "(fit 0.0400, mean 0.0300", "--labels", "--constraints", "--ratios"] {
        assert!(msg.contains(want), "'{want}' missing from: {msg}");
    }
    // every box passed over: the same names
    let msg = auto_failure(&r, &report(None, Some("no candidate passes the occupancy pre-check and the fit limit"))).expect("a refusal").to_string();
    for want in ["diffused no candidate", "2x1x1: no candidate passes", "nearest candidates: THC+Z,cube", "--labels", "--constraints", "--ratios"] {
        assert!(msg.contains(want), "'{want}' missing from: {msg}");
    }
}

#[test]
fn the_trim_takes_every_cells_lower_ranked_labels_before_its_best_three() {
    // eight genus-0 cells with five kept labels each: 5^8 products, over the
    // budget; 3^8 are within it, so every cell keeps its best three
    let names = ["BHC+X", "BHC-Y", "cube", "BHC+Z", "THC+X"];
    let mut options: Vec<Vec<Primitive>> = Vec::new();
    let mut locals: Vec<LocalResult> = Vec::new();
    for c in 0..8 {
        // cell 0's third label is far worse than its best (the ratio alone would drop it first)
        let fits: Vec<(String, f64)> = names.iter().enumerate().map(|(k, n)| (n.to_string(), 0.01 * (1.0 + k as f64 * if c == 0 { 20.0 } else { 1.0 }))).collect();
        options.push(names.iter().map(|n| Primitive::parse(n).unwrap()).collect());
        locals.push(LocalResult { subregion: subregion(c, 0.9, 0), fits, kept: names.iter().map(|n| n.to_string()).collect(), verified: Vec::new() });
    }
    trim_to_budget(&mut options, &mut locals, MAX_COMBINATIONS);
    let product: usize = options.iter().map(|o| o.len()).product();
    assert!(product <= MAX_COMBINATIONS, "{product}");
    for o in &options {
        assert!(o.len() >= 3 && o[..3].iter().map(|p| p.name()).eq(names[..3].iter().copied()), "{o:?}");
    }
}


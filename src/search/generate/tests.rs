use super::*;

fn cand(fit: f64, stage: Stage) -> Candidate {
    Candidate {
        context: Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap(),
        labels: [0; NUM_CELLS],
        rotation: String::new(),
        axis_rotation: rotations()[0],
        occupancy: Occupancy { area_fraction: [0.0; NUM_CELLS], in_empty_cells: 0.0, starved_cells: Vec::new() },
        fit,
        fit_mean: fit,
        stage,
        report: None,
        refusal: None,
        visible_retry: false,
        warp: None,
        warped: false,
        holes_shown: 0,
        openings_missed: 0,
        fidelity: None,
        score: None,
        input: None,
        output: None,
    }
}

#[test]
fn fit_limit_is_absolute_or_relative_to_the_best_candidate() {
    let stages = |c: &[Candidate]| c.iter().map(|c| c.stage).collect::<Vec<_>>();
    // a real part: nothing under max_fit; the best and those within 2x are diffused
    let mut c = vec![cand(0.083, Stage::Pending), cand(0.15, Stage::Pending), cand(0.17, Stage::Pending), cand(f64::INFINITY, Stage::Occupancy)];
    limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
    assert_eq!(stages(&c), [Stage::Pending, Stage::Pending, Stage::Occupancy, Stage::Occupancy]);
    // the relative rule off: max_fit alone refuses them all
    let mut c = vec![cand(0.083, Stage::Pending), cand(0.15, Stage::Pending)];
    limit_fit(&mut c, &PolycubeOptions { relative_fit: 0.0, ..Default::default() }, f64::INFINITY);
    assert_eq!(stages(&c), [Stage::Occupancy, Stage::Occupancy]);
    // a good fit: max_fit admits up to 0.05 even beyond 2x the best
    let mut c = vec![cand(0.004, Stage::Pending), cand(0.04, Stage::Pending), cand(0.06, Stage::Pending)];
    limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
    assert_eq!(stages(&c), [Stage::Pending, Stage::Pending, Stage::Occupancy]);
    // another box fits far better: these are judged against its best
    let mut c = vec![cand(1.05, Stage::Pending), cand(1.06, Stage::Pending)];
    limit_fit(&mut c, &PolycubeOptions::default(), 0.28);
    assert_eq!(stages(&c), [Stage::Occupancy, Stage::Occupancy]);
    // ... but never above the cap
    let mut c = vec![cand(0.45, Stage::Pending), cand(0.6, Stage::Pending), cand(0.67, Stage::Pending)];
    limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
    assert_eq!(stages(&c), [Stage::Pending, Stage::Occupancy, Stage::Occupancy]);
    // a NaN fit is never admitted
    let mut c = vec![cand(f64::NAN, Stage::Pending)];
    limit_fit(&mut c, &PolycubeOptions::default(), f64::INFINITY);
    assert_eq!(stages(&c), [Stage::Occupancy]);
}

#[test]
fn only_candidates_the_fit_limit_admits_are_laid_out() {
    // a through-hole cube input; contexts with the hole (fit) and without (refused)
    let truth = Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let mesh = crate::polycube::boundary(&truth.assemble()).to_trimesh();
    let opts = PolycubeOptions::default();
    let input = prepare_input(&mesh, &opts).unwrap();
    let mut cands = Vec::new();
    for c in ["THC+X,0,0,0,0,0,0,0,0,0,0,0", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "Cube,0,0,0,0,0,0,0,0,0,0,0", "Cube,Cube,0,0,0,0,0,0,0,0,0,0"] {
        cands.extend(precheck(&input, &Context::parse(c).unwrap(), &without_fit_limit(&opts)).unwrap());
    }
    // the pre-check lays out nothing
    assert!(cands.iter().all(|c| c.input.is_none()));
    limit_fit(&mut cands, &opts, f64::INFINITY);
    lay_out(&input, &mut cands, &opts).unwrap();
    let pending = cands.iter().filter(|c| c.stage == Stage::Pending).count();
    assert!(pending >= 1 && pending < cands.len(), "{:?}", cands.iter().map(|c| (c.context.to_string(), c.fit, c.stage)).collect::<Vec<_>>());
    for c in &cands {
        // laid out exactly when admitted, with the occupancy of all samples
        assert_eq!(c.input.is_some(), c.stage == Stage::Pending, "{} {:?}", c.context, c.stage);
        if let Some(i) = &c.input {
            assert_eq!(i.occupancy.area_fraction, c.occupancy.area_fraction);
        }
    }
}

#[test]
fn the_visible_retry_verifies_a_true_context_the_whole_prior_refuses() {
    // held-in case 26 of `eval-model --cases 96 --min 4 --max 12 --seed 7000`: with
    // the whole-primitive prior its BHC-X cell comes out nearer THC+X (BENCHMARKS.md
    // "TCV centring"); the visible prior's output passes ("The visible prior")
    // (the template estimate, the only generator with a prior)
    let (truth, mesh) = crate::search::synthetic::cases(7000, 27, 4, 12, &Default::default()).swap_remove(26);
    let model = Model::template();
    let g = truth.validity().genus.unwrap();
    let no_retry = PolycubeOptions { visible_retry: false, ..PolycubeOptions::template() };
    let plain = generate_from_contexts(&model, &mesh, g, &[truth], &no_retry, &mut crate::error::NoProgress).unwrap();
    assert_eq!(plain.candidates[0].stage, Stage::Tcv);
    assert!(plain.chosen.is_none() && !plain.candidates[0].visible_retry);
    // on in the template estimate's options
    let r = generate_from_contexts(&model, &mesh, g, &[truth], &PolycubeOptions::template(), &mut crate::error::NoProgress).unwrap();
    let c = &r.candidates[0];
    assert_eq!(c.stage, Stage::Verified);
    assert!(c.visible_retry && r.chosen.is_some());
    assert!(c.report.as_ref().unwrap().passed);
    // the ranking score is the mean cell fit, whichever run verified it
    assert_eq!(c.score, Some(c.fit_mean));
    assert_eq!(c.score, plain.candidates[0].score);
}

#[test]
fn worst_and_mean_skip_unoccupied_cells_and_keep_an_infinite_one() {
    let mut cells = [f64::NAN; NUM_CELLS];
    cells[0] = 0.01;
    cells[5] = 0.05;
    cells[7] = 0.03;
    let (w, m) = worst_and_mean(&cells);
    assert_eq!(w, 0.05);
    assert!((m - 0.03).abs() < 1e-15);
    cells[3] = f64::INFINITY;
    assert_eq!(worst_and_mean(&cells), (f64::INFINITY, f64::INFINITY));
    assert_eq!(worst_and_mean(&[f64::NAN; NUM_CELLS]), (0.0, 0.0));
}

#[test]
fn the_mean_cell_fit_separates_contexts_the_worst_cell_ties() {
    // held-in recovery cases (`cargo run --release --example recovery -- 24 5000`,
    // medium group seed 5001 case 10, complex group seed 5002 case 2), the truth and
    // a wrong context that both verified in the automated run, in its working frame:
    // they differ in one cell that fits better than the worst one, so the worst
    // cell ties them (to 1e-3) and the mean ranks the truth first
    for (seed, min, max, case, truth, wrong) in [
        (5001, 4, 6, 10, "BHC-Y,BHC-Z,THC+Z,0,cube,cube,BHC-X,0,0,0,0,0", "BHC-Y,BHC-Z,THC+Z,0,cube,cube,BHC-Y,0,0,0,0,0"),
        (5002, 7, 12, 2, "THC+Y,THC+Z,THC+Z,cube,0,BHC-Z,THC+Y,0,0,THC+X,0,cube", "THC+Y,THC+Z,THC+Z,cube,0,BHC-Z,THC+Y,0,0,THC+Y,0,cube"),
    ] {
        let (_, mesh) = crate::search::synthetic::cases(seed, case + 1, min, max, &Default::default()).swap_remove(case);
        let input = prepare_input(&mesh, &PolycubeOptions::default()).unwrap();
        let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
        let fits = |c: &str| {
            let c = Context::parse(c).unwrap();
            worst_and_mean(&fit_score_cells(fit_sub, &c, rotations()[0], &polycube_samples(&c, FIT_SAMPLES), [1.0; 3]))
        };
        let (t, w) = (fits(truth), fits(wrong));
        assert!((t.0 - w.0).abs() < 1e-3 * t.0, "{seed}/{case}: worst {} vs {}", t.0, w.0);
        assert!(t.1 < 0.97 * w.1, "{seed}/{case}: mean {} vs {}", t.1, w.1);
    }
}

#[test]
fn a_context_one_label_from_a_far_better_fit_is_refused_and_named() {
    // held-in synthetic cases (the generator's seed 7000, never trained on): the
    // true context is never refused; a wrong genus-consistent one that the
    // occupancy and fit tests pass is refused in most cases, with the cell and
    // both labels named
    let opts = PolycubeOptions::default();
    let (mut reached, mut refused) = (0, 0);
    for (i, (truth, mesh)) in crate::search::synthetic::cases(7000, 24, 1, 3, &Default::default()).into_iter().enumerate() {
        let input = prepare_input(&mesh, &opts).unwrap();
        let mut t = precheck(&input, &truth, &without_fit_limit(&opts)).unwrap();
        limit_fit(&mut t, &opts, f64::INFINITY);
        assert_eq!(t[0].stage, Stage::Pending, "case {i} {truth}");
        refuse_worse_than_neighbours(&input, &mut t, opts.neighbour_fit_ratio);
        assert_eq!(t[0].stage, Stage::Pending, "case {i} {truth}: {:?}", t[0].refusal);
        let Some(w) = crate::search::eval::wrong_context(&truth, i as u64) else { continue };
        let mut c = precheck(&input, &w, &without_fit_limit(&opts)).unwrap();
        limit_fit(&mut c, &opts, f64::INFINITY);
        if c[0].stage != Stage::Pending {
            continue;
        }
        reached += 1;
        refuse_worse_than_neighbours(&input, &mut c, opts.neighbour_fit_ratio);
        if let Some(why) = &c[0].refusal {
            refused += 1;
            assert_eq!(c[0].stage, Stage::Occupancy);
            // the cell named, with its given label (the best one-cell fix under the
            // wrong context's own orientation: usually, not always, the changed cell)
            let n: usize = why.strip_prefix("cell ").and_then(|r| r.split(' ').next()).and_then(|k| k.parse().ok()).expect(why);
            assert!(why.contains(&format!("than with the given {}", w.labels[n].name())), "case {i}: {why}");
        }
        // off: never refused
        let mut c = precheck(&input, &w, &without_fit_limit(&opts)).unwrap();
        limit_fit(&mut c, &opts, f64::INFINITY);
        refuse_worse_than_neighbours(&input, &mut c, 0.0);
        assert!(c[0].refusal.is_none());
    }
    assert!(reached >= 8 && 2 * refused > reached, "{refused} of {reached} refused");
}

#[test]
fn among_verified_candidates_the_openings_come_before_the_fit() {
    let truth = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    let mesh = crate::polycube::boundary(&truth.assemble()).to_trimesh();
    let (alignment, frame) = crate::geometry::orient::align_axes(&mesh).unwrap();
    let verified = |fit: f64, missed: u8| Candidate { score: Some(fit), openings_missed: missed, output: Some(Vec::new()), ..cand(fit, Stage::Verified) };
    let pick = |cands: Vec<Candidate>| finish(PreparedInput { alignment: alignment.clone(), frame, samples: Vec::new(), area: 1.0 }, 0, "auto", cands, PolycubeTimings::default(), "test".into()).chosen;
    // a blind hole the cell does not show, fitting better, against the cube it shows
    assert_eq!(pick(vec![verified(0.45, 1), verified(1.08, 0)]), Some(1));
    // the same count: the fit decides; a candidate not verified is never chosen
    assert_eq!(pick(vec![verified(0.45, 1), verified(1.08, 1), cand(0.01, Stage::Tcv)]), Some(0));
}

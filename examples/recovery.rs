//! The recovery study: synthetic deformed assemblies the model never saw
//! (seed 5000 by default, not the training seed 42), grouped as the paper's
//! scalability table (simple 1-3, medium 4-6, complex 7+ occupied cells), each
//! surface subdivided, smoothly warped, randomly rotated, scaled and moved.
//! For every case:
//! - automated mode (default options): does the chosen polycube have the true
//!   context's solid (same sub-voxel set up to a translation and one of the 24
//!   cube rotations, `polycube::assembly::congruent`)? Is the true solid among the
//!   verified candidates, or among all global candidates? How many candidates,
//!   how many verified, how long; and is the chosen polycube where the part is
//!   (two-sided Hausdorff distance between its surface in the user's frame and
//!   the input, in cell widths; a sub-voxel put on the wrong side, e.g. a hole
//!   along the wrong axis, moves the surface by 1/3 cell, so "placed" means below
//!   1/6 cell; the warp moves points by at most about 0.1 cell);
//! - user-guided mode with the true context: verified or not.
//!
//! Prints one line per case, a Markdown table per group and writes a CSV.
//!
//! `cargo run --release --example recovery -- [CASES_PER_GROUP] [SEED] [CSV] [GROUPS]`
//! (environment: RECOVERY_GENERATOR=template runs the baseline generator,
//! RECOVERY_WEIGHTS=FILE other learned weights, RECOVERY_TAU_CD overrides TCV's tau_CD, RECOVERY_VISIBLE_COVERAGE=0/1
//! sets VerifyOptions::visible_coverage, RECOVERY_VISIBLE_PRIOR=0/1
//! SamplerOptions::visible_prior, RECOVERY_START_STEP=t SamplerOptions::start_step,
//! RECOVERY_VISIBLE_RETRY=0/1 PolycubeOptions::visible_retry (default on), RECOVERY_JOINT=1 turns on
//! AutoOptions::joint_labels, RECOVERY_DIAG=1 prints where each true placement
//! stands in the automated search, RECOVERY_USER_ONLY=1 runs
//! only the user-guided mode, RECOVERY_DUMP=FILE appends every automated candidate's
//! per-cell fits and PCDs as JSON lines, RECOVERY_VERBOSE=1 prints boxes, candidates and the
//! user-guided verification per cell)
//! (defaults 8, 5000, build/recovery.csv, simple,medium,complex)
use sddpm::search::auto::AutoOptions;
use sddpm::search::generate::{PolycubeOptions, Stage};
use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::pipeline::{generate_polycube, ContextRequest};
use sddpm::polycube::assembly::congruent;
use sddpm::search::synthetic::{cases, SyntheticOptions, GROUPS};
use sddpm::geometry::bvh::SurfaceLocator;
use sddpm::mesh::TriMesh;
use sddpm::pipeline::polycube_user_mesh;
use std::fmt::Write as _;
use std::time::Instant;

#[derive(Default)]
struct Row {
    auto_verified: bool,
    auto_recovered: bool,
    /// Congruent and placed (Hausdorff below 1/6 cell).
    auto_placed: bool,
    hausdorff_cells: f64,
    true_among_verified: bool,
    true_among_candidates: bool,
    global_candidates: usize,
    kept: usize,
    verified: usize,
    auto_s: f64,
    user_verified: bool,
    /// Where the user-guided run with the true context stopped (the stage of its
    /// best candidate: Occupancy = refused by the pre-check, Gocc / Tcv = failed
    /// there, Verified).
    user_stage: String,
    user_s: f64,
}

/// Points on every triangle of `m` (a 4 x 4 barycentric lattice, corners included).
fn dense(m: &TriMesh) -> Vec<[f64; 3]> {
    let k = 4;
    let mut v = Vec::new();
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        for i in 0..=k {
            for j in 0..=k - i {
                let (u, w) = (i as f64 / k as f64, j as f64 / k as f64);
                v.push(std::array::from_fn(|d| a[d] + u * (b[d] - a[d]) + w * (c[d] - a[d])));
            }
        }
    }
    v
}

/// Two-sided Hausdorff distance between two surfaces (dense samples of each).
fn hausdorff(a: &TriMesh, b: &TriMesh) -> f64 {
    SurfaceLocator::new(b).max_distance(&dense(a)).max(SurfaceLocator::new(a).max_distance(&dense(b)))
}

/// The input's cell width: sqrt(input area / area of the true assembly in cell units).
fn cell_width(truth: &sddpm::context::Context, mesh: &TriMesh) -> f64 {
    let exact = sddpm::polycube::boundary(&truth.assemble()).area();
    (mesh.check().area / exact).sqrt()
}

/// RECOVERY_DIAG=1: where is the truth lost? Every placement of the true assembly
/// in the automated mode's working frame (the 24 rotations that fit the grid): its
/// fit against the best candidate's, its validity, the local rank of each true
/// label in the box of its dimensions, and whether the pre-check passes it.
fn diagnose(truth: &sddpm::context::Context, mesh: &TriMesh, popts: &PolycubeOptions, pr: &sddpm::search::generate::PolycubeResult, auto: Option<&sddpm::search::auto::AutoReport>) -> sddpm::Result<()> {
    use sddpm::search::generate::{fit_score, fit_score_cells, polycube_samples, precheck, prepare_input, without_fit_limit, OrientationSearch, FIT_SAMPLES};
    use sddpm::polycube::orientation::AxisRotation;
    let input = prepare_input(mesh, popts)?;
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let best = pr.candidates.iter().map(|c| c.fit).fold(f64::INFINITY, f64::min);
    println!("  diag: best candidate fit {best:.4}; boxes tried in order: {:?}", auto.map(|a| a.chosen_box));
    let mut o = without_fit_limit(popts);
    o.orientations = OrientationSearch::Identity;
    for (r, c) in truth.rotations() {
        let tgt = polycube_samples(&c, FIT_SAMPLES);
        let fit = fit_score(fit_sub, &c, AxisRotation::IDENTITY, &tgt);
        let cells = fit_score_cells(fit_sub, &c, AxisRotation::IDENTITY, &tgt, [1.0; 3]);
        let dims = sddpm::polycube::assembly::occupied_cell_box(&c.labels).map(|(lo, hi)| [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]).unwrap();
        let pc = precheck(&input, &c, &o)?;
        let occ = pc.first().map(|x| format!("{:?} in-empty {:.3} starved {:?}", x.stage, x.occupancy.in_empty_cells, x.occupancy.starved_cells)).unwrap_or_default();
        let mut ranks = Vec::new();
        if let Some(b) = auto.and_then(|a| a.boxes.iter().find(|b| b.dims == dims)) {
            for l in &b.locals {
                let lab = c.labels[l.subregion.cell].name();
                let rank = l.fits.iter().position(|f| f.0 == lab);
                ranks.push(format!("c{} {lab} g{} rank {:?}/{} kept {}", l.subregion.cell, l.subregion.genus, rank, l.fits.len(), l.kept.iter().any(|k| k == lab)));
            }
        }
        let worst: Vec<String> = cells.iter().enumerate().filter(|(_, v)| !v.is_nan()).map(|(i, v)| format!("{i}:{v:.4}")).collect();
        println!("  diag: truth {} as {c} box {dims:?}: fit {fit:.4} cells [{}] | precheck {occ} | {}", r.name(), worst.join(" "), ranks.join("; "));
    }
    Ok(())
}

/// RECOVERY_DUMP=FILE: appends one JSON line per automated candidate (group, case,
/// context, stage, score, whether it is the truth, its per-cell geometric fits and
/// per-cell target PCD and nearest-other-template PCD), for studying rankings offline.
fn dump_candidates(path: &std::path::Path, group: &str, case: usize, mesh: &TriMesh, popts: &PolycubeOptions, pr: &sddpm::search::generate::PolycubeResult, truth_solid: &sddpm::geometry::VoxelGrid) -> sddpm::Result<()> {
    use sddpm::search::generate::{fit_score_cells, polycube_samples, prepare_input, FIT_SAMPLES};
    use std::io::Write as _;
    let input = prepare_input(mesh, popts)?;
    let fit_sub = &input.samples[..input.samples.len().min(FIT_SAMPLES)];
    let io = |e: std::io::Error| sddpm::Error::io(path.display(), e);
    let mut f = std::fs::OpenOptions::new().create(true).append(true).open(path).map_err(io)?;
    for (k, c) in pr.candidates.iter().enumerate() {
        let cells = fit_score_cells(fit_sub, &c.context, c.axis_rotation, &polycube_samples(&c.context, FIT_SAMPLES), [1.0; 3]);
        let cell_fit: Vec<Option<f64>> = cells.iter().map(|v| (!v.is_nan()).then_some(*v)).collect();
        let (pcd_target, pcd_other): (Vec<f64>, Vec<f64>) = c
            .report
            .as_ref()
            .map(|r| {
                r.cells
                    .iter()
                    .map(|cr| {
                        // pcd[j] is the template of label j + 1 (labels 1..10)
                        let li = sddpm::polycube::Primitive::solids().position(|p| p.name() == cr.label);
                        let t = li.and_then(|i| cr.pcd.get(i)).copied().unwrap_or(f64::NAN);
                        let o = cr.pcd.iter().enumerate().filter(|(j, _)| Some(*j) != li).map(|(_, v)| *v).fold(f64::INFINITY, f64::min);
                        (t, o)
                    })
                    .unzip()
            })
            .unwrap_or_default();
        let line = serde_json::json!({
            "group": group, "case": case, "k": k, "context": c.context.names(), "rotation": c.rotation,
            "stage": format!("{:?}", c.stage), "fit": c.fit, "score": c.score, "fidelity": c.fidelity,
            "chosen": pr.chosen == Some(k), "truth": congruent(&c.context.assemble(), truth_solid),
            "cell_fit": cell_fit, "pcd_target": pcd_target, "pcd_other": pcd_other,
            "pcd_mean": c.report.as_ref().map(|r| r.mean_target_pcd),
        });
        writeln!(f, "{line}").map_err(io)?;
    }
    Ok(())
}

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map(|s| s.parse().expect("CASES_PER_GROUP")).unwrap_or(8);
    let seed: u64 = a.get(2).map(|s| s.parse().expect("SEED")).unwrap_or(5000);
    let csv_path = a.get(3).cloned().unwrap_or_else(|| "build/recovery.csv".into());
    let groups: Vec<String> = a.get(4).map(|s| s.split(',').map(str::to_string).collect()).unwrap_or_else(|| GROUPS.iter().map(|g| g.0.to_string()).collect());
    assert_ne!(seed, 42, "42 is the training seed");
    // RECOVERY_USER_ONLY=1: only the user-guided runs (seconds per case)
    let user_only = std::env::var_os("RECOVERY_USER_ONLY").is_some();
    // RECOVERY_GENERATOR=template: the closed-form template estimate with its options;
    // RECOVERY_WEIGHTS=FILE: learned weights other than the embedded ones
    let (model, mut popts) = match (std::env::var("RECOVERY_GENERATOR").as_deref(), std::env::var("RECOVERY_WEIGHTS")) {
        (Ok("template"), _) => (Model::template(), PolycubeOptions::template()),
        (_, Ok(w)) => (Model::from_file(std::path::Path::new(&w), sddpm::diffusion::Backend::Flex)?, PolycubeOptions::default()),
        _ => (Model::default_model()?, PolycubeOptions::default()),
    };
    // RECOVERY_TAU_CD=x: TCV's threshold (VerifyOptions::tau_cd) for this run
    if let Some(t) = std::env::var("RECOVERY_TAU_CD").ok().and_then(|s| s.parse().ok()) {
        popts.verify.tau_cd = t;
    }
    // RECOVERY_VISIBLE_COVERAGE=0/1: TCV's coverage off the shared faces (VerifyOptions::visible_coverage)
    if let Ok(v) = std::env::var("RECOVERY_VISIBLE_COVERAGE") {
        popts.verify.visible_coverage = v == "1";
    }
    // RECOVERY_VISIBLE_PRIOR=0/1: the template attention's prior off the shared faces (SamplerOptions::visible_prior)
    if let Ok(v) = std::env::var("RECOVERY_VISIBLE_PRIOR") {
        popts.sampler.visible_prior = v == "1";
    }
    // RECOVERY_VISIBLE_RETRY=0/1: PolycubeOptions::visible_retry (default: the library's)
    if let Ok(v) = std::env::var("RECOVERY_VISIBLE_RETRY") {
        popts.visible_retry = v != "0";
    }
    // RECOVERY_START_STEP=t: the sampler's start step (SamplerOptions::start_step)
    if let Some(t) = std::env::var("RECOVERY_START_STEP").ok().and_then(|s| s.parse().ok()) {
        popts.sampler.start_step = t;
    }
    // RECOVERY_STEPS=n: the sampler's strided steps (SamplerOptions::steps) for this run
    if let Some(n) = std::env::var("RECOVERY_STEPS").ok().and_then(|s| s.parse().ok()) {
        popts.sampler.steps = n;
    }
    let mut aopts = AutoOptions::default();
    // RECOVERY_JOINT=1: AutoOptions::joint_labels on
    aopts.joint_labels = std::env::var_os("RECOVERY_JOINT").is_some();
    // RECOVERY_MAX_GLOBAL=n, RECOVERY_MAX_BOXES=n: AutoOptions::max_global / max_boxes
    if let Some(n) = std::env::var("RECOVERY_MAX_GLOBAL").ok().and_then(|s| s.parse().ok()) {
        aopts.max_global = n;
    }
    if let Some(n) = std::env::var("RECOVERY_MAX_BOXES").ok().and_then(|s| s.parse().ok()) {
        aopts.max_boxes = n;
    }
    let mut csv = String::from("group,case,context,cells,genus,auto_verified,auto_recovered,auto_placed,hausdorff_cells,true_among_verified,true_among_candidates,global_candidates,kept,verified,auto_s,user_verified,user_stage,user_s,chosen\n");
    let mut summary = Vec::new();
    for (gi, &(name, lo, hi)) in GROUPS.iter().enumerate() {
        if !groups.iter().any(|g| g == name) {
            continue;
        }
        // a different seed per group, so that the groups are independent draws
        let cs = cases(seed + gi as u64, n, lo, hi, &SyntheticOptions::default());
        let mut rows = Vec::new();
        for (i, (truth, mesh)) in cs.iter().enumerate() {
            let genus = truth.validity().genus.expect("a valid context");
            let measured = mesh.validate()?.genus;
            assert_eq!(measured, Some(genus), "synthetic mesh genus");
            let truth_solid = truth.assemble();
            let mut r = Row::default();
            let t = Instant::now();
            let chosen;
            let auto = if user_only { Err(sddpm::Error::Cancelled("user-guided runs only".into())) } else { generate_polycube(&model, mesh, genus, &ContextRequest::Auto, &popts, &aopts, &mut NoProgress) };
            match auto {
                Ok((pr, auto, _err)) => {
                    r.auto_s = t.elapsed().as_secs_f64();
                    if std::env::var_os("RECOVERY_VERBOSE").is_some() {
                        for b in auto.iter().flat_map(|a| a.boxes.iter()) {
                            println!("  box {:?}: {} candidates, best fit {:?}, refused {:?}", b.dims, b.candidates, b.best_fit, b.refused);
                            for l in &b.locals {
                                println!("    cell {} genus {} fill {:.2}: fits {:?} kept {:?} verified {:?}", l.subregion.cell, l.subregion.genus, l.subregion.fill, l.fits, l.kept, l.verified);
                            }
                        }
                        for c in &pr.candidates {
                            let pcd = c.report.as_ref().map(|r| r.mean_target_pcd);
                            let truth_like = congruent(&c.context.assemble(), &truth_solid);
                            println!("  cand {} {} fit {:.4} {:?} score {:?} pcd {:?} fidelity {:?} retry {} truth {}", c.context, c.rotation, c.fit, c.stage, c.score, pcd, c.fidelity, c.visible_retry, truth_like);
                        }
                    }
                    if let Some(path) = std::env::var_os("RECOVERY_DUMP") {
                        dump_candidates(std::path::Path::new(&path), name, i, mesh, &popts, &pr, &truth_solid)?;
                    }
                    if std::env::var_os("RECOVERY_DIAG").is_some() {
                        diagnose(truth, mesh, &popts, &pr, auto.as_ref())?;
                    }
                    r.global_candidates = auto.as_ref().map(|a| a.boxes.iter().map(|b| b.candidates).sum()).unwrap_or(0);
                    r.kept = pr.candidates.len();
                    r.verified = pr.candidates.iter().filter(|c| c.stage == Stage::Verified).count();
                    let same = |c: &sddpm::search::generate::Candidate| congruent(&c.context.assemble(), &truth_solid);
                    r.true_among_candidates = pr.candidates.iter().any(same);
                    r.true_among_verified = pr.candidates.iter().any(|c| c.stage == Stage::Verified && same(c));
                    match pr.chosen {
                        Some(k) => {
                            r.auto_verified = true;
                            r.auto_recovered = same(&pr.candidates[k]);
                            r.hausdorff_cells = hausdorff(&polycube_user_mesh(&pr, &pr.candidates[k]), mesh) / cell_width(truth, mesh);
                            r.auto_placed = r.auto_recovered && r.hausdorff_cells < 1.0 / 6.0;
                            chosen = format!("{} {}", pr.candidates[k].context, pr.candidates[k].rotation);
                        }
                        None => chosen = "none verified".into(),
                    }
                }
                Err(e) => {
                    r.auto_s = t.elapsed().as_secs_f64();
                    chosen = format!("error: {e}");
                }
            }
            let t = Instant::now();
            match generate_polycube(&model, mesh, genus, &ContextRequest::Contexts(vec![truth.clone()]), &popts, &aopts, &mut NoProgress) {
                Ok((pr, _, _)) => {
                    r.user_verified = pr.chosen.is_some();
                    if std::env::var_os("RECOVERY_VERBOSE").is_some() {
                        for c in pr.candidates.iter().filter(|c| c.report.is_some()) {
                            let rep = c.report.as_ref().unwrap();
                            println!("  user-guided {} {}: {:?}", c.context, c.rotation, rep.reason);
                            for cr in rep.cells.iter().filter(|cr| !cr.pcd.is_empty()) {
                                let lab = sddpm::polycube::Primitive::parse(&cr.label).map(|p| p.label() as usize).unwrap_or(1);
                                let target = cr.pcd.get(lab.saturating_sub(1)).copied().unwrap_or(f64::NAN);
                                let min = cr.pcd.iter().copied().fold(f64::INFINITY, f64::min);
                                println!("    cell {} {}: target PCD {target:.4}, nearest {:?} {min:.4}, inside {:.2}, pass {}", cr.cell, cr.label, cr.nearest, cr.inside_fraction, cr.pass);
                            }
                        }
                    }
                    let rank = |s: Stage| [Stage::Pending, Stage::Occupancy, Stage::Gocc, Stage::Tcv, Stage::Verified].iter().position(|x| *x == s).unwrap_or(0);
                    r.user_stage = pr.candidates.iter().map(|c| c.stage).max_by_key(|s| rank(*s)).map(|s| format!("{s:?}")).unwrap_or_else(|| "none".into());
                }
                Err(e) => r.user_stage = format!("error: {e}"),
            }
            r.user_s = t.elapsed().as_secs_f64();
            let cells = truth.labels.iter().filter(|l| **l != sddpm::polycube::Primitive::Null).count();
            println!(
                "{name} {i}: {truth} ({cells} cells, genus {genus}) | auto: {chosen}; recovered {} placed {} (Hausdorff {:.3} cell; true verified {}, among candidates {}), {} genus-consistent, {} kept, {} verified, {:.1} s | user-guided: {} ({}) {:.1} s",
                r.auto_recovered, r.auto_placed, r.hausdorff_cells, r.true_among_verified, r.true_among_candidates, r.global_candidates, r.kept, r.verified, r.auto_s, r.user_verified, r.user_stage, r.user_s
            );
            let _ = writeln!(
                csv,
                "{name},{i},{},{cells},{genus},{},{},{},{:.3},{},{},{},{},{},{:.2},{},{},{:.2},\"{}\"",
                truth.names(),
                r.auto_verified,
                r.auto_recovered,
                r.auto_placed,
                r.hausdorff_cells,
                r.true_among_verified,
                r.true_among_candidates,
                r.global_candidates,
                r.kept,
                r.verified,
                r.auto_s,
                r.user_verified,
                r.user_stage,
                r.user_s,
                chosen.replace('"', "'")
            );
            rows.push(r);
        }
        summary.push((name, rows));
        if let Some(dir) = std::path::Path::new(&csv_path).parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        std::fs::write(&csv_path, &csv).expect("write the CSV");
    }
    println!();
    println!("| group | cases | automated: recovered (chosen congruent to the truth) | automated: recovered and placed (Hausdorff < 1/6 cell) | automated: a verified polycube | true solid among the verified | true solid among the global candidates | user-guided with the true context: verified | mean genus-consistent candidates | mean kept | verified / kept | mean automated s | mean user-guided s |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, rows) in &summary {
        let m = rows.len().max(1) as f64;
        let cnt = |f: &dyn Fn(&Row) -> bool| rows.iter().filter(|r| f(r)).count();
        let pct = |k: usize| format!("{k}/{} ({:.0} %)", rows.len(), 100.0 * k as f64 / m);
        let kept: usize = rows.iter().map(|r| r.kept).sum();
        let ver: usize = rows.iter().map(|r| r.verified).sum();
        println!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {:.1} | {ver}/{kept} ({:.1} %) | {:.1} | {:.1} |",
            rows.len(),
            pct(cnt(&|r| r.auto_recovered)),
            pct(cnt(&|r| r.auto_placed)),
            pct(cnt(&|r| r.auto_verified)),
            pct(cnt(&|r| r.true_among_verified)),
            pct(cnt(&|r| r.true_among_candidates)),
            pct(cnt(&|r| r.user_verified)),
            rows.iter().map(|r| r.global_candidates).sum::<usize>() as f64 / m,
            kept as f64 / m,
            100.0 * ver as f64 / kept.max(1) as f64,
            rows.iter().map(|r| r.auto_s).sum::<f64>() / m,
            rows.iter().map(|r| r.user_s).sum::<f64>() / m,
        );
    }
    println!("\nCSV: {csv_path}");
    Ok(())
}

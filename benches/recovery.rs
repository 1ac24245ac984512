//! Context recovery on the independent evaluation set ([`sddpm::search::evalset`]):
//! the automated mode, run on each case's mesh as `sddpm polycube MESH --auto`
//! runs it (the mesh check's genus, [`ContextRequest::Auto`], the command line's
//! default polycube and automated options, seed 0), and the funnel's verdict
//! ([`sddpm::search::funnel::classify`]): recovered when the chosen polycube's
//! solid is congruent to the truth's, else the stage and reason at which the
//! truth dropped out.
//!
//! `cargo bench --bench recovery -- [--seed 9100] [--per-group 48]
//! [--families reported|tuning|all|name,...] [--groups simple,medium,complex]
//! [--generator learned|template] [--csv FILE] [--threads N] [--register-cells] [--local-keep N]`
//!
//! Case k of group g is [`EvalCase::generate`] with seed `case_seed(seed, g, k)`,
//! deformed by the k-th of the families in turn (the families spread evenly over
//! each group). Progress lines go to stderr, one per case; the tables (Markdown)
//! to stdout: recovery per group and per family, the funnel (loss stage and
//! reason per group), seconds per case, and the confidence calibration
//! (recovery among the cases whose chosen candidate verified against all
//! cases, verified candidates per case, and the runner-up's gap).
//!
//! `--threads N` runs N cases at a time, each thread with its own model (the
//! library's calls take the model by reference and allocate everything else
//! per call); default 1, since the automated mode already uses every core for
//! its batches and concurrent cases make the times per case meaningless.

use sddpm::diffusion::Model;
use sddpm::error::NoProgress;
use sddpm::pipeline::{generate_polycube, ContextRequest};
use sddpm::polycube::assembly::congruent;
use sddpm::search::auto::AutoOptions;
use sddpm::search::evalset::{case_seed, Deformation, EvalCase, COMPLEXITY_GROUPS, REPORT_SEED};
use sddpm::search::funnel::{classify, classify_error, LossStage, Verdict};
use sddpm::search::generate::{PolycubeOptions, PolycubeResult, Stage};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// A verified candidate of another solid scores within this relative gap of the
/// chosen one: a close call (the calibration table counts them).
const CLOSE_GAP: f64 = 0.1;

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).map(|v| v.parse().unwrap_or_else(|_| panic!("{name}: cannot parse '{v}'")))
}

/// One case to run.
#[derive(Clone, Copy)]
struct Job {
    gi: usize,
    k: usize,
    seed: u64,
    family: Deformation,
}

/// One case's outcome.
struct Row {
    job: Job,
    group: &'static str,
    truth: String,
    cells: usize,
    genus: i64,
    triangles: usize,
    attempts: usize,
    verdict: Verdict,
    /// The chosen (verified) candidate.
    chosen: Option<String>,
    candidates: usize,
    verified: usize,
    /// The best-scoring verified candidate of another solid than the chosen one,
    /// and its score's gap to the chosen one's, relative to the chosen one's.
    runner_up: Option<(String, f64)>,
    seconds: f64,
    /// The run's error (the refusal, or a case that could not be generated).
    error: Option<String>,
}

/// The relative score gap between the chosen candidate and the best verified
/// candidate whose solid differs from it.
fn runner_up(pr: &PolycubeResult) -> Option<(String, f64)> {
    let c = &pr.candidates[pr.chosen?];
    let solid = c.context.assemble();
    let s1 = c.score.unwrap_or(c.fit_mean);
    pr.candidates
        .iter()
        .filter(|o| o.stage == Stage::Verified && !congruent(&o.context.assemble(), &solid))
        .map(|o| (o.context.names(), o.score.unwrap_or(o.fit_mean)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(n, s2)| (n, (s2 - s1) / s1.abs().max(1e-12)))
}

fn run_case(model: &Model, opts: &PolycubeOptions, aopts: &AutoOptions, job: Job) -> Row {
    let g = COMPLEXITY_GROUPS[job.gi];
    let mut row = Row {
        job,
        group: g.0,
        truth: String::new(),
        cells: 0,
        genus: 0,
        triangles: 0,
        attempts: 0,
        verdict: Verdict { recovered: false, loss: None },
        chosen: None,
        candidates: 0,
        verified: 0,
        runner_up: None,
        seconds: 0.0,
        error: None,
    };
    let case = match EvalCase::generate(job.seed, g, job.family) {
        Ok(c) => c,
        Err(e) => {
            row.verdict = classify_error(&e);
            row.error = Some(format!("case not generated: {e}"));
            return row;
        }
    };
    row.truth = case.context.names();
    row.cells = case.cells;
    row.genus = case.genus;
    row.triangles = case.mesh.triangles.len();
    row.attempts = case.attempts;
    // as the command line: the genus the mesh check measures
    let genus = case.mesh.check().genus.unwrap_or(case.genus);
    let t = Instant::now();
    let out = generate_polycube(model, &case.mesh, genus, &ContextRequest::Auto, opts, aopts, &mut NoProgress);
    row.seconds = t.elapsed().as_secs_f64();
    match out {
        Ok((pr, rep, err)) => {
            row.verdict = classify(&case.context, &pr, rep.as_ref(), opts);
            row.chosen = pr.chosen.map(|k| pr.candidates[k].context.names());
            row.candidates = pr.candidates.len();
            row.verified = pr.verified().count();
            row.runner_up = runner_up(&pr);
            row.error = err.map(|e| e.to_string());
        }
        Err(e) => {
            row.verdict = classify_error(&e);
            row.error = Some(e.to_string());
        }
    }
    row
}

fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (z, nf) = (1.96f64, n as f64);
    let p = k as f64 / nf;
    let d = 1.0 + z * z / nf;
    let c = (p + z * z / (2.0 * nf)) / d;
    let h = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

fn pct(k: usize, n: usize) -> String {
    if n == 0 {
        return "-".into();
    }
    format!("{k}/{n} ({:.0} %)", 100.0 * k as f64 / n as f64)
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn csv_field(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "'").replace('\n', " "))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = arg(&args, "--seed").unwrap_or(REPORT_SEED);
    let per_group: usize = arg(&args, "--per-group").unwrap_or(48);
    let families = Deformation::parse_list(&arg::<String>(&args, "--families").unwrap_or_else(|| "reported".into())).expect("--families");
    let groups: Vec<String> = arg::<String>(&args, "--groups").map(|s| s.split(',').map(|t| t.trim().to_string()).collect()).unwrap_or_else(|| COMPLEXITY_GROUPS.iter().map(|g| g.0.to_string()).collect());
    for g in &groups {
        assert!(COMPLEXITY_GROUPS.iter().any(|c| c.0 == g), "--groups: unknown group '{g}' (simple, medium, complex)");
    }
    let generator: String = arg(&args, "--generator").unwrap_or_else(|| "learned".into());
    let csv_path: Option<String> = arg(&args, "--csv");
    let threads: usize = arg::<usize>(&args, "--threads").unwrap_or(1).max(1);
    // `--register-cells`: rank the labels by the in-context fit after the cell registration
    // `--opening-labels on|off`: rank first the labels whose hole the subregion shows
    // `--axis-frames on|off`: also split with the grid's X along the input's Y and Z
    // `--local-keep N`: labels kept per subregion after the in-context fit
    let aopts = AutoOptions {
        register_cells: args.iter().any(|a| a == "--register-cells"),
        opening_labels: arg::<String>(&args, "--opening-labels").map_or(AutoOptions::default().opening_labels, |v| v == "on"),
        axis_frames: arg::<String>(&args, "--axis-frames").map_or(AutoOptions::default().axis_frames, |v| v == "on"),
        local_keep: arg(&args, "--local-keep").unwrap_or(AutoOptions::default().local_keep),
        ..AutoOptions::default()
    };
    // the command line's options for `--generator` (learned: the embedded weights)
    // `--warp-fit on|off`: fit and lay out after the quadratic registration
    let warp_fit: Option<bool> = arg::<String>(&args, "--warp-fit").map(|v| v == "on");
    let load = || -> (Model, PolycubeOptions) {
        let (model, mut opts) = match generator.as_str() {
            "learned" => (Model::default_model().expect("the embedded model"), PolycubeOptions::default()),
            "template" => (Model::template(), PolycubeOptions::template()),
            other => panic!("--generator must be learned or template, got '{other}'"),
        };
        if let Some(w) = warp_fit {
            opts.warp_fit = w;
        }
        (model, opts)
    };
    let mut jobs = Vec::new();
    for (gi, g) in COMPLEXITY_GROUPS.iter().enumerate() {
        if groups.iter().any(|x| x == g.0) {
            for k in 0..per_group {
                jobs.push(Job { gi, k, seed: case_seed(seed, gi, k), family: families[k % families.len()] });
            }
        }
    }
    let fam_names: Vec<String> = families.iter().map(|f| format!("{f} ({})", f.split())).collect();
    eprintln!("recovery: seed {seed}, {per_group} cases per group of {}, families {}, generator {generator}, {threads} thread(s)", groups.join(","), fam_names.join(", "));
    let t_all = Instant::now();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let rows: Mutex<Vec<Option<Row>>> = Mutex::new((0..jobs.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads.min(jobs.len().max(1)) {
            s.spawn(|| {
                let (model, opts) = load();
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&job) = jobs.get(i) else { break };
                    let r = run_case(&model, &opts, &aopts, job);
                    let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                    let outcome = match (&r.verdict.loss, &r.chosen) {
                        (None, _) => format!("recovered ({})", r.chosen.as_deref().unwrap_or("-")),
                        (Some(l), c) => format!("lost at {} [{}]: {}; chosen {}", l.stage, l.reason, l.detail, c.as_deref().unwrap_or("none")),
                    };
                    eprintln!(
                        "[{n}/{}] {} {} {} (seed {}): {} ({} cells, genus {}) | {} | {}/{} verified | {:.1} s",
                        jobs.len(),
                        r.group,
                        r.job.k,
                        r.job.family,
                        r.job.seed,
                        r.truth,
                        r.cells,
                        r.genus,
                        outcome,
                        r.verified,
                        r.candidates,
                        r.seconds
                    );
                    rows.lock().expect("rows")[i] = Some(r);
                }
            });
        }
    });
    let rows: Vec<Row> = rows.into_inner().expect("rows").into_iter().map(|r| r.expect("every case ran")).collect();
    let wall = t_all.elapsed().as_secs_f64();

    if let Some(path) = &csv_path {
        let mut csv = String::from("group,case,seed,family,split,truth,cells,genus,triangles,attempts,recovered,chosen_verified,chosen,candidates,verified,runner_up,runner_up_gap,loss_stage,loss_reason,loss_detail,seconds,error\n");
        for r in &rows {
            let (stage, reason, detail) = r.verdict.loss.as_ref().map(|l| (l.stage.number().to_string(), l.reason.to_string(), l.detail.clone())).unwrap_or_default();
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.2},{}",
                r.group,
                r.job.k,
                r.job.seed,
                r.job.family,
                r.job.family.split(),
                csv_field(&r.truth),
                r.cells,
                r.genus,
                r.triangles,
                r.attempts,
                r.verdict.recovered,
                r.chosen.is_some(),
                csv_field(r.chosen.as_deref().unwrap_or("")),
                r.candidates,
                r.verified,
                csv_field(r.runner_up.as_ref().map(|x| x.0.as_str()).unwrap_or("")),
                r.runner_up.as_ref().map(|x| format!("{:.4}", x.1)).unwrap_or_default(),
                stage,
                reason,
                csv_field(&detail),
                r.seconds,
                csv_field(r.error.as_deref().unwrap_or(""))
            );
        }
        if let Some(dir) = std::path::Path::new(path).parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        std::fs::write(path, csv).expect("write the CSV");
    }

    // Columns: the groups run, then all of them together.
    let mut cols: Vec<&'static str> = COMPLEXITY_GROUPS.iter().map(|g| g.0).filter(|g| groups.iter().any(|x| x == g)).collect();
    cols.push("all");
    let of = |c: &str| -> Vec<&Row> { rows.iter().filter(|r| c == "all" || r.group == c).collect() };
    let header = |first: &str| {
        let names: Vec<String> = cols
            .iter()
            .map(|c| match COMPLEXITY_GROUPS.iter().find(|g| g.0 == *c) {
                Some(g) => format!("{} ({}–{})", g.0, g.1, g.2),
                None => "all".into(),
            })
            .collect();
        println!("| {first} | {} |", names.join(" | "));
        println!("|---|{}", "---:|".repeat(cols.len()));
    };

    println!("\n## Context recovery, seed {seed}, {per_group} cases per group, generator {generator}\n");
    println!("Families: {}. Wall time {:.0} s, {threads} thread(s).\n", fam_names.join(", "), wall);
    println!("### Recovery (chosen polycube congruent to the truth; Wilson 95 %)\n");
    header("");
    let line = |name: &str, f: &dyn Fn(&[&Row]) -> String| {
        let v: Vec<String> = cols.iter().map(|c| f(&of(c))).collect();
        println!("| {name} | {} |", v.join(" | "));
    };
    line("recovered", &|v| {
        let k = v.iter().filter(|r| r.verdict.recovered).count();
        let (lo, hi) = wilson(k, v.len());
        format!("**{}** ({:.0}–{:.0} %)", pct(k, v.len()), 100.0 * lo, 100.0 * hi)
    });
    line("a verified polycube chosen", &|v| pct(v.iter().filter(|r| r.chosen.is_some()).count(), v.len()));
    line("refused (no candidate verified)", &|v| pct(v.iter().filter(|r| r.chosen.is_none()).count(), v.len()));
    line("cases not generated", &|v| v.iter().filter(|r| r.truth.is_empty()).count().to_string());

    println!("\n### Recovery per family\n");
    header("family");
    for f in &families {
        let v: Vec<String> = cols
            .iter()
            .map(|c| {
                let rs: Vec<&Row> = of(c).into_iter().filter(|r| r.job.family == *f).collect();
                pct(rs.iter().filter(|r| r.verdict.recovered).count(), rs.len())
            })
            .collect();
        println!("| {f} ({}) | {} |", f.split(), v.join(" | "));
    }

    println!("\n### Funnel: where the truth was lost (cases)\n");
    header("stage: reason");
    line("recovered", &|v| v.iter().filter(|r| r.verdict.recovered).count().to_string());
    let mut reasons: BTreeMap<(LossStage, &'static str), ()> = BTreeMap::new();
    for r in &rows {
        if let Some(l) = &r.verdict.loss {
            reasons.insert((l.stage, l.reason), ());
        }
    }
    for s in LossStage::ALL {
        let name = format!("{s}");
        line(&format!("**{name}**"), &|v| v.iter().filter(|r| r.verdict.stage() == Some(s)).count().to_string());
        for &(_, reason) in reasons.keys().filter(|(st, _)| *st == s) {
            line(&format!("{name}: {reason}"), &|v| v.iter().filter(|r| r.verdict.loss.as_ref().is_some_and(|l| l.stage == s && l.reason == reason)).count().to_string());
        }
    }

    println!("\n### Seconds per case (the automated mode alone)\n");
    header("");
    line("median", &|v| format!("{:.1}", median(v.iter().filter(|r| !r.truth.is_empty()).map(|r| r.seconds).collect())));
    line("max", &|v| format!("{:.1}", v.iter().map(|r| r.seconds).fold(0.0, f64::max)));
    line("mean", &|v| format!("{:.1}", v.iter().map(|r| r.seconds).sum::<f64>() / v.len().max(1) as f64));

    println!("\n### Confidence calibration\n");
    header("");
    let rec = |v: &[&Row]| v.iter().filter(|r| r.verdict.recovered).count();
    line("recovered among all cases", &|v| pct(rec(v), v.len()));
    line("recovered among cases whose chosen candidate verified", &|v| {
        let ver: Vec<&Row> = v.iter().copied().filter(|r| r.chosen.is_some()).collect();
        pct(rec(&ver), ver.len())
    });
    line("difference (points)", &|v| {
        let ver: Vec<&Row> = v.iter().copied().filter(|r| r.chosen.is_some()).collect();
        if ver.is_empty() || v.is_empty() {
            return "-".into();
        }
        format!("{:+.1}", 100.0 * (rec(&ver) as f64 / ver.len() as f64 - rec(v) as f64 / v.len() as f64))
    });
    line("verified candidates per case (mean)", &|v| format!("{:.1}", v.iter().map(|r| r.verified).sum::<usize>() as f64 / v.len().max(1) as f64));
    line("candidates per case (mean)", &|v| format!("{:.1}", v.iter().map(|r| r.candidates).sum::<usize>() as f64 / v.len().max(1) as f64));
    line("chosen with a verified runner-up of another solid", &|v| pct(v.iter().filter(|r| r.runner_up.is_some()).count(), v.iter().filter(|r| r.chosen.is_some()).count()));
    line("runner-up's relative score gap (median)", &|v| {
        let g: Vec<f64> = v.iter().filter_map(|r| r.runner_up.as_ref().map(|x| x.1)).collect();
        if g.is_empty() {
            "-".into()
        } else {
            format!("{:.3}", median(g))
        }
    });
    line(&format!("recovered when the runner-up is within {:.0} %", 100.0 * CLOSE_GAP), &|v| {
        let close: Vec<&Row> = v.iter().copied().filter(|r| r.runner_up.as_ref().is_some_and(|x| x.1 < CLOSE_GAP)).collect();
        pct(rec(&close), close.len())
    });
    line(&format!("recovered when no runner-up within {:.0} %", 100.0 * CLOSE_GAP), &|v| {
        let clear: Vec<&Row> = v.iter().copied().filter(|r| r.chosen.is_some() && r.runner_up.as_ref().is_none_or(|x| x.1 >= CLOSE_GAP)).collect();
        pct(rec(&clear), clear.len())
    });
    if let Some(p) = &csv_path {
        println!("\nCSV: {p}");
    }
}

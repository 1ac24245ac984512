//! The run folder of the main job (DESIGN.md "Command line"): polycube.obj, the hex
//! files, the spline files, report.json and report.html with its PNG pictures and
//! plots. Used by `sddpm run` and available to every caller of [`super::run`].

use super::RunResult;
use crate::error::{Error, Result};
use crate::export::plot::{bars_png, histogram_png};
use crate::export::render::{hex_boundary, render_png, Camera, Layer};
use crate::mesh::{MeshReport, TriMesh};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;

/// The input as report.json describes it, with the request that made the run.
pub struct InputInfo<'a> {
    pub path: &'a str,
    pub mesh: &'a TriMesh,
    pub report: &'a MeshReport,
    /// The command line that made the run (report.json "command"); None: a library
    /// call, recorded as [`LIBRARY_COMMAND`].
    pub command: Option<&'a str>,
}

/// report.json's "command" when the run folder was not written by the command line.
pub const LIBRARY_COMMAND: &str = "sddpm::pipeline::run (library call)";

/// File names inside the run folder (besides the hex and spline files).
pub const POLYCUBE_OBJ: &str = "polycube.obj";
pub const REPORT_JSON: &str = "report.json";
pub const REPORT_HTML: &str = "report.html";

/// Every file name the command line writes into an output folder, with what it
/// holds: the run folder of `sddpm run` (and of each input of `sddpm batch`),
/// `sddpm polycube`'s candidates.json and `sddpm batch`'s summaries. `--force`
/// removes these names, and only these, before a run ([`clear_outputs`]); the
/// manifest of report.json ("files") describes each file with its entry here.
pub const OUTPUT_FILES: &[(&str, &str)] = &[
    (POLYCUBE_OBJ, "the chosen polycube's surface in the input's coordinates (OBJ)"),
    ("hex.vtu", "the hex mesh with the scaled Jacobian per element (VTK XML, ParaView)"),
    ("hex.vtk", "the hex mesh with the scaled Jacobian per element (legacy VTK)"),
    ("hex.mesh", "the hex mesh (Medit; Gmsh, meshio)"),
    ("hex.k", "the hex mesh as LS-DYNA nodes and solid elements"),
    ("spline.bext", "the volumetric spline: control points and Bézier extraction operators (BEXT)"),
    ("model.k", "LS-DYNA IGA deck that includes spline.bext"),
    ("spline.vtk", "the spline sampled per element with its Jacobian (binary legacy VTK, ParaView)"),
    ("spline_control.vtk", "the spline's control mesh (legacy VTK)"),
    ("input.png", "picture of the input surface"),
    ("polycube.png", "picture of the chosen polycube"),
    ("hex.png", "picture of the hex mesh's boundary"),
    ("scaled_jacobian.png", "histogram of the elements' scaled Jacobian (log counts, goal line)"),
    ("timings.png", "chart of the stage timings"),
    (REPORT_JSON, "the run's figures, options, provenance and this list of files (JSON)"),
    (REPORT_HTML, "this report"),
    ("candidates.json", "every polycube candidate with its stage and scores (sddpm polycube)"),
    ("summary.json", "one row per input file (sddpm batch, JSON)"),
    ("summary.md", "one row per input file (sddpm batch, Markdown table)"),
];

/// What a file of [`OUTPUT_FILES`] holds ("" for another name).
pub fn describe_output(name: &str) -> &'static str {
    OUTPUT_FILES.iter().find(|(n, _)| *n == name).map(|(_, w)| *w).unwrap_or("")
}

/// The names in `dir`, sorted (none when it does not exist).
pub fn folder_entries(dir: &Path) -> Result<Vec<String>> {
    if !dir.exists() {
        return Ok(Vec::new());
    }
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir.display(), e))?;
    let mut v: Vec<String> = rd.filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    Ok(v)
}

/// Remove the files of [`OUTPUT_FILES`] from `dir` and return their names; any
/// other entry (the caller's files, folders) is left as it is.
pub fn clear_outputs(dir: &Path) -> Result<Vec<String>> {
    let mut removed = Vec::new();
    for (name, _) in OUTPUT_FILES {
        let p = dir.join(name);
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|e| Error::io(p.display(), e))?;
            removed.push(name.to_string());
        }
    }
    Ok(removed)
}

/// report.json's text for a command that wrote `names` into `dir`: `report` gets
/// "files", the manifest of those files and of report.json itself, whose size is
/// the size of the text returned (rendered until it holds).
pub fn json_with_manifest(dir: &Path, names: &[&str], report: &mut Value) -> Result<String> {
    let mut size = 0u64;
    let mut text = String::new();
    for _ in 0..8 {
        let mut files: Vec<Value> = names.iter().map(|f| manifest_entry(dir, f)).collect();
        files.push(json!({ "name": REPORT_JSON, "bytes": size, "what": describe_output(REPORT_JSON) }));
        report["files"] = Value::Array(files);
        text = serde_json::to_string_pretty(report).map_err(|e| Error::Internal(e.to_string()))?;
        if text.len() as u64 == size {
            break;
        }
        size = text.len() as u64;
    }
    Ok(text)
}

/// One entry of report.json's "files": a file this run wrote, its size and what it
/// holds.
fn manifest_entry(dir: &Path, name: &str) -> Value {
    let bytes = std::fs::metadata(dir.join(name)).map(|m| m.len()).unwrap_or(0);
    json!({ "name": name, "bytes": bytes, "what": describe_output(name) })
}

fn write_text(path: &Path, s: &str) -> Result<()> {
    std::fs::write(path, s).map_err(|e| Error::io(path.display(), e))
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Write every file of the run folder and return report.json's content.
/// `total_seconds` is the caller's wall clock for the whole job (loading included).
pub fn write_run_folder(dir: &Path, input: &InputInfo, r: &RunResult, total_seconds: f64) -> Result<Value> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    let t_write = std::time::Instant::now();
    // no candidate was formed for a part the grid cannot hold: no polycube.obj,
    // polycube.png or polycube labels then
    let cand = r.candidate.map(|c| &r.polycube.candidates[c]);
    let poly = cand.map(|c| super::polycube_user_mesh(&r.polycube, c));
    // the files written, in order (report.json's "files")
    let mut written: Vec<String> = Vec::new();
    if let (Some(cand), Some(poly)) = (cand, &poly) {
        crate::export::obj::write_obj(&dir.join(POLYCUBE_OBJ), poly, &format!("libsddpm polycube {} (user coordinates)", cand.context))?;
        written.push(POLYCUBE_OBJ.into());
    }
    crate::export::hexfmt::write_hex_files(dir, &r.hex)?;
    for f in [crate::hex::report::HEX_VTU, crate::hex::report::HEX_VTK, crate::hex::report::HEX_MESH, crate::hex::report::HEX_K] {
        written.push(f.into());
    }
    let mut hex_json = crate::hex::report_json(&r.hex);
    if let Some(m) = hex_json.as_object_mut() {
        m.insert("candidates_meshed".into(), serde_json::to_value(&r.hex_attempts).unwrap_or(Value::Null));
    }
    let spline_json = match &r.spline {
        Some(sp) => {
            let o = crate::export::spline_files::OutputOptions::default();
            let j = crate::export::spline_files::write_outputs(dir, sp, &o)?;
            written.push(o.bext.clone());
            written.push(o.lsdyna.clone());
            written.extend(o.vtk.iter().cloned());
            written.extend(o.control_vtk.iter().cloned());
            j
        }
        None => Value::Null,
    };
    // pictures and plots
    let mut pictures = Vec::new();
    let cam = Camera::default();
    let mut pic = |name: &str, layers: &[Layer]| {
        if render_png(&dir.join(name), layers, 640, 480, cam).is_ok() {
            pictures.push(name.to_string());
        }
    };
    pic("input.png", &[Layer::Surface { vertices: &input.mesh.vertices, triangles: &input.mesh.triangles, edges: &[], colour: [200, 200, 210] }]);
    if let (Some(cand), Some(pq)) = (cand, &poly) {
        let qm = crate::polycube::boundary(&cand.context.assemble());
        let pedges: Vec<[u32; 2]> = {
            // the quad edges of the polycube boundary (its triangles come two per quad)
            let mut e = std::collections::BTreeSet::new();
            for q in &qm.quads {
                for i in 0..4 {
                    let (a, b) = (q[i], q[(i + 1) % 4]);
                    e.insert([a.min(b), a.max(b)]);
                }
            }
            if pq.vertices.len() == qm.vertices.len() {
                e.into_iter().collect()
            } else {
                Vec::new()
            }
        };
        pic("polycube.png", &[Layer::Surface { vertices: &pq.vertices, triangles: &pq.triangles, edges: &pedges, colour: [120, 170, 230] }]);
    }
    let (ht, he) = hex_boundary(&r.hex.mesh.elements);
    let he = if he.len() > 60_000 { Vec::new() } else { he };
    pic("hex.png", &[Layer::Surface { vertices: &r.hex.mesh.nodes, triangles: &ht, edges: &he, colour: [230, 180, 120] }]);
    let goal_min = r.options.hex.goals.min_scaled_jacobian;
    let hist_ok = histogram_png(
        &dir.join("scaled_jacobian.png"),
        &r.hex.histogram,
        -1.0,
        1.0,
        "Scaled Jacobian of the hex elements",
        "scaled Jacobian (Verdict)",
        Some((goal_min, &format!("goal: min >= {goal_min}"))),
    )
    .is_ok();

    let mut seconds = serde_json::Map::new();
    seconds.insert("total".into(), total_seconds.into());
    for (k, v) in &r.seconds {
        seconds.insert(k.clone(), (*v).into());
    }
    for (k, v) in crate::hex::report::stage_seconds(&r.hex) {
        seconds.insert(k, v.into());
    }
    let mut bars: Vec<(String, f64)> = r.seconds.clone();
    bars.push(("write outputs".into(), t_write.elapsed().as_secs_f64()));
    let timing_ok = bars_png(&dir.join("timings.png"), &bars, "Stage timings", "seconds").is_ok();
    written.extend(pictures.iter().cloned());
    for (ok, f) in [(hist_ok, "scaled_jacobian.png"), (timing_ok, "timings.png")] {
        if ok {
            written.push(f.into());
        }
    }
    seconds.insert("write".into(), t_write.elapsed().as_secs_f64().into());
    let rep = input.report;
    let goals = &r.options.hex.goals;
    let q = &r.hex.quality;
    let goal_rows = json!([
        { "goal": "no inverted element", "target": "inverted = 0", "value": q.inverted, "met": q.inverted == 0 },
        { "goal": "minimum scaled Jacobian", "target": format!(">= {}", goals.min_scaled_jacobian), "value": q.min, "met": q.min >= goals.min_scaled_jacobian },
        { "goal": "mean scaled Jacobian", "target": format!(">= {}", goals.mean_scaled_jacobian), "value": q.mean, "met": q.mean >= goals.mean_scaled_jacobian },
        { "goal": "Hausdorff distance / bounding-box diagonal", "target": format!("<= {} %", 100.0 * goals.hausdorff), "value": r.hex.hausdorff_relative, "met": r.hex.hausdorff_relative <= goals.hausdorff },
    ]);
    if let Some(m) = hex_json.as_object_mut() {
        m.insert("goals".into(), goal_rows);
    }
    let from_polycube = r.hex.from_polycube();
    let mesh_path = json!({
        "from": if from_polycube { "polycube" } else { "grid-based fallback" },
        "domain": r.hex.domain,
        "polycube": cand.filter(|_| from_polycube).map(|c| c.context.describe()),
        "verified": r.verified,
        "why": mesh_path_reason(r),
    });
    let mut report = json!({
        "version": env!("CARGO_PKG_VERSION"),
        "command": input.command.unwrap_or(LIBRARY_COMMAND),
        "options": serde_json::to_value(&r.options).unwrap_or(Value::Null),
        "mesh_path": mesh_path,
        "input": {
            "path": input.path, "vertices": rep.vertices, "triangles": rep.triangles,
            "genus": rep.genus, "volume": rep.volume, "area": rep.area,
            "bbox": [rep.bbox_min, rep.bbox_max],
        },
        "polycube": {
            "labels": cand.map(|c| c.labels.to_vec()),
            "names": cand.map(|c| c.context.names()),
            "description": cand.map(|c| c.context.describe()),
            "source": r.polycube.source,
            "generator": r.polycube.generator,
            "candidates": r.polycube.candidates.len(),
            "verified": r.polycube.verified().count(),
            // candidates that went through the diffusion (the others were refused
            // by the pre-check or the fit limit)
            "diffused": r.polycube.candidates.iter().filter(|c| c.report.is_some()).count(),
            "genus": cand.and_then(|c| c.context.validity().genus),
            "rotation": cand.map(|c| c.rotation.clone()),
            "fit": cand.map(|c| c.fit),
            "score": cand.and_then(|c| c.score),
            "file": cand.map(|_| POLYCUBE_OBJ),
            "verified_choice": r.verified,
            "verification_error": r.verification_error,
            "timings": r.polycube.timings,
            "auto": r.auto,
        },
        "hex": hex_json,
        "spline": spline_json,
        "seconds": Value::Object(seconds),
        "pictures": pictures,
    });
    // the manifest: every file written, report.json and report.html included, whose
    // sizes depend on the manifest itself: rendered until the sizes they state hold
    let mut sizes = (0u64, 0u64);
    let (mut json_text, mut html_text) = (String::new(), String::new());
    for _ in 0..8 {
        let mut files: Vec<Value> = written.iter().map(|f| manifest_entry(dir, f)).collect();
        files.push(json!({ "name": REPORT_JSON, "bytes": sizes.0, "what": describe_output(REPORT_JSON) }));
        files.push(json!({ "name": REPORT_HTML, "bytes": sizes.1, "what": describe_output(REPORT_HTML) }));
        report["files"] = Value::Array(files);
        json_text = serde_json::to_string_pretty(&report).map_err(|e| Error::Internal(e.to_string()))?;
        html_text = html(&report, r, hist_ok, timing_ok);
        let now = (json_text.len() as u64, html_text.len() as u64);
        if now == sizes {
            break;
        }
        sizes = now;
    }
    write_text(&dir.join(REPORT_JSON), &json_text)?;
    write_text(&dir.join(REPORT_HTML), &html_text)?;
    Ok(report)
}

/// Why the mesh comes from where it does (report.json "mesh_path.why").
fn mesh_path_reason(r: &RunResult) -> String {
    match (&r.verification_error, r.hex.from_polycube()) {
        (None, true) => {
            let d = r.candidate.map(|c| r.polycube.candidates[c].context.describe()).unwrap_or_default();
            if r.options.hex.goals.missed(&r.hex) == 0 {
                return format!("the hex mesh of the verified polycube {d} meets every quality goal");
            }
            match r.hex_attempts.iter().find(|a| a.candidate.is_none()) {
                Some(a) if a.error.is_none() => {
                    format!("the hex mesh of the verified polycube {d} misses a quality goal but ranks better than the grid-based fallback's ({})", a.describe())
                }
                Some(a) => format!("the hex mesh of the verified polycube {d} misses a quality goal; the grid-based fallback failed ({})", a.error.as_deref().unwrap_or("")),
                None => format!("the hex mesh of the verified polycube {d} misses a quality goal; the grid-based fallback was not tried (turned off, or a fixed --level whose mesh has no inverted element)"),
            }
        }
        (Some(e), _) => e.clone(),
        (None, false) => "the grid-based fallback's mesh ranked better than every polycube mesh".into(),
    }
}

fn num(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_f64() {
            Some(f) if n.is_f64() => {
                if f != 0.0 && (f.abs() < 1e-3 || f.abs() >= 1e6) {
                    format!("{f:.3e}")
                } else {
                    format!("{f:.4}")
                }
            }
            _ => n.to_string(),
        },
        Value::Null => "-".into(),
        Value::String(s) => esc(s),
        o => esc(&o.to_string()),
    }
}

fn table(rows: &[(&str, String)]) -> String {
    let mut s = String::from("<table>");
    for (k, v) in rows {
        let _ = write!(s, "<tr><th>{}</th><td>{}</td></tr>", esc(k), v);
    }
    s.push_str("</table>");
    s
}

/// A context's names ("THC+Z,null,...") as [`crate::context::Context::describe`]
/// writes them; other text (the fallback's "voxel 24") as it is.
fn readable_context(names: &str) -> String {
    crate::context::Context::parse(names).map(|c| c.describe()).unwrap_or_else(|_| names.to_string())
}

/// A relative distance as a percentage, as the command line prints it.
fn percent(v: &Value) -> String {
    match v.as_f64() {
        Some(f) if f.is_finite() => format!("{:.2} %", 100.0 * f),
        _ => "-".into(),
    }
}

fn mark(met: bool) -> String {
    if met {
        "<td class=\"ok goal-pass\">&#10004; met</td>".into()
    } else {
        "<td class=\"bad goal-fail\">&#10008; missed</td>".into()
    }
}

fn html(j: &Value, r: &RunResult, hist: bool, timings: bool) -> String {
    let inp = &j["input"];
    let pc = &j["polycube"];
    let hx = &j["hex"];
    let sp = &j["spline"];
    let path = &j["mesh_path"];
    let fallback = !r.hex.from_polycube();
    let mut s = String::new();
    s.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>libsddpm report</title><style>\
body{font-family:DejaVu Sans,Arial,sans-serif;margin:24px;color:#222;max-width:1400px}\
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:28px}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:13px}\
th{background:#f2f2f2}.pics img{border:1px solid #ddd;margin:4px;max-width:32%}.ok{color:#1a7f37}.bad{color:#b42318}\
.note{color:#8a5a00}.path{font-size:16px;padding:8px 12px;border:1px solid #ccc;background:#f7f7f7;display:inline-block}\
code{font-size:12px;word-break:break-all}\
</style></head><body>\n");
    let _ = writeln!(s, "<h1>libsddpm report: {}</h1>", num(&inp["path"]));
    // the answer first: where the mesh comes from and whether it meets each goal
    let _ = write!(
        s,
        "<p class=\"path\" id=\"mesh-path\"><b>Mesh made by: {}</b> ({})</p><p>{}</p>",
        esc(path["from"].as_str().unwrap_or("?")),
        if fallback { format!("lattice {}", esc(path["domain"].as_str().unwrap_or("?"))) } else { format!("polycube {}", esc(&r.candidate.map(|c| r.polycube.candidates[c].context.describe()).unwrap_or_default())) },
        esc(path["why"].as_str().unwrap_or(""))
    );
    s.push_str("<h2>Quality goals</h2><table id=\"goals\"><tr><th>goal</th><th>target</th><th>value</th><th>result</th></tr>");
    if let Some(goals) = hx["goals"].as_array() {
        for g in goals {
            let value = if g["goal"].as_str().is_some_and(|n| n.starts_with("Hausdorff")) { percent(&g["value"]) } else { num(&g["value"]) };
            let _ = write!(s, "<tr><td>{}</td><td>{}</td><td>{}</td>{}</tr>", num(&g["goal"]), num(&g["target"]), value, mark(g["met"].as_bool() == Some(true)));
        }
    }
    s.push_str("</table>");
    s.push_str("<h2>Input and hex mesh</h2><div class=\"pics\">");
    let mut pics = vec![("input.png", "input surface")];
    if !fallback {
        pics.push(("polycube.png", "chosen polycube"));
    }
    pics.push(("hex.png", "hex mesh boundary"));
    let present: Vec<&str> = j["pictures"].as_array().map(|a| a.iter().filter_map(|v| v.as_str()).collect()).unwrap_or_default();
    for (f, alt) in pics.iter().filter(|(f, _)| present.contains(f)) {
        let _ = write!(s, "<img src=\"{f}\" alt=\"{alt}\" title=\"{alt}\">");
    }
    s.push_str("</div>");
    s.push_str(&table(&[
        ("vertices", num(&inp["vertices"])),
        ("triangles", num(&inp["triangles"])),
        ("genus", num(&inp["genus"])),
        ("volume", num(&inp["volume"])),
        ("area", num(&inp["area"])),
    ]));
    let polycube_section = |s: &mut String| {
        if fallback {
            s.push_str("<h2>Polycube (not used for the mesh)</h2><p>The polycube candidates below were generated and meshed, but the grid-based fallback's mesh ranked better; this section is for reference.</p>");
            if present.contains(&"polycube.png") {
                s.push_str("<div class=\"pics\"><img src=\"polycube.png\" alt=\"best polycube candidate\" title=\"best polycube candidate\"></div>");
            }
        } else {
            s.push_str("<h2>Polycube</h2>");
            if let Some(e) = &r.verification_error {
                let _ = write!(s, "<p class=\"note\"><b>Unverified polycube.</b> {} The mesh comes from this candidate and is measured on its own (the goals above); run with --strict to refuse instead.</p>", esc(e));
            }
        }
        s.push_str(&table(&[
            ("context", num(&pc["description"])),
            ("labels", esc(&pc["labels"].to_string())),
            ("source", num(&pc["source"])),
            ("rotation", num(&pc["rotation"])),
            ("genus", num(&pc["genus"])),
            ("candidates / verified", format!("{} / {}", num(&pc["candidates"]), num(&pc["verified"]))),
            ("fit, score", format!("{}, {}", num(&pc["fit"]), num(&pc["score"]))),
        ]));
        s.push_str("<h3>Candidates (best 40 by stage and score)</h3><table><tr><th>#</th><th>context</th><th>rotation</th><th>stage</th><th>fit</th><th>score</th><th>mean target PCD</th><th>reason</th></tr>");
        let mut idx: Vec<usize> = (0..r.polycube.candidates.len()).collect();
        let rank = |st: crate::search::generate::Stage| {
            use crate::search::generate::Stage::*;
            match st {
                Verified => 0,
                Tcv => 1,
                Gocc => 2,
                Pending => 3,
                Occupancy => 4,
            }
        };
        idx.sort_by(|&a, &b| {
            let (ca, cb) = (&r.polycube.candidates[a], &r.polycube.candidates[b]);
            (rank(ca.stage), ca.score.unwrap_or(ca.fit)).partial_cmp(&(rank(cb.stage), cb.score.unwrap_or(cb.fit))).unwrap_or(std::cmp::Ordering::Equal)
        });
        for &i in idx.iter().take(40) {
            let c = &r.polycube.candidates[i];
            let stage = serde_json::to_value(c.stage).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default();
            let cls = if stage == "verified" { "ok" } else { "bad" };
            let (pcd, reason) = match &c.report {
                Some(rep) => (format!("{:.4}", rep.mean_target_pcd), rep.reason.clone().unwrap_or_default()),
                None => ("-".into(), c.refusal.clone().unwrap_or_default()),
            };
            let chosen = if Some(i) == r.candidate && !fallback { " (meshed)" } else { "" };
            let _ = write!(
                s,
                "<tr><td>{i}{chosen}</td><td>{}</td><td>{}</td><td class=\"{cls}\">{stage}</td><td>{:.4}</td><td>{}</td><td>{pcd}</td><td>{}</td></tr>",
                esc(&c.context.describe()),
                esc(&c.rotation),
                c.fit,
                c.score.map(|v| format!("{v:.4}")).unwrap_or("-".into()),
                esc(&reason)
            );
        }
        s.push_str("</table>");
    };
    if !fallback {
        polycube_section(&mut s);
    }
    s.push_str("<h2>Hex mesh</h2>");
    let irregular = format!("{} ({} interior, {} boundary)", num(&hx["irregular_edges"]), num(&hx["irregular_edges_interior"]), num(&hx["irregular_edges_boundary"]));
    s.push_str(&table(&[
        ("nodes", num(&hx["vertices"])),
        ("elements", num(&hx["elements"])),
        if fallback { ("lattice", num(&hx["domain"])) } else { ("octree level", num(&hx["level"])) },
        ("min scaled Jacobian", num(&hx["min_scaled_jacobian"])),
        ("mean scaled Jacobian", num(&hx["mean_scaled_jacobian"])),
        ("inverted elements", num(&hx["inverted"])),
        ("Hausdorff / bbox diagonal", percent(&hx["hausdorff_relative"])),
        ("irregular edges", irregular),
        ("volume (input)", format!("{} ({})", num(&hx["volume"]), num(&hx["input_volume"]))),
    ]));
    if hist {
        s.push_str("<p><img src=\"scaled_jacobian.png\" alt=\"scaled Jacobian histogram\"></p>");
    }
    if let Some(stages) = hx["stages"].as_array() {
        s.push_str("<table><tr><th>quality step</th><th>min SJ before</th><th>min SJ after</th><th>inverted after</th><th>seconds</th></tr>");
        for st in stages {
            let _ = write!(
                s,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                num(&st["stage"]),
                num(&st["before"]["min"]),
                num(&st["after"]["min"]),
                num(&st["after"]["inverted"]),
                num(&st["seconds"])
            );
        }
        s.push_str("</table>");
    }
    // every mesh built for the choice (polycube candidates, the fallback), with why
    // a build failed: shown when there was a choice or a failure
    if let Some(att) = hx["candidates_meshed"].as_array().filter(|a| a.len() > 1 || a.iter().any(|x| !x["error"].is_null())) {
        s.push_str("<h3>Meshes built</h3><table><tr><th>mesh</th><th>inverted</th><th>min SJ</th><th>mean SJ</th><th>Hausdorff / diagonal</th><th>goals missed</th><th>seconds</th><th>error</th></tr>");
        for a in att {
            let _ = write!(
                s,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&readable_context(a["context"].as_str().unwrap_or(""))),
                num(&a["inverted"]),
                num(&a["min_scaled_jacobian"]),
                num(&a["mean_scaled_jacobian"]),
                percent(&a["hausdorff_relative"]),
                num(&a["goals_missed"]),
                num(&a["seconds"]),
                if a["error"].is_null() { String::new() } else { num(&a["error"]) }
            );
        }
        s.push_str("</table>");
    }
    if !sp.is_null() {
        s.push_str("<h2>Spline</h2>");
        s.push_str(&table(&[
            ("elements", num(&sp["elements"])),
            ("basis functions", num(&sp["basis_functions"])),
            ("extraordinary edges", num(&sp["extraordinary_edges"])),
            ("C2 interior faces", format!("{} of {} ({:.1} %)", num(&sp["c2_faces"]), num(&sp["interior_faces"]), 100.0 * sp["c2_face_share"].as_f64().unwrap_or(0.0))),
            ("min scaled Jacobian (Gauss points)", num(&sp["min_scaled_jacobian"])),
            ("elements with det J <= 0", num(&sp["negative_jacobian_elements"])),
            ("repaired elements", num(&sp["repaired_elements"])),
            ("boundary distance after fit (max)", num(&sp["fitting_after"]["max"])),
            ("BEXT rows, operator tolerance", format!("{}, {}", if sp["bext_sparse"] == Value::Bool(true) { "sparse" } else { "dense" }, num(&sp["bext_tolerance"]))),
        ]));
    }
    if fallback {
        polycube_section(&mut s);
    }
    s.push_str("<h2>Timings</h2>");
    if timings {
        s.push_str("<p><img src=\"timings.png\" alt=\"stage timings\"></p>");
    }
    if let Some(m) = j["seconds"].as_object() {
        let rows: Vec<(&str, String)> = m.iter().map(|(k, v)| (k.as_str(), num(v))).collect();
        s.push_str(&table(&rows));
    }
    // the files this run wrote (report.json "files"): no link to a file of another run
    s.push_str("<h2>Files</h2><table id=\"files\"><tr><th>file</th><th>bytes</th><th>holds</th></tr>");
    if let Some(files) = j["files"].as_array() {
        for f in files {
            let name = esc(f["name"].as_str().unwrap_or(""));
            let _ = write!(s, "<tr><td><a href=\"{name}\">{name}</a></td><td>{}</td><td>{}</td></tr>", num(&f["bytes"]), num(&f["what"]));
        }
    }
    s.push_str("</table>");
    // provenance
    s.push_str("<h2>Provenance</h2>");
    s.push_str(&table(&[("libsddpm version", num(&j["version"])), ("command", format!("<code>{}</code>", num(&j["command"])))]));
    let opts = serde_json::to_string_pretty(&j["options"]).unwrap_or_default();
    let _ = write!(s, "<details><summary>Options of the run (report.json \"options\")</summary><pre>{}</pre></details>", esc(&opts));
    s.push_str("</body></html>\n");
    s
}

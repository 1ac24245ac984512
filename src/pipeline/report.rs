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

/// The input as report.json describes it.
pub struct InputInfo<'a> {
    pub path: &'a str,
    pub mesh: &'a TriMesh,
    pub report: &'a MeshReport,
}

/// File names inside the run folder (besides the hex and spline files).
pub const POLYCUBE_OBJ: &str = "polycube.obj";
pub const REPORT_JSON: &str = "report.json";
pub const REPORT_HTML: &str = "report.html";

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
    let cand = &r.polycube.candidates[r.candidate];
    let poly = super::polycube_user_mesh(&r.polycube, cand);
    crate::export::obj::write_obj(&dir.join(POLYCUBE_OBJ), &poly, &format!("libsddpm polycube {} (user coordinates)", cand.context))?;
    crate::export::hexfmt::write_hex_files(dir, &r.hex)?;
    let mut hex_json = crate::hex::report_json(&r.hex);
    if let Some(m) = hex_json.as_object_mut() {
        m.insert("candidates_meshed".into(), serde_json::to_value(&r.hex_attempts).unwrap_or(Value::Null));
    }
    let spline_json = match &r.spline {
        Some(sp) => crate::export::spline_files::write_outputs(dir, sp, &crate::export::spline_files::OutputOptions::default())?,
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
    let qm = crate::polycube::boundary(&cand.context.assemble());
    let pq = poly.clone();
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
    let (ht, he) = hex_boundary(&r.hex.mesh.elements);
    let he = if he.len() > 60_000 { Vec::new() } else { he };
    pic("hex.png", &[Layer::Surface { vertices: &r.hex.mesh.nodes, triangles: &ht, edges: &he, colour: [230, 180, 120] }]);
    let hist_ok = histogram_png(&dir.join("scaled_jacobian.png"), &r.hex.histogram, -1.0, 1.0, "Scaled Jacobian of the hex elements", "scaled Jacobian (Verdict)").is_ok();
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
    seconds.insert("write".into(), t_write.elapsed().as_secs_f64().into());
    let rep = input.report;
    let report = json!({
        "input": {
            "path": input.path, "vertices": rep.vertices, "triangles": rep.triangles,
            "genus": rep.genus, "volume": rep.volume, "area": rep.area,
            "bbox": [rep.bbox_min, rep.bbox_max],
        },
        "polycube": {
            "labels": cand.labels.to_vec(),
            "names": cand.context.names(),
            "source": r.polycube.source,
            "generator": r.polycube.generator,
            "candidates": r.polycube.candidates.len(),
            "verified": r.polycube.verified().count(),
            // candidates that went through the diffusion (the others were refused
            // by the pre-check or the fit limit)
            "diffused": r.polycube.candidates.iter().filter(|c| c.report.is_some()).count(),
            "genus": cand.context.validity().genus,
            "rotation": cand.rotation,
            "fit": cand.fit,
            "score": cand.score,
            "file": POLYCUBE_OBJ,
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
    let s = serde_json::to_string_pretty(&report).map_err(|e| Error::Internal(e.to_string()))?;
    write_text(&dir.join(REPORT_JSON), &s)?;
    write_text(&dir.join(REPORT_HTML), &html(&report, r, hist_ok, timing_ok))?;
    Ok(report)
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

fn html(j: &Value, r: &RunResult, hist: bool, timings: bool) -> String {
    let inp = &j["input"];
    let pc = &j["polycube"];
    let hx = &j["hex"];
    let sp = &j["spline"];
    let mut s = String::new();
    s.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>libsddpm report</title><style>\
body{font-family:DejaVu Sans,Arial,sans-serif;margin:24px;color:#222;max-width:1400px}\
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:28px}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:13px}\
th{background:#f2f2f2}.pics img{border:1px solid #ddd;margin:4px;max-width:32%}.ok{color:#1a7f37}.bad{color:#b42318}\
</style></head><body>\n");
    let _ = writeln!(s, "<h1>libsddpm report: {}</h1>", num(&inp["path"]));
    s.push_str("<h2>Input, polycube and hex mesh</h2><div class=\"pics\">");
    for (f, alt) in [("input.png", "input surface"), ("polycube.png", "chosen polycube"), ("hex.png", "hex mesh boundary")] {
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
    s.push_str("<h2>Polycube</h2>");
    if let Some(e) = &r.verification_error {
        let _ = write!(s, "<p class=\"bad\"><b>Unverified polycube.</b> No candidate passed verification ({}); the candidate with the best geometric fit was meshed instead. Revise the context, try other splitting ratios, or run with --strict to refuse.</p>", esc(e));
    }
    s.push_str(&table(&[
        ("context", num(&pc["names"])),
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
        let chosen = if i == r.candidate { " (meshed)" } else { "" };
        let _ = write!(
            s,
            "<tr><td>{i}{chosen}</td><td>{}</td><td>{}</td><td class=\"{cls}\">{stage}</td><td>{:.4}</td><td>{}</td><td>{pcd}</td><td>{}</td></tr>",
            esc(&c.context.names()),
            esc(&c.rotation),
            c.fit,
            c.score.map(|v| format!("{v:.4}")).unwrap_or("-".into()),
            esc(&reason)
        );
    }
    s.push_str("</table>");
    s.push_str("<h2>Hex mesh</h2>");
    s.push_str(&table(&[
        ("nodes", num(&hx["vertices"])),
        ("elements", num(&hx["elements"])),
        ("level", num(&hx["level"])),
        ("min scaled Jacobian", num(&hx["min_scaled_jacobian"])),
        ("mean scaled Jacobian", num(&hx["mean_scaled_jacobian"])),
        ("inverted elements", num(&hx["inverted"])),
        ("Hausdorff / bbox diagonal", num(&hx["hausdorff_relative"])),
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
                num(&a["context"]),
                num(&a["inverted"]),
                num(&a["min_scaled_jacobian"]),
                num(&a["mean_scaled_jacobian"]),
                num(&a["hausdorff_relative"]),
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
            ("min scaled Jacobian (Gauss points)", num(&sp["min_scaled_jacobian"])),
            ("elements with det J <= 0", num(&sp["negative_jacobian_elements"])),
            ("repaired elements", num(&sp["repaired_elements"])),
            ("boundary distance after fit (max)", num(&sp["fitting_after"]["max"])),
            ("files", format!("{}, {}", num(&sp["bext"]), num(&sp["lsdyna"]))),
        ]));
    }
    s.push_str("<h2>Timings</h2>");
    if timings {
        s.push_str("<p><img src=\"timings.png\" alt=\"stage timings\"></p>");
    }
    if let Some(m) = j["seconds"].as_object() {
        let rows: Vec<(&str, String)> = m.iter().map(|(k, v)| (k.as_str(), num(v))).collect();
        s.push_str(&table(&rows));
    }
    s.push_str("<h2>Files</h2><ul>");
    for f in ["polycube.obj", "hex.vtu", "hex.vtk", "hex.mesh", "hex.k", "spline.bext", "model.k", "spline.vtk", "report.json"] {
        let _ = write!(s, "<li><a href=\"{f}\">{f}</a></li>");
    }
    s.push_str("</ul></body></html>\n");
    s
}

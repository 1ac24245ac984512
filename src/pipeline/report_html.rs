//! report.html: the run folder's report as one self-contained page. Every picture
//! is embedded as a base64 data URI (the page shows them without the PNG files
//! next to it); the only links are to the files of the run (report.json "files").
//! Sections, each one function: the mesh path and the quality goals first, then
//! the input, the polycube (after the mesh when the fallback made it), the hex
//! mesh with a cut view through its mid plane, the spline, the timings, the files
//! and the provenance.

use super::RunResult;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The pictures of a run folder as data URIs, by file name.
pub struct Pictures {
    uris: Vec<(String, String)>,
}

impl Pictures {
    /// Read the PNG files `names` of `dir` (a missing or unreadable one is left out).
    pub fn load(dir: &Path, names: &[String]) -> Pictures {
        let uris = names.iter().filter_map(|n| std::fs::read(dir.join(n)).ok().map(|b| (n.clone(), format!("data:image/png;base64,{}", base64(&b))))).collect();
        Pictures { uris }
    }

    fn get(&self, name: &str) -> Option<&str> {
        self.uris.iter().find(|(n, _)| n == name).map(|(_, u)| u.as_str())
    }

    /// An `<img>` of picture `name` (nothing when it was not written).
    fn img(&self, name: &str, alt: &str) -> String {
        match self.get(name) {
            Some(u) => format!("<img src=\"{u}\" alt=\"{alt}\" title=\"{alt}\" data-file=\"{name}\">"),
            None => String::new(),
        }
    }
}

/// Standard base64 (RFC 4648, with padding).
pub fn base64(b: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(b.len().div_ceil(3) * 4);
    for c in b.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}


const STYLE: &str = "<style>\
body{font-family:DejaVu Sans,Arial,sans-serif;margin:24px;color:#222;max-width:1400px}\
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:28px}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:13px}\
th{background:#f2f2f2}.pics img{border:1px solid #ddd;margin:4px;max-width:32%}.ok{color:#1a7f37}.bad{color:#b42318}\
.note{color:#8a5a00}.path{font-size:16px;padding:8px 12px;border:1px solid #ccc;background:#f7f7f7;display:inline-block}\
code{font-size:12px;word-break:break-all}\
</style>";

/// The page of report.json `j` for the run `r`, its pictures embedded.
pub fn html(j: &Value, r: &RunResult, pics: &Pictures) -> String {
    let fallback = !r.hex.from_polycube();
    let mut s = String::new();
    let _ = write!(s, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>libsddpm report</title>{STYLE}</head><body>\n");
    let _ = writeln!(s, "<h1>libsddpm report: {}</h1>", num(&j["input"]["path"]));
    path_and_goals(&mut s, j, r);
    input_section(&mut s, j, pics, fallback);
    if !fallback {
        polycube_section(&mut s, j, r, pics);
    }
    hex_section(&mut s, j, r, pics);
    spline_section(&mut s, &j["spline"]);
    if fallback {
        polycube_section(&mut s, j, r, pics);
    }
    timings_section(&mut s, j, pics);
    files_section(&mut s, j);
    provenance_section(&mut s, j);
    s.push_str("</body></html>\n");
    s
}

/// The answer first: where the mesh comes from and whether it meets each goal.
fn path_and_goals(s: &mut String, j: &Value, r: &RunResult) {
    let path = &j["mesh_path"];
    let made = if r.hex.from_polycube() {
        format!("polycube {}", esc(&r.candidate.map(|c| r.polycube.candidates[c].context.describe()).unwrap_or_default()))
    } else {
        format!("lattice {}", esc(path["domain"].as_str().unwrap_or("?")))
    };
    let _ = write!(
        s,
        "<p class=\"path\" id=\"mesh-path\"><b>Mesh made by: {}</b> ({made})</p><p>{}</p>",
        esc(path["from"].as_str().unwrap_or("?")),
        esc(path["why"].as_str().unwrap_or(""))
    );
    s.push_str("<h2>Quality goals</h2><table id=\"goals\"><tr><th>goal</th><th>target</th><th>value</th><th>result</th></tr>");
    for g in j["hex"]["goals"].as_array().into_iter().flatten() {
        let value = if g["goal"].as_str().is_some_and(|n| n.starts_with("Hausdorff")) { percent(&g["value"]) } else { num(&g["value"]) };
        let _ = write!(s, "<tr><td>{}</td><td>{}</td><td>{}</td>{}</tr>", num(&g["goal"]), num(&g["target"]), value, mark(g["met"].as_bool() == Some(true)));
    }
    s.push_str("</table>");
}

fn input_section(s: &mut String, j: &Value, pics: &Pictures, fallback: bool) {
    let inp = &j["input"];
    s.push_str("<h2>Input and hex mesh</h2><div class=\"pics\">");
    s.push_str(&pics.img("input.png", "input surface"));
    if !fallback {
        s.push_str(&pics.img("polycube.png", "chosen polycube"));
    }
    s.push_str(&pics.img("hex.png", "hex mesh boundary"));
    s.push_str("</div>");
    s.push_str(&table(&[
        ("vertices", num(&inp["vertices"])),
        ("triangles", num(&inp["triangles"])),
        ("genus", num(&inp["genus"])),
        ("volume", num(&inp["volume"])),
        ("area", num(&inp["area"])),
    ]));
}

fn polycube_section(s: &mut String, j: &Value, r: &RunResult, pics: &Pictures) {
    let pc = &j["polycube"];
    if !r.hex.from_polycube() {
        s.push_str("<h2>Polycube (not used for the mesh)</h2><p>The polycube candidates below were generated and meshed, but the grid-based fallback's mesh ranked better; this section is for reference.</p>");
        let _ = write!(s, "<div class=\"pics\">{}</div>", pics.img("polycube.png", "best polycube candidate"));
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
    candidates_table(s, r);
}

/// The best 40 candidates by stage and score.
fn candidates_table(s: &mut String, r: &RunResult) {
    use crate::search::generate::Stage::*;
    s.push_str("<h3>Candidates (best 40 by stage and score)</h3><table><tr><th>#</th><th>context</th><th>rotation</th><th>stage</th><th>fit</th><th>score</th><th>mean target PCD</th><th>reason</th></tr>");
    let rank = |st: crate::search::generate::Stage| match st {
        Verified => 0,
        Tcv => 1,
        Gocc => 2,
        Pending => 3,
        Occupancy => 4,
    };
    let cands = &r.polycube.candidates;
    let mut idx: Vec<usize> = (0..cands.len()).collect();
    idx.sort_by(|&a, &b| {
        let (ca, cb) = (&cands[a], &cands[b]);
        (rank(ca.stage), ca.score.unwrap_or(ca.fit)).partial_cmp(&(rank(cb.stage), cb.score.unwrap_or(cb.fit))).unwrap_or(std::cmp::Ordering::Equal)
    });
    for &i in idx.iter().take(40) {
        let c = &cands[i];
        let stage = serde_json::to_value(c.stage).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default();
        let cls = if stage == "verified" { "ok" } else { "bad" };
        let (pcd, reason) = match &c.report {
            Some(rep) => (format!("{:.4}", rep.mean_target_pcd), rep.reason.clone().unwrap_or_default()),
            None => ("-".into(), c.refusal.clone().unwrap_or_default()),
        };
        let chosen = if Some(i) == r.candidate && r.hex.from_polycube() { " (meshed)" } else { "" };
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
}

fn hex_section(s: &mut String, j: &Value, r: &RunResult, pics: &Pictures) {
    let hx = &j["hex"];
    s.push_str("<h2>Hex mesh</h2>");
    let irregular = format!("{} ({} interior, {} boundary)", num(&hx["irregular_edges"]), num(&hx["irregular_edges_interior"]), num(&hx["irregular_edges_boundary"]));
    s.push_str(&table(&[
        ("nodes", num(&hx["vertices"])),
        ("elements", num(&hx["elements"])),
        if r.hex.from_polycube() { ("octree level", num(&hx["level"])) } else { ("lattice", num(&hx["domain"])) },
        ("mean edge length", num(&hx["mean_edge_length"])),
        ("min scaled Jacobian", num(&hx["min_scaled_jacobian"])),
        ("mean scaled Jacobian", num(&hx["mean_scaled_jacobian"])),
        ("inverted elements", num(&hx["inverted"])),
        ("Hausdorff / bbox diagonal", percent(&hx["hausdorff_relative"])),
        ("irregular edges", irregular),
        ("volume (input)", format!("{} ({})", num(&hx["volume"]), num(&hx["input_volume"]))),
    ]));
    if pics.get("cut.png").is_some() {
        let _ = write!(
            s,
            "<h3>Cut view</h3><p id=\"cut-view\">{}<br>The elements behind the mid plane {}; elements below the minimum scaled Jacobian goal in red.</p>",
            pics.img("cut.png", "hex elements cut by the mid plane"),
            esc(j["cut_view"]["plane"].as_str().unwrap_or(""))
        );
    }
    let _ = write!(s, "<p>{}</p>", pics.img("scaled_jacobian.png", "scaled Jacobian histogram"));
    stages_table(s, hx);
    attempts_table(s, hx);
}

fn stages_table(s: &mut String, hx: &Value) {
    let Some(stages) = hx["stages"].as_array() else { return };
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

/// Every mesh built for the choice (polycube candidates, the fallback), with why a
/// build failed: shown when there was a choice or a failure.
fn attempts_table(s: &mut String, hx: &Value) {
    let Some(att) = hx["candidates_meshed"].as_array().filter(|a| a.len() > 1 || a.iter().any(|x| !x["error"].is_null())) else { return };
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

fn spline_section(s: &mut String, sp: &Value) {
    if sp.is_null() {
        return;
    }
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
        ("sampled file, cells per element edge", format!("{}, {}", num(&sp["vtu"]), num(&sp["sample_cells_per_edge"]))),
    ]));
}

fn timings_section(s: &mut String, j: &Value, pics: &Pictures) {
    s.push_str("<h2>Timings</h2>");
    let _ = write!(s, "<p>{}</p>", pics.img("timings.png", "stage timings"));
    if let Some(m) = j["seconds"].as_object() {
        let rows: Vec<(&str, String)> = m.iter().map(|(k, v)| (k.as_str(), num(v))).collect();
        s.push_str(&table(&rows));
    }
}

/// The files this run wrote (report.json "files") with their sizes and the total:
/// no link to a file of another run.
fn files_section(s: &mut String, j: &Value) {
    s.push_str("<h2>Files</h2><table id=\"files\"><tr><th>file</th><th>bytes</th><th>holds</th></tr>");
    for f in j["files"].as_array().into_iter().flatten() {
        let name = esc(f["name"].as_str().unwrap_or(""));
        let _ = write!(s, "<tr><td><a href=\"{name}\">{name}</a></td><td>{}</td><td>{}</td></tr>", num(&f["bytes"]), num(&f["what"]));
    }
    let _ = write!(s, "<tr><th>total</th><th>{}</th><th></th></tr></table>", num(&j["files_bytes"]));
}

fn provenance_section(s: &mut String, j: &Value) {
    s.push_str("<h2>Provenance</h2>");
    s.push_str(&table(&[("libsddpm version", num(&j["version"])), ("command", format!("<code>{}</code>", num(&j["command"])))]));
    let opts = serde_json::to_string_pretty(&j["options"]).unwrap_or_default();
    let _ = write!(s, "<details><summary>Options of the run (report.json \"options\")</summary><pre>{}</pre></details>", esc(&opts));
    let outs = serde_json::to_string_pretty(&j["outputs"]).unwrap_or_default();
    let _ = write!(s, "<details><summary>Options of the files (report.json \"outputs\")</summary><pre>{}</pre></details>", esc(&outs));
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

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

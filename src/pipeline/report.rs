//! The run folder of the main job (DESIGN.md "Command line"): polycube.obj, the hex
//! files, the spline files, report.json and report.html (one self-contained page,
//! [`super::report_html`]) with its PNG pictures and plots. Used by `sddpm run` and available to every caller of [`super::run`].

use super::RunResult;
use crate::error::{Error, Result};
use crate::export::plot::{bars_png, histogram_png};
use crate::export::render::{hex_boundary, render_png, Camera, Layer};
use crate::mesh::{MeshReport, TriMesh};
use super::report_html::{html, Pictures};
use crate::export::spline_files::OutputOptions;
use serde_json::{json, Value};
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
    ("hex.k", "LS-DYNA deck of the hex mesh: nodes, solid elements, part, section, material, analysis"),
    ("spline.bext", "the volumetric spline: control points and Bézier extraction operators (BEXT)"),
    ("model.k", "LS-DYNA IGA deck that includes spline.bext"),
    ("spline.vtu", "the spline sampled per element with its Jacobian (binary VTK XML; ParaView, VTK, meshio)"),
    ("spline.vtk", "the spline sampled per element with its Jacobian (binary legacy VTK)"),
    ("spline_control.vtk", "the spline's control mesh (legacy VTK)"),
    ("input.png", "picture of the input surface"),
    ("polycube.png", "picture of the chosen polycube"),
    ("hex.png", "picture of the hex mesh's boundary"),
    ("cut.png", "the hex elements behind the mid plane, those below the minimum scaled Jacobian goal in red"),
    ("scaled_jacobian.png", "histogram of the elements' scaled Jacobian (log counts, goal line)"),
    ("timings.png", "chart of the stage timings"),
    (REPORT_JSON, "the run's figures, options, provenance and this list of files (JSON)"),
    (REPORT_HTML, "this report, one self-contained page (pictures embedded)"),
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

/// Write every file of the run folder and return report.json's content.
/// `files`: the spline files' names and settings and the decks' options (model.k
/// and hex.k). `total_seconds` is the caller's wall clock for the whole job
/// (loading included).
pub fn write_run_folder(dir: &Path, input: &InputInfo, r: &RunResult, files: &OutputOptions, total_seconds: f64) -> Result<Value> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    let t_write = std::time::Instant::now();
    // the files written, in order (report.json's "files")
    let mut written: Vec<String> = Vec::new();
    let (hex_json, spline_json) = write_mesh_files(dir, r, files, &mut written)?;
    let (mut pictures, cut) = write_pictures(dir, input, r);
    pictures.extend(write_plots(dir, r, t_write));
    written.extend(pictures.iter().cloned());
    let mut seconds = serde_json::Map::new();
    seconds.insert("total".into(), total_seconds.into());
    for (k, v) in r.seconds.iter().cloned().chain(crate::hex::report::stage_seconds(&r.hex)) {
        seconds.insert(k, v.into());
    }
    seconds.insert("write".into(), t_write.elapsed().as_secs_f64().into());
    let mut report = report_json(input, r, hex_json, spline_json);
    report["seconds"] = Value::Object(seconds);
    report["pictures"] = json!(pictures);
    report["cut_view"] = cut;
    report["outputs"] = serde_json::to_value(files).unwrap_or(Value::Null);
    write_reports(dir, &written, &mut report, r, &Pictures::load(dir, &pictures))?;
    Ok(report)
}

/// polycube.obj, the hex files and the spline files; the "hex" and "spline"
/// objects of report.json.
fn write_mesh_files(dir: &Path, r: &RunResult, files: &OutputOptions, written: &mut Vec<String>) -> Result<(Value, Value)> {
    // no candidate was formed for a part the grid cannot hold: no polycube.obj,
    // polycube.png or polycube labels then
    if let Some(cand) = r.candidate.map(|c| &r.polycube.candidates[c]) {
        let poly = super::polycube_user_mesh(&r.polycube, cand);
        crate::export::obj::write_obj(&dir.join(POLYCUBE_OBJ), &poly, &format!("libsddpm polycube {} (user coordinates)", cand.context))?;
        written.push(POLYCUBE_OBJ.into());
    }
    crate::export::hexfmt::write_hex_files(dir, &r.hex, &files.deck)?;
    use crate::hex::report::{HEX_K, HEX_MESH, HEX_VTK, HEX_VTU};
    written.extend([HEX_VTU, HEX_VTK, HEX_MESH, HEX_K].map(String::from));
    let mut hex_json = crate::hex::report_json(&r.hex);
    if let Some(m) = hex_json.as_object_mut() {
        m.insert("candidates_meshed".into(), serde_json::to_value(&r.hex_attempts).unwrap_or(Value::Null));
        m.insert("mean_edge_length".into(), json!(mean_edge_length(&r.hex.mesh)));
        m.insert("goals".into(), goal_rows(r));
    }
    let spline_json = match &r.spline {
        Some(sp) => {
            let j = crate::export::spline_files::write_outputs(dir, sp, files)?;
            written.extend([Some(&files.bext), Some(&files.lsdyna), files.vtu.as_ref(), files.vtk.as_ref(), files.control_vtk.as_ref()].into_iter().flatten().cloned());
            j
        }
        None => Value::Null,
    };
    Ok((hex_json, spline_json))
}

/// The mean length of the hex mesh's element edges (each element's 12 edges;
/// shared edges counted once per element), in model units.
pub fn mean_edge_length(m: &crate::hex::HexMesh) -> f64 {
    const EDGES: [(usize, usize); 12] = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)];
    let mut sum = 0.0;
    for e in &m.elements {
        for (a, b) in EDGES {
            let (p, q) = (m.nodes[e[a] as usize], m.nodes[e[b] as usize]);
            sum += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        }
    }
    if m.elements.is_empty() {
        0.0
    } else {
        sum / (12 * m.elements.len()) as f64
    }
}

/// report.json's "hex.goals": each quality goal with its target, value and mark.
fn goal_rows(r: &RunResult) -> Value {
    let goals = &r.options.hex.goals;
    let q = &r.hex.quality;
    json!([
        { "goal": "no inverted element", "target": "inverted = 0", "value": q.inverted, "met": q.inverted == 0 },
        { "goal": "minimum scaled Jacobian", "target": format!(">= {}", goals.min_scaled_jacobian), "value": q.min, "met": q.min >= goals.min_scaled_jacobian },
        { "goal": "mean scaled Jacobian", "target": format!(">= {}", goals.mean_scaled_jacobian), "value": q.mean, "met": q.mean >= goals.mean_scaled_jacobian },
        { "goal": "Hausdorff distance / bounding-box diagonal", "target": format!("<= {} %", 100.0 * goals.hausdorff), "value": r.hex.hausdorff_relative, "met": r.hex.hausdorff_relative <= goals.hausdorff },
    ])
}

/// The pictures of the input, the polycube, the hex mesh and the cut view (those
/// that rendered), with report.json's "cut_view".
fn write_pictures(dir: &Path, input: &InputInfo, r: &RunResult) -> (Vec<String>, Value) {
    let mut pictures = Vec::new();
    let cam = Camera::default();
    let mut pic = |name: &str, layers: &[Layer]| {
        if render_png(&dir.join(name), layers, 640, 480, cam).is_ok() {
            pictures.push(name.to_string());
        }
    };
    pic("input.png", &[Layer::Surface { vertices: &input.mesh.vertices, triangles: &input.mesh.triangles, edges: &[], colour: [200, 200, 210] }]);
    if let Some(cand) = r.candidate.map(|c| &r.polycube.candidates[c]) {
        let pq = super::polycube_user_mesh(&r.polycube, cand);
        let pedges = polycube_edges(cand, &pq);
        pic("polycube.png", &[Layer::Surface { vertices: &pq.vertices, triangles: &pq.triangles, edges: &pedges, colour: [120, 170, 230] }]);
    }
    let (ht, he) = hex_boundary(&r.hex.mesh.elements);
    let he = if he.len() > 60_000 { Vec::new() } else { he };
    pic("hex.png", &[Layer::Surface { vertices: &r.hex.mesh.nodes, triangles: &ht, edges: &he, colour: [230, 180, 120] }]);
    let cut = cut_view(r);
    let (good, bad) = (hex_boundary(&cut.good), hex_boundary(&cut.bad));
    let edges = |e: Vec<[u32; 2]>| if e.len() > 60_000 { Vec::new() } else { e };
    let (ge, be) = (edges(good.1), edges(bad.1));
    let mut layers = vec![Layer::Surface { vertices: &r.hex.mesh.nodes, triangles: &good.0, edges: &ge, colour: [230, 180, 120] }];
    if !cut.bad.is_empty() {
        layers.push(Layer::Surface { vertices: &r.hex.mesh.nodes, triangles: &bad.0, edges: &be, colour: [220, 40, 40] });
    }
    if !cut.good.is_empty() || !cut.bad.is_empty() {
        pic("cut.png", &layers);
    }
    let plane = format!("{} = {:.6}", ["x", "y", "z"][cut.axis], cut.at);
    (pictures, json!({ "file": "cut.png", "plane": plane, "elements": cut.good.len() + cut.bad.len(), "below_goal": cut.bad.len() }))
}

/// The quad edges of the polycube boundary (its triangles come two per quad).
fn polycube_edges(cand: &crate::search::generate::Candidate, pq: &TriMesh) -> Vec<[u32; 2]> {
    let qm = crate::polycube::boundary(&cand.context.assemble());
    if pq.vertices.len() != qm.vertices.len() {
        return Vec::new();
    }
    let mut e = std::collections::BTreeSet::new();
    for q in &qm.quads {
        for i in 0..4 {
            let (a, b) = (q[i], q[(i + 1) % 4]);
            e.insert([a.min(b), a.max(b)]);
        }
    }
    e.into_iter().collect()
}

/// The hex elements behind the mid plane, split by the minimum scaled Jacobian goal.
struct Cut {
    axis: usize,
    at: f64,
    good: Vec<[u32; 8]>,
    bad: Vec<[u32; 8]>,
}

/// The cut of the report's picture: the plane through the middle of the mesh's
/// bounding box across y (the axis that faces the default camera most), the
/// elements whose centroid lies behind it (y >= the middle) kept, so that the cut
/// face looks at the camera and shows the elements inside.
fn cut_view(r: &RunResult) -> Cut {
    let m = &r.hex.mesh;
    let axis = 1;
    let (lo, hi) = m.nodes.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[axis]), hi.max(p[axis])));
    let at = 0.5 * (lo + hi);
    let goal = r.options.hex.goals.min_scaled_jacobian;
    let mut cut = Cut { axis, at, good: Vec::new(), bad: Vec::new() };
    for (k, e) in m.elements.iter().enumerate() {
        let c = e.iter().map(|&v| m.nodes[v as usize][axis]).sum::<f64>() / 8.0;
        if c >= at {
            let q = r.hex.scaled_jacobian.get(k).copied().unwrap_or(1.0);
            if q >= goal { cut.good.push(*e) } else { cut.bad.push(*e) }
        }
    }
    cut
}

/// The histogram of the scaled Jacobian and the chart of the stage timings (those
/// that rendered).
fn write_plots(dir: &Path, r: &RunResult, t_write: std::time::Instant) -> Vec<String> {
    let mut out = Vec::new();
    let goal_min = r.options.hex.goals.min_scaled_jacobian;
    let label = format!("goal: min >= {goal_min}");
    if histogram_png(&dir.join("scaled_jacobian.png"), &r.hex.histogram, -1.0, 1.0, "Scaled Jacobian of the hex elements", "scaled Jacobian (Verdict)", Some((goal_min, &label))).is_ok() {
        out.push("scaled_jacobian.png".to_string());
    }
    let mut bars: Vec<(String, f64)> = r.seconds.clone();
    bars.push(("write outputs".into(), t_write.elapsed().as_secs_f64()));
    if bars_png(&dir.join("timings.png"), &bars, "Stage timings", "seconds").is_ok() {
        out.push("timings.png".to_string());
    }
    out
}

/// report.json without the pictures, timings and manifest.
fn report_json(input: &InputInfo, r: &RunResult, hex_json: Value, spline_json: Value) -> Value {
    let cand = r.candidate.map(|c| &r.polycube.candidates[c]);
    let rep = input.report;
    let from_polycube = r.hex.from_polycube();
    json!({
        "version": env!("CARGO_PKG_VERSION"),
        "command": input.command.unwrap_or(LIBRARY_COMMAND),
        "options": serde_json::to_value(&r.options).unwrap_or(Value::Null),
        "mesh_path": {
            "from": if from_polycube { "polycube" } else { "grid-based fallback" },
            "domain": r.hex.domain,
            "polycube": cand.filter(|_| from_polycube).map(|c| c.context.describe()),
            "verified": r.verified,
            "why": mesh_path_reason(r),
        },
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
    })
}

/// report.json and report.html with the manifest of every file written, the two
/// reports included, whose sizes depend on the manifest itself: rendered until the
/// sizes they state hold. "files_bytes" is the total.
fn write_reports(dir: &Path, written: &[String], report: &mut Value, r: &RunResult, pics: &Pictures) -> Result<()> {
    let mut sizes = (0u64, 0u64);
    let (mut json_text, mut html_text) = (String::new(), String::new());
    for _ in 0..8 {
        let mut files: Vec<Value> = written.iter().map(|f| manifest_entry(dir, f)).collect();
        files.push(json!({ "name": REPORT_JSON, "bytes": sizes.0, "what": describe_output(REPORT_JSON) }));
        files.push(json!({ "name": REPORT_HTML, "bytes": sizes.1, "what": describe_output(REPORT_HTML) }));
        report["files_bytes"] = json!(files.iter().filter_map(|f| f["bytes"].as_u64()).sum::<u64>());
        report["files"] = Value::Array(files);
        json_text = serde_json::to_string_pretty(&report).map_err(|e| Error::Internal(e.to_string()))?;
        html_text = html(report, r, pics);
        let now = (json_text.len() as u64, html_text.len() as u64);
        if now == sizes {
            break;
        }
        sizes = now;
    }
    write_text(&dir.join(REPORT_JSON), &json_text)?;
    write_text(&dir.join(REPORT_HTML), &html_text)
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

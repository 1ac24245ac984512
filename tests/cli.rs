//! `sddpm info` as DESIGN.md specifies: exit 0 with measurements, exit 2 with
//! `error: <what>` on stderr for a mesh that cannot go on, one JSON object with --json.

use std::process::Command;

fn sddpm(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sddpm"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run sddpm");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn info_on_a_good_mesh() {
    let (code, out, err) = sddpm(&["info", "tests/data/meshes/cgal_hole.off"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("genus:                1"), "{out}");
    assert!(out.contains("closed:               yes"), "{out}");
    let (code, out, _) = sddpm(&["info", "tests/data/meshes/cgal_eight.off", "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    for key in ["vertices", "triangles", "components", "closed", "manifold", "oriented", "genus", "volume", "area", "bbox"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["genus"], 2);
    assert_eq!(v["ok"], true);
    assert_eq!(out.trim().lines().count(), 1);
}

#[test]
fn info_refuses_with_exit_2() {
    let (code, out, err) = sddpm(&["info", "tests/data/meshes/bad/cgal_mech-holes-shark.off"]);
    assert_eq!(code, 2);
    assert!(out.contains("boundary edges"), "prints what it measured first: {out}");
    assert!(err.starts_with("error: ") && err.contains("304 boundary edges"), "{err}");
    let (code, out, err) = sddpm(&["info", "--json", "tests/data/meshes/bad/cgal_cow.off"]);
    assert_eq!(code, 2);
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["ok"], false);
    assert_eq!(v["non_manifold_vertices"], 1);
    assert!(err.starts_with("error: "));
    let (code, out, err) = sddpm(&["info", "--json", "no/such/file.obj"]);
    assert_eq!(code, 2);
    assert!(err.starts_with("error: ") && err.contains("no/such/file.obj"));
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["status"], "IO");
    let (code, _, err) = sddpm(&["info"]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn info_repair_is_explicit() {
    let (code, _, _) = sddpm(&["info", "tests/data/meshes/bad/cgal_oblong-shuffled.off"]);
    assert_eq!(code, 2);
    let (code, out, err) = sddpm(&["info", "--repair-orientation", "tests/data/meshes/bad/cgal_oblong-shuffled.off"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("re-oriented"), "{out}");
}

/// The main job end to end on a genus-1 part with a complete context: every file of
/// DESIGN.md, report.json's keys, a valid hex mesh and spline, a report.html whose
/// pictures exist and are not blank.
#[test]
fn run_writes_the_whole_run_folder() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let (code, out, err) = sddpm(&["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "--level", "1", "--json", "-q"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    for f in ["polycube.obj", "hex.vtu", "hex.vtk", "hex.mesh", "hex.k", "spline.bext", "model.k", "spline.vtu", "report.json", "report.html", "scaled_jacobian.png", "input.png", "polycube.png", "hex.png", "cut.png"] {
        let p = dir.join(f);
        assert!(p.is_file() && std::fs::metadata(&p).unwrap().len() > 0, "missing {f}");
    }
    assert!(!dir.join("spline.vtk").exists(), "the sampled spline is spline.vtu only");
    // spline.vtu: 2 sub-cells per element edge by default, 8 cells per element
    let vtu = sddpm::export::spline_vtu::parse_spline_vtu(&std::fs::read(dir.join("spline.vtu")).unwrap()).unwrap();
    let types = vtu.iter().find(|a| a.name == "types").unwrap();
    assert_eq!(types.values.len() as u64, 8 * v["spline"]["elements"].as_u64().unwrap());
    assert_eq!(v["spline"]["sample_cells_per_edge"], 2);
    for k in ["path", "vertices", "triangles", "genus", "volume"] {
        assert!(!v["input"][k].is_null(), "input.{k}");
    }
    for k in ["labels", "source", "candidates", "verified", "diffused", "genus"] {
        assert!(!v["polycube"][k].is_null(), "polycube.{k}");
    }
    // verified <= diffused <= candidates: only diffused candidates can be verified
    let count = |k: &str| v["polycube"][k].as_u64().unwrap();
    assert!(count("verified") <= count("diffused") && count("diffused") <= count("candidates"), "{}", v["polycube"]);
    for k in ["vertices", "elements", "min_scaled_jacobian", "mean_scaled_jacobian", "inverted", "hausdorff_relative", "file"] {
        assert!(!v["hex"][k].is_null(), "hex.{k}");
    }
    for k in ["elements", "basis_functions", "bext", "lsdyna"] {
        assert!(!v["spline"][k].is_null(), "spline.{k}");
    }
    assert!(v["seconds"]["total"].as_f64().unwrap() > 0.0);
    assert_eq!(v["input"]["genus"], 1);
    assert_eq!(v["polycube"]["genus"], 1);
    assert_eq!(v["polycube"]["labels"][0], 2, "THC+Z is label 2");
    // the hex stage never returns inverted elements on this part (BENCHMARKS.md)
    assert_eq!(v["hex"]["inverted"], 0);
    assert!(v["hex"]["min_scaled_jacobian"].as_f64().unwrap() > 0.2);
    assert!(v["hex"]["hausdorff_relative"].as_f64().unwrap() < 0.01);
    assert_eq!(v["spline"]["elements"], v["hex"]["elements"]);
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    for needle in ["data-file=\"scaled_jacobian.png\"", "data-file=\"hex.png\"", "data-file=\"cut.png\"", "id=\"cut-view\"", "min scaled Jacobian", "THC+Z at (0,0,0)", "Mesh made by: polycube", "goal-pass", "irregular edges", "Provenance"] {
        assert!(html.contains(needle), "report.html lacks {needle}");
    }
    assert!(!html.contains("THC+Z,null"), "contexts are readable");
    // one self-contained page: every picture a data URI, links only to the run's files
    let srcs: Vec<&str> = html.split(" src=\"").skip(1).map(|t| &t[..t.find('"').unwrap()]).collect();
    assert!(srcs.len() >= 6 && srcs.iter().all(|u| u.starts_with("data:image/png;base64,")), "{:?}", srcs.iter().map(|u| &u[..u.len().min(40)]).collect::<Vec<_>>());
    let names: Vec<&str> = v["files"].as_array().unwrap().iter().map(|f| f["name"].as_str().unwrap()).collect();
    for href in html.split("href=\"").skip(1).map(|t| &t[..t.find('"').unwrap()]) {
        assert!(names.contains(&href), "a link to {href}, not a file of the run");
    }
    assert!(!html.contains("http://") && !html.contains("https://"), "no external link");
    assert_eq!(v["cut_view"]["file"], "cut.png");
    assert!(v["cut_view"]["elements"].as_u64().unwrap() > 0);
    // the sizes of every file and their total
    let total: u64 = v["files"].as_array().unwrap().iter().map(|f| f["bytes"].as_u64().unwrap()).sum();
    assert_eq!(v["files_bytes"].as_u64().unwrap(), total);
    assert!(v["hex"]["mean_edge_length"].as_f64().unwrap() > 0.0);
    // provenance: version, command line, options
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert!(v["command"].as_str().unwrap().contains("run tests/data/meshes/cgal_hole.off"), "{}", v["command"]);
    assert_eq!(v["options"]["hex_candidates"], 4);
    assert_eq!(v["options"]["spline"]["sparse_bext"], true);
    assert_eq!(v["mesh_path"]["from"], "polycube");
    assert_eq!(v["hex"]["goals"].as_array().unwrap().len(), 4);
    assert!(v["hex"]["irregular_edges"].is_u64());
    // hex.k is a keyword deck that runs alone, with as many elements as the report says
    let k = std::fs::read_to_string(dir.join("hex.k")).unwrap();
    assert!(k.starts_with("*KEYWORD") && k.contains("*NODE") && k.contains("*ELEMENT_SOLID") && k.trim_end().ends_with("*END"));
    for kw in ["*PART", "*SECTION_SOLID", "*MAT_ELASTIC", "*CONTROL_IMPLICIT_EIGENVALUE"] {
        assert!(k.contains(kw), "hex.k lacks {kw}");
    }
    assert_eq!(sddpm::export::hexfmt::parse_lsdyna(&k).unwrap().elements.len() as u64, v["hex"]["elements"].as_u64().unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The fallback's options from the command line: a fixed coarse lattice with the
/// coverage step besides the default sharp-edge capture (hepta at HexGen's element
/// count, BENCHMARKS.md "Sharp-edge capture": 1,384 elements at 1.49 %, minimum
/// at least HexGen's), and without the capture; bad values refused.
#[test]
fn run_takes_the_fallback_options() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-fallback-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    // the last run's report.json
    let last_report = || -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap() };
    let common = ["run", "tests/data/meshes/hexgen_hepta.obj", "-o", d, "--labels", "cube,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "--no-spline", "--json", "-q", "--force"];
    // a looser distance goal (2.5 %) that the first lattice meets: no finer one
    // follows (the default goal, 1 %, refines it; hepta at 12 voxels with the
    // coverage step is 1.5-1.9 % away)
    let args: Vec<&str> = common.iter().copied().chain(["--voxel-resolution", "12", "--pin-uncovered", "0.6", "--goal-hausdorff", "0.025"]).collect();
    let (code, out, err) = sddpm(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    assert_eq!(v["hex"]["domain"], "voxel 12", "{}", v["hex"]);
    assert_eq!(v["hex"]["inverted"], 0);
    assert!(v["hex"]["hausdorff_relative"].as_f64().unwrap() < 0.025, "{}", v["hex"]);
    // side by side with HexGen's published mesh of the part (reference_hex, its
    // scaled Jacobian measured by the same code, 944 elements, minimum 0.242):
    // at a comparable element count (at most 1.5x; 1,384 measured) the minimum is
    // at least HexGen's (0.411 measured; BENCHMARKS.md "At HexGen's element counts")
    let hexgen = sddpm::export::vtk::read_vtk_legacy(std::path::Path::new("tests/data/meshes/reference_hex/hexgen_hepta_hex.vtk")).unwrap();
    let hexgen_min = sddpm::hex::quality::summarize(&sddpm::hex::quality::element_qualities(&hexgen)).min;
    assert!((hexgen_min - 0.242).abs() < 5e-4, "{hexgen_min}");
    let elements = v["hex"]["elements"].as_u64().unwrap() as f64;
    assert!(elements <= 1.5 * hexgen.elements.len() as f64, "{elements} against {}", hexgen.elements.len());
    assert!(v["hex"]["min_scaled_jacobian"].as_f64().unwrap() >= hexgen_min, "{}", v["hex"]);
    let report = last_report();
    // the report says the fallback made the mesh, and does not lead with the unused polycube
    assert_eq!(report["mesh_path"]["from"], "grid-based fallback", "{}", report["mesh_path"]);
    assert!(report["mesh_path"]["why"].as_str().unwrap().contains("grid-based fallback"), "{}", report["mesh_path"]);
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("Mesh made by: grid-based fallback") && html.contains("lattice voxel 12"), "report.html lacks the path");
    assert!(html.contains("Polycube (not used for the mesh)") && !html.contains("Unverified polycube"));
    assert!(html.find("Polycube (not used").unwrap() > html.find("<h2>Hex mesh</h2>").unwrap(), "the unused polycube comes after the mesh");
    assert!(html.contains("&#10004; met"), "goal marks");
    // the 12-voxel lattice, then again with its planes on the input's faces
    // (hepta's base, ledge, top and flat side; 3.5 % away there: not kept)
    let meshed = report["hex"]["stages"][0]["details"]["lattices_meshed"].as_array().unwrap();
    assert_eq!(meshed.len(), 2, "{meshed:?}");
    assert!(meshed[0]["planes_on_faces"].is_null() && meshed[1]["planes_on_faces"] == serde_json::json!(true), "{meshed:?}");
    assert!(meshed.iter().all(|m| m["resolution"] == 12), "{meshed:?}");
    let stages: Vec<&str> = report["hex"]["stages"].as_array().unwrap().iter().map(|s| s["stage"].as_str().unwrap()).collect();
    assert!(stages.contains(&"capture") && stages.contains(&"coverage") && stages.contains(&"recapture"), "{stages:?}");
    // the capture after the optimisation is kept only when it brings the boundary closer
    let re = report["hex"]["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "recapture").unwrap();
    let d = &re["details"];
    assert_eq!(d["kept"], serde_json::json!(true), "{d}");
    assert!(d["hausdorff_relative_after"].as_f64().unwrap() < d["hausdorff_relative_before"].as_f64().unwrap(), "{d}");
    // the coverage step's pins slide again in the boundary mean ascent, whose fit
    // guard keeps the vertices they reached (82 released, mean 0.877 -> 0.886,
    // 1.50 -> 1.42 % measured)
    let ba = report["hex"]["stages"].as_array().unwrap().iter().find(|s| s["stage"] == "boundary ascent").unwrap();
    let d = &ba["details"];
    assert!(d["pins_released"].as_u64().unwrap() > 0 && d["kept"] == serde_json::json!(true), "{d}");
    assert!(d["hausdorff_relative_after"].as_f64().unwrap() <= d["hausdorff_relative_before"].as_f64().unwrap(), "{d}");
    // --no-capture-features: neither capture step; --local-refinement 1: the
    // 12-voxel lattice is meshed a second time with some voxels split;
    // --lattice-planes 0: not with its planes on the faces
    let args: Vec<&str> = common.iter().copied().chain(["--voxel-resolution", "12", "--voxel-refinements", "0", "--no-capture-features", "--local-refinement", "1", "--lattice-planes", "0"]).collect();
    let (code, _, err) = sddpm(&args);
    assert_eq!(code, 0, "{err}");
    let report = last_report();
    let stages: Vec<&str> = report["hex"]["stages"].as_array().unwrap().iter().map(|s| s["stage"].as_str().unwrap()).collect();
    assert!(!stages.contains(&"capture") && !stages.contains(&"recapture"), "{stages:?}");
    let meshed = report["hex"]["stages"][0]["details"]["lattices_meshed"].as_array().unwrap();
    assert_eq!(meshed.len(), 2, "{meshed:?}");
    assert!(meshed.iter().all(|m| m["resolution"] == 12) && meshed[1]["elements"].as_u64() > meshed[0]["elements"].as_u64(), "{meshed:?}");
    // --max-elements below any lattice of the input's topology: the fallback fails,
    // the polycube mesh is kept and the failure is reported, not dropped
    let args: Vec<&str> = common.iter().copied().chain(["--max-elements", "100"]).collect();
    let (code, _, err) = sddpm(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("grid-based fallback was tried and failed") && err.contains("100 elements"), "{err}");
    let report = last_report();
    let built = report["hex"]["candidates_meshed"].as_array().unwrap();
    let fallback = built.iter().find(|a| a["candidate"].is_null()).expect("the fallback's attempt");
    assert!(fallback["error"].as_str().is_some_and(|e| e.contains("100 elements")), "{fallback}");
    assert!(fallback["min_scaled_jacobian"].is_null(), "{fallback}");
    assert_eq!(report["hex"]["domain"], "polycube");
    assert!(std::fs::read_to_string(dir.join("report.html")).unwrap().contains("Meshes built"));
    for bad in [
        &["--voxel-resolution", "1"][..],
        &["--pin-uncovered=-1"][..],
        &["--pin-uncovered", "nan"][..],
        &["--feature-median-angle", "200"][..],
        &["--lattice-planes", "1"][..],
        &["--lattice-planes=-0.1"][..],
        &["--lattice-planes", "nan"][..],
        &["--feature-median-angle", "nan"][..],
        &["--goal-hausdorff", "0"][..],
        &["--goal-min-sj=-1"][..],
        &["--goal-mean-sj", "1.5"][..],
        &["--max-elements", "0"][..],
    ] {
        let args: Vec<&str> = common.iter().copied().chain(bad.iter().copied()).collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 2, "{bad:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(bad[0].split('=').next().unwrap()), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_refuses_a_genus_inconsistent_context_before_diffusion() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-run-bad-{}", std::process::id()));
    let (code, _, err) = sddpm(&["run", "tests/data/meshes/cgal_hole.off", "-o", dir.to_str().unwrap(), "--labels", "cube,0,0,0,0,0,0,0,0,0,0,0", "-q"]);
    assert_eq!(code, 2);
    assert!(err.contains("genus") && err.contains('1') && err.contains('0'), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `sddpm batch` takes `sddpm run`'s hex-stage options, checked before any file is read.
#[test]
fn batch_checks_the_hex_options_of_run() {
    let out = std::env::temp_dir().join(format!("sddpm-cli-batch-opts-{}", std::process::id()));
    for bad in [&["--max-elements", "0"][..], &["--goal-hausdorff", "inf"][..], &["--voxel-resolution", "500"][..], &["--local-refinement", "x"][..]] {
        let args: Vec<&str> = ["batch", "tests/data/meshes", "-o", out.to_str().unwrap(), "-q"].into_iter().chain(bad.iter().copied()).collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 2, "{bad:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(bad[0]), "{err}");
    }
    assert!(!out.exists(), "nothing is written for bad options");
}

/// `sddpm batch`: every mesh of a folder, in parallel, with a summary; a bad file is
/// a row with its status, not the end of the batch.
#[test]
fn batch_meshes_a_folder_with_a_summary() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("sddpm-cli-batch-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let inp = dir.join("in");
    std::fs::create_dir_all(&inp).unwrap();
    std::fs::copy(root.join("tests/data/meshes/cgal_hole.off"), inp.join("hole.off")).unwrap();
    std::fs::copy(root.join("tests/data/meshes/cinolib_torus.obj"), inp.join("torus.obj")).unwrap();
    std::fs::copy(root.join("tests/data/meshes/bad/cgal_mech-holes-shark.off"), inp.join("open.off")).unwrap();
    std::fs::write(inp.join("notes.txt"), "not a mesh").unwrap();
    let out = dir.join("out");
    let (code, stdout, err) = sddpm(&["batch", inp.to_str().unwrap(), "-o", out.to_str().unwrap(), "--steps", "10", "--level", "1", "--no-spline", "--json", "-q"]);
    assert_eq!(code, 2, "one file is bad: {err}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(v["files"], 3);
    assert_eq!(v["ok"], 2);
    let runs = v["runs"].as_array().unwrap();
    let open = runs.iter().find(|r| r["folder"] == "open").unwrap();
    assert_eq!(open["status"], "INVALID_MESH");
    assert!(open["error"].as_str().unwrap().contains("boundary edges"));
    for name in ["hole", "torus"] {
        assert!(out.join(name).join("report.json").is_file(), "{name}");
        assert!(out.join(name).join("hex.vtu").is_file(), "{name}");
    }
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("| hole | OK | 1 |") && md.contains("INVALID_MESH"), "{md}");
    // every part's files with their sizes, and its status
    for r in runs {
        let folder = r["folder"].as_str().unwrap();
        let files = r["files"].as_array().unwrap();
        assert_eq!(files.is_empty(), r["status"] != "OK", "{r}");
        for f in files {
            let name = f["name"].as_str().unwrap();
            assert_eq!(std::fs::metadata(out.join(folder).join(name)).unwrap().len(), f["bytes"].as_u64().unwrap(), "{folder}/{name}");
            assert!(md.contains(&format!("[{folder}/{name}]({folder}/{name})")), "summary.md lacks {folder}/{name}");
        }
    }
    assert!(md.contains("### open (INVALID_MESH)\n\nno file written"), "{md}");
    assert_eq!(v["bytes"].as_u64().unwrap(), runs.iter().map(|r| r["files_bytes"].as_u64().unwrap()).sum::<u64>());
    // the used output folder is refused; --force clears the tool's files in it and
    // in each input's folder (a file of the caller's stays) and meshes again
    let batch = ["batch", inp.to_str().unwrap(), "-o", out.to_str().unwrap(), "--steps", "10", "--level", "1", "--no-spline", "-q"];
    let (code, _, err) = sddpm(&batch);
    assert_eq!(code, 2);
    assert!(err.contains("not empty") && err.contains(out.to_str().unwrap()), "{err}");
    std::fs::write(out.join("hole").join("mine.txt"), "kept").unwrap();
    let args: Vec<&str> = batch.iter().copied().chain(["--force"]).collect();
    let (code, _, err) = sddpm(&args);
    assert_eq!(code, 2, "one file is still bad: {err}");
    assert!(!err.contains("not empty"), "{err}");
    assert!(out.join("hole").join("mine.txt").is_file() && out.join("hole").join("report.json").is_file() && out.join("summary.md").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A screenshot by headless Chromium of `html` copied alone into `dir`: the page
/// must show everything without the files of its run folder.
fn screenshot(chromium: &str, html: &std::path::Path, dir: &std::path::Path) -> image::RgbImage {
    std::fs::create_dir_all(dir).unwrap();
    let alone = dir.join("report.html");
    std::fs::copy(html, &alone).unwrap();
    let shot = dir.join("screenshot.png");
    let out = Command::new(chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--window-size=1280,2400"])
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", alone.display()))
        .output()
        .expect("run chromium");
    assert!(shot.is_file(), "no screenshot: {}", String::from_utf8_lossy(&out.stderr));
    image::open(&shot).expect("a PNG").to_rgb8()
}

/// What the screenshot shows: not blank, the pictures (many distinct colours), the
/// path box (#f7f7f7) above the goals, and a mark (green #1a7f37 or red #b42318)
/// on each of the 4 goal rows: the first 4 bands of mark-coloured pixels from the
/// top, evenly spaced as table rows are, with no fifth one in the table.
fn check_screenshot(img: &image::RgbImage, what: &str) {
    let (w, h) = img.dimensions();
    let non_white = img.pixels().filter(|p| p.0 != [255, 255, 255]).count() as f64 / (w * h) as f64;
    let colours: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0.map(|c| c / 16)).collect();
    assert!(non_white > 0.05, "{what}: the page looks blank: {:.1}% non-white", 100.0 * non_white);
    assert!(colours.len() > 50, "{what}: only {} colours: the pictures did not load", colours.len());
    let near = |p: [u8; 3], c: [u8; 3]| p.iter().zip(c).map(|(&a, b)| (a as i32 - b as i32).pow(2)).sum::<i32>() < 40 * 40;
    let marked: Vec<bool> = (0..h).map(|y| (0..w).filter(|&x| { let p = img.get_pixel(x, y).0; near(p, [26, 127, 55]) || near(p, [180, 35, 24]) }).count() >= 2).collect();
    let mut bands: Vec<(u32, u32)> = Vec::new();
    for y in 0..h {
        if marked[y as usize] {
            match bands.last_mut() {
                Some(b) if b.1 + 4 >= y => b.1 = y,
                _ => bands.push((y, y)),
            }
        }
    }
    assert!(bands.len() >= 4, "{what}: {} mark rows in the screenshot: {bands:?}", bands.len());
    let centre = |b: (u32, u32)| (b.0 + b.1) as f64 / 2.0;
    let step = centre(bands[1]) - centre(bands[0]);
    for k in 1..4 {
        let d = centre(bands[k]) - centre(bands[k - 1]);
        assert!((d - step).abs() <= 4.0 && step > 10.0, "{what}: goal rows not evenly spaced: {bands:?}");
    }
    if let Some(b) = bands.get(4) {
        assert!(centre(*b) - centre(bands[3]) > 1.5 * step, "{what}: a fifth mark row: {bands:?}");
    }
    let path_box = (0..bands[0].0).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| img.get_pixel(x, y).0 == [247, 247, 247]).count();
    assert!(path_box > 2_000, "{what}: no path box above the goals ({path_box} pixels)");
}

/// report.html renders in headless Chromium as one self-contained page (copied
/// alone into another folder), for a polycube mesh and for a fallback mesh: the
/// screenshot shows the pictures, the path and a mark on every goal's row, and the
/// rendered page names the path. Chromium comes with the test command's packages;
/// without it the test is skipped unless SDDPM_REQUIRE_CHROMIUM=1.
#[test]
fn report_html_renders_in_headless_chromium() {
    let chromium = ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find(|c| Command::new(c).arg("--version").output().map(|o| o.status.success()).unwrap_or(false));
    let Some(chromium) = chromium else {
        assert!(std::env::var("SDDPM_REQUIRE_CHROMIUM").is_err(), "chromium is required (SDDPM_REQUIRE_CHROMIUM) but not installed");
        eprintln!("skipped: no chromium");
        return;
    };
    let dir = std::env::temp_dir().join(format!("sddpm-cli-html-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let pc = dir.join("polycube");
    let (code, _, err) = sddpm(&["run", "tests/data/meshes/cinolib_torus.obj", "-o", pc.to_str().unwrap(), "--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "--level", "1", "-q"]);
    assert_eq!(code, 0, "{err}");
    check_screenshot(&screenshot(chromium, &pc.join("report.html"), &dir.join("alone-polycube")), "polycube mesh");
    // the page as Chromium rendered it names the path and marks every goal
    let rendered = |html: &std::path::Path| {
        let out = Command::new(chromium).args(["--headless", "--no-sandbox", "--disable-gpu", "--dump-dom"]).arg(format!("file://{}", html.display())).output().expect("run chromium");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let marks = |dom: &str| dom.matches("goal-pass").count() + dom.matches("goal-fail").count();
    let dom = rendered(&dir.join("alone-polycube/report.html"));
    assert!(dom.contains("Mesh made by: polycube") && dom.contains("THC+Z at (0,0,0)"), "no path in the rendered page");
    assert_eq!(marks(&dom), 4, "a mark per goal");
    let fb = dir.join("fallback");
    let (code, _, err) = sddpm(&[
        "run", "tests/data/meshes/hexgen_hepta.obj", "-o", fb.to_str().unwrap(), "--labels", "cube,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "--no-spline",
        "--voxel-resolution", "12", "--voxel-refinements", "0", "--goal-hausdorff", "0.025", "-q",
    ]);
    assert_eq!(code, 0, "{err}");
    check_screenshot(&screenshot(chromium, &fb.join("report.html"), &dir.join("alone-fallback")), "fallback mesh");
    let dom = rendered(&dir.join("alone-fallback/report.html"));
    assert!(dom.contains("Mesh made by: grid-based fallback"), "no fallback path in the rendered page");
    assert_eq!(marks(&dom), 4, "a mark per goal");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A used output folder is refused (exit 2, naming the folder) unless --force,
/// which removes the files of the earlier run (a run with the spline, then one
/// without: no spline file is left) and keeps the caller's; report.json's
/// manifest lists exactly the files of the run, with their sizes, and report.html
/// links those.
#[test]
fn run_refuses_a_used_folder_unless_forced() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-force-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let base = ["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "--level", "1", "-q"];
    let (code, _, err) = sddpm(&base);
    assert_eq!(code, 0, "{err}");
    for f in ["spline.bext", "model.k", "spline.vtu", "spline_control.vtk"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let (code, _, err) = sddpm(&base);
    assert_eq!(code, 2, "a used folder is refused: {err}");
    assert!(err.starts_with("error: ") && err.contains(d) && err.contains("--force"), "{err}");
    std::fs::write(dir.join("notes.txt"), "the caller's file").unwrap();
    let args: Vec<&str> = base.iter().copied().chain(["--force", "--no-spline"]).collect();
    let (code, _, err) = sddpm(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "the caller's file", "--force keeps other files");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let files = report["files"].as_array().unwrap();
    let listed: std::collections::BTreeSet<String> = files.iter().map(|f| f["name"].as_str().unwrap().to_string()).collect();
    let present: std::collections::BTreeSet<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).filter(|n| n != "notes.txt").collect();
    assert_eq!(listed, present, "no file of the first run is left that the second did not write");
    for f in ["spline.bext", "model.k", "spline.vtu", "spline_control.vtk"] {
        assert!(!dir.join(f).exists(), "{f} of the first run is left");
    }
    for f in files {
        let name = f["name"].as_str().unwrap();
        assert_eq!(f["bytes"].as_u64().unwrap(), std::fs::metadata(dir.join(name)).unwrap().len(), "size of {name}");
        assert!(!f["what"].as_str().unwrap().is_empty(), "{name}");
    }
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let links: std::collections::BTreeSet<String> = html.split("<a href=\"").skip(1).map(|t| t[..t.find('"').unwrap()].to_string()).collect();
    assert_eq!(links, listed, "report.html links the files of the run");
    // `sddpm polycube` refuses the folder too
    let (code, _, err) = sddpm(&["polycube", "tests/data/meshes/cgal_hole.off", "-o", d, "--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "2", "-q"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not empty"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The torus at default options: the whole run folder stays under 40 MB (sparse
/// BEXT within 1e-8, binary sampled VTK; 105 MB with dense exact BEXT and ASCII
/// VTK) and its BEXT reads back with the project's reader with the extraction
/// operators of an exact run within 1e-8.
#[test]
fn torus_run_folder_stays_compact() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-torus-size-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (code, _, err) = sddpm(&["run", "tests/data/meshes/cinolib_torus.obj", "-o", dir.to_str().unwrap(), "-q"]);
    assert_eq!(code, 0, "{err}");
    let total: u64 = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().metadata().unwrap().len()).sum();
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let sizes: Vec<String> = report["files"].as_array().unwrap().iter().map(|f| format!("{} {}", f["name"], f["bytes"])).collect();
    assert!(total < 40_000_000, "{total} bytes: {sizes:?}");
    assert_eq!(report["files_bytes"].as_u64().unwrap(), total, "report.json states the folder's size");
    assert!(!dir.join("spline.vtk").exists() && dir.join("spline.vtu").is_file());
    let b = sddpm::export::bext::read_bext(&dir.join("spline.bext")).unwrap();
    assert_eq!(b.elements.len() as u64, report["spline"]["elements"].as_u64().unwrap());
    assert_eq!(b.nodes.len() as u64, report["spline"]["basis_functions"].as_u64().unwrap());
    assert_eq!(report["spline"]["bext_sparse"], true);
    assert_eq!(report["spline"]["bext_tolerance"], 1e-8);
    // the same run with exact entries: the same ids and control points, every
    // operator entry within the stated tolerance
    let exact_dir = dir.join("exact");
    let (code, _, err) = sddpm(&["run", "tests/data/meshes/cinolib_torus.obj", "-o", exact_dir.to_str().unwrap(), "-q", "--bext-tolerance", "0"]);
    assert_eq!(code, 0, "{err}");
    let e = sddpm::export::bext::read_bext(&exact_dir.join("spline.bext")).unwrap();
    assert_eq!(e.nodes, b.nodes);
    assert_eq!(e.elements.len(), b.elements.len());
    for (x, y) in e.elements.iter().zip(&b.elements) {
        assert_eq!(x.ids, y.ids);
        assert!(x.operator.iter().zip(&y.operator).all(|(u, v)| (u - v).abs() <= 1e-8));
    }
    eprintln!("torus run folder: {total} bytes: {sizes:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--kernel-gate -1` (the learned gate) parses as a value, not as a flag; a
/// non-finite gate is refused with exit 2.
#[test]
fn kernel_gate_accepts_a_negative_value_and_refuses_nan() {
    let dir = std::env::temp_dir().join(format!("sddpm-cli-gate-{}", std::process::id()));
    let d = dir.to_str().unwrap();
    let args = |g: &'static str| ["polycube", "tests/data/meshes/cgal_hole.off", "-o", d, "--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "2", "-q", "--force", "--kernel-gate", g];
    let (code, _, err) = sddpm(&args("-1"));
    assert!(!err.contains("unexpected argument"), "{err}");
    assert!(code == 0 || code == 2, "exit {code}: {err}");
    // report.json lists the files written, itself included, with their sizes
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let files = report["files"].as_array().unwrap();
    assert!(files.iter().any(|f| f["name"] == "candidates.json") && files.iter().any(|f| f["name"] == "report.json"), "{files:?}");
    for f in files {
        assert_eq!(f["bytes"].as_u64().unwrap(), std::fs::metadata(dir.join(f["name"].as_str().unwrap())).unwrap().len(), "{f}");
    }
    assert_eq!(report["version"], env!("CARGO_PKG_VERSION"));
    let (code, _, err) = sddpm(&args("NaN"));
    assert_eq!(code, 2);
    assert!(err.contains("kernel_gate") && err.contains("finite"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

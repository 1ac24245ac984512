//! `sddpm run`'s controls for an engineer: the option headings of --help, the
//! target element size (--size), the sampled spline's resolution
//! (--spline-sample) and the LS-DYNA decks' units, material and analysis.

use sddpm::export::lsdyna::{field, parse_deck, Keyword};
use std::process::Command;

fn sddpm(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sddpm")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().expect("run sddpm");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("sddpm-cli-out-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

const HOLE: [&str; 5] = ["--labels", "THC+Z,0,0,0,0,0,0,0,0,0,0,0", "--steps", "10", "-q"];

/// `sddpm run --help` groups the options under headings, the developer knobs last.
#[test]
fn run_help_groups_the_options() {
    let (code, out, err) = sddpm(&["run", "--help"]);
    assert_eq!(code, 0, "{err}");
    let at = |h: &str| out.find(h).unwrap_or_else(|| panic!("--help lacks {h}:\n{out}"));
    let headings = ["Input and output:", "Polycube:", "Mesh size and quality goals:", "Grid-based fallback:", "Spline and files:", "LS-DYNA decks:", "Developer:"];
    for h in headings {
        at(h);
    }
    assert!(at("Developer:") > at("LS-DYNA decks:") && at("Developer:") > at("Mesh size and quality goals:"), "{out}");
    for (flag, heading) in [("--size <H>", "Mesh size and quality goals:"), ("--spline-sample <N>", "Spline and files:"), ("--units <U>", "LS-DYNA decks:"), ("--kernel-gate", "Developer:"), ("--feature-median-angle", "Developer:")] {
        let f = at(flag);
        let owner = headings.iter().filter(|h| at(h) < f).max_by_key(|h| at(h)).unwrap();
        assert_eq!(*owner, heading, "{flag} is under {owner}");
    }
}

fn keyword<'a>(deck: &'a [Keyword], name: &str) -> &'a Keyword {
    deck.iter().find(|k| k.name == name).unwrap_or_else(|| panic!("no *{name}"))
}

/// RO, E and PR of a deck's *MAT_ELASTIC card.
fn material(deck: &[Keyword]) -> [f64; 3] {
    let card = &keyword(deck, "MAT_ELASTIC").cards[0];
    [10, 20, 30].map(|c| field(card, c, 10).parse::<f64>().unwrap())
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs()
}

/// hex.k and model.k run alone: every keyword of the chosen analysis, the part,
/// section and material, the material in the chosen units; bad values refused.
#[test]
fn decks_take_units_material_and_analysis() {
    let dir = tmp("deck");
    let d = dir.to_str().unwrap();
    let run = |extra: &[&str]| {
        let args: Vec<&str> = ["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--level", "1", "--force"].iter().chain(&HOLE).chain(extra).copied().collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 0, "{extra:?}: {err}");
        let read = |f: &str| parse_deck(&std::fs::read_to_string(dir.join(f)).unwrap());
        (read("hex.k"), read("model.k"))
    };
    // the defaults: steel in mm-t-s, modal
    let (hex, model) = run(&[]);
    for deck in [&hex, &model] {
        for k in ["KEYWORD", "PART", "SECTION_SOLID", "MAT_ELASTIC", "CONTROL_IMPLICIT_GENERAL", "CONTROL_IMPLICIT_EIGENVALUE", "CONTROL_TERMINATION", "END"] {
            keyword(deck, k);
        }
        let [ro, e, pr] = material(deck);
        assert!(close(ro, 7.85e-9) && close(e, 210000.0) && close(pr, 0.3), "{ro} {e} {pr}");
    }
    keyword(&hex, "NODE");
    keyword(&hex, "ELEMENT_SOLID");
    keyword(&model, "IGA_INCLUDE_BEZIER");
    assert_eq!(field(&keyword(&hex, "SECTION_SOLID").cards[0], 10, 10), "2");
    assert_eq!(field(&keyword(&model, "SECTION_SOLID").cards[0], 10, 10), "201");
    // aluminium in SI, static
    let (hex, model) = run(&["--units", "m-kg-s", "--material", "aluminium", "--analysis", "static"]);
    for deck in [&hex, &model] {
        let [ro, e, pr] = material(deck);
        assert!(close(ro, 2700.0) && close(e, 70e9) && close(pr, 0.33), "{ro} {e} {pr}");
        keyword(deck, "CONTROL_IMPLICIT_GENERAL");
        assert!(!deck.iter().any(|k| k.name == "CONTROL_IMPLICIT_EIGENVALUE"));
    }
    // a material of the caller's in mm-kg-ms (GPa, kg/mm^3), no analysis
    let (hex, _) = run(&["--units", "mm-kg-ms", "--material", "200e9,0.29,7900", "--analysis", "none"]);
    let [ro, e, pr] = material(&hex);
    assert!(close(ro, 7.9e-6) && close(e, 200.0) && close(pr, 0.29), "{ro} {e} {pr}");
    assert!(!hex.iter().any(|k| k.name.starts_with("CONTROL")));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["outputs"]["deck"]["units"], "MmKgMs");
    for bad in [&["--units", "inch"][..], &["--material", "wood"][..], &["--material", "1e9,0.5,1000"][..], &["--material", "1e9,0.3"][..], &["--analysis", "explicit"][..], &["--spline-sample", "9"][..]] {
        let args: Vec<&str> = ["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--force"].iter().chain(&HOLE).chain(bad).copied().collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 2, "{bad:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(bad[0]), "{bad:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// --spline-sample N: N^3 cells per element in spline.vtu; 0: no spline.vtu.
#[test]
fn spline_sample_sets_the_vtu_resolution() {
    let dir = tmp("sample");
    let d = dir.to_str().unwrap();
    let mut cells = Vec::new();
    for n in ["1", "3", "0"] {
        let args: Vec<&str> = ["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--level", "1", "--force", "--spline-sample", n].iter().chain(&HOLE).copied().collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 0, "{err}");
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
        let listed = report["files"].as_array().unwrap().iter().any(|f| f["name"] == "spline.vtu");
        assert_eq!(listed, n != "0");
        assert_eq!(dir.join("spline.vtu").is_file(), n != "0");
        if n != "0" {
            let vtu = sddpm::export::spline_vtu::parse_spline_vtu(&std::fs::read(dir.join("spline.vtu")).unwrap()).unwrap();
            let ne = report["spline"]["elements"].as_u64().unwrap() as usize;
            let k: usize = n.parse().unwrap();
            cells.push(vtu.iter().find(|a| a.name == "types").unwrap().values.len());
            assert_eq!(*cells.last().unwrap(), ne * k * k * k);
            assert_eq!(vtu.iter().find(|a| a.name == "Points").unwrap().values.len(), 3 * ne * (k + 1).pow(3));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// --size H: a smaller size gives more elements, and the mean edge length of the
/// mesh is within a factor 1.5 of H, on the polycube path (level chosen from the
/// size) and on the fallback's (lattice chosen from the size).
#[test]
fn size_sets_the_element_size() {
    let dir = tmp("size");
    let d = dir.to_str().unwrap();
    let longest = |mesh: &str| {
        let (code, out, err) = sddpm(&["info", mesh, "--json"]);
        assert_eq!(code, 0, "{err}");
        let info: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
        (0..3).map(|a| info["bbox_max"][a].as_f64().unwrap() - info["bbox_min"][a].as_f64().unwrap()).fold(0.0, f64::max)
    };
    let run = |mesh: &str, labels: &str, h: f64, extra: &[&str]| {
        let hs = format!("{h}");
        let args: Vec<&str> = ["run", mesh, "-o", d, "--force", "--no-spline", "--size", hs.as_str(), "--json", "--labels", labels, "--steps", "10", "-q"].iter().chain(extra).copied().collect();
        let (code, out, err) = sddpm(&args);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
        let (n, edge) = (v["hex"]["elements"].as_u64().unwrap(), v["hex"]["mean_edge_length"].as_f64().unwrap());
        eprintln!("{mesh} --size {h} {extra:?}: {} ({}), {n} elements, mean edge {edge} ({:.2} H)", v["mesh_path"]["from"], v["hex"]["domain"], edge / h);
        assert!(edge > h / 1.5 && edge < 1.5 * h, "--size {h}: mean edge {edge}");
        (n, v["mesh_path"]["from"].as_str().unwrap().to_string())
    };
    // the polycube path (goals every mesh meets: no fallback)
    let (hole, thc) = ("tests/data/meshes/cgal_hole.off", "THC+Z,0,0,0,0,0,0,0,0,0,0,0");
    let loose = ["--goal-hausdorff", "1", "--goal-min-sj=-0.99", "--goal-mean-sj=-0.99"];
    let l = longest(hole);
    let (coarse, from) = run(hole, thc, l / 6.0, &loose);
    assert_eq!(from, "polycube");
    let (fine, _) = run(hole, thc, l / 12.0, &loose);
    assert!(fine > coarse, "{fine} against {coarse}");
    // the fallback's lattice (a single cube misses hepta's lugs: the lattice ranks better)
    let (hepta, cube) = ("tests/data/meshes/hexgen_hepta.obj", "cube,0,0,0,0,0,0,0,0,0,0,0");
    let l = longest(hepta);
    let (coarse, from) = run(hepta, cube, l / 12.0, &["--goal-hausdorff", "0.025"]);
    assert_eq!(from, "grid-based fallback");
    let (fine, from) = run(hepta, cube, l / 20.0, &["--goal-hausdorff", "0.025"]);
    assert_eq!(from, "grid-based fallback");
    assert!(fine > coarse, "{fine} against {coarse}");
    for bad in ["0", "-1", "nan", "inf"] {
        let flag = format!("--size={bad}");
        let args: Vec<&str> = ["run", hole, "-o", d, "--force", flag.as_str()].iter().chain(&HOLE).copied().collect();
        let (code, _, err) = sddpm(&args);
        assert_eq!(code, 2, "--size {bad}: {err}");
        assert!(err.starts_with("error: ") && err.contains("--size"), "{err}");
    }
    let (code, _, err) = sddpm(&["run", "tests/data/meshes/cgal_hole.off", "-o", d, "--size", "1", "--level", "2"]);
    assert_eq!(code, 2, "--size with --level: {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

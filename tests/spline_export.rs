//! Exports of the spline: BEXT round trip, LS-DYNA deck layout against the
//! keyword-manual fixture, VTK of the sampled spline.

use sddpm::error::NoProgress;
use sddpm::export::bext::{parse_bext, read_bext, to_bext_string, write_bext, Bext};
use sddpm::export::lsdyna::{field, iga_deck_string, parse_deck, write_iga_deck, DeckOptions, IncludeStyle};
use sddpm::export::spline_vtk::{spline_vtk_string, write_control_mesh_vtk, write_control_points_vtk};
use sddpm::export::vtk::parse_vtk_legacy;
use sddpm::spline::{build_spline, Spline, SplineOptions};

use std::path::PathBuf;
use tempfile::TempDir;

#[path = "support/meshes.rs"]
mod meshes;

/// A directory of the test's own, removed with everything in it when the test ends.
fn tmpdir() -> TempDir {
    tempfile::Builder::new().prefix("sddpm_spline_export_").tempdir().unwrap()
}

fn refined_spline() -> Spline {
    let hex = meshes::extraordinary_edge(5, 2, 3);
    let mut sp = build_spline(&hex, None, &SplineOptions::default(), &mut NoProgress).unwrap();
    sp.refine(&[0, 7]).unwrap();
    sp
}

#[test]
fn spline_bext_round_trip_dense_and_sparse() {
    let sp = refined_spline();
    let d = tmpdir();
    for sparse in [false, true] {
        let path = d.path().join(if sparse { "s.bext" } else { "d.bext" });
        write_bext(&path, &sp, sparse).unwrap();
        let b = read_bext(&path).unwrap();
        assert_eq!(b.nodes.len(), sp.num_basis());
        assert_eq!(b.elements.len(), sp.num_elements());
        for (i, p) in sp.control_points().iter().enumerate() {
            assert_eq!([b.nodes[i][0], b.nodes[i][1], b.nodes[i][2]], *p, "control point {i}");
            assert_eq!(b.nodes[i][3], 1.0);
        }
        for e in 0..sp.num_elements() {
            assert_eq!(b.elements[e].ids.as_slice(), sp.element_basis(e).unwrap());
            assert_eq!(b.elements[e].operator, sp.extraction_operator(e).unwrap(), "operator of element {e}");
            let pb = sp.bezier_points(e).unwrap();
            let qb = b.bezier_points(e);
            for k in 0..64 {
                for i in 0..3 {
                    assert!((pb[k][i] - qb[k][i]).abs() < 1e-12);
                }
            }
        }
        // writing the parsed content again gives the same text
        assert_eq!(sddpm::export::bext::bext_text(&b, sparse), to_bext_string(&sp, sparse));
    }
    let text = to_bext_string(&sp, false);
    assert!(text.starts_with("B E X T\ntype hex\nnodeN "));
    assert!(text.contains("\nbelem "));
}

#[test]
fn spline_bext_rejects_malformed() {
    let sp = refined_spline();
    let good = to_bext_string(&sp, true);
    assert!(parse_bext(&good).is_ok());
    for bad in [
        good.replacen("B E X T", "BEXX", 1),
        good.replacen("type hex", "type quad", 1),
        good.replacen("belem", "bel", 1),
        good.replacen(" 3 3 3", " 2 2 2", 1),
        good[..good.len() / 2].to_string(),
        good.replacen("\ns ", "\nq ", 1),
    ] {
        assert!(parse_bext(&bad).is_err());
    }
    let d = tmpdir();
    let e = read_bext(&d.path().join("does_not_exist.bext")).unwrap_err();
    assert_eq!(e.status(), sddpm::Status::Io);
    std::fs::write(d.path().join("bad.bext"), "B E X T\nnodeN x\n").unwrap();
    assert_eq!(read_bext(&d.path().join("bad.bext")).unwrap_err().status(), sddpm::Status::Parse);
    let _ = Bext::default();
}

struct Layout {
    keyword: String,
    card: usize,
    name: String,
    ty: char,
    start: usize,
    width: usize,
}

fn layouts() -> Vec<Layout> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/lsdyna/keyword_layouts.txt");
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            Layout {
                keyword: t[0].into(),
                card: t[1].parse().unwrap(),
                name: t[2].into(),
                ty: t[3].chars().next().unwrap(),
                start: t[4].parse().unwrap(),
                width: t[5].parse().unwrap(),
            }
        })
        .collect()
}

/// Check every card of the keywords listed in the fixture: fixed columns,
/// numbers where the manual has numbers, nothing beyond the last field.
/// Returns the parsed value of each (keyword, field).
fn check_deck(text: &str) -> std::collections::HashMap<(String, String), String> {
    let deck = parse_deck(text);
    assert_eq!(deck.first().map(|k| k.name.as_str()), Some("KEYWORD"));
    assert_eq!(deck.last().map(|k| k.name.as_str()), Some("END"));
    let lay = layouts();
    let mut values = std::collections::HashMap::new();
    for kw in &deck {
        let fields: Vec<&Layout> = lay.iter().filter(|l| l.keyword == kw.name).collect();
        if fields.is_empty() {
            assert!(["KEYWORD", "END"].contains(&kw.name.as_str()), "keyword {} has no layout in the fixture", kw.name);
            continue;
        }
        let ncards = fields.iter().map(|f| f.card).max().unwrap();
        assert_eq!(kw.cards.len(), ncards, "{}: {} cards, the manual has {}", kw.name, kw.cards.len(), ncards);
        for (ci, line) in kw.cards.iter().enumerate() {
            let cf: Vec<&&Layout> = fields.iter().filter(|f| f.card == ci + 1).collect();
            let end = cf.iter().map(|f| f.start + f.width).max().unwrap();
            assert!(line.len() <= end, "{} card {}: '{line}' is longer than its {end} columns", kw.name, ci + 1);
            assert!(!line.contains(','), "{} card {}: free format in a fixed-format deck", kw.name, ci + 1);
            for f in cf {
                let v = field(line, f.start, f.width);
                // a field must not straddle into the next one: its text sits inside its columns
                if f.ty != 'A' && !v.is_empty() {
                    let raw = &line[f.start..(f.start + f.width).min(line.len())];
                    assert!(raw.starts_with(' ') || raw.len() == f.width, "{}.{} not right-aligned: '{raw}'", kw.name, f.name);
                }
                match f.ty {
                    'I' => assert!(v.is_empty() || v.parse::<i64>().is_ok(), "{}.{} = '{v}' is not an integer", kw.name, f.name),
                    'F' => assert!(v.is_empty() || v.parse::<f64>().is_ok(), "{}.{} = '{v}' is not a real", kw.name, f.name),
                    _ => {}
                }
                values.insert((kw.name.clone(), f.name.clone()), v.to_string());
            }
        }
    }
    values
}

#[test]
fn spline_lsdyna_fixture_is_consistent() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/lsdyna/reference_deck.k");
    let v = check_deck(&std::fs::read_to_string(p).unwrap());
    assert_eq!(v[&("SECTION_SOLID".into(), "ELFORM".into())], "201");
}

#[test]
fn spline_lsdyna_deck_matches_manual_layout() {
    let opts = DeckOptions::default();
    let text = iga_deck_string("spline.bext", &opts).unwrap();
    let v = check_deck(&text);
    let g = |k: &str, f: &str| v[&(k.to_string(), f.to_string())].clone();
    assert_eq!(g("IGA_INCLUDE_BEZIER", "FILENAME"), "spline.bext");
    assert_eq!(g("IGA_INCLUDE_BEZIER", "FILETYPE"), "1");
    assert_eq!(g("IGA_INCLUDE_BEZIER", "DIM"), "3");
    assert_eq!(g("IGA_INCLUDE_BEZIER", "PID"), g("PART", "PID"));
    assert_eq!(g("PART", "SECID"), g("SECTION_SOLID", "SECID"));
    assert_eq!(g("PART", "MID"), g("MAT_ELASTIC", "MID"));
    assert_eq!(g("SECTION_SOLID", "ELFORM"), "201");
    assert_eq!(g("MAT_ELASTIC", "E").parse::<f64>().unwrap(), 210000.0);
    assert_eq!(g("MAT_ELASTIC", "RO").parse::<f64>().unwrap(), 7.85e-9);
    assert_eq!(g("MAT_ELASTIC", "PR").parse::<f64>().unwrap(), 0.3);
    assert_eq!(g("CONTROL_IMPLICIT_EIGENVALUE", "NEIG"), "10");
    // the same keyword sequence as the hand-written manual-layout deck
    let names: Vec<String> = parse_deck(&text).into_iter().map(|k| k.name).collect();
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/lsdyna/reference_deck.k");
    let reference: Vec<String> = parse_deck(&std::fs::read_to_string(p).unwrap()).into_iter().map(|k| k.name).collect();
    assert_eq!(names, reference);
    // file output, odd numbers still fit their fields, bad options refused
    let d = tmpdir();
    let path = d.path().join("model.k");
    let odd = DeckOptions { density: 1.234567891e-9, youngs_modulus: 123456789.0, poisson_ratio: 0.33333333, ..Default::default() };
    write_iga_deck(&path, "spline.bext", &odd).unwrap();
    let v = check_deck(&std::fs::read_to_string(&path).unwrap());
    let ro: f64 = v[&("MAT_ELASTIC".to_string(), "RO".to_string())].parse().unwrap();
    assert!((ro / 1.234567891e-9 - 1.0).abs() < 1e-4, "{ro}");
    assert!(iga_deck_string("", &opts).is_err());
    assert!(iga_deck_string("a\nb", &opts).is_err());
    assert!(iga_deck_string("x.bext", &DeckOptions { poisson_ratio: 0.5, ..Default::default() }).is_err());
    let legacy = iga_deck_string("rod.bext", &DeckOptions { include: IncludeStyle::IncludeTransform, ..Default::default() }).unwrap();
    assert!(legacy.contains("*INCLUDE_TRANSFORM\nrod.bext\n1,0,1,0,0\n"));
}

/// The binary sampled VTK holds the ASCII one's points (as 32-bit floats) and its
/// cells, in the sections of the legacy format.
#[test]
fn spline_vtk_binary_matches_the_ascii_form() {
    let sp = refined_spline();
    let ascii = parse_vtk_legacy(&spline_vtk_string(&sp, 2).unwrap()).unwrap();
    let b = sddpm::export::spline_vtk::spline_vtk_binary(&sp, 2).unwrap();
    let npts = ascii.nodes.len();
    let head = format!("BINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS {npts} float\n");
    let at = b.windows(head.len()).position(|w| w == head.as_bytes()).expect("the header") + head.len();
    for (n, p) in ascii.nodes.iter().enumerate() {
        for i in 0..3 {
            let o = at + 12 * n + 4 * i;
            let v = f32::from_be_bytes(b[o..o + 4].try_into().unwrap()) as f64;
            assert!((v - p[i]).abs() <= 1e-6 * (1.0 + p[i].abs()), "point {n}");
        }
    }
    let cells = format!("\nCELLS {} {}\n", ascii.elements.len(), 9 * ascii.elements.len());
    let at = b.windows(cells.len()).position(|w| w == cells.as_bytes()).expect("the cells") + cells.len();
    for (c, el) in ascii.elements.iter().enumerate() {
        let o = at + 36 * c;
        assert_eq!(i32::from_be_bytes(b[o..o + 4].try_into().unwrap()), 8);
        for (k, &v) in el.iter().enumerate() {
            assert_eq!(i32::from_be_bytes(b[o + 4 + 4 * k..o + 8 + 4 * k].try_into().unwrap()) as usize, v as usize, "cell {c}");
        }
    }
    for section in ["CELL_TYPES", "SCALARS element int 1", "SCALARS level int 1", "SCALARS jacobian float 1", "SCALARS scaled_jacobian float 1"] {
        assert!(b.windows(section.len()).any(|w| w == section.as_bytes()), "{section}");
    }
}

/// BEXT written within a tolerance (the run folder's form: sparse, operator
/// entries within 1e-8) reads back with the project's reader with the same basis
/// ids, exact control points and every operator entry within the tolerance; the
/// Bézier points move by at most the tolerance times the control points' sizes.
#[test]
fn spline_bext_within_a_tolerance_reads_back() {
    let sp = refined_spline();
    let exact = Bext::from_spline(&sp);
    let tol = sddpm::export::bext::RUN_FOLDER_TOLERANCE;
    assert_eq!(tol, 1e-8);
    assert_eq!(tol, SplineOptions::default().bext_tolerance);
    let d = tmpdir();
    let path = d.path().join("t.bext");
    sddpm::export::bext::write_bext_within(&path, &sp, true, tol).unwrap();
    let b = read_bext(&path).unwrap();
    assert_eq!(b.nodes, exact.nodes);
    assert_eq!(b.elements.len(), exact.elements.len());
    for (e, (x, y)) in exact.elements.iter().zip(&b.elements).enumerate() {
        assert_eq!(x.ids, y.ids, "element {e}");
        for (k, (u, v)) in x.operator.iter().zip(&y.operator).enumerate() {
            assert!((u - v).abs() <= tol, "element {e} entry {k}: {u} against {v}");
        }
        let size: f64 = x.ids.iter().map(|&i| exact.nodes[i as usize][..3].iter().map(|c| c * c).sum::<f64>().sqrt()).sum();
        for (p, q) in exact.bezier_points(e).iter().zip(b.bezier_points(e)) {
            for i in 0..3 {
                assert!((p[i] - q[i]).abs() <= tol * size + 1e-12, "element {e}");
            }
        }
    }
    let exact_len = to_bext_string(&sp, false).len();
    let len = std::fs::metadata(&path).unwrap().len() as usize;
    assert!(len < exact_len, "{len} against {exact_len}");
    // tolerance 0 is the exact form
    assert_eq!(sddpm::export::bext::bext_text_within(&exact, true, 0.0), to_bext_string(&sp, true));
}

#[test]
fn spline_vtk_exports() {
    let sp = refined_spline();
    let s = spline_vtk_string(&sp, 3).unwrap();
    let m = parse_vtk_legacy(&s).unwrap();
    assert_eq!(m.elements.len(), sp.num_elements() * 27);
    assert_eq!(m.nodes.len(), sp.num_elements() * 64);
    assert!(s.contains("SCALARS jacobian double 1"));
    // first sampled point of element 0 is its corner
    let (x, _) = sp.evaluate(0, 0.0, 0.0, 0.0).unwrap();
    for i in 0..3 {
        assert!((m.nodes[0][i] - x[i]).abs() < 1e-12);
    }
    assert!(spline_vtk_string(&sp, 0).is_err());
    let d = tmpdir();
    write_control_mesh_vtk(&d.path().join("control.vtk"), &sp).unwrap();
    let c = sddpm::export::vtk::read_vtk_legacy(&d.path().join("control.vtk")).unwrap();
    assert_eq!(c.elements.len(), sp.topology().ne);
    write_control_points_vtk(&d.path().join("points.vtk"), &sp).unwrap();
}

#[test]
fn spline_write_outputs_for_the_pipeline() {
    let sp = refined_spline();
    let d = tmpdir();
    let dir = d.path().join("run");
    let j = sddpm::export::spline_files::write_outputs(&dir, &sp, &Default::default()).unwrap();
    for k in ["elements", "basis_functions", "bext", "lsdyna", "min_scaled_jacobian"] {
        assert!(j.get(k).is_some(), "{k}");
    }
    assert_eq!(j["bext"], "spline.bext");
    assert_eq!(j["lsdyna"], "model.k");
    assert_eq!(j["elements"].as_u64().unwrap() as usize, sp.num_elements());
    let b = read_bext(&dir.join("spline.bext")).unwrap();
    assert_eq!(b.elements.len(), sp.num_elements());
    let deck = std::fs::read_to_string(dir.join("model.k")).unwrap();
    assert!(deck.contains("\nspline.bext\n"));
    assert!(dir.join("spline.vtu").exists() && dir.join("spline_control.vtk").exists());
    assert!(!dir.join("spline.vtk").exists(), "the legacy sampled file is off by default");
    assert_eq!(j["vtu"], "spline.vtu");
    assert_eq!(j["sample_cells_per_edge"], 2);
}

/// spline.vtu holds the legacy VTK's grid (points as 32-bit floats), cells and
/// data, and reads back with the project's reader.
#[test]
fn spline_vtu_matches_the_legacy_form() {
    let sp = refined_spline();
    for s in [1, 2, 3] {
        let legacy = parse_vtk_legacy(&spline_vtk_string(&sp, s).unwrap()).unwrap();
        let b = sddpm::export::spline_vtu::spline_vtu_bytes(&sp, s).unwrap();
        assert!(b.starts_with(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
        let arrays = sddpm::export::spline_vtu::parse_spline_vtu(&b).unwrap();
        let get = |n: &str| &arrays.iter().find(|a| a.name == n).unwrap_or_else(|| panic!("no {n}")).values;
        let pts = get("Points");
        assert_eq!(pts.len(), 3 * legacy.nodes.len());
        for (k, p) in legacy.nodes.iter().enumerate() {
            for i in 0..3 {
                assert!((pts[3 * k + i] - p[i]).abs() <= 1e-6 * (1.0 + p[i].abs()), "point {k}");
            }
        }
        let conn = get("connectivity");
        let flat: Vec<f64> = legacy.elements.iter().flat_map(|e| e.iter().map(|&v| v as f64)).collect();
        assert_eq!(conn, &flat);
        let offsets = get("offsets");
        assert_eq!(offsets.len(), legacy.elements.len());
        assert_eq!(*offsets.last().unwrap(), 8.0 * legacy.elements.len() as f64);
        assert!(get("types").iter().all(|&t| t == 12.0));
        assert_eq!(get("element").len(), legacy.elements.len());
        assert_eq!(get("element")[s * s * s], 1.0);
        assert_eq!(get("level").len(), legacy.elements.len());
        assert_eq!(get("jacobian").len(), legacy.nodes.len());
        assert!(get("scaled_jacobian").iter().all(|&q| q > 0.0 && q <= 1.0 + 1e-6));
    }
    assert!(sddpm::export::spline_vtu::spline_vtu_bytes(&sp, 0).is_err());
    // write_outputs refuses a sample count out of range
    let d = tmpdir();
    let o = sddpm::export::spline_files::OutputOptions { vtk_samples: 9, ..Default::default() };
    assert!(sddpm::export::spline_files::write_outputs(d.path(), &sp, &o).is_err());
}

/// The decks' material in each unit system: steel and aluminium scaled from SI.
#[test]
fn deck_material_in_each_unit_system() {
    use sddpm::export::lsdyna::{model_cards, Analysis, Material, Units};
    for (units, ro, e) in [(Units::MmTonneS, 7.85e-9, 210000.0), (Units::MKgS, 7850.0, 210e9), (Units::MmKgMs, 7.85e-6, 210.0)] {
        let o = DeckOptions::default().with_material(Material::steel(), units).unwrap();
        let deck = parse_deck(&iga_deck_string("x.bext", &o).unwrap());
        let card = &deck.iter().find(|k| k.name == "MAT_ELASTIC").unwrap().cards[0];
        let v: Vec<f64> = [10, 20, 30].iter().map(|&c| field(card, c, 10).parse().unwrap()).collect();
        assert!((v[0] - ro).abs() <= 1e-9 * ro && (v[1] - e).abs() <= 1e-9 * e && v[2] == 0.3, "{units:?}: {v:?}");
    }
    assert_eq!(Material::parse("aluminium").unwrap(), Material::aluminium());
    assert_eq!(Material::parse("7e10, 0.33, 2700").unwrap(), Material::aluminium());
    for bad in ["wood", "1,2", "0,0.3,1000", "1e9,0.5,1000", "1e9,0.3,-1", "a,b,c"] {
        assert!(Material::parse(bad).is_err(), "{bad}");
    }
    let none = model_cards(&DeckOptions { analysis: Analysis::None, ..Default::default() }, 2, "h").unwrap();
    assert!(!none.contains("*CONTROL"));
    let st = model_cards(&DeckOptions { analysis: Analysis::Static, ..Default::default() }, 2, "h").unwrap();
    assert!(st.contains("*CONTROL_IMPLICIT_GENERAL") && !st.contains("EIGENVALUE"));
    assert!(Units::parse("inch").is_err() && Analysis::parse("explicit").is_err());
}

//! Exports of the hex stage: VTU, legacy VTK, Medit .mesh and LS-DYNA .k written and
//! parsed back with the project's readers. The files stay in target/hex-fixtures for
//! the C++ test (cpp_tests/test_vtk_quality.cpp), which reads the VTU / VTK files with
//! VTK's readers and compares vtkMeshQuality's hex scaled Jacobian with the cell data
//! "scaled_jacobian" written here, and reads the sampled spline (spline.vtu) with
//! VTK's XML reader.

use sddpm::context::Context;
use sddpm::error::NoProgress;
use sddpm::export::hexfmt::{read_lsdyna, read_medit, read_vtu, write_lsdyna, write_medit, write_vtu};
use sddpm::export::vtk::{read_vtk_legacy, write_vtk_legacy};
use sddpm::hex::quality::element_qualities;
use sddpm::hex::{build_hex_mesh, HexInput, HexMesh, HexOptions, MapOptions};
use sddpm::mesh::{LoadOptions, TriMesh};
use std::path::PathBuf;

fn fixtures() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/hex-fixtures");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Hand-made hexes with known quality: a unit cube, a sheared, a tapered, a one-corner
/// pulled and an inverted (flipped node order) element, side by side.
fn zoo() -> HexMesh {
    let unit = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]];
    let mut shapes = vec![unit];
    let mut s = unit;
    for p in s.iter_mut().skip(4) {
        p[0] += 0.75;
    }
    shapes.push(s);
    let mut t = unit;
    for p in t.iter_mut().skip(4) {
        p[0] = 0.25 + 0.5 * p[0];
        p[1] = 0.25 + 0.5 * p[1];
    }
    shapes.push(t);
    let mut c = unit;
    c[6] = [2.0, 2.0, 2.0];
    shapes.push(c);
    shapes.push([unit[4], unit[5], unit[6], unit[7], unit[0], unit[1], unit[2], unit[3]]);
    let mut m = HexMesh::default();
    for (k, sh) in shapes.iter().enumerate() {
        let base = m.nodes.len() as u32;
        for p in sh {
            m.nodes.push([p[0] + 3.0 * k as f64, p[1], p[2]]);
        }
        m.elements.push(std::array::from_fn(|i| base + i as u32));
    }
    m
}

fn write_all(name: &str, m: &HexMesh) {
    let d = fixtures();
    let sj = element_qualities(m);
    write_vtu(&d.join(format!("{name}.vtu")), m, &[("scaled_jacobian", &sj)]).unwrap();
    write_vtk_legacy(&d.join(format!("{name}.vtk")), m, name, &[("scaled_jacobian", &sj)]).unwrap();
    write_medit(&d.join(format!("{name}.mesh")), m).unwrap();
    write_lsdyna(&d.join(format!("{name}.k")), m, name).unwrap();
    std::fs::write(d.join(format!("{name}.counts")), format!("{} {}\n", m.nodes.len(), m.elements.len())).unwrap();

    let (v, data) = read_vtu(&d.join(format!("{name}.vtu"))).unwrap();
    assert_eq!(&v, m);
    assert_eq!(data.len(), 1);
    assert_eq!(data[0].0, "scaled_jacobian");
    assert_eq!(data[0].1.len(), sj.len());
    for (a, b) in data[0].1.iter().zip(&sj) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
    let l = read_vtk_legacy(&d.join(format!("{name}.vtk"))).unwrap();
    assert_eq!(&l, m);
    let me = read_medit(&d.join(format!("{name}.mesh"))).unwrap();
    assert_eq!(&me, m);
    let k = read_lsdyna(&d.join(format!("{name}.k"))).unwrap();
    assert_eq!(k.elements, m.elements);
    assert_eq!(k.nodes.len(), m.nodes.len());
    let scale = m.nodes.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs())).max(1.0);
    for (a, b) in k.nodes.iter().zip(&m.nodes) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-8 * scale, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn hand_made_hexes_round_trip() {
    let m = zoo();
    let sj = element_qualities(&m);
    assert!((sj[0] - 1.0).abs() < 1e-15);
    assert!((sj[2] - 1.0 / 1.125f64.sqrt()).abs() < 1e-12);
    assert!((sj[3] - 2.0 / (3.0 * 6f64.sqrt())).abs() < 1e-12);
    assert!(sj[4] < 0.0);
    write_all("zoo", &m);
}

#[test]
fn pipeline_meshes_round_trip() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let mesh = TriMesh::load(dir.join("cgal_hole.off"), &LoadOptions::default()).unwrap();
    let input = HexInput::from_user_mesh(&mesh, Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()).unwrap();
    let r = build_hex_mesh(&input, &HexOptions { map: MapOptions { level: Some(1), ..Default::default() }, ..Default::default() }, &mut NoProgress).unwrap();
    assert_eq!(r.scaled_jacobian, element_qualities(&r.mesh));
    write_all("hole_level1", &r.mesh);
    // the mapped mesh too: it has elements of every quality down to nearly flat ones
    write_all("hole_level1_mapped", &r.mapped);
    // the spline of the mesh sampled as spline.vtu (2 sub-cells per element edge), for
    // the VTK test's reader; spline_vtu.counts: points, cells, elements
    let sp = sddpm::spline::build_spline(&r.mesh, None, &sddpm::spline::SplineOptions::default(), &mut NoProgress).unwrap();
    let d = fixtures();
    sddpm::export::spline_vtu::write_spline_vtu(&d.join("spline.vtu"), &sp, 2).unwrap();
    let ne = sp.num_elements();
    std::fs::write(d.join("spline_vtu.counts"), format!("{} {} {}\n", 27 * ne, 8 * ne, ne)).unwrap();
    let back = sddpm::export::spline_vtu::parse_spline_vtu(&std::fs::read(d.join("spline.vtu")).unwrap()).unwrap();
    assert_eq!(back.iter().find(|a| a.name == "types").unwrap().values.len(), 8 * ne);
}

#[test]
fn run_folder_files_and_report_keys() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    let mesh = TriMesh::load(dir.join("cinolib_torus.obj"), &LoadOptions::default()).unwrap();
    let input = HexInput::from_user_mesh(&mesh, Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()).unwrap();
    let r = build_hex_mesh(&input, &HexOptions { map: MapOptions { level: Some(1), ..Default::default() }, ..Default::default() }, &mut NoProgress).unwrap();
    let out = fixtures().join("run");
    std::fs::create_dir_all(&out).unwrap();
    sddpm::export::hexfmt::write_hex_files(&out, &r, &Default::default()).unwrap();
    let j = sddpm::hex::report_json(&r);
    for key in ["vertices", "elements", "min_scaled_jacobian", "mean_scaled_jacobian", "inverted", "hausdorff_relative", "file"] {
        assert!(j.get(key).is_some(), "report.json hex.{key} missing");
    }
    assert_eq!(j["file"], "hex.vtu");
    assert_eq!(j["elements"].as_u64().unwrap() as usize, r.mesh.elements.len());
    let (v, data) = read_vtu(&out.join("hex.vtu")).unwrap();
    assert_eq!(v, r.mesh);
    assert_eq!(data[0].1, r.scaled_jacobian);
    assert_eq!(read_vtk_legacy(&out.join("hex.vtk")).unwrap(), r.mesh);
    assert_eq!(read_medit(&out.join("hex.mesh")).unwrap(), r.mesh);
    assert_eq!(read_lsdyna(&out.join("hex.k")).unwrap().elements, r.mesh.elements);
    // the report serialises
    let text = serde_json::to_string(&j).unwrap();
    assert!(text.contains("\"stages\""));
}

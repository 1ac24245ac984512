//! The error catalogue (docs/errors.md): every status of the C header is documented
//! there, and every status is produced by a real call in this file (through the Rust
//! API, whose `Error::status()` is exactly what the C ABI returns).

use sddpm::search::generate::PolycubeOptions;
use sddpm::search::auto::AutoOptions;
use sddpm::context::Context;
use sddpm::diffusion::{Backend, Model};
use sddpm::error::{Error, NoProgress, Status};
use sddpm::hex::HexMesh;
use sddpm::mesh::{LoadOptions, TriMesh};
use sddpm::pipeline::{generate_polycube, run, ContextRequest, RunOptions};
use std::collections::BTreeSet;

const ALL: [Status; 15] = Status::ALL;

fn data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

fn load(name: &str) -> TriMesh {
    TriMesh::load(data(name), &LoadOptions::default()).expect("test mesh")
}

fn status_of<T>(r: sddpm::Result<T>) -> (Status, String) {
    match r {
        Ok(_) => (Status::Ok, String::new()),
        Err(e) => (e.status(), e.to_string()),
    }
}

#[test]
fn every_header_status_is_in_the_catalogue() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let header = std::fs::read_to_string(root.join("include/sddpm.h")).unwrap();
    let doc = std::fs::read_to_string(root.join("docs/errors.md")).unwrap();
    let mut in_header = BTreeSet::new();
    for line in header.lines() {
        let l = line.trim();
        if let Some(rest) = l.strip_prefix("SDDPM_STATUS_") {
            let name = rest.split(|c: char| c == ' ' || c == '=' || c == ',').next().unwrap();
            in_header.insert(name.to_string());
        }
    }
    assert_eq!(in_header.len(), ALL.len(), "header statuses: {in_header:?}");
    for s in ALL {
        assert!(in_header.contains(s.name()), "{} not in the header", s.name());
        let heading = format!("### {} = {}", s.name(), s as i32);
        assert!(doc.contains(&heading), "docs/errors.md lacks the heading `{heading}`");
    }
}

/// One call per status; the message names what is wrong.
#[test]
fn every_status_is_produced() {
    let mut seen: Vec<(Status, String)> = Vec::new();
    let mut push = |r: (Status, String)| seen.push(r);

    // OK
    push(status_of(TriMesh::from_arrays(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], &[0u32, 1, 2], &LoadOptions::default())));
    // INVALID_ARGUMENT: a coordinate array whose length is not a multiple of 3
    push(status_of(TriMesh::from_arrays(&[0.0; 4], &[0u32, 1, 2], &LoadOptions::default())));
    // IO: a path that does not exist
    push(status_of(TriMesh::load("/nonexistent/part.off", &LoadOptions::default())));
    // PARSE: an OFF file whose face line is cut short
    let dir = std::env::temp_dir().join(format!("sddpm-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad_off = dir.join("short.off");
    std::fs::write(&bad_off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n").unwrap();
    push(status_of(TriMesh::load(&bad_off, &LoadOptions::default())));
    // INVALID_MESH: an open surface
    let open = load("bad/cgal_mech-holes-shark.off");
    push(status_of(open.validate()));
    // INVALID_CONTEXT: a context with 3 labels instead of 12
    push(status_of(Context::parse("cube,0,0")));
    // MODEL: bytes that are not a weights file
    push(status_of(Model::from_bytes(b"not a weights file", Backend::default())));
    // BUFFER_TOO_SMALL and INTERNAL: through the C ABI
    unsafe {
        // a panic inside the C boundary (what the test-hooks build's sddpm_test_force_panic does)
        let st = sddpm::ffi::guard(|| -> sddpm::Result<()> {
            if std::hint::black_box(true) {
                panic!("forced");
            }
            Ok(())
        });
        push((st, "forced panic".into()));
        let mut buf = [0 as std::ffi::c_char; 4];
        let mut need = 0usize;
        let st = sddpm::ffi::sddpm_last_error_message(buf.as_mut_ptr(), buf.len(), &mut need);
        assert!(need > 4, "the message is longer than 4 bytes: {need}");
        push((st, format!("needs {need} bytes")));
    }
    // LIMIT_EXCEEDED: more triangles than an input may have (refused before any check)
    let n = sddpm::mesh::MAX_TRIANGLES + 1;
    let tri = vec![0u32; 3 * n];
    push(status_of(TriMesh::from_arrays(&[0.0; 9], &tri, &LoadOptions::default())));
    // LIMIT_EXCEEDED also for coordinates near the f64 limits and for a microscopic part
    let cube: Vec<f64> = (0..8).flat_map(|i: u32| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
    let quads = [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let tris: Vec<u32> = quads.iter().flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]]).collect();
    for (s, what) in [(1e307, "coordinate of magnitude above"), (1e-300, "below")] {
        let x: Vec<f64> = cube.iter().map(|v| v * s).collect();
        let r = TriMesh::from_arrays(&x, &tris, &LoadOptions::default());
        let (st, m) = status_of(r);
        assert_eq!(st, Status::LimitExceeded, "{m}");
        assert!(m.contains(what), "{m}");
    }
    // a part thinner than the weld distance is refused with the fix, not collapsed silently
    let x: Vec<f64> = cube.chunks(3).flat_map(|p| [p[0] * 1e6, p[1], p[2] * 1e-6]).collect();
    let (st, m) = status_of(TriMesh::from_arrays(&x, &tris, &LoadOptions::default()).and_then(|m| m.validate().map(|_| ())));
    assert_eq!(st, Status::InvalidMesh);
    assert!(m.contains("collapsed") && m.contains("weld tolerance"), "{m}");
    assert!(TriMesh::from_arrays(&x, &tris, &LoadOptions { weld_tolerance: 0.0, ..Default::default() }).unwrap().validate().is_ok());
    // SPLINE_FAILED: a heat-conduction solve on a flat element (singular Jacobian)
    // the unit cube's element (VTK_HEXAHEDRON order) pressed flat onto z = 0
    let flat = HexMesh { nodes: (0..8).map(|i: usize| [((i + 1) / 2 % 2) as f64, (i / 2 % 2) as f64, 0.0]).collect(), elements: vec![[0, 1, 2, 3, 4, 5, 6, 7]] };
    let so = sddpm::spline::SplineOptions { repair_jacobian: false, ..Default::default() };
    push(status_of(sddpm::spline::build_spline(&flat, None, &so, &mut NoProgress).and_then(|sp| {
        sddpm::spline::iga::solve_poisson(&sp, |_| 1.0, |_| 0.0, &sddpm::spline::iga::PoissonOptions::default())
    })));

    let model = Model::default_model().unwrap();
    let hole = load("cgal_hole.off");
    let fast = {
        let mut o = PolycubeOptions::default();
        o.sampler.steps = 5;
        o
    };
    // GENUS_MISMATCH: a genus-0 context for the genus-1 part, refused before diffusion
    let cube = Context::parse("cube,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    push(status_of(generate_polycube(&model, &hole, 1, &ContextRequest::Contexts(vec![cube]), &fast, &AutoOptions::default(), &mut NoProgress)));
    // VERIFICATION_FAILED: an L of three cells leaves a quarter of the box-filling part
    // in the empty fourth cell: the occupancy pre-check refuses it
    let l = Context::parse("THC+Z,cube,0,cube,0,0,0,0,0,0,0,0").unwrap();
    assert_eq!(l.validity().genus, Some(1));
    let (_, _, err) = generate_polycube(&model, &hole, 1, &ContextRequest::Contexts(vec![l]), &fast, &AutoOptions::default(), &mut NoProgress).unwrap();
    let err = err.expect("refused");
    push((err.status(), err.to_string()));
    // CANCELLED: the progress callback says stop
    let mut cancel = |_f: f64, _s: &str| false;
    push(status_of(generate_polycube(&model, &hole, 1, &ContextRequest::Contexts(vec![Context::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap()]), &fast, &AutoOptions::default(), &mut cancel)));
    // MESHING_FAILED: the hex mesh of a one-cell polycube for the two-holed rod keeps
    // inverted elements, and the caller asked for a valid mesh or nothing
    let rod = load("hexgen_rod.obj");
    let mut ro = RunOptions { polycube: fast.clone(), require_valid_hex: true, accept_unverified: true, spline: None, hex_candidates: 1, ..Default::default() };
    ro.hex.map.level = Some(1);
    // the polycube's mesh alone: the grid-based fallback (a minute and more on the
    // rod, with tests of its own) would stand in for it
    ro.hex.fallback.enabled = false;
    let two = Context::parse("THC+Y,THC+Y,0,0,0,0,0,0,0,0,0,0").unwrap();
    let r = run(&model, &rod, 2, &ContextRequest::Contexts(vec![two]), &ro, &mut NoProgress);
    let (st, msg) = status_of(r);
    if st == Status::Ok {
        // the mesh came out valid: then MESHING_FAILED must still be reachable through
        // the mapped mesh alone (no quality steps), which folds on this part
        ro.hex.quality.pillow = false;
        ro.hex.quality.smooth_iterations = 0;
        ro.hex.quality.optimise_passes = 0;
        let r = run(&model, &rod, 2, &ContextRequest::Contexts(vec![Context::parse("THC+Y,THC+Y,0,0,0,0,0,0,0,0,0,0").unwrap()]), &ro, &mut NoProgress);
        push(status_of(r));
    } else {
        push((st, msg));
    }
    let _ = std::fs::remove_dir_all(&dir);

    let produced: BTreeSet<i32> = seen.iter().map(|(s, _)| *s as i32).collect();
    for (s, m) in &seen {
        eprintln!("{:>20}: {m}", s.name());
        if *s != Status::Ok {
            assert!(!m.is_empty(), "{} without a message", s.name());
        }
    }
    for s in ALL {
        assert!(produced.contains(&(s as i32)), "no call produced {}: {seen:?}", s.name());
    }
    // the messages name what is wrong
    let msg = |st: Status| seen.iter().find(|(s, _)| *s == st).unwrap().1.clone();
    assert!(msg(Status::Io).contains("/nonexistent/part.off"));
    assert!(msg(Status::InvalidMesh).contains("boundary edge"), "{}", msg(Status::InvalidMesh));
    assert!(msg(Status::GenusMismatch).contains("genus 1") && msg(Status::GenusMismatch).contains("genus 0"), "{}", msg(Status::GenusMismatch));
    assert!(msg(Status::LimitExceeded).contains("triangles"));
    assert!(msg(Status::SplineFailed).contains("element 0"), "{}", msg(Status::SplineFailed));
    assert!(msg(Status::MeshingFailed).contains("inverted") && msg(Status::MeshingFailed).contains("element"), "{}", msg(Status::MeshingFailed));
    let _ = Error::Internal(String::new());
}

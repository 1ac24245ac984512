//! The C ABI contract, exercised from Rust (the C++ peer in cpp_tests/ does the
//! same through the header): NULL arguments, small buffers, bad paths and a
//! forced panic each give a status and a message, and nothing crashes.

use sddpm::ffi::*;
use sddpm::Status;
use std::ffi::{CStr, CString};
use std::ptr::{null, null_mut};

#[path = "../fuzz/decode.rs"]
mod decode;

fn last_message() -> String {
    let mut needed = 0usize;
    unsafe {
        assert_eq!(sddpm_last_error_message(null_mut(), 0, &mut needed), Status::BufferTooSmall);
        let mut buf = vec![0 as std::ffi::c_char; needed];
        assert_eq!(sddpm_last_error_message(buf.as_mut_ptr(), buf.len(), null_mut()), Status::Ok);
        CStr::from_ptr(buf.as_ptr()).to_string_lossy().into_owned()
    }
}

fn data(name: &str) -> CString {
    CString::new(format!("{}/tests/data/meshes/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn versions() {
    assert_eq!(sddpm_abi_version(), ABI_VERSION);
    let v = unsafe { CStr::from_ptr(sddpm_version_string()) };
    assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    let name = |n: i32| unsafe { CStr::from_ptr(sddpm_status_name(n)).to_str().unwrap().to_string() };
    assert_eq!(name(4), "INVALID_MESH");
    assert_eq!(name(14), "INTERNAL");
    assert_eq!(name(99), "UNKNOWN");
    let header = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/include/sddpm.h")).unwrap();
    assert!(header.contains(&format!("#define SDDPM_ABI_VERSION {ABI_VERSION}\n")), "header and ABI_VERSION disagree");
}

#[test]
fn null_arguments_are_errors() {
    unsafe {
        let mut m = null_mut();
        assert_eq!(sddpm_mesh_load(null(), null(), &mut m), Status::InvalidArgument);
        assert!(last_message().contains("`path` is NULL"));
        assert_eq!(sddpm_mesh_load(data("cgal_hole.off").as_ptr(), null(), null_mut()), Status::InvalidArgument);
        assert!(last_message().contains("`out` is NULL"));
        assert_eq!(sddpm_mesh_new_from_arrays(null(), 3, null(), 1, null(), &mut m), Status::InvalidArgument);
        assert!(m.is_null(), "out written on failure");
        let mut n = 0usize;
        assert_eq!(sddpm_mesh_counts(null(), &mut n, &mut n), Status::InvalidArgument);
        assert_eq!(sddpm_mesh_check(null(), null_mut()), Status::InvalidArgument);
        assert_eq!(sddpm_mesh_validate(null()), Status::InvalidArgument);
        assert_eq!(sddpm_mesh_genus(null(), null_mut()), Status::InvalidArgument);
        assert_eq!(sddpm_mesh_copy_vertices(null(), null_mut(), 0), Status::InvalidArgument);
        assert_eq!(sddpm_load_options_default(null_mut()), Status::InvalidArgument);
        sddpm_mesh_free(null_mut());
        assert_eq!(sddpm_last_error_status(), Status::InvalidArgument);
        sddpm_last_error_clear();
        assert_eq!(sddpm_last_error_status(), Status::Ok);
        assert_eq!(last_message(), "");
    }
}

#[test]
fn arrays_round_trip_and_buffers() {
    let xyz = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let tri = [0u32, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];
    unsafe {
        let mut opts = std::mem::zeroed();
        assert_eq!(sddpm_load_options_default(&mut opts), Status::Ok);
        assert_eq!(opts.weld_tolerance, 1e-9);
        let mut m = null_mut();
        assert_eq!(sddpm_mesh_new_from_arrays(xyz.as_ptr(), 4, tri.as_ptr(), 4, &opts, &mut m), Status::Ok);
        let (mut nv, mut nt) = (0, 0);
        assert_eq!(sddpm_mesh_counts(m, &mut nv, &mut nt), Status::Ok);
        assert_eq!((nv, nt), (4, 4));
        let mut small = [7.0f64; 11];
        assert_eq!(sddpm_mesh_copy_vertices(m, small.as_mut_ptr(), 11), Status::BufferTooSmall);
        assert_eq!(small, [7.0; 11], "written on failure");
        assert!(last_message().contains("12 are needed"));
        let mut out = [0.0f64; 12];
        assert_eq!(sddpm_mesh_copy_vertices(m, out.as_mut_ptr(), 12), Status::Ok);
        assert_eq!(out, xyz);
        let mut t = [0u32; 12];
        assert_eq!(sddpm_mesh_copy_triangles(m, t.as_mut_ptr(), 11), Status::BufferTooSmall);
        assert_eq!(sddpm_mesh_copy_triangles(m, t.as_mut_ptr(), 12), Status::Ok);
        assert_eq!(t, tri);
        let mut g = -5;
        assert_eq!(sddpm_mesh_genus(m, &mut g), Status::Ok);
        assert_eq!(g, 0);
        let mut r = SddpmMeshReport::default();
        assert_eq!(sddpm_mesh_check(m, &mut r), Status::Ok);
        assert!(r.closed && r.can_proceed && (r.volume - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(sddpm_mesh_validate(m), Status::Ok);
        sddpm_mesh_free(m);

        // NaN coordinates and out-of-range indices
        let mut bad = xyz;
        bad[4] = f64::NAN;
        let mut m = null_mut();
        assert_eq!(sddpm_mesh_new_from_arrays(bad.as_ptr(), 4, tri.as_ptr(), 4, null(), &mut m), Status::InvalidMesh);
        assert!(last_message().contains("non-finite"));
        let badtri = [0u32, 1, 4];
        assert_eq!(sddpm_mesh_new_from_arrays(xyz.as_ptr(), 4, badtri.as_ptr(), 1, null(), &mut m), Status::InvalidArgument);
        assert!(m.is_null());
    }
}

#[test]
fn invalid_paths_and_bad_meshes() {
    unsafe {
        let mut m = null_mut();
        let p = CString::new("/no/such/file.off").unwrap();
        assert_eq!(sddpm_mesh_load(p.as_ptr(), null(), &mut m), Status::Io);
        assert!(last_message().contains("/no/such/file.off"));
        assert!(m.is_null());
        assert_eq!(sddpm_mesh_load(data("CATALOG.md").as_ptr(), null(), &mut m), Status::Parse);
        for (name, needle) in [
            ("bad/cgal_bones.off", "26 connected components"),
            ("bad/cgal_cow.off", "non-manifold vertices"),
            ("bad/cgal_mech-holes-shark.off", "304 boundary edges"),
            ("bad/cgal_oblong-shuffled.off", "inconsistent orientation"),
        ] {
            assert_eq!(sddpm_mesh_load(data(name).as_ptr(), null(), &mut m), Status::Ok, "{name}");
            assert_eq!(sddpm_mesh_validate(m), Status::InvalidMesh, "{name}");
            let msg = last_message();
            assert!(msg.contains(needle), "{name}: {msg}");
            sddpm_mesh_free(m);
        }
    }
}

/// A panic inside the boundary every export runs in (what the test-only export
/// sddpm_test_force_panic of the `test-hooks` build does from C).
fn force_panic() -> Status {
    sddpm::ffi::guard(|| -> sddpm::Result<()> {
        if std::hint::black_box(true) {
            panic!("forced by the test");
        }
        Ok(())
    })
}

#[test]
fn a_panic_becomes_internal_and_the_process_survives() {
    let s = force_panic();
    assert_eq!(s, Status::Internal);
    assert_eq!(sddpm_last_error_status(), Status::Internal);
    let msg = last_message();
    assert!(msg.contains("panic") && msg.contains("forced"), "{msg}");
    // and the library still works
    assert_eq!(sddpm_abi_version(), ABI_VERSION);
}

#[test]
fn last_error_is_per_thread() {
    let _ = force_panic();
    let other = std::thread::spawn(|| sddpm_last_error_status()).join().unwrap();
    assert_eq!(other, Status::Ok);
    assert_eq!(sddpm_last_error_status(), Status::Internal);
}

#[test]
fn progress_adapter_cancels_on_nonzero() {
    use sddpm::error::{check_progress, Progress};
    unsafe extern "C" fn cb(f: f64, stage: *const std::ffi::c_char, user: *mut std::ffi::c_void) -> std::ffi::c_int {
        let seen = &mut *(user as *mut Vec<(f64, String)>);
        seen.push((f, CStr::from_ptr(stage).to_string_lossy().into_owned()));
        (f >= 0.5) as std::ffi::c_int
    }
    let mut seen: Vec<(f64, String)> = Vec::new();
    let mut p = CProgress { callback: Some(cb), user_data: &mut seen as *mut _ as *mut std::ffi::c_void };
    assert!(p.report(0.25, "load"));
    let e = check_progress(&mut p, 0.5, "check").unwrap_err();
    assert_eq!(e.status(), Status::Cancelled);
    assert_eq!(seen, vec![(0.25, "load".to_string()), (0.5, "check".to_string())]);
}

/// Hex and spline handles: NULL arguments, small buffers, out-of-range element and
/// parameters, bad format, a cancel from the callback; out-parameters untouched on failure.
#[test]
fn hex_and_spline_handles_contract() {
    unsafe extern "C" fn cancel(_f: f64, _s: *const std::ffi::c_char, _u: *mut std::ffi::c_void) -> std::ffi::c_int {
        1
    }
    unsafe {
        let mut h = null_mut();
        assert_eq!(sddpm_hex_mesh_build(null(), null(), None, null_mut(), &mut h), Status::InvalidArgument);
        assert!(last_message().contains("`polycube` is NULL"));
        assert!(h.is_null());
        // the unit cube from arrays, then one with a bad index
        let xyz = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 0., 0., 1., 1., 0., 1., 1., 1., 1., 0., 1., 1.];
        let bad = [0u32, 1, 2, 3, 4, 5, 6, 8];
        assert_eq!(sddpm_hex_mesh_new_from_arrays(xyz.as_ptr(), 8, bad.as_ptr(), 1, &mut h), Status::InvalidArgument);
        assert!(last_message().contains("element 0 refers to node 8"));
        let conn = [0u32, 1, 2, 3, 4, 5, 6, 7];
        assert_eq!(sddpm_hex_mesh_new_from_arrays(xyz.as_ptr(), 8, conn.as_ptr(), 1, &mut h), Status::Ok);
        let mut q = std::mem::zeroed::<SddpmHexQuality>();
        assert_eq!(sddpm_hex_mesh_quality(h, &mut q), Status::Ok);
        assert_eq!((q.elements, q.nodes, q.inverted, q.level), (1, 8, 0, -1));
        assert!((q.min_scaled_jacobian - 1.0).abs() < 1e-15 && (q.volume - 1.0).abs() < 1e-14);
        let mut small = [0f64; 5];
        assert_eq!(sddpm_hex_mesh_copy_nodes(h, small.as_mut_ptr(), small.len()), Status::BufferTooSmall);
        assert!(last_message().contains("24 values needed"));
        assert_eq!(small, [0.0; 5], "buffer touched on failure");
        let mut counts = [0usize; 4];
        assert_eq!(sddpm_hex_mesh_histogram(h, counts.as_mut_ptr(), 4), Status::Ok);
        assert_eq!(counts, [0, 0, 0, 1]);
        // the report of a mesh from arrays counts its irregular edges as
        // report.json does (the twelve edges of one cube, each on one element)
        let mut need = 0usize;
        assert_eq!(sddpm_hex_mesh_report_json(h, null_mut(), 0, &mut need), Status::BufferTooSmall);
        let mut buf = vec![0 as std::os::raw::c_char; need];
        assert_eq!(sddpm_hex_mesh_report_json(h, buf.as_mut_ptr(), need, null_mut()), Status::Ok);
        let rep: serde_json::Value = serde_json::from_str(std::ffi::CStr::from_ptr(buf.as_ptr()).to_str().unwrap()).unwrap();
        assert_eq!(rep["irregular_edges"], 12, "{rep}");
        assert_eq!(rep["irregular_edges_boundary"], 12, "{rep}");
        let dir = std::env::temp_dir().join(format!("sddpm-ffi-hex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = CString::new(dir.join("cube.k").to_str().unwrap()).unwrap();
        assert_eq!(sddpm_hex_mesh_write(h, path.as_ptr(), 7), Status::InvalidArgument);
        assert!(last_message().contains("format 7"));
        assert_eq!(sddpm_hex_mesh_write(h, path.as_ptr(), SddpmHexFormat::Lsdyna as i32), Status::Ok);
        assert!(std::fs::read_to_string(dir.join("cube.k")).unwrap().contains("*ELEMENT_SOLID"));
        // spline of the cube: cancel, then build
        let mut s = null_mut();
        assert_eq!(sddpm_spline_build(h, null(), null(), Some(cancel), null_mut(), &mut s), Status::Cancelled);
        assert!(s.is_null());
        let mut o = null_mut();
        assert_eq!(sddpm_options_new(&mut o), Status::Ok);
        let fit = CString::new("spline.fit.enabled").unwrap();
        assert_eq!(sddpm_options_set_bool(o, fit.as_ptr(), false), Status::Ok);
        assert_eq!(sddpm_spline_build(h, null(), o, None, null_mut(), &mut s), Status::Ok);
        sddpm_options_free(o);
        let (mut ne, mut nb) = (0usize, 0usize);
        assert_eq!(sddpm_spline_counts(s, &mut ne, &mut nb), Status::Ok);
        assert_eq!(ne, 1);
        let mut n = 0usize;
        assert_eq!(sddpm_spline_element_extraction(s, 0, null_mut(), null_mut(), 0, &mut n), Status::BufferTooSmall);
        assert!(n > 0 && n <= nb);
        let mut ids = vec![0u32; n];
        let mut op = vec![0f64; 64 * n];
        assert_eq!(sddpm_spline_element_extraction(s, 0, ids.as_mut_ptr(), op.as_mut_ptr(), n, &mut n), Status::Ok);
        for b in 0..64 {
            let col: f64 = (0..n).map(|r| op[r * 64 + b]).sum();
            assert!((col - 1.0).abs() < 1e-12, "partition of unity, Bernstein {b}: {col}");
        }
        assert_eq!(sddpm_spline_element_extraction(s, 1, ids.as_mut_ptr(), op.as_mut_ptr(), n, &mut n), Status::InvalidArgument);
        assert!(last_message().contains("element 1 does not exist"));
        let mut x = [0f64; 3];
        let mut j = [0f64; 9];
        assert_eq!(sddpm_spline_evaluate(s, 0, 0.5, 0.5, 0.5, x.as_mut_ptr(), j.as_mut_ptr()), Status::Ok);
        assert!(x.iter().all(|v| (v - 0.5).abs() < 1e-12), "{x:?}");
        assert_eq!(sddpm_spline_evaluate(s, 0, -0.1, 0.5, 0.5, x.as_mut_ptr(), null_mut()), Status::InvalidArgument);
        let dpath = CString::new(dir.to_str().unwrap()).unwrap();
        assert_eq!(sddpm_spline_write(s, dpath.as_ptr()), Status::Ok);
        assert!(dir.join("spline.bext").is_file() && dir.join("model.k").is_file());
        sddpm_spline_free(s);
        sddpm_spline_free(null_mut());
        sddpm_hex_mesh_free(h);
        sddpm_hex_mesh_free(null_mut());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The slow units the fuzzer found in `ffi_inputs` (docs/fuzzing.md): constraint sets
/// over five or six allowed cells with free counts, decoded exactly as the fuzz target
/// decodes its selector-4 inputs (fuzz/decode.rs). The first enumerated for 24 s under
/// ASan before `context::MAX_ASSIGNMENTS`; the two of 2026-12-03 took 100 and 127 s
/// under ASan on a loaded machine, 2–6 s in a release build, within that bound. Each
/// gives contexts or a refusal (INVALID_ARGUMENT: too loose, with how to narrow them;
/// INVALID_CONTEXT: nothing satisfies them).
#[test]
fn fuzz_regression_slow_constraints_end_with_a_status() {
    for name in ["ffi_inputs-slow-constraints.bin", "ffi_inputs-slow-constraints-2.bin", "ffi_inputs-slow-constraints-3.bin"] {
        replay_constraints_unit(name);
    }
}

fn replay_constraints_unit(name: &str) {
    let data = std::fs::read(format!("{}/tests/data/fuzz/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let (&sel, rest) = data.split_first().unwrap();
    assert_eq!(sel % 6, 4, "the unit is a constraint set");
    let k = decode::constraints(rest).expect("24 bytes or more");
    unsafe {
        let mut c = null_mut();
        match sddpm_context_new_from_constraints(&k, &mut c) {
            Status::Ok => {
                let mut n = 0usize;
                assert_eq!(sddpm_context_count(c, &mut n), Status::Ok);
                assert!(n > 0);
                sddpm_context_free(c);
            }
            Status::InvalidArgument | Status::InvalidContext => {
                assert!(c.is_null());
                let m = last_message();
                assert!(m.contains("label assignments") || m.contains("constraint"), "{m}");
            }
            s => panic!("unexpected status {s:?}: {}", last_message()),
        }
    }
}

/// The polycube report of one explicit-context run through the C ABI, without its
/// timings (which differ from run to run).
unsafe fn polycube_report(model: *const SddpmModel, mesh: *const SddpmMesh, ctx: *const SddpmContext, seed: u64) -> String {
    let mut o = null_mut();
    assert_eq!(sddpm_options_new(&mut o), Status::Ok);
    for name in ["polycube.seed", "polycube.sampler.seed"] {
        let n = CString::new(name).unwrap();
        assert_eq!(sddpm_options_set_number(o, n.as_ptr(), seed as f64), Status::Ok);
    }
    let mut p = null_mut();
    assert_eq!(sddpm_generate_polycube(model, mesh, ctx, null(), null(), o, None, null_mut(), &mut p), Status::Ok, "{}", last_message());
    sddpm_options_free(o);
    let mut need = 0usize;
    assert_eq!(sddpm_polycube_report_json(p, null_mut(), 0, &mut need), Status::BufferTooSmall);
    let mut buf = vec![0 as std::ffi::c_char; need];
    assert_eq!(sddpm_polycube_report_json(p, buf.as_mut_ptr(), need, null_mut()), Status::Ok);
    sddpm_polycube_free(p);
    let mut j: serde_json::Value = serde_json::from_str(CStr::from_ptr(buf.as_ptr()).to_str().unwrap()).unwrap();
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("timings");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    strip(&mut j);
    j.to_string()
}

/// The default model, the through-hole test mesh and its true context (THC+Z), as
/// C handles (the caller frees them).
unsafe fn hole_handles() -> (*mut SddpmModel, *mut SddpmMesh, *mut SddpmContext) {
    let mut model = null_mut();
    assert_eq!(sddpm_model_new_default(&mut model), Status::Ok);
    let mut mesh = null_mut();
    assert_eq!(sddpm_mesh_load(data("cgal_hole.off").as_ptr(), null(), &mut mesh), Status::Ok);
    let mut ctx = null_mut();
    let s = CString::new("THC+Z,0,0,0,0,0,0,0,0,0,0,0").unwrap();
    assert_eq!(sddpm_context_new_from_string(s.as_ptr(), &mut ctx), Status::Ok);
    (model, mesh, ctx)
}

/// The options handle carries the core's defaults; a value out of range is refused
/// at once naming the option (the handle keeps its valid value), an unknown name
/// is refused naming it, and the generation takes what was set (0: the
/// neighbour test off).
#[test]
fn options_handle_defaults_refusals_and_a_neighbour_ratio() {
    unsafe {
        let mut o = null_mut();
        assert_eq!(sddpm_options_new(&mut o), Status::Ok);
        let name = CString::new("polycube.neighbour_fit_ratio").unwrap();
        let core = sddpm::search::generate::PolycubeOptions::default();
        let mut x = 0.0;
        assert_eq!(sddpm_options_get_number(o, name.as_ptr(), &mut x), Status::Ok);
        assert_eq!(x, core.neighbour_fit_ratio);
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(sddpm_options_set_number(o, name.as_ptr(), bad), Status::InvalidArgument);
            assert!(last_message().contains("option polycube.neighbour_fit_ratio must be"), "{}", last_message());
        }
        assert_eq!(sddpm_options_get_number(o, name.as_ptr(), &mut x), Status::Ok);
        assert_eq!(x, core.neighbour_fit_ratio, "a refused value changed the option");
        let unknown = CString::new("polycube.neighbor_fit_ratio").unwrap();
        assert_eq!(sddpm_options_set_number(o, unknown.as_ptr(), 1.0), Status::InvalidArgument);
        assert!(last_message().contains("unknown option \"polycube.neighbor_fit_ratio\""), "{}", last_message());
        let mut need = 0usize;
        assert_eq!(sddpm_options_describe_json(o, null_mut(), 0, &mut need), Status::BufferTooSmall);
        let mut buf = vec![0 as std::ffi::c_char; need];
        assert_eq!(sddpm_options_describe_json(o, buf.as_mut_ptr(), need, null_mut()), Status::Ok);
        let j: serde_json::Value = serde_json::from_str(CStr::from_ptr(buf.as_ptr()).to_str().unwrap()).unwrap();
        assert_eq!(j.as_object().unwrap().len(), sddpm::pipeline::options::OPTIONS.len());
        assert_eq!(j["hex.goals.hausdorff"]["default"].as_f64(), Some(0.01));

        assert_eq!(sddpm_options_set_number(o, name.as_ptr(), 0.0), Status::Ok);
        let (model, mesh, ctx) = hole_handles();
        let mut p = null_mut();
        assert_eq!(sddpm_generate_polycube(model, mesh, ctx, null(), null(), o, None, null_mut(), &mut p), Status::Ok, "{}", last_message());
        sddpm_polycube_free(p);
        sddpm_options_free(o);
        sddpm_context_free(ctx);
        sddpm_mesh_free(mesh);
        sddpm_model_free(model);
    }
}

/// One model handle, one mesh handle and one context handle shared by four threads
/// running polycube generation at once through the C ABI: every report equals the
/// sequential run's with the same seed (the handles are documented as usable from
/// several threads at once).
#[test]
fn c_abi_handles_shared_by_four_threads_give_the_sequential_results() {
    unsafe {
        let (model, mesh, ctx) = hole_handles();
        let seeds = [1u64, 2, 1, 3];
        let seq: Vec<String> = seeds.iter().map(|&sd| polycube_report(model, mesh, ctx, sd)).collect();
        assert_eq!(seq[0], seq[2], "the same seed gave two different reports");
        assert_ne!(seq[0], seq[1], "the seed has no effect");
        let (m, me, c) = (model as usize, mesh as usize, ctx as usize);
        let par: Vec<String> = std::thread::scope(|sc| {
            let hs: Vec<_> = seeds.iter().map(|&sd| sc.spawn(move || polycube_report(m as *const _, me as *const _, c as *const _, sd))).collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (i, (a, b)) in seq.iter().zip(&par).enumerate() {
            assert!(a == b, "thread {i}: the concurrent report differs from the sequential one");
        }
        sddpm_context_free(ctx);
        sddpm_mesh_free(mesh);
        sddpm_model_free(model);
    }
}

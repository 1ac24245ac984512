//! The C ABI contract, exercised from Rust (the C++ peer in cpp_tests/ does the
//! same through the header): NULL arguments, small buffers, bad paths and a
//! forced panic each give a status and a message, and nothing crashes.

use sddpm::ffi::*;
use sddpm::Status;
use std::ffi::{CStr, CString};
use std::ptr::{null, null_mut};

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

#[test]
fn a_panic_becomes_internal_and_the_process_survives() {
    let s = sddpm_test_force_panic();
    assert_eq!(s, Status::Internal);
    assert_eq!(sddpm_last_error_status(), Status::Internal);
    let msg = last_message();
    assert!(msg.contains("panic") && msg.contains("forced"), "{msg}");
    // and the library still works
    assert_eq!(sddpm_abi_version(), ABI_VERSION);
}

#[test]
fn last_error_is_per_thread() {
    let _ = sddpm_test_force_panic();
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

//! C ABI entry points that take caller data: mesh arrays, context labels, one-hot
//! vectors, context strings, constraints, hex arrays, load options and the copy
//! functions' capacities, weights bytes, polycube options and ratios (the search is
//! cancelled at its first progress report, so what runs is the argument checking
//! and the work before it), spline options and the evaluate / extraction
//! arguments. Every call must return a status (never crash, never hang).
#![no_main]
use libfuzzer_sys::fuzz_target;
use sddpm::ffi::*;
use std::ptr::null_mut;

#[path = "../decode.rs"]
mod decode;

fn f64s(b: &[u8]) -> Vec<f64> {
    b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()
}
fn u32s(b: &[u8]) -> Vec<u32> {
    b.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect()
}
fn f64_at(b: &[u8], i: usize) -> f64 {
    b.get(8 * i..8 * i + 8).map_or(0.5, |c| f64::from_le_bytes(c.try_into().unwrap()))
}

/// The unit cube's surface (8 vertices, 12 triangles, outward).
fn cube_arrays() -> (Vec<f64>, Vec<u32>) {
    let xyz: Vec<f64> = (0..8u32).flat_map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
    let quads = [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    (xyz, quads.iter().flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]]).collect())
}

unsafe extern "C" fn cancel_at_once(_f: f64, _stage: *const std::ffi::c_char, _u: *mut std::ffi::c_void) -> std::ffi::c_int {
    1
}

/// The embedded model, decoded once (the handle is shared read-only).
fn model() -> *const SddpmModel {
    static M: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *M.get_or_init(|| unsafe {
        let mut m = null_mut();
        assert_eq!(sddpm_model_new_default(&mut m), sddpm::Status::Ok);
        m as usize
    }) as *const SddpmModel
}

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else { return };
    let half = rest.len() / 2;
    unsafe {
        match sel % 10 {
            0 => {
                let (xyz, tri) = (f64s(&rest[..half]), u32s(&rest[half..]));
                let mut m = null_mut();
                if sddpm_mesh_new_from_arrays(xyz.as_ptr(), xyz.len() / 3, tri.as_ptr(), tri.len() / 3, std::ptr::null(), &mut m) == sddpm::Status::Ok {
                    let _ = sddpm_mesh_validate(m);
                    sddpm_mesh_free(m);
                }
            }
            1 => {
                let labels: Vec<i32> = u32s(rest).into_iter().map(|v| (v % 16) as i32 - 2).collect();
                let mut c = null_mut();
                if sddpm_context_new_from_labels(labels.as_ptr(), labels.len(), &mut c) == sddpm::Status::Ok {
                    let mut g = 0i64;
                    let _ = sddpm_context_genus(c, 0, &mut g);
                    sddpm_context_free(c);
                }
            }
            2 => {
                let v: Vec<f32> = rest.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
                let mut c = null_mut();
                if sddpm_context_new_from_one_hot(v.as_ptr(), v.len(), &mut c) == sddpm::Status::Ok {
                    sddpm_context_free(c);
                }
            }
            3 => {
                let mut s: Vec<u8> = rest.iter().copied().filter(|&b| b != 0).collect();
                s.push(0);
                let mut c = null_mut();
                if sddpm_context_new_from_string(s.as_ptr() as *const std::ffi::c_char, &mut c) == sddpm::Status::Ok {
                    sddpm_context_free(c);
                }
            }
            4 => {
                let Some(k) = decode::constraints(rest) else { return };
                // the full grid with free counts is large: keep fuzzing iterations short
                if (k.allowed_mask & 0x0fff).count_ones() > 6 {
                    return;
                }
                let mut c = null_mut();
                if sddpm_context_new_from_constraints(&k, &mut c) == sddpm::Status::Ok {
                    sddpm_context_free(c);
                }
            }
            6 => {
                // load options and the copy functions' capacities
                let mut o = std::mem::zeroed::<SddpmLoadOptions>();
                let _ = sddpm_load_options_default(&mut o);
                o.weld_tolerance = f64_at(rest, 0);
                o.remove_unreferenced = rest.get(8).is_some_and(|b| b & 1 == 1);
                o.repair_orientation = rest.get(8).is_some_and(|b| b & 2 == 2);
                let (xyz, tri) = cube_arrays();
                let mut m = null_mut();
                if sddpm_mesh_new_from_arrays(xyz.as_ptr(), 8, tri.as_ptr(), 12, &o, &mut m) == sddpm::Status::Ok {
                    let cap = rest.get(9).copied().unwrap_or(0) as usize;
                    let mut v = vec![0.0f64; cap];
                    let mut t = vec![0u32; cap];
                    let _ = sddpm_mesh_copy_vertices(m, v.as_mut_ptr(), cap);
                    let _ = sddpm_mesh_copy_triangles(m, t.as_mut_ptr(), cap);
                    let mut r = std::mem::zeroed::<SddpmMeshReport>();
                    let _ = sddpm_mesh_check(m, &mut r);
                    let mut buf = vec![0 as std::ffi::c_char; cap];
                    let mut need = 0usize;
                    let _ = sddpm_last_error_message(buf.as_mut_ptr(), cap, &mut need);
                    sddpm_mesh_free(m);
                }
            }
            7 => {
                let mut m = null_mut();
                if sddpm_model_new_from_bytes(rest.as_ptr(), rest.len(), &mut m) == sddpm::Status::Ok {
                    sddpm_model_free(m);
                }
            }
            8 => {
                // polycube options and ratios, cancelled at the first progress report
                let mut o = std::mem::zeroed::<SddpmPolycubeOptions>();
                let _ = sddpm_polycube_options_default(&mut o);
                o.seed = rest.first().copied().unwrap_or(0) as u64;
                o.sampler_steps = u32s(rest.get(1..5).unwrap_or(&[])).first().copied().unwrap_or(0) % 1024;
                o.orientations = rest.get(5).copied().unwrap_or(2) as u32 % 4;
                o.tau_cd = f64_at(rest, 1);
                o.max_in_empty_fraction = f64_at(rest, 2);
                o.max_fit = f64_at(rest, 3);
                o.auto_resolution = u32s(rest.get(32..36).unwrap_or(&[])).first().copied().unwrap_or(48);
                let ratios: Vec<f64> = (0..7).map(|i| f64_at(rest, 5 + i)).collect();
                let use_ratios = rest.get(6).is_some_and(|b| b & 1 == 1);
                let (xyz, tri) = cube_arrays();
                let mut m = null_mut();
                if sddpm_mesh_new_from_arrays(xyz.as_ptr(), 8, tri.as_ptr(), 12, std::ptr::null(), &mut m) == sddpm::Status::Ok {
                    let mut p = null_mut();
                    let r = if use_ratios { ratios.as_ptr() } else { std::ptr::null() };
                    if sddpm_generate_polycube(model(), m, std::ptr::null(), std::ptr::null(), r, &o, Some(cancel_at_once), null_mut(), &mut p) == sddpm::Status::Ok {
                        sddpm_polycube_free(p);
                    }
                    sddpm_mesh_free(m);
                }
            }
            9 => {
                // spline options, then evaluation and extraction at caller-chosen arguments
                let mut o = std::mem::zeroed::<SddpmSplineOptions>();
                let _ = sddpm_spline_options_default(&mut o);
                o.sharp_angle_deg = f64_at(rest, 0);
                let flags = rest.get(8).copied().unwrap_or(0);
                o.boundary_enrichment = flags & 1 == 1;
                o.interpolate_vertices = flags & 2 == 2;
                o.repair_jacobian = flags & 4 == 4;
                o.fit = flags & 8 == 8;
                o.sparse_bext = flags & 16 == 16;
                let xyz: Vec<f64> = (0..8u32).flat_map(|i| [((i + 1) / 2 % 2) as f64, (i / 2 % 2) as f64, (i / 4) as f64]).collect();
                let conn: Vec<u32> = (0..8).collect();
                let mut h = null_mut();
                if sddpm_hex_mesh_new_from_arrays(xyz.as_ptr(), 8, conn.as_ptr(), 1, &mut h) != sddpm::Status::Ok {
                    return;
                }
                let mut sp = null_mut();
                if sddpm_spline_build(h, std::ptr::null(), &o, None, null_mut(), &mut sp) == sddpm::Status::Ok {
                    let e = rest.get(9).copied().unwrap_or(0) as usize % 4;
                    let mut x = [0.0f64; 3];
                    let mut j = [0.0f64; 9];
                    let _ = sddpm_spline_evaluate(sp, e, f64_at(rest, 2), f64_at(rest, 3), f64_at(rest, 4), x.as_mut_ptr(), j.as_mut_ptr());
                    let cap = rest.get(10).copied().unwrap_or(0) as usize % 128;
                    let mut ids = vec![0u32; cap];
                    let mut op = vec![0.0f64; 64 * cap];
                    let mut n = 0usize;
                    let _ = sddpm_spline_element_extraction(sp, e, ids.as_mut_ptr(), op.as_mut_ptr(), cap, &mut n);
                    sddpm_spline_free(sp);
                }
                sddpm_hex_mesh_free(h);
            }
            _ => {
                let (xyz, conn) = (f64s(&rest[..half]), u32s(&rest[half..]));
                let mut h = null_mut();
                if sddpm_hex_mesh_new_from_arrays(xyz.as_ptr(), xyz.len() / 3, conn.as_ptr(), conn.len() / 8, &mut h) == sddpm::Status::Ok {
                    let mut q = std::mem::zeroed::<SddpmHexQuality>();
                    let _ = sddpm_hex_mesh_quality(h, &mut q);
                    sddpm_hex_mesh_free(h);
                }
            }
        }
    }
});

//! C ABI entry points that take caller data: mesh arrays, context labels, one-hot
//! vectors, context strings, constraints, hex arrays. Every call must return a
//! status (never crash, never hang).
#![no_main]
use libfuzzer_sys::fuzz_target;
use sddpm::ffi::*;
use std::ptr::null_mut;

fn f64s(b: &[u8]) -> Vec<f64> {
    b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()
}
fn u32s(b: &[u8]) -> Vec<u32> {
    b.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect()
}

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else { return };
    let half = rest.len() / 2;
    unsafe {
        match sel % 6 {
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
                if rest.len() < 24 {
                    return;
                }
                let mut k = std::mem::zeroed::<SddpmConstraints>();
                let _ = sddpm_constraints_default(&mut k);
                k.cube = (rest[0] % 14) as i32 - 1;
                k.thc = (rest[1] % 14) as i32 - 1;
                k.bhc = (rest[2] % 14) as i32 - 1;
                k.allowed_mask = u16::from_le_bytes([rest[3], rest[4]]);
                k.required_mask = u16::from_le_bytes([rest[5], rest[6]]) & k.allowed_mask;
                k.genus = (rest[7] % 6) as i64 - 1;
                for i in 0..11 {
                    k.per_label[i] = if rest[8 + i] % 3 == 0 { (rest[8 + i] % 5) as i32 } else { -1 };
                }
                // the full grid with free counts is large: keep fuzzing iterations short
                if (k.allowed_mask & 0x0fff).count_ones() > 6 {
                    return;
                }
                let mut c = null_mut();
                if sddpm_context_new_from_constraints(&k, &mut c) == sddpm::Status::Ok {
                    sddpm_context_free(c);
                }
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

//! How the `ffi_inputs` fuzz target turns bytes into C ABI arguments, shared with
//! the regression tests (tests/ffi.rs includes this file) so that a unit the
//! fuzzer found is replayed exactly.
use sddpm::ffi::{sddpm_constraints_default, SddpmConstraints};

/// Selector 4: a constraint set from at least 24 bytes (None if shorter).
pub fn constraints(rest: &[u8]) -> Option<SddpmConstraints> {
    if rest.len() < 24 {
        return None;
    }
    // SAFETY: SddpmConstraints is plain data; the default fills every field.
    let mut k = unsafe { std::mem::zeroed::<SddpmConstraints>() };
    unsafe {
        let _ = sddpm_constraints_default(&mut k);
    }
    k.cube = (rest[0] % 14) as i32 - 1;
    k.thc = (rest[1] % 14) as i32 - 1;
    k.bhc = (rest[2] % 14) as i32 - 1;
    k.allowed_mask = u16::from_le_bytes([rest[3], rest[4]]);
    k.required_mask = u16::from_le_bytes([rest[5], rest[6]]) & k.allowed_mask;
    k.genus = (rest[7] % 6) as i64 - 1;
    for i in 0..11 {
        k.per_label[i] = if rest[8 + i] % 3 == 0 { (rest[8 + i] % 5) as i32 } else { -1 };
    }
    Some(k)
}

//! OBJ / STL / OFF readers and the mesh checks: the first byte picks the format
//! (0 OBJ, 1 STL, 2 OFF, else sniffed), the rest is the file.
#![no_main]
use libfuzzer_sys::fuzz_target;
use sddpm::mesh::{Format, LoadOptions, TriMesh};

fuzz_target!(|data: &[u8]| {
    let Some((&sel, bytes)) = data.split_first() else { return };
    let format = match sel % 4 {
        0 => Some(Format::Obj),
        1 => Some(Format::Stl),
        2 => Some(Format::Off),
        _ => None,
    };
    if let Ok(m) = TriMesh::from_bytes(bytes, format, "fuzz", &LoadOptions::default()) {
        let _ = m.check();
        let _ = m.validate();
    }
});

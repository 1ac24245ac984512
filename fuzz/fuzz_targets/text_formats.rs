//! The text readers of the export formats (BEXT, VTU, Medit, LS-DYNA keyword).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, bytes)) = data.split_first() else { return };
    let text = String::from_utf8_lossy(bytes);
    match sel % 4 {
        0 => drop(sddpm::export::bext::parse_bext(&text)),
        1 => drop(sddpm::export::hexfmt::parse_vtu(&text)),
        2 => drop(sddpm::export::hexfmt::parse_medit(&text)),
        _ => drop(sddpm::export::hexfmt::parse_lsdyna(&text)),
    }
});

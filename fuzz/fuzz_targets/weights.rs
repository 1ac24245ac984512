//! The weights-file reader (SDDPMW header + burnpack record).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = sddpm::diffusion::Model::from_bytes(data, sddpm::diffusion::Backend::default());
});

//! Any bytes: the PC2 and glb readers return data or an error, never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = surfcap_formats::pc2::parse_pc2(data);
    let _ = surfcap_formats::glb::parse_glb(data);
});

//! Any bytes: the PLY reader returns a mesh or an error, never panics or allocates from a
//! header's claimed counts alone.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = surfcap_formats::ply::parse_ply(data) {
        let _ = m.topology();
    }
});

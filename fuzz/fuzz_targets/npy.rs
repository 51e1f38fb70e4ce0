//! Any bytes: the npy reader returns an array or an error for every element type.
#![no_main]
use libfuzzer_sys::fuzz_target;
use surfcap_mesh::npy::parse_npy;

fuzz_target!(|data: &[u8]| {
    let n = data.len() as u64;
    let _ = parse_npy::<f32>(data, n);
    let _ = parse_npy::<u32>(data, n);
    let _ = parse_npy::<u8>(data, n);
});

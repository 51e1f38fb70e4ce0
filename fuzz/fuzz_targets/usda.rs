//! Any bytes: the `.usda` reader returns a stage or an error, never panics, overflows the stack
//! or allocates beyond what its input holds; a stage it returns has meshes whose positions fit
//! their topology.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(s) = surfcap_formats::usda_read::parse_usda(data) {
        for m in &s.meshes {
            let v = m.topology.n_vertices() * 3;
            assert!(v > 0 && m.positions.len() == v * m.times.len());
            assert!(m.positions.iter().all(|x| x.is_finite()));
        }
    }
});

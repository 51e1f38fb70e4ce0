//! Any bytes: the BVH reader returns a clip or an error, never panics, overflows the stack or
//! allocates beyond its input; a clip it returns runs forward kinematics and the unit guess on
//! its first and last frames.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(b) = surfcap_builtin::bvh::parse_bvh(text) {
        let _ = b.world(0);
        let _ = b.world(b.n_frames() - 1);
        let _ = (b.fps(), b.guess_metres_per_unit());
    }
});

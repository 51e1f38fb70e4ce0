//! Any bytes: the OBJ reader returns a mesh or an error, never panics; a mesh it returns
//! has a valid topology or a clear error for it.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = surfcap_formats::obj::parse_obj(data) {
        let _ = m.topology();
    }
});

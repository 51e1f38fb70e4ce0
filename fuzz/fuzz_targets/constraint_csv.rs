//! Any bytes as a synthesis constraint file: the first byte picks the reader (curve with an up
//! axis and planar flag, key poses, or a tag restriction), the rest is its text. Each returns
//! a value or an error naming the line, never panics. The subject is a small built-in tube with
//! tagged sequences, so frame specs and tags resolve.
#![no_main]
use std::path::Path;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use surfcap_mesh::{Subject, UpAxis};
use surfcap_pipeline::constraint_files::{parse_curve, parse_key_poses, parse_restriction};

fn subject() -> &'static Subject {
    static S: OnceLock<Subject> = OnceLock::new();
    S.get_or_init(|| {
        let p = surfcap_builtin::WormParams { rings: 4, segments: 4, frames: 8, ..Default::default() };
        surfcap_builtin::worm_subject(&p).expect("the built-in worm")
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let Ok(text) = std::str::from_utf8(rest) else { return };
    let path = Path::new("fuzz.csv");
    match pick % 4 {
        0 | 1 => {
            let up = [UpAxis::PosY, UpAxis::PosZ][(pick / 4 % 2) as usize];
            if let Ok(c) = parse_curve(text, path, up, pick % 4 == 1) {
                let _ = c.at(c.length() / 2.0);
            }
        }
        2 => {
            let _ = parse_key_poses(text, path, subject());
        }
        _ => {
            let _ = parse_restriction(subject(), text);
        }
    }
});

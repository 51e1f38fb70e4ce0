//! Any bytes: the Alembic (`.abc`, Ogawa) reader returns an archive or an error, never panics,
//! loops, overflows the stack or allocates beyond what its input holds; an archive it returns
//! has meshes whose positions fit their topology, one frame per sample time, all finite.
#![no_main]
use libfuzzer_sys::fuzz_target;
use surfcap_formats::abc_read::{AbcFrames, parse_abc};

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = parse_abc(data) {
        assert!(!a.meshes.is_empty());
        for m in &a.meshes {
            let n = m.times.len();
            match &m.frames {
                AbcFrames::Constant { topology, positions } => {
                    let v = topology.n_vertices() * 3;
                    assert!(v > 0 && positions.len() == v * n);
                    assert!(positions.iter().all(|x| x.is_finite()));
                }
                AbcFrames::Varying { frames } => {
                    assert_eq!(frames.len(), n);
                    for f in frames {
                        assert_eq!(f.positions.len(), f.topology.n_vertices() * 3);
                        assert!(f.positions.iter().all(|x| x.is_finite()));
                    }
                    assert!(m.topology_change().is_some());
                }
            }
            if let Some(l) = &m.labels {
                assert_eq!(l.len(), n);
            }
        }
    }
});

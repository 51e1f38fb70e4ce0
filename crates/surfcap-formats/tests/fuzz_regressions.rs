//! Inputs the fuzzers found (see fuzz/FINDINGS.md): each must give an error, quickly and
//! without a crash or a huge allocation. (The npy cases are surfcap-mesh's.)

use std::path::Path;

use surfcap_mesh::ErrorKind;

fn case(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions").join(name)
}

#[test]
fn glb_with_a_header_length_below_12_is_an_error_not_a_panic() {
    for name in ["glb_length_underflow.bin", "glb_version_0.bin"] {
        let bytes = std::fs::read(case(name)).unwrap();
        let e = surfcap_formats::glb::parse_glb(&bytes).unwrap_err();
        assert!(!e.message.contains("malformed"), "{name}: caught a panic instead of checking: {e}");
        assert!(surfcap_formats::pc2::parse_pc2(&bytes).is_err());
    }
}

#[test]
fn pc2_whose_point_and_sample_counts_overflow_is_an_error() {
    let bytes = std::fs::read(case("pc2_count_overflow.bin")).unwrap();
    let e = surfcap_formats::pc2::parse_pc2(&bytes).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Truncated, "{e}");
}

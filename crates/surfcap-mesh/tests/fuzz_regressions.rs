//! Inputs the fuzzers found (see fuzz/FINDINGS.md): each must give an error, quickly and
//! without a crash or a huge allocation.

use std::path::Path;

use surfcap_mesh::ErrorKind;
use surfcap_mesh::npy::read_npy;

fn case(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions").join(name)
}

#[test]
fn npy_header_length_of_3_gb_is_an_error_not_an_allocation() {
    let e = read_npy::<f32>(&case("npy_header_length_3gb.npy")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Truncated, "{e}");
    assert!(e.to_string().contains("npy_header_length_3gb.npy"), "{e}");
}

/// Headers nesting dozens of brackets: npyz's backtracking grammar ran for minutes on them
/// (the npy target's 254-byte timeout input of 2026-11-23, and a 196-byte shape nesting 40
/// brackets). Now refused before npyz sees them.
#[test]
fn npy_header_with_deeply_nested_brackets_is_refused_before_parsing() {
    let e = read_npy::<f32>(&case("npy_nested_braces_timeout.npy")).unwrap_err();
    assert!(
        e.to_string().ends_with("byte 22: header nests brackets deeper than 4: expected a NumPy header dict"),
        "{e}"
    );
    let e = read_npy::<f32>(&case("npy_nested_header.npy")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
    assert!(
        e.to_string().ends_with("byte 63: header nests brackets deeper than 4: expected a NumPy header dict"),
        "{e}"
    );
}

/// A format-1 header declaring a length below 2: the first 12 bytes read to check the header
/// already hold data, and the bracket check added the same day sliced past them (a panic the
/// npy target found in its 60 s run after that fix, 2026-11-23).
#[test]
fn npy_header_shorter_than_the_prefix_is_an_error_not_a_panic() {
    let e = read_npy::<f32>(&case("npy_header_shorter_than_prefix.npy")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
}

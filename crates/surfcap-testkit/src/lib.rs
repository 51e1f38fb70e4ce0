//! Test support shared by the surfcap crates' tests (a dev-dependency only).
//!
//! Real data lives in `../shared/data` next to the project (or where `SURFCAP_DATA` points).
//! A test that needs it fails when `CI=true` and it is missing, and otherwise skips with a
//! message, so a newcomer without the data can still run the unit tests.

use std::path::{Path, PathBuf};

/// The workspace root (two levels above a crate's manifest).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("workspace root exists")
}

/// The shared real-data folder, or `None` (after printing why) when it is missing outside CI.
///
/// # Panics
/// When `CI=true` and the folder is missing: CI must not silently skip real-data tests.
pub fn shared_data() -> Option<PathBuf> {
    let dir =
        std::env::var_os("SURFCAP_DATA").map(PathBuf::from).unwrap_or_else(|| workspace_root().join("../shared/data"));
    if dir.join("README.md").is_file() {
        return Some(dir);
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("real data missing at {} (CI=true: real-data tests must not be skipped)", dir.display());
    }
    eprintln!("skipping: real data missing at {} (set SURFCAP_DATA)", dir.display());
    None
}

/// Reads a dataset's `meta.json`.
pub fn meta(dataset: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dataset.join("meta.json")).expect("meta.json readable");
    serde_json::from_str(&text).expect("meta.json is JSON")
}

/// Runs the Khronos glTF validator on `.glb` files; returns its per-file JSON reports.
///
/// # Panics
/// When node or `tools/node_modules/gltf-validator` is missing (the README's test command
/// installs it), or when the validator reports an error or a warning.
pub fn validate_glb(files: &[PathBuf]) -> Vec<serde_json::Value> {
    let root = workspace_root();
    let tools = root.join("tools");
    assert!(
        tools.join("node_modules/gltf-validator").is_dir(),
        "gltf-validator is not installed in {}: run scripts/test (it runs npm ci there)",
        tools.display()
    );
    let out = std::process::Command::new("node")
        .arg(tools.join("validate-gltf.mjs"))
        .args(files)
        .output()
        .expect("node runs (install Node.js)");
    let reports: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("validator prints JSON lines"))
        .collect();
    assert!(
        out.status.success(),
        "glTF validator found problems:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(reports.len(), files.len());
    reports
}

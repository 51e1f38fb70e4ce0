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

/// A raw HTTP/1.1 request to `url` (`http://host:port/`), the target sent exactly as written
/// (no normalisation, so path-traversal attempts reach the server): status and body.
///
/// # Panics
/// When the server cannot be reached or does not answer HTTP.
pub fn http_request(url: &str, method: &str, target: &str) -> (u16, Vec<u8>) {
    use std::io::{Read, Write};
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).expect("the server accepts connections");
    write!(s, "{method} {target} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n").unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let head_end = buf.windows(4).position(|w| w == b"\r\n\r\n").expect("an HTTP response") + 4;
    let head = String::from_utf8_lossy(&buf[..head_end]).into_owned();
    let status = head.split_whitespace().nth(1).and_then(|x| x.parse().ok()).expect("an HTTP status line");
    (status, buf[head_end..].to_vec())
}

/// A running `surfcap view`, killed when dropped.
pub struct ViewServer {
    child: std::process::Child,
    pub url: String,
}

impl ViewServer {
    /// Starts `<surfcap> view <args>` and waits for the URL it prints.
    pub fn start(surfcap: &str, args: &[&str]) -> Self {
        use std::io::BufRead;
        let mut child = std::process::Command::new(surfcap)
            .arg("view")
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("surfcap runs");
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let url = line.trim().to_string();
        assert!(url.starts_with("http://127.0.0.1:"), "surfcap view printed {url:?}");
        ViewServer { child, url }
    }

    pub fn get(&self, target: &str) -> (u16, Vec<u8>) {
        http_request(&self.url, "GET", target)
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

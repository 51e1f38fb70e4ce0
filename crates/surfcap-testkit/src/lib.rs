//! Test support shared by the surfcap crates' tests (a dev-dependency only).
//!
//! # Real data
//!
//! Real data lives in `../shared/data` next to the project (or where `SURFCAP_DATA` points).
//! A test that needs it calls [`shared_data`], which makes it tell the truth:
//!
//! - data present: the test runs;
//! - data missing: the test **fails**, naming the folder it looked in, and saying that
//!   `SURFCAP_DATA` points elsewhere and that `SURFCAP_SKIP_REAL_DATA=1` skips real-data tests;
//! - data missing and `SURFCAP_SKIP_REAL_DATA=1`: the test is skipped deliberately. It still
//!   shows as passed (libtest has no "skipped" at run time), so it prints
//!   `SKIPPED <test name>: real data missing at <dir>` to stderr; the test harness captures a
//!   passing test's output, so run `cargo test -- --nocapture` to see those lines;
//! - `CI=true`: never skipped; a missing folder fails even with `SURFCAP_SKIP_REAL_DATA=1`.
//!
//! # The `surfcap` program
//!
//! [`surfcap!`] runs the program under test (in surfcap-cli's integration tests),
//! [`surfcap_bench!`] the benchmarks' program (in surfcap-bench's), [`p`] and [`stderr`]
//! shorten what those tests write around it. [`meta`] reads a dataset's `meta.json`.
//!
//! # Checks with outside tools
//!
//! [`validate_glb`] runs the Khronos glTF validator and [`three_load_glb`] /
//! [`three_play_textured_glb`] three.js's GLTFLoader (Node.js tools in `tools/`, installed by
//! `scripts/setup`); [`read_usd`] and [`read_abc`] read files back with Pixar's USD and the
//! reference Alembic library (Python in `tools/venv`). [`ViewServer`] starts `surfcap view`, and
//! [`http_request`] sends raw HTTP requests (no URL normalisation, so traversal attempts reach the
//! server).
//!
//! # Markdown tables
//!
//! [`markdown_cells`] splits a row of a markdown table into its cells (`\|` is a literal bar),
//! for tests that compare generated pages with the numbers they came from.
//!
//! # Documentation examples
//!
//! [`doc_examples()`] lists every command example of `README.md` and `docs/**/*.md` with its
//! file, line and words, so a test can parse each against the program's command line.

use std::path::{Path, PathBuf};
use std::process::Output;

pub mod doc_examples;
pub use doc_examples::{DocExample, doc_examples};

/// The workspace root (two levels above a crate's manifest).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("workspace root exists")
}

/// The shared real-data folder: `SURFCAP_DATA`, or `../shared/data` next to the workspace.
///
/// Returns `None` only when the folder is missing and `SURFCAP_SKIP_REAL_DATA=1` (and `CI` is
/// not `true`), after printing `SKIPPED <test name>: real data missing at <dir>` to stderr;
/// the caller then returns from the test. The test name is the current thread's, which the
/// test harness names after the test.
///
/// # Panics
/// When the folder (its `README.md`) is missing and the skip was not asked for, or `CI=true`:
/// a real-data test that did not run must not show as passed. The panic names the caller.
#[track_caller]
pub fn shared_data() -> Option<PathBuf> {
    let from_env = std::env::var_os("SURFCAP_DATA").map(PathBuf::from);
    let dir = from_env.clone().unwrap_or_else(|| workspace_root().join("../shared/data"));
    let found = dir.join("README.md").is_file();
    let skip = std::env::var_os("SURFCAP_SKIP_REAL_DATA").is_some_and(|v| v == "1");
    let ci = std::env::var_os("CI").is_some_and(|v| v == "true");
    match real_data(&dir, from_env.is_some(), found, skip, ci) {
        RealData::Found => Some(dir),
        RealData::Skip(line) => {
            let thread = std::thread::current();
            eprintln!("SKIPPED {}: {line}", thread.name().unwrap_or("<unnamed test>"));
            None
        }
        RealData::Fail(message) => panic!("{message}"),
    }
}

/// What [`shared_data`] does, decided from what it read.
#[derive(Debug, PartialEq)]
enum RealData {
    Found,
    /// Skip the test; the text after `SKIPPED <test name>: `.
    Skip(String),
    /// Fail the test with this message.
    Fail(String),
}

fn real_data(dir: &Path, from_env: bool, found: bool, skip: bool, ci: bool) -> RealData {
    if found {
        return RealData::Found;
    }
    let missing = format!("real data missing at {}", dir.display());
    if skip && !ci {
        return RealData::Skip(missing);
    }
    let looked = if from_env {
        "the folder SURFCAP_DATA names".to_string()
    } else {
        format!("../shared/data next to the workspace {}; SURFCAP_DATA is not set", workspace_root().display())
    };
    let what_now = if ci {
        "CI=true: real-data tests never skip, SURFCAP_SKIP_REAL_DATA=1 is ignored".to_string()
    } else {
        "Set SURFCAP_DATA=<folder> to read the data from elsewhere, or SURFCAP_SKIP_REAL_DATA=1 to \
         skip real-data tests deliberately (each then prints SKIPPED; see it with --nocapture)"
            .to_string()
    };
    RealData::Fail(format!("{missing}: no README.md there (it is {looked}). {what_now}"))
}

/// A procedural walker (its walk and jog clips of 2 s, 1,000 vertices) written to
/// `dir/walker.subject` by the `surfcap` program `exe`; its clips give about 20 m of path loop
/// over their frames. CLI tests call it through [`procedural_walker!`].
pub fn procedural_walker_with(exe: &str, dir: &Path) -> PathBuf {
    let walker = dir.join("walker.subject");
    let args = [
        "make",
        "mannequin",
        "--procedural",
        "walk,jog",
        "--duration",
        "2",
        "--vertices",
        "1000",
        "-o",
        p(&walker),
        "--quiet",
    ];
    let o = run(exe, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    walker
}

/// [`procedural_walker_with`] run by the `surfcap` program of the test being compiled:
/// `procedural_walker!(dir)` is the subject's path.
#[macro_export]
macro_rules! procedural_walker {
    ($dir:expr $(,)?) => {
        $crate::procedural_walker_with(env!("CARGO_BIN_EXE_surfcap"), $dir)
    };
}

/// Runs the `surfcap` program with the given arguments (`&[&str]`) and waits for its
/// [`Output`] (exit status, stdout, stderr).
///
/// Usable only in surfcap-cli's integration tests: a macro, so that
/// `env!("CARGO_BIN_EXE_surfcap")` is expanded in the test being compiled, where cargo sets it.
/// (Cargo 1.95 also sets it in the environment when `cargo test` runs the test, but not when
/// the test executable is started on its own, so this crate does not read it at run time.)
#[macro_export]
macro_rules! surfcap {
    ($args:expr $(,)?) => {
        $crate::run(env!("CARGO_BIN_EXE_surfcap"), $args)
    };
}

/// Runs the `surfcap-bench` program (the benchmarks) with the given arguments, as [`surfcap!`]
/// runs `surfcap`.
///
/// Usable only in surfcap-bench's integration tests, where cargo sets
/// `CARGO_BIN_EXE_surfcap-bench`.
#[macro_export]
macro_rules! surfcap_bench {
    ($args:expr $(,)?) => {
        $crate::run(env!("CARGO_BIN_EXE_surfcap-bench"), $args)
    };
}

/// Runs the program `exe` with `args` and waits for its output.
///
/// # Panics
/// When the program cannot be started.
pub fn run(exe: &str, args: &[&str]) -> Output {
    std::process::Command::new(exe).args(args).output().unwrap_or_else(|e| panic!("{exe} runs: {e}"))
}

/// A path as a command-line argument (the tests' temporary paths are UTF-8).
pub fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A program's stderr as text (for assertion messages).
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Reads a dataset's `meta.json`.
pub fn meta(dataset: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dataset.join("meta.json")).expect("meta.json readable");
    serde_json::from_str(&text).expect("meta.json is JSON")
}

/// Reads a `.usda` file back with Pixar's USD (usd-core, in `tools/venv`, installed by
/// `scripts/setup`) through `tools/usd-read.py`; returns what it read as JSON.
///
/// # Panics
/// When the virtual environment is missing or USD cannot read the file.
pub fn read_usd(file: &Path) -> serde_json::Value {
    let root = workspace_root();
    let python = root.join("tools/venv/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/test (it installs usd-core)", python.display());
    let o = std::process::Command::new(&python)
        .arg(root.join("tools/usd-read.py"))
        .arg(file)
        .output()
        .expect("python runs");
    assert!(o.status.success(), "USD could not read {}:\n{}", file.display(), String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("usd-read.py prints JSON")
}

/// Reads an Alembic archive with the reference library (PyPI `alembic3d` in `tools/venv`,
/// installed by `scripts/setup`) through `tools/abc-read.py`; returns its JSON (archive
/// metadata, time samplings, and every PolyMesh's samples, UVs, normals and arbitrary
/// geometry parameters).
///
/// # Panics
/// When the virtual environment is missing or the reference library cannot read the file.
pub fn read_abc(file: &Path) -> serde_json::Value {
    let root = workspace_root();
    let python = root.join("tools/venv/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/test (it installs alembic3d)", python.display());
    let o = std::process::Command::new(&python)
        .arg(root.join("tools/abc-read.py"))
        .arg(file)
        .output()
        .expect("python runs");
    assert!(o.status.success(), "Alembic could not read {}:\n{}", file.display(), String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("abc-read.py prints JSON")
}

/// Runs the Khronos glTF validator on `.glb` files; returns its per-file JSON reports.
///
/// # Panics
/// When node or `tools/node_modules/gltf-validator` is missing (`scripts/setup`
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

/// Loads `.glb` files with three.js's GLTFLoader (the viewer's three.js) and evaluates their
/// weights tracks (`tools/three-gltf-check.mjs`); returns its per-file JSON reports.
///
/// # Panics
/// When node or the viewer's `node_modules/three` is missing (building `surfcap-view` installs
/// it), or when a file does not load or a key's weights are not 1 on its own target.
pub fn three_load_glb(files: &[PathBuf]) -> Vec<serde_json::Value> {
    let root = workspace_root();
    let three = root.join("crates/surfcap-view/web/node_modules/three");
    assert!(three.is_dir(), "three.js is not installed in {}: build surfcap-view (it runs npm ci)", three.display());
    let out = std::process::Command::new("node")
        .arg(root.join("tools/three-gltf-check.mjs"))
        .args(files)
        .output()
        .expect("node runs (install Node.js)");
    assert!(
        out.status.success(),
        "three.js GLTFLoader check failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let reports: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("the check prints JSON lines"))
        .collect();
    assert_eq!(reports.len(), files.len());
    reports
}

/// Plays a frame-set `.glb` with a texture per frame in headless Chromium with three.js's
/// GLTFLoader (`tools/three-gltf-textures.mjs`): at every frame the frame's own mesh is shown
/// with the texture its material names bound as `material.map`. Returns the script's report
/// (per animation the texture bound at each frame, and each texture's size and mean colour).
///
/// # Panics
/// When node, Chromium or the viewer's three.js is missing, or a frame shows the wrong mesh or
/// texture.
pub fn three_play_textured_glb(file: &Path) -> serde_json::Value {
    let root = workspace_root();
    let out = std::process::Command::new("node")
        .arg(root.join("tools/three-gltf-textures.mjs"))
        .arg(file)
        .output()
        .expect("node runs (install Node.js)");
    assert!(
        out.status.success(),
        "three.js textured glb check failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the check prints one JSON line")
}

/// A raw HTTP/1.1 request to `url` (`http://host:port/`), the target sent exactly as written
/// (no normalisation, so path-traversal attempts reach the server): status and body.
///
/// # Panics
/// When the server cannot be reached or does not answer HTTP.
pub fn http_request(url: &str, method: &str, target: &str) -> (u16, Vec<u8>) {
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    http_request_as(url, method, target, host)
}

/// [`http_request`] with the given `Host` header (as a DNS-rebinding page would send it).
pub fn http_request_as(url: &str, method: &str, target: &str, host_header: &str) -> (u16, Vec<u8>) {
    use std::io::{Read, Write};
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).expect("the server accepts connections");
    write!(s, "{method} {target} HTTP/1.1\r\nHost: {host_header}\r\nConnection: close\r\n\r\n").unwrap();
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
        Self::start_command(surfcap, &["view"], args)
    }

    /// Starts `<surfcap> <command...> <args>` (a command that serves the viewer, such as
    /// `parts show`) and waits for the URL it prints.
    pub fn start_command(surfcap: &str, command: &[&str], args: &[&str]) -> Self {
        use std::io::BufRead;
        let mut child = std::process::Command::new(surfcap)
            .args(command)
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("surfcap runs");
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let url = line.trim().to_string();
        assert!(url.starts_with("http://127.0.0.1:"), "surfcap {} printed {url:?}", command.join(" "));
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

/// The cells of a markdown table row, trimmed: `| a \\| b | c |` gives `["a | b", "c"]` (a
/// backslash before a bar makes it a literal bar, as the generated pages escape it).
pub fn markdown_cells(row: &str) -> Vec<String> {
    let inner = row.trim().trim_start_matches('|').trim_end_matches('|');
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                chars.next();
                out.last_mut().expect("never empty").push('|');
            }
            '|' => out.push(String::new()),
            _ => out.last_mut().expect("never empty").push(c),
        }
    }
    out.iter().map(|s| s.trim().to_string()).collect()
}

/// A valid 1 x 1 PNG of one opaque RGB colour (stored, uncompressed deflate), for tests.
pub fn png_1x1(rgb: [u8; 3]) -> Vec<u8> {
    fn crc(bytes: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }
    fn adler(bytes: &[u8]) -> u32 {
        let (mut a, mut b) = (1u32, 0u32);
        for &x in bytes {
            a = (a + x as u32) % 65521;
            b = (b + a) % 65521;
        }
        (b << 16) | a
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc(&body).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&1u32.to_be_bytes());
    ihdr.extend_from_slice(&1u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    let raw = [0, rgb[0], rgb[1], rgb[2]];
    let mut z = vec![0x78, 0x01, 1, raw.len() as u8, 0, !(raw.len() as u8), 0xff];
    z.extend_from_slice(&raw);
    z.extend_from_slice(&adler(&raw).to_be_bytes());
    chunk(b"IDAT", &z);
    chunk(b"IEND", &[]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn present_data_is_used_whatever_the_switches() {
        for (skip, ci) in [(false, false), (true, false), (false, true), (true, true)] {
            assert_eq!(real_data(Path::new("/d"), false, true, skip, ci), RealData::Found);
        }
    }

    #[test]
    fn missing_data_fails_and_says_where_it_looked_and_how_to_skip() {
        let RealData::Fail(m) = real_data(Path::new("/nowhere/data"), true, false, false, false) else {
            panic!("a missing folder must fail")
        };
        assert!(m.contains("real data missing at /nowhere/data"), "{m}");
        assert!(m.contains("SURFCAP_DATA"), "{m}");
        assert!(m.contains("SURFCAP_SKIP_REAL_DATA=1"), "{m}");
        let RealData::Fail(m) = real_data(Path::new("/x"), false, false, false, false) else { panic!() };
        assert!(m.contains("../shared/data next to the workspace") && m.contains("SURFCAP_DATA is not set"), "{m}");
    }

    #[test]
    fn missing_data_skips_only_when_asked_and_never_under_ci() {
        assert_eq!(
            real_data(Path::new("/nowhere"), false, false, true, false),
            RealData::Skip("real data missing at /nowhere".into())
        );
        let RealData::Fail(m) = real_data(Path::new("/nowhere"), false, false, true, true) else {
            panic!("CI=true must fail even with the skip")
        };
        assert!(m.contains("CI=true"), "{m}");
        assert!(matches!(real_data(Path::new("/nowhere"), false, false, false, true), RealData::Fail(_)));
    }

    #[test]
    fn markdown_cells_keep_escaped_bars_and_trim() {
        assert_eq!(markdown_cells("| a \\| b | c |"), ["a | b", "c"]);
        assert_eq!(markdown_cells("  | x |y|  "), ["x", "y"]);
        assert_eq!(markdown_cells("| one |"), ["one"]);
        assert_eq!(markdown_cells("| a \\ b |"), ["a \\ b"], "a backslash alone stays");
    }
}

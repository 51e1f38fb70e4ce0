//! Every tutorial of the user guide runs as written. A section of a page under `docs/src` is a
//! tutorial when the line `<!-- tutorial -->` follows its heading (before any code block); its
//! ```` ```sh ````, ```` ```bash ```` and ```` ```console ```` blocks (in a console block, the
//! lines after `$ `), up to the next heading of the same or a higher level, are joined in order
//! into one bash script (`set -euo pipefail`, each command traced), run in a fresh temporary
//! folder outside the checkout with the built `surfcap` first on `PATH` and `SURFCAP_DATA` set
//! to the real data. So a tutorial must create everything it uses, in order, and a broken
//! example fails here.
//!
//! One thing differs from a terminal: `surfcap view` serves until Ctrl-C, so in the script it
//! runs until it prints its URL, its `/api/items` must answer with at least one item, and it is
//! then stopped (a view that fails, or serves nothing, fails the tutorial).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use surfcap_testkit::workspace_root;

/// A tutorial: the page and heading it comes from, and its commands as a script.
#[derive(Debug)]
struct Tutorial {
    page: PathBuf,
    heading: String,
    /// (line in the page, text) of each script line.
    lines: Vec<(usize, String)>,
}

const MARK: &str = "<!-- tutorial -->";

/// The level of a Markdown heading line (`## x`: 2), or None.
fn heading_level(line: &str) -> Option<usize> {
    let level = line.chars().take_while(|&c| c == '#').count();
    (level > 0 && line[level..].starts_with(' ')).then_some(level)
}

/// The tutorials of one page's text.
fn tutorials_in(page: &Path, text: &str) -> Vec<Tutorial> {
    let mut out: Vec<Tutorial> = Vec::new();
    // The open tutorial's level, whether its mark may still come (before its first block), and
    // whether it is marked.
    let mut section: Option<(usize, String, bool, bool)> = None;
    let mut lines = Vec::new();
    // The open code block: its fence and whether it is a shell (Some(console?)) block.
    let mut block: Option<(String, Option<bool>)> = None;
    let close =
        |section: &Option<(usize, String, bool, bool)>, lines: &mut Vec<(usize, String)>, out: &mut Vec<Tutorial>| {
            if let Some((_, heading, _, true)) = section {
                out.push(Tutorial { page: page.to_path_buf(), heading: heading.clone(), lines: std::mem::take(lines) });
            }
            lines.clear();
        };
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some((fence, kind)) = &block {
            if trimmed.starts_with(fence.as_str()) && trimmed[fence.len()..].trim().is_empty() {
                block = None;
            } else if let Some(console) = kind {
                let command = if *console { trimmed.strip_prefix("$ ") } else { Some(line) };
                if let Some(c) = command {
                    lines.push((i + 1, c.to_string()));
                }
            }
            continue;
        }
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            let c = trimmed.chars().next().unwrap();
            let fence: String = trimmed.chars().take_while(|&x| x == c).collect();
            let info = trimmed[fence.len()..].trim();
            let kind = match info.split([' ', ',', '{']).next().unwrap_or("") {
                "sh" | "bash" | "shell" => Some(false),
                "console" => Some(true),
                _ => None,
            };
            if let Some(s) = section.as_mut() {
                s.2 = false;
            }
            block = Some((fence, kind));
            continue;
        }
        if let Some(level) = heading_level(line) {
            if section.as_ref().is_some_and(|s| s.3 && level > s.0) {
                // A sub-heading inside a tutorial: still the tutorial.
                continue;
            }
            close(&section, &mut lines, &mut out);
            section = Some((level, line[level..].trim().to_string(), true, false));
            continue;
        }
        if trimmed == MARK {
            let s =
                section.as_mut().unwrap_or_else(|| panic!("{}:{}: {MARK} before any heading", page.display(), i + 1));
            assert!(s.2, "{}:{}: {MARK} after the section's first code block", page.display(), i + 1);
            s.3 = true;
        }
    }
    close(&section, &mut lines, &mut out);
    out
}

/// Every tutorial of the guide's pages, by page name.
fn guide_tutorials() -> Vec<Tutorial> {
    let dir = workspace_root().join("docs/src");
    let mut pages: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    pages.sort();
    pages.iter().flat_map(|p| tutorials_in(p, &std::fs::read_to_string(p).unwrap())).collect()
}

/// What runs before a tutorial's own lines: strict bash, traced, and `surfcap view` bounded.
const PRELUDE: &str = r#"set -euo pipefail
PS4='+ $ '
__surfcap_view() {
  local log url="" pid
  log=$(mktemp)
  command surfcap view "$@" >"$log" 2>&1 &
  pid=$!
  for _ in $(seq 1200); do
    url=$(grep -o -m1 'http://127\.0\.0\.1:[0-9]*' "$log" || true)
    [ -n "$url" ] && break
    if ! kill -0 "$pid" 2>/dev/null; then
      cat "$log" >&2; echo "surfcap view $*: exited before serving" >&2; return 1
    fi
    sleep 0.1
  done
  if [ -z "$url" ]; then echo "surfcap view $*: no URL after 120 s" >&2; kill "$pid"; return 1; fi
  local items
  items=$(curl -fsS "$url/api/items") || { kill "$pid"; echo "surfcap view $*: $url/api/items did not answer" >&2; return 1; }
  kill "$pid"; wait "$pid" 2>/dev/null || true
  case "$items" in
    *'"items":[{'*) echo "surfcap view $*: served at $url" >&2 ;;
    *) echo "surfcap view $*: no items: $items" >&2; return 1 ;;
  esac
}
surfcap() {
  if [ "${1-}" = view ]; then shift; __surfcap_view "$@"; else command surfcap "$@"; fi
}
set -x
"#;

/// Runs one tutorial in a fresh folder; Err(what went wrong) when it fails.
fn run(t: &Tutorial, data: &Path) -> Result<Duration, String> {
    let exe = Path::new(env!("CARGO_BIN_EXE_surfcap"));
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let script = format!("{PRELUDE}{}\n", t.lines.iter().map(|(_, l)| l.as_str()).collect::<Vec<_>>().join("\n"));
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![exe.parent().unwrap().to_path_buf()];
    paths.extend(std::env::split_paths(&path));
    let t0 = Instant::now();
    let o = Command::new("timeout")
        .args(["600", "bash", "-c", &script])
        .current_dir(&work)
        .env("PATH", std::env::join_paths(paths).unwrap())
        .env("SURFCAP_DATA", data)
        .env("HOME", tmp.path())
        .env_remove("CARGO_TARGET_DIR")
        .output()
        .unwrap();
    let took = t0.elapsed();
    if o.status.success() {
        Ok(took)
    } else {
        let err = String::from_utf8_lossy(&o.stderr);
        let tail: Vec<&str> = err.lines().rev().take(40).collect::<Vec<_>>().into_iter().rev().collect();
        Err(format!(
            "{} \"{}\" (lines {}-{}) failed ({}) after {:.0} s:\n{}",
            t.page.display(),
            t.heading,
            t.lines.first().map_or(0, |l| l.0),
            t.lines.last().map_or(0, |l| l.0),
            o.status,
            took.as_secs_f64(),
            tail.join("\n")
        ))
    }
}

#[test]
fn every_tutorial_of_the_guide_runs_as_written_from_an_empty_folder() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tutorials = guide_tutorials();
    let first_hour: Vec<&str> =
        tutorials.iter().filter(|t| t.page.ends_with("first-hour.md")).map(|t| t.heading.as_str()).collect();
    assert!(first_hour.len() >= 3, "the first hour's tutorials: {first_hour:?}");
    let mut failures = Vec::new();
    for t in &tutorials {
        assert!(!t.lines.is_empty(), "{} \"{}\": a tutorial without commands", t.page.display(), t.heading);
        match run(t, &data) {
            Ok(took) => eprintln!("{} \"{}\": ran in {:.1} s", t.page.display(), t.heading, took.as_secs_f64()),
            Err(e) => failures.push(e),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn tutorial_sections_are_found_with_their_blocks_in_order() {
    let page = "# P\n\n## A\n<!-- tutorial -->\n```sh\nsurfcap a\n```\n### A.1\n```console\n$ surfcap b\nout\n```\n\
                ```text\nnot run\n```\n## B\n```sh\nsurfcap c\n```\n## C\n\n*Tutorial.*\n<!-- tutorial -->\n```bash\ntouch x\n```\n";
    let t = tutorials_in(Path::new("p.md"), page);
    let got: Vec<(&str, Vec<&str>)> =
        t.iter().map(|t| (t.heading.as_str(), t.lines.iter().map(|l| l.1.as_str()).collect())).collect();
    assert_eq!(got, [("A", vec!["surfcap a", "surfcap b"]), ("C", vec!["touch x"])]);
    assert_eq!(t[0].lines[1].0, 10, "the page's line numbers");
    let late = std::panic::catch_unwind(|| tutorials_in(Path::new("p.md"), "## A\n```sh\nx\n```\n<!-- tutorial -->\n"));
    assert!(late.is_err(), "a mark after the first block is refused");
}

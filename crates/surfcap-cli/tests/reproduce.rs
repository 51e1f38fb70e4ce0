//! `surfcap reproduce`: the catalogue, item selection, the output folder's rules, and a quick
//! run on the Vlasic crane (Fig. 2.8 and 2.15) whose page headless Chromium renders with every
//! figure loaded; a second run keeps the finished evals.

use std::path::Path;
use std::process::Command;

use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn list_shows_the_embedded_catalogue() {
    let o = surfcap!(&["reproduce", "--list"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("thesis-fig-2.15") && out.contains("transitions"), "{out}");
    let o = surfcap!(&["reproduce", "--list", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["items"].as_array().unwrap().iter().any(|i| i["id"] == "thesis-fig-2.15"));
}

#[test]
fn a_selection_is_required_and_must_name_items() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("repro");
    let o = surfcap!(&["reproduce", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--all, --figure") && stderr(&o).contains("--list"), "{}", stderr(&o));
    let o = surfcap!(&["reproduce", "--figure", "9.99", "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--figure 9.99"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing written for a refused selection");
}

#[test]
fn a_folder_surfcap_did_not_write_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "keep me").unwrap();
    let data = tmp.path().join("data");
    std::fs::create_dir(&data).unwrap();
    let o = surfcap!(&["reproduce", "--figure", "2.8", "-o", p(&out), "--data", p(&data)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("mine"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "keep me");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1, "nothing added to the user's folder");
}

/// The page as headless Chromium leaves it after loading: (number of <img>, the page's own
/// count of loaded images, of broken ones).
fn rendered(index: &Path) -> (usize, u64, u64) {
    let chromium = Path::new("/usr/bin/chromium");
    assert!(chromium.is_file(), "/usr/bin/chromium is missing");
    let profile = tempfile::tempdir().unwrap();
    let o = Command::new(chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000"])
        .arg(format!("--user-data-dir={}", p(profile.path())))
        .arg("--dump-dom")
        .arg(format!("file://{}", p(&index.canonicalize().unwrap())))
        .output()
        .expect("chromium runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dom = String::from_utf8_lossy(&o.stdout).to_string();
    let attr = |name: &str| -> u64 {
        let at =
            dom.find(&format!("{name}=\"")).unwrap_or_else(|| panic!("{name} not set: the load script did not run"));
        let rest = &dom[at + name.len() + 2..];
        rest[..rest.find('"').unwrap()].parse().unwrap()
    };
    (dom.matches("<img ").count(), attr("data-images-loaded"), attr("data-images-broken"))
}

#[test]
fn quick_run_writes_a_page_that_renders_every_figure_and_resumes() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("repro");
    let cache = tmp.path().join("cache");
    let args =
        ["reproduce", "--figure", "2.8,2.15", "--quick", "--data", p(&data), "-o", p(&out), "--cache-dir", p(&cache)];
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("[1/2] eval ") && e.contains("[2/2] eval "), "{e}");
    assert!(e.contains("eval interpolation") && e.contains("eval transitions"), "{e}");
    let results: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(results["quick"], true);
    let items = results["items"].as_array().unwrap();
    let mut ids: Vec<&str> = items.iter().map(|i| i["id"].as_str().unwrap()).collect();
    ids.sort();
    assert_eq!(ids, ["thesis-fig-2.15", "thesis-fig-2.8"]);
    let costs = items.iter().find(|i| i["id"] == "thesis-fig-2.15").unwrap();
    let values: Vec<&serde_json::Value> = items.iter().flat_map(|i| i["values"].as_array().unwrap()).collect();
    let measured = costs["values"].as_array().unwrap().iter().filter(|v| v["status"] != "not_measured").count();
    assert!(measured > 0, "no value of Fig. 2.15 measured: {costs}");
    for v in &values {
        if v["status"] != "not_measured" {
            assert!(v["ours"].as_f64().is_some_and(f64::is_finite), "{v}");
        }
    }
    for eval in ["interpolation", "transitions"] {
        let run = &results["runs"][eval];
        assert!(run["seconds"].as_f64().is_some(), "{run}");
        assert!(run["machine"]["cores"].as_u64().is_some_and(|c| c >= 1), "{run}");
        assert!(!run["figures"].as_array().unwrap().is_empty(), "{run}");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + values.len());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("id=\"quick-mode\""));
    // Every figure renders: as many <img> as loaded images, none broken, at least one per eval.
    let (imgs, loaded, broken) = rendered(&out.join("index.html"));
    assert!(imgs >= 2, "{imgs} images");
    assert_eq!((loaded, broken), (imgs as u64, 0));
    // A second run keeps both finished evals (their records unchanged) and rewrites the page.
    let record = std::fs::read(out.join("runs/transitions.run.json")).unwrap();
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("finished earlier").count(), 2, "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("runs/transitions.run.json")).unwrap(), record);
    // --redo runs them again.
    let mut redo = args.to_vec();
    redo.push("--redo");
    let o = surfcap!(&redo);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("finished earlier"), "{}", stderr(&o));
}

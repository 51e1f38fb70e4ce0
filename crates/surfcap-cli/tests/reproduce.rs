//! `surfcap reproduce`: the catalogue, item selection, the output folder's rules, and a quick
//! run on the Vlasic crane (Fig. 2.8 and 2.15, the latter under both readings of the DTW's
//! first step) whose page headless Chromium renders with every figure loaded, whose markdown
//! pages (`--results-dir`) hold the numbers of results.json, and whose page shows the evals'
//! printed tables; a second run keeps the finished evals; surfcap's own checks (no paper
//! figure) run with their printed tables.

use std::path::Path;
use std::process::Command;

use surfcap_testkit::{markdown_cells as cells, p, stderr, surfcap};

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
    let md = tmp.path().join("results");
    let args = [
        "reproduce",
        "--figure",
        "2.8,2.15",
        "--quick",
        "--data",
        p(&data),
        "-o",
        p(&out),
        "--cache-dir",
        p(&cache),
        "--results-dir",
        p(&md),
    ];
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("[1/2] eval ") && e.contains("[2/2] eval "), "{e}");
    assert!(e.contains("eval interpolation") && e.contains("eval transitions"), "{e}");
    assert!(e.contains("eq. 2.53 read literally"), "the literal reading runs too: {e}");
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
    // Fig. 2.15 under both readings: every value measured under surfcap's reading has its
    // literal-reading counterpart from runs/transitions-literal.
    let alt = &results["runs"]["transitions"]["alternates"][0];
    assert_eq!(alt["folder"], "runs/transitions-literal", "{alt}");
    assert!(alt["args"].as_array().unwrap().iter().any(|a| a == "literal"), "{alt}");
    assert!(out.join("runs/transitions-literal/transitions.json").is_file());
    let mut differ = 0;
    for v in costs["values"].as_array().unwrap() {
        let other = &v["other_readings"][0];
        assert!(other["reading"].as_str().unwrap().contains("literally"), "{v}");
        if v["ours"].is_number() {
            assert!(other["ours"].as_f64().is_some_and(f64::is_finite), "{v}");
            differ += usize::from(other["ours"] != v["ours"]);
        }
    }
    assert!(differ > 0, "the two readings give the same numbers on every value");
    // And under eq. 2.55's least ratio found exactly: never above surfcap's normalised costs.
    let exact = &results["runs"]["transitions"]["alternates"][1];
    assert_eq!(exact["folder"], "runs/transitions-exact-ratio", "{exact}");
    assert!(e.contains("eq. 2.55's least ratio found exactly"), "{e}");
    let mut lower = 0;
    for v in costs["values"].as_array().unwrap() {
        let other = &v["other_readings"][1];
        assert!(other["reading"].as_str().unwrap().contains("2.55"), "{v}");
        if let (Some(ours), Some(x)) = (v["ours"].as_f64(), other["ours"].as_f64())
            && v["label"].as_str().unwrap().contains("mean normalised cost")
        {
            assert!(x <= ours * (1.0 + 1e-12), "{v}");
            lower += usize::from(x < ours);
        }
    }
    assert!(lower > 0, "the exact ratio is lower on no mean cost");
    // The evals' own printed tables are kept and shown.
    for eval in ["interpolation", "transitions"] {
        let printed = results["runs"][eval]["printed"].as_str().unwrap_or_default();
        assert!(printed.lines().count() >= 2, "{eval} printed: {printed:?}");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + values.len());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("id=\"quick-mode\""));
    assert_eq!(html.matches("<details class=\"printed\">").count(), 4, "interpolation, transitions thrice");
    assert!(html.contains("--dtw-first-step literal"));
    // The markdown pages hold the numbers of results.json.
    markdown_matches_json(&md, &results);
    // Every figure renders: as many <img> as loaded images, none broken, at least one per eval.
    let (imgs, loaded, broken) = rendered(&out.join("index.html"));
    assert!(imgs >= 2, "{imgs} images");
    assert_eq!((loaded, broken), (imgs as u64, 0));
    // A second run keeps both finished evals (their records unchanged) and rewrites the page.
    let record = std::fs::read(out.join("runs/transitions.run.json")).unwrap();
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("finished earlier").count(), 4, "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("runs/transitions.run.json")).unwrap(), record);
    // --redo runs them again.
    let mut redo = args.to_vec();
    redo.push("--redo");
    let o = surfcap!(&redo);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("finished earlier"), "{}", stderr(&o));
}

/// Every value of results.json is a row of its eval's markdown page, with the same label,
/// published number, ours, status and other readings; every page carries the command.
fn markdown_matches_json(dir: &Path, results: &serde_json::Value) {
    use surfcap_eval::reproduce_markdown::{INDEX, is_own_page, page_name};
    use surfcap_eval::reproduce_report::fmt_num;
    let index = std::fs::read_to_string(dir.join(INDEX)).unwrap();
    assert!(is_own_page(&index) && index.contains("```sh\nsurfcap reproduce --figure 2.8,2.15 --quick"), "{index}");
    let num = |v: &serde_json::Value| v.as_f64().map(fmt_num).unwrap_or_else(|| "-".into());
    let mut rows_checked = 0;
    for item in results["items"].as_array().unwrap() {
        let page = std::fs::read_to_string(dir.join(page_name(item["eval"].as_str().unwrap()))).unwrap();
        assert!(is_own_page(&page));
        let title = format!("## {}: ", item["number"].as_str().map(|n| format!("Thesis Fig. {n}")).unwrap());
        let section = &page[page.find(&title).unwrap_or_else(|| panic!("{title} not in {page}"))..];
        let rows: Vec<Vec<String>> = section
            .lines()
            .skip_while(|l| !l.starts_with("| value"))
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .map(cells)
            .collect();
        let values = item["values"].as_array().unwrap();
        assert_eq!(rows.len(), values.len(), "{title}");
        for (row, v) in rows.iter().zip(values) {
            assert_eq!(row[0], v["label"].as_str().unwrap());
            assert_eq!(row[1].trim_start_matches("≈ "), num(&v["published"]));
            assert_eq!(row[2], num(&v["ours"]), "{row:?}");
            assert_eq!(row[4].replace(' ', "_"), v["status"].as_str().unwrap());
            for (k, o) in v["other_readings"].as_array().unwrap().iter().enumerate() {
                assert_eq!(row[5 + 2 * k], num(&o["ours"]), "{row:?}");
                assert_eq!(row[6 + 2 * k].replace(' ', "_"), o["status"].as_str().unwrap());
            }
            rows_checked += 1;
        }
        if item["eval"] == "transitions" {
            assert!(page.contains("## What `surfcap eval transitions` printed ("), "{page}");
        }
    }
    assert!(rows_checked > 10, "{rows_checked} rows");
}

#[test]
fn a_hand_written_results_page_is_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let md = tmp.path().join("results");
    std::fs::create_dir(&md).unwrap();
    std::fs::write(md.join("reproduce.md"), "# my notes\n").unwrap();
    let out = tmp.path().join("repro");
    let data = tmp.path().join("data");
    std::fs::create_dir(&data).unwrap();
    let o = surfcap!(&["reproduce", "--figure", "2.8", "-o", p(&out), "--data", p(&data), "--results-dir", p(&md)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("reproduce.md: not written by surfcap reproduce"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(md.join("reproduce.md")).unwrap(), "# my notes\n");
    assert!(!out.exists(), "nothing run for a refused results folder");
}

#[test]
fn an_own_check_runs_with_its_printed_tables_on_the_page() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("repro");
    let o = surfcap!(&["reproduce", "--check", "interchange", "--quick", "--data", p(&data), "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let results: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(results["items"][0]["id"], "surfcap-check-interchange");
    assert_eq!(results["items"][0]["kind"], "check");
    let printed = results["runs"]["interchange"]["printed"].as_str().unwrap();
    assert!(printed.contains("walking_cat_depraz"), "{printed}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("surfcap&#39;s own check") || html.contains("surfcap's own check"), "{html}");
    assert!(html.contains("<details class=\"printed\">"));
}

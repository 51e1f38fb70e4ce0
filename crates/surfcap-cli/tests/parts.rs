//! `surfcap parts propose|check|show` end to end on the KayKit knight (a small skinned subject
//! with joints and separate meshes): the proposal written and read back, a user's labels file,
//! a bad file named in the error, and the viewer serving per-part colours.

use surfcap_testkit::{ViewServer, http_request, p, stderr, surfcap};

/// `surfcap parts show ...` running until dropped.
fn show(args: &[&str]) -> ViewServer {
    ViewServer::start_command(env!("CARGO_BIN_EXE_surfcap"), &["parts", "show"], args)
}

#[test]
fn propose_check_and_show_parts_of_the_knight() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let knight = data.join("kaykit_adventurers/knight_Walking_A");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("knight.parts.json");
    let o = surfcap!(&["--json", "parts", "propose", p(&knight), "--method", "components", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["report"]["method"], "components");
    let names: Vec<&str> = v["parts"].as_array().unwrap().iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["torso", "arm_left", "arm_right", "leg_left", "leg_right"]);
    let total: u64 = v["parts"].as_array().unwrap().iter().map(|r| r["vertices"].as_u64().unwrap()).sum();
    assert_eq!(total, 2145, "separate meshes: no vertex in two parts");
    let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written["format"], "surfcap-parts");

    // The written file checks; so does a labels file made from it, with names by default.
    let o = surfcap!(&["--json", "parts", "check", p(&knight), "--parts", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(c["parts"], v["parts"]);
    let mut labels = vec![0u16; 2145];
    for (k, part) in written["parts"].as_array().unwrap().iter().enumerate() {
        for x in part["vertices"].as_array().unwrap() {
            labels[x.as_u64().unwrap() as usize] = k as u16;
        }
    }
    let txt = d.path().join("labels.txt");
    std::fs::write(&txt, labels.iter().map(|l| format!("{l}\n")).collect::<String>()).unwrap();
    let o = surfcap!(&["parts", "check", p(&knight), "--parts", p(&txt)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("5 parts fit knight_Walking_A (2145 vertices, 0 in overlaps)"), "{text}");
    assert!(text.contains("arm_left") && text.contains("child of torso"), "{text}");

    // A bad file: the error names it and what was expected; exit code 1.
    let bad = d.path().join("bad.json");
    std::fs::write(&bad, r#"{"labels": [0, 1, 1], "names": ["torso", "arm"]}"#).unwrap();
    let o = surfcap!(&["parts", "check", p(&knight), "--parts", p(&bad)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains(&format!("{}: 3 labels: expected one per template vertex (2145)", bad.display())), "{e}");
    std::fs::write(&bad, "{\"labels\": [0, 1,\n 2").unwrap();
    let o = surfcap!(&["parts", "check", p(&knight), "--parts", p(&bad)]);
    let e = stderr(&o);
    assert!(e.contains(&format!("{}: line 2, column", bad.display())), "{e}");
    // The output may not replace the subject.
    let o = surfcap!(&["parts", "propose", p(&knight), "-o", p(&knight.join("template.obj"))]);
    assert!(!o.status.success());

    // Shown: the items carry per-vertex colours and the parts' legend.
    let show = show(&[p(&knight), "--parts", p(&out)]);
    let (status, body) = http_request(&show.url, "GET", "/api/items");
    assert_eq!(status, 200);
    let items: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let item = &items["items"][0];
    assert_eq!(item["has_colours"], true);
    let legend: Vec<&str> = item["colour_legend"].as_array().unwrap().iter().map(|r| r[1].as_str().unwrap()).collect();
    assert_eq!(legend, ["torso", "arm_left", "arm_right", "leg_left", "leg_right", "overlap (darker)"]);
    let (status, body) = http_request(&show.url, "GET", "/api/items/0/colours");
    assert_eq!(status, 200);
    assert_eq!(body.len(), 2145 * 3 * 4);
    let colours: Vec<f32> = body.chunks(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    assert!(colours.iter().all(|c| (0.0..=1.0).contains(c)));
    let distinct: std::collections::BTreeSet<[u32; 3]> =
        colours.chunks(3).map(|c| [c[0].to_bits(), c[1].to_bits(), c[2].to_bits()]).collect();
    assert_eq!(distinct.len(), 5, "one colour per part (no overlaps between separate meshes)");
}

/// Runs tools/browser-test.mjs on the page at `url` and returns what it saw.
fn browser_test(url: &str, png: &std::path::Path) -> serde_json::Value {
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let o = std::process::Command::new("node")
        .arg(tools.join("browser-test.mjs"))
        .args([url, p(png)])
        .output()
        .expect("node runs");
    assert!(
        o.status.success(),
        "browser test failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn parts_show_draws_one_colour_per_part_in_chromium() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let knight = data.join("kaykit_adventurers/knight_Idle");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("knight.parts.json");
    let o = surfcap!(&["parts", "propose", p(&knight), "--method", "components", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let show = show(&[p(&knight), "--parts", p(&out)]);
    let seen = browser_test(&show.url, &d.path().join("parts.png"));
    let legend: Vec<&str> = seen["legend"].as_array().unwrap().iter().map(|x| x.as_str().unwrap()).collect();
    assert_eq!(&legend[..6], ["torso", "arm_left", "arm_right", "leg_left", "leg_right", "overlap (darker)"]);
    assert!(!legend.contains(&"original frame"), "{legend:?}");
    // The arms are drawn orange and blue, the torso grey; no frame green.
    let count =
        |colour: &str| seen.pointer(&format!("/colours/original/{colour}")).and_then(|v| v.as_u64()).unwrap_or(0);
    assert!(count("orange") > 50 && count("blue") > 50, "{seen}");
    assert_eq!(count("red"), 0, "{seen}");
}

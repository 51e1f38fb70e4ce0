//! `surfcap eval vary` on a small CMU case (the 1,000-vertex mannequin, walk and jog, GPDMs of
//! 20 iterations, 2 variants): the report and the plots written, the exit code saying whether
//! a criterion was missed, the same numbers on one thread, and bad options named.

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn run(data: &std::path::Path, out: &std::path::Path, threads: &str) -> (std::process::Output, Value) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_surfcap"))
        .env("RAYON_NUM_THREADS", threads)
        .args([
            "eval",
            "vary",
            "--data",
            p(data),
            "--only",
            "cmu",
            "--cmu-clips",
            "16_15,16_36",
            "--vertices",
            "1000",
            "--variants",
            "2",
            "--iterations",
            "20",
            "--seed",
            "3",
            "-o",
            p(out),
            "--json",
        ])
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stderr(&o)));
    (o, v)
}

/// The report without its timings and file list.
fn numbers(v: &Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter()
                .filter(|(k, _)| !k.ends_with("seconds") && k.as_str() != "written")
                .map(|(k, x)| (k.clone(), numbers(x)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.iter().map(numbers).collect()),
        x => x.clone(),
    }
}

#[test]
fn vary_evaluation_writes_its_report_and_plots_and_fails_on_a_missed_criterion() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("vary");
    let (o, v) = run(&data, &out, "2");
    let missed = v["missed"].as_u64().unwrap();
    if missed == 0 {
        assert!(o.status.success(), "{}", stderr(&o));
    } else {
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(&format!("{missed} variation criteria MISSED")), "{}", stderr(&o));
    }
    let file: Value = serde_json::from_slice(&std::fs::read(out.join("vary.json")).unwrap()).unwrap();
    assert_eq!(file, v);
    let c = &v["cases"][0];
    assert_eq!(c["name"], "cmu");
    assert_eq!(c["sequences"].as_array().unwrap().len(), 3, "walk, jog and their blend");
    let rec = &c["reconstruction"]["overall"];
    assert!(rec["gpdm_training"].as_f64().unwrap() < rec["pca_training"].as_f64().unwrap(), "{rec}");
    let var = c["variation"].as_array().unwrap();
    assert_eq!(var.len(), 2);
    let failed: u64 = var
        .iter()
        .map(|s| s["passes"].as_object().unwrap().values().filter(|p| !p.as_bool().unwrap()).count() as u64)
        .sum();
    assert_eq!(failed, missed);
    let mut files = vec!["cmu_fig6_4".to_string(), "cmu_fig6_7".to_string()];
    files.extend(c["parts"].as_array().unwrap().iter().map(|p| format!("cmu_latent_{}", p.as_str().unwrap())));
    for f in &files {
        for ext in ["svg", "png"] {
            assert!(out.join(format!("{f}.{ext}")).is_file(), "{f}.{ext}");
        }
    }
    assert_eq!(v["written"].as_array().unwrap().len(), 2 * files.len());
    // One thread: the same numbers.
    let (_, one) = run(&data, &tmp.path().join("vary1"), "1");
    assert_eq!(numbers(&one), numbers(&v));
    // Bad options.
    let o = surfcap!(&["eval", "vary", "--data", p(&data), "--only", "mocap", "-o", p(&tmp.path().join("x"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--only mocap: expected cmu or kaykit"), "{}", stderr(&o));
    let o = surfcap!(&[
        "eval",
        "vary",
        "--data",
        p(&data),
        "--only",
        "cmu",
        "--cmu-clips",
        "16_15",
        "-o",
        p(&tmp.path().join("y"))
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--cmu-clips: expected at least two clips"), "{}", stderr(&o));
}

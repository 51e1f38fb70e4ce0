//! `surfcap tiles` on real data: a KayKit character's walk and run planned in
//! tiles, every job run from the command line, merged; the distances equal `surfcap distance`'s
//! matrix to the bit, and zarr-python (the reference implementation numpy/xarray users have)
//! reads every array of the work folder with the tiles as chunks. Errors name what was expected.

use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn tiled_work_on_real_data_equals_the_one_machine_matrix_and_opens_in_zarr_python() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let k = data.join("kaykit_adventurers");
    let subject = d.path().join("knight.subject");
    let o = surfcap!(&[
        "--quiet",
        "import",
        p(&k.join("knight_Walking_A")),
        p(&k.join("knight_Running_A")),
        "-o",
        p(&subject)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let work = d.path().join("work");
    let o = surfcap!(&[
        "--quiet",
        "tiles",
        "plan",
        p(&subject),
        "-o",
        p(&work),
        "--tile",
        "16",
        "--l-min",
        "3",
        "--l-max",
        "8",
        "--k",
        "6"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // One job from the command line, then the rest of everything (the done one skipped).
    let o = surfcap!(&["--json", "tiles", "run", p(&work), "--stage", "distances", "--index", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let one: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(one["jobs"][0]["skipped"], false);
    assert!(one["jobs"][0]["record"]["span"].as_str().unwrap().contains("knight_Walking_A:"), "{one}");
    let o = surfcap!(&["--json", "tiles", "run", p(&work), "--all"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let all: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let jobs = all["jobs"].as_array().unwrap();
    assert_eq!(jobs.iter().filter(|j| j["skipped"] == true).count(), 1, "the job already done is skipped");
    let o = surfcap!(&["--json", "tiles", "merge", p(&work)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let merged: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(merged["graph_edges"].as_u64().unwrap() > 0, "{merged}");

    let npy = d.path().join("d.npy");
    let o = surfcap!(&["--quiet", "distance", p(&subject), "-o", p(&npy), "--cache-dir", p(&d.path().join("cache"))]);
    assert!(o.status.success(), "{}", stderr(&o));
    let expected = surfcap_mesh::npy::read_npy::<f64>(&npy).unwrap();

    let python = surfcap_testkit::workspace_root().join("tools/venv/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/test (it installs zarr)", python.display());
    let out = d.path().join("read");
    let o = std::process::Command::new(&python)
        .arg(surfcap_testkit::workspace_root().join("tools/zarr-read.py"))
        .args([&work, &out])
        .output()
        .unwrap();
    assert!(o.status.success(), "zarr-python could not read the work folder:\n{}", stderr(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let n = expected.shape[0] as u64;
    assert_eq!(summary["distances.zarr"]["shape"], serde_json::json!([n, n]));
    assert_eq!(summary["distances.zarr"]["chunks"], serde_json::json!([16, 16]), "chunks are the tiles");
    assert_eq!(summary["table/len.zarr"]["dtype"], "uint32");
    let read = surfcap_mesh::npy::read_npy::<f64>(&out.join("distances.npy")).unwrap();
    assert_eq!(read.shape, expected.shape);
    let differ = read.data.iter().zip(&expected.data).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    assert_eq!(differ, 0, "tiled distances read by zarr-python vs `surfcap distance`");
    let costs = surfcap_mesh::npy::read_npy::<f64>(&out.join("paths_costs.npy")).unwrap();
    assert!(costs.data.iter().all(|c| !c.is_nan()), "every path cost written");
}

#[test]
fn tile_commands_refuse_bad_requests_by_name() {
    let d = tempfile::tempdir().unwrap();
    let subject = d.path().join("m.subject");
    let o =
        surfcap!(&["--quiet", "make", "mannequin", "--procedural", "walk", "--vertices", "1000", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Not a subject cache.
    let o = surfcap!(&["tiles", "plan", p(&d.path().join("nothing")), "-o", p(&d.path().join("w"))]);
    assert!(!o.status.success() && stderr(&o).contains("expected a subject cache"), "{}", stderr(&o));
    let work = d.path().join("work");
    let o = surfcap!(&["--quiet", "tiles", "plan", p(&subject), "-o", p(&work), "--tile", "30"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "run", p(&work), "--stage", "distance", "--index", "0"]);
    assert!(stderr(&o).contains("expected one of distances, table, scale, candidates, paths"), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "run", p(&work), "--stage", "distances", "--index", "99"]);
    assert!(stderr(&o).contains("job 99 of stage distances"), "{}", stderr(&o));
    // A later stage before its inputs: refused, naming what to run first.
    let o = surfcap!(&["tiles", "run", p(&work), "--stage", "table", "--index", "0"]);
    assert!(!o.status.success() && stderr(&o).contains("run the earlier stage"), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "merge", p(&work)]);
    assert!(!o.status.success() && stderr(&o).contains("stage distances"), "{}", stderr(&o));
    let o = surfcap!(&["--json", "tiles", "count", p(&work), "--stage", "table"]);
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(c["jobs"].as_u64().unwrap() > 1);
    // Another plan into the same folder, and a changed subject.
    let o = surfcap!(&["tiles", "plan", p(&subject), "-o", p(&work), "--tile", "31"]);
    assert!(!o.status.success() && stderr(&o).contains("another subject or other parameters"), "{}", stderr(&o));
    let o = surfcap!(&["--quiet", "make", "mannequin", "--procedural", "jog", "--vertices", "1000", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "status", p(&work)]);
    assert!(!o.status.success() && stderr(&o).contains("changed since it was planned"), "{}", stderr(&o));
}

#[test]
fn tiles_status_and_merge_exit_non_zero_naming_a_damaged_chunk() {
    let d = tempfile::tempdir().unwrap();
    let subject = d.path().join("m.subject");
    let o =
        surfcap!(&["--quiet", "make", "mannequin", "--procedural", "walk", "--vertices", "1000", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let work = d.path().join("work");
    let o = surfcap!(&["--quiet", "tiles", "plan", p(&subject), "-o", p(&work), "--tile", "16"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["--quiet", "tiles", "run", p(&work), "--stage", "distances", "--all"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "status", p(&work)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A chunk of the right size filled with NaN: found by its content hash, not by --quick.
    let chunk = work.join("distances.zarr/c/0/1");
    let len = std::fs::metadata(&chunk).unwrap().len() as usize;
    std::fs::write(&chunk, (0..len).map(|i| f64::NAN.to_le_bytes()[i % 8]).collect::<Vec<u8>>()).unwrap();
    let o = surfcap!(&["tiles", "status", p(&work), "--quick"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "status", p(&work)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("1 problem") && e.contains("distances.zarr/c/0/1: content differs from its job record"), "{e}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("damaged 1"), "the stage line names the damaged job");
    let o = surfcap!(&["tiles", "merge", p(&work)]);
    assert!(!o.status.success() && stderr(&o).contains("distances.zarr/c/0/1"), "{}", stderr(&o));
    // `run` computes the damaged job again; status is clean.
    let o = surfcap!(&["--quiet", "tiles", "run", p(&work), "--stage", "distances", "--all"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["tiles", "status", p(&work)]);
    assert!(o.status.success(), "{}", stderr(&o));
}

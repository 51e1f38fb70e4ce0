//! One-cycle game clips (a walk and a run authored as single loops, as most game locomotion
//! is) on real data: `import` and `info` say they loop, the graph plays each clip's last frame
//! into its first, and path following on them meets the errors it meets on long clips. The
//! clips are cut here to exactly one cycle from the shared KayKit knight and from the
//! procedural mannequin.

use std::path::{Path, PathBuf};
use std::process::Output;

use surfcap_geometry::motion_plane_alignment::motion_plane_alignment;
use surfcap_mesh::{Subject, UpAxis};
use surfcap_testkit::{p, procedural_walker, stderr, surfcap};

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("--json prints the result")
}

/// Body-frame distance of two frames (eq. 2.2 after the motion-plane alignment).
fn body(a: &[f32], b: &[f32], up: UpAxis) -> f64 {
    motion_plane_alignment(a, b, None, up).1.sqrt()
}

/// The length of one cycle of `frames` ([F][V][3] flattened, `per` numbers a frame): the
/// distance to the first pose rises above half its largest value, falls back below it, and the
/// frame where it is smallest before it rises again starts the next cycle, so frames 0..k are
/// one cycle.
fn cycle_length(frames: &[f32], per: usize, up: UpAxis) -> usize {
    let f = frames.len() / per;
    let frame = |k: usize| &frames[k * per..(k + 1) * per];
    let d: Vec<f64> = (0..f).map(|k| body(frame(0), frame(k), up)).collect();
    let half = d.iter().copied().fold(0.0, f64::max) / 2.0;
    let risen = (0..f).find(|&k| d[k] > half).unwrap();
    let back = (risen..f).find(|&k| d[k] < half).unwrap();
    let again = (back..f).find(|&k| d[k] > half).unwrap_or(f);
    (back..again).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap()
}

/// A KayKit clip cut to one cycle, as a dataset folder (template.obj + positions.npy).
fn kaykit_cycle(data: &Path, clip: &str, dir: &Path) -> (PathBuf, usize) {
    let src = data.join("kaykit_adventurers").join(clip);
    let a = surfcap_mesh::npy::read_npy::<f32>(&src.join("positions.npy")).unwrap();
    let per = a.shape[1] * 3;
    let k = cycle_length(&a.data, per, UpAxis::parse("+y").unwrap());
    let out = dir.join(clip);
    std::fs::create_dir_all(&out).unwrap();
    std::fs::copy(src.join("template.obj"), out.join("template.obj")).unwrap();
    let file = std::fs::File::create(out.join("positions.npy")).unwrap();
    surfcap_mesh::npy::write_npy(file, &[k, a.shape[1], 3], &a.data[..k * per]).unwrap();
    (out, k)
}

/// The procedural mannequin's walk and jog (with their own root travel), each cut to one cycle.
fn mannequin_cycles(dir: &Path) -> (PathBuf, Vec<usize>) {
    let long = procedural_walker!(dir);
    let s = surfcap_mesh::cache::read_cache(&long, &surfcap_mesh::NoProgress).unwrap();
    let per = 3 * s.topology().n_vertices();
    let mut lengths = Vec::new();
    let sequences = s
        .sequences()
        .iter()
        .map(|q| {
            let k = cycle_length(q.positions(), per, s.up_axis);
            lengths.push(k);
            surfcap_mesh::Sequence::new(q.name.clone(), s.topology().n_vertices(), q.positions()[..k * per].to_vec())
                .unwrap()
                .with_tags(q.tags.clone())
        })
        .collect();
    let cut =
        Subject::new("walker_cycles", s.topology().clone(), sequences, s.fps, s.up_axis, s.units.clone()).unwrap();
    let out = dir.join("cycles.subject");
    surfcap_mesh::cache::write_cache(&out, &cut, false, &surfcap_mesh::NoProgress).unwrap();
    (out, lengths)
}

/// Follows `curve` on `subject`; the report, and whether the walk used a wrap edge (the last
/// frame of a clip followed by its first).
fn follow(subject: &Path, curve: &Path, out: &Path, cache: &Path) -> (serde_json::Value, usize) {
    let r = json(&surfcap!(&[
        "synth",
        "path",
        p(subject),
        "--curve",
        p(curve),
        "-o",
        p(out),
        "--cache-dir",
        p(cache),
        "--json"
    ]));
    let info = json(&surfcap!(&["info", p(subject), "--json"]));
    let mut ends = Vec::new();
    let mut start = 0u64;
    for q in info["sequences"].as_array().unwrap() {
        let n = q["frames"].as_u64().unwrap();
        ends.push((start + n - 1, start));
        start += n;
    }
    let walk: Vec<u64> = r["walk"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
    let wraps = walk.windows(2).filter(|w| ends.iter().any(|&(last, first)| w[0] == last && w[1] == first)).count();
    (r, wraps)
}

fn line_curve(dir: &Path) -> PathBuf {
    let line = dir.join("line.csv");
    std::fs::write(&line, "x,z\n0,0\n10,0\n").unwrap();
    line
}

fn s_curve() -> PathBuf {
    surfcap_testkit::workspace_root().join("examples").join("s_path_15m.csv")
}

/// Every clip loops (import and info say so), walks play wrap edges, and the 15 m S-curve and a
/// 10 m line are followed within 0.1 m mean centre error.
fn check_character(subject: &Path, clips: usize, dir: &Path, what: &str) {
    let info = json(&surfcap!(&["info", p(subject), "--json"]));
    let seqs = info["sequences"].as_array().unwrap();
    assert_eq!(seqs.len(), clips);
    for q in seqs {
        assert_eq!(q["loops"], true, "{what}: {q}");
        assert_eq!(q["loop_wraps_to_frame"], 0, "{what}: {q}");
    }
    let cache = dir.join("cache");
    let line = line_curve(dir);
    for (name, curve) in [("line", &line), ("S-curve", &s_curve())] {
        let (r, wraps) = follow(subject, curve, &dir.join(format!("{name}.glb")), &cache);
        let (mean, max) = (r["mean_error"].as_f64().unwrap(), r["max_error"].as_f64().unwrap());
        eprintln!(
            "{what}, {name}: mean error {mean:.3} m, max {max:.3} m, {} frames, {} transitions, {wraps} wraps",
            r["frames"], r["transitions"]
        );
        assert!(wraps > 0, "{what}, {name}: no wrap edge played");
        assert!(r["travelled"].as_f64().unwrap() >= r["curve_length"].as_f64().unwrap() - 0.01);
        assert!(mean < 0.1, "{what}, {name}: mean centre error {mean} m; {}", r["missed_stretches"]);
    }
}

#[test]
fn one_cycle_kaykit_walk_and_run_loop_and_follow_the_s_curve() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let (walk, kw) = kaykit_cycle(&data, "knight_Walking_A", tmp.path());
    let (run, kr) = kaykit_cycle(&data, "knight_Running_A", tmp.path());
    // The source clips repeat their first frame at the end: one cycle is one frame shorter.
    assert_eq!((kw, kr), (32, 24));
    let subject = tmp.path().join("knight.subject");
    let r = json(&surfcap!(&[
        "import",
        p(&walk),
        p(&run),
        "--root-motion",
        "contacts",
        "--fps",
        "30",
        "--up-axis",
        "+y",
        "--units",
        "m",
        "-o",
        p(&subject),
        "--json"
    ]));
    assert_eq!(r["loops"], serde_json::json!(["knight_Walking_A", "knight_Running_A"]), "{r}");
    check_character(&subject, 2, tmp.path(), "KayKit knight");
}

#[test]
fn one_cycle_mannequin_walk_and_jog_loop_and_follow_the_s_curve() {
    let tmp = tempfile::tempdir().unwrap();
    let (subject, lengths) = mannequin_cycles(tmp.path());
    eprintln!("mannequin cycles: {lengths:?} frames");
    check_character(&subject, 2, tmp.path(), "procedural mannequin");
    // A path off by more than the tolerance is not "followed": the line says missed and where,
    // the report lists the stretch, and --strict exits 3 as every missed constraint does.
    let glb = tmp.path().join("missed.glb");
    let (curve, cache) = (s_curve(), tmp.path().join("cache"));
    let args = ["synth", "path", p(&subject), "--curve", p(&curve), "-o", p(&glb), "--tolerance", "0.001"];
    let extra = ["--cache-dir", p(&cache)];
    let o = surfcap!(&[&args[..], &extra, &["--strict"]].concat());
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.starts_with("missed a 14.99 m curve") && !out.contains("followed"), "{out}");
    assert!(out.contains("off the curve from"), "{out}");
    assert!(stderr(&o).contains("constraint path missed"), "{}", stderr(&o));
    let r = json(&surfcap!(&[&args[..], &extra, &["--json", "--force"]].concat()));
    assert_eq!(r["constraints"][0]["missed"], true);
    assert!(!r["missed_stretches"].as_array().unwrap().is_empty(), "{r}");
}

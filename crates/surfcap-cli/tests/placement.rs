//! Transitions keep the captured placement of a subject that does not travel: on the moving
//! head (the scan bent at the neck, `make head`), key poses across nod, turn and tilt turn
//! the head while the bust's bottom stays where the capture has it, as in the source.

use surfcap_formats::import::{ImportOptions, open_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_testkit::{p, stderr, surfcap};

/// The vertices of the bust's bottom (the lowest tenth of the rest frame's height) and how far
/// any frame of `s` moves them from the rest frame, largest over frames and vertices.
fn bottom_displacement(rest: &[f32], s: &Subject) -> (usize, f64, f64) {
    let ys: Vec<f32> = rest.chunks_exact(3).map(|v| v[1]).collect();
    let (lo, hi) = ys.iter().fold((f32::MAX, f32::MIN), |(a, b), &y| (a.min(y), b.max(y)));
    let height = f64::from(hi - lo);
    let bottom: Vec<usize> = (0..ys.len()).filter(|&v| f64::from(ys[v] - lo) < 0.1 * height).collect();
    let mut worst: f64 = 0.0;
    for g in 0..s.n_frames() {
        let f = s.frame(g).unwrap();
        for &v in &bottom {
            let d: f64 = (0..3).map(|k| f64::from(f[3 * v + k] - rest[3 * v + k]).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d);
        }
    }
    (bottom.len(), worst, height)
}

#[test]
fn key_poses_on_the_moving_head_keep_its_shoulders_in_place() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (subject, cache, out) = (dir.join("head.subject"), dir.join("cache"), dir.join("keyposes"));
    let o = surfcap!(&[
        "make",
        "head",
        p(&data.join("leeperrysmith_head")),
        "--frames-per-sequence",
        "12",
        "-o",
        p(&subject),
        "--quiet"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let keys = dir.join("keys.csv");
    std::fs::write(&keys, "nod:2,0\nturn:8,30\ntilt:5,60\n").unwrap();
    let o = surfcap!(&[
        "--json",
        "synth",
        "keyposes",
        p(&subject),
        "--keys",
        p(&keys),
        "--l-min",
        "3",
        "--l-max",
        "8",
        "--cache-dir",
        p(&cache),
        "--format",
        "npy",
        "-o",
        p(&out)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(r["transitions"].as_u64().unwrap() >= 2, "{}", r["segments"]);
    assert_eq!(r["placement"], "captured", "the head does not travel");
    let source = open_subject(&subject, &ImportOptions::default(), &NoProgress).unwrap().subject;
    let played = open_subject(&out, &ImportOptions::default(), &NoProgress).unwrap().subject;
    let rest = source.frame(0).unwrap();
    let (n, in_source, height) = bottom_displacement(rest, &source);
    let (_, in_output, _) = bottom_displacement(rest, &played);
    eprintln!(
        "{n} bottom vertices: moved at most {in_source:.4} in the source, {in_output:.4} in the key poses \
         (bust height {height:.3})"
    );
    assert!(n > 100, "{n} bottom vertices");
    // The neck's bend moves the bottom a little in the source (about 5% of the height); the
    // transitions add at most 1% of the height to it (re-placed, they moved it by 90%).
    assert!(in_output <= in_source + 0.01 * height, "{in_output} vs {in_source} in the source (height {height})");
}

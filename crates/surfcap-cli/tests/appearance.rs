//! `surfcap appearance generate`: benchmark textures from the real head scan (small size for
//! speed), read back through the library's reader; the same seed gives the same files; a mesh
//! without texture coordinates is refused by name.

use surfcap_appearance::generated_frames::GeneratedFrames;
use surfcap_testkit::{p, stderr, surfcap};

#[test]
fn generate_writes_a_sequence_the_reader_opens() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("gen");
    let args = |out: &std::path::Path| {
        vec![
            "--json".to_string(),
            "appearance".into(),
            "generate".into(),
            "--data".into(),
            p(&data).into(),
            "--frames".into(),
            "8".into(),
            "--seed".into(),
            "7".into(),
            "--size".into(),
            "128".into(),
            "--hole-fraction".into(),
            "0.25".into(),
            "-o".into(),
            p(out).into(),
        ]
    };
    let a: Vec<String> = args(&out);
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["frames"], 8);
    assert_eq!(report["width"], 128);
    assert_eq!(report["hole_frames"].as_array().unwrap().len(), 2);
    let g = GeneratedFrames::open(&out).unwrap();
    assert_eq!((g.frames(), g.width(), g.height()), (8, 128, 128));
    assert_eq!(g.header().seed, 7);
    let k = g.header().hole_frames[0];
    let hole = g.hole(k).unwrap();
    let frame = g.frame(k).unwrap();
    assert!(hole.iter().any(|&h| h));
    assert!(hole.iter().enumerate().filter(|(_, h)| **h).all(|(i, _)| (0..3).all(|c| frame.plane(c)[i] == 0.0)));
    assert!(g.header().source_mesh.ends_with("leeperrysmith_head/template.obj"));
    // Same seed, same bytes; the earlier folder of the same kind is replaced.
    let again = d.path().join("again");
    let a2 = args(&again);
    let o = surfcap!(&a2.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["frame_003.png", "clean_005.png", "holes.npy"] {
        assert_eq!(std::fs::read(out.join(name)).unwrap(), std::fs::read(again.join(name)).unwrap(), "{name}");
    }
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "rewriting its own folder: {}", stderr(&o));
}

#[test]
fn a_mesh_without_texture_coordinates_is_named() {
    let d = tempfile::tempdir().unwrap();
    let mesh = d.path().join("plain.obj");
    std::fs::write(&mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let texture = d.path().join("t.png");
    // A 2x2 PNG written by the library itself.
    surfcap_appearance::TextureImage::zeros(2, 2, 3).write_png(&texture).unwrap();
    let o = surfcap!(&[
        "appearance",
        "generate",
        "--mesh",
        p(&mesh),
        "--texture",
        p(&texture),
        "--frames",
        "2",
        "-o",
        p(&d.path().join("out")),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("plain.obj") && e.contains("no texture coordinates"), "{e}");
    // A missing data folder is named too.
    let o =
        surfcap!(&["appearance", "generate", "--data", p(&d.path().join("nowhere")), "-o", p(&d.path().join("o2"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nowhere/leeperrysmith_head"), "{}", stderr(&o));
}

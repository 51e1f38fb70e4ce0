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

/// Runs `surfcap --json ARGS` and returns its JSON result, failing with its stderr.
fn run_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    let o = surfcap!(&all);
    assert!(o.status.success(), "surfcap {}: {}", args.join(" "), stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn a_model_built_from_generated_maps_reconstructs_interpolates_and_completes() {
    use surfcap_appearance::TextureImage;
    use surfcap_appearance::image_similarity::mse;
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let gen_dir = d.path().join("gen");
    let (model, cache) = (d.path().join("head.appearance"), d.path().join("cache"));
    run_json(&[
        "appearance",
        "generate",
        "--data",
        p(&data),
        "--frames",
        "10",
        "--seed",
        "3",
        "--size",
        "96",
        "--hole-fraction",
        "0.2",
        "-o",
        p(&gen_dir),
    ]);
    let g = GeneratedFrames::open(&gen_dir).unwrap();
    // Built from the folder alone: its template.obj gives the atlas, the file stems the names;
    // the frames with holes are left out (thesis 4.6.2).
    let built = run_json(&["appearance", "build", p(&gen_dir), "--cache-dir", p(&cache), "-o", p(&model)]);
    let holed = g.header().hole_frames.len();
    assert_eq!(holed, 2);
    assert_eq!(built["frames"], 10 - holed);
    assert_eq!(built["eigen_textures"], 9 - holed);
    assert_eq!(built["eigen_warps"], 9 - holed);
    assert!(built["reference"].as_str().unwrap().starts_with("frame_"));
    let errors = built["medoid_errors"].as_array().unwrap();
    assert!(!errors.is_empty());
    // Every flow was cached: a second build computes none and gives the same model.
    let flows = std::fs::read_dir(&cache).unwrap().count();
    assert!(flows >= 9 - holed, "{flows} cached flows");
    let model2 = d.path().join("again.appearance");
    let again = run_json(&["appearance", "build", p(&gen_dir), "--cache-dir", p(&cache), "-o", p(&model2)]);
    assert_eq!(again["reference"], built["reference"]);
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), flows);
    assert_eq!(
        std::fs::read(model.join("eigen_textures.npy")).unwrap(),
        std::fs::read(model2.join("eigen_textures.npy")).unwrap()
    );

    // Reconstruction with every component is close to the input map; with none it is the mean,
    // farther away.
    let active: Vec<bool> = {
        let m = surfcap_appearance::AppearanceModel::load(&model).unwrap();
        (0..96 * 96).map(|i| m.mask().is_active(i)).collect()
    };
    let frame = (0..10).find(|k| !g.header().hole_frames.contains(k)).unwrap();
    let name = format!("frame_{frame:03}");
    let full = d.path().join("full.png");
    let none = d.path().join("none.png");
    run_json(&["appearance", "reconstruct", p(&model), "--frame", &name, "-o", p(&full)]);
    run_json(&["appearance", "reconstruct", p(&model), "--frame", &name, "--components", "0", "-o", p(&none)]);
    let input = g.frame(frame).unwrap();
    let e_full = mse(&TextureImage::read(&full).unwrap(), &input, &active).unwrap();
    let e_none = mse(&TextureImage::read(&none).unwrap(), &input, &active).unwrap();
    assert!(e_full < 0.5 * e_none, "all components {e_full}, none {e_none}");

    // Interpolation: weights 1/0 give the frame's reconstruction; a frame the model lacks is
    // refused by name.
    let one = d.path().join("one.png");
    let other = format!("frame_{:03}", (0..10).find(|k| *k != frame && !g.header().hole_frames.contains(k)).unwrap());
    run_json(&["appearance", "interpolate", p(&model), "--frames", &format!("{name}=1,{other}=0"), "-o", p(&one)]);
    let diff = mse(&TextureImage::read(&one).unwrap(), &TextureImage::read(&full).unwrap(), &active).unwrap();
    assert!(diff < 1.0, "{diff}");
    let o = surfcap!(&["appearance", "interpolate", p(&model), "--frames", "walk:3,frame_001", "-o", p(&one)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("frame \"walk:3\": the model has no frame of that name"), "{}", stderr(&o));

    // Completion of a map with a hole: the hole's texels are filled, closer to the clean frame
    // than the black hole.
    let k = g.header().hole_frames[0];
    let holed = gen_dir.join(&g.header().frame_files[k]);
    let done = d.path().join("done.png");
    let r = run_json(&["appearance", "complete", p(&model), p(&holed), "--cache-dir", p(&cache), "-o", p(&done)]);
    assert!(r["missing_texels"].as_u64().unwrap() > 0);
    let hole = g.hole(k).unwrap();
    let in_hole: Vec<bool> = hole.iter().zip(&active).map(|(h, a)| *h && *a).collect();
    let clean = g.clean(k).unwrap();
    let before = mse(&g.frame(k).unwrap(), &clean, &in_hole).unwrap();
    let after = mse(&TextureImage::read(&done).unwrap(), &clean, &in_hole).unwrap();
    assert!(after < 0.2 * before, "hole MSE: completed {after}, holed {before}");
}

#[test]
fn build_refuses_a_folder_without_a_mesh_and_maps_of_different_sizes() {
    let d = tempfile::tempdir().unwrap();
    let maps = d.path().join("maps");
    std::fs::create_dir(&maps).unwrap();
    surfcap_appearance::TextureImage::zeros(8, 8, 3).write_png(&maps.join("a_1.png")).unwrap();
    surfcap_appearance::TextureImage::zeros(8, 6, 3).write_png(&maps.join("a_2.png")).unwrap();
    let o = surfcap!(&["appearance", "build", p(&maps), "-o", p(&d.path().join("m"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no template.obj in the folder: give the UV-mapped mesh"), "{}", stderr(&o));
    let mesh = d.path().join("quad.obj");
    std::fs::write(&mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
    let o = surfcap!(&["appearance", "build", p(&maps), "--mesh", p(&mesh), "-o", p(&d.path().join("m"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("a_2.png: the texture map is 8x6: expected 8x8"), "{}", stderr(&o));
}

//! Shape and appearance animated together (thesis Fig. 7.1), end to end on the
//! real head scan at a tiny size: `make head` (the scan bent into nod, turn and tilt, its UV
//! atlas kept), `appearance generate --mesh SUBJECT` (one map per frame), `appearance build
//! --mesh SUBJECT` (the model's frames named `sequence:frame`), then `synth keyposes` and
//! `interpolate` with `--appearance`: a valid glb with a texture per frame, captured frames
//! showing the model's reconstruction, transition frames its interpolation with the report's
//! weight (different from both ends), the report's provenance agreeing with the walk.

use std::path::Path;

use surfcap_appearance::AppearanceModel;
use surfcap_mesh::FrameTextures;
use surfcap_testkit::{p, stderr, surfcap};

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("--json prints the result")
}

fn rgb8(png: &[u8]) -> Vec<u8> {
    image::load_from_memory(png).unwrap().to_rgb8().into_raw()
}

/// The glb's textures (validated by the Khronos validator first) and its frame count.
fn textures_of(glb: &Path) -> (FrameTextures, usize) {
    surfcap_testkit::validate_glb(&[glb.to_path_buf()]);
    let bytes = std::fs::read(glb).unwrap();
    let (set, textures) = surfcap_formats::glb_frame_set::parse_glb_frame_set_textured(&bytes, "out").unwrap();
    let textures = textures.expect("a texture per frame");
    assert!(set.sequences()[0].frames().iter().all(|f| f.topology().uv().is_some()), "every frame keeps its UVs");
    (textures, set.frame_count())
}

/// Checks every frame's texture against the model as the report's `appearance.per_frame` says
/// it was made; returns how many frames are transition blends.
fn check_textures(model: &AppearanceModel, glb: &Path, appearance: &serde_json::Value) -> usize {
    let (textures, frames) = textures_of(glb);
    let per_frame = appearance["per_frame"].as_array().unwrap();
    assert_eq!(per_frame.len(), frames);
    assert_eq!(appearance["textures"].as_u64().unwrap() as usize, textures.images().len());
    assert_eq!(
        appearance["reconstructed"].as_u64().unwrap() + appearance["interpolated"].as_u64().unwrap(),
        textures.images().len() as u64
    );
    assert!(appearance["instantiate_seconds"].as_f64().unwrap() > 0.0);
    let index = |name: &serde_json::Value| model.names().iter().position(|n| n == name.as_str().unwrap()).unwrap();
    let own = |k: usize| model.reconstruct(k).unwrap().to_rgb8();
    let mut blends = 0;
    for (f, made) in per_frame.iter().enumerate() {
        let shown = rgb8(textures.frame_png(0, f));
        if let Some(frame) = made.get("frame") {
            assert_eq!(shown, own(index(frame)), "frame {f} ({made}) is its reconstruction");
        } else {
            let (a, b, w) = (index(&made["from"]), index(&made["to"]), made["weight"].as_f64().unwrap());
            assert!(0.0 < w && w < 1.0, "{made}");
            assert_ne!(shown, own(a), "frame {f} ({made}) differs from its source");
            assert_ne!(shown, own(b), "frame {f} ({made}) differs from its destination");
            let expected = model.interpolate(&[(a, 1.0 - w), (b, w)]).unwrap().to_rgb8();
            // The report's weight is the f32 weight in its shortest form: equal to 8 bits.
            let off = shown.iter().zip(&expected).filter(|(x, y)| x.abs_diff(**y) > 1).count();
            assert!(off == 0, "frame {f} ({made}): {off} values differ from the model's interpolation");
            blends += 1;
        }
    }
    blends
}

#[test]
fn keyposes_and_interpolate_on_the_textured_head() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let head = data.join("leeperrysmith_head");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (subject, maps, model_dir, cache) =
        (dir.join("head.subject"), dir.join("gen"), dir.join("head.appearance"), dir.join("cache"));
    let o = surfcap!(&["make", "head", p(&head), "--frames-per-sequence", "12", "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let texture = head.join("Map-COL.jpg");
    let o = surfcap!(&[
        "--json",
        "appearance",
        "generate",
        "--mesh",
        p(&subject),
        "--texture",
        p(&texture),
        "--size",
        "64",
        "--seed",
        "5",
        // No occlusion holes: every frame keeps its map, so the model names all the subject's
        // frames (a build leaves holed frames out).
        "--hole-fraction",
        "0",
        "-o",
        p(&maps),
    ]);
    assert_eq!(json(&o)["frames"], 36, "one map per frame of the subject by default");
    let o = surfcap!(&[
        "--json",
        "appearance",
        "build",
        p(&maps),
        "--mesh",
        p(&subject),
        "-o",
        p(&model_dir),
        "--cache-dir",
        p(&cache),
    ]);
    json(&o);
    let model = AppearanceModel::load(&model_dir).unwrap();
    assert_eq!(&model.names()[..2], ["nod:0", "nod:1"]);

    // Key poses across the three sequences: transitions between them.
    let keys = dir.join("keys.csv");
    std::fs::write(&keys, "nod:2,0\ntilt:8,30\n").unwrap();
    let glb = dir.join("out.glb");
    let synth = |extra: &[&str]| {
        let mut args = vec!["synth", "keyposes", p(&subject), "--keys", p(&keys), "--cache-dir", p(&cache)];
        args.extend(["--l-min", "3", "--l-max", "8", "--json"]);
        args.extend(extra);
        surfcap!(&args)
    };
    let r = json(&synth(&["--appearance", p(&model_dir), "-o", p(&glb)]));
    let appearance = &r["appearance"];
    assert_eq!(appearance["model"], p(&model_dir));
    let blends = check_textures(&model, &glb, appearance);
    assert!(r["transitions"].as_u64().unwrap() > 0 && blends > 0, "{}", r["segments"]);
    // Provenance follows the walk: the first run's frames are shown as themselves, and only
    // synthetic frames blend.
    let per_frame = appearance["per_frame"].as_array().unwrap();
    let run = &r["segments"][0];
    let (first, last) = (run["first"].as_u64().unwrap(), run["last"].as_u64().unwrap());
    for (k, f) in (first..=last).enumerate() {
        assert_eq!(per_frame[k]["frame"], format!("{}:{f}", run["sequence"].as_str().unwrap()));
    }
    let side: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("out.json")).unwrap()).unwrap();
    let labels = side["sequences"][0]["frame_labels"].as_array().unwrap();
    for (made, label) in per_frame.iter().zip(labels) {
        if made.get("from").is_some() {
            assert_eq!(label, "synthetic", "{made}");
        }
    }
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out.report.json")).unwrap()).unwrap();
    assert_eq!(written["appearance"], *appearance, "the report file holds the provenance");

    // interpolate: the in-between frames blend with the geometry's weight.
    let iglb = dir.join("interp.glb");
    let o = surfcap!(&[
        "interpolate",
        p(&subject),
        "--from",
        "nod:3",
        "--to",
        "turn:4",
        "--steps",
        "5",
        "--appearance",
        p(&model_dir),
        "-o",
        p(&iglb),
        "--json",
    ]);
    let r = json(&o);
    let weights: Vec<f64> =
        r["appearance"]["per_frame"].as_array().unwrap().iter().filter_map(|m| m["weight"].as_f64()).collect();
    assert_eq!(weights, [0.25, 0.5, 0.75]);
    assert_eq!(r["appearance"]["per_frame"][0]["frame"], "nod:3");
    assert_eq!(r["appearance"]["per_frame"][4]["frame"], "turn:4");
    assert_eq!(check_textures(&model, &iglb, &r["appearance"]), 3);

    // Refused: a format that cannot carry a texture per frame, and a model of other frames.
    let o = synth(&["--appearance", p(&model_dir), "-o", p(&dir.join("out.abc"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--format abc cannot carry one"), "{}", stderr(&o));
    let other = dir.join("other.appearance");
    std::fs::create_dir(&other).unwrap();
    for e in std::fs::read_dir(&model_dir).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), other.join(e.file_name())).unwrap();
    }
    let text = std::fs::read_to_string(other.join("model.json")).unwrap();
    std::fs::write(other.join("model.json"), text.replacen("\"turn:3\"", "\"frame_015\"", 1)).unwrap();
    let o = synth(&["--appearance", p(&other), "-o", p(&dir.join("other.glb"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("turn:3 is not in the model") && e.contains("frame_015"), "{e}");
}

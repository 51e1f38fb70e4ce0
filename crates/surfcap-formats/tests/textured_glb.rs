//! A texture per frame in a glb on the real head scan: its UV atlas and its
//! real colour texture (downsampled to 128 x 128 for speed), three textures (the scan's
//! colours, a red and a blue tint) over four frames of a moving head, the first texture shown
//! twice. The file passes the Khronos validator, reads back with every frame's texture and UVs,
//! and plays in three.js (GLTFLoader in Chromium) with the right texture bound at each frame.

use std::path::Path;

use surfcap_formats::glb_frame_set::{parse_glb_frame_set_textured, write_glb_subject_textured};
use surfcap_mesh::{FrameTextures, Sequence, Subject, Units, UpAxis};

/// The head's colour texture at 128 x 128, each channel scaled by `tint`, as a PNG.
fn texture(path: &Path, tint: [f32; 3]) -> Vec<u8> {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    let mut small = image::imageops::resize(&img, 128, 128, image::imageops::FilterType::Triangle);
    for p in small.pixels_mut() {
        for (x, t) in p.0.iter_mut().zip(tint) {
            *x = (*x as f32 * t).round().min(255.0) as u8;
        }
    }
    let mut png = Vec::new();
    image::DynamicImage::ImageRgb8(small)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageOutputFormat::Png)
        .unwrap();
    png
}

#[test]
fn the_head_scan_plays_a_texture_per_frame() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let head = data.join("leeperrysmith_head");
    let obj = surfcap_formats::obj::read_obj(&head.join("template.obj")).unwrap();
    let topology = obj.topology().unwrap();
    assert!(topology.uv().is_some(), "the head scan has a UV atlas");
    // Four frames: the head nodding a little (a rotation about x).
    let nv = topology.n_vertices();
    let mut positions = Vec::with_capacity(4 * 3 * nv);
    for f in 0..4 {
        let (s, c) = (0.05 * f as f32).sin_cos();
        for p in obj.positions.chunks_exact(3) {
            positions.extend_from_slice(&[p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]]);
        }
    }
    let seq = Sequence::new("nod", nv, positions).unwrap();
    let subject = Subject::new("head", topology, vec![seq], 25.0, UpAxis::PosY, Units::arbitrary()).unwrap();
    let map = head.join("Map-COL.jpg");
    let images = vec![texture(&map, [1.0, 1.0, 1.0]), texture(&map, [1.0, 0.3, 0.3]), texture(&map, [0.3, 0.3, 1.0])];
    let textures = FrameTextures::new(images, vec![vec![0, 1, 2, 0]]).unwrap();

    let tmp = tempfile::tempdir().unwrap();
    let glb = tmp.path().join("head.glb");
    let mut bytes = Vec::new();
    write_glb_subject_textured(&mut bytes, &subject, &textures).unwrap();
    std::fs::write(&glb, &bytes).unwrap();
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));

    // Read back: every frame's positions and triangles exactly, its texture, its corners' UVs.
    let (set, back) = parse_glb_frame_set_textured(&bytes, "head").unwrap();
    assert_eq!(back.as_ref(), Some(&textures));
    let atlas = subject.topology().uv().unwrap();
    for (f, frame) in set.sequences()[0].frames().iter().enumerate() {
        assert_eq!(frame.positions(), subject.sequences()[0].frame(f));
        assert_eq!(frame.topology().triangles(), subject.topology().triangles());
        let uv = frame.topology().uv().unwrap();
        for (a, b) in uv.corners.iter().flatten().zip(atlas.corners.iter().flatten()) {
            let (p, q) = (uv.coords[*a as usize], atlas.coords[*b as usize]);
            assert!(p[0] == q[0] && (p[1] - q[1]).abs() <= 3e-8, "frame {f}: {p:?} vs {q:?}");
        }
    }

    // three.js: the frame's texture is bound at each frame; the tints show in the images.
    let seen = surfcap_testkit::three_play_textured_glb(&glb);
    assert_eq!(seen["frames"], serde_json::json!([[0, 1, 2, 0]]), "{seen}");
    assert_eq!((seen["textures"].as_u64(), seen["materials"].as_u64()), (Some(3), Some(3)), "{seen}");
    let mean = |t: &str| -> Vec<f64> {
        seen["means"][t]["mean"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
    };
    let (plain, red, blue) = (mean("0"), mean("1"), mean("2"));
    assert!(red[0] > 2.0 * red[2] && blue[2] > 2.0 * blue[0], "{seen}");
    assert!((plain[0] - red[0]).abs() < 3.0 && (plain[2] - blue[2]).abs() < 3.0, "{seen}");
    assert_eq!(seen["means"]["0"]["size"], serde_json::json!([128, 128]), "{seen}");
    assert_eq!(seen["means"]["0"]["flipY"], false, "GLTFLoader's convention: {seen}");
}

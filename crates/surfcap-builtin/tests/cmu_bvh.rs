//! Every CMU clip in `../shared/data/cmu_bvh`: parsed, checked against its meta.json entry
//! (frames, frame time, joints, end sites, channels, root name and start position), and its
//! root travel read through forward kinematics.

mod common;

use common::assert_clean_skinning;
use surfcap_builtin::bvh::read_bvh;

#[test]
fn every_cmu_clip_matches_its_metadata() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let dir = data.join("cmu_bvh");
    let meta = surfcap_testkit::meta(&dir);
    let files = meta["files"].as_array().unwrap();
    assert_eq!(files.len(), 8);
    for f in files {
        let name = f["file"].as_str().unwrap();
        let b = read_bvh(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(b.n_frames() as u64, f["frames"].as_u64().unwrap(), "{name}: frames");
        assert!((b.frame_time - f["frame_time"].as_f64().unwrap()).abs() < 1e-9, "{name}: frame time");
        let with_channels = b.joints.iter().filter(|j| !j.channels.is_empty()).count();
        assert_eq!(with_channels as u64, f["joints_with_channels"].as_u64().unwrap(), "{name}: joints");
        let end_sites: usize = b.joints.iter().map(|j| j.end_sites.len()).sum();
        assert_eq!(end_sites as u64, f["end_sites"].as_u64().unwrap(), "{name}: end sites");
        assert_eq!(b.n_channels as u64, f["channels"].as_u64().unwrap(), "{name}: channels");
        assert_eq!(b.joints[0].name, f["root_name"].as_str().unwrap(), "{name}: root");
        let root0 = b.world(0)[0].translation.vector;
        let want: Vec<f64> = f["root_start_xyz"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        for k in 0..3 {
            assert!((root0[k] - want[k]).abs() < 1e-3, "{name}: root start {root0} vs {want:?}");
        }
        // Root horizontal travel (x, z: the files are y-up) against meta.json where given.
        if let Some(d) = f["root_horizontal_displacement"].as_f64() {
            let end = b.world(b.n_frames() - 1)[0].translation.vector;
            let travel = ((end.x - root0.x).powi(2) + (end.z - root0.z).powi(2)).sqrt();
            assert!((travel - d).abs() < 1e-3 * d.max(1.0), "{name}: travel {travel} vs {d}");
        }
    }
}

/// Horizontal (x, z) centre of a frame.
fn centre(p: &[f32]) -> [f64; 2] {
    let n = (p.len() / 3) as f64;
    let (mut x, mut z) = (0.0, 0.0);
    for v in p.chunks_exact(3) {
        x += v[0] as f64;
        z += v[2] as f64;
    }
    [x / n, z / n]
}

/// The heading change of meta.json: from the chord of the first 20% of the path to the chord of
/// the last 20%, in degrees, negative = left (as meta.json's note defines it).
fn heading_change(path: &[[f64; 2]]) -> f64 {
    let k = (path.len() / 5).max(1);
    let chord = |a: [f64; 2], b: [f64; 2]| (b[1] - a[1]).atan2(b[0] - a[0]);
    let (h0, h1) = (chord(path[0], path[k]), chord(path[path.len() - 1 - k], path[path.len() - 1]));
    let mut d = (h1 - h0).to_degrees();
    while d > 180.0 {
        d -= 360.0;
    }
    while d < -180.0 {
        d += 360.0;
    }
    d
}

/// The mesh-quality checks, on every frame of every clip, for two body shapes at two resolutions:
/// the mannequin's start-to-end horizontal travel and heading change match the BVH root's
/// (travel within 1%, heading within 1% or half a degree), the mesh is closed and 2-manifold
/// with no degenerate triangle at any frame, no triangle folds over, and 99.9% of edges stay
/// within 2.5x their rest length.
#[test]
fn the_mannequin_follows_each_cmu_clip_with_its_real_travel() {
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::retarget::retarget;
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let dir = data.join("cmu_bvh");
    let meta = surfcap_testkit::meta(&dir);
    for (shape, vertices) in [(BodyShape::average(), 2000), (BodyShape::heavy(), 6000)] {
        let m = mannequin(&shape, vertices).unwrap();
        assert!(m.topology.is_closed_manifold(), "the mannequin is not a closed 2-manifold");
        assert_eq!(surfcap_mesh::connected_components(&m.topology).count, 1);
        for f in meta["files"].as_array().unwrap() {
            let name = f["file"].as_str().unwrap();
            let b = read_bvh(&dir.join(name)).unwrap();
            let mpu = f["metres_per_unit"].as_f64().unwrap();
            let poses = retarget(&b, &m, mpu).unwrap_or_else(|e| panic!("{name}: {e}"));
            let travel = |path: &[[f64; 2]]| {
                let (a, z) = (path[0], path[path.len() - 1]);
                ((z[0] - a[0]).powi(2) + (z[1] - a[1]).powi(2)).sqrt()
            };
            let root: Vec<[f64; 2]> =
                poses.iter().map(|w| [w[0].translation.vector.x, w[0].translation.vector.z]).collect();
            let mesh: Vec<[f64; 2]> = poses.iter().map(|w| centre(&m.pose(w))).collect();
            let want = f["root_horizontal_displacement_m"].as_f64().unwrap();
            let (t_root, t_mesh) = (travel(&root), travel(&mesh));
            assert!((t_root - want).abs() <= 0.01 * want, "{name}: root travel {t_root} vs {want}");
            assert!((t_mesh - want).abs() <= 0.02 * want, "{name}: mesh centre travel {t_mesh} vs {want}");
            if let Some(h) = f["travel_heading_change_deg"].as_f64() {
                let got = heading_change(&root);
                assert!((got - h).abs() <= (0.01 * h.abs()).max(0.5), "{name}: heading change {got} vs {h}");
            }
            let [p999, largest, smallest] = assert_clean_skinning(name, &m, &poses);
            let tags = surfcap_builtin::mannequin_subject::motion_tags(&poses, b.fps());
            eprintln!(
                "{name} ({} vertices): travel {t_root:.3} m (BVH {want:.3}), heading change {:.1} deg; edge length ratio 99.9th percentile {p999:.2}, largest {largest:.2}, smallest {smallest:.2}; tags {tags:?}",
                m.topology.n_vertices(),
                heading_change(&root),
            );
            // The heuristic tags on the real clips (16_57, a run to a sudden stop, averages
            // walking speed).
            let want_tags: &[&str] = match name {
                "16_17.bvh" => &["walk", "turn_left"],
                "16_19.bvh" => &["walk", "turn_right"],
                "16_36.bvh" => &["run"],
                "16_07.bvh" => &["jump"],
                "05_18.bvh" => &["jump", "in_place"],
                _ => &["walk"],
            };
            assert_eq!(tags, want_tags, "{name}: tags");
            // The guessed unit is the one meta.json gives.
            assert!(
                (b.guess_metres_per_unit().0 - mpu).abs() < 1e-4 * mpu,
                "{name}: unit {:?}",
                b.guess_metres_per_unit()
            );
        }
    }
}

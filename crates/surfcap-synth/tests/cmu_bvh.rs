//! Every CMU clip in `../shared/data/cmu_bvh`: parsed, checked against its meta.json entry
//! (frames, frame time, joints, end sites, channels, root name and start position), and its
//! root travel read through forward kinematics.

use nalgebra::Vector3;
use surfcap_synth::bvh::read_bvh;

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

/// Every undirected edge is used by exactly two triangles, once in each direction.
fn closed_two_manifold(t: &surfcap_mesh::Topology) -> bool {
    let mut directed = std::collections::HashMap::new();
    for tri in t.triangles() {
        for k in 0..3 {
            *directed.entry((tri[k], tri[(k + 1) % 3])).or_insert(0u32) += 1;
        }
    }
    directed.iter().all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
}

fn point(s: &[f32], i: u32) -> Vector3<f64> {
    let k = 3 * i as usize;
    Vector3::new(s[k] as f64, s[k + 1] as f64, s[k + 2] as f64)
}

fn normal(s: &[f32], t: &[u32; 3]) -> Vector3<f64> {
    (point(s, t[1]) - point(s, t[0])).cross(&(point(s, t[2]) - point(s, t[0])))
}

/// The checks, on every frame of every clip, for two body shapes at two resolutions:
/// the mannequin's start-to-end horizontal travel and heading change match the BVH root's
/// (travel within 1%, heading within 1% or half a degree), the mesh is closed and 2-manifold
/// with no degenerate triangle at any frame, no triangle folds over, and 99.9% of edges stay
/// within 2.5x their rest length.
#[test]
fn the_mannequin_follows_each_cmu_clip_with_its_real_travel() {
    use surfcap_synth::mannequin::{BodyShape, mannequin};
    use surfcap_synth::retarget::retarget;
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let dir = data.join("cmu_bvh");
    let meta = surfcap_testkit::meta(&dir);
    for (shape, vertices) in [(BodyShape::average(), 2000), (BodyShape::heavy(), 6000)] {
        let m = mannequin(&shape, vertices).unwrap();
        assert!(closed_two_manifold(&m.topology), "the mannequin is not a closed 2-manifold");
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
            let mut stretches = Vec::new();
            for (frame, w) in poses.iter().enumerate() {
                let posed = m.pose(w);
                let turn = m.vertex_rotations(w);
                assert_eq!(m.topology.count_degenerate_triangles(&posed, 1e-12), 0, "{name} frame {frame}");
                for t in m.topology.triangles() {
                    // A fold: the posed normal points against the rest normal turned by the
                    // skinning rotations at the triangle's corners (turning the body is no fold).
                    let rest = normal(&m.positions, t);
                    let expected: Vector3<f64> = t.iter().map(|&v| turn[v as usize] * rest).sum();
                    assert!(expected.dot(&normal(&posed, t)) > 0.0, "{name} frame {frame}: triangle {t:?} folded over");
                    for k in 0..3 {
                        let (a, b) = (t[k], t[(k + 1) % 3]);
                        stretches.push(
                            (point(&posed, a) - point(&posed, b)).norm()
                                / (point(&m.positions, a) - point(&m.positions, b)).norm(),
                        );
                    }
                }
            }
            stretches.sort_by(f64::total_cmp);
            let p999 = stretches[(stretches.len() as f64 * 0.999) as usize];
            eprintln!(
                "{name} ({} vertices): travel {t_root:.3} m (BVH {want:.3}), heading change {:.1} deg; edge length ratio 99.9th percentile {p999:.2}, largest {:.2}, smallest {:.2}",
                m.topology.n_vertices(),
                heading_change(&root),
                stretches.last().unwrap(),
                stretches[0]
            );
            assert!(p999 <= 2.5, "{name}: 99.9th percentile edge stretch {p999}");
        }
    }
}

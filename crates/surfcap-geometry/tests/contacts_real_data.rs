//! Ground contacts, the feet's contact signals and foot sliding on real motion capture: CMU
//! subject 16's straight walk (16_15, 117 frames at 30 fps) driving the built-in mannequin
//! (2000 vertices), the feet being the vertices skinned mostly to each leg's joints. Measured
//! values are printed (`--nocapture`).

use nalgebra::{Isometry3, Vector3};
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, Mannequin, mannequin};
use surfcap_builtin::mannequin_subject::Clip;
use surfcap_geometry::foot_contacts::foot_contacts;
use surfcap_geometry::foot_sliding::foot_sliding;
use surfcap_geometry::ground_contacts::{ContactParams, ground_contacts};
use surfcap_mesh::UpAxis;

/// The walk's vertex positions `[frames][vertices][3]` as captured and with the root's
/// horizontal travel stripped (an in-place clip), the mannequin, and the fps.
fn cmu_walk() -> Option<(Vec<f32>, Vec<f32>, Mannequin, f64)> {
    let data = surfcap_testkit::shared_data()?;
    let path = data.join("cmu_bvh/16_15.bvh");
    let bvh = read_bvh(&path).unwrap();
    let m = mannequin(&BodyShape::average(), 2000).unwrap();
    let clip = Clip::from_bvh(&path, &bvh, &m, bvh.guess_metres_per_unit().0).unwrap();
    let start = clip.poses[0][0].translation.vector;
    let mut travelling = Vec::new();
    let mut in_place = Vec::new();
    for w in &clip.poses {
        travelling.extend(m.pose(w));
        let t = w[0].translation.vector - start;
        let back = Vector3::new(-t.x, 0.0, -t.z);
        let stripped: Vec<Isometry3<f64>> =
            w.iter().map(|j| Isometry3::from_parts((j.translation.vector + back).into(), j.rotation)).collect();
        in_place.extend(m.pose(&stripped));
    }
    Some((travelling, in_place, m, clip.fps))
}

/// The vertices skinned mostly to the left leg's joints (lfemur, ltibia, lfoot) and the right's.
fn legs(m: &Mannequin) -> Vec<Vec<u32>> {
    let joint = |n: &str| m.skeleton.names.iter().position(|&x| x == n).unwrap() as u16;
    [["lfemur", "ltibia", "lfoot"], ["rfemur", "rtibia", "rfoot"]]
        .iter()
        .map(|names| {
            let js: Vec<u16> = names.iter().map(|n| joint(n)).collect();
            (0..m.weights.len() as u32)
                .filter(|&v| {
                    let top = m.weights[v as usize].iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
                    js.contains(&top.0)
                })
                .collect()
        })
        .collect()
}

/// Frames where a signal rises through 0.5 (the foot comes down) after having fallen below
/// 0.25 (the foot lifted) since the previous landing.
fn landings(s: &[f64]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut up = s[0] < 0.25;
    for f in 1..s.len() {
        if up && s[f - 1] < 0.5 && s[f] >= 0.5 {
            out.push(f);
            up = false;
        }
        up |= s[f] < 0.25;
    }
    out
}

#[test]
fn cmu_walk_feet_land_in_turn_and_planted_feet_slide_far_less_than_in_place_ones() {
    let Some((travelling, in_place, m, fps)) = cmu_walk() else { return };
    let nv = m.topology.n_vertices();
    let feet = legs(&m);
    assert!(feet.iter().all(|f| f.len() > 100), "leg sizes {:?}", feet.iter().map(Vec::len).collect::<Vec<_>>());
    let params = ContactParams::default();
    let c = ground_contacts(&travelling, nv, fps, UpAxis::PosY, &params);
    assert_eq!(c.frames, 117);
    // The mannequin is 1.75 m tall to the top of its head (1.61 m measured walking: the
    // capture's knees and hips never straighten fully) and stands on y = 0.
    assert!((1.5..1.8).contains(&c.subject_height), "subject height {}", c.subject_height);
    assert!(c.ground.abs() < 0.03, "ground {}", c.ground);
    let fc = foot_contacts(&c, nv, &feet).unwrap();
    let (l, r) = (&fc.feet[0], &fc.feet[1]);
    let (ll, rl) = (landings(l), landings(r));
    eprintln!("left lands at {ll:?}, right at {rl:?}");
    // About 1.1 s per stride: 3 to 4 landings of each foot in 3.9 s, interleaved.
    assert!((2..=5).contains(&ll.len()) && (2..=5).contains(&rl.len()), "landings {ll:?} / {rl:?}");
    let mut all: Vec<(usize, usize)> = ll.iter().map(|&f| (f, 0)).chain(rl.iter().map(|&f| (f, 1))).collect();
    all.sort();
    for w in all.windows(2) {
        assert_ne!(w[0].1, w[1].1, "a foot lands twice without the other landing between: {all:?}");
    }
    // Walking: some foot is down at (nearly) every frame, and both are rarely fully up.
    let down = (0..fc.frames).filter(|&f| l[f].max(r[f]) > 0.25).count();
    assert!(down as f64 > 0.9 * fc.frames as f64, "a foot down at {down} of {} frames", fc.frames);
    // Sliding: the captured walk's planted feet stay nearly still (they slide by the leg
    // length mismatch between the mannequin and the capture's skeleton); the in-place clip's
    // planted feet slide backwards at the walking speed.
    let s = foot_sliding(&travelling, nv, fps, UpAxis::PosY, &c, &params, &feet).unwrap();
    let ci = ground_contacts(&in_place, nv, fps, UpAxis::PosY, &params);
    let si = foot_sliding(&in_place, nv, fps, UpAxis::PosY, &ci, &params, &feet).unwrap();
    eprintln!(
        "sliding: travelling {:.3} m/s (feet {:?}), in place {:.3} m/s (feet {:?})",
        s.mean_speed, s.per_foot, si.mean_speed, si.per_foot
    );
    assert!(s.mean_speed < 0.25 * si.mean_speed, "travelling {} vs in place {}", s.mean_speed, si.mean_speed);
    assert!(si.mean_speed > 0.8, "in place the planted feet slide at about the walking speed: {}", si.mean_speed);
    for k in 0..2 {
        assert!(s.per_foot[k].unwrap() < 0.25 * si.per_foot[k].unwrap());
    }
}

//! Body-part proposals on real data from `../shared/data` and on the built-in mannequin
//! (thesis 5.4.2, N = 5: torso, two arms, two legs).

use std::path::PathBuf;

use surfcap_formats::import::{ImportOptions, import};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_proposal::{HUMANOID_NAMES, Method, agreement, propose};

fn subject(rel: &[&str]) -> Option<Subject> {
    let data = surfcap_testkit::shared_data()?;
    let paths: Vec<PathBuf> = rel.iter().map(|r| data.join(r)).collect();
    Some(import(&paths, &ImportOptions::default(), &NoProgress).unwrap().subject)
}

fn centroid(s: &Subject, vs: &[u32]) -> [f64; 3] {
    let p = s.frame(0).unwrap();
    let mut c = [0.0; 3];
    for &v in vs {
        for k in 0..3 {
            c[k] += p[3 * v as usize + k] as f64;
        }
    }
    c.map(|x| x / vs.len() as f64)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Frame-0 world position of the joint named `name`.
fn joint(s: &Subject, name: &str) -> [f64; 3] {
    let j = s.sequences()[0].joints.as_ref().unwrap();
    let k = j.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no joint {name}"));
    let m = &j.matrices[16 * k..16 * k + 16];
    [m[3] as f64, m[7] as f64, m[11] as f64]
}

/// Five valid parts with the humanoid names, fitting the subject.
fn check_five(s: &Subject, b: &BodyParts) {
    assert_eq!(b.names(), HUMANOID_NAMES.to_vec());
    b.validate().unwrap();
    b.check_fits(s.topology()).unwrap();
    for k in 1..5 {
        assert_eq!(b.parent(k), Some(0));
    }
}

/// Each limb's core centroid is nearer the named joint on its own side than on the other.
fn check_sides(s: &Subject, b: &BodyParts, hands: [&str; 2], feet: [&str; 2]) {
    let (labels, _) = b.display_labels();
    let core =
        |k: usize| -> Vec<u32> { (0..labels.len() as u32).filter(|&v| labels[v as usize] as usize == k).collect() };
    for (k, own, other) in
        [(1, hands[0], hands[1]), (2, hands[1], hands[0]), (3, feet[0], feet[1]), (4, feet[1], feet[0])]
    {
        let c = centroid(s, &core(k));
        let (d_own, d_other) = (dist(c, joint(s, own)), dist(c, joint(s, other)));
        assert!(d_own < d_other, "{}: {d_own} from {own}, {d_other} from {other}", b.parts[k].name);
    }
}

#[test]
fn knight_by_components_and_by_joints_gives_five_parts_on_the_right_sides() {
    let Some(s) = subject(&[
        "kaykit_adventurers/knight_Idle",
        "kaykit_adventurers/knight_Walking_A",
        "kaykit_adventurers/knight_Cheer",
    ]) else {
        return;
    };
    let (bc, rc) = propose(&s, Method::Components, 5, 2).unwrap();
    eprintln!(
        "knight: forward {:?}, hand.l {:?}, foot.l {:?}, toes.l {:?}",
        rc.forward,
        joint(&s, "hand.l"),
        joint(&s, "foot.l"),
        joint(&s, "toes.l")
    );
    check_five(&s, &bc);
    check_sides(&s, &bc, ["hand.l", "hand.r"], ["foot.l", "foot.r"]);
    // Separate meshes: no overlap, every part a whole piece.
    assert!(rc.parts.iter().skip(1).all(|p| p.overlap == 0), "{rc:?}");
    let (bj, rj) = propose(&s, Method::Auto, 5, 2).unwrap();
    assert_eq!(rj.method, Method::Joints);
    check_five(&s, &bj);
    check_sides(&s, &bj, ["hand.l", "hand.r"], ["foot.l", "foot.r"]);
    let a = agreement(&bc, &bj);
    eprintln!(
        "knight: components {:?}",
        rc.parts.iter().map(|p| (p.name.as_str(), p.core_vertices)).collect::<Vec<_>>()
    );
    eprintln!(
        "knight: joints {:?}",
        rj.parts.iter().map(|p| (p.name.as_str(), p.core_vertices, p.overlap)).collect::<Vec<_>>()
    );
    eprintln!("knight: joints vs components agreement {a:.4}, frames {}", rj.frames_used);
    assert!(a > 0.9, "knight: joints vs components agree on {a}");
    assert!(rj.parts[1].joints.iter().any(|j| j == "upperarm.l"), "{:?}", rj.parts[1].joints);
}

#[test]
fn mannequin_joints_and_rigidity_agree() {
    use surfcap_builtin::locomotion::Gait;
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
    let m = mannequin(&BodyShape::average(), 3000).unwrap();
    let clips: Vec<Clip> = [Gait::Walk, Gait::Jog, Gait::Jump]
        .into_iter()
        .map(|g| Clip::procedural(&m, g, 30.0, 2.0, 3).unwrap())
        .collect();
    let s = mannequin_subject("mannequin", &m, &clips, 30.0).unwrap();
    let (bj, rj) = propose(&s, Method::Auto, 5, 2).unwrap();
    assert_eq!(rj.method, Method::Joints);
    check_five(&s, &bj);
    check_sides(&s, &bj, ["lhand", "rhand"], ["lfoot", "rfoot"]);
    assert_eq!(rj.parts[1].joints, vec!["lhumerus", "lradius", "lhand"]);
    assert_eq!(rj.parts[3].joints, vec!["lfemur", "ltibia", "lfoot"]);
    let (br, rr) = propose(&s, Method::Rigidity, 5, 2).unwrap();
    check_five(&s, &br);
    let a = agreement(&bj, &br);
    eprintln!(
        "mannequin: joints {:?}",
        rj.parts.iter().map(|p| (p.name.as_str(), p.core_vertices, p.overlap)).collect::<Vec<_>>()
    );
    eprintln!(
        "mannequin: rigidity {:?}, rigid pieces {:?}",
        rr.parts.iter().map(|p| (p.name.as_str(), p.core_vertices, p.overlap)).collect::<Vec<_>>(),
        rr.rigid_pieces
    );
    eprintln!("mannequin: rigidity vs joints agreement {a:.4}");
    check_sides(&s, &br, ["lhand", "rhand"], ["lfoot", "rfoot"]);
    assert!(a > 0.8, "mannequin: rigidity agrees with joints on {a}");
}

#[test]
fn crane_by_rigidity_gives_five_parts_arms_above_legs() {
    let Some(s) = subject(&["vlasic2008/crane"]) else { return };
    let (b, r) = propose(&s, Method::Auto, 5, 2).unwrap();
    assert_eq!(r.method, Method::Rigidity);
    check_five(&s, &b);
    let (labels, _) = b.display_labels();
    let core =
        |k: usize| -> Vec<u32> { (0..labels.len() as u32).filter(|&v| labels[v as usize] as usize == k).collect() };
    let c: Vec<[f64; 3]> = (0..5).map(|k| centroid(&s, &core(k))).collect();
    let (up, sign) = s.up_axis.axis_and_sign();
    let h = |k: usize| sign * c[k][up];
    eprintln!(
        "crane: {:?}, rigid pieces {:?}, forward {:?}",
        r.parts.iter().map(|p| (p.name.as_str(), p.core_vertices, p.overlap)).collect::<Vec<_>>(),
        r.rigid_pieces,
        r.forward
    );
    eprintln!("crane: centroids {c:?}");
    assert!(h(1).min(h(2)) > h(3).max(h(4)), "arms above legs: {c:?}");
    for k in 1..5 {
        assert!(r.parts[k].core_vertices > 300, "{:?}", r.parts[k]);
        assert!(r.parts[k].overlap > 0, "{:?}", r.parts[k]);
    }
    // Left arm and left leg on the same side.
    let side: Vec<f64> = (0..3).map(|k| c[1][k] - c[2][k]).collect();
    let legs: f64 = (0..3).map(|k| (c[3][k] - c[4][k]) * side[k]).sum();
    assert!(legs > 0.0, "left leg on the left arm's side: {c:?}");
}

#[test]
fn knight_idle_alone_joints_agree_with_its_separate_meshes() {
    let Some(s) = subject(&["kaykit_adventurers/knight_Idle"]) else { return };
    let (bc, _) = propose(&s, Method::Components, 5, 2).unwrap();
    let (bj, rj) = propose(&s, Method::Joints, 5, 2).unwrap();
    let a = agreement(&bc, &bj);
    eprintln!("knight_Idle: joints vs components agreement {a:.4} over {} frames", rj.frames_used);
    check_sides(&s, &bj, ["hand.l", "hand.r"], ["foot.l", "foot.r"]);
    assert!(a > 0.93, "knight_Idle: joints vs components agree on {a}");
}

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

/// The procedural mannequin (walk, jog, jump), whose rig names its sides `l`/`r` (CMU style).
fn mannequin_subject_walking() -> Subject {
    use surfcap_builtin::locomotion::Gait;
    use surfcap_builtin::mannequin::{BodyShape, mannequin};
    use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
    let m = mannequin(&BodyShape::average(), 3000).unwrap();
    let clips: Vec<Clip> = [Gait::Walk, Gait::Jog, Gait::Jump]
        .into_iter()
        .map(|g| Clip::procedural(&m, g, 30.0, 2.0, 3).unwrap())
        .collect();
    mannequin_subject("mannequin", &m, &clips, 30.0).unwrap()
}

/// The subject with its joint tracks changed by `f` (names or parents dropped).
fn with_rig(s: &Subject, f: impl Fn(&mut surfcap_mesh::JointTrack)) -> Subject {
    let seqs: Vec<surfcap_mesh::Sequence> = s
        .sequences()
        .iter()
        .map(|q| {
            let mut q = q.clone();
            if let Some(j) = q.joints.as_mut() {
                f(j);
            }
            q
        })
        .collect();
    Subject::new(s.name.clone(), s.topology().clone(), seqs, s.fps, s.up_axis, s.units.clone()).unwrap()
}

/// Each arm's core holds the rig's shoulder-to-hand joints of its own side (named by the rig:
/// `upper` and `hand` for the left, `upper_r`/`hand_r` for the right), and reaches from the
/// shoulder joint to the hand joint: a core vertex within 8% of the height of each.
fn check_arms(
    s: &Subject,
    b: &BodyParts,
    r: &surfcap_transfer::body_parts_proposal::ProposalReport,
    joints: [[&str; 2]; 2],
) {
    let (labels, _) = b.display_labels();
    let p0 = s.frame(0).unwrap();
    let (lo, hi) = surfcap_mesh::bounding_box(p0);
    let k = s.up_axis.axis_and_sign().0;
    let height = (hi[k] - lo[k]) as f64;
    for (part, [upper, hand]) in [(1usize, joints[0]), (2, joints[1])] {
        let name = &b.parts[part].name;
        assert!(r.parts[part].joints.iter().any(|j| j == upper), "{}: {name} has {:?}", s.name, r.parts[part].joints);
        assert!(r.parts[part].joints.iter().any(|j| j == hand), "{}: {name} has {:?}", s.name, r.parts[part].joints);
        for j in [upper, hand] {
            let at = joint(s, j);
            let nearest = (0..labels.len())
                .filter(|&v| labels[v] as usize == part)
                .map(|v| dist(at, [p0[3 * v] as f64, p0[3 * v + 1] as f64, p0[3 * v + 2] as f64]))
                .fold(f64::INFINITY, f64::min);
            assert!(nearest < 0.08 * height, "{}: {name} is {nearest} from {j} (height {height})", s.name);
        }
    }
}

#[test]
fn every_kaykit_character_and_the_mannequin_get_arms_from_shoulder_to_hand_on_the_rigs_sides() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    // One walk each: on the knight's Walking_A alone the facing cue alone picks the wrong side.
    for c in ["knight", "barbarian", "mage", "rogue"] {
        let path = data.join("kaykit_adventurers").join(format!("{c}_Walking_A"));
        let s = import(&[path], &ImportOptions::default(), &NoProgress).unwrap().subject;
        let (b, r) = propose(&s, Method::Auto, 5, 2).unwrap();
        assert_eq!(r.method, Method::Joints, "{c}");
        assert_eq!(r.sides_from, "joint names", "{c}");
        check_five(&s, &b);
        check_arms(&s, &b, &r, [["upperarm.l", "hand.l"], ["upperarm.r", "hand.r"]]);
        check_sides(&s, &b, ["hand.l", "hand.r"], ["foot.l", "foot.r"]);
        // No joint of the other side in a limb.
        for (k, other) in [(1, ".r"), (2, ".l"), (3, ".r"), (4, ".l")] {
            assert!(r.parts[k].joints.iter().all(|j| !j.ends_with(other)), "{c}: {:?}", r.parts[k]);
        }
    }
    let s = mannequin_subject_walking();
    let (b, r) = propose(&s, Method::Auto, 5, 2).unwrap();
    assert_eq!(r.sides_from, "joint names");
    check_arms(&s, &b, &r, [["lhumerus", "lhand"], ["rhumerus", "rhand"]]);
}

#[test]
fn without_side_names_left_is_the_mannequins_own_left_by_its_facing() {
    let s = mannequin_subject_walking();
    // The rig's hierarchy kept, its names replaced by numbers.
    let unnamed = with_rig(&s, |j| j.names = (0..j.names.len()).map(|k| format!("joint_{k}")).collect());
    let (b, r) = propose(&unnamed, Method::Auto, 5, 2).unwrap();
    assert_eq!(r.method, Method::Joints);
    assert_eq!(r.sides_from, "facing");
    check_five(&unnamed, &b);
    // The original subject's names say where its left hand and foot are.
    check_sides(&s, &b, ["lhand", "rhand"], ["lfoot", "rfoot"]);
}

#[test]
fn joints_without_their_hierarchy_fall_back_to_rigidity_naming_the_subject() {
    let s = mannequin_subject_walking();
    let flat = with_rig(&s, |j| {
        j.parents = vec![None; j.names.len()];
        j.names = (0..j.names.len()).map(|k| format!("joint_{k}")).collect();
    });
    let e = propose(&flat, Method::Joints, 5, 2).unwrap_err().to_string();
    assert!(e.contains("subject \"mannequin\": found 0 limb candidates by joints"), "{e}");
    let (b, r) = propose(&flat, Method::Auto, 5, 2).unwrap();
    assert_eq!(r.method, Method::Rigidity);
    assert_eq!(r.notes.len(), 1, "{:?}", r.notes);
    assert!(r.notes[0].contains("subject \"mannequin\": found 0 limb candidates by joints"), "{:?}", r.notes);
    assert!(r.notes[0].contains("fell back to the rigidity of the motion"), "{:?}", r.notes);
    check_five(&flat, &b);
    check_sides(&s, &b, ["lhand", "rhand"], ["lfoot", "rfoot"]);
}

//! Parametric blending in the interactive controller, on the procedural mannequin: which clips
//! pair up, the blended centre track is Algorithm 2's rigid part at a constant weight, and a
//! straight walk blended with a turning walk turns in between.

mod common;

use common::prepared;
use surfcap_builtin::locomotion::Gait as Procedural;
use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_motion::blend::{Lambda, blend_placements_from};
use surfcap_synthesis::controller::parametric_blend::{
    BlendContext, BlendState, WEIGHT_PER_SECOND, frame_angle, weight_towards,
};
use surfcap_synthesis::controller::{Controller, ControllerOptions};

fn options(parametric: bool) -> ControllerOptions {
    ControllerOptions { parametric, ..Default::default() }
}

#[test]
fn walks_pair_with_turns_but_never_with_a_stand() {
    let prep = prepared(&[Procedural::Walk, Procedural::Jog, Procedural::TurnLeft, Procedural::Idle]);
    let c = Controller::new(&prep, options(true)).unwrap();
    let s = prep.subject();
    let pairs = c.partners().pairs(s);
    let names: Vec<String> = s.sequences().iter().map(|q| q.name.clone()).collect();
    assert!(!pairs.is_empty(), "no pair qualifies: {:?}", c.partners().none_because);
    assert!(pairs.iter().all(|(a, b, _)| a != &names[3] && b != &names[3]), "a stand paired: {pairs:?}");
    // The walk pairs with the turning walk; the jog's poses are too far from the walk's here.
    assert!(pairs.iter().any(|(a, b, _)| a == &names[0] && b == &names[2]), "walk and turn: {pairs:?}");
    // Off: no partners at all.
    let off = Controller::new(&prep, options(false)).unwrap();
    assert_eq!(off.partners().frames_with_partners(), 0);
    // The weight ramps at its rate and lands on the target.
    let fps = 30.0;
    assert!((weight_towards(0.0, 1.0, fps) - WEIGHT_PER_SECOND / fps).abs() < 1e-12);
    assert_eq!(weight_towards(0.9, 1.0, fps), 1.0);
    assert_eq!(weight_towards(0.05, 0.0, fps), 0.0);
}

#[test]
fn a_constant_weight_blend_follows_algorithm_2s_rigid_part() {
    let prep = prepared(&[Procedural::Walk, Procedural::TurnLeft]);
    let c = Controller::new(&prep, options(true)).unwrap();
    let s = prep.subject();
    let d = prep.pipe.chain_distances().unwrap().value;
    let angle = |a: u32, b: u32| frame_angle(s, a, b);
    let (index, model) = (c.index().clone(), prep.model.clone());
    let cx = BlendContext { model: &model, index: &index, d: &d.values, angle: &angle };
    let partners = c.partners();
    let (iu, iv, iw) = plane_axes(s.up_axis);
    let mut compared = 0;
    for a in 0..s.n_frames() as u32 {
        for k in partners.of(a) {
            let b = partners.partner[k];
            for w in [0.3, 0.7] {
                // The blend at a constant weight while its warp is one-to-one (no wrap).
                let mut states = vec![BlendState::begin(&cx, a, b, w)];
                while states.len() < 20 {
                    let last = states[states.len() - 1];
                    match last.advance(&cx, w) {
                        Some(n) if n.a == last.a + 1 && n.b == last.b + 1 => states.push(n),
                        _ => break,
                    }
                }
                if states.len() < 8 {
                    continue;
                }
                let l = states.len();
                let cs = &model.centres[a as usize..a as usize + l];
                let cd = &model.centres[b as usize..b as usize + l];
                let path: Vec<(usize, usize)> = (0..l).map(|t| (t, t)).collect();
                let steps = blend_placements_from(s.up_axis, cs, cd, &path, Lambda::Constant(w), |n, m| {
                    frame_angle(s, a + n as u32, b + m as u32)
                });
                for (st, bs) in states.iter().zip(&steps) {
                    for axis in [iu, iv, iw] {
                        assert!(
                            (st.p[axis] - bs.centre[axis]).abs() < 1e-9,
                            "{a}+{b} at {w}: {:?} against {:?}",
                            st.p,
                            bs.centre
                        );
                    }
                    assert!((st.gs.theta - bs.src.theta).abs() < 1e-9 && (st.gd.theta - bs.dst.theta).abs() < 1e-9);
                }
                compared += 1;
            }
        }
    }
    assert!(compared >= 10, "only {compared} one-to-one blends compared");
}

/// Blending a straight walk with a turning walk at half weight turns between the two: over
/// a second, the blended body's change of facing lies between the walk's (weight 0) and the
/// turn's (weight 1), for the pairs whose chains play a second.
#[test]
fn a_walk_blended_with_a_turn_turns_in_between() {
    let prep = prepared(&[Procedural::Walk, Procedural::TurnLeft]);
    let c = Controller::new(&prep, options(true)).unwrap();
    let s = prep.subject();
    let d = prep.pipe.chain_distances().unwrap().value;
    let angle = |a: u32, b: u32| frame_angle(s, a, b);
    let (index, model, motion) = (c.index().clone(), prep.model.clone(), c.motion().clone());
    let cx = BlendContext { model: &model, index: &index, d: &d.values, angle: &angle };
    let partners = c.partners();
    let walk = s.frame_index().range(0);
    let turned = |a: u32, b: u32, w: f64| -> Option<f64> {
        let first = BlendState::begin(&cx, a, b, w);
        let mut st = first;
        for _ in 0..30 {
            st = st.advance(&cx, w)?;
        }
        Some(surfcap_motion::blend::wrap_angle(st.facing(&motion) - first.facing(&motion)))
    };
    let (mut compared, mut between) = (0, 0);
    for a in walk.map(|a| a as u32) {
        for k in partners.of(a) {
            let b = partners.partner[k];
            let (Some(t0), Some(th), Some(t1)) = (turned(a, b, 0.0), turned(a, b, 0.5), turned(a, b, 1.0)) else {
                continue;
            };
            if (t1 - t0).abs() < 5f64.to_radians() {
                continue;
            }
            compared += 1;
            if (th - t0) * (t1 - t0) > 0.0 && (th - t1) * (t0 - t1) > 0.0 {
                between += 1;
            }
        }
    }
    assert!(compared >= 5, "only {compared} pairs turn apart");
    assert!(between * 10 >= compared * 8, "{between} of {compared} half-weight blends turn in between");
}

//! Parametric blending in the interactive controller, on the procedural mannequin: which clips
//! pair up, the blended centre track is Algorithm 2's rigid part at a constant weight, and a
//! blend reaches speeds between a walk's and a jog's that the clips alone do not.

use std::sync::Arc;

use surfcap_builtin::locomotion::Gait as Procedural;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_mesh::{NoProgress, Subject};
use surfcap_motion::blend::{Lambda, blend_placements_from};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};
use surfcap_synthesis::Prepared;
use surfcap_synthesis::controller::parametric_blend::{
    BlendContext, BlendState, WEIGHT_PER_SECOND, frame_angle, weight_towards,
};
use surfcap_synthesis::controller::{Controller, ControllerOptions, Gait, Input, ShownFrame};

/// The mannequin (1,000 vertices) in 2 s clips at 30 fps of the given gaits.
fn prepared(gaits: &[Procedural]) -> Prepared {
    let m = mannequin(&BodyShape::average(), 1000).unwrap();
    let clips: Vec<Clip> =
        gaits.iter().enumerate().map(|(k, &g)| Clip::procedural(&m, g, 30.0, 2.0, k as u64).unwrap()).collect();
    let s: Subject = mannequin_subject("walker", &m, &clips, 30.0).unwrap();
    let (l_min, l_max) = surfcap_motion::segment_bounds(s.fps);
    let params = GraphParams {
        table: TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).unwrap(),
    };
    let pipe = Arc::new(Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress)));
    Prepared::new(pipe, params, None).unwrap()
}

fn options(parametric: bool) -> ControllerOptions {
    ControllerOptions { parametric, ..Default::default() }
}

#[test]
fn walks_pair_with_jogs_and_turns_but_never_with_a_stand() {
    let prep = prepared(&[Procedural::Walk, Procedural::Jog, Procedural::TurnLeft, Procedural::Idle]);
    let c = Controller::new(&prep, options(true)).unwrap();
    let s = prep.subject();
    let pairs = c.partners().pairs(s);
    let names: Vec<String> = s.sequences().iter().map(|q| q.name.clone()).collect();
    assert!(!pairs.is_empty(), "no pair qualifies: {:?}", c.partners().none_because);
    assert!(pairs.iter().all(|(a, b, _)| a != &names[3] && b != &names[3]), "a stand paired: {pairs:?}");
    assert!(pairs.iter().any(|(a, b, _)| a == &names[0] && b == &names[1]), "walk and jog: {pairs:?}");
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

/// Mean absolute ground speed error against `asked` over output frames `from..`, the speed by
/// central difference over a quarter of a second either side.
fn speed_error(frames: &[ShownFrame], from: usize, asked: f64) -> f64 {
    let half = 8;
    let n = frames.len() - half;
    let errs: Vec<f64> = (from..n)
        .map(|k| {
            let (a, b) = (&frames[k - half].centre, &frames[k + half].centre);
            let v = (b[0] - a[0]).hypot(b[2] - a[2]) * 30.0 / (2 * half) as f64;
            (v - asked).abs()
        })
        .collect();
    errs.iter().sum::<f64>() / errs.len() as f64
}

#[test]
fn a_walk_blended_with_a_jog_reaches_the_speeds_between() {
    let prep = prepared(&[Procedural::Walk, Procedural::Jog]);
    let run = |parametric: bool, asked: f64| {
        let mut c = Controller::new(&prep, options(parametric)).unwrap();
        let mut frames = Vec::new();
        for _ in 0..(8.0 * 60.0) as usize {
            frames.extend(c.step(&Input::velocity([asked, 0.0]), 1.0 / 60.0).unwrap().frames);
        }
        (speed_error(&frames, 90, asked), c.blended(), frames.len())
    };
    let probe = Controller::new(&prep, options(false)).unwrap();
    let (walk, jog) = (probe.motion().typical_speed(Gait::Walk).unwrap(), probe.motion().typical_speed(Gait::Run));
    let jog = jog.unwrap_or_else(|| probe.motion().fastest());
    assert!(jog > 1.3 * walk, "walk {walk} m/s, jog {jog} m/s");
    let asked = 0.5 * (walk + jog);
    let (with, blended, n) = run(true, asked);
    let (without, none, _) = run(false, asked);
    assert_eq!(none, 0);
    assert!(blended > n / 3, "{blended} of {n} frames blended");
    assert!(
        with < 0.6 * without,
        "asked {asked:.2} m/s (walk {walk:.2}, jog {jog:.2}): speed error {with:.3} m/s blended, {without:.3} m/s not"
    );
}

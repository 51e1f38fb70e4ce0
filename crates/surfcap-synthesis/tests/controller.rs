//! The interactive controller on the procedural mannequin (walk, jog, turns, idle): it goes
//! where it is asked, turns, stops, decides at least every 0.1 s while no transition plays,
//! never shows a frame the walk cannot go on from, plays transitions with the Blend offline
//! synthesis uses, says what the data cannot follow, and decides the same whatever the thread
//! count.

mod common;

use common::prepared;
use surfcap_builtin::locomotion::Gait as Procedural;
use surfcap_synthesis::Prepared;
use surfcap_synthesis::controller::{Controller, ControllerOptions, Gait, Input, Move, ShownFrame};

fn all_gaits() -> Prepared {
    prepared(&[Procedural::Walk, Procedural::Jog, Procedural::TurnLeft, Procedural::TurnRight, Procedural::Idle])
}

/// Plays `script` (seconds, input) at 60 Hz; returns every frame shown and every decision.
fn play(
    c: &mut Controller,
    script: &[(f64, Input)],
) -> (Vec<ShownFrame>, Vec<surfcap_synthesis::controller::Decision>) {
    let (mut frames, mut decisions) = (Vec::new(), Vec::new());
    for (seconds, input) in script {
        for _ in 0..(seconds * 60.0).round() as usize {
            let out = c.step(input, 1.0 / 60.0).unwrap();
            frames.extend(out.frames);
            decisions.extend(out.decisions);
        }
    }
    (frames, decisions)
}

/// Ground displacement (x, z) between output frames `a` and `b`.
fn moved(frames: &[ShownFrame], a: usize, b: usize) -> [f64; 2] {
    [frames[b].centre[0] - frames[a].centre[0], frames[b].centre[2] - frames[a].centre[2]]
}

#[test]
fn goes_where_asked_turns_stops_and_never_enters_a_dead_end() {
    let prep = all_gaits();
    let mut c = Controller::new(&prep, ControllerOptions::default()).unwrap();
    let walk = c.motion().typical_speed(Gait::Walk).unwrap();
    assert!(walk > 0.5 && walk < 2.5, "walking speed {walk} m/s");
    // Along +x, then along +z (a quarter turn), then stop: 4 s each.
    let script = [(4.0, Input::velocity([walk, 0.0])), (4.0, Input::velocity([0.0, walk])), (4.0, Input::stop())];
    let (frames, decisions) = play(&mut c, &script);
    assert_eq!(frames.len(), c.shown());
    assert!((frames.len() as i64 - 361).abs() <= 1, "{} frames in 12 s at 30 fps", frames.len());
    // Each phase's last 2 s (frames 60-120, 180-240, 300-360).
    let x = moved(&frames, 60, 120);
    assert!(x[0] > 0.5 * walk * 2.0 && x[1].abs() < 0.5 * x[0], "walking along +x moved {x:?}");
    let z = moved(&frames, 180, 240);
    assert!(z[1] > 0.5 * walk * 2.0 && z[0].abs() < 0.5 * z[1], "walking along +z moved {z:?}");
    let stop = moved(&frames, 300, 360);
    assert!(stop[0].hypot(stop[1]) < 0.2 * walk * 2.0, "standing moved {stop:?}");
    // Every frame shown is one the walk can go on from.
    let live = &c.index().live;
    assert!(frames.iter().filter_map(|f| f.frame).all(|f| live[f as usize]));
    // Decisions at least every 0.1 s (3 frames at 30 fps), except while a transition plays.
    for w in decisions.windows(2) {
        let gap = w[1].time - w[0].time;
        match w[0].chosen {
            Move::Continue => assert!(gap <= 0.1 + 1e-9, "{gap} s after a decision at {}", w[0].time),
            Move::Transition { after, from, to, .. } => {
                let t = prep.model.walk_duration(&[from, to]).unwrap() + after;
                assert!(gap <= (t as f64 + 3.0) / 30.0 + 1e-9, "{gap} s after a transition of {t} frames");
            }
        }
    }
    assert!(decisions.iter().any(|d| matches!(d.chosen, Move::Transition { .. })), "no transition taken");
    assert!(decisions.iter().all(|d| d.candidates >= 1 && d.cost.is_finite()));
    let (n, cost) = c.transitions();
    assert!(n >= 1 && cost > 0.0);
}

#[test]
fn meshes_are_the_blended_walk_and_their_centres_the_predicted_ones() {
    let prep = all_gaits();
    let mut c = Controller::new(&prep, ControllerOptions { meshes: true, ..Default::default() }).unwrap();
    let walk = c.motion().typical_speed(Gait::Walk).unwrap();
    let script = [(2.0, Input::velocity([walk, 0.0])), (3.0, Input::velocity([-walk, 0.0]))];
    let (frames, _) = play(&mut c, &script);
    let nv = prep.subject().topology().n_vertices();
    let mut blended = 0;
    for (k, f) in frames.iter().enumerate() {
        let p = f.positions.as_ref().expect("meshes asked");
        assert_eq!(p.len(), 3 * nv);
        let centre = surfcap_motion::blend::centre(p);
        let e = (0..3).map(|a| (centre[a] - f.centre[a]).abs()).fold(0.0, f64::max);
        assert!(e < 1e-3, "frame {k}: centre {centre:?}, predicted {:?}", f.centre);
        let mix = f.mix.expect("meshes give every frame's mix");
        if f.frame.is_none() {
            blended += 1;
            assert!(mix.from != mix.to && mix.weight > 0.0 && mix.weight < 1.0, "{mix:?}");
        }
    }
    assert!(blended > 0, "turning back blends a transition");
}

#[test]
fn inputs_the_data_cannot_follow_are_named() {
    let prep = prepared(&[Procedural::Walk]);
    let mut c = Controller::new(&prep, ControllerOptions::default()).unwrap();
    let run = c.step(&Input::velocity([1.0, 0.0]).with_gait(Gait::Run), 0.1).unwrap();
    assert!(run.cannot_follow.iter().any(|n| n.starts_with("no run clip")), "{:?}", run.cannot_follow);
    // The same input again says nothing new.
    assert!(c.step(&Input::velocity([1.0, 0.0]).with_gait(Gait::Run), 0.1).unwrap().cannot_follow.is_empty());
    let fast = c.step(&Input::velocity([20.0, 0.0]), 0.1).unwrap();
    assert!(
        fast.cannot_follow.iter().any(|n| n.starts_with("asked 20.00 m/s") && n.contains("fastest")),
        "{:?}",
        fast.cannot_follow
    );
    let stop = c.step(&Input::stop(), 0.1).unwrap();
    assert!(stop.cannot_follow.iter().any(|n| n.starts_with("cannot stop")), "{:?}", stop.cannot_follow);
    let bad = c.step(&Input::velocity([f64::NAN, 0.0]), 0.1).unwrap_err().to_string();
    assert!(bad.contains("expected finite numbers"), "{bad}");
    assert!(c.step(&Input::stop(), -1.0).unwrap_err().to_string().contains("non-negative"));
    let opts = ControllerOptions { start: Some(10_000), ..Default::default() };
    let e = Controller::new(&prep, opts).err().expect("start past the frames").to_string();
    assert!(e.contains("start frame 10000"), "{e}");
}

#[test]
fn the_same_inputs_give_the_same_frames_whatever_the_thread_count() {
    let prep = all_gaits();
    let script = [
        (2.0, Input::velocity([1.0, 0.0])),
        (2.0, Input::target([0.0, 3.0])),
        (1.0, Input::velocity([0.0, -2.5]).with_gait(Gait::Run)),
    ];
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut c = Controller::new(&prep, ControllerOptions::default()).unwrap();
            let (frames, decisions) = play(&mut c, &script);
            (frames, decisions.iter().map(|d| (d.frame, d.chosen)).collect::<Vec<_>>())
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
}

/// The live session the play page talks to, without a page: steps return the frames due and
/// the transitions chosen, each chosen transition's blend comes back as a stream of the frames
/// the controller plays (the same whole or piece by piece), and a restart starts again.
#[test]
fn a_live_session_steps_blends_its_transitions_and_restarts() {
    use surfcap_formats::stream::StreamFile;
    use surfcap_synthesis::controller::live_session::{LiveAsk, LiveSession};

    let e = LiveSession::start(all_gaits(), 20).err().expect("20 bits refused").to_string();
    assert!(e.contains("20 bits per coordinate: expected 8 to 16"), "{e}");
    let session = LiveSession::start(all_gaits(), 16).unwrap();
    let info = session.info();
    assert_eq!(info["subject"], "walker");
    assert_eq!(info["frames"].as_u64().unwrap() as usize, session.prepared().subject().n_frames());
    let stream = session.captured_stream();
    let captured = StreamFile::parse(&stream).unwrap();
    let n = session.prepared().subject().topology().n_vertices();
    assert_eq!(captured.decode().unwrap().len(), session.prepared().subject().n_frames() * n * 3);

    // Walk along +x, then along +z: 3 s each at the page's 60 steps a second.
    let (mut frames, mut blends) = (0, Vec::new());
    for k in 0..360 {
        let direction = if k < 180 { [1.0, 0.0] } else { [0.0, 1.0] };
        let out = session.step(&LiveAsk { direction, run: false, dt: 1.0 / 60.0 }).unwrap();
        frames += out["frames"].as_array().unwrap().len();
        for b in out["blends"].as_array().unwrap() {
            blends.push(b["id"].as_u64().unwrap());
        }
        for f in out["frames"].as_array().unwrap() {
            assert!(f["frame"].is_u64() || f["blend"].is_u64(), "{f}");
            assert!(f["theta"].is_f64() && f["t"].is_array(), "{f}");
        }
    }
    assert!((frames as i64 - 180).abs() <= 1, "{frames} frames in 6 s at 30 fps");
    assert!(!blends.is_empty(), "turning a quarter chose no transition");
    for &id in &blends {
        let whole = session.blend(id).unwrap();
        let whole = StreamFile::parse(&whole).unwrap().decode().unwrap();
        assert!(!whole.is_empty() && whole.len().is_multiple_of(n * 3));
        let (piece, total) = session.blend_from(id, 1).unwrap();
        assert_eq!(total, whole.len() / (n * 3), "blend {id}'s frame count");
        // Each stream is quantised on its own bounds (16 bits): equal within a step of them.
        let piece = StreamFile::parse(&piece).unwrap().decode().unwrap();
        assert_eq!(piece.len(), whole.len() - n * 3, "blend {id} from frame 1");
        let off = piece.iter().zip(&whole[n * 3..]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(off < 1e-3, "blend {id} from frame 1 is {off} off the whole blend's frames");
    }
    let made = session.info()["blends_made"]["count"].as_u64().unwrap();
    assert_eq!(made as usize, blends.iter().collect::<std::collections::BTreeSet<_>>().len());
    assert!(session.blend(10_000).unwrap_err().contains("no blend 10000"));

    // A restart plays the start frame again.
    session.restart().unwrap();
    let out = session.step(&LiveAsk { direction: [0.0, 0.0], run: false, dt: 1.0 / 60.0 }).unwrap();
    let start = &info["start"]["frame"];
    let first = out["frames"].as_array().unwrap().first().map(|f| f["frame"].clone());
    assert!(first.is_none() || first.as_ref() == Some(start), "{first:?} after a restart, start {start}");
}

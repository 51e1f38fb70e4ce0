//! Contact-guided time alignment (thesis 6.4, 6.8) on a real character: KayKit's knight,
//! `knight_Walking_A` (33 frames, one cycle) against a known re-timing of itself and against
//! `knight_Running_A` (25 frames), the feet being the two leg meshes (the lowest connected
//! components). Measured values are printed (`--nocapture`).

use surfcap_formats::import::{ImportOptions, import};
use surfcap_geometry::foot_contacts::{FootContacts, foot_contacts};
use surfcap_geometry::ground_contacts::{ContactParams, ground_contacts};
use surfcap_mesh::{NoProgress, Subject, connected_components};
use surfcap_motion::sequence_time_alignment::{TimeAlignmentParams, align_sequences, resample_poses};

fn knight() -> Option<Subject> {
    let data = surfcap_testkit::shared_data()?;
    let paths = ["knight_Walking_A", "knight_Running_A"].map(|c| data.join("kaykit_adventurers").join(c));
    Some(import(&paths, &ImportOptions::default(), &NoProgress).unwrap().subject)
}

/// The two components whose lowest vertex in the first frame is lowest (the legs).
fn legs(s: &Subject) -> Vec<Vec<u32>> {
    let c = connected_components(s.topology());
    let (w, sign) = s.up_axis.axis_and_sign();
    let p = s.frame(0).unwrap();
    let mut lowest = vec![f64::MAX; c.count];
    for (v, &l) in c.labels.iter().enumerate() {
        lowest[l as usize] = lowest[l as usize].min(sign * p[3 * v + w] as f64);
    }
    let mut order: Vec<usize> = (0..c.count).filter(|&k| c.sizes()[k] > 20).collect();
    order.sort_by(|&a, &b| lowest[a].total_cmp(&lowest[b]));
    order[..2]
        .iter()
        .map(|&k| (0..c.labels.len() as u32).filter(|&v| c.labels[v as usize] == k as u32).collect())
        .collect()
}

fn slices(f: &[Vec<f32>]) -> Vec<&[f32]> {
    f.iter().map(Vec::as_slice).collect()
}

fn contacts(s: &Subject, frames: &[Vec<f32>], feet: &[Vec<u32>]) -> FootContacts {
    let nv = s.topology().n_vertices();
    let flat: Vec<f32> = frames.concat();
    let c = ground_contacts(&flat, nv, s.fps, s.up_axis, &ContactParams::default());
    foot_contacts(&c, nv, feet).unwrap()
}

#[test]
fn knight_walk_retimed_is_recovered_and_walk_to_run_follows_the_contacts() {
    let Some(s) = knight() else { return };
    let walk: Vec<Vec<f32>> = (0..s.sequences()[0].n_frames()).map(|f| s.sequences()[0].frame(f).to_vec()).collect();
    let run: Vec<Vec<f32>> = (0..s.sequences()[1].n_frames()).map(|f| s.sequences()[1].frame(f).to_vec()).collect();
    assert_eq!((walk.len(), run.len()), (33, 25));
    let feet = legs(&s);
    let cw = contacts(&s, &walk, &feet);
    // The walk plants each foot in turn: each is down (> 0.5) at some frames, never both fully.
    for k in 0..2 {
        assert!(cw.feet[k].iter().filter(|&&x| x > 0.5).count() >= 5, "foot {k}: {:?}", cw.feet[k]);
    }
    let both = (0..33).filter(|&f| cw.feet[0][f] > 0.9 && cw.feet[1][f] > 0.9).count();
    assert!(both <= 8, "both feet fully down at {both} of 33 frames");

    // A known re-timing: 45 frames, slow then fast, s(j) = 32 (j / 44)^1.3.
    let g = |j: f64| 32.0 * (j / 44.0).powf(1.3);
    let g_inv = |i: f64| 44.0 * (i / 32.0).powf(1.0 / 1.3);
    let times: Vec<f64> = (0..45).map(|j| g(j as f64)).collect();
    let retimed = resample_poses(&slices(&walk), &times).unwrap();
    let cr = contacts(&s, &retimed, &feet);
    let a = align_sequences(
        &slices(&walk),
        &slices(&retimed),
        Some((&cw.by_frame(), &cr.by_frame())),
        &TimeAlignmentParams::default(),
    )
    .unwrap();
    let t = a.time_map.times();
    let worst = (0..33).map(|i| (t[i] - g_inv(i as f64)).abs()).fold(0.0, f64::max);
    eprintln!("re-timed walk: worst time error {worst:.2} frames, cost {:.3}", a.cost);
    assert!(worst <= 1.0, "times {t:?}");
    let inv = a.time_map.inverse();
    let worst_inv = (0..45).map(|j| (inv.times()[j] - g(j as f64)).abs()).fold(0.0, f64::max);
    assert!(worst_inv <= 1.0, "inverse times {:?}", inv.times());

    // Walk (reference) to run: monotone, pinned, and the contacts line up better when they
    // guide the warp than when only the poses do.
    let crun = contacts(&s, &run, &feet);
    let (rw, rr) = (cw.by_frame(), crun.by_frame());
    let mismatch = |path: &[(usize, usize)]| -> f64 {
        path.iter().map(|&(i, j)| (0..2).map(|k| (rw[i][k] - rr[j][k]).abs()).sum::<f64>() / 2.0).sum::<f64>()
            / path.len() as f64
    };
    let guided =
        align_sequences(&slices(&walk), &slices(&run), Some((&rw, &rr)), &TimeAlignmentParams::default()).unwrap();
    let poses_only = align_sequences(&slices(&walk), &slices(&run), None, &TimeAlignmentParams::default()).unwrap();
    let t = guided.time_map.times();
    assert_eq!((t.len(), t[0], t[32]), (33, 0.0, 24.0));
    assert!(t.windows(2).all(|w| w[1] >= w[0]), "{t:?}");
    let (mg, mp) = (mismatch(&guided.path), mismatch(&poses_only.path));
    eprintln!("walk -> run: contact mismatch along the path {mg:.3} guided, {mp:.3} poses only; times {t:?}");
    assert!(mg <= mp, "guided {mg} vs poses only {mp}");
}

//! Eq. 2-5 on real captures: the Vlasic crane (10,002 vertices, loose clothing) and cyclic
//! animations.

use surfcap_formats::import::{ImportOptions, import};
use surfcap_mesh::{Subject, UpAxis};
use surfcap_smg::shape_similarity::{FrameMesh, HistogramParams, frame_histograms, shape_similarity_matrix};
use surfcap_smg::temporal_shape_similarity::optimal_transition;

fn load(path: std::path::PathBuf) -> Subject {
    import(&[path], &ImportOptions::default(), &surfcap_mesh::NoProgress).unwrap().subject
}

fn frames(s: &Subject) -> Vec<FrameMesh<'_>> {
    let t = s.topology().triangles();
    s.sequences()
        .iter()
        .flat_map(|q| (0..q.n_frames()).map(move |f| FrameMesh { positions: q.frame(f), triangles: t }))
        .collect()
}

/// Neighbouring frames are far more similar than frames a second apart, and a frame turned
/// about the vertical axis is found at (nearly) zero distance from itself: eq. 2's rotation
/// search works on real shapes.
#[test]
fn crane_neighbours_are_similar_and_rotation_about_the_vertical_is_undone() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = load(data.join("vlasic2008/crane"));
    let mut meshes = frames(&s);
    meshes.truncate(60);
    // Frame 0 turned by 100 degrees about the up axis, appended as frame 60.
    let (axis, _) = s.up_axis.axis_and_sign();
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let (c, sn) = (100f64.to_radians().cos(), 100f64.to_radians().sin());
    let turned: Vec<f32> = meshes[0]
        .positions
        .chunks_exact(3)
        .flat_map(|p| {
            let mut q = [p[0], p[1], p[2]];
            q[a] = (c * f64::from(p[a]) - sn * f64::from(p[b])) as f32;
            q[b] = (sn * f64::from(p[a]) + c * f64::from(p[b])) as f32;
            q
        })
        .collect();
    meshes.push(FrameMesh { positions: &turned, triangles: s.topology().triangles() });
    let set = frame_histograms(&meshes, s.up_axis, HistogramParams::default()).unwrap();
    let counts: Vec<usize> = set.histograms.iter().map(|h| h.voxels).collect();
    assert!(counts.iter().all(|&c| c > 2_000), "a body fills thousands of voxels at 64 per extent");
    let n = meshes.len();
    let m = shape_similarity_matrix(&set).unwrap();
    let near: Vec<f64> = (0..59).map(|i| m[i * n + i + 1]).collect();
    let far: Vec<f64> = (0..30).map(|i| m[i * n + i + 30]).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!("neighbours {:.4}, a second apart {:.4}, turned {:.4}", mean(&near), mean(&far), m[60]);
    assert!(mean(&near) * 1.5 < mean(&far), "neighbours {} vs a second apart {}", mean(&near), mean(&far));
    // The turned frame: its voxels sit on a turned lattice, so not exactly 0, but within voxel
    // noise (about a neighbour's distance) and far below frames a second apart.
    assert!(m[60] < 1.5 * mean(&near) && m[60] < 0.75 * mean(&far), "turned {} vs neighbours {}", m[60], mean(&near));
    assert_eq!(s.up_axis, UpAxis::PosY);
}

/// A walk cycle's best self-transition jumps back by about one cycle (the KayKit knight's
/// walk: separate, interpenetrating body-part meshes, voxelised as their union).
#[test]
fn a_walk_cycle_transitions_onto_itself_one_cycle_back() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = load(data.join("kaykit_adventurers/knight_Walking_A"));
    let meshes = frames(&s);
    let n = meshes.len();
    let set = frame_histograms(&meshes, s.up_axis, HistogramParams::default()).unwrap();
    let m = shape_similarity_matrix(&set).unwrap();
    let t = optimal_transition(&m, n, 0..n, 0..n, 3..=30).unwrap().unwrap();
    let neighbours = (0..n - 1).map(|i| m[i * n + i + 1]).sum::<f64>() / (n - 1) as f64;
    println!("{n} frames: {t:?}; consecutive frames {neighbours:.4}");
    // The clip's last frame repeats its first: the cycle is n - 1 frames.
    let back = t.last_x + 1 - t.first_y;
    assert!((n - 5..=n).contains(&back), "jumps back {back} frames: {t:?}");
    assert!(t.cost <= neighbours, "a loop as smooth as playing on: {} vs {neighbours}", t.cost);
}

/// Same frames, same matrix, whatever the number of threads.
#[test]
fn the_similarity_matrix_does_not_depend_on_the_thread_count() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = load(data.join("threejs_morph_animals/horse_gallop"));
    let meshes = frames(&s);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            let set = frame_histograms(&meshes, s.up_axis, HistogramParams::default()).unwrap();
            shape_similarity_matrix(&set).unwrap()
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.iter().zip(&two).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert!(one.iter().any(|&x| x > 0.0));
}

/// The similarity needs no correspondence: the crane's frames re-meshed one by one (different
/// vertices and triangles in every frame) give nearly the same matrix as the captured mesh.
#[test]
fn re_meshed_frames_give_the_same_similarities() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = load(data.join("vlasic2008/crane"));
    let opts = surfcap_builtin::frame_remeshing::RemeshFramesOptions {
        seed: 3,
        frames: Some(12),
        target_vertices: Some(4000),
        ..Default::default()
    };
    let set = surfcap_builtin::frame_remeshing::remesh_subject_frames(&s, &opts, &surfcap_mesh::NoProgress).unwrap();
    let remeshed = surfcap_smg::motion_frames::MotionFrames::from_frame_set(&set);
    assert!(remeshed.positions.windows(2).any(|w| w[0].len() != w[1].len()), "frames differ in vertex count");
    let shared = frames(&s);
    let shared: Vec<FrameMesh<'_>> = shared.into_iter().take(12).collect();
    let a =
        shape_similarity_matrix(&frame_histograms(&shared, s.up_axis, HistogramParams::default()).unwrap()).unwrap();
    let b =
        shape_similarity_matrix(&frame_histograms(&remeshed.meshes(), s.up_axis, HistogramParams::default()).unwrap())
            .unwrap();
    let n = 12;
    let off: Vec<(f64, f64)> =
        (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| (a[i * n + j], b[i * n + j])).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (xa, xb): (Vec<f64>, Vec<f64>) = off.iter().copied().unzip();
    let (ma, mb) = (mean(&xa), mean(&xb));
    let cov: f64 = off.iter().map(|(x, y)| (x - ma) * (y - mb)).sum();
    let (va, vb): (f64, f64) = (xa.iter().map(|x| (x - ma).powi(2)).sum(), xb.iter().map(|y| (y - mb).powi(2)).sum());
    let r = cov / (va * vb).sqrt();
    println!("shared mean {ma:.4}, re-meshed mean {mb:.4}, correlation {r:.3}");
    // 0.89 measured over 12 consecutive frames, whose differences are near the voxel noise of
    // a 64-voxel lattice (the same means show no bias).
    assert!(r > 0.8, "correlation {r}");
    assert!((ma - mb).abs() < 0.25 * ma, "means {ma} vs {mb}");
}

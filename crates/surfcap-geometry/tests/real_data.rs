//! Pose geometry on real captures from `../shared/data` (thesis 2.3-2.4).

use std::path::PathBuf;

use faer::sparse::SparseColMat;
use nalgebra::{Matrix3, Vector3};
use surfcap_formats::import::{ImportOptions, import};
use surfcap_geometry::deformation_gradient::{deformation_gradients, vertex};
use surfcap_geometry::distance_matrix::{
    DistanceParams, SLAB_BYTES, distance_matrix, distance_matrix_in_slabs, slab_triangles,
};
use surfcap_geometry::gradient_operator::{GradientOperator, cotangent_laplacian_triplets};
use surfcap_geometry::motion_plane_alignment::rotation_about_up;
use surfcap_geometry::poisson_reconstruction::PoissonSolver;
use surfcap_geometry::polar_decomposition::polar_decomposition;
use surfcap_geometry::pose_distance::{
    DistanceKernel, PoseMetric, deformation_distance_with, kernel_name, triangle_frames,
};
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_geometry::rotation_log_exp::rotation_angle;
use surfcap_geometry::shape_distortion::{edge_length_distortion, volume_change};
use surfcap_mesh::{NoProgress, Sequence, Subject};

fn subject(rel: &[&str]) -> Option<Subject> {
    let data = surfcap_testkit::shared_data()?;
    let paths: Vec<PathBuf> = rel.iter().map(|r| data.join(r)).collect();
    Some(import(&paths, &ImportOptions::default(), &NoProgress).unwrap().subject)
}

fn diag(p: &[f32]) -> f64 {
    let (lo, hi) = surfcap_mesh::bounding_box(p);
    (0..3).map(|k| ((hi[k] - lo[k]) as f64).powi(2)).sum::<f64>().sqrt()
}

fn max_diff(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).fold(0.0, f64::max)
}

#[test]
fn laplacian_is_the_cotangent_laplacian_and_gradients_are_exact_on_real_meshes() {
    for rel in ["vlasic2008/crane", "kaykit_adventurers/knight_Idle", "sumner2004-horse/gallop"] {
        let Some(s) = subject(&[rel]) else { return };
        let p = s.frame(0).unwrap();
        let op = GradientOperator::new(s.topology(), p);
        let n = s.topology().n_vertices();
        let l = op.laplacian();
        let c = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &cotangent_laplacian_triplets(s.topology(), p))
            .unwrap();
        // Compare entry by entry through a dense product with random-ish vectors (N is ~10k).
        let x = faer::Mat::<f64>::from_fn(n, 2, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
        let (lx, cx) = (&l * &x, &c * &x);
        let rel_err = (&lx - &cx).norm_max() / cx.norm_max();
        assert!(rel_err < 1e-9, "{rel}: L vs cotangent Laplacian: {rel_err}");
        // The gradient of a linear function f(x) = M x is M^T on each triangle's plane.
        let m = Matrix3::new(1.0, 2.0, -1.0, 0.5, 0.0, 3.0, -2.0, 1.0, 0.25);
        let f: Vec<f32> = p
            .chunks(3)
            .flat_map(|v| {
                let y = m * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                [y.x as f32, y.y as f32, y.z as f32]
            })
            .collect();
        let grads = op.gradients(&f);
        let mut worst = 0.0f64;
        for (t, (g, &area)) in s.topology().triangles().iter().zip(grads.iter().zip(&op.areas)) {
            if area == 0.0 {
                continue;
            }
            let (v1, v2, v3) = (vertex(p, t[0]), vertex(p, t[1]), vertex(p, t[2]));
            for e in [v1 - v3, v2 - v3] {
                // f32 inputs: compare with the f32-rounded function values' own differences.
                let fe = vertex(&f, t[0]) - vertex(&f, t[2]);
                let fe2 = vertex(&f, t[1]) - vertex(&f, t[2]);
                let want = if e == v1 - v3 { fe } else { fe2 };
                worst = worst.max((g.transpose() * e - want).norm() / (want.norm() + 1e-12));
            }
        }
        assert!(worst < 1e-9, "{rel}: gradient of a linear function off by {worst}");
    }
}

#[test]
fn poisson_reconstructs_meshes_with_several_components() {
    for rel in ["kaykit_adventurers/knight_Running_A", "robot_expressive/Walking"] {
        let Some(s) = subject(&[rel]) else { return };
        let p = s.frame(5).unwrap();
        let solver = PoissonSolver::new(s.topology(), p).unwrap();
        assert!(solver.components().count > 1, "{rel}");
        let back = solver.solve(&solver.operator().gradients(p), &solver.component_centroids(p));
        let err = max_diff(&back, p) / diag(p);
        assert!(err < 1e-6, "{rel}: relative error {err}");
    }
}

#[test]
fn interpolation_reproduces_both_ends() {
    let Some(s) = subject(&["vlasic2008/crane"]) else { return };
    let (pi, pj) = (s.frame(0).unwrap(), s.frame(90).unwrap());
    let it = NonlinearInterpolator::new(s.topology(), pi, pj, s.up_axis).unwrap();
    for stretch in [StretchInterpolation::Linear, StretchInterpolation::Log] {
        let a = it.at(0.0, stretch);
        let b = it.at(1.0, stretch);
        assert!(max_diff(&a, pi) / diag(pi) < 1e-5, "lambda 0: {}", max_diff(&a, pi) / diag(pi));
        let pj_al = it.aligned_target();
        assert!(max_diff(&b, pj_al) / diag(pi) < 1e-5, "lambda 1: {}", max_diff(&b, pj_al) / diag(pi));
    }
}

#[test]
fn nonlinear_interpolation_distorts_less_than_linear_on_far_pairs() {
    // The horse's collapse sequence has another vertex order than its gallop (its import
    // notes say so), so the far horse pair is a gallop frame and one of the 10 key poses.
    let cases: &[(&[&str], &str, &str)] = &[
        (&["vlasic2008/crane"], "crane:0", "crane:120"),
        (&["vlasic2008/samba"], "samba:0", "samba:90"),
        (&["sumner2004-horse/gallop", "sumner2004-horse/poses"], "gallop:0", "poses:3"),
    ];
    for (rel, from, to) in cases {
        let Some(s) = subject(rel) else { return };
        let (gi, gj) = (s.resolve_frame(from).unwrap(), s.resolve_frame(to).unwrap());
        let pi = s.frame(gi).unwrap();
        let it = NonlinearInterpolator::new(s.topology(), pi, s.frame(gj).unwrap(), s.up_axis).unwrap();
        let pj = it.aligned_target();
        let (nl, li) = (it.at(0.5, StretchInterpolation::Linear), it.linear(0.5));
        let t = s.topology();
        let (e_nl, e_li) = (edge_length_distortion(t, pi, pj, &nl, 0.5), edge_length_distortion(t, pi, pj, &li, 0.5));
        let (v_nl, v_li) = (volume_change(t, pi, pj, &nl, 0.5), volume_change(t, pi, pj, &li, 0.5));
        assert!(e_nl < e_li, "{from}->{to}: edge distortion non-linear {e_nl} vs linear {e_li}");
        assert!(v_nl < v_li, "{from}->{to}: volume change non-linear {v_nl} vs linear {v_li}");
    }
}

#[test]
fn deformation_distance_matches_the_svd_route_and_ignores_ground_plane_motion() {
    let Some(s) = subject(&["vlasic2008/crane"]) else { return };
    let topo = s.topology().clone();
    let nv = topo.n_vertices();
    let (pi, pj) = (s.frame(0).unwrap().to_vec(), s.frame(60).unwrap().to_vec());
    // Pose j turned by 1 rad about the up axis and moved: the distance must not change.
    let g = rotation_about_up(s.up_axis, 1.0);
    let moved: Vec<f32> = pj
        .chunks(3)
        .flat_map(|v| {
            let x = g * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64) + Vector3::new(3.0, 0.0, -2.0);
            [x.x as f32, x.y as f32, x.z as f32]
        })
        .collect();
    let mut all = pi.clone();
    all.extend_from_slice(&pj);
    all.extend_from_slice(&moved);
    let sub =
        Subject::new("t", topo.clone(), vec![Sequence::new("s", nv, all).unwrap()], 30.0, s.up_axis, s.units.clone())
            .unwrap();
    for metric in [PoseMetric::Deformation, PoseMetric::DeformationLog, PoseMetric::Euclidean] {
        let d = distance_matrix(&sub, &DistanceParams { metric, ..Default::default() }, &NoProgress);
        let (d01, d02) = (d.get(0, 1), d.get(0, 2));
        assert!((d01 - d02).abs() < 1e-4 * d01, "{metric:?}: {d01} vs {d02}");
        assert_eq!(d.get(1, 0), d01);
        assert_eq!(d.get(0, 0), 0.0);
    }
    // The closed form against the thesis's SVD route (eq. 2.6, 2.8-2.13) for the aligned pair.
    let gram = surfcap_geometry::distance_matrix::alignment_gram(&sub, None);
    let ga = rotation_about_up(s.up_axis, gram.theta(0, 1));
    let reference: f64 = deformation_gradients(&topo, &pi, &pj)
        .into_iter()
        .flatten()
        .map(|j| {
            let (r, st) = polar_decomposition(&(ga * j));
            rotation_angle(&r) + 0.01 * (st - Matrix3::identity()).norm()
        })
        .sum();
    let d = distance_matrix(&sub, &DistanceParams::default(), &NoProgress);
    assert!((d.get(0, 1) - reference).abs() < 1e-8 * reference, "{} vs {reference}", d.get(0, 1));
}

/// The triangle data held one slab at a time (the memory target: 1.9 GB for 547 frames of 14,000
/// vertices when held whole) gives the matrix of the whole-mesh computation to the bit: one slab
/// of every triangle is the previous algorithm; one chunk per slab and a middle size are the most
/// and a typical number of slab boundaries. The barbarian has zero-area triangles (frame 0), so
/// the skipped count is gathered across slabs too.
#[test]
fn distance_matrix_in_slabs_equals_the_whole_mesh_computation_to_the_bit() {
    let Some(crane) = subject(&["vlasic2008/crane"]) else { return };
    let Some(barbarian) = subject(&["kaykit_adventurers/barbarian_Running_A"]) else { return };
    let nv = crane.topology().n_vertices();
    let first: Vec<f32> = (0..30).flat_map(|g| crane.frame(g).unwrap().to_vec()).collect();
    let crane = crane.derived("crane30", Sequence::new("s", nv, first).unwrap()).unwrap();
    for (s, metric) in
        [(&crane, PoseMetric::Deformation), (&crane, PoseMetric::DeformationLog), (&barbarian, PoseMetric::Deformation)]
    {
        let params = DistanceParams { metric, ..Default::default() };
        let whole = distance_matrix_in_slabs(s, &params, &NoProgress, usize::MAX);
        assert!(whole.values.iter().any(|&d| d > 0.0));
        for budget in [1, 1 << 20] {
            let slabs = distance_matrix_in_slabs(s, &params, &NoProgress, budget);
            assert!(
                slabs.values.iter().zip(&whole.values).all(|(a, b)| a.to_bits() == b.to_bits()),
                "{metric:?}, {budget} bytes per slab"
            );
            assert_eq!(slabs.max_skipped_triangles, whole.max_skipped_triangles);
        }
        assert_eq!(distance_matrix(s, &params, &NoProgress), whole);
    }
    assert!(distance_matrix(&barbarian, &DistanceParams::default(), &NoProgress).max_skipped_triangles > 0);
    // The target's subject: 547 frames of 28,000 triangles fit the slab budget.
    assert!(slab_triangles(547, SLAB_BYTES) * 547 * 120 <= SLAB_BYTES);
}

/// Tiles are the unit of work and an entry does not depend on the tiling. The
/// matrix assembled from tiles of 1, 7 and 13 frames (diagonal and off-diagonal tiles, ragged
/// edges) equals the one-tile matrix to the bit for every metric, with and without vertex
/// weights, and the skipped-triangle count is gathered across tiles.
#[test]
fn distance_tiles_give_the_matrix_of_one_tile_to_the_bit() {
    use surfcap_geometry::distance_matrix::distance_matrix_in_tiles;
    use surfcap_geometry::distance_tiles::plan_distance_tiles;
    let Some(barbarian) = subject(&["kaykit_adventurers/barbarian_Running_A"]) else { return };
    let nv = barbarian.topology().n_vertices();
    let weights: Vec<f64> = (0..nv).map(|k| 0.5 + (k % 3) as f64).collect();
    for (metric, vertex_weights) in [
        (PoseMetric::Deformation, None),
        (PoseMetric::DeformationLog, None),
        (PoseMetric::Euclidean, Some(weights.clone())),
        (PoseMetric::Deformation, Some(weights)),
    ] {
        let params = DistanceParams { metric, vertex_weights, ..Default::default() };
        let whole = distance_matrix_in_tiles(&barbarian, &params, &NoProgress, SLAB_BYTES, 0);
        assert!(whole.values.iter().any(|&d| d > 0.0));
        for tile in [1, 7, 13] {
            let tiled = distance_matrix_in_tiles(&barbarian, &params, &NoProgress, 1 << 20, tile);
            let differ = tiled.values.iter().zip(&whole.values).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
            assert_eq!(differ, 0, "{metric:?}, tiles of {tile}");
            assert_eq!(tiled.max_skipped_triangles, whole.max_skipped_triangles);
        }
    }
    let n = barbarian.n_frames();
    let spans = plan_distance_tiles(n, 7);
    assert_eq!(spans.iter().map(|s| s.pairs()).sum::<usize>(), n * (n - 1) / 2, "the tiles cover the upper triangle");
    assert!(spans.iter().all(|s| s.rows.start <= s.cols.start));
}

/// The matrix does not depend on the thread count (identical on 1 and 2
/// threads) with the kernel this CPU runs, for both deformation metrics; and on real triangle
/// data every kernel this CPU has agrees with the scalar loop to 1e-12 relative, the SIMD ones
/// with each other to the bit (the test prints which kernels it ran).
#[test]
fn distance_matrix_is_the_same_on_1_and_2_threads_and_every_kernel_agrees_on_the_crane() {
    let Some(crane) = subject(&["vlasic2008/crane"]) else { return };
    let nv = crane.topology().n_vertices();
    let first: Vec<f32> = (0..40).flat_map(|g| crane.frame(g).unwrap().to_vec()).collect();
    let crane40 = crane.derived("crane40", Sequence::new("s", nv, first).unwrap()).unwrap();
    for metric in [PoseMetric::Deformation, PoseMetric::DeformationLog] {
        let params = DistanceParams { metric, ..Default::default() };
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| distance_matrix(&crane40, &params, &NoProgress))
        };
        let (one, two) = (on(1), on(2));
        assert!(one.values.iter().filter(|&&d| d > 0.0).count() == 40 * 39);
        assert!(
            one.values.iter().zip(&two.values).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{metric:?}: 1 vs 2 threads with the {} kernel",
            kernel_name()
        );
    }
    let triangles = crane.topology().triangles();
    let (mut fi, mut fj) = (Vec::new(), Vec::new());
    let available = DistanceKernel::available();
    for (i, j) in [(0, 1), (10, 11), (0, 120), (60, 174)] {
        triangle_frames(triangles, crane.frame(i).unwrap(), &mut fi);
        triangle_frames(triangles, crane.frame(j).unwrap(), &mut fj);
        let g = rotation_about_up(crane.up_axis, 0.3 * i as f64 - 0.1 * j as f64);
        let d: Vec<f64> = available.iter().map(|&k| deformation_distance_with(k, &fi, &fj, &g, 0.01, false)).collect();
        for (k, x) in available.iter().zip(&d) {
            assert!((x - d[0]).abs() <= 1e-12 * d[0], "crane:{i} - crane:{j}: {} {x} vs scalar {}", k.name(), d[0]);
        }
        assert!(d[1..].iter().all(|x| x.to_bits() == d[d.len() - 1].to_bits()), "crane:{i} - crane:{j}: {d:?}");
    }
    eprintln!(
        "thread independence checked with the {} kernel; kernels compared on crane pairs: {}",
        kernel_name(),
        available.iter().map(|k| k.name()).collect::<Vec<_>>().join(", ")
    );
    if available.len() == 1 {
        eprintln!("this CPU has no SIMD distance kernel: only the scalar loop was checked");
    }
}

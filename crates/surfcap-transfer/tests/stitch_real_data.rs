//! Part correction and stitching (thesis 5.6.1-5.6.2) on a real capture: the Vlasic crane
//! (10,002 vertices, 175 frames) cut by two height planes into a torso (the root), the legs and
//! the head, each overlapping the torso in a band of rings around its plane. Ground truth comes
//! from the capture itself: parts cut out of a true frame must stitch back into it; a distorted
//! child must stitch without a seam; a shrunk part must be corrected back towards the truth.

use std::path::PathBuf;

use nalgebra::{Matrix3, Vector3};
use surfcap_formats::import::{ImportOptions, import};
use surfcap_geometry::rotation_log_exp::exp_rotation;
use surfcap_mesh::{NoProgress, Subject, Topology};
use surfcap_transfer::body_parts::{BodyParts, Part};
use surfcap_transfer::part_correction::{DEFAULT_M_NEAREST, PartCorrector};
use surfcap_transfer::part_stitching::{Cut, Stitcher, average_overlaps, edge_distortion_by_region};

fn crane() -> Option<Subject> {
    let data = surfcap_testkit::shared_data()?;
    let paths: Vec<PathBuf> = vec![data.join("vlasic2008/crane")];
    Some(import(&paths, &ImportOptions::default(), &NoProgress).unwrap().subject)
}

/// The vertices in `set` plus `rings` rings of neighbours around them.
fn grow(t: &Topology, mut set: Vec<bool>, rings: usize) -> Vec<bool> {
    for _ in 0..rings {
        let prev = set.clone();
        for tri in t.triangles() {
            if tri.iter().any(|&v| prev[v as usize]) {
                for &v in tri {
                    set[v as usize] = true;
                }
            }
        }
    }
    set
}

fn indices(set: &[bool]) -> Vec<u32> {
    (0..set.len() as u32).filter(|&v| set[v as usize]).collect()
}

/// Torso (root) between heights h1 and h2 (y up), legs below h1, head above h2, each plane
/// widened into an overlap of about four rings (two on each side).
fn parts(t: &Topology, p: &[f32], h1: f32, h2: f32) -> BodyParts {
    let y: Vec<f32> = p.chunks_exact(3).map(|q| q[1]).collect();
    let legs = grow(t, y.iter().map(|&y| y <= h1).collect(), 2);
    let head = grow(t, y.iter().map(|&y| y > h2).collect(), 2);
    let torso = grow(t, y.iter().map(|&y| y > h1 && y <= h2).collect(), 2);
    let part = |name: &str, parent: Option<&str>, set: &[bool]| Part {
        name: name.into(),
        parent: parent.map(Into::into),
        vertices: indices(set),
    };
    BodyParts::new(
        t.n_vertices(),
        vec![part("torso", None, &torso), part("legs", Some("torso"), &legs), part("head", Some("torso"), &head)],
    )
    .unwrap()
}

fn cut_out(parts: &BodyParts, p: &[f32]) -> Vec<Vec<f32>> {
    parts.parts.iter().map(|q| gather(&q.vertices, p)).collect()
}

fn gather(vertices: &[u32], p: &[f32]) -> Vec<f32> {
    vertices.iter().flat_map(|&v| p[3 * v as usize..3 * v as usize + 3].to_vec()).collect()
}

fn height(p: &[f32]) -> f64 {
    let (lo, hi) = surfcap_mesh::bounding_box(p);
    (hi[1] - lo[1]) as f64
}

fn max_dist(a: &[f32], b: &[f32]) -> f64 {
    a.chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(x, y)| (0..3).map(|k| ((x[k] - y[k]) as f64).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

fn rms_dist(a: &[f32], b: &[f32]) -> f64 {
    let s: f64 = a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum();
    (s / (a.len() / 3) as f64).sqrt()
}

fn centroid(p: &[f32]) -> Vector3<f64> {
    p.chunks_exact(3).map(|q| Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64)).sum::<Vector3<f64>>()
        / (p.len() / 3) as f64
}

fn map(p: &[f32], mut f: impl FnMut(Vector3<f64>) -> Vector3<f64>) -> Vec<f32> {
    p.chunks_exact(3)
        .flat_map(|q| {
            let w = f(Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64));
            [w.x as f32, w.y as f32, w.z as f32]
        })
        .collect()
}

const H1: f32 = 0.87;
const H2: f32 = 1.6;

#[test]
fn parts_of_true_frames_stitch_back_into_the_frames() {
    let Some(s) = crane() else { return };
    let t = s.topology();
    let rest = s.frame(0).unwrap();
    let parts = parts(t, rest, H1, H2);
    let clock = std::time::Instant::now();
    let stitcher = Stitcher::new(t, rest, &parts).unwrap();
    println!("Stitcher::new: {:.3} s", clock.elapsed().as_secs_f64());
    for f in [0, 40, 87, 130, 174] {
        let truth = s.frame(f).unwrap();
        let clock = std::time::Instant::now();
        let (out, report) = stitcher.stitch(&cut_out(&parts, truth)).unwrap();
        println!("frame {f} stitched in {:.3} s", clock.elapsed().as_secs_f64());
        let err = max_dist(&out, truth) / height(truth);
        println!("frame {f}: max error {err:.2e} of the height");
        assert!(err < 1e-5, "frame {f}: stitched off the truth by {err:.2e} of the height");
        for k in [1, 2] {
            let Cut::Loop { vertices, mismatch, .. } = &report.parts[k].cut else {
                panic!("{}: {:?}", parts.parts[k].name, report.parts[k].cut)
            };
            assert!(vertices.len() > 10 && *mismatch < 1e-4, "{}: {} {mismatch}", parts.parts[k].name, vertices.len());
            assert!(report.parts[k].overlap_rms < 1e-5);
        }
    }
}

#[test]
fn a_moved_and_distorted_child_stitches_without_a_seam() {
    let Some(s) = crane() else { return };
    let t = s.topology();
    let rest = s.frame(0).unwrap();
    let parts = parts(t, rest, H1, H2);
    let stitcher = Stitcher::new(t, rest, &parts).unwrap();
    let truth = s.frame(100).unwrap();
    let h = height(truth);
    let mut ps = cut_out(&parts, truth);
    // The legs: turned by 3 degrees, moved by 1% of the height, stretched 4% sideways and
    // bent forward by up to 2% of the height (a mild non-rigid distortion of the prediction).
    let c = centroid(&ps[1]);
    let r = exp_rotation(&Vector3::new(0.0, 0.0, 3f64.to_radians()));
    let a = Matrix3::from_diagonal(&Vector3::new(1.04, 1.0, 0.98));
    ps[1] = map(&ps[1], |v| {
        let d = v - c;
        let bent = a * d + Vector3::new(0.0, 0.0, 0.02 * h * (d.y / (0.5 * h)).powi(2));
        r * bent + c + Vector3::new(0.01 * h, 0.0, -0.005 * h)
    });
    let (out, report) = stitcher.stitch(&ps).unwrap();
    let stitched = edge_distortion_by_region(t, &parts, &out, truth).unwrap();
    let averaged = edge_distortion_by_region(t, &parts, &average_overlaps(&parts, &ps, true).unwrap(), truth).unwrap();
    let unaligned =
        edge_distortion_by_region(t, &parts, &average_overlaps(&parts, &ps, false).unwrap(), truth).unwrap();
    println!("legs cut: {:?}", report.parts[1].cut);
    println!(
        "overlap RMS after alignment {:.4} ({:.2e} of the height)",
        report.parts[1].overlap_rms,
        report.parts[1].overlap_rms / h
    );
    println!("stitched          {stitched:?}");
    println!("averaged, aligned {averaged:?}");
    println!("averaged as is    {unaligned:?}");
    assert!(matches!(report.parts[1].cut, Cut::Loop { .. }), "{:?}", report.parts[1].cut);
    // No seam: edges across the overlaps change no more than the distortion inside the legs.
    assert!(stitched.boundary_max <= 1.25 * stitched.inside_max, "{stitched:?}");
    assert!(stitched.boundary_mean <= 1.5 * stitched.inside_mean, "{stitched:?}");
    // The averaged baseline tears the band's edge, aligned or not.
    assert!(averaged.boundary_max > 4.0 * stitched.boundary_max, "{averaged:?} vs {stitched:?}");
    assert!(unaligned.boundary_max > averaged.boundary_max, "{unaligned:?} vs {averaged:?}");
    // Away from the legs' seam the torso and head are untouched.
    let head = &parts.parts[2].vertices;
    let moved = max_dist(&gather(head, &out), &gather(head, truth)) / h;
    assert!(moved < 0.02, "the head moved by {moved:.2e} of the height");
}

/// KayKit's barbarian is made of separate meshes (head, body, arms, legs) and frame 0 of
/// `Running_A` has zero-area triangles: parts without overlap keep their placement, nothing
/// turns into NaN, and true parts come back as they were.
#[test]
fn separate_parts_without_overlap_keep_their_placement_on_kaykit() {
    let data = match surfcap_testkit::shared_data() {
        Some(d) => d,
        None => return,
    };
    let s = import(&[data.join("kaykit_adventurers/barbarian_Running_A")], &ImportOptions::default(), &NoProgress)
        .unwrap()
        .subject;
    let t = s.topology();
    let rest = s.frame(0).unwrap();
    assert!(t.count_degenerate_triangles(rest, 1e-12) > 0, "frame 0 was expected to hold zero-area triangles");
    let comps = surfcap_mesh::connected_components(t);
    let sizes = comps.sizes();
    let root = (0..comps.count).max_by_key(|&c| (sizes[c], std::cmp::Reverse(c))).unwrap();
    let mut order: Vec<usize> = vec![root];
    order.extend((0..comps.count).filter(|&c| c != root));
    let part_list: Vec<Part> = order
        .iter()
        .map(|&c| Part {
            name: format!("component{c}"),
            parent: (c != root).then(|| format!("component{root}")),
            vertices: (0..t.n_vertices() as u32).filter(|&v| comps.labels[v as usize] as usize == c).collect(),
        })
        .collect();
    // Built without validation: children sharing no vertex with their parent.
    let parts = BodyParts {
        format: surfcap_transfer::body_parts::FORMAT.into(),
        version: surfcap_transfer::body_parts::VERSION,
        n_vertices: t.n_vertices(),
        parts: part_list,
    };
    let stitcher = Stitcher::new(t, rest, &parts).unwrap();
    let truth = s.frame(s.n_frames() / 2).unwrap();
    let h = height(truth);
    let mut ps = cut_out(&parts, truth);
    ps[1] = map(&ps[1], |v| v + Vector3::new(0.05 * h, 0.0, 0.0));
    let (out, report) = stitcher.stitch(&ps).unwrap();
    assert!(out.iter().all(|x| x.is_finite()));
    println!("{} components; cuts {:?}", comps.count, report.parts.iter().map(|p| &p.cut).collect::<Vec<_>>());
    for (k, p) in parts.parts.iter().enumerate() {
        assert_eq!(report.parts[k].cut, if k == 0 { Cut::Root } else { Cut::NoOverlap });
        let err = max_dist(&gather(&p.vertices, &out), &ps[k]) / h;
        println!("{}: {} vertices, max error {err:.2e} of the height", p.name, p.vertices.len());
        assert!(err < 1e-5, "{}: off its predicted placement by {err:.2e} of the height", p.name);
    }
}

#[test]
fn a_shrunk_part_is_corrected_back_towards_the_truth() {
    let Some(s) = crane() else { return };
    let t = s.topology();
    let rest = s.frame(0).unwrap();
    let parts = parts(t, rest, H1, H2);
    for k in 0..3 {
        let sub = parts.submesh(t, k);
        let f = 100;
        // Training: every other frame of the capture away from the test frame (±5 frames).
        let training: Vec<Vec<f32>> =
            (0..s.n_frames()).filter(|&g| g.abs_diff(f) > 5).map(|g| sub.gather(s.frame(g).unwrap())).collect();
        let corrector = PartCorrector::new(&sub.topology, &sub.gather(rest), training, DEFAULT_M_NEAREST).unwrap();
        let truth = sub.gather(s.frame(f).unwrap());
        let c = centroid(&truth);
        let size = (truth
            .chunks_exact(3)
            .map(|q| (Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64) - c).norm_squared())
            .sum::<f64>()
            / (truth.len() / 3) as f64)
            .sqrt();
        // Shrunk by 10% about its centroid, plus deterministic noise of 0.5% of its size.
        let mut i = 0u64;
        let predicted = map(&truth, |v| {
            i += 1;
            let noise = Vector3::new(
                ((i * 7919) % 101) as f64 / 50.0 - 1.0,
                ((i * 104729) % 97) as f64 / 48.0 - 1.0,
                ((i * 1299709) % 89) as f64 / 44.0 - 1.0,
            );
            c + 0.9 * (v - c) + 0.005 * size * noise
        });
        let before = rms_dist(&predicted, &truth);
        let clock = std::time::Instant::now();
        let out = corrector.correct_detailed(&predicted).unwrap();
        println!("{} corrected in {:.3} s", parts.parts[k].name, clock.elapsed().as_secs_f64());
        let after = rms_dist(&out.positions, &truth);
        // For scale: the nearest training mesh itself, moved onto the truth's centroid.
        let nearest = sub.gather(
            s.frame(if out.neighbours[0] < f - 5 { out.neighbours[0] } else { out.neighbours[0] + 11 }).unwrap(),
        );
        let shift = c - centroid(&nearest);
        let nearest_err = rms_dist(&map(&nearest, |v| v + shift), &truth);
        println!("{}: the nearest training frame alone is off by {nearest_err:.4}", parts.parts[k].name);
        println!(
            "{}: {} vertices, size {size:.3}: RMS error before {before:.4}, after {after:.4}; neighbours {:?} weights {:?}",
            parts.parts[k].name,
            truth.len() / 3,
            out.neighbours,
            out.weights
        );
        assert!(
            after < 0.5 * before,
            "{}: RMS error {before:.4} before correction, {after:.4} after",
            parts.parts[k].name
        );
        assert!(
            after < nearest_err,
            "{}: corrected {after:.4}, nearest mesh alone {nearest_err:.4}",
            parts.parts[k].name
        );
    }
}

//! Motion variation on real motion: the built-in mannequin driven by CMU subject 16's walk,
//! turns and jog (real captures, real travel).

use std::path::Path;

use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_variation::VariationModel;
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_sampling::{SamplingOptions, place_and_retime, reconstruct_aligned, sample_variants};

fn cmu_locomotion(data: &Path, vertices: usize) -> Subject {
    let m = mannequin(&BodyShape::average(), vertices).unwrap();
    let clips: Vec<Clip> = ["16_15", "16_17", "16_19", "16_36"]
        .iter()
        .map(|c| {
            let path = data.join("cmu_bvh").join(format!("{c}.bvh"));
            let bvh = read_bvh(&path).unwrap();
            Clip::from_bvh(&path, &bvh, &m, bvh.guess_metres_per_unit().0).unwrap()
        })
        .collect();
    mannequin_subject("cmu", &m, &clips, 30.0).unwrap()
}

/// Mean per-vertex distance between two motions of one frame count.
fn motion_distance(a: &[Vec<f32>], b: &[&[f32]]) -> f64 {
    let mut s = 0.0;
    let mut n = 0usize;
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.chunks_exact(3).zip(y.chunks_exact(3)) {
            s += (0..3).map(|k| ((p[k] - q[k]) as f64).powi(2)).sum::<f64>().sqrt();
            n += 1;
        }
    }
    s / n as f64
}

/// Distance between the centroids of two poses.
fn centre_distance(a: &[f32], b: &[f32]) -> f64 {
    let c = |p: &[f32]| -> [f64; 3] {
        let n = (p.len() / 3) as f64;
        std::array::from_fn(|k| p.chunks_exact(3).map(|v| v[k] as f64).sum::<f64>() / n)
    };
    let (x, y) = (c(a), c(b));
    (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn variants_of_a_cmu_walk_differ_from_it_yet_stay_close_and_survive_a_round_trip() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = cmu_locomotion(&data, 1500);
    let (parts, _) = propose(&s, Method::Auto, 5, 2).unwrap();
    let t0 = std::time::Instant::now();
    let model = VariationModel::train(&s, &[0, 1, 2, 3], &parts, &TrainOptions::default(), &NoProgress).unwrap();
    eprintln!("trained in {:.1} s", t0.elapsed().as_secs_f64());
    for f in &model.fits {
        eprintln!("{}: {} dims, {} iters, objective {:.1}", f.part, f.dimensions, f.fit.iters, f.fit.objective);
    }
    let walk = &s.sequences()[0];
    let t1 = std::time::Instant::now();
    let (variants, chains) = sample_variants(&model, &walk.name, 3, 7, &SamplingOptions::default()).unwrap();
    eprintln!("sampled in {:.1} s: {chains:?}", t1.elapsed().as_secs_f64());
    // The learnt trajectory's reconstruction, in the body frame, on the reference's frames:
    // what a variant's poses are compared with (it is within millimetres of the capture).
    let lat = model.learnt_latents(0).unwrap();
    let (learnt, disp) = reconstruct_aligned(&model, &lat).unwrap();
    let seq = &model.sequences[0];
    let w = place_and_retime(&learnt, &disp, &seq.first_placement, &seq.times, seq.own_frames).unwrap();
    let source: Vec<&[f32]> = (0..walk.n_frames()).map(|f| walk.frame(f)).collect();
    let rec = motion_distance(&w, &source);
    assert!(rec < 0.01, "the learnt walk is reconstructed {rec} m from the capture");
    let learnt_refs: Vec<&[f32]> = learnt.iter().map(|p| p.as_slice()).collect();
    let travel = centre_distance(walk.frame(0), walk.frame(walk.n_frames() - 1));
    for v in &variants {
        assert_eq!(v.world.len(), walk.n_frames());
        let d = motion_distance(&v.aligned, &learnt_refs);
        eprintln!("variant - learnt walk, body frame: {d:.4} m");
        assert!(d > 0.005, "a variant's poses copy the walk's: {d} m");
        assert!(d < 0.08, "a variant's poses are far from the walk's: {d} m");
        let end = centre_distance(v.world.last().unwrap(), walk.frame(walk.n_frames() - 1));
        eprintln!("variant's end {end:.3} m from the walk's, over a travel of {travel:.2} m");
        // By default a variant follows its source's path (VariantPath::Source), so it ends
        // where the walk ends up to its body's own variation; the thesis's sampled
        // displacements drifted 0.2-1.1 m over this 4.5 m walk.
        assert!(end < 0.2 * travel, "the variant ends {end} m from where the walk ends ({travel} m travel)");
    }
    for a in 0..variants.len() {
        for b in a + 1..variants.len() {
            let r: Vec<&[f32]> = variants[b].aligned.iter().map(|p| p.as_slice()).collect();
            let d = motion_distance(&variants[a].aligned, &r);
            assert!(d > 0.002, "variants {a} and {b} are {d} m apart: expected different variants");
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model");
    model.save(&path, false).unwrap();
    let back = VariationModel::load(&path).unwrap();
    // One variant from the loaded model: the chain's first sample does not depend on how many
    // follow it, so it must be the first variant above to the bit.
    let (again, _) = sample_variants(&back, &walk.name, 1, 7, &SamplingOptions::default()).unwrap();
    assert_eq!(variants[0].world, again[0].world, "a loaded model samples differently");
}

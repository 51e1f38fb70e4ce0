//! Motion variation on real motion: the built-in mannequin driven by CMU subject 16's walk,
//! turns and jog (real captures, real travel).

use std::path::Path;

use surfcap_mesh::{NoProgress, Subject};
use surfcap_synth::bvh::read_bvh;
use surfcap_synth::mannequin::{BodyShape, mannequin};
use surfcap_synth::mannequin_subject::{Clip, mannequin_subject};
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_variation::VariationModel;
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_sampling::{SamplingOptions, sample_variants};

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
    let source: Vec<&[f32]> = (0..walk.n_frames()).map(|f| walk.frame(f)).collect();
    {
        use surfcap_variation::variation_sampling::{place_and_retime, reconstruct_aligned};
        let lat = model.learnt_latents(0).unwrap();
        let (al, disp) = reconstruct_aligned(&model, &lat).unwrap();
        let seq = &model.sequences[0];
        let w = place_and_retime(&al, &disp, &seq.first_placement, &seq.times, seq.own_frames);
        eprintln!("learnt reconstruction - walk: {:.4} m", motion_distance(&w, &source));
        let zero: Vec<[f64; 6]> = disp.iter().map(|_| [0.0; 6]).collect();
        for v in &variants {
            let a = place_and_retime(&v.aligned, &zero, &seq.first_placement, &seq.times, seq.own_frames);
            let b = place_and_retime(&al, &zero, &seq.first_placement, &seq.times, seq.own_frames);
            eprintln!("variant body-frame - learnt body-frame: {:.4} m", motion_distance(&a, &b.iter().map(|p| p.as_slice()).collect::<Vec<_>>()));
        }
    }
    for v in &variants {
        assert_eq!(v.world.len(), walk.n_frames());
        let d = motion_distance(&v.world, &source);
        eprintln!("variant - walk: {d:.4} m");
        assert!(d > 0.005, "a variant is a copy of its source: {d}");
        assert!(d < 0.3, "a variant is far from its source: {d}");
    }
    for a in 0..variants.len() {
        for b in a + 1..variants.len() {
            let r: Vec<&[f32]> = variants[b].aligned.iter().map(|p| p.as_slice()).collect();
            eprintln!("variant {a} - variant {b} body frame: {:.4} m", motion_distance(&variants[a].aligned, &r));
        }
    }
    let refs1: Vec<&[f32]> = variants[1].world.iter().map(|p| p.as_slice()).collect();
    assert!(motion_distance(&variants[0].world, &refs1) > 1e-4, "two variants are identical");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model");
    model.save(&path, false).unwrap();
    let back = VariationModel::load(&path).unwrap();
    let (again, _) = sample_variants(&back, &walk.name, 3, 7, &SamplingOptions::default()).unwrap();
    for (a, b) in variants.iter().zip(&again) {
        assert_eq!(a.world, b.world, "a loaded model samples differently");
    }
}

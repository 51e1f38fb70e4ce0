//! Motion transfer on real data with exact ground truth: the KayKit knight and barbarian play
//! the same skeletal clips on two different bodies and topologies, so `knight_X` frame f and
//! `barbarian_X` frame f are a true pair.

use std::path::PathBuf;

use surfcap_formats::import::{ImportOptions, import};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_transfer::BodyParts;
use surfcap_transfer::motion_transfer::{MotionTransfer, PreparedSubject, TrainOptions};
use surfcap_transfer::part_stitching::average_overlaps;
use surfcap_transfer::pose_representation::align_to_reference;
use surfcap_transfer::transfer_model_file::{SubjectsMeta, read_model, write_model};

fn subject(character: &str, clips: &[&str]) -> Option<Subject> {
    let data = surfcap_testkit::shared_data()?;
    let paths: Vec<PathBuf> =
        clips.iter().map(|c| data.join("kaykit_adventurers").join(format!("{character}_{c}"))).collect();
    Some(import(&paths, &ImportOptions::default(), &NoProgress).unwrap().subject)
}

fn height(p: &[f32]) -> f64 {
    let (lo, hi) = surfcap_mesh::bounding_box(p);
    (hi[1] - lo[1]) as f64
}

/// RMS per-vertex distance after aligning `truth` onto `pred` (Procrustes, no scale).
fn rms_after_alignment(pred: &[f32], truth: &[f32]) -> f64 {
    let (aligned, _) = align_to_reference(pred, truth);
    let n = pred.len() / 3;
    let s: f64 = pred.iter().zip(&aligned).map(|(a, b)| ((a - b) as f64).powi(2)).sum();
    (s / n as f64).sqrt()
}

#[test]
fn knight_to_barbarian_walk_transfers_an_unseen_walk_within_a_few_percent_of_height() {
    let clips = ["Walking_A", "Running_A", "Walking_C"];
    let (Some(knight), Some(barbarian)) = (subject("knight", &clips), subject("barbarian", &clips)) else { return };
    // Train on Walking_A and Running_A with every frame paired to its twin.
    let train_seqs = [0usize, 1];
    let src = PreparedSubject::new(&knight, &train_seqs).unwrap();
    let tgt = PreparedSubject::new(&barbarian, &train_seqs).unwrap();
    let frames: Vec<usize> = train_seqs.iter().flat_map(|&s| knight.frame_index().range(s)).collect();
    let pairs: Vec<(usize, usize)> = frames.iter().map(|&g| (g, g)).collect();
    let sp = BodyParts::whole_body(knight.topology().n_vertices());
    let tp = BodyParts::whole_body(barbarian.topology().n_vertices());
    let (model, report) =
        MotionTransfer::train(&src, &sp, &frames, &tgt, &tp, &frames, &pairs, &TrainOptions::default()).unwrap();
    assert_eq!(report.pairs, pairs.len());
    assert!(report.parts[0].target_explained_variance > 0.95, "{:?}", report.parts[0]);

    // Transfer the unseen Walking_C and compare with the barbarian's own Walking_C.
    let (k, kseq) = knight.sequence("knight_Walking_C").unwrap();
    let (_, bseq) = barbarian.sequence("barbarian_Walking_C").unwrap();
    assert_eq!(k, 2);
    let source: Vec<&[f32]> = (0..kseq.n_frames()).map(|f| kseq.frame(f)).collect();
    let out = model.transfer(&source, |p| average_overlaps(&model.target.parts, p, false)).unwrap();
    assert_eq!(out.world.len(), kseq.n_frames());
    let h = height(bseq.frame(0));
    let errs: Vec<f64> =
        (0..bseq.n_frames()).map(|f| rms_after_alignment(&out.aligned[f], bseq.frame(f)) / h).collect();
    let mean = errs.iter().sum::<f64>() / errs.len() as f64;
    let worst = errs.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "knight -> barbarian Walking_C: RMS per-vertex error {:.2}% of height (worst frame {:.2}%)",
        100.0 * mean,
        100.0 * worst
    );
    assert!(mean < 0.03, "mean {mean}");
    assert!(out.world.iter().flatten().all(|v| v.is_finite()));

    // Saved and read back, the model predicts the same poses to the bit.
    let dir = tempfile::tempdir().unwrap();
    let meta = SubjectsMeta::new(&knight, &barbarian);
    write_model(dir.path(), &model, &meta, std::slice::from_ref(&tgt.reference)).unwrap();
    let saved = read_model(dir.path()).unwrap();
    assert_eq!(saved.subjects.source_mesh, meta.source_mesh);
    assert_eq!(saved.target_training.len(), 1);
    let again = saved.model.transfer(&source, |p| average_overlaps(&saved.model.target.parts, p, false)).unwrap();
    assert!(again.world == out.world, "a reloaded model transfers differently");
}

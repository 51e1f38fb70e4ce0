//! The tiled work on a tiny two-sequence tube: every stage run job by job through the store gives
//! the one-machine products to the bit, a job is skipped once done, a lost job is recomputed to
//! the same bytes, and bad requests are errors naming what was expected.

use std::path::Path;

use surfcap_builtin::{WormParams, worm_subject};
use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::{TableParams, transition_table};
use surfcap_tiles::tile_jobs::{JobOutcome, read_scale, run_job};
use surfcap_tiles::tile_merge::{merge, status};
use surfcap_tiles::tile_plan::{Stage, WorkParams, create_work, open_work};
use surfcap_tiles::tile_store::Matrix;
use surfcap_tiles::tile_verify::Depth;

fn tube() -> Subject {
    let a = worm_subject(&WormParams { rings: 8, segments: 6, frames: 23, seed: 1, ..Default::default() }).unwrap();
    let b = worm_subject(&WormParams { rings: 8, segments: 6, frames: 17, seed: 2, ..Default::default() }).unwrap();
    let nv = a.topology().n_vertices();
    let seqs = vec![
        Sequence::new("wave", nv, a.sequences()[0].positions().to_vec()).unwrap(),
        Sequence::new("coil", nv, b.sequences()[0].positions().to_vec()).unwrap(),
    ];
    Subject::new("tube", a.topology().clone(), seqs, 30.0, a.up_axis, a.units.clone()).unwrap()
}

fn params() -> WorkParams {
    WorkParams {
        metric: "deformation".into(),
        w: 0.01,
        l_min: 2,
        l_max: 5,
        slope: Some(3),
        alpha: Alpha::new(0.05).unwrap(),
        k: 4,
    }
}

fn run_stage(work: &Path, stage: Stage) -> Vec<JobOutcome> {
    let (plan, store, frames) = open_work(work).unwrap();
    (0..plan.jobs(stage)).map(|k| run_job(&store, &plan, &frames, stage, k, &NoProgress).unwrap()).collect()
}

#[test]
fn tiles_through_the_store_equal_the_one_machine_products_to_the_bit() {
    let dir = tempfile::tempdir().unwrap();
    let subject = tube();
    let cache = dir.path().join("tube.subject");
    surfcap_mesh::cache::write_cache(&cache, &subject, false, &NoProgress).unwrap();
    let work = dir.path().join("work");
    let plan = create_work(&cache, &work, 7, params()).unwrap();
    let n = subject.n_frames();
    assert_eq!(plan.jobs(Stage::Distances), 21, "6 blocks of 7 frames: 6 * 7 / 2 upper tiles");
    assert_eq!(plan.jobs(Stage::Table), 36);
    for stage in [Stage::Distances, Stage::Table, Stage::Scale] {
        let outcomes = run_stage(&work, stage);
        assert!(outcomes.iter().all(|o| matches!(o, JobOutcome::Done(_))), "{stage:?}");
    }
    let (plan, store, _) = open_work(&work).unwrap();
    let d = distance_matrix(&subject, &DistanceParams::default(), &NoProgress);
    let tiled = store.read_f64(Matrix::Distances, 0..n, 0..n).unwrap();
    assert!(tiled.iter().zip(&d.values).all(|(a, b)| a.to_bits() == b.to_bits()), "distances");
    let p = TableParams { l_min: 2, l_max: 5, slope: Some(3) };
    let t = transition_table(&d.values, subject.frame_index(), &p, &NoProgress).unwrap();
    let cost = store.read_f64(Matrix::TableCost, 0..n, 0..n).unwrap();
    assert!(cost.iter().zip(&t.cost).all(|(a, b)| a.to_bits() == b.to_bits()), "table costs");
    assert_eq!(store.read_u32(Matrix::TableLen, 0..n, 0..n).unwrap(), t.len);
    assert_eq!(store.read_u32(Matrix::TableLi, 0..n, 0..n).unwrap(), t.li);
    assert_eq!(store.read_u32(Matrix::TableLj, 0..n, 0..n).unwrap(), t.lj);
    // Algorithm 1's weights with the looping clips' wrap edges, as the one-machine pipeline has them.
    let mut w = surfcap_motion::edge_weights::edge_weights(&t, subject.frame_index(), params().alpha).unwrap();
    surfcap_motion::clip_loops::add_wrap_edges(&mut w, &surfcap_motion::clip_loops::clip_loops(&subject));
    assert_eq!(read_scale(&store).unwrap().d_scale.to_bits(), w.d_scale.to_bits(), "Algorithm 1's median");
    for stage in [Stage::Candidates, Stage::Paths] {
        run_stage(&work, stage);
    }
    let report = merge(&store, &plan).unwrap();
    let sparse =
        surfcap_motion::sparse_essential_graph::sparse_essential_graph(&w, subject.frame_index(), 4, &NoProgress);
    let costs = store.read_f64(Matrix::PathCosts, 0..n, 0..n).unwrap();
    assert!(costs.iter().zip(&sparse.costs).all(|(a, b)| a.to_bits() == b.to_bits()), "path costs");
    let edges = surfcap_mesh::npy::read_npy::<f64>(&work.join("graph_edges.npy")).unwrap();
    let expected: Vec<f64> = sparse.graph.edges().iter().flat_map(|e| [e.from as f64, e.to as f64, e.weight]).collect();
    assert_eq!(edges.data, expected, "the sparse essential graph");
    assert_eq!(report.graph_edges, sparse.graph.edges().len());
    assert!(report.graph_edges > 0);

    // Done jobs are skipped; a lost job (record and chunk gone) is recomputed to the same bytes.
    assert!(run_stage(&work, Stage::Distances).iter().all(|o| *o == JobOutcome::Skipped));
    let chunk = store.chunk_path(Matrix::Distances, 1, 3).unwrap();
    let before = std::fs::read(&chunk).unwrap();
    std::fs::remove_file(&chunk).unwrap();
    std::fs::remove_file(store.record_path(Stage::Distances, 8)).unwrap();
    let st = status(&store, &plan, Depth::Contents).stages;
    assert_eq!(st[0].missing, vec![8], "tile (1, 3) is job 8: six tiles in row 0, then (1, 1), (1, 2)");
    assert!(store.read_f64(Matrix::Distances, 0..n, 0..n).is_err(), "a region with a missing chunk is refused");
    let again = run_stage(&work, Stage::Distances);
    assert_eq!(again.iter().filter(|o| matches!(o, JobOutcome::Done(_))).count(), 1);
    assert_eq!(std::fs::read(&chunk).unwrap(), before);
    // A missing job is named by the merge.
    std::fs::remove_file(store.record_path(Stage::Paths, 2)).unwrap();
    let e = merge(&store, &plan).unwrap_err().to_string();
    assert!(e.contains("stage paths") && e.contains("job 2"), "{e}");

    // Bad requests.
    let (plan, store, frames) = open_work(&work).unwrap();
    let e = run_job(&store, &plan, &frames, Stage::Table, 36, &NoProgress).unwrap_err().to_string();
    assert!(e.contains("36") && e.contains("0..35"), "{e}");
    let other = WorkParams { k: 8, ..params() };
    let e = create_work(&cache, &work, 7, other).unwrap_err().to_string();
    assert!(e.contains("another subject or other parameters"), "{e}");
    assert!(create_work(&cache, &cache.join("inside"), 7, params()).is_err(), "never inside an input");
    // A plan whose alpha is not a positive number is refused when read, naming the file.
    let plan_file = work.join("plan.json");
    let text = std::fs::read_to_string(&plan_file).unwrap();
    let field = "\"alpha\": 0.05,";
    assert!(text.contains(field), "{text}");
    std::fs::write(&plan_file, text.replace(field, "\"alpha\": 0,")).unwrap();
    let e = open_work(&work).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains(&plan_file.display().to_string()) && e.contains("alpha 0: expected a positive number"), "{e}");
}

/// A clip authored as a loop (played out and back, so its last pose is one step from its first):
/// the `scale` stage finds it from the cached frames, the candidates add its wrap edge (its last
/// frame into its start) at the weight of a successive step, and the merged graph equals the
/// one-machine graph with the wrap edges (`Pipeline::loops()` and `edge_weights`) to the bit.
#[test]
fn a_looping_clips_wrap_edge_is_in_the_tiled_graph_as_in_the_one_machine_graph() {
    let dir = tempfile::tempdir().unwrap();
    let a = worm_subject(&WormParams { rings: 8, segments: 6, frames: 23, seed: 1, ..Default::default() }).unwrap();
    let b = worm_subject(&WormParams { rings: 8, segments: 6, frames: 10, seed: 2, ..Default::default() }).unwrap();
    let nv = a.topology().n_vertices();
    let coil = b.sequences()[0].positions();
    // Frames 0..9 then 8..1: 18 frames whose last is one step from the first.
    let out_and_back: Vec<f32> =
        (0..10).chain((1..9).rev()).flat_map(|f| coil[f * nv * 3..(f + 1) * nv * 3].iter().copied()).collect();
    let seqs = vec![
        Sequence::new("wave", nv, a.sequences()[0].positions().to_vec()).unwrap(),
        Sequence::new("coil", nv, out_and_back).unwrap(),
    ];
    let subject = Subject::new("tube", a.topology().clone(), seqs, 30.0, a.up_axis, a.units.clone()).unwrap();
    let loops = surfcap_motion::clip_loops::clip_loops(&subject);
    let (last, first) = (23 + 17, 23);
    assert!(loops.iter().any(|l| (l.last, l.first) == (last, first)), "the coil loops: {loops:?}");
    let cache = dir.path().join("tube.subject");
    surfcap_mesh::cache::write_cache(&cache, &subject, false, &NoProgress).unwrap();
    let work = dir.path().join("work");
    create_work(&cache, &work, 7, params()).unwrap();
    for stage in Stage::ALL {
        run_stage(&work, stage);
    }
    let (plan, store, _) = open_work(&work).unwrap();
    let scale = read_scale(&store).unwrap();
    let wraps: Vec<(u32, u32, &str, &str)> =
        scale.wrap_edges.iter().map(|w| (w.last, w.first, w.from.as_str(), w.to.as_str())).collect();
    let expected: Vec<(u32, u32)> = loops.iter().map(|l| (l.last, l.first)).collect();
    assert_eq!(wraps.iter().map(|w| (w.0, w.1)).collect::<Vec<_>>(), expected, "the loops of the subject");
    assert!(wraps.contains(&(last, first, "coil:17", "coil:0")), "{wraps:?}");
    merge(&store, &plan).unwrap();
    let d = distance_matrix(&subject, &DistanceParams::default(), &NoProgress);
    let t = transition_table(
        &d.values,
        subject.frame_index(),
        &TableParams { l_min: 2, l_max: 5, slope: Some(3) },
        &NoProgress,
    )
    .unwrap();
    let mut w = surfcap_motion::edge_weights::edge_weights(&t, subject.frame_index(), params().alpha).unwrap();
    let before = w.at(last as usize, first as usize);
    surfcap_motion::clip_loops::add_wrap_edges(&mut w, &loops);
    assert!(before != 0.05, "without the wrap, last -> first is an ordinary transition ({before})");
    let sparse =
        surfcap_motion::sparse_essential_graph::sparse_essential_graph(&w, subject.frame_index(), 4, &NoProgress);
    let edges = surfcap_mesh::npy::read_npy::<f64>(&work.join("graph_edges.npy")).unwrap();
    let one_machine: Vec<f64> =
        sparse.graph.edges().iter().flat_map(|e| [e.from as f64, e.to as f64, e.weight]).collect();
    assert_eq!(edges.data, one_machine, "the sparse essential graph with the wrap edge");
    let candidates = surfcap_tiles::graph_jobs::sparse_graph(&store, &plan).unwrap();
    let k = candidates.find(last as usize, first as usize).expect("the wrap edge is a candidate");
    assert_eq!(candidates.edges()[k].weight, 0.05, "a successive step's weight, alpha");
    let costs = store.read_f64(Matrix::PathCosts, 0..subject.n_frames(), 0..subject.n_frames()).unwrap();
    assert!(costs.iter().zip(&sparse.costs).all(|(a, b)| a.to_bits() == b.to_bits()), "path costs");
}

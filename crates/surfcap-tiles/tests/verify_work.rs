//! A work folder checked against its plan, on a tiny two-sequence tube (11 frames in tiles of 4:
//! 6 distance jobs, 9 table jobs): deleted, truncated, NaN-filled and folder-replaced chunks,
//! `zarr.json` of another shape or data type, records and chunks of another plan, and plans
//! edited by hand are each named with what was expected; a damaged job is computed again by
//! `run`, to the same bytes.

use std::path::{Path, PathBuf};

use surfcap_builtin::{WormParams, worm_subject};
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_tiles::tile_jobs::{JobOutcome, run_job};
use surfcap_tiles::tile_merge::{merge, status};
use surfcap_tiles::tile_plan::{Alpha, MAX_STAGE_JOBS, Plan, Stage, WorkParams, create_work, open_work};
use surfcap_tiles::tile_verify::Depth;

fn tube() -> Subject {
    let a = worm_subject(&WormParams { rings: 4, segments: 4, frames: 6, seed: 1, ..Default::default() }).unwrap();
    let b = worm_subject(&WormParams { rings: 4, segments: 4, frames: 5, seed: 2, ..Default::default() }).unwrap();
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
        l_max: 3,
        slope: Some(3),
        alpha: Alpha::new(0.05).unwrap(),
        k: 3,
    }
}

fn run_all(work: &Path) {
    let (plan, store, frames) = open_work(work).unwrap();
    for stage in Stage::ALL {
        for k in 0..plan.jobs(stage) {
            run_job(&store, &plan, &frames, stage, k, &NoProgress).unwrap();
        }
    }
}

/// A subject cache and a work folder with every job done (the other plan's folder when asked).
fn done(tile: usize, params: WorkParams) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("tube.subject");
    surfcap_mesh::cache::write_cache(&cache, &tube(), false, &NoProgress).unwrap();
    let work = dir.path().join("work");
    create_work(&cache, &work, tile, params).unwrap();
    run_all(&work);
    (dir, cache, work)
}

/// The problems `status` finds (contents checked), as text.
fn problems(work: &Path, depth: Depth) -> Vec<String> {
    let (plan, store, _) = open_work(work).unwrap();
    status(&store, &plan, depth).problems.iter().map(|p| p.to_string()).collect()
}

fn merge_error(work: &Path) -> String {
    let (plan, store, _) = open_work(work).unwrap();
    merge(&store, &plan).unwrap_err().to_string()
}

#[test]
fn a_clean_folder_has_no_problems_and_merges() {
    let (_d, _, work) = done(4, params());
    assert_eq!(problems(&work, Depth::Contents), Vec::<String>::new());
    let (plan, store, _) = open_work(&work).unwrap();
    assert_eq!(plan.jobs(Stage::Distances), 6);
    assert_eq!(plan.jobs(Stage::Table), 9);
    // Spans derived from a job index equal the listed tiles of the one-machine code.
    let listed = surfcap_geometry::distance_tiles::plan_distance_tiles(11, 4);
    assert_eq!((0..6).map(|k| plan.distance_span(k)).collect::<Vec<_>>(), listed);
    let listed = surfcap_motion::transition_tiles::plan_table_tiles(11, 4);
    assert_eq!((0..9).map(|k| plan.table_span(k)).collect::<Vec<_>>(), listed);
    merge(&store, &plan).unwrap();
    let rec = store.record(Stage::Distances, 1).unwrap().unwrap();
    assert_eq!(rec.plan, plan.hash, "a record carries its plan's hash");
    let files: Vec<&str> = rec.outputs.iter().map(|o| o.file.as_str()).collect();
    assert_eq!(files, ["distances.zarr/c/0/1", "distances.zarr/c/1/0"], "tile (0, 1) and its mirror");
    let bytes = std::fs::read(work.join(files[0])).unwrap();
    assert_eq!(rec.outputs[0].blake3, blake3::hash(&bytes).to_hex().to_string());
}

#[test]
fn a_deleted_chunk_is_named_and_computed_again_by_run() {
    let (_d, _, work) = done(4, params());
    let chunk = work.join("distances.zarr/c/0/1");
    let before = std::fs::read(&chunk).unwrap();
    std::fs::remove_file(&chunk).unwrap();
    let p = problems(&work, Depth::Sizes);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("distances.zarr/c/0/1: missing"), "{p:?}");
    let (plan, store, frames) = open_work(&work).unwrap();
    let st = status(&store, &plan, Depth::Contents);
    assert_eq!(st.stages[0].damaged, vec![1], "the job of tile (0, 1) is not done");
    assert_eq!(st.stages[0].done, 5);
    let e = merge_error(&work);
    assert!(e.contains("1 problem") && e.contains("distances.zarr/c/0/1: missing"), "{e}");
    // `run` computes the job again; the other jobs stay done.
    let out = run_job(&store, &plan, &frames, Stage::Distances, 1, &NoProgress).unwrap();
    assert!(matches!(out, JobOutcome::Done(_)));
    assert_eq!(std::fs::read(&chunk).unwrap(), before, "the same bytes");
    assert_eq!(run_job(&store, &plan, &frames, Stage::Distances, 2, &NoProgress).unwrap(), JobOutcome::Skipped);
    assert!(problems(&work, Depth::Contents).is_empty());
    merge(&store, &plan).unwrap();
}

#[test]
fn truncated_and_nan_filled_chunks_are_detected_and_computed_again() {
    let (_d, _, work) = done(4, params());
    let cost = work.join("table/cost.zarr/c/1/2");
    let dist = work.join("distances.zarr/c/2/2");
    let (cost_before, dist_before) = (std::fs::read(&cost).unwrap(), std::fs::read(&dist).unwrap());
    std::fs::write(&cost, &cost_before[..100]).unwrap();
    let nan: Vec<u8> = (0..dist_before.len()).map(|i| f64::NAN.to_le_bytes()[i % 8]).collect();
    std::fs::write(&dist, nan).unwrap();
    // Sizes alone see the truncation, not the NaN of the right size.
    let quick = problems(&work, Depth::Sizes);
    assert_eq!(quick.len(), 1, "{quick:?}");
    assert!(quick[0].contains("table/cost.zarr/c/1/2: 100 bytes: expected 128"), "{quick:?}");
    let full = problems(&work, Depth::Contents);
    assert_eq!(full.len(), 2, "{full:?}");
    assert!(full[0].starts_with("distances.zarr/c/2/2: content differs from its job record"), "{full:?}");
    let e = merge_error(&work);
    assert!(e.contains("2 problems") && e.contains("table/cost.zarr/c/1/2"), "{e}");
    run_all(&work);
    assert_eq!(std::fs::read(&cost).unwrap(), cost_before);
    assert_eq!(std::fs::read(&dist).unwrap(), dist_before);
    assert!(problems(&work, Depth::Contents).is_empty());
}

#[test]
fn a_folder_in_place_of_a_chunk_is_refused_by_name_and_left_alone() {
    let (_d, _, work) = done(4, params());
    let chunk = work.join("table/len.zarr/c/0/0");
    std::fs::remove_file(&chunk).unwrap();
    std::fs::create_dir(&chunk).unwrap();
    std::fs::write(chunk.join("user.txt"), "mine").unwrap();
    let p = problems(&work, Depth::Contents);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("table/len.zarr/c/0/0: a folder where a file of 64 bytes belongs"), "{p:?}");
    let (plan, store, frames) = open_work(&work).unwrap();
    let e = run_job(&store, &plan, &frames, Stage::Table, 0, &NoProgress).unwrap_err().to_string();
    assert!(e.contains("table/len.zarr/c/0/0: a folder"), "{e}");
    assert_eq!(std::fs::read_to_string(chunk.join("user.txt")).unwrap(), "mine", "nothing of the user's removed");
    assert!(merge_error(&work).contains("table/len.zarr/c/0/0"));
}

#[test]
fn zarr_json_of_another_shape_or_data_type_is_named() {
    let (_d, _, work) = done(4, params());
    let meta = work.join("distances.zarr/zarr.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    let shape = text.replace("11,\n    11\n", "12,\n    12\n");
    assert_ne!(shape, text, "{text}");
    std::fs::write(&meta, shape).unwrap();
    let len = work.join("table/len.zarr/zarr.json");
    let text = std::fs::read_to_string(&len).unwrap();
    assert!(text.contains("\"uint32\""), "{text}");
    std::fs::write(&len, text.replace("\"uint32\"", "\"float64\"")).unwrap();
    let p = problems(&work, Depth::Sizes);
    assert_eq!(p.len(), 2, "{p:?}");
    assert!(
        p[0].starts_with("distances.zarr/zarr.json: shape [12,12]") && p[0].contains("expected shape [11,11]"),
        "{p:?}"
    );
    assert!(p[1].starts_with("table/len.zarr/zarr.json: shape [11,11], data type \"float64\""), "{p:?}");
    assert!(p[1].contains("expected shape [11,11], data type \"uint32\""), "{p:?}");
    assert!(merge_error(&work).contains("distances.zarr/zarr.json"));
}

#[test]
fn records_and_chunks_of_another_plan_are_refused_by_name() {
    let (_d, _, work) = done(4, params());
    let (_o, _, other) = done(4, WorkParams { metric: "euclidean".into(), ..params() });
    let (_t, _, tiles3) = done(3, params());
    let plan = Plan::read(&work).unwrap();
    let other_plan = Plan::read(&other).unwrap();
    // A record of another plan.
    std::fs::copy(other.join("jobs/distances/0.json"), work.join("jobs/distances/0.json")).unwrap();
    // A chunk of another plan under this plan's record: its content differs.
    std::fs::copy(other.join("distances.zarr/c/1/1"), work.join("distances.zarr/c/1/1")).unwrap();
    // Chunks of a plan with smaller tiles: outside this plan's 3 x 3 grid.
    std::fs::create_dir_all(work.join("distances.zarr/c/3")).unwrap();
    std::fs::copy(tiles3.join("distances.zarr/c/3/3"), work.join("distances.zarr/c/3/3")).unwrap();
    let p = problems(&work, Depth::Contents);
    assert_eq!(p.len(), 3, "{p:?}");
    assert_eq!(
        p[0], "distances.zarr/c/3: not a row of this plan's 3 x 3 chunks (from another plan?)",
        "the arrays are checked first"
    );
    let foreign = format!(
        "jobs/distances/0.json: written for another plan (plan hash {}…, this plan {}…)",
        &other_plan.hash[..12],
        &plan.hash[..12]
    );
    assert!(p[1].starts_with(&foreign), "{p:?}");
    assert!(p[2].starts_with("distances.zarr/c/1/1: content differs from its job record"), "{p:?}");
    // `run` refuses the foreign record by name and leaves it; it computes the changed chunk again.
    let (plan, store, frames) = open_work(&work).unwrap();
    let e = run_job(&store, &plan, &frames, Stage::Distances, 0, &NoProgress).unwrap_err().to_string();
    assert!(e.contains(&foreign), "{e}");
    assert_eq!(
        std::fs::read(work.join("jobs/distances/0.json")).unwrap(),
        std::fs::read(other.join("jobs/distances/0.json")).unwrap()
    );
    let k = (0..plan.jobs(Stage::Distances)).find(|&k| plan.distance_tile(k) == (1, 1)).unwrap();
    assert!(matches!(run_job(&store, &plan, &frames, Stage::Distances, k, &NoProgress).unwrap(), JobOutcome::Done(_)));
    // A record moved to another job's place is refused too.
    std::fs::copy(work.join("jobs/table/1.json"), work.join("jobs/table/2.json")).unwrap();
    let e = merge_error(&work);
    assert!(e.contains("jobs/table/2.json: the record of job 1 of stage table: expected job 2 of stage table"), "{e}");
    assert!(e.contains("jobs/distances/0.json: written for another plan"), "{e}");
}

/// Sets `"field": old` to `"field": new` in `plan.json`.
fn edit_plan(work: &Path, old: &str, new: &str) -> String {
    let file = work.join("plan.json");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains(old), "{old} in {text}");
    std::fs::write(&file, text.replacen(old, new, 1)).unwrap();
    open_work(work).map(|_| ()).unwrap_err().to_string()
}

#[test]
fn edited_plans_are_refused_on_load_naming_the_field() {
    let (_d, _, work) = done(4, params());
    let plan_file = work.join("plan.json");
    let clean = std::fs::read(&plan_file).unwrap();
    let file = plan_file.display().to_string();
    let cases = [
        ("\"tile\": 4", "\"tile\": 0", "tile 0: expected 1 to 11 frames per tile side"),
        ("\"tile\": 4", "\"tile\": 1000000000000", "tile 1000000000000: expected 1 to 11"),
        ("\"tile\": 4", "\"tile\": 1e12", "not a surfcap tile plan"),
        ("\"metric\": \"deformation\"", "\"metric\": \"nope\"", "metric \"nope\": expected deformation"),
        ("\"l_max\": 3", "\"l_max\": 1", "l_min 2 l_max 1: expected 1 <= l_min <= l_max"),
        ("\"l_max\": 3", "\"l_max\": 4", "edited since it was planned"),
        (
            "\"jobs\": 9",
            "\"jobs\": 1000000000000",
            "stage table: 1000000000000 jobs: expected 9 for 11 frames in tiles of 4",
        ),
        ("\"tile\": 4", "\"tile\": 3", "stage distances: 6 jobs: expected 10 for 11 frames in tiles of 3"),
        ("\"k\": 3", "\"k\": 0", "k 0: expected at least 1"),
    ];
    for (old, new, expected) in cases {
        std::fs::write(&plan_file, &clean).unwrap();
        let e = edit_plan(&work, old, new);
        assert!(e.contains(&file) && e.contains(expected), "{new}: {e}");
    }
    // A consistent edit of tile and every job count is still another plan: its hash differs.
    std::fs::write(&plan_file, &clean).unwrap();
    let text = std::fs::read_to_string(&plan_file).unwrap();
    let text = text.replace("\"jobs\": 3\n", "\"jobs\": 2\n").replacen("\"jobs\": 6\n", "\"jobs\": 3\n", 1);
    let text = text.replacen("\"jobs\": 9\n", "\"jobs\": 4\n", 1).replacen("\"tile\": 4", "\"tile\": 6", 1);
    std::fs::write(&plan_file, text).unwrap();
    let e = open_work(&work).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("edited since it was planned"), "{e}");
}

#[test]
fn plans_of_too_many_jobs_are_refused_without_sizing_anything() {
    let (_d, _, work) = done(4, params());
    let clean = Plan::read(&work).unwrap();
    // 10^7 frames in tiles of 1: 10^14 table jobs, counted without listing them.
    let mut stamp = clean.subject.clone();
    stamp.frames = 10_000_000;
    let e = Plan::new(stamp.clone(), 1, params(), clean.job_memory_bytes.clone()).unwrap_err().to_string();
    assert!(e.contains(&format!("stage distances: 50000005000000 jobs: at most {MAX_STAGE_JOBS} per stage")), "{e}");
    // 2^40 frames in tiles of 1: the counts overflow.
    stamp.frames = 1 << 40;
    let e = Plan::new(stamp, 1, params(), clean.job_memory_bytes.clone()).unwrap_err().to_string();
    assert!(e.contains("the job counts overflow"), "{e}");
    // The spans are derived without listing every tile: the last tile of a large plan.
    let mut big = clean.subject.clone();
    big.frames = 100_000;
    let plan = Plan::new(big, 100, params(), clean.job_memory_bytes).unwrap();
    let last = plan.jobs(Stage::Distances) - 1;
    assert_eq!(plan.distance_tile(last), (999, 999));
    assert_eq!(plan.distance_span(1000).rows, 100..200, "row 0 holds 1000 tiles; job 1000 starts row 1");
    assert_eq!(plan.table_span(1001).cols, 100..200);
}

#[test]
fn a_job_refuses_to_compute_from_a_damaged_input() {
    let (_d, _, work) = done(4, params());
    // Table job (0, 1) reads the distance tiles (0, 0), (0, 1) and (1, 1) of its halo; damage (0, 1).
    let chunk = work.join("distances.zarr/c/0/1");
    let len = std::fs::metadata(&chunk).unwrap().len() as usize;
    std::fs::write(&chunk, (0..len).map(|i| f64::NAN.to_le_bytes()[i % 8]).collect::<Vec<u8>>()).unwrap();
    std::fs::remove_file(work.join("jobs/table/1.json")).unwrap();
    let (plan, store, frames) = open_work(&work).unwrap();
    let e = run_job(&store, &plan, &frames, Stage::Table, 1, &NoProgress).unwrap_err().to_string();
    assert!(
        e.contains("job 1 of stage table reads job 1 of stage distances, which is not done (distances.zarr/c/0/1: content differs"),
        "{e}"
    );
    assert!(!work.join("jobs/table/1.json").exists());
    run_all(&work);
    assert!(problems(&work, Depth::Contents).is_empty());
    merge(&store, &plan).unwrap();
}

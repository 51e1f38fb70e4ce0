//! Checks a work folder's files against its plan, so that a corrupt result is never taken as
//! done: every job record must be readable, written for this plan (its `plan` field is the
//! plan's content hash) and for its own job, and list exactly the files its job writes; every
//! file it lists must be a regular file of the recorded size and (at [`Depth::Contents`]) of the
//! recorded BLAKE3; every array's `zarr.json` must be the one this plan makes (shape, data type,
//! chunk shape), and no chunk may lie outside the plan's grid of tiles.
//!
//! A job is then in one of four states ([`JobState`]): not run (no record), done, damaged (its
//! own record, but an output missing, truncated or changed: `run` computes it again, over files
//! its record names as surfcap's), or refused (a record of another plan or another job, one that
//! cannot be read, or a folder or link where an output belongs: nothing surfcap may overwrite,
//! so it is named and left for the user to remove).
//!
//! Cost: [`Depth::Contents`] reads every byte the jobs wrote once (BLAKE3 runs at about 2 GB/s,
//! so the check costs about what reading the products costs: 0.4 to 0.6 s for the 155 MB of a
//! 2,006-frame plan in tiles of 256, on a loaded 2-core machine); [`Depth::Sizes`] reads only
//! the records and the files' metadata (0.01 to 0.14 s there).

use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::graph_jobs::{edges_file, tree_file};
use crate::tile_jobs::SCALE_FILE;
use crate::tile_plan::{Plan, Stage, short};
use crate::tile_store::{JobRecord, Matrix, Store, read_regular};

/// How deeply the outputs of a job are checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Records, and each output's kind (a regular file) and size.
    Sizes,
    /// Also each output's BLAKE3 against its record (reads every output).
    Contents,
}

/// Something wrong in a work folder: the file (relative to the work folder) and what was expected.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Problem {
    pub file: String,
    pub message: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.file, self.message)
    }
}

fn problem(file: &str, message: String) -> Problem {
    Problem { file: file.to_string(), message }
}

/// The state of one job.
#[derive(Debug, Clone, PartialEq)]
pub enum JobState {
    /// No record: the job has not run (or was interrupted before its record).
    NotRun,
    /// Its record and every output it lists check out.
    Done(JobRecord),
    /// Its own record, but outputs missing or changed: not done, `run` computes it again.
    Damaged(Vec<Problem>),
    /// A record or a file surfcap may not take as its own: `run` refuses the job by name.
    Refused(Problem),
}

/// The files job `index` of `stage` writes, relative to the work folder, with their size where
/// the plan fixes it (chunks).
pub fn expected_outputs(store: &Store, plan: &Plan, stage: Stage, index: usize) -> Vec<(String, Option<u64>)> {
    let chunk = |m: Matrix, a: usize, b: usize| (store.chunk_file(m, a, b), Some(store.chunk_bytes(m)));
    match stage {
        Stage::Distances => {
            let (a, b) = plan.distance_tile(index);
            let mut v = vec![chunk(Matrix::Distances, a, b)];
            if a != b {
                v.push(chunk(Matrix::Distances, b, a));
            }
            v
        }
        Stage::Table => {
            let (a, b) = plan.table_tile(index);
            [Matrix::TableLen, Matrix::TableLi, Matrix::TableLj, Matrix::TableCost]
                .into_iter()
                .map(|m| chunk(m, a, b))
                .collect()
        }
        Stage::Scale => vec![(SCALE_FILE.to_string(), None)],
        Stage::Candidates => vec![(edges_file(index), None)],
        Stage::Paths => {
            let mut v: Vec<_> = (0..plan.blocks()).map(|cj| chunk(Matrix::PathCosts, index, cj)).collect();
            v.push((tree_file(index), None));
            v
        }
    }
}

/// The record file of a job, relative to the work folder.
pub fn record_file(stage: Stage, index: usize) -> String {
    format!("jobs/{}/{index}.json", stage.name())
}

/// Checks job `index` of `stage` (an index below the stage's job count).
pub fn check_job(store: &Store, plan: &Plan, stage: Stage, index: usize, depth: Depth) -> JobState {
    let rel = record_file(stage, index);
    let bytes = match read_regular(&store.record_path(stage, index)) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return JobState::NotRun,
        Err(e) => {
            return JobState::Refused(problem(&rel, format!("cannot be read ({e}): remove it to run the job again")));
        }
    };
    let record: JobRecord = match serde_json::from_slice(&bytes) {
        Ok(r) => r,
        Err(e) => {
            return JobState::Refused(problem(&rel, format!("not a job record ({e}): delete it to run the job again")));
        }
    };
    if record.plan != plan.hash {
        return JobState::Refused(problem(
            &rel,
            format!(
                "written for another plan (plan hash {}…, this plan {}…): delete it to run the job again",
                short(&record.plan),
                short(&plan.hash)
            ),
        ));
    }
    if record.stage != stage || record.index != index {
        return JobState::Refused(problem(
            &rel,
            format!(
                "the record of job {} of stage {}: expected job {index} of stage {}; delete it to run the job again",
                record.index,
                record.stage.name(),
                stage.name()
            ),
        ));
    }
    let expected = expected_outputs(store, plan, stage, index);
    let listed: Vec<&str> = record.outputs.iter().map(|o| o.file.as_str()).collect();
    let wanted: Vec<&str> = expected.iter().map(|(f, _)| f.as_str()).collect();
    if listed != wanted {
        return JobState::Refused(problem(
            &rel,
            format!(
                "lists the files [{}]: expected [{}]; delete it to run the job again",
                listed.join(", "),
                wanted.join(", ")
            ),
        ));
    }
    let mut damaged = Vec::new();
    for (out, (_, size)) in record.outputs.iter().zip(&expected) {
        if let Some(size) = size
            && out.bytes != *size
        {
            return JobState::Refused(problem(
                &rel,
                format!("records {} as {} bytes: expected {size}; delete it to run the job again", out.file, out.bytes),
            ));
        }
        match check_output(store.root(), &out.file, out.bytes, &out.blake3, depth) {
            Ok(None) => {}
            Ok(Some(p)) => damaged.push(p),
            Err(p) => return JobState::Refused(p),
        }
    }
    if damaged.is_empty() { JobState::Done(record) } else { JobState::Damaged(damaged) }
}

/// Checks one output against its record: `Ok(None)` when it matches, `Ok(Some(_))` when it is
/// missing or its bytes differ (surfcap may rewrite it), `Err(_)` when something other than a
/// regular file is at its place (surfcap may not).
fn check_output(
    root: &Path,
    file: &str,
    bytes: u64,
    blake3: &str,
    depth: Depth,
) -> std::result::Result<Option<Problem>, Problem> {
    let path = root.join(file);
    let md = match std::fs::symlink_metadata(&path) {
        Ok(md) => md,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Some(problem(file, format!("missing: expected {bytes} bytes (its job will run again)"))));
        }
        Err(e) => return Err(problem(file, format!("cannot be read ({e})"))),
    };
    if !md.is_file() {
        let what = if md.is_dir() {
            "a folder"
        } else if md.file_type().is_symlink() {
            "a symbolic link"
        } else {
            "not a regular file"
        };
        return Err(problem(
            file,
            format!("{what} where a file of {bytes} bytes belongs: remove it, then run its job again"),
        ));
    }
    if md.len() != bytes {
        return Ok(Some(problem(
            file,
            format!("{} bytes: expected {bytes} (truncated or replaced; its job will run again)", md.len()),
        )));
    }
    if depth == Depth::Contents {
        let data = match read_regular(&path) {
            Ok(d) => d,
            Err(e) => return Err(problem(file, format!("cannot be read ({e})"))),
        };
        let got = blake3::hash(&data).to_hex().to_string();
        if got != blake3 {
            return Ok(Some(problem(
                file,
                format!(
                    "content differs from its job record (BLAKE3 {}…, recorded {}…): damaged, or written by another plan (its job will run again)",
                    short(&got),
                    short(blake3)
                ),
            )));
        }
    }
    Ok(None)
}

/// `shape [..], data type .., chunks [..]` of an array's metadata, for messages.
fn describe(meta: &serde_json::Value) -> String {
    let chunks = &meta["chunk_grid"]["configuration"]["chunk_shape"];
    format!("shape {}, data type {}, chunks {}", meta["shape"], meta["data_type"], chunks)
}

/// Checks every array's `zarr.json` against the plan, and that no chunk lies outside the
/// plan's grid.
pub fn check_arrays(store: &Store, plan: &Plan) -> Vec<Problem> {
    let mut out = Vec::new();
    let nb = plan.blocks();
    for m in Matrix::ALL {
        let rel = format!("{}/zarr.json", m.dir());
        let expected = match store.expected_metadata(m) {
            Ok(v) => v,
            Err(e) => {
                out.push(problem(&rel, e.to_string()));
                continue;
            }
        };
        let found = read_regular(&store.root().join(&rel))
            .map_err(|e| e.to_string())
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).map_err(|e| format!("not JSON ({e})")));
        match found {
            Err(e) => out.push(problem(&rel, format!("{e}: expected the array's metadata ({})", describe(&expected)))),
            Ok(v) if v != expected => {
                let (got, want) = (describe(&v), describe(&expected));
                let message = if got != want {
                    format!("{got}: expected {want} (plan again into a new folder)")
                } else {
                    format!("metadata other than this plan's (codecs, fill value or names): expected {want}")
                };
                out.push(problem(&rel, message));
            }
            Ok(_) => {}
        }
        out.extend(stray_chunks(store.root(), m, nb));
    }
    out
}

/// Entries of `m`'s chunk folder outside the nb x nb grid (chunks of a plan with other tiles).
fn stray_chunks(root: &Path, m: Matrix, nb: usize) -> Vec<Problem> {
    let mut out = Vec::new();
    let in_grid = |name: &std::ffi::OsStr| name.to_str().and_then(|s| s.parse::<usize>().ok()).is_some_and(|i| i < nb);
    let c = format!("{}/c", m.dir());
    let Ok(rows) = std::fs::read_dir(root.join(&c)) else { return out };
    for row in rows.flatten() {
        let name = row.file_name();
        let rel = format!("{c}/{}", name.to_string_lossy());
        let is_dir = row.file_type().is_ok_and(|t| t.is_dir());
        if !in_grid(&name) || !is_dir {
            out.push(problem(&rel, format!("not a row of this plan's {nb} x {nb} chunks (from another plan?)")));
            continue;
        }
        let Ok(cols) = std::fs::read_dir(row.path()) else { continue };
        for col in cols.flatten() {
            let name = col.file_name();
            // Temporaries of a write in progress are the atomic writer's, not chunks.
            if name.to_string_lossy().starts_with('.') {
                continue;
            }
            if !in_grid(&name) {
                out.push(problem(
                    &format!("{rel}/{}", name.to_string_lossy()),
                    format!("not a chunk of this plan's {nb} x {nb} chunks (from another plan?)"),
                ));
            }
        }
    }
    out
}

/// Done, not run and damaged jobs of one stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageCheck {
    pub stage: Stage,
    pub jobs: usize,
    pub done: usize,
    /// Jobs with no record.
    pub missing: Vec<usize>,
    /// Jobs with a record but problems (damaged outputs, or refused).
    pub damaged: Vec<usize>,
}

/// What [`check_work`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkCheck {
    pub stages: Vec<StageCheck>,
    /// Everything wrong, in stage and job order (the arrays' metadata first).
    pub problems: Vec<Problem>,
    /// The records of the done jobs, per stage.
    #[serde(skip)]
    pub records: Vec<Vec<JobRecord>>,
}

/// Checks every array and every job of the plan. Jobs are checked in parallel; the result does
/// not depend on the thread count.
pub fn check_work(store: &Store, plan: &Plan, depth: Depth) -> WorkCheck {
    let mut problems = check_arrays(store, plan);
    let mut stages = Vec::new();
    let mut records = Vec::new();
    for s in &plan.stages {
        let states: Vec<JobState> =
            (0..s.jobs).into_par_iter().map(|k| check_job(store, plan, s.name, k, depth)).collect();
        let (mut missing, mut damaged, mut done) = (Vec::new(), Vec::new(), Vec::new());
        for (k, state) in states.into_iter().enumerate() {
            match state {
                JobState::NotRun => missing.push(k),
                JobState::Done(r) => done.push(r),
                JobState::Damaged(p) => {
                    damaged.push(k);
                    problems.extend(p);
                }
                JobState::Refused(p) => {
                    damaged.push(k);
                    problems.push(p);
                }
            }
        }
        stages.push(StageCheck { stage: s.name, jobs: s.jobs, done: done.len(), missing, damaged });
        records.push(done);
    }
    WorkCheck { stages, problems, records }
}

/// Index of the `distances` job of tile (a, b), a <= b < blocks (the inverse of
/// [`Plan::distance_tile`]).
fn distance_job(nb: usize, a: usize, b: usize) -> usize {
    a * nb - a * a.saturating_sub(1) / 2 + (b - a)
}

/// The jobs of earlier stages whose outputs job `index` of `stage` reads.
pub fn input_jobs(plan: &Plan, stage: Stage, index: usize) -> Vec<(Stage, usize)> {
    let nb = plan.blocks();
    let t = plan.tile;
    match stage {
        Stage::Distances => Vec::new(),
        Stage::Table => {
            let (hr, hc) = plan.table_span(index).halo(plan.frames(), plan.params.l_max);
            let mut v = Vec::new();
            for x in hr.start / t..hr.end.div_ceil(t) {
                for y in hc.start / t..hc.end.div_ceil(t) {
                    v.push((Stage::Distances, distance_job(nb, x.min(y), x.max(y))));
                }
            }
            v.sort_unstable_by_key(|&(_, k)| k);
            v.dedup();
            v
        }
        Stage::Scale => (0..plan.jobs(Stage::Table)).map(|k| (Stage::Table, k)).collect(),
        Stage::Candidates => {
            let mut v: Vec<_> = (0..nb).map(|c| (Stage::Table, index * nb + c)).collect();
            v.push((Stage::Scale, 0));
            v
        }
        Stage::Paths => (0..plan.jobs(Stage::Candidates)).map(|k| (Stage::Candidates, k)).collect(),
    }
}

/// Checks (contents included) that every job whose outputs job `index` of `stage` reads is
/// done, so a job never computes from a missing, damaged or foreign input: the first that is
/// not is named.
pub fn check_inputs(store: &Store, plan: &Plan, stage: Stage, index: usize) -> crate::Result<()> {
    for (s, k) in input_jobs(plan, stage, index) {
        let why = match check_job(store, plan, s, k, Depth::Contents) {
            JobState::Done(_) => continue,
            JobState::NotRun => "not run".to_string(),
            JobState::Damaged(p) => p.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("; "),
            JobState::Refused(p) => p.to_string(),
        };
        return Err(crate::Error::Job(format!(
            "{}: job {index} of stage {} reads job {k} of stage {}, which is not done ({why}): run the earlier stage's jobs first",
            store.root().display(),
            stage.name(),
            s.name()
        )));
    }
    Ok(())
}

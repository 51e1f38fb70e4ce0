//! One job of one stage of a work folder (see `tile_plan.rs` for the stages). A job reads only
//! what its tile needs (its frames from the subject cache, its halo of distances, its rows of
//! the table), writes its results atomically and then its record; a job whose record is present
//! is skipped, so rerunning a stage after an interruption or a failure computes only what is
//! missing, and computing a job twice writes the same bytes.

use std::time::Instant;

use serde::{Deserialize, Serialize};
use surfcap_geometry::distance_matrix::{DistanceParams, SLAB_BYTES};
use surfcap_geometry::distance_tiles::{PoseFrames, distance_tile};
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::Progress;
use surfcap_mesh::cache::CachedFrames;
use surfcap_motion::transition_table::{SegmentRoom, TableParams};
use surfcap_motion::transition_tiles::{DistanceBlock, transition_tile};

use crate::cost_median::finite_cost_median;
use crate::error::{Error, Result};
use crate::tile_plan::{Plan, Stage};
use crate::tile_store::{JobRecord, Matrix, OutputHash, Store};
use crate::tile_verify::JobState;

/// What running a job did.
#[derive(Debug, Clone, PartialEq)]
pub enum JobOutcome {
    /// Its record was already there: nothing was computed.
    Skipped,
    /// Computed now.
    Done(JobRecord),
}

/// The frames of a tile, read from the subject cache.
struct LoadedFrames {
    ids: Vec<usize>,
    data: Vec<Vec<f32>>,
}

impl PoseFrames for LoadedFrames {
    fn pose(&self, g: usize) -> &[f32] {
        &self.data[self.ids.binary_search(&g).expect("a frame of the tile")]
    }
}

/// What the `scale` stage writes: Algorithm 1's median and the looping clips' wrap edges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scale {
    /// The median of the finite transition costs (1 when there are none or it is 0).
    pub d_scale: f64,
    /// The wrap edge of every clip authored as a loop (`surfcap_motion::clip_loops`: its last
    /// pose as close to its first as its own successive frames are), last frame -> first frame
    /// played (global frames): the candidates give it the weight of a successive step, as the
    /// one-machine graph does (`Pipeline::edge_weights`).
    pub wrap_edges: Vec<WrapEdge>,
}

/// A looping clip's wrap edge, global frames, with their `sequence:frame` names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrapEdge {
    pub last: u32,
    pub first: u32,
    pub from: String,
    pub to: String,
}

/// Peak resident memory of this process so far (Linux `VmHWM`), bytes; 0 where unknown.
pub fn peak_resident_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// The name of the pose-distance kernel this process uses.
pub fn kernel_name() -> String {
    surfcap_geometry::pose_distance::kernel_name().to_string()
}

/// The distance parameters of a plan.
pub fn distance_params(plan: &Plan) -> Result<DistanceParams> {
    let metric = PoseMetric::parse(&plan.params.metric).ok_or_else(|| {
        Error::Job(format!(
            "metric {:?} in the plan: expected deformation, deformation-log, deformation-literal or euclidean",
            plan.params.metric
        ))
    })?;
    Ok(DistanceParams { metric, w: plan.params.w, vertex_weights: None })
}

/// The table parameters of a plan.
pub fn table_params(plan: &Plan) -> TableParams {
    TableParams { l_min: plan.params.l_min, l_max: plan.params.l_max, slope: plan.params.slope }
}

/// Runs job `index` of `stage` unless it is done: its record is there, written for this plan,
/// and every output it lists has its size and content hash. A job whose outputs are missing or
/// damaged is computed again (its files are surfcap's, named by its own record); a record that
/// cannot be read, or was written for another plan or another job, is refused by name and left
/// as it is (`tile_verify.rs`). Every job of an earlier stage whose outputs it reads must be
/// done (contents checked), so a result is never computed from a damaged or foreign input.
pub fn run_job(
    store: &Store,
    plan: &Plan,
    subject: &CachedFrames,
    stage: Stage,
    index: usize,
    progress: &dyn Progress,
) -> Result<JobOutcome> {
    plan.check_job(stage, index)?;
    match crate::tile_verify::check_job(store, plan, stage, index, crate::tile_verify::Depth::Contents) {
        JobState::Done(_) => return Ok(JobOutcome::Skipped),
        JobState::NotRun | JobState::Damaged(_) => {}
        JobState::Refused(problem) => {
            return Err(Error::Damaged { work: store.root().to_path_buf(), problems: vec![problem] });
        }
    }
    crate::tile_verify::check_inputs(store, plan, stage, index)?;
    let start = Instant::now();
    let (span, kernel, details, outputs) = match stage {
        Stage::Distances => distances_job(store, plan, subject, index, progress)?,
        Stage::Table => table_job(store, plan, subject, index, progress)?,
        Stage::Scale => scale_job(store, plan, subject)?,
        Stage::Candidates | Stage::Paths => crate::graph_jobs::run(store, plan, subject, stage, index, progress)?,
    };
    let record = JobRecord {
        plan: plan.hash.clone(),
        stage,
        index,
        span,
        kernel,
        seconds: start.elapsed().as_secs_f64(),
        peak_bytes: peak_resident_bytes(),
        details,
        outputs,
    };
    store.write_record(&record)?;
    Ok(JobOutcome::Done(record))
}

/// What a job reports: its span in the user's terms, the distance kernel (or empty), details,
/// the files it wrote.
pub(crate) type JobResult = (String, String, serde_json::Value, Vec<OutputHash>);

/// Frames `r` as `sequence:frame .. sequence:frame`.
pub(crate) fn frames_text(subject: &CachedFrames, r: &std::ops::Range<usize>) -> String {
    if r.is_empty() {
        return "no frames".into();
    }
    format!("{} .. {}", subject.index.label(r.start), subject.index.label(r.end - 1))
}

fn distances_job(
    store: &Store,
    plan: &Plan,
    subject: &CachedFrames,
    index: usize,
    progress: &dyn Progress,
) -> Result<JobResult> {
    let span = plan.distance_span(index);
    let params = distance_params(plan)?;
    let ids = span.frames();
    let (ids, data): (Vec<usize>, Vec<Vec<f32>>) = subject.read(&ids)?.into_iter().unzip();
    let frames = LoadedFrames { ids, data };
    let t = distance_tile(&frames, subject.topology.triangles(), subject.up_axis, &span, &params, SLAB_BYTES, progress);
    let (ci, cj) = (span.rows.start / plan.tile, span.cols.start / plan.tile);
    let (nr, nc) = (span.rows.len(), span.cols.len());
    let mut outputs = vec![store.write_chunk_f64(Matrix::Distances, ci, cj, nr, nc, &t.values)?];
    if ci != cj {
        let mut mirror = vec![0.0; nr * nc];
        for r in 0..nr {
            for c in 0..nc {
                mirror[c * nr + r] = t.values[r * nc + c];
            }
        }
        outputs.push(store.write_chunk_f64(Matrix::Distances, cj, ci, nc, nr, &mirror)?);
    }
    let text = format!("rows {} x columns {}", frames_text(subject, &span.rows), frames_text(subject, &span.cols));
    let details = serde_json::json!({
        "pairs": span.pairs(),
        "triangle_pairs": span.pairs() * subject.topology.n_triangles(),
        "max_skipped_triangles": t.max_skipped_triangles,
    });
    Ok((text, kernel_name(), details, outputs))
}

fn table_job(
    store: &Store,
    plan: &Plan,
    subject: &CachedFrames,
    index: usize,
    progress: &dyn Progress,
) -> Result<JobResult> {
    let span = plan.table_span(index);
    let p = table_params(plan);
    let n = plan.frames();
    let (hr, hc) = span.halo(n, p.l_max);
    let values = store.read_f64(Matrix::Distances, hr.clone(), hc.clone())?;
    let block = DistanceBlock { rows: hr, cols: hc, values: &values };
    block.check()?;
    let after = SegmentRoom::new(&subject.index).after;
    let t = transition_tile(&block, &after, &p, &span, progress)?;
    let (ci, cj) = (span.rows.start / plan.tile, span.cols.start / plan.tile);
    let (nr, nc) = (span.rows.len(), span.cols.len());
    let outputs = vec![
        store.write_chunk_u32(Matrix::TableLen, ci, cj, nr, nc, &t.len)?,
        store.write_chunk_u32(Matrix::TableLi, ci, cj, nr, nc, &t.li)?,
        store.write_chunk_u32(Matrix::TableLj, ci, cj, nr, nc, &t.lj)?,
        store.write_chunk_f64(Matrix::TableCost, ci, cj, nr, nc, &t.cost)?,
    ];
    let text = format!("sources {} x ends {}", frames_text(subject, &span.rows), frames_text(subject, &span.cols));
    let finite = t.cost.iter().filter(|c| c.is_finite()).count();
    Ok((text, String::new(), serde_json::json!({ "pairs": nr * nc, "finite": finite }), outputs))
}

/// The looping clips of the subject's frames (read from the cache a few at a time), as
/// `Pipeline::loops()` finds them on the subject.
fn wrap_edges(subject: &CachedFrames) -> Result<Vec<WrapEdge>> {
    let loops = surfcap_motion::clip_loops::clip_loops_streamed(&subject.index, subject.up_axis, |g| {
        subject.read(&[g]).map(|mut f| f.pop().map(|(_, p)| p).unwrap_or_default())
    })?;
    Ok(loops
        .iter()
        .map(|l| WrapEdge {
            last: l.last,
            first: l.first,
            from: subject.index.label(l.last as usize),
            to: subject.index.label(l.first as usize),
        })
        .collect())
}

fn scale_job(store: &Store, plan: &Plan, subject: &CachedFrames) -> Result<JobResult> {
    let n = plan.frames();
    let blocks: Vec<std::ops::Range<usize>> = (0..plan.jobs(Stage::Candidates)).map(|k| plan.row_block(k)).collect();
    let d_scale = finite_cost_median(|visit| {
        for rows in &blocks {
            let v = store.read_f64(Matrix::TableCost, rows.clone(), 0..n)?;
            visit(&v);
        }
        Ok::<(), Error>(())
    })?;
    let wrap_edges = wrap_edges(subject)?;
    let loops = wrap_edges.len();
    let scale = Scale { d_scale, wrap_edges };
    let bytes = serde_json::to_vec_pretty(&scale).expect("plain data");
    let outputs = vec![store.write_file(SCALE_FILE, &bytes)?];
    Ok((
        "the whole table; every frame for the looping clips".into(),
        String::new(),
        serde_json::json!({ "d_scale": d_scale, "looping_clips": loops }),
        outputs,
    ))
}

/// The file of the `scale` stage's result.
pub const SCALE_FILE: &str = "scale.json";

/// Reads the `scale` stage's result.
pub fn read_scale(store: &Store) -> Result<Scale> {
    let p = store.file(SCALE_FILE);
    let bytes = crate::tile_store::read_regular(&p)
        .map_err(|e| Error::Job(format!("{}: {e}: run the scale stage first", p.display())))?;
    let scale: Scale = serde_json::from_slice(&bytes)
        .map_err(|e| Error::Plan { path: p.clone(), message: format!("damaged ({e})") })?;
    if !(scale.d_scale.is_finite() && scale.d_scale > 0.0) {
        return Err(Error::Plan {
            path: p,
            message: format!("d_scale {}: expected a finite median > 0", scale.d_scale),
        });
    }
    if let Some(w) = scale.wrap_edges.iter().find(|w| w.first >= w.last) {
        return Err(Error::Plan {
            path: p,
            message: format!(
                "wrap edge {} -> {}: expected a clip's last frame back to an earlier frame, its start",
                w.last, w.first
            ),
        });
    }
    Ok(scale)
}

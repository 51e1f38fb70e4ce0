//! The status of a work folder and its merge: every array, record and output is checked against
//! the plan (`tile_verify.rs`); once every job of every stage is done and nothing is wrong, the
//! records are checked (one distance kernel throughout: kernels differ in the last bits) and the
//! merged products written: `merge.json` (per stage the jobs' time and peak memory, the kernel,
//! the median scale) and the sparse essential graph's edges, the union of the trees of the
//! `paths` stage (`graph_edges.npy`). The distance matrix, the table and the path costs stay
//! in their Zarr arrays, whose chunks are already the merged matrices.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::tile_plan::{Plan, Stage};
use crate::tile_store::Store;
use crate::tile_verify::{Depth, WorkCheck, check_work};

/// The status of every stage of the plan, every job and array checked against the plan
/// (`tile_verify.rs`): done, missing and damaged jobs, and every problem found.
pub fn status(store: &Store, plan: &Plan, depth: Depth) -> WorkCheck {
    check_work(store, plan, depth)
}

/// Per stage, what its jobs cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageCost {
    pub stage: Stage,
    pub jobs: usize,
    /// Sum of the jobs' wall times, seconds.
    pub seconds: f64,
    pub slowest_job_seconds: f64,
    /// Largest peak resident memory of a process that ran one of its jobs, bytes.
    pub peak_bytes: u64,
}

/// What `merge` wrote (`merge.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MergeReport {
    pub frames: usize,
    pub tile: usize,
    pub kernel: String,
    pub d_scale: f64,
    pub stages: Vec<StageCost>,
    /// Edges of the sparse essential graph (`graph_edges.npy`: from, to, weight).
    pub graph_edges: usize,
}

/// Checks every array, record and output against the plan (contents included), refuses any
/// problem and any job not done by name, and writes the merged products.
pub fn merge(store: &Store, plan: &Plan) -> Result<MergeReport> {
    let check = check_work(store, plan, Depth::Contents);
    if !check.problems.is_empty() {
        return Err(Error::Damaged { work: store.root().to_path_buf(), problems: check.problems });
    }
    for st in &check.stages {
        if let Some(&first) = st.missing.first() {
            return Err(Error::Missing {
                stage: st.stage.name(),
                count: st.missing.len(),
                jobs: st.jobs,
                first: format!("job {first}"),
            });
        }
    }
    let mut stages = Vec::new();
    let mut kernel = String::new();
    for (s, recs) in plan.stages.iter().zip(check.records) {
        if s.name == Stage::Distances {
            let mut kernels: Vec<&str> = recs.iter().map(|r| r.kernel.as_str()).collect();
            kernels.sort_unstable();
            kernels.dedup();
            if kernels.len() > 1 {
                let by: Vec<String> = kernels
                    .iter()
                    .map(|k| {
                        let first = recs.iter().find(|r| r.kernel == *k).map_or(0, |r| r.index);
                        format!("{k} (job {first}...)")
                    })
                    .collect();
                return Err(Error::Mixed(format!(
                    "distance tiles were computed by different kernels: {}; results differ in the last bits: rerun the jobs of one kernel on machines of the other (delete their records in jobs/distances/)",
                    by.join(", ")
                )));
            }
            kernel = kernels.first().map_or(String::new(), |k| k.to_string());
        }
        stages.push(StageCost {
            stage: s.name,
            jobs: recs.len(),
            seconds: recs.iter().map(|r| r.seconds).sum(),
            slowest_job_seconds: recs.iter().map(|r| r.seconds).fold(0.0, f64::max),
            peak_bytes: recs.iter().map(|r| r.peak_bytes).max().unwrap_or(0),
        });
    }
    let d_scale = crate::tile_jobs::read_scale(store)?.d_scale;
    let graph = crate::graph_jobs::merged_graph(store, plan)?;
    let flat: Vec<f64> = graph.edges().iter().flat_map(|e| [e.from as f64, e.to as f64, e.weight]).collect();
    let graph_edges = graph.edges().len();
    surfcap_mesh::atomic::write_file(&store.file("graph_edges.npy"), |w| {
        surfcap_mesh::npy::write_npy(w, &[graph_edges, 3], &flat)
    })?;
    let report = MergeReport { frames: plan.frames(), tile: plan.tile, kernel, d_scale, stages, graph_edges };
    let bytes = serde_json::to_vec_pretty(&report).expect("plain data");
    surfcap_mesh::atomic::write_file(&store.file("merge.json"), |w| w.write_all(&bytes))?;
    Ok(report)
}

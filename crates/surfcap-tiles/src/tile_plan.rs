//! The plan of a work folder (`plan.json`): the subject, the parameters, and per stage its number
//! of jobs. A job's span is derived from (frames, tile) by the same functions the one-machine
//! pipeline uses, so the plan is small and a job index is all a worker needs.
//!
//! Stages, in order (each needs every job of the ones before):
//! 1. `distances`: the upper-triangle tiles of the pose distance matrix (`distance_tiles.rs`);
//! 2. `table`: every tile of the transition table, each reading its halo of distances
//!    (`transition_tiles.rs`);
//! 3. `scale`: one job, the median of the table's finite costs (Algorithm 1 divides D by it);
//! 4. `candidates`: per block of source rows, each frame's k cheapest transitions and its
//!    original edge (`sparse_essential_graph.rs`);
//! 5. `paths`: per block of source rows, the shortest-path trees on the sparse graph.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use surfcap_geometry::distance_tiles::{TileSpan, plan_distance_tiles};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_tiles::{TableSpan, plan_table_tiles};

use crate::error::{Error, Result};

const FORMAT: &str = "surfcap-tiles";
const VERSION: u32 = 1;
/// The marker kind of a work folder.
pub const WORK_KIND: &str = "tile-work";

/// The stages of the work, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Distances,
    Table,
    Scale,
    Candidates,
    Paths,
}

impl Stage {
    pub const ALL: [Stage; 5] = [Stage::Distances, Stage::Table, Stage::Scale, Stage::Candidates, Stage::Paths];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Distances => "distances",
            Stage::Table => "table",
            Stage::Scale => "scale",
            Stage::Candidates => "candidates",
            Stage::Paths => "paths",
        }
    }

    pub fn parse(s: &str) -> Result<Stage> {
        Stage::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
            Error::Job(format!("stage {s:?}: expected one of distances, table, scale, candidates, paths"))
        })
    }
}

/// The parameters of the products (as the one-machine commands take them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkParams {
    /// Pose metric name (`deformation`, `deformation-log`, `euclidean`).
    pub metric: String,
    /// Stretch weight w of eq. 2.13.
    pub w: f64,
    pub l_min: usize,
    pub l_max: usize,
    /// Slope constraint p of eq. 2.53 (`None`: unconstrained).
    pub slope: Option<usize>,
    /// Tolerance alpha of Algorithm 1 (a plan whose alpha is not > 0 is refused when read).
    pub alpha: Alpha,
    /// Transitions kept per frame by the sparse graph.
    pub k: usize,
}

/// What a plan knows of its subject, to refuse a subject changed since planning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubjectStamp {
    pub path: PathBuf,
    pub name: String,
    pub frames: usize,
    pub vertices: usize,
    pub triangles: usize,
    /// BLAKE3 of `subject.json` and `faces.npy`, and the sizes of the position files.
    pub fingerprint: String,
}

/// Jobs of one stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StagePlan {
    pub name: Stage,
    pub jobs: usize,
}

/// A work folder's plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub format: String,
    pub version: u32,
    pub subject: SubjectStamp,
    /// Frames per side of a tile (and per block of source rows).
    pub tile: usize,
    pub params: WorkParams,
    pub stages: Vec<StagePlan>,
    /// Bytes of memory a job of each stage holds at most (estimated from its tile).
    pub job_memory_bytes: Vec<(Stage, usize)>,
}

impl Plan {
    pub fn new(subject: SubjectStamp, tile: usize, params: WorkParams, job_memory_bytes: Vec<(Stage, usize)>) -> Plan {
        let n = subject.frames;
        let tile = tile.max(1);
        let rows = n.div_ceil(tile);
        let stages = vec![
            StagePlan { name: Stage::Distances, jobs: plan_distance_tiles(n, tile).len() },
            StagePlan { name: Stage::Table, jobs: plan_table_tiles(n, tile).len() },
            StagePlan { name: Stage::Scale, jobs: 1 },
            StagePlan { name: Stage::Candidates, jobs: rows },
            StagePlan { name: Stage::Paths, jobs: rows },
        ];
        Plan { format: FORMAT.into(), version: VERSION, subject, tile, params, stages, job_memory_bytes }
    }

    pub fn frames(&self) -> usize {
        self.subject.frames
    }

    pub fn jobs(&self, stage: Stage) -> usize {
        self.stages.iter().find(|s| s.name == stage).map_or(0, |s| s.jobs)
    }

    /// Checks `index` against the stage's job count.
    pub fn check_job(&self, stage: Stage, index: usize) -> Result<()> {
        let jobs = self.jobs(stage);
        if index >= jobs {
            return Err(Error::Job(format!(
                "job {index} of stage {}: the stage has {jobs} jobs (0..{})",
                stage.name(),
                jobs.saturating_sub(1)
            )));
        }
        Ok(())
    }

    pub fn distance_span(&self, index: usize) -> TileSpan {
        plan_distance_tiles(self.frames(), self.tile).swap_remove(index)
    }

    pub fn table_span(&self, index: usize) -> TableSpan {
        plan_table_tiles(self.frames(), self.tile).swap_remove(index)
    }

    /// Source rows of job `index` of the `candidates` and `paths` stages.
    pub fn row_block(&self, index: usize) -> std::ops::Range<usize> {
        let s = index * self.tile;
        s..(s + self.tile).min(self.frames())
    }

    /// Reads `plan.json` of a work folder.
    pub fn read(work: &Path) -> Result<Plan> {
        let path = work.join("plan.json");
        let text = std::fs::read(&path).map_err(|e| Error::Plan {
            path: path.clone(),
            message: format!("cannot read the plan ({e}): expected a work folder made by `surfcap tiles plan`"),
        })?;
        let plan: Plan = serde_json::from_slice(&text)
            .map_err(|e| Error::Plan { path: path.clone(), message: format!("not a surfcap tile plan: {e}") })?;
        if plan.format != FORMAT || plan.version != VERSION {
            return Err(Error::Plan {
                path,
                message: format!(
                    "format {:?} version {}: expected {FORMAT:?} version {VERSION} (plan again with this surfcap)",
                    plan.format, plan.version
                ),
            });
        }
        Ok(plan)
    }

    /// Writes `plan.json` atomically.
    pub fn write(&self, work: &Path) -> Result<()> {
        let json = serde_json::to_vec_pretty(self).expect("plans are plain data");
        surfcap_mesh::atomic::write_file(&work.join("plan.json"), |w| w.write_all(&json))?;
        Ok(())
    }
}

/// The stamp of the subject cache at `path`: its description, topology and the sizes of its
/// position files, hashed (the positions themselves are not read: a tile job reads only its
/// frames).
pub fn subject_stamp(path: &Path, frames: &surfcap_mesh::cache::CachedFrames) -> Result<SubjectStamp> {
    let mut h = blake3::Hasher::new();
    for name in ["subject.json", "faces.npy"] {
        let p = path.join(name);
        h.update(&std::fs::read(&p).map_err(|e| surfcap_mesh::Error::io(&p, "read", e))?);
    }
    for s in 0..frames.index.n_sequences() {
        let p = path.join(format!("positions_{s}.npy"));
        let len = std::fs::metadata(&p).map_err(|e| surfcap_mesh::Error::io(&p, "read", e))?.len();
        h.update(&len.to_le_bytes());
    }
    let path = std::fs::canonicalize(path).map_err(|e| surfcap_mesh::Error::io(path, "resolve", e))?;
    Ok(SubjectStamp {
        path,
        name: frames.name.clone(),
        frames: frames.index.len(),
        vertices: frames.topology.n_vertices(),
        triangles: frames.topology.n_triangles(),
        fingerprint: h.finalize().to_hex().to_string(),
    })
}

/// Estimated peak bytes of one job of each stage (the inputs and outputs it holds; the
/// program itself adds a few tens of MB).
pub fn job_memory(
    frames: usize,
    tile: usize,
    vertices: usize,
    triangles: usize,
    params: &WorkParams,
) -> Vec<(Stage, usize)> {
    use surfcap_geometry::distance_matrix::SLAB_BYTES;
    use surfcap_geometry::distance_tiles::tile_memory_bytes;
    let t = tile.min(frames.max(1));
    let span = TileSpan { rows: 0..t, cols: t.min(frames)..(2 * t).min(frames) };
    let span = if span.cols.is_empty() { TileSpan { rows: 0..t, cols: 0..t } } else { span };
    let halo = (t + params.l_max) * (t + params.l_max) * 8;
    let table_out = t * t * 20 + params.l_max * params.l_max * 16;
    let rows = t * frames;
    vec![
        (Stage::Distances, tile_memory_bytes(&span, vertices, triangles, SLAB_BYTES)),
        (Stage::Table, halo + table_out),
        (Stage::Scale, rows * 8 + (1 << 19)),
        (Stage::Candidates, rows * 12 + frames * 8 + t * (params.k + 1) * 24),
        (Stage::Paths, frames * (params.k + 1) * 24 + rows * 12),
    ]
}

/// Makes (or resumes) the work folder `work` for the subject cache `subject`: an existing work
/// folder with the same plan is kept as it is (its done jobs stay done); one with another plan
/// is refused, since its results belong to other parameters or another subject.
pub fn create_work(subject: &Path, work: &Path, tile: usize, params: WorkParams) -> Result<Plan> {
    let frames = surfcap_mesh::cache::CachedFrames::open(subject)?;
    let stamp = subject_stamp(subject, &frames)?;
    if tile == 0 {
        return Err(Error::Job("tile 0: expected at least 1 frame per tile side".into()));
    }
    let memory = job_memory(stamp.frames, tile, stamp.vertices, stamp.triangles, &params);
    let plan = Plan::new(stamp, tile, params, memory);
    surfcap_mesh::output_path::check_not_input(work, &[subject])?;
    let work = surfcap_mesh::output_path::claim_dir(work, WORK_KIND, false)?;
    if work.join("plan.json").is_file() {
        let old = Plan::read(&work)?;
        if old.subject != plan.subject || old.tile != plan.tile || old.params != plan.params {
            return Err(Error::Plan {
                path: work.join("plan.json"),
                message: "this work folder was planned for another subject or other parameters: plan into a new folder"
                    .into(),
            });
        }
        return Ok(old);
    }
    let store = crate::tile_store::Store::open(&work, &plan)?;
    store.create_arrays()?;
    plan.write(&work)?;
    Ok(plan)
}

/// Opens a work folder: its plan, its store and its subject, checked unchanged since planning.
pub fn open_work(work: &Path) -> Result<(Plan, crate::tile_store::Store, surfcap_mesh::cache::CachedFrames)> {
    let plan = Plan::read(work)?;
    let frames = surfcap_mesh::cache::CachedFrames::open(&plan.subject.path)?;
    let stamp = subject_stamp(&plan.subject.path, &frames)?;
    if stamp != plan.subject {
        return Err(Error::Plan {
            path: work.join("plan.json"),
            message: format!(
                "the subject {} changed since it was planned: plan again into a new folder",
                plan.subject.path.display()
            ),
        });
    }
    let store = crate::tile_store::Store::open(work, &plan)?;
    Ok((plan, store, frames))
}

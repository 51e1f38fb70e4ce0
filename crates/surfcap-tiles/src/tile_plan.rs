//! The plan of a work folder (`plan.json`): the subject, the parameters, and per stage its number
//! of jobs. A job's span is derived from (frames, tile) by the same functions the one-machine
//! pipeline uses, so the plan is small and a job index is all a worker needs.
//!
//! Stages, in order (each needs every job of the ones before):
//! 1. `distances`: the upper-triangle tiles of the pose distance matrix (`distance_tiles.rs`);
//! 2. `table`: every tile of the transition table, each reading its halo of distances
//!    (`transition_tiles.rs`);
//! 3. `scale`: one job, the median of the table's finite costs (Algorithm 1 divides D by it), and
//!    the clips authored as loops (`clip_loops.rs`, every frame read once, a few at a time);
//! 4. `candidates`: per block of source rows, each frame's k cheapest transitions and its
//!    original edge, and a looping clip's wrap edge (`sparse_essential_graph.rs`);
//! 5. `paths`: per block of source rows, the shortest-path trees on the sparse graph.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use surfcap_geometry::distance_tiles::TileSpan;
use surfcap_geometry::pose_distance::PoseMetric;
pub use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_tiles::TableSpan;

use crate::error::{Error, Result};

const FORMAT: &str = "surfcap-tiles";
/// Version 2: the plan records its own content hash, job records the plan's hash and their
/// outputs' hashes. Version 3: the `scale` stage also finds the looping clips, whose wrap edges
/// the candidates add (a version 2 folder's graph has none: plan again).
const VERSION: u32 = 3;
/// The most jobs a stage may have: a plan beyond it is refused (a larger tile makes fewer jobs),
/// so no loop over a stage's jobs can run for hours.
pub const MAX_STAGE_JOBS: usize = 10_000_000;
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
    /// BLAKE3 of the plan's canonical content (this file as surfcap writes it, with this field
    /// empty): a plan edited by hand no longer matches it and is refused; every job record
    /// carries it, so a record of another plan is recognised.
    pub hash: String,
}

/// Job counts of the stages of `frames` frames in tiles of `tile` (>= 1), in stage order,
/// computed with checked arithmetic; `None` on overflow.
pub fn stage_job_counts(frames: usize, tile: usize) -> Option<[(Stage, usize); 5]> {
    let blocks = frames.div_ceil(tile.max(1));
    let upper = blocks.checked_mul(blocks.checked_add(1)?)? / 2;
    let all = blocks.checked_mul(blocks)?;
    Some([
        (Stage::Distances, upper),
        (Stage::Table, all),
        (Stage::Scale, 1),
        (Stage::Candidates, blocks),
        (Stage::Paths, blocks),
    ])
}

impl Plan {
    /// The plan of `subject` in tiles of `tile` frames (a tile larger than the subject is one
    /// tile of all its frames), checked as [`Plan::read`] checks it and hashed.
    pub fn new(
        subject: SubjectStamp,
        tile: usize,
        params: WorkParams,
        job_memory_bytes: Vec<(Stage, usize)>,
    ) -> Result<Plan> {
        let tile = tile.max(1).min(subject.frames.max(1));
        let stages = stage_job_counts(subject.frames, tile)
            .map(|c| c.iter().map(|&(name, jobs)| StagePlan { name, jobs }).collect())
            .unwrap_or_default();
        let mut plan = Plan {
            format: FORMAT.into(),
            version: VERSION,
            subject,
            tile,
            params,
            stages,
            job_memory_bytes,
            hash: String::new(),
        };
        plan.hash = plan.content_hash();
        plan.validate(Path::new("plan.json"))?;
        Ok(plan)
    }

    /// BLAKE3 of the plan's canonical content: its compact JSON with `hash` empty.
    pub fn content_hash(&self) -> String {
        let mut bare = self.clone();
        bare.hash.clear();
        let json = serde_json::to_vec(&bare).expect("plans are plain data");
        blake3::hash(&json).to_hex().to_string()
    }

    /// Checks what the plan says against itself, before anything is sized from it: the format,
    /// at least one frame, a tile of 1 to `frames` frames, a known metric, w finite and >= 0,
    /// 1 <= l_min <= l_max <= 2^32 - 1 (lengths are stored as u32), k >= 1, the five stages in
    /// order with the job counts that (frames, tile) give (computed without overflow, at most
    /// [`MAX_STAGE_JOBS`] each), and finally its own content hash. `path` names the file in
    /// the errors.
    pub fn validate(&self, path: &Path) -> Result<()> {
        let bad = |message: String| Err(Error::Plan { path: path.to_path_buf(), message });
        if self.format != FORMAT || self.version != VERSION {
            return bad(format!(
                "format {:?} version {}: expected {FORMAT:?} version {VERSION} (plan again with this surfcap)",
                self.format, self.version
            ));
        }
        let n = self.subject.frames;
        if n == 0 {
            return bad("subject frames 0: expected a subject with at least one frame".into());
        }
        if self.tile == 0 || self.tile > n {
            return bad(format!(
                "tile {}: expected 1 to {n} frames per tile side (the subject has {n} frames)",
                self.tile
            ));
        }
        let p = &self.params;
        if PoseMetric::parse(&p.metric).is_none() {
            return bad(format!(
                "metric {:?}: expected deformation, deformation-log, deformation-literal or euclidean",
                p.metric
            ));
        }
        if !(p.w.is_finite() && p.w >= 0.0) {
            return bad(format!("w {}: expected a finite stretch weight >= 0", p.w));
        }
        if p.l_min < 1 || p.l_min > p.l_max || p.l_max > u32::MAX as usize {
            return bad(format!(
                "segment lengths l_min {} l_max {}: expected 1 <= l_min <= l_max <= {}",
                p.l_min,
                p.l_max,
                u32::MAX
            ));
        }
        if p.k == 0 {
            return bad("k 0: expected at least 1 transition kept per frame".into());
        }
        let Some(counts) = stage_job_counts(n, self.tile) else {
            return bad(format!("{n} frames in tiles of {}: the job counts overflow", self.tile));
        };
        let names: Vec<Stage> = self.stages.iter().map(|s| s.name).collect();
        if names != Stage::ALL {
            let got: Vec<&str> = names.iter().map(|s| s.name()).collect();
            return bad(format!("stages [{}]: expected distances, table, scale, candidates, paths", got.join(", ")));
        }
        for (s, (_, expected)) in self.stages.iter().zip(counts) {
            if s.jobs != expected {
                return bad(format!(
                    "stage {}: {} jobs: expected {expected} for {n} frames in tiles of {}",
                    s.name.name(),
                    s.jobs,
                    self.tile
                ));
            }
            if expected > MAX_STAGE_JOBS {
                return bad(format!(
                    "stage {}: {expected} jobs: at most {MAX_STAGE_JOBS} per stage (plan with a larger tile)",
                    s.name.name()
                ));
            }
        }
        let hash = self.content_hash();
        if hash != self.hash {
            return bad(format!(
                "edited since it was planned (its content hashes to {}…, it records {}…): plan again into a new folder",
                short(&hash),
                short(&self.hash)
            ));
        }
        Ok(())
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

    /// Frames of block `b` (rows or columns of tiles).
    fn block(&self, b: usize) -> std::ops::Range<usize> {
        let s = b * self.tile;
        s..(s + self.tile).min(self.frames())
    }

    /// Number of blocks of frames per side.
    pub fn blocks(&self) -> usize {
        self.frames().div_ceil(self.tile)
    }

    /// Tile (row block, column block) of `distances` job `index` (< the stage's jobs): the upper
    /// tiles row by row, as `plan_distance_tiles` lists them, found without listing them.
    pub fn distance_tile(&self, index: usize) -> (usize, usize) {
        let nb = self.blocks();
        let mut k = index;
        for a in 0..nb {
            let row = nb - a;
            if k < row {
                return (a, a + k);
            }
            k -= row;
        }
        (nb, nb)
    }

    pub fn distance_span(&self, index: usize) -> TileSpan {
        let (a, b) = self.distance_tile(index);
        TileSpan { rows: self.block(a), cols: self.block(b) }
    }

    /// Tile (row block, column block) of `table` job `index`, as `plan_table_tiles` lists them.
    pub fn table_tile(&self, index: usize) -> (usize, usize) {
        let nb = self.blocks().max(1);
        (index / nb, index % nb)
    }

    pub fn table_span(&self, index: usize) -> TableSpan {
        let (a, b) = self.table_tile(index);
        TableSpan { rows: self.block(a), cols: self.block(b) }
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
        plan.validate(&path)?;
        Ok(plan)
    }

    /// Writes `plan.json` atomically.
    pub fn write(&self, work: &Path) -> Result<()> {
        let json = serde_json::to_vec_pretty(self).expect("plans are plain data");
        surfcap_mesh::atomic::write_file(&work.join("plan.json"), |w| w.write_all(&json))?;
        Ok(())
    }
}

/// The first 12 hex digits of a hash, for messages.
pub fn short(hash: &str) -> &str {
    hash.get(..12).unwrap_or(hash)
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
    // Saturating: the estimate of an absurd request stays a (huge) number, never an overflow.
    let side = t.saturating_add(params.l_max);
    let halo = side.saturating_mul(side).saturating_mul(8);
    let table_out = (t * t * 20).saturating_add(params.l_max.saturating_mul(params.l_max).saturating_mul(16));
    let rows = t.saturating_mul(frames);
    let kept = params.k.saturating_add(1).saturating_mul(24);
    vec![
        (Stage::Distances, tile_memory_bytes(&span, vertices, triangles, SLAB_BYTES)),
        (Stage::Table, halo.saturating_add(table_out)),
        // The rows of costs, and the four frames the loop detection holds.
        (Stage::Scale, rows.saturating_mul(8).saturating_add(1 << 19).saturating_add(vertices.saturating_mul(48))),
        (Stage::Candidates, rows.saturating_mul(12).saturating_add(frames * 8).saturating_add(t.saturating_mul(kept))),
        (Stage::Paths, frames.saturating_mul(kept).saturating_add(rows.saturating_mul(12))),
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
    let plan = Plan::new(stamp, tile, params, memory).map_err(|e| match e {
        Error::Plan { message, .. } => Error::Plan { path: work.join("plan.json"), message },
        e => e,
    })?;
    surfcap_mesh::output_path::check_not_input(work, &[subject])?;
    let work = surfcap_mesh::output_path::claim_dir(work, WORK_KIND, false)?;
    if work.join("plan.json").is_file() {
        let old = Plan::read(&work)?;
        if old.hash != plan.hash {
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

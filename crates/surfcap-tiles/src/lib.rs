//! surfcap scale-out: the all-pairs work of a subject (pose distances, the transition table, the
//! sparse essential graph) cut into tiles, each an independent, idempotent job that reads only
//! what it needs, writes its result atomically and is skipped when already present, so any engine
//! that can run a command many times (a shell's `xargs -P`, Ray, Slurm job arrays) can run it and
//! an interrupted run resumes. The work folder's layout is in `docs/formats.md`.
//!
//! - [`tile_plan`]: `plan.json`: the subject's stamp (path, counts, BLAKE3 of its description and
//!   faces, position file sizes: a changed subject is refused), the parameters (checked on load:
//!   tile, metric, lengths, job counts computed without overflow and bounded, and the plan's
//!   own content hash, so an edited plan is refused), the stages
//!   distances -> table -> scale -> candidates -> paths with their job counts and per-job memory
//!   estimates; a job's span derived from (frames, tile) by the functions the one-machine code uses;
//! - [`tile_store`]: Zarr v3 arrays whose chunks are the tiles (f64 distances, each upper tile
//!   written with its mirror; table costs and path costs with NaN fill, so a chunk never written
//!   is never read as a number; u32 L, l^i, l^j), chunks encoded into memory then renamed into
//!   place; regions read only when every chunk is there; a job's record written last marks it done;
//! - [`cost_median`]: the exact median of the table's finite costs streamed in two radix passes
//!   (Algorithm 1's scale, the same bits as the in-memory selection);
//! - the `scale` job also finds the clips authored as loops (`surfcap_motion::clip_loops`, on
//!   the cached frames read a few at a time) and writes their wrap edges beside the median;
//! - [`tile_jobs`]: distance jobs read only their frames from the subject cache, table jobs their
//!   halo; the kernel and the process's peak memory recorded; [`graph_jobs`]: each frame's k
//!   cheapest transitions from rows of the table (a looping clip's wrap edge weighted as a
//!   successive step, as the one-machine graph), then Dijkstra per block of sources;
//! - [`tile_verify`]: every record (written for this plan, this job, listing this job's files),
//!   every output (a regular file of the recorded size and BLAKE3) and every `zarr.json` checked
//!   against the plan; a damaged job is not done (and `run` computes it again), a foreign record
//!   or a folder in an output's place is refused by name;
//! - [`tile_merge`]: status from the checks; the merge refuses any problem and missing jobs by
//!   name, never mixes distance kernels, writes `merge.json`, `graph_edges.npy`.
//!
//! The tile functions themselves live with their algorithms (`surfcap_geometry::distance_tiles`,
//! `surfcap_motion::transition_tiles`, `surfcap_motion::sparse_essential_graph`), where the
//! one-machine pipeline calls them too: one code path, the same bits.
//!
//! zarrs (the maintained Rust Zarr, conformant with Zarr 3.1, only its `filesystem` feature) turns
//! on serde_json's `preserve_order` for the whole workspace: JSON objects keep insertion order
//! (struct-serialised cache keys are unaffected; tests compare objects as maps or sort keys).
//! Chunks are uncompressed: distances do not compress, and a chunk's size then follows from its tile.

pub mod cost_median;
pub mod error;
pub mod graph_jobs;
pub mod tile_jobs;
pub mod tile_merge;
pub mod tile_plan;
pub mod tile_store;
pub mod tile_verify;

pub use error::{Error, Result};
pub use tile_plan::{Plan, Stage};

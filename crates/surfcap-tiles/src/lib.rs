//! surfcap scale-out (issue 21): the all-pairs work of a subject (pose distances, the transition
//! table, the sparse essential graph) cut into tiles, each an independent, idempotent job that
//! reads only what it needs, writes its result atomically and is skipped when already present,
//! so any engine that can run a command many times (a shell's `xargs -P`, Ray, Slurm job arrays)
//! can run it and an interrupted run resumes.
//!
//! - `tile_plan.rs`: the work folder's plan: stages, their jobs, the parameters;
//! - `tile_store.rs`: the Zarr arrays (chunks = tiles) and small `.npy` files of a work folder;
//! - `cost_median.rs`: the exact median of the table's finite costs, streamed over its tiles;
//! - `tile_jobs.rs`: one job of one stage; `graph_jobs.rs`: those of the graph's stages;
//! - `tile_merge.rs`: the merged products, once every job is done.
//!
//! The tile functions themselves live with their algorithms (`surfcap_geometry::distance_tiles`,
//! `surfcap_motion::transition_tiles`, `surfcap_motion::sparse_essential_graph`), where the
//! one-machine pipeline calls them too: one code path.

pub mod cost_median;
pub mod error;
pub mod graph_jobs;
pub mod tile_jobs;
pub mod tile_merge;
pub mod tile_plan;
pub mod tile_store;

pub use error::{Error, Result};
pub use tile_plan::{Plan, Stage};

//! Errors of the tiled work: each names the work folder's file, the stage and job.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
    #[error(transparent)]
    Motion(#[from] surfcap_motion::Error),
    /// A Zarr array that cannot be created, read or written.
    #[error("{path}: {message}")]
    Zarr { path: PathBuf, message: String },
    /// A plan that cannot be used.
    #[error("{path}: {message}")]
    Plan { path: PathBuf, message: String },
    /// A job index outside its stage, or a stage name that is not one.
    #[error("{0}")]
    Job(String),
    /// Jobs whose results are missing.
    #[error("stage {stage}: {count} of {jobs} jobs not done (first: {first}); run them, then merge again")]
    Missing { stage: &'static str, count: usize, jobs: usize, first: String },
    /// Results made by different distance kernels (they differ in the last bits).
    #[error("{0}")]
    Mixed(String),
    /// Files of the work folder that do not match its plan or their job records.
    #[error("{}", damaged_text(work, problems))]
    Damaged { work: PathBuf, problems: Vec<crate::tile_verify::Problem> },
}

/// At most this many problems are listed in a message (all are in `tiles status --json`).
const LISTED: usize = 20;

fn damaged_text(work: &std::path::Path, problems: &[crate::tile_verify::Problem]) -> String {
    let mut s = format!(
        "{}: {} problem{} in the work folder:",
        work.display(),
        problems.len(),
        if problems.len() == 1 { "" } else { "s" }
    );
    for p in problems.iter().take(LISTED) {
        s.push_str(&format!("\n  {p}"));
    }
    if problems.len() > LISTED {
        s.push_str(&format!("\n  ... and {} more", problems.len() - LISTED));
    }
    s
}

pub type Result<T> = std::result::Result<T, Error>;

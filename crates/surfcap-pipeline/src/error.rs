//! The pipeline's one error type.

use std::path::PathBuf;

/// What can go wrong while producing a derived product or reading a constraint file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading the subject, or reading or writing a cache file (the data layer's error names
    /// the file).
    #[error(transparent)]
    Data(#[from] surfcap_mesh::Error),
    /// A parameter outside its domain (the message says which and what was expected).
    #[error("{name} {value}: {expected}")]
    Parameter { name: &'static str, value: String, expected: &'static str },
    /// A product that does not fit the subject or its parameters (the shape, a value): a cache
    /// entry that is then recomputed, or, for one just computed, a bug.
    #[error("{kind}: {reason}")]
    Product { kind: &'static str, reason: String },
    /// The motion layer refused its input (an inconsistent matrix, a parameter).
    #[error(transparent)]
    Motion(#[from] surfcap_motion::Error),
    /// A constraint file (curve, key poses) that cannot be used: the file, its line when there
    /// is one, and what was expected.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    File { path: PathBuf, line: Option<usize>, message: String },
    /// A frame, tag or vertex the subject does not have, or a request it cannot satisfy.
    #[error("{0}")]
    Request(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn file(path: &std::path::Path, line: Option<usize>, message: impl Into<String>) -> Self {
        Error::File { path: path.to_path_buf(), line, message: message.into() }
    }
}

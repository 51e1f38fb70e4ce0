//! The one error type of surfcap-appearance.

use std::path::PathBuf;

/// What can fail while reading, aligning or modelling texture maps. Messages name the file
/// (and the frame, where there is one) and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A texture file could not be read or decoded.
    #[error("{path}: cannot read the texture map: {message}")]
    ReadImage { path: PathBuf, message: String },
    /// A texture file could not be encoded or written.
    #[error("{path}: cannot write the texture map: {message}")]
    WriteImage { path: PathBuf, message: String },
    /// Two inputs that must agree in size or layout do not.
    #[error("{0}")]
    Mismatch(String),
    /// An input or option outside what the computation accepts.
    #[error("{0}")]
    Invalid(String),
    /// A sparse system (the Poisson warp's normal equations, eq. 4.3) could not be factorised.
    #[error("{what}: {message}")]
    Solver { what: String, message: String },
    /// The data layer (atomic writes, regular files, npy).
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

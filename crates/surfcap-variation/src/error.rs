//! The one error type of surfcap-variation.

/// What can fail in motion variation. Messages name what was expected; a front end adds the
/// file or subject they came from.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Sequences, options or a request that do not fit the model or the subject.
    #[error("{0}")]
    Invalid(String),
    /// A saved model that cannot be read back (the file and what was expected).
    #[error("{0}")]
    Model(String),
    /// A learning step failed (GPDM fit, HMC).
    #[error("learning")]
    Learn(#[from] surfcap_learn::LearnError),
    /// Body parts or their stitching.
    #[error("body parts")]
    Transfer(#[from] surfcap_transfer::Error),
    /// A non-linear interpolation or Poisson system failed.
    #[error("geometry")]
    Geometry(#[from] surfcap_geometry::Error),
    /// Temporal pre-alignment (DTW) of the sequences.
    #[error("time alignment")]
    Motion(#[from] surfcap_motion::Error),
    /// Mesh data or files.
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

//! The surface motion graph's one error type.

/// What can go wrong in the surface motion graph's computations.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The frames' data (reading, caching).
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
    /// An input or parameter outside its domain, said with what was expected.
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

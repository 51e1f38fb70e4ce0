//! The skinning decomposition's one error type.

/// What can go wrong when a mesh sequence is decomposed into a skinned rig.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input or parameter outside its domain, said with what was expected.
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

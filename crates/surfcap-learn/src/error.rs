//! Typed errors of the learning toolkit: bad input is an error that says what was expected,
//! never a panic and never a silently wrong result.

/// What went wrong, with a message naming the offending sizes or values.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// Matrices or vectors whose sizes do not fit together.
    #[error("dimension mismatch: {0}")]
    Dimension(String),
    /// NaN or infinite input.
    #[error("non-finite value: {0}")]
    NonFinite(String),
    /// Too few samples, an empty input, a parameter out of range.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// A kernel matrix that stays non-positive-definite after the largest jitter.
    #[error("matrix not positive definite: {0}")]
    NotPositiveDefinite(String),
    /// A decomposition (SVD, eigen) that did not converge.
    #[error("decomposition failed: {0}")]
    Decomposition(String),
    /// The optimiser could not make progress from any start.
    #[error("optimisation failed: {0}")]
    Optimisation(String),
    /// Reading or writing a file.
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
}

/// Result with [`LearnError`].
pub type Result<T> = std::result::Result<T, LearnError>;

//! The one error type of surfcap-geometry.

use faer::linalg::cholesky::llt::factor::LltError;
use faer::sparse::{CreationError, FaerError};

/// What can fail in the pose geometry: the Poisson system (thesis eq. 2.48) of a pose, which
/// should not fail on a mesh with positive areas. Each variant carries faer's own error as its
/// source, which the message does not repeat (error printers show the chain: repeating it gave
/// the same text twice).
#[derive(Debug, Clone, thiserror::Error)]
pub enum Error {
    /// The reduced Laplacian could not be assembled from its triplets.
    #[error("Poisson system: cannot assemble")]
    PoissonAssemble(#[source] CreationError),
    /// The symbolic Cholesky factorisation of the reduced Laplacian's pattern failed.
    #[error("Poisson system: symbolic factorisation failed")]
    PoissonSymbolic(#[source] FaerError),
    /// The numeric Cholesky factorisation of a pose's reduced Laplacian failed.
    #[error("Poisson system: numeric factorisation failed")]
    PoissonNumeric(#[source] LltError),
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::Error;

    #[test]
    fn faer_error_is_the_source_and_not_repeated_in_the_message() {
        let e = Error::PoissonSymbolic(faer::sparse::FaerError::OutOfMemory);
        assert_eq!(e.to_string(), "Poisson system: symbolic factorisation failed");
        let source = std::error::Error::source(&e).expect("faer's error is the source");
        assert_eq!(source.to_string(), "OutOfMemory");
    }
}

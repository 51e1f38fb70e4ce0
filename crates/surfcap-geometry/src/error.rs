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
    /// A foot's vertex set (foot contacts, foot sliding) names a vertex the mesh does not have.
    #[error("foot {foot}: vertex {vertex} is not a vertex of the mesh (expected 0 to {})", .n_vertices.saturating_sub(1))]
    FootVertex { foot: usize, vertex: u32, n_vertices: usize },
    /// Ground contacts detected on a clip of `contacts` frames, used with one of `frames`.
    #[error("ground contacts of {contacts} frames given for a clip of {frames} frames")]
    ContactFrames { contacts: usize, frames: usize },
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
        let foot = Error::FootVertex { foot: 1, vertex: 40, n_vertices: 40 };
        assert_eq!(foot.to_string(), "foot 1: vertex 40 is not a vertex of the mesh (expected 0 to 39)");
    }
}

//! The one error type of surfcap-transfer.

/// What can fail in motion transfer. Messages name what was expected; a front end adds the
/// file or subject they came from.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Body parts that do not fit the subject or are inconsistent.
    #[error("body parts: {0}")]
    Parts(String),
    /// Training pairs, sequences or dimensions that do not fit together.
    #[error("{0}")]
    Invalid(String),
    /// A learning step failed (PCA, GP regression, linear regression).
    #[error("learning")]
    Learn(#[from] surfcap_learn::LearnError),
    /// A Poisson reconstruction failed.
    #[error("Poisson reconstruction")]
    Geometry(#[from] surfcap_geometry::Error),
    /// Mesh data that does not fit (topology, frames).
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Checks that `p` holds `n` finite positions (`[n][3]`); `what` names it in the error
/// ("the predicted part has 9 coordinates: expected 3 x 4 = 12").
pub(crate) fn check_positions(p: &[f32], n: usize, what: &str) -> Result<()> {
    if p.len() != 3 * n {
        return Err(Error::Invalid(format!("{what} has {} coordinates: expected 3 x {n} = {}", p.len(), 3 * n)));
    }
    if let Some(i) = p.iter().position(|x| !x.is_finite()) {
        return Err(Error::Invalid(format!(
            "{what} has a non-finite coordinate at vertex {}: expected finite positions",
            i / 3
        )));
    }
    Ok(())
}

//! The synthesis layer's one error type.
//!
//! Its messages are the ones the command line shows (they name the option or file a request
//! came from, and what was expected); a message that adds context to a lower layer's error keeps
//! that error as its source, so a front end can show the chain ("caused by").

/// What can go wrong while preparing a subject, checking a request, searching, playing or
/// writing an animation.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The data layer (reading, writing, output safety): its error names the file.
    #[error(transparent)]
    Mesh(#[from] surfcap_mesh::Error),
    /// Geometry (pose distances).
    #[error(transparent)]
    Geometry(#[from] surfcap_geometry::Error),
    /// The motion layer (searches, graphs).
    #[error(transparent)]
    Motion(#[from] surfcap_motion::Error),
    /// Derived products and constraint files.
    #[error(transparent)]
    Pipeline(#[from] surfcap_pipeline::Error),
    /// Appearance models and textures.
    #[error(transparent)]
    Appearance(#[from] surfcap_appearance::Error),
    /// Variation models and their sampling.
    #[error(transparent)]
    Variation(#[from] surfcap_variation::Error),
    /// The surface motion graph.
    #[error(transparent)]
    Smg(#[from] surfcap_smg::Error),
    /// Motion transfer (body parts, training, reconstruction).
    #[error(transparent)]
    Transfer(#[from] surfcap_transfer::Error),
    /// A request refused before (or instead of) any work: what was asked and what was expected.
    #[error("{0}")]
    Request(String),
    /// An error with what was being done when it happened (the error is its source).
    #[error("{context}")]
    Context {
        context: String,
        #[source]
        source: Box<Error>,
    },
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Adds what was being done to an error, keeping the error as the source.
pub(crate) trait Context<T> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| Error::Context { context: context(), source: Box::new(e.into()) })
    }
}

/// `Err(Error::Request(format!(...)))`.
macro_rules! refuse {
    ($($t:tt)*) => { return Err($crate::error::Error::Request(format!($($t)*))) };
}
pub(crate) use refuse;

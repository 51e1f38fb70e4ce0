//! The evaluations' one error type.

/// What can go wrong while running an evaluation.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Producing a derived product (distances, transition table, graph), with its cache.
    #[error(transparent)]
    Pipeline(#[from] surfcap_pipeline::Error),
    /// The subject's data: a frame that does not resolve, a derived subject that cannot be built.
    #[error(transparent)]
    Data(#[from] surfcap_mesh::Error),
    /// Factorising a Poisson system (non-linear interpolation).
    #[error(transparent)]
    Poisson(#[from] surfcap_geometry::Error),
    /// Texture maps, flows, warps and the appearance model (thesis chapter 4).
    #[error(transparent)]
    Appearance(#[from] surfcap_appearance::Error),
    /// Motion variation (thesis chapter 6): preparation, training, sampling.
    #[error(transparent)]
    Variation(#[from] surfcap_variation::Error),
    /// The interactive controller and offline synthesis (`surfcap eval play`).
    #[error(transparent)]
    Synthesis(#[from] surfcap_synthesis::Error),
    /// A learning step failed; `context` says which (e.g. "fitting the GPDM").
    #[error("{context}")]
    Learn {
        context: &'static str,
        #[source]
        source: surfcap_learn::LearnError,
    },
    /// An option outside its domain, named as on the command line: "--slopes: expected whole
    /// numbers >= 1", "--alpha: expected at least one value".
    #[error("{option}{}: {expected}", value.as_ref().map(|v| format!(" {v}")).unwrap_or_default())]
    Parameter { option: &'static str, value: Option<String>, expected: String },
    /// A subject this evaluation cannot use (no ground-truth joints, too few frames, ...).
    #[error("{0}")]
    Unsuitable(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn parameter(option: &'static str, value: Option<String>, expected: impl Into<String>) -> Self {
        Error::Parameter { option, value, expected: expected.into() }
    }

    /// A learning error with what was being done, as `anyhow`'s `context` put it before.
    pub(crate) fn learn(context: &'static str) -> impl FnOnce(surfcap_learn::LearnError) -> Self {
        move |source| Error::Learn { context, source }
    }
}

//! Progress reporting without printing: the library calls these hooks, the CLI draws bars.

/// Receives progress of a long operation. Implementations must be cheap and thread-safe.
pub trait Progress: Sync {
    /// A new stage of `total` steps begins.
    fn start(&self, _label: &str, _total: u64) {}
    /// `n` more steps are done.
    fn advance(&self, _n: u64) {}
    /// The current stage is done.
    fn finish(&self) {}
    /// Something the user should know that is not an error (e.g. a cache entry that was
    /// rejected and recomputed): libraries do not print, so they say it here.
    fn note(&self, _text: &str) {}
}

/// Reports nothing.
pub struct NoProgress;

impl Progress for NoProgress {}

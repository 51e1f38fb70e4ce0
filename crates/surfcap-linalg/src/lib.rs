//! surfcap's shared linear-algebra set-ups over faer, each written once for every crate that
//! needs it: [`sparse_cholesky`], the sparse LLT factorisation with the symbolic part done once
//! per sparsity pattern and the numeric part once per matrix, solved sequentially (the Poisson
//! reconstruction of `surfcap-geometry`, the Poisson texture warp of `surfcap-appearance`); and
//! [`vector_state`], the clear of the upper vector-register halves after faer's AVX-512 kernels
//! (`surfcap-geometry`'s pose distance, `surfcap-learn`'s kernels, GPDM and HMC).
//!
//! Depends on faer only, and on no surfcap crate: it sits at the bottom of the workspace, beside
//! `surfcap-mesh`, so that the geometry, learning and appearance crates can all use it without
//! depending on one another.

pub mod sparse_cholesky;
pub mod vector_state;

pub use sparse_cholesky::{NumericLlt, SymbolicLlt};
pub use vector_state::clear_upper_vector_state;

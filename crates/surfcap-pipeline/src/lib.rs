//! surfcap pipeline: one subject's derived products as a library, for every front end (the
//! command-line program today, a binding or a server tomorrow).
//!
//! A [`Pipeline`] over a `Subject`, a [`CacheStore`] and a `Progress` produces each derived
//! product lazily, once, and from the on-disk cache when it is there: the pose distance matrix
//! (any metric and vertex weights), the transition table, edge weights, the essential and
//! motion graphs and the walk model. Each product's cache key is a typed struct
//! ([`product_key`]) and its `.npy` layout is documented on the method that produces it.
//! Beside the chain: the constraint files of synthesis (curves, key poses, tag restrictions)
//! and walk playback, with learned variants shown when a walk repeats its frames.
//!
//! The chapters still to come (motion transfer, variation, appearance) add their products here.

pub mod constraint_files;
pub mod error;
pub mod frame_variants;
pub mod graph_kind;
pub mod pipeline;
pub mod product_key;
pub mod walk_playback;

pub use error::{Error, Result};
pub use graph_kind::GraphKind;
pub use pipeline::{CacheStore, Fetched, GraphParams, Pipeline, PoseDistances};

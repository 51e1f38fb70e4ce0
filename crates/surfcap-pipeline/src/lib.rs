//! surfcap pipeline: one subject's derived products as a library, for every front end.
//!
//! A [`Pipeline`] over a `Subject`, a [`CacheStore`] (a cache folder or memory only, with refresh)
//! and a `Progress` produces each derived product lazily, once per process, and from the disk
//! cache when an entry is there and decodes for this subject: pose distances (any metric and
//! vertex weights), the transition table, edge weights, the essential (exact or sparse) and motion
//! graphs, and the walk model ([`pipeline`]). Each product's cache key is a typed struct holding
//! its parameters, its parent's key and a layout version ([`product_key`]: serialised in
//! declaration order, floats in shortest exact form, hashed with BLAKE3 into the file name), so a
//! changed parameter recomputes only what depends on it; an entry that does not decode (damaged,
//! older layout) is recomputed and replaced. Each product's `.npy` layout is documented on the
//! method that produces it (and in `docs/formats.md`). [`GraphKind`] (`essential`,
//! `sparse-essential:K`, `motion`) is written and read in that form, so a graph's key holds k;
//! [`GraphOptions`] turns the front ends' graph options into [`GraphParams`] ([`graph_options`]);
//! [`GraphSummary`] and [`write_graph`] are what `graph build` writes about a graph
//! ([`graph_summary`]).
//!
//! Beside the chain: the constraint files of synthesis ([`constraint_files`]: curves, key poses,
//! tag restrictions, errors naming file and line); walk playback into a labelled `Sequence` with
//! its statistics, segments, each frame's `FrameMix` and `FramePlay`, a repeat summary and the
//! passes a walk needs per sequence ([`walk_playback`]); learned variants of sequences as the
//! `FrameSource` a repeated run plays, pass p showing variant (p - 1) mod K ([`frame_variants`]).
//! One [`Error`] (thiserror).

pub mod constraint_files;
pub mod error;
pub mod frame_variants;
pub mod graph_kind;
pub mod graph_options;
pub mod graph_summary;
pub mod pipeline;
pub mod product_key;
pub mod walk_playback;

pub use error::{Error, Result};
pub use graph_kind::GraphKind;
pub use graph_options::{GraphOptions, table_params};
pub use graph_summary::{GraphSummary, edge_arrays, write_graph};
pub use pipeline::{CacheStore, Fetched, GraphParams, Pipeline, PoseDistances, default_cache_dir};

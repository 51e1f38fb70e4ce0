//! One file (or folder) per command family. Commands import the shared modules of the crate
//! (`crate::options`, `crate::output`, `crate::synthesis`, ...), never each other.

pub mod appearance;
pub mod demo;
pub mod distance;
pub mod eval;
pub mod export;
pub mod graph;
pub mod import;
pub mod info;
pub mod interpolate;
pub mod make;
pub mod parts;
// ---- live play ----
pub mod play;
// ---- end live play ----
pub mod remesh_frames;
pub mod render;
pub mod report;
pub mod reproduce;
pub mod rig;
pub mod smg;
pub mod synth;
pub mod tiles;
pub mod transfer;
pub mod transition;
pub mod transitions;
pub mod vary;
pub mod view;

//! The small subject the controller's tests play: the procedural mannequin (1,000 vertices) in
//! 2 s clips at 30 fps of the given gaits, prepared in memory with the essential graph (slope
//! constraint 3, alpha 0.05). Shared by controller.rs and parametric_blend.rs.

use std::sync::Arc;

use surfcap_builtin::locomotion::Gait as Procedural;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};
use surfcap_synthesis::Prepared;

/// The mannequin walker of `gaits` (clip k seeded with k), prepared for the controller.
pub fn prepared(gaits: &[Procedural]) -> Prepared {
    let m = mannequin(&BodyShape::average(), 1000).unwrap();
    let clips: Vec<Clip> =
        gaits.iter().enumerate().map(|(k, &g)| Clip::procedural(&m, g, 30.0, 2.0, k as u64).unwrap()).collect();
    let s: Subject = mannequin_subject("walker", &m, &clips, 30.0).unwrap();
    let (l_min, l_max) = surfcap_motion::segment_bounds(s.fps);
    let params = GraphParams {
        table: TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).unwrap(),
    };
    let pipe = Arc::new(Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress)));
    Prepared::new(pipe, params, None).unwrap()
}

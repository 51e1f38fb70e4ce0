//! Cache keys of the derived products, built from their typed parameters.
//!
//! Every product has a key struct that holds exactly what the product depends on, including
//! the key of the product it is computed from (a transition table's key holds its distance
//! matrix's key, a graph's key its table's key, and so on), and a layout version bumped when
//! the product's `.npy` layout or its algorithm changes. The file name is
//! `<kind>-<16 hex digits>.npy` in the cache folder, the digits a BLAKE3 hash of the subject's
//! geometry, the kind and the key serialised as JSON (fields in declaration order, floats in
//! their shortest exact form), so two runs with the same typed parameters find the same file
//! and any changed parameter (vertex weights included) gives a new one.

use std::path::PathBuf;

use serde::Serialize;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::TableParams;

use crate::graph_kind::GraphKind;

/// The identity of a derived product in the cache.
pub trait ProductKey: Serialize {
    /// Readable file-name prefix, e.g. `distance-deformation`.
    fn kind(&self) -> String;
    /// Bumped when the product's layout or algorithm changes (old files are then ignored).
    const VERSION: u32;

    /// The product's file in `cache`.
    fn path(&self, cache: &DerivedCache, subject: &blake3::Hash) -> PathBuf {
        let text = serde_json::to_string(&(Self::VERSION, self)).expect("keys are plain data");
        cache.path(&self.kind(), subject, &text)
    }
}

/// The pose distance matrix: metric, stretch weight and vertex weights (eq. 2.2-2.5, 2.13).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DistanceKey {
    pub metric: &'static str,
    pub w: f64,
    /// The per-vertex alignment weights, `None` for all ones.
    pub vertex_weights: Option<Vec<f64>>,
    /// The matrix's [`ProductKey::VERSION`], part of the key so that every product computed from
    /// the matrix (table, graphs, walk model: their keys hold this one) changes with it.
    pub layout: u32,
}

impl DistanceKey {
    pub fn new(p: &DistanceParams) -> Self {
        DistanceKey {
            metric: p.metric.name(),
            w: p.w,
            vertex_weights: p.vertex_weights.clone(),
            layout: <DistanceKey as ProductKey>::VERSION,
        }
    }
}

impl ProductKey for DistanceKey {
    fn kind(&self) -> String {
        format!("distance-{}", self.metric)
    }
    /// 3: each pair aligned from its own inner products (tiles), not the all-frames
    /// Gram matrices: the values moved in the last bits.
    const VERSION: u32 = 3;
}

/// The transition table: its distance matrix and the segment bounds and slope (thesis 2.5).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableKey {
    pub distance: DistanceKey,
    pub l_min: usize,
    pub l_max: usize,
    pub slope: Option<usize>,
}

impl TableKey {
    pub fn new(distance: &DistanceParams, p: &TableParams) -> Self {
        TableKey { distance: DistanceKey::new(distance), l_min: p.l_min, l_max: p.l_max, slope: p.slope }
    }
}

impl ProductKey for TableKey {
    fn kind(&self) -> String {
        "transitions".into()
    }
    const VERSION: u32 = 2;
}

/// A graph over the frames: its table, which graph and the tolerance alpha (thesis 3.3).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraphKey {
    pub table: TableKey,
    pub kind: GraphKind,
    /// Serialised as the bare number.
    pub alpha: Alpha,
}

impl ProductKey for GraphKey {
    fn kind(&self) -> String {
        "graph".into()
    }
    /// 4: looping clips' wrap edges (last frame -> start) weigh as successive steps.
    const VERSION: u32 = 4;
}

/// The walk model of a graph: every transition's rigid track of the tracked vertices' centre.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WalkModelKey {
    pub graph: GraphKey,
    /// The vertices whose centre is tracked, `None` for all (the centre of mass).
    pub tracked: Option<Vec<usize>>,
    /// Transitions keep the captured placement (a subject that does not travel); absent from
    /// the key otherwise, so a travelling subject's models keep their files.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub captured_placement: bool,
}

impl ProductKey for WalkModelKey {
    fn kind(&self) -> String {
        "walkmodel".into()
    }
    /// 3: rows for looping clips' wrap edges.
    const VERSION: u32 = 3;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_changes_the_file_and_equal_parameters_share_it() {
        let cache = DerivedCache::new("/tmp/unused");
        let h = blake3::hash(b"subject");
        let base = DistanceParams::default();
        let p = |d: &DistanceParams| DistanceKey::new(d).path(&cache, &h);
        assert_eq!(p(&base), p(&DistanceParams::default()));
        assert!(p(&base).file_name().unwrap().to_str().unwrap().starts_with("distance-deformation-"));
        assert_ne!(p(&base), p(&DistanceParams { w: 0.02, ..DistanceParams::default() }));
        // The vertex weights are part of the key.
        let weighted = DistanceParams { vertex_weights: Some(vec![1.0, 2.0]), ..DistanceParams::default() };
        assert_ne!(p(&base), p(&weighted));
        assert_ne!(p(&base), DistanceKey::new(&base).path(&cache, &blake3::hash(b"other subject")));
        let t = TableParams { l_min: 8, l_max: 48, slope: Some(3) };
        let table = TableKey::new(&base, &t);
        assert_ne!(table.path(&cache, &h), TableKey::new(&weighted, &t).path(&cache, &h));
        assert_ne!(table.path(&cache, &h), TableKey::new(&base, &TableParams { slope: None, ..t }).path(&cache, &h));
        let g =
            |kind, alpha| GraphKey { table: table.clone(), kind, alpha: Alpha::new(alpha).unwrap() }.path(&cache, &h);
        assert_ne!(g(GraphKind::Essential, 0.05), g(GraphKind::Motion, 0.05));
        assert_ne!(g(GraphKind::Essential, 0.05), g(GraphKind::Essential, 0.1));
        // The sparse essential graph's k is part of the key.
        let sparse = |k| g(GraphKind::SparseEssential { k }, 0.05);
        assert_ne!(sparse(8), sparse(16));
        assert_ne!(sparse(16), g(GraphKind::Essential, 0.05));
        assert_eq!(sparse(16), sparse(16));
        let graph = GraphKey { table, kind: GraphKind::Essential, alpha: Alpha::new(0.05).unwrap() };
        // alpha is written as the bare number (the key's bytes, so the cache files' names, are
        // those of a plain f64 field).
        let plain = format!(
            r#"{{"table":{},"kind":{},"alpha":0.05}}"#,
            serde_json::to_string(&graph.table).unwrap(),
            serde_json::to_string(&graph.kind).unwrap()
        );
        assert_eq!(serde_json::to_string(&graph).unwrap(), plain);
        let w = |tracked| WalkModelKey { graph: graph.clone(), tracked, captured_placement: false }.path(&cache, &h);
        assert_ne!(w(None), w(Some(vec![1, 2])));
        assert_ne!(w(Some(vec![1, 2])), w(Some(vec![1, 3])));
        // A subject kept in its captured placement has its own walk models; a travelling
        // subject's key is the one it had before the placement was part of it.
        let captured = WalkModelKey { graph: graph.clone(), tracked: None, captured_placement: true };
        assert_ne!(captured.path(&cache, &h), w(None));
        assert!(
            !serde_json::to_string(&WalkModelKey { captured_placement: false, ..captured })
                .unwrap()
                .contains("placement")
        );
    }
}

//! The sparse essential graph against the exact one on a small subset of the
//! evaluation's subject: the mannequin moved by every CMU clip, resampled to 10 fps (about 380
//! frames instead of the evaluation's 1,900 at 50 fps), so the test runs in seconds.

use surfcap_eval::sparse_graph_eval::{SparseGraphEvalOptions, cmu_subject, sparse_graph_eval};
use surfcap_mesh::NoProgress;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::segment_bounds;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};

/// Costs only rise as edges are dropped, fall as k grows, and with every transition kept the
/// sparse build is the exact graph: every pair's cost, every edge and every query the same.
#[test]
fn sparse_costs_rise_with_fewer_transitions_and_all_of_them_give_the_exact_graph() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = cmu_subject(&data, 1000, 10.0).unwrap();
    let n = s.n_frames();
    assert!((300..500).contains(&n), "{n} frames");
    let (l_min, l_max) = segment_bounds(s.fps);
    let graph = GraphParams {
        table: TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).unwrap(),
    };
    let mut opts = SparseGraphEvalOptions::cmu(graph);
    opts.ks = vec![2, 8, 32, n - 1];
    let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
    let r = sparse_graph_eval(&pipe, &opts, &NoProgress).unwrap();
    assert_eq!(r.frames, n);
    assert_eq!(r.rows.len(), 4);
    assert!(r.connected_pairs > n * (n - 1) / 2, "the CMU clips connect most pairs: {}", r.connected_pairs);
    for pair in r.rows.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        assert!(a.within_tolerance <= b.within_tolerance, "k {} -> {}", a.k, b.k);
        assert!(a.unreachable >= b.unreachable, "k {} -> {}", a.k, b.k);
        // The mean is over the pairs both graphs connect: comparable when those are the same.
        if a.unreachable == b.unreachable {
            assert!(a.mean_ratio >= b.mean_ratio, "k {} -> {}", a.k, b.k);
        }
        assert!(a.sparse_edges < b.sparse_edges);
    }
    assert!(r.rows[0].mean_ratio > 1.0, "two transitions per frame lose some shortest paths");
    for x in &r.rows {
        assert!(x.mean_ratio >= 1.0 && x.max_ratio >= 1.0, "k {}: costs never fall", x.k);
        assert!(x.edges <= x.sparse_edges);
    }
    let all = r.rows.last().unwrap();
    assert_eq!((all.within_tolerance, all.mean_ratio, all.max_ratio, all.unreachable), (1.0, 1.0, 1.0, 0));
    assert_eq!((all.edges, all.transitions), (r.exact.edges, r.exact.transitions));
    assert!(all.acceptable && r.chosen_k.is_some_and(|k| k < n));
    assert_eq!(all.queries.len(), r.exact.queries.len());
    assert_eq!(all.queries.len(), 6, "two paths and four key poses");
    for (q, (name, _, e)) in all.queries.iter().zip(&r.exact.queries) {
        assert!(e.failed.is_none(), "{name}: {:?}", e.failed);
        assert_eq!((q.sparse.error, q.sparse.cost, q.sparse.transitions), (e.error, e.cost, e.transitions), "{name}");
        assert!(!q.worse, "{name}");
    }
}

//! Every sequence of `../shared/data` through USD text and Alembic and back, exactly: positions to the bit, topology with UVs, names, labels, rate, up axis, units.

use surfcap_eval::{InterchangeOptions, interchange_eval};
use surfcap_formats::export::ExportFormat;

#[test]
fn every_sequence_of_the_shared_data_round_trips_exactly_through_usda_and_abc() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let scratch = tempfile::tempdir().unwrap();
    let opts = InterchangeOptions {
        data,
        datasets: Vec::new(),
        formats: vec![ExportFormat::Usda, ExportFormat::Abc],
        scratch: scratch.path().to_path_buf(),
        default_fps: 30.0,
    };
    let r = interchange_eval(&opts, &surfcap_mesh::NoProgress).unwrap();
    // 150 sequences in 11 datasets, the head scan (UVs) included; cmu_bvh and cmu_bvh_loops
    // hold skeletons only, and only they are skipped.
    assert!(r.sequences >= 150, "{} sequences", r.sequences);
    assert!(r.round_trips.iter().any(|t| t.uv && t.format == "abc"), "the head scan's UVs went through");
    let mut skipped: Vec<&str> = r.skipped.iter().map(|s| s.dataset.as_str()).collect();
    skipped.sort();
    assert_eq!(skipped, ["cmu_bvh", "cmu_bvh_loops"]);
    let bad: Vec<String> = r
        .round_trips
        .iter()
        .filter(|t| !t.exact)
        .map(|t| format!("{} {} as {}: {}", t.dataset, t.sequence, t.format, t.difference.as_deref().unwrap_or("")))
        .collect();
    assert!(bad.is_empty(), "not exact:\n{}", bad.join("\n"));
    assert_eq!(r.round_trips.len(), 2 * r.sequences);
}

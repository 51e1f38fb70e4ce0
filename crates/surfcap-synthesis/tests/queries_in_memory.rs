//! A front end that keeps a subject's pipeline (the Python `Subject`) prepares it without giving
//! it up, and asks queries whose animation it wants in memory: nothing is written, the outcome
//! holds the animation and its report, and the same query with an output writes exactly that.

use std::sync::Arc;

use surfcap_builtin::locomotion::Gait;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_mesh::{NoProgress, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};
use surfcap_synthesis::{CurveSource, Output, PathRequest, Prepared, ReachRequest, SizeLimits, Tolerances};

/// The mannequin (1,000 vertices) walking and jogging for 2 s each at 30 fps.
fn walker() -> Subject {
    let m = mannequin(&BodyShape::average(), 1000).unwrap();
    let clips: Vec<Clip> =
        [Gait::Walk, Gait::Jog].iter().map(|&g| Clip::procedural(&m, g, 30.0, 2.0, 0).unwrap()).collect();
    mannequin_subject("walker", &m, &clips, 30.0).unwrap()
}

fn request(columns: usize, values: Vec<f64>) -> PathRequest {
    PathRequest {
        curve: CurveSource::Points { name: "curve".into(), columns, values },
        planar: false,
        tags: Vec::new(),
        start: None,
        track: Vec::new(),
        window: None,
        max_transitions: None,
        branching: 8,
    }
}

#[test]
fn a_query_without_an_output_writes_nothing_and_returns_the_animation_the_output_gets() {
    let dir = tempfile::tempdir().unwrap();
    let s = walker();
    let (l_min, l_max) = surfcap_motion::segment_bounds(s.fps);
    let params = GraphParams {
        table: TableParams { l_min, l_max, slope: Some(3) },
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05).unwrap(),
    };
    let pipe = Arc::new(Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress)));
    let prep = Prepared::new(Arc::clone(&pipe), params.clone(), None).unwrap();
    // The pipeline is shared, not taken: its graph is the prepared subject's, not a second one.
    assert!(Arc::ptr_eq(&pipe.graph(&params).unwrap().value, &prep.graph));

    // 5 m on the ground plane (x, z for +y up), as an array of two columns.
    let memory = Output::in_memory(Tolerances::default());
    let checked = request(2, vec![0.0, 0.0, 5.0, 0.0]).check(&pipe, &memory, &SizeLimits::default()).unwrap();
    let o = prep.follow_path(&checked.query(), &memory, &NoProgress).unwrap();
    assert!(o.played.written.is_empty() && o.played.report_path.is_none() && o.report.walk.outputs.is_empty());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
    assert_eq!(o.played.output.n_frames(), o.frames);
    assert!(o.frames > 30 && o.max_error < 1.0, "{} frames, max error {}", o.frames, o.max_error);

    // The same query with an output: the same walk, written with its report.
    let out = Output::new(dir.path().join("path.glb"));
    let w = prep.follow_path(&checked.query(), &out, &NoProgress).unwrap();
    assert_eq!(w.report.walk.walk, o.report.walk.walk);
    assert_eq!(w.played.output.sequences()[0].positions(), o.played.output.sequences()[0].positions());
    assert!(!w.played.written.is_empty() && w.played.written.iter().all(|f| f.exists()));
    assert!(w.played.report_path.as_ref().is_some_and(|r| r.ends_with("path.report.json") && r.exists()));

    // A reach query checked on the prepared subject: in memory too.
    let reach = ReachRequest {
        from: "0".into(),
        to: "70".into(),
        distance: 2.0,
        time: "2".parse().unwrap(),
        distance_scale: 0.3,
        time_scale: 10.0,
    };
    let q = reach.check(prep.subject(), &memory, &SizeLimits::default()).unwrap();
    let r = prep.reach(&q, &memory, &NoProgress).unwrap();
    assert!(r.played.written.is_empty() && r.played.report_path.is_none());
    assert_eq!(r.played.output.n_frames(), r.report.walk.frames);
}

#[test]
fn curve_points_are_checked_as_a_curve_file_is() {
    let s = walker();
    let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
    let memory = Output::in_memory(Tolerances::default());
    let e = request(2, vec![0.0, 0.0, f64::NAN, 1.0]).check(&pipe, &memory, &SizeLimits::default()).unwrap_err();
    assert_eq!(e.to_string(), "curve: point 1: NaN is not a finite number");
    let e = request(4, vec![0.0; 8]).check(&pipe, &memory, &SizeLimits::default()).unwrap_err();
    assert!(e.to_string().contains("4 columns; expected x,y,z or two ground-plane coordinates"), "{e}");
    let e = request(3, Vec::new()).check(&pipe, &memory, &SizeLimits::default()).unwrap_err();
    assert_eq!(e.to_string(), "curve: no curve points");
}

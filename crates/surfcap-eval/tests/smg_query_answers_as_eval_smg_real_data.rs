//! `surfcap smg query` (`surfcap_synthesis::smg_query`) builds the graph `surfcap eval smg`
//! measures, by default (self-transitions chosen among the loops a query may play, spanning the
//! key frames) and with `--eq5-self-transitions` (the paper's graph as printed): on the stand /
//! walk / jog / hit clips both give the same transitions and the same answer to every target,
//! so the command answers what the evaluation measured.

use std::path::PathBuf;

use surfcap_eval::smg_eval::{
    STAND_WALK_JOG_HIT_CONNECTIONS, SmgEvalOptions, grid, smg_eval, stand_walk_jog_hit_subject,
};
use surfcap_formats::import::{Imported, ImportedData};
use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit};
use surfcap_smg::loop_exclusion::LoopRule;
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_synthesis::Tolerances;
use surfcap_synthesis::smg_query::{SimilarityCache, SmgGraph, SmgGraphRequest, SmgQuery};

#[test]
fn smg_query_builds_eval_smgs_graph_and_gives_its_answers() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let s = stand_walk_jog_hit_subject(&data, 1000).unwrap();
    let frames = MotionFrames::from_subject(&s);
    let (from, to) = ("stand:0", "walk:16");
    let targets = grid(&[2.0, 6.0, 12.0], &[8.0, 20.0, 33.0]);
    let dir = tempfile::tempdir().unwrap();
    let store = surfcap_mesh::derived_cache::DerivedCache::new(dir.path());
    let cache = SimilarityCache { dir: dir.path().to_path_buf(), refresh: false };
    let connect: Vec<String> = STAND_WALK_JOG_HIT_CONNECTIONS.iter().map(|(a, b)| format!("{a}:{b}")).collect();
    let mut joined = Vec::new();
    for loops in [Some(LoopRule::default()), None] {
        let opts = SmgEvalOptions { targets: targets.clone(), loops, ..Default::default() };
        let eval = smg_eval(
            &frames,
            "shared topology",
            &STAND_WALK_JOG_HIT_CONNECTIONS,
            &[(from, to)],
            &opts,
            Some((&store, false)),
            &surfcap_mesh::NoProgress,
        )
        .unwrap();
        // The command's defaults: windows 3-30, one transition per connection 15 frames apart,
        // 64 voxels, two self-transitions per sequence.
        let request = SmgGraphRequest {
            input: PathBuf::from("stand-walk-jog-hit"),
            connect: connect.clone(),
            windows: "3-30".into(),
            transitions: 1,
            separation: 15,
            resolution: 64,
            loops,
            loops_per_sequence: SmgGraphRequest::DEFAULT_LOOPS_PER_SEQUENCE,
        };
        let subject = ImportedData::Subject(Imported { subject: s.clone(), notes: Vec::new(), sources: Vec::new() });
        let keys = [("--from", from), ("--to", to)];
        let g = SmgGraph::from_data(subject, &request, Some(&cache), &keys, &surfcap_mesh::NoProgress).unwrap();
        assert!(g.similarity_cached, "the evaluation's similarity is read back");
        let mut built: Vec<(String, String, usize)> =
            g.transitions().into_iter().map(|t| (t.from, t.to, t.window)).collect();
        let mut measured: Vec<(String, String, usize)> =
            eval.transitions.iter().map(|t| (t.from.clone(), t.to.clone(), t.window)).collect();
        built.sort();
        measured.sort();
        assert_eq!(built, measured, "loops {loops:?}: the same transitions");
        let report = g.report(&request);
        assert_eq!(report.self_transitions.choice, if loops.is_some() { "spanning" } else { "eq5" });
        let row = &eval.pairs[0];
        joined.push(row.not_connected.is_none());
        if row.not_connected.is_some() {
            continue;
        }
        // Every target: eq. 6's optimum (the paper's cost, as the evaluation's per-target
        // errors are) played by the command's library, the same distance and time errors.
        for (k, &(d, secs)) in targets.iter().enumerate() {
            let q = SmgQuery {
                from: from.into(),
                to: to.into(),
                distance: d,
                time: TimeSpec { value: secs, unit: Some(TimeUnit::Seconds) },
                distance_weight: opts.w_d,
                time_weight: opts.w_t,
                paper_cost: true,
                loops: loops.unwrap_or(LoopRule { min_frames: 1, variation_floor: 0.0 }),
            };
            let played = g.play(&request, &q, &Tolerances::default()).unwrap();
            let r = &played.report;
            assert_eq!(r.target_frames as f64, (secs * 30.0).round(), "round(T x fps) frames asked");
            let answer = &row.outcomes[k];
            assert!(
                (played.path.distance_error - answer.distance_error).abs() < 1e-9
                    && played.path.time_error == answer.time_error,
                "loops {loops:?}, {d} m in {secs} s: query {} m / {} frames, eval {} m / {} frames",
                played.path.distance_error,
                played.path.time_error,
                answer.distance_error,
                answer.time_error
            );
            assert_eq!((r.frames as f64 - r.target_frames as f64).abs(), played.path.time_error);
        }
    }
    // The default graph joins the pair; the paper's graph as printed does not.
    assert_eq!(joined, [true, false]);
}

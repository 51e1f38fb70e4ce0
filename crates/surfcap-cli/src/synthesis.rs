//! Constrained synthesis as the commands run it (thesis 3.5): a subject prepared with its graph
//! and walk model from the pipeline, a search (path, key poses, distance and time), the walk
//! played by the library and written with its JSON report. Shared by `synth path | keyposes |
//! reach`, `demo` and `bench synth`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use serde_json::json;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::export::{ExportOptions, export};
use surfcap_mesh::{Subject, UpAxis};
use surfcap_motion::graph::Graph;
use surfcap_motion::path_following::{Curve, PathSearch, Restriction, follow_path, path_errors};
use surfcap_motion::timed_walk::TimedGraph;
use surfcap_motion::walk_sequence::WalkModel;
use surfcap_pipeline::constraint_files::KeyPose;
use surfcap_pipeline::walk_playback::play_walk;
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::options::OutOpts;
use crate::output::write_json;

/// A subject with its graph and walk model.
pub struct Prepared {
    pub pipe: Pipeline,
    pub params: GraphParams,
    pub graph: Arc<Graph>,
    pub model: Arc<WalkModel>,
    /// The vertices whose centre is followed (`None`: all).
    pub tracked: Option<Vec<usize>>,
    /// Time to read or build the graph and the walk model.
    pub seconds: f64,
}

impl Prepared {
    /// Reads (or builds) the graph and walk model of `params` from the pipeline.
    pub fn new(pipe: Pipeline, params: GraphParams, tracked: Option<&[usize]>) -> anyhow::Result<Self> {
        let t0 = Instant::now();
        if let Some(ids) = tracked {
            let nv = pipe.subject().topology().n_vertices();
            if let Some(v) = ids.iter().find(|&&v| v >= nv) {
                anyhow::bail!("--track {v}: the subject has vertices 0 to {}", nv - 1);
            }
        }
        let graph = pipe.graph(&params)?.value;
        let model = pipe.walk_model(&params, tracked)?.value;
        let tracked = tracked.map(<[usize]>::to_vec);
        Ok(Prepared { pipe, params, graph, model, tracked, seconds: t0.elapsed().as_secs_f64() })
    }

    pub fn subject(&self) -> &Subject {
        self.pipe.subject()
    }

    pub fn up(&self) -> UpAxis {
        self.subject().up_axis
    }
}

/// What writing a played walk produced.
pub struct Played {
    pub written: Vec<PathBuf>,
    /// Where [`Played::save_report`] writes `report`.
    pub report_path: PathBuf,
    pub report: serde_json::Value,
    /// Tracked centre of every output frame, from the written positions.
    pub centres: Vec<[f64; 3]>,
    pub transitions: usize,
}

impl Played {
    /// Writes the report to its `report_path`.
    pub fn save_report(&self) -> anyhow::Result<()> {
        write_json(&self.report_path, &self.report)
    }
}

/// Plays `walk` (Algorithm 3), writes the animation, and completes `report` with frame counts,
/// the walk and timings (the caller adds what it measures, then saves the report).
pub fn write_walk(
    ctx: &crate::Ctx,
    prep: &Prepared,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
    out: &OutOpts,
    mut report: serde_json::Value,
) -> anyhow::Result<Played> {
    let s = prep.subject();
    let played = play_walk(&prep.pipe, &prep.params, prep.tracked.as_deref(), walk, start, name)?;
    let frames = played.frames();
    let result = s.derived(format!("{}-{name}", s.name), played.sequence)?;
    let bar = crate::progress::Bar::new(ctx);
    let written = export(&result, out.format(), &out.output, ExportOptions::default(), &bar)?;
    let obj = report.as_object_mut().expect("reports are JSON objects");
    obj.insert("subject".into(), json!(s.name));
    obj.insert("graph".into(), json!({ "kind": prep.params.kind, "alpha": prep.params.alpha,
        "edges": prep.graph.edges().len(), "transitions": prep.model.n_transitions(), "prepare_seconds": prep.seconds }));
    obj.insert("fps".into(), json!(s.fps));
    obj.insert("frames".into(), json!(frames));
    obj.insert("original_frames".into(), json!(played.original_frames));
    obj.insert("synthetic_frames".into(), json!(played.synthetic_frames));
    obj.insert("transitions".into(), json!(played.transitions));
    obj.insert("blend_seconds".into(), json!(played.blend_seconds));
    obj.insert("walk".into(), json!(walk));
    obj.insert("segments".into(), json!(played.segments));
    obj.insert("outputs".into(), json!(written));
    Ok(Played {
        written,
        report_path: report_path(&out.output),
        report,
        centres: played.centres,
        transitions: played.transitions,
    })
}

/// `x.glb` -> `x.report.json`, `dir/out` -> `dir/out.report.json`.
pub fn report_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "walk".into());
    output.with_file_name(format!("{stem}.report.json"))
}

fn mean_max(x: &[f64]) -> (f64, f64) {
    (x.iter().sum::<f64>() / x.len().max(1) as f64, x.iter().copied().fold(0.0, f64::max))
}

/// Summary of a path-following run.
pub struct PathOutcome {
    pub played: Played,
    pub mean_error: f64,
    pub max_error: f64,
    pub frames: usize,
    pub search_seconds: f64,
}

/// Follows `curve` (thesis 3.5.1) on a prepared subject and writes the animation and report;
/// the errors are measured on the written frames.
pub fn run_path(
    ctx: &crate::Ctx,
    prep: &Prepared,
    curve: &Curve,
    restrictions: &[Restriction],
    start: Option<u32>,
    search: &PathSearch,
    out: &OutOpts,
) -> anyhow::Result<PathOutcome> {
    let r = follow_path(&prep.model, &prep.graph, curve, restrictions, start, search)?;
    let (pred_mean, pred_max) = mean_max(&r.errors);
    let report = json!({
        "constraint": "path",
        "curve_length": curve.length(),
        "planar": curve.axes().len() == 2,
        "search": { "window": search.window, "max_transitions": search.max_transitions, "windows": r.windows,
            "expanded": r.expanded, "seconds": r.seconds },
        "predicted": { "mean_error": pred_mean, "max_error": pred_max },
    });
    let mut played = write_walk(ctx, prep, &r.walk, &r.start, "path", out, report)?;
    let (errors, travelled) = path_errors(curve, &played.centres);
    let (mean, max) = mean_max(&errors);
    let o = played.report.as_object_mut().expect("object");
    o.insert("mean_error".into(), json!(mean));
    o.insert("max_error".into(), json!(max));
    o.insert("travelled".into(), json!(travelled));
    o.insert("per_frame".into(), json!({ "error": errors, "centre": played.centres }));
    o.insert("curve".into(), json!((0..=200).map(|k| curve.at(curve.length() * k as f64 / 200.0)).collect::<Vec<_>>()));
    played.save_report()?;
    Ok(PathOutcome { frames: errors.len(), played, mean_error: mean, max_error: max, search_seconds: r.seconds })
}

/// Summary of a key-pose timing run.
pub struct KeyposesOutcome {
    pub played: Played,
    /// The output frame at which each key pose appears.
    pub obtained: Vec<i64>,
    pub mean_abs_error: f64,
    pub search_seconds: f64,
}

/// Key-pose timing (thesis 3.5.2): the walk through `keys` meeting their requested times as
/// closely as the graph allows, written with its report.
pub fn run_keyposes(
    ctx: &crate::Ctx,
    prep: &Prepared,
    keys: &[KeyPose],
    out: &OutOpts,
) -> anyhow::Result<KeyposesOutcome> {
    let t0 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let longest = tg.longest_edge();
    let mut walk = vec![keys[0].frame];
    let mut obtained = vec![keys[0].requested];
    for (k, pair) in keys.windows(2).enumerate() {
        let now = *obtained.last().expect("one key at least");
        let w = tg
            .walk_with_duration(pair[0].frame, pair[1].frame, pair[1].requested - now, longest)
            .map_err(|e| anyhow::anyhow!("keys {} and {} ({} -> {}): {e}", k + 1, k + 2, pair[0].spec, pair[1].spec))?;
        walk.extend_from_slice(&w.walk[1..]);
        obtained.push(now + w.frames as i64);
    }
    let search_seconds = t0.elapsed().as_secs_f64();
    let errors: Vec<i64> = keys.iter().zip(&obtained).map(|(k, o)| (o - k.requested).abs()).collect();
    let mean_abs_error = errors.iter().sum::<i64>() as f64 / errors.len() as f64;
    let report = json!({
        "constraint": "keyposes",
        "keys": keys.iter().zip(&obtained).map(|(k, o)| json!({
            "frame": k.spec, "input_time": k.input, "requested_time": k.requested, "obtained_time": o,
            "error": (o - k.requested).abs() })).collect::<Vec<_>>(),
        "mean_abs_error_frames": mean_abs_error,
        "search_seconds": search_seconds,
    });
    let played = write_walk(ctx, prep, &walk, &PlaneMotion::identity(prep.up()), "keyposes", out, report)?;
    played.save_report()?;
    Ok(KeyposesOutcome { played, obtained, mean_abs_error, search_seconds })
}

//! `surfcap view SUBJECT --direct`: the viewer's [`Director`] on a subject prepared once (its
//! graph and walk model read from the cache or built, as `synth` does), answering the page's
//! directions with `surfcap_synthesis`'s queries run in memory: a path drawn on the ground
//! (thesis 3.5.1), key poses at new times (3.5.2), a distance in a time (Huang et al. 2009's
//! reach), or one transition of the graph (2.5.4, Algorithm 2, as `surfcap transition` makes it).
//! The last result is kept, and written on demand as glb, abc or usda for the page to download.

use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

use surfcap_formats::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::{FrameLabel, NoProgress, Subject};
use surfcap_motion::edge_weights::EdgeWeights;
use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit, key_poses_from_rows};
use surfcap_pipeline::{GraphKind, GraphParams};
use surfcap_synthesis::{Constraint, CurveSource, Output, PathRequest, Prepared, ReachRequest, SizeLimits, Tolerances};
use surfcap_view::direct::{
    Directed, Direction, Director, Exported, GraphTimeline, KeyAsk, TimelineArc, TimelineSequence,
};
use surfcap_view::{Overlay, ViewItem};

use crate::options::{AlphaOpt, CacheOpts, SourceOpts, TableOpts, count};

/// `--direct` and the graph it directs in (as `synth`'s graph options).
#[derive(clap::Args, Debug, Clone)]
pub struct DirectOpts {
    /// Direct the subject from the page: draw a path on the ground, move key poses on the
    /// timeline, ask for a distance in a time, or play one transition of the graph; the result
    /// is synthesised here and played, and can be downloaded as glb, abc or usda. Needs one
    /// subject; its graph is read from the cache or built first, as `synth` does.
    #[arg(long)]
    pub direct: bool,
    /// With --direct: essential, sparse-essential or motion (as `synth --kind`).
    #[arg(long, default_value = "essential", requires = "direct")]
    pub kind: GraphKind,
    /// With --direct and --kind sparse-essential: transitions kept per frame.
    #[arg(long, value_parser = count, requires = "direct")]
    pub k: Option<usize>,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
}

/// The director of `--direct` on the one subject of `paths`, or `None` without `--direct`.
pub fn director(
    ctx: &crate::Ctx,
    o: &DirectOpts,
    paths: &[std::path::PathBuf],
    source: &SourceOpts,
) -> anyhow::Result<Option<std::sync::Arc<dyn Director>>> {
    if !o.direct {
        return Ok(None);
    }
    let [path] = paths else {
        anyhow::bail!("--direct: give exactly one subject to direct ({} given)", paths.len());
    };
    let s = crate::options::open(ctx, path, source)?;
    let pipe = o.cache.pipeline(ctx, s)?;
    let params = GraphParams { table: o.table.params_for(&pipe)?, kind: o.kind.with_k(o.k)?, alpha: o.alpha.value() };
    let prep = Prepared::new(pipe, params, None)?;
    let limits = SizeLimits { max_memory: ctx.max_memory, ..SizeLimits::default() };
    let timeline = timeline(&prep);
    if !ctx.quiet && !ctx.json {
        eprintln!(
            "surfcap view: directing {} in its {} ({:.2} s to prepare)",
            path.display(),
            timeline.graph,
            prep.seconds
        );
    }
    let d: std::sync::Arc<dyn Director> =
        std::sync::Arc::new(SubjectDirector { prep, limits, timeline, last: Mutex::new(None) });
    Ok(Some(d))
}

/// A prepared subject answering the page's directions.
struct SubjectDirector {
    prep: Prepared,
    limits: SizeLimits,
    timeline: GraphTimeline,
    /// The last result, what the page exports.
    last: Mutex<Option<(String, Subject)>>,
}

/// The graph of `prep` as the page's timeline: a row per sequence, an arc per edge that is not
/// a step to the next frame of the same sequence nor a looping clip's wrap.
fn timeline(prep: &Prepared) -> GraphTimeline {
    let s = prep.subject();
    let index = s.frame_index();
    let loops = prep.pipe.loops();
    let sequences = s
        .sequences()
        .iter()
        .enumerate()
        .map(|(k, q)| TimelineSequence {
            name: q.name.clone(),
            first: index.range(k).start,
            frames: q.n_frames(),
            looping: loops.iter().any(|l| l.sequence == k),
        })
        .collect();
    let is_wrap = |i: u32, j: u32| loops.iter().any(|l| l.last == i && l.first == j);
    let transitions: Vec<TimelineArc> = prep
        .graph
        .edges()
        .iter()
        .filter(|e| !EdgeWeights::is_original(index, e.from as usize, e.to as usize) && !is_wrap(e.from, e.to))
        .map(|e| TimelineArc {
            from: e.from as usize,
            to: e.to as usize,
            from_frame: index.label(e.from as usize),
            to_frame: index.label(e.to as usize),
            weight: e.weight,
        })
        .collect();
    let kind = match prep.params.kind {
        GraphKind::Essential => "essential graph".to_string(),
        GraphKind::Motion => "motion graph".to_string(),
        GraphKind::SparseEssential { k } => format!("sparse essential graph (k {k})"),
    };
    let graph = format!(
        "{kind}, alpha {}: {} edges, {}",
        prep.params.alpha,
        prep.graph.edges().len(),
        crate::output::count_of(transitions.len(), "transition")
    );
    GraphTimeline {
        subject: s.name.clone(),
        fps: s.fps,
        units: s.units.symbol().to_string(),
        graph,
        sequences,
        transitions,
    }
}

/// Output frames where a transition starts: the first frame of every run of synthetic frames.
fn transition_marks(labels: &[FrameLabel]) -> Vec<usize> {
    (0..labels.len())
        .filter(|&f| labels[f] == FrameLabel::Synthetic && (f == 0 || labels[f - 1] != FrameLabel::Synthetic))
        .collect()
}

/// The page's item of a one-sequence animation, with its centre track, the curve asked for if
/// any, its transitions and what was asked and achieved.
fn item_of(
    animation: &Subject,
    centres: Option<Vec<[f64; 3]>>,
    curve: Option<Vec<[f64; 3]>>,
    centre_errors: Option<Vec<f64>>,
    constraints: &[Constraint],
) -> ViewItem {
    let mut item = crate::view_items::view_items(animation, &[]).remove(0);
    let labels = &animation.sequences()[0].labels;
    item.overlay = centres.map(|centres| Overlay {
        curve,
        centres,
        transitions: transition_marks(labels),
        constraints: constraints.iter().map(Constraint::summary).collect(),
        centre_errors,
    });
    item
}

impl SubjectDirector {
    fn subject(&self) -> &Subject {
        self.prep.subject()
    }

    fn run(&self, d: &Direction) -> anyhow::Result<(Directed, Subject)> {
        let t0 = Instant::now();
        let out = Output::in_memory(Tolerances::default());
        let s = self.subject();
        let length = |x: f64| crate::output::length(x, &s.units, 2);
        let (item, summary, animation) = match d {
            Direction::Path { points } => {
                anyhow::ensure!(
                    points.len() >= 2,
                    "the drawn path has {} point(s); expected at least two",
                    points.len()
                );
                let request = PathRequest {
                    curve: CurveSource::Points {
                        name: "the drawn path".into(),
                        columns: 3,
                        values: points.iter().flatten().copied().collect(),
                    },
                    planar: true,
                    tags: Vec::new(),
                    start: None,
                    track: Vec::new(),
                    window: None,
                    max_transitions: None,
                    branching: 8,
                };
                let checked = request.check(&self.prep.pipe, &out, &self.limits)?;
                let o = self.prep.follow_path(&checked.query(), &out, &NoProgress)?;
                let verb = if o.constraints.iter().any(|c| c.missed) { "missed" } else { "followed" };
                let summary = vec![format!(
                    "{verb} a {} path: {} frames, {} transitions; centre error mean {}, max {}",
                    length(o.report.curve_length),
                    o.frames,
                    o.played.transitions,
                    crate::output::length(o.mean_error, &s.units, 3),
                    crate::output::length(o.max_error, &s.units, 3)
                )];
                let item = item_of(
                    &o.played.output,
                    Some(o.played.centres.clone()),
                    Some(o.report.curve.clone()),
                    Some(o.report.per_frame.error.clone()),
                    &o.constraints,
                );
                (item, summary, o.played.output)
            }
            Direction::Keyposes { keys } => {
                let rows = keys
                    .iter()
                    .enumerate()
                    .map(|(k, KeyAsk { frame, time })| (k + 1, vec![frame.clone(), time.to_string()]))
                    .collect();
                let keys = key_poses_from_rows(rows, Path::new("the key poses"), s)?;
                surfcap_synthesis::check_key_poses(s, &keys, "the key poses", &out, &self.limits)?;
                let o = self.prep.time_key_poses(&keys, &out, &NoProgress)?;
                let mut summary = vec![format!(
                    "{} key poses met within {:.1} frames on average ({} frames)",
                    keys.len(),
                    o.mean_abs_error,
                    o.played.output.n_frames()
                )];
                for k in &o.report.keys {
                    let why = k.unreachable_why.as_deref().map(|w| format!(": {w}")).unwrap_or_default();
                    summary.push(format!(
                        "{} asked at frame {}, shown at {}{why}",
                        k.frame, k.requested_time, k.obtained_time
                    ));
                }
                let item = item_of(&o.played.output, Some(o.played.centres.clone()), None, None, &o.constraints);
                (item, summary, o.played.output)
            }
            Direction::Reach { from, to, distance, seconds } => {
                let request = ReachRequest {
                    from: from.clone(),
                    to: to.clone(),
                    distance: *distance,
                    time: TimeSpec { value: *seconds, unit: Some(TimeUnit::Seconds) },
                    distance_scale: 0.3,
                    time_scale: 10.0,
                };
                let query = request.check(s, &out, &self.limits)?;
                let o = self.prep.reach(&query, &out, &NoProgress)?;
                let r = &o.report;
                let mut summary = vec![format!(
                    "{} -> {}: {} travelled (asked {}) in {:.2} s (asked {:.2} s)",
                    o.from_label,
                    o.to_label,
                    length(r.distance),
                    length(*distance),
                    r.seconds,
                    r.target_seconds
                )];
                if let Some(why) = &r.unreachable_why {
                    summary.push(format!("no walk of the graph can meet this target: {why}"));
                }
                let item = item_of(&o.played.output, Some(o.played.centres.clone()), None, None, &o.constraints);
                (item, summary, o.played.output)
            }
            Direction::Transition { from, to } => {
                let (i, j) = (s.resolve_frame(from)?, s.resolve_frame(to)?);
                let t = surfcap_synthesis::transition(
                    &self.prep.pipe,
                    (i, from.as_str()),
                    (j, to.as_str()),
                    &self.prep.params.table,
                )?;
                let r = &t.report;
                let summary = vec![format!(
                    "transition {} -> {}: source segment {} frames, destination {}, {} frames, normalised cost {:.3}",
                    r.from_frame, r.to_frame, r.source_length, r.destination_length, r.duration, r.normalised_cost
                )];
                let item = item_of(&t.animation, None, None, None, &[]);
                (item, summary, t.animation)
            }
        };
        let seconds = t0.elapsed().as_secs_f64();
        Ok((Directed { item, summary, seconds }, animation))
    }
}

/// What a direction is called in file names.
fn kind_name(d: &Direction) -> &'static str {
    match d {
        Direction::Path { .. } => "path",
        Direction::Keyposes { .. } => "keyposes",
        Direction::Reach { .. } => "reach",
        Direction::Transition { .. } => "transition",
    }
}

impl Director for SubjectDirector {
    fn timeline(&self) -> &GraphTimeline {
        &self.timeline
    }

    fn direct(&self, d: &Direction) -> Result<Directed, String> {
        match self.run(d) {
            Ok((directed, animation)) => {
                *self.last.lock().unwrap_or_else(|e| e.into_inner()) = Some((kind_name(d).to_string(), animation));
                Ok(directed)
            }
            Err(e) => Err(format!("{} not made: {e:#}", kind_name(d))),
        }
    }

    fn export(&self, format: &str) -> Result<Exported, String> {
        let (f, content_type) = match format {
            "glb" => (ExportFormat::Glb, "model/gltf-binary"),
            "abc" => (ExportFormat::Abc, "application/octet-stream"),
            "usda" => (ExportFormat::Usda, "model/vnd.usda"),
            _ => return Err(format!("export {format:?}: expected glb, abc or usda")),
        };
        let last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let Some((name, animation)) = last.as_ref() else {
            return Err("nothing to export yet: direct an animation first".into());
        };
        let file = format!("{name}.{format}");
        let dir = tempfile::tempdir().map_err(|e| format!("export {file}: no temporary folder: {e}"))?;
        let path = dir.path().join(&file);
        export(animation, f, &path, ExportOptions::default(), &NoProgress)
            .map_err(|e| format!("export {file}: {e}"))?;
        let bytes = std::fs::read(&path).map_err(|e| format!("export {file}: {e}"))?;
        Ok(Exported { name: file, content_type, bytes })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transitions_are_marked_where_synthetic_runs_start() {
        use FrameLabel::{Original as O, Synthetic as S};
        assert_eq!(transition_marks(&[O, O, S, S, O, S, O]), vec![2, 5]);
        assert_eq!(transition_marks(&[S, O]), vec![0]);
        assert!(transition_marks(&[O, O]).is_empty());
    }
}

//! Path following (thesis 3.5.1): the centre of mass (or of chosen vertices) follows a 3D or
//! ground-plane curve; the walk is searched window by window in the graph, played, written, and
//! its errors measured on the written frames.

use std::path::PathBuf;
use std::sync::Arc;

use serde::Serialize;
use surfcap_mesh::Progress;
use surfcap_motion::path_following::{Curve, PathSearch, Restriction, follow_path, path_errors};
use surfcap_pipeline::constraint_files::{curve_from_points, parse_restriction, read_curve};
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::animation_output::write_report;
use crate::constraint::Constraint;
use crate::error::{Context, Error, Result};
use crate::prepared::{Output, Prepared};
use crate::request_size::{Request, SizeLimits, fastest_speed};
use crate::walk_output::{Played, WalkReport, play_and_write, pose_distance_to_output};
use crate::words::{length, length_unit, mean, unit_name};

/// A path query on a prepared subject.
#[derive(Debug, Clone)]
pub struct PathQuery<'a> {
    pub curve: &'a Curve,
    /// Motion types allowed on parts of the curve.
    pub restrictions: &'a [Restriction],
    /// The first frame (global); default: the best of all frames from which the walk can go on.
    pub start: Option<u32>,
    pub search: PathSearch,
}

/// The report's `search`.
#[derive(Debug, Clone, Serialize)]
pub struct SearchReport {
    pub window: f64,
    pub max_transitions: usize,
    pub windows: usize,
    pub expanded: u64,
    pub seconds: f64,
}

/// Mean and largest centre error.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorSummary {
    pub mean_error: f64,
    pub max_error: f64,
}

/// The report's `per_frame` of a path: centre error and centre of every output frame.
#[derive(Debug, Clone, Serialize)]
pub struct PathPerFrame {
    pub error: Vec<f64>,
    pub centre: Vec<[f64; 3]>,
}

/// The report of a path-following run (`<output>.report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct PathReport {
    /// `path`.
    pub constraint: &'static str,
    pub curve_length: f64,
    pub planar: bool,
    pub search: SearchReport,
    /// The errors the search predicted from the walk model.
    pub predicted: ErrorSummary,
    #[serde(flatten)]
    pub walk: WalkReport,
    /// Measured on the written frames.
    pub mean_error: f64,
    pub max_error: f64,
    /// Arc length of the curve covered.
    pub travelled: f64,
    pub path_length: f64,
    pub net_displacement: f64,
    pub per_frame: PathPerFrame,
    /// The curve, 201 points evenly spaced along it.
    pub curve: Vec<[f64; 3]>,
    /// Pose distance between the asked start frame and the first frame shown.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose_distance_start: Option<f64>,
    pub constraints: Vec<Constraint>,
    /// Where the path was missed: the stretches of the curve (arc lengths from, to) along which
    /// the centre was farther from the curve than the tolerance, with the curve's sharpest turn
    /// there (degrees per unit of length); empty when the path was followed.
    pub missed_stretches: Vec<MissedStretch>,
}

/// A stretch of the curve the walk did not follow within the tolerance.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MissedStretch {
    /// Arc lengths along the curve where the stretch starts and ends.
    pub from: f64,
    pub to: f64,
    /// The curve's sharpest turn over the stretch, degrees per unit of length (measured over
    /// one unit of arc length).
    pub turn_degrees_per_unit: f64,
}

/// The stretches of `curve` along which `errors` (per frame, at arc lengths `arcs`) exceed
/// `tolerance`.
fn missed_stretches(curve: &Curve, arcs: &[f64], errors: &[f64], tolerance: f64) -> Vec<MissedStretch> {
    let mut out: Vec<MissedStretch> = Vec::new();
    let mut open: Option<f64> = None;
    let heading = |s: f64| {
        let s = s.clamp(0.0, (curve.length() - 0.05).max(0.0));
        let axes = curve.axes();
        let (a, b) = (curve.at(s), curve.at(s + 0.05));
        let (i, j) = (axes[0], axes[axes.len() - 1]);
        (b[j] - a[j]).atan2(b[i] - a[i])
    };
    let close = |from: f64, to: f64| {
        let steps = ((to - from) / 0.1).ceil().max(1.0) as usize;
        let turn = (0..=steps)
            .map(|k| {
                let s = from + (to - from) * k as f64 / steps as f64;
                surfcap_motion::blend::wrap_angle(heading(s + 0.5) - heading(s - 0.5)).abs().to_degrees()
            })
            .fold(0.0, f64::max);
        MissedStretch { from, to, turn_degrees_per_unit: turn }
    };
    for (k, (&s, &e)) in arcs.iter().zip(errors).enumerate() {
        match (open, e > tolerance) {
            (None, true) => open = Some(s),
            (Some(from), false) => {
                out.push(close(from, arcs[k - 1].max(from)));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(from) = open {
        out.push(close(from, arcs.last().copied().unwrap_or(from)));
    }
    out
}

/// A path-following run: the animation written, its report (written beside it) and summary.
pub struct PathOutcome {
    pub played: Played,
    pub report: PathReport,
    pub mean_error: f64,
    pub max_error: f64,
    pub frames: usize,
    pub search_seconds: f64,
    pub constraints: Vec<Constraint>,
}

fn mean_max(x: &[f64]) -> (f64, f64) {
    (mean(x.iter().copied()), x.iter().copied().fold(0.0, f64::max))
}

impl Prepared {
    /// Follows the query's curve and writes the animation and its report to `out`.
    pub fn follow_path(&self, q: &PathQuery, out: &Output, progress: &dyn Progress) -> Result<PathOutcome> {
        let (curve, search) = (q.curve, &q.search);
        let r = follow_path(&self.model, &self.graph, curve, q.restrictions, q.start, search).map_err(|e| {
            // The search's own messages give lengths as bare numbers (the motion library does
            // not know units): say which unit they are in.
            use surfcap_motion::Error::{PathStalls, PathStuck};
            if matches!(e, PathStuck { .. } | PathStalls { .. }) {
                Error::Context {
                    context: format!(
                        "the curve could not be followed (lengths in {})",
                        unit_name(&self.subject().units)
                    ),
                    source: Box::new(e.into()),
                }
            } else {
                e.into()
            }
        })?;
        let (pred_mean, pred_max) = mean_max(&r.errors);
        let played = play_and_write(self, &r.walk, &r.start, "path", out, progress)?;
        let (errors, travelled) = path_errors(curve, &played.centres);
        let (mean, max) = mean_max(&errors);
        let tolerance = out.tolerances.distance(curve.length());
        let mut arcs = Vec::with_capacity(played.centres.len());
        for (k, c) in played.centres.iter().enumerate() {
            let before = if k == 0 { 0.0 } else { arcs[k - 1] + curve.distance(&played.centres[k - 1], c) };
            arcs.push(before);
        }
        let missed = missed_stretches(curve, &arcs, &errors, tolerance);
        // Path length adds up the centre's sway; the net displacement says whether it went anywhere.
        let (net, _) = surfcap_motion::clip_travel::horizontal_travel(&played.centres, self.up());
        let pose_distance_start = match q.start {
            // The pose shown first against the asked start frame.
            Some(f) => Some(pose_distance_to_output(self, &played.output, f, 0)?),
            None => None,
        };
        let constraints = vec![
            Constraint::new("path", length_unit(self.subject()), curve.length(), travelled, max, tolerance)
                .relative_to(curve.length()),
        ];
        let report = PathReport {
            constraint: "path",
            curve_length: curve.length(),
            planar: curve.axes().len() == 2,
            search: SearchReport {
                window: search.window,
                max_transitions: search.max_transitions,
                windows: r.windows,
                expanded: r.expanded,
                seconds: r.seconds,
            },
            predicted: ErrorSummary { mean_error: pred_mean, max_error: pred_max },
            walk: played.report.clone(),
            mean_error: mean,
            max_error: max,
            travelled,
            path_length: travelled,
            net_displacement: net,
            per_frame: PathPerFrame { error: errors.clone(), centre: played.centres.clone() },
            curve: (0..=200).map(|k| curve.at(curve.length() * k as f64 / 200.0)).collect(),
            pose_distance_start,
            constraints: constraints.clone(),
            missed_stretches: missed,
        };
        if let Some(path) = &played.report_path {
            write_report(path, &report)?;
        }
        Ok(PathOutcome {
            frames: errors.len(),
            played,
            report,
            mean_error: mean,
            max_error: max,
            search_seconds: r.seconds,
            constraints,
        })
    }
}

/// Where a curve comes from: a CSV file (`--curve`), or points a front end already holds.
#[derive(Debug, Clone)]
pub enum CurveSource {
    /// CSV of curve points (x,y,z in the subject's axes and units, or two ground-plane columns).
    File(PathBuf),
    /// Points of `columns` (2: ground-plane coordinates, 3: x,y,z) finite numbers each, row
    /// after row; `name` says where they came from in messages (e.g. `curve`).
    Points { name: String, columns: usize, values: Vec<f64> },
}

impl CurveSource {
    /// The curve, read as `read_curve` reads a file (a two-column curve, or `planar`, follows
    /// the ground-plane projection).
    pub fn read(&self, up: surfcap_mesh::UpAxis, planar: bool) -> Result<Curve> {
        Ok(match self {
            CurveSource::File(path) => read_curve(path, up, planar)?,
            CurveSource::Points { name, columns, values } => {
                curve_from_points(values, *columns, std::path::Path::new(name), up, planar)?
            }
        })
    }

    /// How the request names the curve in messages: `--curve FILE`, or the points' name.
    fn describe(&self) -> String {
        match self {
            CurveSource::File(path) => format!("--curve {}", path.display()),
            CurveSource::Points { name, values, columns } => {
                format!("{name} ({} points)", values.len() / (*columns).max(1))
            }
        }
    }
}

/// What `synth path` asks: a curve and how to follow it.
#[derive(Debug, Clone)]
pub struct PathRequest {
    /// The curve (`--curve`: a CSV file of x,y,z in the subject's axes and units, or two
    /// ground-plane columns).
    pub curve: CurveSource,
    /// Follow only the projection on the ground plane (implied by a two-column curve).
    pub planar: bool,
    /// Motion types on parts of the curve, `TAG:FROM-TO` (arc lengths).
    pub tags: Vec<String>,
    /// The first frame (`sequence:frame` or global).
    pub start: Option<String>,
    /// Follow the centre of these vertices instead of the centre of mass.
    pub track: Vec<usize>,
    /// Window, transitions per window (`None`: [`PathSearch::for_clips`]'s for the subject's
    /// looping clips), branching (the frame-rate dependent rest from the subject's fps).
    pub window: Option<f64>,
    pub max_transitions: Option<usize>,
    pub branching: usize,
}

/// A path request checked against its subject: the query's owned parts.
#[derive(Debug, Clone)]
pub struct CheckedPath {
    pub curve: Curve,
    pub restrictions: Vec<Restriction>,
    pub start: Option<u32>,
    pub search: PathSearch,
}

impl CheckedPath {
    /// The query to run on the prepared subject.
    pub fn query(&self) -> PathQuery<'_> {
        PathQuery {
            curve: &self.curve,
            restrictions: &self.restrictions,
            start: self.start,
            search: self.search.clone(),
        }
    }
}

impl PathRequest {
    /// The request checked and sized before any search: the curve read, the animation's size
    /// estimated from the subject's fastest motion against `limits`, the tags parsed, the clips
    /// checked to travel, the start frame resolved and the search's defaults taken from the
    /// subject's looping clips (`pipe`'s). (`track` is the prepared subject's: see
    /// [`synthesize_path`].)
    pub fn check(&self, pipe: &Pipeline, out: &Output, limits: &SizeLimits) -> Result<CheckedPath> {
        let s = pipe.subject();
        let curve = self.curve.read(s.up_axis, self.planar)?;
        if let Some(speed) = fastest_speed(s, curve.axes()) {
            let what = format!(
                "{} ({} long, the subject's fastest motion covers {} a second)",
                self.curve.describe(),
                length(curve.length(), &s.units, 1),
                length(speed, &s.units, 2)
            );
            let frames = curve.length() / speed * s.fps;
            limits.check(&Request { what, frames, subject: s, search_bytes: 0, format: out.format() })?;
        }
        let restrictions = self
            .tags
            .iter()
            .map(|t| parse_restriction(s, t).with_context(|| format!("--tags {t:?}")))
            .collect::<Result<Vec<_>>>()?;
        let travel = surfcap_motion::clip_travel::subject_travel(s);
        crate::travel_check::require_travel(s, &travel, "a path constraint", None)?;
        for (t, r) in self.tags.iter().zip(&restrictions) {
            crate::travel_check::require_travel(s, &travel, &format!("--tags {t}"), Some(&r.allowed))?;
        }
        let start = self.start.as_deref().map(|x| s.resolve_frame(x)).transpose()?.map(|g| g as u32);
        let shortest_loop =
            pipe.loops().iter().map(|l| s.frame_index().range(l.sequence).len() as f64 / s.fps).min_by(f64::total_cmp);
        let defaults = PathSearch::for_clips(s.fps, shortest_loop);
        let search = PathSearch {
            window: self.window.unwrap_or(defaults.window),
            max_transitions: self.max_transitions.unwrap_or(defaults.max_transitions),
            branching: self.branching,
            ..defaults
        };
        Ok(CheckedPath { curve, restrictions, start, search })
    }
}

/// One path-following synthesis from an unprepared subject: the playback opened and the
/// request checked and sized ([`PathRequest::check`]) before any work, then the subject
/// prepared with `prepare` (appearance and variants: [`crate::Playback`]) and the path followed.
pub fn synthesize_path(
    pipe: impl Into<Arc<Pipeline>>,
    params: GraphParams,
    request: &PathRequest,
    playback: crate::Playback,
    out: &Output,
    limits: &SizeLimits,
    progress: &dyn Progress,
) -> Result<PathOutcome> {
    let pipe: Arc<Pipeline> = pipe.into();
    let playback = playback.open(pipe.subject(), out)?;
    let checked = request.check(&pipe, out, limits)?;
    let tracked = (!request.track.is_empty()).then_some(request.track.as_slice());
    let prep = playback.prepare(pipe, params, tracked)?;
    prep.follow_path(&checked.query(), out, progress)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 m line then a quarter circle of radius 2: frames off by more than the tolerance
    /// make one stretch, measured where it is along the curve, with the circle's turn
    /// (1/2 rad per metre, about 29 degrees) and none of the line's.
    #[test]
    fn missed_stretches_say_where_and_how_sharply_the_curve_turns() {
        let mut pts = vec![[0.0, 0.0, 0.0]];
        pts.extend((0..=40).map(|k| {
            let a = std::f64::consts::FRAC_PI_2 * k as f64 / 40.0;
            [10.0 + 2.0 * a.sin(), 0.0, 2.0 - 2.0 * a.cos()]
        }));
        let curve = Curve::new(pts, vec![0, 2]).unwrap();
        let arcs: Vec<f64> = (0..=26).map(|k| 0.5 * k as f64).collect();
        let errors: Vec<f64> = arcs.iter().map(|&s| if (11.0..=12.5).contains(&s) { 0.5 } else { 0.01 }).collect();
        let m = missed_stretches(&curve, &arcs, &errors, 0.1);
        assert_eq!(m.len(), 1, "{m:?}");
        assert_eq!((m[0].from, m[0].to), (11.0, 12.5));
        assert!((m[0].turn_degrees_per_unit - 28.6).abs() < 1.5, "{m:?}");
        let on_line = missed_stretches(
            &curve,
            &arcs,
            &arcs.iter().map(|&s| if s <= 5.0 { 0.5 } else { 0.0 }).collect::<Vec<_>>(),
            0.1,
        );
        assert_eq!((on_line[0].from, on_line[0].to), (0.0, 5.0));
        assert!(on_line[0].turn_degrees_per_unit < 0.1, "{on_line:?}");
        assert!(missed_stretches(&curve, &arcs, &vec![0.0; arcs.len()], 0.1).is_empty());
    }
}

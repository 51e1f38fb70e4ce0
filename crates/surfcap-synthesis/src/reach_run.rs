//! Reach (Huang et al. 2009's constraint, searched in the essential graph): from one frame to
//! another covering a ground distance in a time, at the least realism cost
//! (`TimedGraph::walk_with_distance_and_time`: distance and timing errors weighed by their
//! scales against the walk's transition cost).

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::Progress;
use surfcap_motion::timed_walk::{ExcludedLoop, LoopRule, TimedGraph, Unreachable, distance_search_table_bytes};
use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit};
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::animation_output::{Travel, write_report};
use crate::constraint::Constraint;
use crate::error::{Result, refuse};
use crate::prepared::{Output, Prepared};
use crate::request_size::{Request, SizeLimits};
use crate::walk_output::{Played, WalkReport, play_and_write, pose_distance_to_output};
use crate::words::length_unit;

/// A reach query: frames, distance, duration and the scales of the realism cost.
#[derive(Debug, Clone)]
pub struct ReachQuery {
    /// Start and end frames as the user wrote them (for the report).
    pub from_spec: String,
    pub to_spec: String,
    /// Start and end frames, global.
    pub from: u32,
    pub to: u32,
    /// Ground-plane distance the centre of mass must travel (subject units).
    pub distance: f64,
    /// Duration as frames shown, start included: a duration T is round(T x fps) frames (the
    /// surface motion graph's count), so the walk takes one step fewer. At least 2.
    pub frames: usize,
    /// Distance error and timing error (frames) worth one unit of realism cost (Huang et al.:
    /// 0.3 m and 10 frames).
    pub distance_scale: f64,
    pub time_scale: f64,
}

/// The report of a reach run.
#[derive(Debug, Clone, Serialize)]
pub struct ReachReport {
    /// `reach`.
    pub constraint: &'static str,
    pub from: String,
    pub to: String,
    pub target_distance: f64,
    pub distance: f64,
    pub distance_error: f64,
    pub target_seconds: f64,
    pub seconds: f64,
    /// Frames shown for the asked duration and for the obtained one, start included: a
    /// duration T is round(T x fps) frames, as the surface motion graph counts them
    /// (`target_seconds` and `seconds` are these counts over fps).
    pub target_frames: usize,
    pub obtained_frames: usize,
    pub time_error_frames: usize,
    pub realism_cost: f64,
    pub total_cost: f64,
    pub search_seconds: f64,
    /// Both targets met within the tolerances (`--tolerance`, `--frame-tolerance`).
    pub met: bool,
    /// When not met: why no walk of the graph can meet them (the surface motion graph's
    /// reasons: too_short, too_near, no_loop, too_fast, too_slow, granularity), if the graph
    /// proves it; absent on a met target or one the search missed.
    pub unreachable: Option<Unreachable>,
    /// The same reason in words.
    pub unreachable_why: Option<String>,
    /// Loops never played to pad time, and the rule that excluded them.
    pub loop_rule: LoopRule,
    pub excluded_loops: Vec<ExcludedLoop>,
    #[serde(flatten)]
    pub walk: WalkReport,
    #[serde(flatten)]
    pub travel: Travel,
    /// Pose distances between the frames asked for and the first and last frames shown.
    pub pose_distance_from: f64,
    pub pose_distance_to: f64,
    pub constraints: Vec<Constraint>,
}

/// A reach run: the animation written, its report and summary.
pub struct ReachOutcome {
    pub played: Played,
    pub report: ReachReport,
    /// The start and end frames as `sequence:frame`.
    pub from_label: String,
    pub to_label: String,
    pub constraints: Vec<Constraint>,
}

impl Prepared {
    /// The walk of the reach query, written with its report to `out`.
    pub fn reach(&self, q: &ReachQuery, out: &Output, progress: &dyn Progress) -> Result<ReachOutcome> {
        let t0 = Instant::now();
        // Degenerate loops (too short, or too still) never pad time.
        let pose = self.pipe.chain_distances()?.value;
        let loop_rule = LoopRule::default();
        let (tg, excluded_loops) = TimedGraph::new(&self.graph, &self.model)
            .without_degenerate_loops(loop_rule, &|i, j| pose.values[i * pose.n + j]);
        let scales = (q.distance_scale, q.time_scale);
        let tol = &out.tolerances;
        let tolerance = (tol.distance(q.distance), tol.frames().floor() as usize);
        // The duration is frames shown, start included: the walk takes one step fewer.
        let steps = q.frames.saturating_sub(1);
        let found = tg.walk_within(q.from, q.to, (q.distance, steps), scales, tolerance, tg.longest_edge())?;
        let (w, cost) = (found.walk, found.total_cost);
        let search_seconds = t0.elapsed().as_secs_f64();
        // Counts below are frames shown, start included, as `frames` is: a walk of n steps
        // shows n + 1 frames.
        let (asked_frames, obtained_frames) = (q.frames, w.frames + 1);
        let distance_error = (w.distance - q.distance).abs();
        let time_error = obtained_frames.abs_diff(asked_frames);
        let fps = self.subject().fps;
        let played = play_and_write(self, &w.walk, &PlaneMotion::identity(self.up()), "reach", out, progress)?;
        // The viewer draws the centre track over the animation, as it does for paths.
        let travel = Travel::of(&played.centres, self.up());
        // The poses shown first and last against the frames asked for there.
        let last = played.output.n_frames() - 1;
        let pose_distance_from = pose_distance_to_output(self, &played.output, q.from, 0)?;
        let pose_distance_to = pose_distance_to_output(self, &played.output, q.to, last)?;
        let constraints = vec![
            Constraint::new(
                "distance",
                length_unit(self.subject()),
                q.distance,
                w.distance,
                distance_error,
                tol.distance(q.distance),
            )
            .relative_to(q.distance),
            Constraint::new(
                "time",
                "frames",
                asked_frames as f64,
                obtained_frames as f64,
                time_error as f64,
                tol.frames(),
            )
            .relative_to(asked_frames as f64),
        ];
        let report = ReachReport {
            constraint: "reach",
            from: q.from_spec.clone(),
            to: q.to_spec.clone(),
            target_distance: q.distance,
            distance: w.distance,
            distance_error,
            target_seconds: asked_frames as f64 / fps,
            seconds: obtained_frames as f64 / fps,
            target_frames: asked_frames,
            obtained_frames,
            time_error_frames: time_error,
            realism_cost: w.cost,
            total_cost: cost,
            search_seconds,
            met: found.met,
            unreachable_why: found.unreachable.as_ref().map(|u| u.in_unit(&length_unit(self.subject()))),
            unreachable: found.unreachable,
            loop_rule,
            excluded_loops,
            walk: played.report.clone(),
            travel,
            pose_distance_from,
            pose_distance_to,
            constraints: constraints.clone(),
        };
        if let Some(path) = &played.report_path {
            write_report(path, &report)?;
        }
        let index = self.subject().frame_index();
        Ok(ReachOutcome {
            played,
            report,
            from_label: index.label(q.from as usize),
            to_label: index.label(q.to as usize),
            constraints,
        })
    }
}

/// What `synth reach` asks, as the user wrote it.
#[derive(Debug, Clone)]
pub struct ReachRequest {
    /// Start and end frames (`sequence:frame` or global).
    pub from: String,
    pub to: String,
    /// Ground-plane distance (subject units), >= 0.
    pub distance: f64,
    /// Duration: seconds (bare or `3s`, round(T x fps) frames shown, start included) or
    /// frames shown (`90f`).
    pub time: TimeSpec,
    pub distance_scale: f64,
    pub time_scale: f64,
}

impl ReachRequest {
    /// The duration as given, with its unit.
    pub fn time_text(&self) -> String {
        match self.time.unit {
            Some(TimeUnit::Frames) => format!("{}f", self.time.value),
            Some(TimeUnit::Seconds) | None => format!("{}s", self.time.value),
        }
    }
}

impl ReachRequest {
    /// The request checked and sized before any search: the frames resolved, the duration
    /// turned into frames shown (at least two), the animation and the search's tables sized
    /// against `limits`, and, for a distance, the clips checked to travel.
    pub fn check(&self, s: &surfcap_mesh::Subject, out: &Output, limits: &SizeLimits) -> Result<ReachQuery> {
        let (from, to) = (s.resolve_frame(&self.from)? as u32, s.resolve_frame(&self.to)? as u32);
        // A duration T shows round(T x fps) frames, start included (the surface motion graph's
        // count); a walk from one frame to another shows at least two.
        let frames = match self.time.frames(s.fps, TimeUnit::Seconds) {
            Some(f) if f >= 2 => f as usize,
            _ => refuse!(
                "--time {}: expected a duration of at least two frames shown (at {} fps), e.g. 90f or 3s",
                self.time_text(),
                s.fps
            ),
        };
        let search_bytes = distance_search_table_bytes(s.n_frames(), frames);
        let what = format!("--time {} at {} fps", self.time_text(), s.fps);
        limits.check(&Request { what, frames: frames as f64, subject: s, search_bytes, format: out.format() })?;
        if self.distance > 0.0 {
            let travel = surfcap_motion::clip_travel::subject_travel(s);
            crate::travel_check::require_travel(s, &travel, &format!("--distance {}", self.distance), None)?;
        }
        Ok(ReachQuery {
            from_spec: self.from.clone(),
            to_spec: self.to.clone(),
            from,
            to,
            distance: self.distance,
            frames,
            distance_scale: self.distance_scale,
            time_scale: self.time_scale,
        })
    }
}

/// One reach synthesis from an unprepared subject: the request checked and sized
/// ([`ReachRequest::check`]) before any work, then the subject prepared and searched.
pub fn synthesize_reach(
    pipe: impl Into<Arc<Pipeline>>,
    params: GraphParams,
    request: &ReachRequest,
    playback: crate::Playback,
    out: &Output,
    limits: &SizeLimits,
    progress: &dyn Progress,
) -> Result<ReachOutcome> {
    let pipe: Arc<Pipeline> = pipe.into();
    let playback = playback.open(pipe.subject(), out)?;
    let query = request.check(pipe.subject(), out, limits)?;
    let prep = playback.prepare(pipe, params, None)?;
    prep.reach(&query, out, progress)
}

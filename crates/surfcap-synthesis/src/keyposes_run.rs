//! Key-pose timing (thesis 3.5.2, Fig. 3.18): key poses moved to new times; the walk through
//! them meets each requested time as closely as the graph allows (`TimedGraph`, a shortest path
//! of a given duration between consecutive keys), and the pose shown at each obtained time is
//! compared with the key's. A time no walk from the previous key can meet within the frame
//! tolerance says why, in the surface motion graph's words (`Unreachable`).

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::Progress;
use surfcap_motion::timed_walk::{TimedGraph, Unreachable, search_table_bytes};
use surfcap_pipeline::constraint_files::{KeyPose, read_key_poses};
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::animation_output::{CentreTrack, write_report};
use crate::constraint::Constraint;
use crate::error::{Error, Result};
use crate::prepared::{Output, Prepared};
use crate::request_size::{Request, SizeLimits};
use crate::walk_output::{Played, WalkReport, play_and_write, pose_distance_to_output};

/// One key of the report: asked, obtained, and the pose distance at the obtained time.
#[derive(Debug, Clone, Serialize)]
pub struct KeyReport {
    /// The frame as the user wrote it.
    pub frame: String,
    /// Its frame number inside its own sequence (Fig. 3.18's "Input").
    pub input_time: usize,
    pub requested_time: i64,
    pub obtained_time: i64,
    pub error: i64,
    /// Pose distance (eq. 2.13) between the key's pose and the frame shown at its time.
    pub pose_distance: f64,
    /// When the time is not met within the frame tolerance: why no walk from the previous key
    /// can meet it (the surface motion graph's reasons: too_short, no_loop, granularity);
    /// absent on a met time and on the first key.
    pub unreachable: Option<Unreachable>,
    /// The same reason in words.
    pub unreachable_why: Option<String>,
}

/// The report of a key-pose timing run.
#[derive(Debug, Clone, Serialize)]
pub struct KeyposesReport {
    /// `keyposes`.
    pub constraint: &'static str,
    pub keys: Vec<KeyReport>,
    pub mean_abs_error_frames: f64,
    pub search_seconds: f64,
    #[serde(flatten)]
    pub walk: WalkReport,
    pub per_frame: CentreTrack,
    pub constraints: Vec<Constraint>,
}

/// A key-pose timing run: the animation written, its report and summary.
pub struct KeyposesOutcome {
    pub played: Played,
    pub report: KeyposesReport,
    /// The output frame at which each key pose appears.
    pub obtained: Vec<i64>,
    pub mean_abs_error: f64,
    pub search_seconds: f64,
    pub constraints: Vec<Constraint>,
}

impl Prepared {
    /// The walk through `keys` meeting their requested times as closely as the graph allows,
    /// written with its report to `out`.
    pub fn time_key_poses(&self, keys: &[KeyPose], out: &Output, progress: &dyn Progress) -> Result<KeyposesOutcome> {
        let t0 = Instant::now();
        let tg = TimedGraph::new(&self.graph, &self.model);
        let longest = tg.longest_edge();
        let mut walk = vec![keys[0].frame];
        let mut obtained = vec![keys[0].requested];
        let mut reasons: Vec<Option<Unreachable>> = vec![None];
        let tol_t = out.tolerances.frames().floor() as usize;
        for (k, pair) in keys.windows(2).enumerate() {
            let now = *obtained.last().expect("one key at least");
            let asked = pair[1].requested - now;
            let found =
                tg.walk_with_duration_within(pair[0].frame, pair[1].frame, asked, tol_t, longest).map_err(|e| {
                    let label = |k: &KeyPose| self.subject().frame_index().label(k.frame as usize);
                    Error::Request(format!(
                        "keys {} and {} ({} -> {}): {e}",
                        k + 1,
                        k + 2,
                        label(&pair[0]),
                        label(&pair[1])
                    ))
                })?;
            let w = found.walk;
            walk.extend_from_slice(&w.walk[1..]);
            obtained.push(now + w.frames as i64);
            reasons.push(found.unreachable);
        }
        let search_seconds = t0.elapsed().as_secs_f64();
        let errors: Vec<i64> = keys.iter().zip(&obtained).map(|(k, o)| (o - k.requested).abs()).collect();
        let mean_abs_error = errors.iter().sum::<i64>() as f64 / errors.len() as f64;
        let played = play_and_write(self, &walk, &PlaneMotion::identity(self.up()), "keyposes", out, progress)?;
        let mut key_reports = Vec::with_capacity(keys.len());
        for ((k, &o), why) in keys.iter().zip(&obtained).zip(reasons) {
            // The pose shown at the key's obtained time against the pose asked for there.
            let pose_distance = pose_distance_to_output(self, &played.output, k.frame, (o - obtained[0]) as usize)?;
            key_reports.push(KeyReport {
                frame: k.spec.clone(),
                input_time: k.input,
                requested_time: k.requested,
                obtained_time: o,
                error: (o - k.requested).abs(),
                pose_distance,
                unreachable_why: why.as_ref().map(|u| u.in_unit(&crate::words::length_unit(self.subject()))),
                unreachable: why,
            });
        }
        let constraints: Vec<Constraint> = keys
            .iter()
            .zip(&obtained)
            .map(|(k, &o)| {
                let error = (o - k.requested).abs() as f64;
                Constraint::new(
                    format!("key {}", k.spec),
                    "frames",
                    k.requested as f64,
                    o as f64,
                    error,
                    out.tolerances.frames(),
                )
            })
            .collect();
        let report = KeyposesReport {
            constraint: "keyposes",
            keys: key_reports,
            mean_abs_error_frames: mean_abs_error,
            search_seconds,
            walk: played.report.clone(),
            // The viewer draws this track over the animation, as it does for paths and reach.
            per_frame: CentreTrack { centre: played.centres.clone() },
            constraints: constraints.clone(),
        };
        if let Some(path) = &played.report_path {
            write_report(path, &report)?;
        }
        Ok(KeyposesOutcome { played, report, obtained, mean_abs_error, search_seconds, constraints })
    }
}

/// Refuses, before any work, key poses whose animation (from the first key's time to the
/// last's) or whose timed search would exceed `limits`; `source` names the keys in the message
/// (the key file).
pub fn check_key_poses(
    s: &surfcap_mesh::Subject,
    keys: &[KeyPose],
    source: &str,
    out: &Output,
    limits: &SizeLimits,
) -> Result<()> {
    let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
        crate::error::refuse!("{source}: no key poses; expected at least two");
    };
    let (first, last) = (first.requested, last.requested);
    let longest = keys.windows(2).map(|p| (p[1].requested - p[0].requested) as usize).max().unwrap_or(0);
    let what = format!("{source}: keys from output frame {first} to {last}");
    let frames = (last - first + 1) as f64;
    let search_bytes = search_table_bytes(s.n_frames(), longest);
    limits.check(&Request { what, frames, subject: s, search_bytes, format: out.format() })
}

/// One key-pose synthesis from an unprepared subject: the key file (`frame,time` lines) read,
/// the request sized before any work ([`check_key_poses`]), the subject prepared and the keys
/// timed.
pub fn synthesize_keyposes(
    pipe: impl Into<Arc<Pipeline>>,
    params: GraphParams,
    keys_file: &std::path::Path,
    playback: crate::Playback,
    out: &Output,
    limits: &SizeLimits,
    progress: &dyn Progress,
) -> Result<KeyposesOutcome> {
    let pipe: Arc<Pipeline> = pipe.into();
    let s = pipe.subject();
    let playback = playback.open(s, out)?;
    let keys = read_key_poses(keys_file, s)?;
    check_key_poses(s, &keys, &keys_file.display().to_string(), out, limits)?;
    let prep = playback.prepare(pipe, params, None)?;
    prep.time_key_poses(&keys, out, progress)
}

//! How well the interactive controller (`surfcap_synthesis::controller`) follows scripted
//! inputs, and what interactivity costs against offline path following on the same
//! trajectory (`surfcap eval play`).
//!
//! Scripts ([`Script`]), in the character's own start frame (it starts at the origin facing
//! the first ground axis; left is the up axis crossed with forward), played at 60 Hz:
//! - `straight-run`: run forward for 6 s from the start (a standing start when the data has one);
//! - `turn-left`: walk forward 3 s, then walk to the left (90 degrees) for 4 s;
//! - `stop-and-idle`: walk forward 3 s, then stop and stand for 4 s;
//! - `zig-zag`: walk 45 degrees to the left, then to the right, changing every 2 s, for 8 s;
//! - `circle`: walk around a circle of radius 1.5 subject heights, turning left, for 10 s;
//! - `speed-ramp`: walk forward 2 s, then speed up evenly to the running speed over 4 s and
//!   run 2 s, no gait asked (the speeds between a walk's and a run's, which parametric
//!   blending is for).
//!
//! Walking and running speeds are the subject's own (the median speed of its walking and
//! running frames, [`surfcap_synthesis::controller::FrameMotion::typical_speed`]); a gait the
//! data lacks is asked at 0.8 (walk) or 1.6 (run) heights per second, and the controller's
//! notes say it cannot be followed.
//!
//! Measures, per output frame (30 fps for the mannequin) and summarised per script:
//! - heading and speed of the character: its tracked centre's ground velocity by central
//!   difference over a quarter of a second either side (the sway within a step averages out);
//!   heading error against the commanded direction where both move (commanded speed above 0,
//!   the character above 0.2 heights per second), speed error everywhere;
//! - response latency at every change of the commands: from the change to the first frame at
//!   which the character's heading (for a change of direction above 20 degrees) or speed (for a
//!   change above 0.2 heights per second) has gone half of the commanded change;
//! - foot sliding of the played meshes ([`crate::variation_eval::foot_sliding`]);
//! - transitions taken and their realism cost (the sum of their edge weights);
//! - path error: the distance from the centre to the commanded trajectory (the integral of the
//!   commanded velocity from the start) at the same arc length, as path following measures it.
//!
//! Subjects: the mannequin moved by real CMU clips ([`cmu_play_subject`]), the KayKit knight
//! with its travel recovered from ground contacts ([`knight_play_subject`]) and a Vlasic et al.
//! capture ([`vlasic_play_subject`]).
//!
//! Parametric blending (`surfcap_synthesis::controller::parametric_blend`): when the
//! controller blends and the subject has clip pairs, each script is played twice, with the
//! captured clips only and with blending, and the pairs are listed. The subject's quickest
//! captured turns ([`quickest_turn`]) bound how fast a turn can be answered.
//!
//! Offline comparison: the commanded trajectory's moving part as a ground curve, followed by
//! `Prepared::follow_path` (thesis 3.5.1) from the same start frame with the subject's default
//! search: its path error, transitions and cost, and foot sliding, beside the controller's.
//! (Offline synthesis knows the whole curve in advance; the controller sees one input at a
//! time. The stop has no offline counterpart: a curve cannot ask to stand.)

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_mesh::{NoProgress, Subject, UpAxis};
use surfcap_motion::blend::wrap_angle;
use surfcap_motion::path_following::{Curve, PathSearch, path_errors};
use surfcap_motion::walk_sequence::Step as EdgeStep;
use surfcap_synthesis::controller::frame_motion::IDLE_HEIGHTS_PER_SECOND;
use surfcap_synthesis::controller::{Controller, ControllerOptions, Gait, Input};
use surfcap_synthesis::{Output, PathQuery, Prepared, Tolerances};

use crate::error::{Error, Result};
use crate::variation_eval::foot_sliding;

/// A scripted input sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Script {
    StraightRun,
    TurnLeft,
    StopAndIdle,
    ZigZag,
    Circle,
    SpeedRamp,
}

impl Script {
    pub const ALL: [Script; 6] =
        [Script::StraightRun, Script::TurnLeft, Script::StopAndIdle, Script::ZigZag, Script::Circle, Script::SpeedRamp];

    pub fn name(self) -> &'static str {
        match self {
            Script::StraightRun => "straight-run",
            Script::TurnLeft => "turn-left",
            Script::StopAndIdle => "stop-and-idle",
            Script::ZigZag => "zig-zag",
            Script::Circle => "circle",
            Script::SpeedRamp => "speed-ramp",
        }
    }

    pub fn parse(text: &str) -> Option<Script> {
        Script::ALL.into_iter().find(|s| s.name() == text)
    }

    /// Seconds the script lasts.
    pub fn seconds(self) -> f64 {
        match self {
            Script::StraightRun => 6.0,
            Script::TurnLeft | Script::StopAndIdle => 7.0,
            Script::ZigZag | Script::SpeedRamp => 8.0,
            Script::Circle => 10.0,
        }
    }

    /// The command at time `t`: (commanded ground velocity, gait). `left` is +1 or -1: the
    /// sign of the angle (from the first ground axis towards the second) that turns left.
    fn command(self, t: f64, walk: f64, run: f64, left: f64, radius: f64) -> ([f64; 2], Gait) {
        let at = |angle: f64, speed: f64| [speed * angle.cos(), speed * angle.sin()];
        let quarter = left * std::f64::consts::FRAC_PI_2;
        match self {
            Script::StraightRun => (at(0.0, run), Gait::Run),
            Script::TurnLeft => (at(if t < 3.0 { 0.0 } else { quarter }, walk), Gait::Walk),
            Script::StopAndIdle if t < 3.0 => (at(0.0, walk), Gait::Walk),
            Script::StopAndIdle => ([0.0, 0.0], Gait::Idle),
            Script::ZigZag => {
                let side = if ((t / 2.0).floor() as i64) % 2 == 0 { 1.0 } else { -1.0 };
                (at(side * quarter / 2.0, walk), Gait::Walk)
            }
            Script::Circle => (at(left * walk / radius * t, walk), Gait::Walk),
            Script::SpeedRamp => {
                let x = ((t - 2.0) / 4.0).clamp(0.0, 1.0);
                (at(0.0, walk + x * (run - walk)), if x < 0.5 { Gait::Walk } else { Gait::Run })
            }
        }
    }
}

/// Options of [`play_eval`].
#[derive(Debug, Clone)]
pub struct PlayEvalOptions {
    pub scripts: Vec<Script>,
    /// The controller's options (meshes are always returned: foot sliding is measured on them).
    pub controller: ControllerOptions,
    /// Also follow each script's trajectory offline.
    pub offline: bool,
    /// When the controller blends ([`ControllerOptions::parametric`]), also play each script
    /// without blending, for the comparison.
    pub compare_parametric: bool,
}

impl Default for PlayEvalOptions {
    fn default() -> Self {
        PlayEvalOptions {
            scripts: Script::ALL.to_vec(),
            controller: ControllerOptions::default(),
            offline: true,
            compare_parametric: true,
        }
    }
}

/// The offline path-following walk on a script's trajectory.
#[derive(Debug, Clone, Serialize)]
pub struct OfflineWalk {
    pub frames: usize,
    pub mean_path_error: f64,
    pub max_path_error: f64,
    pub transitions: usize,
    pub transition_cost: f64,
    pub foot_sliding: Option<f64>,
    pub search_seconds: f64,
}

/// Per-frame series of one script (for plots and checks).
#[derive(Debug, Clone, Serialize)]
pub struct OverTime {
    pub time: Vec<f64>,
    /// Character's ground centre and commanded position (integral of the commands).
    pub centre: Vec<[f64; 2]>,
    pub commanded: Vec<[f64; 2]>,
    /// Degrees; `None` where either stands.
    pub heading_error: Vec<Option<f64>>,
    /// The character's and the commanded heading, degrees, unwrapped over time (`None` where
    /// it stands or is asked to stand).
    pub heading: Vec<Option<f64>>,
    pub commanded_heading: Vec<Option<f64>>,
    pub speed: Vec<f64>,
    pub commanded_speed: Vec<f64>,
    /// The parametric blend's weight at each frame (0: a captured frame or a transition).
    pub blend_weight: Vec<f64>,
}

/// One script on one subject.
#[derive(Debug, Clone, Serialize)]
pub struct ScriptResult {
    pub script: Script,
    /// Whether the controller could blend clips parametrically.
    pub parametric: bool,
    /// Output frames that were parametric blends (weight above 0).
    pub blended_frames: usize,
    pub seconds: f64,
    pub frames: usize,
    /// Mean and 90th percentile heading error, degrees (`None`: never both moving).
    pub heading_error_mean: Option<f64>,
    pub heading_error_p90: Option<f64>,
    /// Mean absolute speed error, subject units per second.
    pub speed_error_mean: f64,
    /// Commanded speed (the largest of the script), subject units per second.
    pub commanded_speed: f64,
    /// Per change of direction / of speed: seconds to half the change (`None`: never reached).
    pub heading_latency: Vec<Option<f64>>,
    pub speed_latency: Vec<Option<f64>>,
    pub foot_sliding: Option<f64>,
    pub transitions: usize,
    pub transition_cost: f64,
    pub decisions: usize,
    pub decision_p99_ms: f64,
    /// Path error against the commanded trajectory (at the same arc length), mean and largest.
    pub mean_path_error: f64,
    pub max_path_error: f64,
    /// What the controller said it cannot follow with the data.
    pub cannot_follow: Vec<String>,
    pub offline: Option<OfflineWalk>,
    /// Why the offline walk was not made, if it was asked and not made.
    pub offline_refused: Option<String>,
    pub over_time: OverTime,
    /// Every decision: when, from which frame, the move or blend chosen and its cost.
    pub decision_log: Vec<surfcap_synthesis::controller::Decision>,
}

/// One subject's results.
#[derive(Debug, Clone, Serialize)]
pub struct PlayEval {
    pub subject: String,
    pub frames: usize,
    pub vertices: usize,
    pub fps: f64,
    pub unit: String,
    pub height: f64,
    pub walk_speed: Option<f64>,
    pub run_speed: Option<f64>,
    pub moves: usize,
    pub precompute_seconds: f64,
    /// The clip pairs parametric blending may mix: (clip, partner clip, frames of the clip
    /// with a partner in it).
    pub blend_pairs: Vec<(String, String, usize)>,
    /// Why no pair qualifies, when none does.
    pub no_blend_pairs: Option<String>,
    /// The data's quickest turns: seconds for the heading of a captured clip to change by 45
    /// and by 90 degrees ([`quickest_turn`]; `None`: no clip turns that far). A response
    /// latency to half of a 90-degree command cannot beat the first by playing captured frames.
    pub quickest_turn_45: Option<f64>,
    pub quickest_turn_90: Option<f64>,
    pub scripts: Vec<ScriptResult>,
    pub seconds: f64,
}

/// The CMU-driven mannequin's clips (dataset folder, trial): subject 16's walk, left and right
/// turns, start from standstill, jog and run-to-stop, and 113_21 ("Standing Still", its leading
/// T-pose frame dropped, 6 s kept) so that the character can stand.
pub const CMU_PLAY_CLIPS: [(&str, &str); 7] = [
    ("cmu_bvh", "16_15"),
    ("cmu_bvh", "16_17"),
    ("cmu_bvh", "16_19"),
    ("cmu_bvh", "16_31"),
    ("cmu_bvh", "16_36"),
    ("cmu_bvh", "16_57"),
    ("cmu_bvh_loops", "113_21"),
];

/// The KayKit knight's clips: standing, walking and running, authored in place.
pub const KNIGHT_PLAY_CLIPS: [&str; 3] = ["knight_Idle", "knight_Walking_A", "knight_Running_A"];

/// The Vlasic et al. capture.
pub const VLASIC_PLAY_SEQUENCE: &str = "vlasic2008/crane";

/// The mannequin of about `vertices` vertices moved by [`CMU_PLAY_CLIPS`] at 30 fps (metres).
pub fn cmu_play_subject(data: &Path, vertices: usize) -> Result<Subject> {
    let m = mannequin(&BodyShape::average(), vertices)?;
    let mut clips = Vec::new();
    for (folder, trial) in CMU_PLAY_CLIPS {
        let path = data.join(folder).join(format!("{trial}.bvh"));
        let bvh = read_bvh(&path)?;
        let mpu = bvh.guess_metres_per_unit().0;
        let mut clip = Clip::from_bvh(&path, &bvh, &m, mpu)?;
        if folder == "cmu_bvh_loops" {
            // The cgspeed conversions start with a T-pose reference frame.
            clip.poses.remove(0);
            clip.poses.truncate((6.0 * clip.fps).round() as usize + 1);
        }
        clips.push(clip);
    }
    Ok(mannequin_subject("mannequin-cmu-play", &m, &clips, 30.0)?)
}

/// The KayKit knight's [`KNIGHT_PLAY_CLIPS`] with their travel recovered from the feet's
/// ground contacts (`surfcap import --root-motion contacts`).
pub fn knight_play_subject(data: &Path) -> Result<Subject> {
    let paths: Vec<std::path::PathBuf> =
        KNIGHT_PLAY_CLIPS.iter().map(|c| data.join("kaykit_adventurers").join(c)).collect();
    let imported = surfcap_formats::import::import(&paths, &Default::default(), &NoProgress)
        .map_err(|e| Error::Unsuitable(format!("importing the knight: {e}")))?;
    let params = surfcap_geometry::root_motion_from_contacts::ContactParams::default();
    let (s, _) = surfcap_motion::in_place_root_motion::recover_in_place_root_motion(imported.subject, &params)
        .map_err(|e| Error::Unsuitable(format!("the knight's root motion from contacts: {e}")))?;
    Ok(s)
}

/// The Vlasic et al. capture [`VLASIC_PLAY_SEQUENCE`] as a subject.
pub fn vlasic_play_subject(data: &Path) -> Result<Subject> {
    let path = data.join(VLASIC_PLAY_SEQUENCE);
    let imported = surfcap_formats::import::import(std::slice::from_ref(&path), &Default::default(), &NoProgress)
        .map_err(|e| Error::Unsuitable(format!("importing {}: {e}", path.display())))?;
    Ok(imported.subject)
}

/// The sign of the ground angle that turns left for this up axis (up x forward).
fn left_sign(up: UpAxis) -> f64 {
    let (iu, iv, iw) = plane_axes(up);
    let mut n = [0.0; 3];
    n[iw] = up.axis_and_sign().1;
    let mut e = [0.0; 3];
    e[iu] = 1.0;
    let cross = [n[1] * e[2] - n[2] * e[1], n[2] * e[0] - n[0] * e[2], n[0] * e[1] - n[1] * e[0]];
    if cross[iv] >= 0.0 { 1.0 } else { -1.0 }
}

fn mean(x: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, n) = x.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| s / n as f64)
}

fn quantile(mut v: Vec<f64>, q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[((v.len() - 1) as f64 * q).round() as usize])
}

/// Ground velocity of a track by central difference over `half` frames either side.
fn velocities(track: &[[f64; 2]], half: usize, fps: f64) -> Vec<[f64; 2]> {
    let n = track.len();
    (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half).min(n - 1));
            if b == a {
                return [0.0, 0.0];
            }
            let dt = (b - a) as f64 / fps;
            [(track[b][0] - track[a][0]) / dt, (track[b][1] - track[a][1]) / dt]
        })
        .collect()
}

/// The shortest time, over the frames of every clip as captured, for the heading
/// ([`surfcap_synthesis::controller::FrameMotion`]) to change by `degrees` while moving
/// (every frame in between has a heading), in seconds; `None` when no clip turns that far.
pub fn quickest_turn(s: &Subject, motion: &surfcap_synthesis::controller::FrameMotion, degrees: f64) -> Option<f64> {
    let index = s.frame_index();
    let mut best: Option<usize> = None;
    for q in 0..index.n_sequences() {
        let r = index.range(q);
        for a in r.clone() {
            if !motion.heading[a].is_finite() {
                continue;
            }
            // Unwrapped heading change from frame a on, until a frame without heading.
            let (mut turned, mut last) = (0.0f64, motion.heading[a]);
            for b in a + 1..r.end {
                let h = motion.heading[b];
                if !h.is_finite() || best.is_some_and(|x| b - a >= x) {
                    break;
                }
                turned += wrap_angle(h - last);
                last = h;
                if turned.abs().to_degrees() >= degrees {
                    best = Some(b - a);
                    break;
                }
            }
        }
    }
    best.map(|f| f as f64 / s.fps)
}

/// Runs the scripts of `opts` on `prep` (see the module doc).
pub fn play_eval(prep: &Prepared, opts: &PlayEvalOptions) -> Result<PlayEval> {
    let t0 = Instant::now();
    let s = prep.subject();
    let controller_options = ControllerOptions { meshes: true, ..opts.controller.clone() };
    let tp = Instant::now();
    let probe = Controller::new(prep, controller_options.clone())?;
    let (index, motion) = (probe.index().clone(), probe.motion().clone());
    let has_pairs = probe.partners().frames_with_partners() > 0;
    let precompute_seconds = tp.elapsed().as_secs_f64();
    drop(probe);
    let height = motion.height;
    let (walk_speed, run_speed) = (motion.typical_speed(Gait::Walk), motion.typical_speed(Gait::Run));
    let walk = walk_speed.unwrap_or(0.8 * height);
    let run = run_speed.unwrap_or(1.6 * height);
    let modes: Vec<bool> = if controller_options.parametric && opts.compare_parametric && has_pairs {
        vec![false, true]
    } else {
        vec![controller_options.parametric]
    };
    let mut scripts = Vec::new();
    let (mut blend_pairs, mut no_blend_pairs) = (Vec::new(), None);
    for &script in &opts.scripts {
        // The offline walk is the same for both modes: made once.
        let mut offline: Option<(Option<OfflineWalk>, Option<String>)> = None;
        for &parametric in &modes {
            let options = ControllerOptions { parametric, ..controller_options.clone() };
            let c = Controller::with_index(prep, index.clone(), motion.clone(), options)?;
            if parametric {
                blend_pairs = c.partners().pairs(s);
                no_blend_pairs = c.partners().none_because.clone();
            }
            scripts.push(run_script(prep, c, script, walk, run, opts.offline, &mut offline)?);
        }
    }
    Ok(PlayEval {
        subject: s.name.clone(),
        frames: s.n_frames(),
        vertices: s.topology().n_vertices(),
        fps: s.fps,
        unit: s.units.symbol().to_string(),
        height,
        walk_speed,
        run_speed,
        moves: index.n_transitions(),
        precompute_seconds,
        blend_pairs,
        no_blend_pairs,
        quickest_turn_45: quickest_turn(s, &motion, 45.0),
        quickest_turn_90: quickest_turn(s, &motion, 90.0),
        scripts,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn run_script(
    prep: &Prepared,
    mut c: Controller,
    script: Script,
    walk: f64,
    run: f64,
    offline: bool,
    offline_made: &mut Option<(Option<OfflineWalk>, Option<String>)>,
) -> Result<ScriptResult> {
    let parametric = c.partners().frames_with_partners() > 0;
    let s = prep.subject();
    let (fps, up) = (s.fps, s.up_axis);
    let (iu, iv, _) = plane_axes(up);
    let height = c.motion().height;
    let left = left_sign(up);
    let radius = 1.5 * height;
    let dt = 1.0 / 60.0;
    let steps = (script.seconds() / dt).round() as usize;
    let (mut frames, mut decisions, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..steps {
        let t = i as f64 * dt;
        let (v, gait) = script.command(t, walk, run, left, radius);
        let input = match gait {
            Gait::Idle => Input::stop(),
            // Speeds between the gaits': no gait asked.
            _ if script == Script::SpeedRamp => Input::velocity(v),
            _ => Input::velocity(v).with_gait(gait),
        };
        let out = c.step(&input, dt)?;
        for n in out.cannot_follow {
            // A speed asked beyond the data's is said once, at its largest (the speed ramp
            // changes the input every step).
            if n.starts_with("asked ") {
                notes.retain(|x: &String| !x.starts_with("asked "));
            }
            if !notes.contains(&n) {
                notes.push(n);
            }
        }
        frames.extend(out.frames);
        decisions.extend(out.decisions);
    }
    let n = frames.len();
    let centre: Vec<[f64; 2]> = frames.iter().map(|f| [f.centre[iu], f.centre[iv]]).collect();
    let time: Vec<f64> = (0..n).map(|k| k as f64 / fps).collect();
    let commands: Vec<([f64; 2], Gait)> = time.iter().map(|&t| script.command(t, walk, run, left, radius)).collect();
    let mut commanded = Vec::with_capacity(n);
    let mut p = centre.first().copied().unwrap_or([0.0, 0.0]);
    for (k, (v, _)) in commands.iter().enumerate() {
        if k > 0 {
            p = [p[0] + v[0] / fps, p[1] + v[1] / fps];
        }
        commanded.push(p);
    }
    let half = (0.25 * fps).round().max(1.0) as usize;
    let vel = velocities(&centre, half, fps);
    let speed: Vec<f64> = vel.iter().map(|v| v[0].hypot(v[1])).collect();
    let heading: Vec<f64> = vel.iter().map(|v| v[1].atan2(v[0])).collect();
    let commanded_speed: Vec<f64> = commands.iter().map(|(v, _)| v[0].hypot(v[1])).collect();
    let commanded_heading: Vec<f64> = commands.iter().map(|(v, _)| v[1].atan2(v[0])).collect();
    let moving = |k: usize| commanded_speed[k] > 0.0 && speed[k] >= IDLE_HEIGHTS_PER_SECOND * height;
    let heading_error: Vec<Option<f64>> =
        (0..n).map(|k| moving(k).then(|| wrap_angle(heading[k] - commanded_heading[k]).abs().to_degrees())).collect();
    let errors: Vec<f64> = heading_error.iter().flatten().copied().collect();
    let speed_error_mean = mean((0..n).map(|k| (speed[k] - commanded_speed[k]).abs())).unwrap_or(0.0);
    // Response latencies at every change of the commands.
    let (mut heading_latency, mut speed_latency) = (Vec::new(), Vec::new());
    for k in 0..n {
        let before = if k == 0 { ([0.0, 0.0], Gait::Idle) } else { commands[k - 1] };
        let (sb, sa) = (before.0[0].hypot(before.0[1]), commanded_speed[k]);
        if (sa - sb).abs() > 0.2 * height {
            let sign = (sa - sb).signum();
            let reached = (k..n).find(|&j| (speed[j] - sb) * sign >= 0.5 * (sa - sb).abs());
            speed_latency.push(reached.map(|j| (j - k) as f64 / fps));
        }
        if k > 0 && sb > 0.0 && sa > 0.0 {
            let hb = before.0[1].atan2(before.0[0]);
            let change = wrap_angle(commanded_heading[k] - hb);
            if change.abs() > 20f64.to_radians() {
                let reached =
                    (k..n).find(|&j| moving(j) && wrap_angle(heading[j] - hb) * change.signum() >= 0.5 * change.abs());
                heading_latency.push(reached.map(|j| (j - k) as f64 / fps));
            }
        }
    }
    let meshes: Vec<&[f32]> = frames.iter().filter_map(|f| f.positions.as_deref()).collect();
    let sliding = if meshes.len() == n && n > 2 { Some(foot_sliding(&meshes, fps, up, &[])?.speed) } else { None };
    let (transitions, transition_cost) = c.transitions();
    let mut latencies: Vec<f64> =
        decisions.iter().map(|d: &surfcap_synthesis::controller::Decision| d.seconds).collect();
    latencies.sort_by(f64::total_cmp);
    let decision_p99_ms = 1e3 * quantile(latencies, 0.99).unwrap_or(f64::NAN);
    // The commanded trajectory's moving part as a ground curve at the start's height.
    let y = frames.first().map_or(0.0, |f| f.centre[plane_axes(up).2]);
    let points: Vec<[f64; 3]> = commanded
        .iter()
        .zip(&commanded_speed)
        .filter(|(_, v)| **v > 0.0)
        .map(|(p, _)| {
            let mut q = [0.0; 3];
            q[iu] = p[0];
            q[iv] = p[1];
            q[plane_axes(up).2] = y;
            q
        })
        .collect();
    let curve = Curve::new(points, vec![iu, iv]).map_err(|e| Error::Unsuitable(format!("{}: {e}", script.name())))?;
    let centres3: Vec<[f64; 3]> = frames.iter().map(|f| f.centre).collect();
    let (path_error, _) = path_errors(&curve, &centres3);
    let mean_path_error = mean(path_error.iter().copied()).unwrap_or(0.0);
    let max_path_error = path_error.iter().copied().fold(0.0, f64::max);
    let start = frames.first().and_then(|f| f.frame);
    let (offline_walk, offline_refused) = match offline_made {
        Some(made) => made.clone(),
        None if offline => {
            let made = match offline_path(prep, &curve, start) {
                Ok(w) => (Some(w), None),
                Err(e) => (None, Some(e)),
            };
            *offline_made = Some(made.clone());
            made
        }
        None => (None, None),
    };
    let blend_weight: Vec<f64> =
        frames.iter().map(|f| f.mix.filter(|_| f.transition.is_none()).map_or(0.0, |m| m.weight as f64)).collect();
    let unwrapped = |h: &[f64], keep: &dyn Fn(usize) -> bool| -> Vec<Option<f64>> {
        let mut last: Option<f64> = None;
        (0..n)
            .map(|k| {
                if !keep(k) {
                    return None;
                }
                let d = h[k].to_degrees();
                let u = last.map_or(d, |l| l + wrap_angle((d - l).to_radians()).to_degrees());
                last = Some(u);
                Some(u)
            })
            .collect()
    };
    let heading_deg = unwrapped(&heading, &|k| speed[k] >= IDLE_HEIGHTS_PER_SECOND * height);
    let commanded_heading_deg = unwrapped(&commanded_heading, &|k| commanded_speed[k] > 0.0);
    Ok(ScriptResult {
        script,
        parametric,
        blended_frames: c.blended(),
        seconds: script.seconds(),
        frames: n,
        heading_error_mean: mean(errors.iter().copied()),
        heading_error_p90: quantile(errors, 0.9),
        speed_error_mean,
        commanded_speed: commanded_speed.iter().copied().fold(0.0, f64::max),
        heading_latency,
        speed_latency,
        foot_sliding: sliding,
        transitions,
        transition_cost,
        decisions: decisions.len(),
        decision_p99_ms,
        mean_path_error,
        max_path_error,
        cannot_follow: notes,
        offline: offline_walk,
        offline_refused,
        over_time: OverTime {
            time,
            centre,
            commanded,
            heading_error,
            heading: heading_deg,
            commanded_heading: commanded_heading_deg,
            speed,
            commanded_speed,
            blend_weight,
        },
        decision_log: decisions,
    })
}

/// Follows `curve` offline from `start` (the subject's default search); the error text when
/// the subject cannot follow a path at all.
fn offline_path(prep: &Prepared, curve: &Curve, start: Option<u32>) -> std::result::Result<OfflineWalk, String> {
    let s = prep.subject();
    let travel = surfcap_motion::clip_travel::subject_travel(s);
    surfcap_synthesis::travel_check::require_travel(s, &travel, "offline path following", None)
        .map_err(|e| e.to_string())?;
    let shortest_loop =
        prep.pipe.loops().iter().map(|l| s.frame_index().range(l.sequence).len() as f64 / s.fps).min_by(f64::total_cmp);
    let query = PathQuery { curve, restrictions: &[], start, search: PathSearch::for_clips(s.fps, shortest_loop) };
    let o =
        prep.follow_path(&query, &Output::in_memory(Tolerances::default()), &NoProgress).map_err(|e| e.to_string())?;
    let walk = &o.report.walk.walk;
    let cost: f64 = walk
        .windows(2)
        .filter(|w| matches!(prep.model.step(w[0], w[1]), Some(EdgeStep::Transition(_))))
        .filter_map(|w| prep.graph.find(w[0] as usize, w[1] as usize).map(|k| prep.graph.edges()[k].weight))
        .sum();
    let out = &o.played.output;
    let frames: Vec<&[f32]> = (0..out.n_frames()).filter_map(|k| out.frame(k)).collect();
    let sliding = foot_sliding(&frames, s.fps, s.up_axis, &[]).ok().map(|f| f.speed);
    Ok(OfflineWalk {
        frames: o.frames,
        mean_path_error: o.mean_error,
        max_path_error: o.max_error,
        transitions: o.played.transitions,
        transition_cost: cost,
        foot_sliding: sliding,
        search_seconds: o.search_seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_is_up_crossed_with_forward_and_scripts_turn_that_way() {
        // +y up: forward +x, left -z (x cross y = z is right).
        assert_eq!(left_sign(UpAxis::parse("+y").unwrap()), -1.0);
        // +z up: forward +x, left +y.
        assert_eq!(left_sign(UpAxis::parse("+z").unwrap()), 1.0);
        let (v, g) = Script::TurnLeft.command(4.0, 1.0, 2.0, -1.0, 3.0);
        assert!(v[0].abs() < 1e-12 && (v[1] + 1.0).abs() < 1e-12 && g == Gait::Walk);
        let (v, g) = Script::StopAndIdle.command(5.0, 1.0, 2.0, -1.0, 3.0);
        assert!(v == [0.0, 0.0] && g == Gait::Idle);
        let (a, b) =
            (Script::ZigZag.command(1.0, 1.0, 2.0, 1.0, 3.0).0, Script::ZigZag.command(3.0, 1.0, 2.0, 1.0, 3.0).0);
        assert!((a[1] + b[1]).abs() < 1e-12 && a[1] > 0.0);
        assert_eq!(Script::parse("zig-zag"), Some(Script::ZigZag));
        let v = velocities(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]], 1, 10.0);
        assert!(v.iter().all(|x| (x[0] - 10.0).abs() < 1e-12 && x[1] == 0.0));
    }

    /// A quad walking a circle at 90 degrees per second turns 45 degrees in half a second and
    /// 90 in one; one walking straight never turns.
    #[test]
    fn the_quickest_turn_of_a_circling_walk() {
        use surfcap_mesh::{Sequence, Topology, Units};
        let quad = |x: f32, z: f32| vec![x, 0.0, z, x + 0.1, 1.0, z, x, 0.0, z + 0.1, x + 0.1, 0.0, z + 0.1];
        let fps = 30.0f64;
        let circle: Vec<f32> = (0..90)
            .flat_map(|f| {
                let a = std::f64::consts::FRAC_PI_2 * f as f64 / fps;
                quad(a.sin() as f32, (1.0 - a.cos()) as f32)
            })
            .collect();
        let straight: Vec<f32> = (0..90).flat_map(|f| quad(f as f32 / 30.0, 0.0)).collect();
        let topology = Topology::new(4, vec![[0, 1, 2], [1, 3, 2]], None).unwrap();
        let subject = |p: Vec<f32>| {
            Subject::new(
                "q",
                topology.clone(),
                vec![Sequence::new("a", 4, p).unwrap()],
                fps,
                UpAxis::PosY,
                Units::metres(),
            )
            .unwrap()
        };
        let (s, flat) = (subject(circle), subject(straight));
        let centres = |s: &Subject| -> Vec<[f64; 3]> {
            (0..s.n_frames()).map(|g| surfcap_motion::blend::centre(s.frame(g).unwrap())).collect()
        };
        let m = surfcap_synthesis::controller::FrameMotion::new(&s, &centres(&s));
        let t45 = quickest_turn(&s, &m, 45.0).unwrap();
        let t90 = quickest_turn(&s, &m, 90.0).unwrap();
        assert!((t45 - 0.5).abs() <= 1.0 / fps + 1e-9, "{t45}");
        assert!((t90 - 1.0).abs() <= 1.0 / fps + 1e-9, "{t90}");
        let m = surfcap_synthesis::controller::FrameMotion::new(&flat, &centres(&flat));
        assert_eq!(quickest_turn(&flat, &m, 45.0), None);
    }
}

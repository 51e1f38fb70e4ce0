//! The interactive controller: a prepared subject steered by a stream of inputs, one output
//! frame at a time (motion matching on the essential graph; see the module doc of
//! [`crate::controller`]).
//!
//! Time: [`Controller::step`] advances the clock by `dt` and shows the output frames that fall
//! due (the subject's frame rate; a 60 Hz caller sees a new frame every other call at 30 fps).
//! Decisions: before the frame that is due, when the last decision is at least
//! `decision_interval` old and the frames queued are only the clip continuing (not yet a
//! transition), or when nothing is queued. A transition, once chosen, plays to its end (its
//! frames are blended as offline synthesis blends them: `surfcap_motion::walk_sequence`,
//! thesis Algorithm 3), so a decision waits for it.
//!
//! Placement: the first frame is shown with its centre at the origin of the ground plane,
//! heading along the first ground axis (a standing frame, which has no direction of travel,
//! faces the way its clip's transitions into walking or running set off: [`walk_off_heading`]); every frame after is placed as the walk model places
//! it (the rigid track of each transition, the wrap of a looping clip).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_mesh::UpAxis;
use surfcap_motion::transition_frames::FrameMix;
use surfcap_motion::walk_sequence::{Step as EdgeStep, WalkModel, walk_sequence};
use surfcap_pipeline::{Pipeline, PoseDistances};

use super::desired_trajectory::{TrajectoryGoal, desired_trajectory};
use super::frame_motion::{FrameMotion, Gait};
use super::future_trajectory::FutureTrajectories;
use super::move_choice::{Ahead, GaitAsked, LocalGoal, MatchWeights, Move, choose_move};
use crate::error::{Result, refuse};
use crate::prepared::Prepared;
use crate::words::length;

/// How the controller decides and what it returns.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerOptions {
    /// Seconds between decisions at most (while no transition is playing).
    pub decision_interval: f64,
    /// Seconds for half of an input's change to reach the asked trajectory
    /// ([`super::desired_trajectory`]).
    pub halflife: f64,
    pub weights: MatchWeights,
    /// The first frame (global); default: the slowest live frame (a standing start).
    pub start: Option<u32>,
    /// Return every output frame's vertex positions (off: frames, centres and placements only).
    pub meshes: bool,
}

impl Default for ControllerOptions {
    fn default() -> Self {
        ControllerOptions {
            decision_interval: 0.1,
            halflife: 0.2,
            weights: MatchWeights::default(),
            start: None,
            meshes: false,
        }
    }
}

/// Where the input asks the character to go.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Goal {
    /// A ground velocity, subject units per second along the two ground axes (`[0, 0]`: stop).
    Velocity([f64; 2]),
    /// A point on the ground to walk to (and stop at).
    Target([f64; 2]),
}

/// One input: where to go, optionally which way to face and in which gait.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Input {
    pub goal: Goal,
    /// Facing, radians from the first ground axis towards the second (`None`: face where you go).
    pub facing: Option<f64>,
    pub gait: Option<Gait>,
}

impl Input {
    /// Go at this ground velocity.
    pub fn velocity(v: [f64; 2]) -> Self {
        Input { goal: Goal::Velocity(v), facing: None, gait: None }
    }

    /// Stand still.
    pub fn stop() -> Self {
        Input { goal: Goal::Velocity([0.0, 0.0]), facing: None, gait: Some(Gait::Idle) }
    }

    /// Walk (or run, with a gait) to this ground point.
    pub fn target(p: [f64; 2]) -> Self {
        Input { goal: Goal::Target(p), facing: None, gait: None }
    }

    pub fn with_gait(mut self, gait: Gait) -> Self {
        self.gait = Some(gait);
        self
    }

    pub fn with_facing(mut self, facing: f64) -> Self {
        self.facing = Some(facing);
        self
    }
}

/// One output frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ShownFrame {
    /// The captured frame shown (global), `None` inside a transition's blend.
    pub frame: Option<u32>,
    /// The captured frames it is made of, with the blend weight (`None` inside a blend when
    /// meshes are not returned: the Blend was not played).
    pub mix: Option<FrameMix>,
    /// The tracked centre, as placed (the walk model's prediction of the played mesh's centre).
    pub centre: [f64; 3],
    /// The transition this frame belongs to (its source and destination), if any.
    pub transition: Option<(u32, u32)>,
    /// The vertex positions `[vertices][3]`, when [`ControllerOptions::meshes`] asks for them.
    pub positions: Option<Vec<f32>>,
}

/// What one decision saw and chose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Decision {
    /// Seconds since the controller started.
    pub time: f64,
    /// The frame shown when it was made (global).
    pub frame: u32,
    pub chosen: Move,
    pub cost: f64,
    /// Moves compared.
    pub candidates: usize,
    /// How long the decision took (seconds; the asked trajectory and the scan).
    pub seconds: f64,
}

/// What [`Controller::step`] returns: the frames that fell due, the decisions made and, when
/// the input changed, what of it the data cannot follow.
#[derive(Debug, Clone, Default)]
pub struct Step {
    pub frames: Vec<ShownFrame>,
    pub decisions: Vec<Decision>,
    /// What of the new input cannot be followed with the subject's data, and why (empty when
    /// the input did not change or can be followed).
    pub cannot_follow: Vec<String>,
}

/// A frame queued to be shown, and the frame and placement it leaves the walk at.
#[derive(Debug, Clone)]
struct Queued {
    frame: ShownFrame,
    /// Part of a chosen transition (its lead-in or blend): not replaced by a new decision.
    committed: bool,
    at: Option<(u32, PlaneMotion)>,
}

/// What the data allows, found once.
#[derive(Debug, Clone)]
struct Abilities {
    /// Some move turns the heading by more than [`TURN_DEGREES`] within a second.
    turns: bool,
    fastest: f64,
}

/// A change of heading that counts as a turn, degrees.
const TURN_DEGREES: f64 = 20.0;

/// The controller: the subject, its precomputed moves and the walk so far.
pub struct Controller {
    pipe: Arc<Pipeline>,
    model: Arc<WalkModel>,
    /// The distance matrix the walk model was built from (for the Blend's warps), when meshes
    /// are returned.
    distances: Option<Arc<PoseDistances>>,
    index: Arc<FutureTrajectories>,
    motion: Arc<FrameMotion>,
    abilities: Abilities,
    options: ControllerOptions,
    node: u32,
    g: PlaneMotion,
    queue: VecDeque<Queued>,
    /// Output frames shown so far.
    shown: usize,
    /// Output frames due but not shown yet (fractional).
    due: f64,
    last_decision: Option<f64>,
    input: Option<Input>,
    transitions: usize,
    realism: f64,
}

impl Controller {
    /// A controller on `prep`'s graph and walk model: the moves' features and the dead-end
    /// analysis are computed here (once; a few seconds on a dense graph of thousands of frames).
    pub fn new(prep: &Prepared, options: ControllerOptions) -> Result<Self> {
        let s = prep.subject();
        if !(options.decision_interval > 0.0 && options.decision_interval.is_finite()) {
            refuse!("decision interval {}: expected a positive number of seconds", options.decision_interval);
        }
        if !(options.halflife > 0.0 && options.halflife.is_finite()) {
            refuse!("half-life {}: expected a positive number of seconds", options.halflife);
        }
        let motion = Arc::new(FrameMotion::new(s, &prep.model.centres));
        let index = Arc::new(FutureTrajectories::new(&prep.model, &prep.graph, &motion));
        Self::with_index(prep, index, motion, options)
    }

    /// The same with moves and frame motion already computed for `prep` (shared by several
    /// controllers of one subject).
    pub fn with_index(
        prep: &Prepared,
        index: Arc<FutureTrajectories>,
        motion: Arc<FrameMotion>,
        options: ControllerOptions,
    ) -> Result<Self> {
        let s = prep.subject();
        let n = s.n_frames();
        if index.live.len() != n || motion.speed.len() != n {
            refuse!("the controller's moves were computed for another subject ({} frames, not {n})", index.live.len());
        }
        let start = match options.start {
            Some(f) if (f as usize) < n && index.live[f as usize] => f,
            Some(f) if (f as usize) < n => refuse!(
                "start frame {}: the walk cannot go on from it (it leads only to the end of its clip); \
                 start from a frame that transitions or loops",
                s.frame_index().label(f as usize)
            ),
            Some(f) => refuse!("start frame {f}: the subject has frames 0 to {}", n - 1),
            None => match (0..n as u32)
                .filter(|&u| index.live[u as usize])
                .min_by(|&a, &b| motion.speed[a as usize].total_cmp(&motion.speed[b as usize]).then(a.cmp(&b)))
            {
                Some(u) => u,
                None => refuse!(
                    "{}: no frame from which a walk can go on (no clip loops and no transition leads back): \
                     the controller needs a graph with cycles",
                    s.name
                ),
            },
        };
        let (iu, iv, _) = plane_axes(s.up_axis);
        let c = prep.model.centres[start as usize];
        let theta = match motion.heading[start as usize] {
            h if h.is_finite() => h,
            _ => walk_off_heading(&index, &motion, s, start).unwrap_or(0.0),
        };
        let rot = PlaneMotion { theta, t: [0.0, 0.0], up: s.up_axis };
        let r = rot.apply_point(c);
        let g = PlaneMotion { theta, t: [-r[iu], -r[iv]], up: s.up_axis };
        let distances = if options.meshes { Some(prep.pipe.chain_distances()?.value) } else { None };
        let abilities = abilities(&index, &motion);
        let mut c = Controller {
            pipe: prep.pipe.clone(),
            model: prep.model.clone(),
            distances,
            index,
            motion,
            abilities,
            options,
            node: start,
            g,
            queue: VecDeque::new(),
            shown: 0,
            due: 1.0,
            last_decision: None,
            input: None,
            transitions: 0,
            realism: 0.0,
        };
        // The first frame is shown at time 0.
        let first = c.original(start, &g);
        c.queue.push_back(Queued { frame: first, committed: true, at: Some((start, g)) });
        Ok(c)
    }

    /// The precomputed moves (for measures and sharing).
    pub fn index(&self) -> &Arc<FutureTrajectories> {
        &self.index
    }

    pub fn motion(&self) -> &Arc<FrameMotion> {
        &self.motion
    }

    /// Output frames shown so far.
    pub fn shown(&self) -> usize {
        self.shown
    }

    /// The frame shown last (global) and its placement.
    pub fn current(&self) -> (u32, PlaneMotion) {
        (self.node, self.g)
    }

    /// Transitions played so far and the sum of their edge weights (the walk's realism cost).
    pub fn transitions(&self) -> (usize, f64) {
        (self.transitions, self.realism)
    }

    pub fn up(&self) -> UpAxis {
        self.model.up
    }

    /// Advances the clock by `dt` seconds under `input` and returns the frames that fell due
    /// (the first call shows the start frame).
    pub fn step(&mut self, input: &Input, dt: f64) -> Result<Step> {
        if !(dt >= 0.0 && dt.is_finite()) {
            refuse!("time step {dt}: expected a non-negative number of seconds");
        }
        check_input(input)?;
        let mut out = Step::default();
        if self.input.as_ref() != Some(input) {
            out.cannot_follow = self.cannot_follow(input);
            self.input = Some(*input);
        }
        let fps = self.model.fps;
        self.due += dt * fps;
        while self.due >= 1.0 - 1e-9 {
            self.due -= 1.0;
            let now = self.shown as f64 / fps;
            let stale = self.last_decision.is_none_or(|t| now - t >= self.options.decision_interval - 1e-9);
            // Only the clip continuing is queued (a decision never queues it behind a
            // transition): it gives way to a new decision when the last one is stale.
            if self.queue.front().is_none_or(|q| !q.committed) && (self.queue.is_empty() || stale) {
                self.queue.clear();
                out.decisions.push(self.decide(input, now)?);
            }
            let Some(q) = self.queue.pop_front() else {
                refuse!("the controller found no move from frame {}", self.label(self.node));
            };
            if let Some((node, g)) = q.at {
                self.node = node;
                self.g = g;
            }
            self.shown += 1;
            out.frames.push(q.frame);
        }
        Ok(out)
    }

    /// `sequence:frame` of a global frame.
    fn label(&self, f: u32) -> String {
        self.pipe.subject().frame_index().label(f as usize)
    }

    /// The original frame `f` placed by `g`.
    fn original(&self, f: u32, g: &PlaneMotion) -> ShownFrame {
        let positions = self.options.meshes.then(|| {
            let mut p = self.pipe.subject().frame(f as usize).expect("graph nodes are frames").to_vec();
            g.apply(&mut p);
            p
        });
        ShownFrame {
            frame: Some(f),
            mix: Some(FrameMix::original(f)),
            centre: g.apply_point(self.model.centres[f as usize]),
            transition: None,
            positions,
        }
    }

    /// Queues the frames edge `u` -> `v` (played by `step`) adds after `u` placed by `g`, and
    /// returns v's placement.
    fn queue_edge(
        &mut self,
        step: EdgeStep<'_>,
        u: u32,
        v: u32,
        g: &PlaneMotion,
        committed: bool,
    ) -> Result<PlaneMotion> {
        let model = self.model.clone();
        match step {
            EdgeStep::Original | EdgeStep::Wrap(_) => {
                let g2 = model.advance(step, g, v, |_, _| {});
                let frame = self.original(v, &g2);
                self.queue.push_back(Queued { frame, committed, at: Some((v, g2)) });
                Ok(g2)
            }
            EdgeStep::Transition(_) => {
                let mut centres = Vec::new();
                let g2 = model.advance(step, g, v, |c, _| centres.push(c));
                let played = match &self.distances {
                    Some(d) => Some(walk_sequence(self.pipe.subject(), &model, &d.values, &[u, v], g)?),
                    None => None,
                };
                let per = 3 * self.pipe.subject().topology().n_vertices();
                for (k, c) in centres.iter().enumerate() {
                    let last = k + 1 == centres.len();
                    // Output frame k + 1 of the played pair (frame 0 is u, shown already).
                    let mix = played.as_ref().map(|p| p.mix[k + 1]);
                    let positions = played.as_ref().map(|p| p.positions[(k + 1) * per..(k + 2) * per].to_vec());
                    let frame = ShownFrame {
                        frame: last.then_some(v),
                        mix: if last { Some(FrameMix::original(v)) } else { mix },
                        centre: *c,
                        transition: Some((u, v)),
                        positions,
                    };
                    self.queue.push_back(Queued { frame, committed, at: last.then_some((v, g2)) });
                }
                Ok(g2)
            }
        }
    }

    /// The current ground velocity and facing of the character, from the frame shown.
    fn velocity_and_facing(&self) -> ([f64; 2], f64) {
        let u = self.node as usize;
        let h = self.motion.heading[u] - self.g.theta;
        if self.motion.heading[u].is_finite() {
            let v = self.motion.speed[u];
            ([v * h.cos(), v * h.sin()], h)
        } else {
            ([0.0, 0.0], f64::NAN)
        }
    }

    /// The ground velocity `input` asks for when the character is at `at`.
    fn goal_velocity(&self, input: &Input, at: [f64; 2]) -> [f64; 2] {
        match input.goal {
            Goal::Velocity(v) => v,
            Goal::Target(p) => {
                let d = [p[0] - at[0], p[1] - at[1]];
                let dist = d[0].hypot(d[1]);
                if dist < ARRIVED_HEIGHTS * self.motion.height {
                    return [0.0, 0.0];
                }
                let speed = self.target_speed(input.gait).min(dist / ARRIVE_SECONDS);
                [d[0] / dist * speed, d[1] / dist * speed]
            }
        }
    }

    /// The speed a target is walked to at: the typical speed of the asked gait (walk by
    /// default), else of whichever travelling gait the data has.
    fn target_speed(&self, gait: Option<Gait>) -> f64 {
        let m = &self.motion;
        [gait.filter(|g| *g != Gait::Idle).unwrap_or(Gait::Walk), Gait::Walk, Gait::Run]
            .iter()
            .find_map(|g| m.typical_speed(*g))
            .unwrap_or(0.0)
    }

    /// One decision at time `now` (seconds), its move queued.
    fn decide(&mut self, input: &Input, now: f64) -> Result<Decision> {
        let t0 = Instant::now();
        let model = self.model.clone();
        let index = self.index.clone();
        let fps = model.fps;
        let (iu, iv, _) = plane_axes(model.up);
        let lookahead = (self.options.decision_interval * fps).ceil().max(1.0) as usize;
        // The frames about to be shown as captured (no wrap: a wrap moves the placement).
        let mut frames = vec![self.node];
        while frames.len() < lookahead {
            let u = *frames.last().expect("one frame at least");
            match model.next(u) {
                Some((v, EdgeStep::Original)) if index.continues[u as usize] => frames.push(v),
                _ => break,
            }
        }
        let centres: Vec<[f64; 2]> = frames
            .iter()
            .map(|&f| {
                let c = model.centres[f as usize];
                [c[iu], c[iv]]
            })
            .collect();
        let here = self.g.apply_point(model.centres[self.node as usize]);
        let position = [here[iu], here[iv]];
        let (velocity, facing) = self.velocity_and_facing();
        let goal_velocity = self.goal_velocity(input, position);
        let moving = goal_velocity[0].hypot(goal_velocity[1])
            >= super::frame_motion::IDLE_HEIGHTS_PER_SECOND * self.motion.height;
        let gait = match input.gait {
            Some(g) => GaitAsked::Exactly(g),
            None if moving => GaitAsked::Moving,
            None => GaitAsked::Any,
        };
        let goal = TrajectoryGoal {
            position,
            velocity,
            facing,
            goal_velocity,
            goal_facing: input.facing,
            halflife: self.options.halflife,
        };
        let horizon = index.horizons[index.horizons.len() - 1];
        let desired = desired_trajectory(&goal, fps, frames.len() - 1 + horizon);
        // In the coordinates where the frame shown now is unmoved: x = g^-1(world).
        let (s, c) = self.g.theta.sin_cos();
        let local = LocalGoal {
            positions: desired
                .positions
                .iter()
                .map(|p| {
                    let (a, b) = (p[0] - self.g.t[0], p[1] - self.g.t[1]);
                    [c * a - s * b, s * a + c * b]
                })
                .collect(),
            facing: desired.facing.iter().map(|f| f + self.g.theta).collect(),
        };
        let ahead = Ahead { frames: &frames, centres: &centres };
        let choice = choose_move(&index, &self.motion, &ahead, &local, gait, &self.options.weights);
        let seconds = t0.elapsed().as_secs_f64();
        if !choice.cost.is_finite() {
            refuse!("the controller found no move from frame {}", self.label(self.node));
        }
        let mut g = self.g;
        match choice.chosen {
            Move::Continue => {
                let mut u = self.node;
                for _ in 0..lookahead {
                    let Some((v, step)) = model.next(u).filter(|_| index.continues[u as usize]) else { break };
                    g = self.queue_edge(step, u, v, &g, false)?;
                    u = v;
                }
            }
            Move::Transition { after, from, to, weight } => {
                for w in frames[..=after].windows(2) {
                    g = self.queue_edge(EdgeStep::Original, w[0], w[1], &g, true)?;
                }
                let Some(step @ EdgeStep::Transition(_)) = model.step(from, to) else {
                    refuse!("{} -> {}: not a transition of the walk model", self.label(from), self.label(to));
                };
                self.queue_edge(step, from, to, &g, true)?;
                self.transitions += 1;
                self.realism += weight;
            }
        }
        self.last_decision = Some(now);
        Ok(Decision {
            time: now,
            frame: self.node,
            chosen: choice.chosen,
            cost: choice.cost,
            candidates: choice.candidates,
            seconds,
        })
    }

    /// What of `input` the data cannot follow, and why.
    fn cannot_follow(&self, input: &Input) -> Vec<String> {
        let s = self.pipe.subject();
        let m = &self.motion;
        let speed_text = |x: f64| format!("{}/s", length(x, &s.units, 2));
        let mut notes = Vec::new();
        if let Some(g) = input.gait
            && !m.has(g)
        {
            let have: Vec<&str> = Gait::ALL.iter().filter(|x| m.has(**x)).map(|x| x.name()).collect();
            notes.push(format!(
                "no {} clip: {} has frames that {} only (idle under {}, run from {}), so {} is matched by speed alone",
                g.name(),
                s.name,
                have.join(", "),
                speed_text(super::frame_motion::IDLE_HEIGHTS_PER_SECOND * m.height),
                speed_text(super::frame_motion::RUN_HEIGHTS_PER_SECOND * m.height),
                g.name()
            ));
        }
        let asked = match input.goal {
            Goal::Velocity(v) => v[0].hypot(v[1]),
            Goal::Target(_) => self.target_speed(input.gait),
        };
        let travels = m.has(Gait::Walk) || m.has(Gait::Run);
        if asked > 0.0 && !travels {
            notes.push(format!(
                "no clip travels: every frame of {} moves slower than {} (a fifth of its height a second), so it \
                 cannot go anywhere; give in-place clips their travel back: surfcap import <sources> --root-motion \
                 contacts -o <subject>",
                s.name,
                speed_text(super::frame_motion::IDLE_HEIGHTS_PER_SECOND * m.height)
            ));
        } else if asked > self.abilities.fastest * 1.1 {
            notes.push(format!(
                "asked {}: the fastest frame of {} moves {}",
                speed_text(asked),
                s.name,
                speed_text(self.abilities.fastest)
            ));
        }
        if asked == 0.0 && !m.has(Gait::Idle) {
            let slowest = m.speed.iter().copied().fold(f64::INFINITY, f64::min);
            notes.push(format!(
                "cannot stop: {} has no idle frame (the slowest moves {})",
                s.name,
                speed_text(slowest)
            ));
        }
        if !self.abilities.turns {
            let (_, facing) = self.velocity_and_facing();
            let asked_dir = input.facing.or(match input.goal {
                Goal::Velocity(v) if v[0].hypot(v[1]) > 0.0 => Some(v[1].atan2(v[0])),
                _ => None,
            });
            if let Some(a) = asked_dir
                && facing.is_finite()
                && surfcap_motion::blend::wrap_angle(a - facing).abs() > TURN_DEGREES.to_radians()
            {
                notes.push(format!(
                    "cannot turn: no clip or transition of {} turns by more than {TURN_DEGREES} degrees within a second",
                    s.name
                ));
            }
        }
        notes
    }
}

/// Within this many subject heights of a target, the character has arrived.
const ARRIVED_HEIGHTS: f64 = 0.1;
/// A target closer than the gait's speed times this (seconds) is approached more slowly.
const ARRIVE_SECONDS: f64 = 0.5;

/// Refuses non-finite numbers in an input.
fn check_input(input: &Input) -> Result<()> {
    let numbers = match input.goal {
        Goal::Velocity(v) | Goal::Target(v) => v,
    };
    if numbers.iter().chain(input.facing.iter()).any(|x| !x.is_finite()) {
        refuse!("input {input:?}: expected finite numbers (subject units, radians)");
    }
    Ok(())
}

/// What the moves of `index` allow: whether some move turns within a second, the fastest frame.
fn abilities(index: &FutureTrajectories, motion: &FrameMotion) -> Abilities {
    let last = 4 * (index.horizons.len() - 1);
    let turns_from = |u: usize, f: &[f32]| {
        let h = motion.heading[u];
        (f[last + 2] != 0.0 || f[last + 3] != 0.0)
            && h.is_finite()
            && surfcap_motion::blend::wrap_angle((f[last + 3] as f64).atan2(f[last + 2] as f64) - h).abs()
                > TURN_DEGREES.to_radians()
    };
    let n = index.live.len();
    let turns = (0..n).any(|u| {
        index.live[u]
            && (turns_from(u, index.continuation(u as u32))
                || index.leaving(u as u32).any(|k| turns_from(u, index.feature(k))))
    });
    Abilities { turns, fastest: motion.fastest() }
}

/// The direction a standing frame faces, taken as the way its clip sets off: the mean of the
/// one-second headings of the transitions from the frames of its sequence into travelling
/// frames (in the sequence's captured coordinates), `None` when none leaves it.
fn walk_off_heading(
    index: &FutureTrajectories,
    motion: &FrameMotion,
    s: &surfcap_mesh::Subject,
    f: u32,
) -> Option<f64> {
    let index_of = s.frame_index();
    let q = index_of.locate(f as usize)?.0;
    let last = 4 * (index.horizons.len() - 1);
    let (mut c, mut n) = (0.0, 0.0);
    for u in index_of.range(q) {
        for k in index.leaving(u as u32) {
            if motion.gait[index.to[k] as usize] != Gait::Idle {
                let feature = index.feature(k);
                c += feature[last + 2] as f64;
                n += feature[last + 3] as f64;
            }
        }
    }
    (c.hypot(n) > 1e-9).then(|| n.atan2(c))
}

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

use std::cell::RefCell;
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_geometry::poisson_reconstruction::PoissonPattern;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_mesh::UpAxis;
use surfcap_motion::transition_frames::FrameMix;
use surfcap_motion::walk_sequence::{Step as EdgeStep, WalkModel, walk_sequence};
use surfcap_pipeline::{Pipeline, PoseDistances};

use super::desired_trajectory::{TrajectoryGoal, desired_trajectory};
use super::frame_motion::{FrameMotion, Gait};
use super::future_trajectory::FEATURE;
use super::future_trajectory::FutureTrajectories;
use super::move_choice::{Ahead, GaitAsked, LocalGoal, MatchWeights, Move, choose_move, feature_cost, gait_mismatch};
use super::parametric_blend::{BlendContext, BlendPartners, BlendState, frame_angle, weight_towards};
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
    /// Parametric blending: mix a partner clip of the same kind into the clip played, at a
    /// continuous weight, to reach speeds and turn rates between the captured ones
    /// ([`super::parametric_blend`]; off by default, [`PARAMETRIC_BY_DEFAULT`]).
    pub parametric: bool,
}

impl Default for ControllerOptions {
    fn default() -> Self {
        ControllerOptions {
            decision_interval: 0.1,
            halflife: 0.2,
            weights: MatchWeights::default(),
            start: None,
            meshes: false,
            parametric: PARAMETRIC_BY_DEFAULT,
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

/// Whether [`ControllerOptions::parametric`] is on by default: off, because a decision with
/// blending has not yet been measured under the 2 ms p99 of `surfcap-bench play` (each new
/// partner chain computes eq. 2.3 angles over the mesh), and it helps some scripts and not
/// others (docs/results/play.md).
pub const PARAMETRIC_BY_DEFAULT: bool = false;

/// A parametric blend a decision chose: the partner frame mixed in and the weight aimed at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BlendChoice {
    /// The clip's frame (global) and its partner's.
    pub frame: u32,
    pub partner: u32,
    /// The weight aimed at (reached at [`super::parametric_blend::WEIGHT_PER_SECOND`]).
    pub weight: f64,
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
    /// The parametric blend played instead of `chosen`, if one was (`chosen` then says what
    /// the graph's moves alone would have done).
    pub blend: Option<BlendChoice>,
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
    /// The blend after this frame, and where the blend's coordinates are placed.
    blend: Option<(BlendState, PlaneMotion)>,
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
    /// Partner frames for parametric blending (empty when it is off).
    partners: Arc<BlendPartners>,
    /// The blend playing after the frame shown, if any.
    blend: Option<(BlendState, PlaneMotion)>,
    /// Eq. 2.3 angles between frames the blends have paired so far.
    angles: HashMap<(u32, u32), f64>,
    /// Blended frames played so far.
    blended: usize,
    pattern: Option<Arc<PoissonPattern>>,
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
        let distances =
            if options.meshes || options.parametric { Some(prep.pipe.chain_distances()?.value) } else { None };
        let partners = match (&distances, options.parametric) {
            (Some(d), true) => Arc::new(BlendPartners::new(s, &prep.model, &motion, &index, &d.values)),
            _ => Arc::new(BlendPartners::default()),
        };
        let pattern = if options.meshes && options.parametric && partners.frames_with_partners() > 0 {
            Some(Arc::new(PoissonPattern::new(s.topology())?))
        } else {
            None
        };
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
            partners,
            blend: None,
            angles: HashMap::new(),
            blended: 0,
            pattern,
        };
        // The first frame is shown at time 0.
        let first = c.original(start, &g);
        c.queue.push_back(Queued { frame: first, committed: true, at: Some((start, g)), blend: None });
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

    /// The partner frames parametric blending may mix in (none when it is off).
    pub fn partners(&self) -> &Arc<BlendPartners> {
        &self.partners
    }

    /// Output frames shown so far that were parametric blends (weight above 0).
    pub fn blended(&self) -> usize {
        self.blended
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
            self.blend = q.blend;
            self.blended += usize::from(q.blend.is_some());
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
                self.queue.push_back(Queued { frame, committed, at: Some((v, g2)), blend: None });
                Ok(g2)
            }
            EdgeStep::Transition(_) => {
                let mut centres = Vec::new();
                let g2 = model.advance(step, g, v, |c, _| centres.push(c));
                let played = match &self.distances {
                    Some(d) if self.options.meshes => {
                        Some(walk_sequence(self.pipe.subject(), &model, &d.values, &[u, v], g)?)
                    }
                    _ => None,
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
                    self.queue.push_back(Queued { frame, committed, at: last.then_some((v, g2)), blend: None });
                }
                Ok(g2)
            }
        }
    }

    /// The current ground velocity and facing of the character, from the frame shown.
    fn velocity_and_facing(&self) -> ([f64; 2], f64) {
        if let Some((st, g0)) = &self.blend {
            let h = st.facing(&self.motion) - g0.theta;
            if h.is_finite() {
                let v = st.speed(&self.motion);
                return ([v * h.cos(), v * h.sin()], h);
            }
        }
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
        let candidate =
            if self.partners.frames_with_partners() > 0 { self.best_blend(&local, gait, centres[0]) } else { None };
        let seconds = t0.elapsed().as_secs_f64();
        let blending = self.blend.is_some_and(|(st, _)| st.lambda > 0.0);
        let played = match candidate {
            // A blend is kept while it beats the graph's moves; otherwise it fades out first (a
            // transition is taken from the clip itself).
            Some(b) if blending && choice.cost < b.cost => Some(BlendCandidate { target: 0.0, ..b }),
            Some(b) if blending || b.cost < choice.cost => Some(b),
            _ => None,
        };
        let mut blend_choice = None;
        if let Some(b) = played {
            blend_choice = self.queue_blend(&b)?;
        }
        if blend_choice.is_none() {
            // No blend plays (or its partner cannot go on: it ends here).
            self.blend = None;
            self.queue_move(&choice, &frames, lookahead)?;
        }
        self.last_decision = Some(now);
        Ok(Decision {
            time: now,
            frame: self.node,
            chosen: choice.chosen,
            cost: blend_choice.map_or(choice.cost, |_| played.map_or(choice.cost, |b| b.cost)),
            candidates: choice.candidates + played.map_or(0, |b| b.candidates),
            seconds,
            blend: blend_choice,
        })
    }

    /// Queues the frames of the graph move `choice` from the frames `frames` about to be shown.
    fn queue_move(&mut self, choice: &super::move_choice::Choice, frames: &[u32], lookahead: usize) -> Result<()> {
        if !choice.cost.is_finite() {
            refuse!("the controller found no move from frame {}", self.label(self.node));
        }
        let model = self.model.clone();
        let index = self.index.clone();
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
        Ok(())
    }

    /// Queues the blend `b` for the next decision interval: returns what was chosen, `None`
    /// when the partner cannot go on from the first frame (nothing queued).
    fn queue_blend(&mut self, b: &BlendCandidate) -> Result<Option<BlendChoice>> {
        let model = self.model.clone();
        let index = self.index.clone();
        let Some(d) = self.distances.clone() else { return Ok(None) };
        let fps = model.fps;
        let lookahead = (self.options.decision_interval * fps).ceil().max(1.0) as usize;
        let memo = RefCell::new(std::mem::take(&mut self.angles));
        let pipe = self.pipe.clone();
        let angle = |a: u32, x: u32| cached_angle(&memo, pipe.subject(), a, x);
        let cx = BlendContext { model: &model, index: &index, d: &d.values, angle: &angle };
        let mut states = Vec::with_capacity(lookahead);
        let mut st = b.start;
        for _ in 0..lookahead {
            let Some(next) = st.advance(&cx, weight_towards(st.lambda, b.target, fps)) else { break };
            st = next;
            states.push(st);
        }
        self.angles = memo.into_inner();
        if states.is_empty() {
            return Ok(None);
        }
        for st in states {
            let frame = self.blend_frame(&st, &b.g0)?;
            let at = Some((st.a, b.g0.after(&st.gs)));
            self.queue.push_back(Queued {
                frame,
                committed: false,
                at,
                blend: (st.lambda > 0.0).then_some((st, b.g0)),
            });
        }
        Ok(Some(BlendChoice { frame: b.start.a, partner: b.start.b, weight: b.target }))
    }

    /// One output frame of a blend: A's and B's frames moved where the blend put them and
    /// mixed by the non-linear interpolation (when meshes are returned).
    fn blend_frame(&self, st: &BlendState, g0: &PlaneMotion) -> Result<ShownFrame> {
        let s = self.pipe.subject();
        let positions = match &self.pattern {
            Some(pattern) => {
                let frame = |f: u32| s.frame(f as usize).expect("graph nodes are frames");
                let (mut a, mut b) = (frame(st.a).to_vec(), frame(st.b).to_vec());
                g0.after(&st.gs).apply(&mut a);
                g0.after(&st.gd).apply(&mut b);
                Some(if st.lambda > 0.0 {
                    NonlinearInterpolator::with_pattern(pattern, s.topology(), &a, &b, s.up_axis)?
                        .at(st.lambda, StretchInterpolation::Linear)
                } else {
                    a
                })
            }
            None => None,
        };
        let mix = FrameMix { from: st.a, to: st.b, weight: st.lambda as f32 };
        Ok(ShownFrame {
            frame: (st.lambda == 0.0).then_some(st.a),
            mix: Some(if st.lambda > 0.0 { mix } else { FrameMix::original(st.a) }),
            centre: g0.apply_point(st.p),
            transition: None,
            positions,
        })
    }

    /// The best parametric blend from the frame shown for the asked trajectory `goal` (local
    /// coordinates, as the graph's moves are scored; `origin` the frame's ground centre): the
    /// blend playing, or a new one with each partner of the frame, at the weights of a grid of
    /// [`WEIGHT_STEPS`] steps refined by a parabola through the best and its neighbours (the
    /// weight is continuous). Its cost is the graph moves' matching cost of its predicted
    /// future (the blend played forward, the weight moving to the target) plus the realism
    /// weight times the change of weight times the pair's pose distance (in units of the
    /// median partner distance).
    fn best_blend(&mut self, goal: &LocalGoal, gait: GaitAsked, origin: [f64; 2]) -> Option<BlendCandidate> {
        let model = self.model.clone();
        let index = self.index.clone();
        let motion = self.motion.clone();
        let d = self.distances.clone()?;
        let partners = self.partners.clone();
        let fps = model.fps;
        let (iu, iv, _) = plane_axes(model.up);
        let memo = RefCell::new(std::mem::take(&mut self.angles));
        let pipe = self.pipe.clone();
        let angle = |a: u32, x: u32| cached_angle(&memo, pipe.subject(), a, x);
        let cx = BlendContext { model: &model, index: &index, d: &d.values, angle: &angle };
        // (the blend's state at the frame shown, where its coordinates are placed, pose distance)
        let starts: Vec<(BlendState, PlaneMotion, f64)> = match self.blend {
            Some((st, g0)) => {
                let n = model.centres.len();
                let dist = partners.of(st.a).find(|&k| partners.partner[k] == st.b).map_or(
                    d.values[st.a as usize * n + st.b as usize] / partners.median.max(f64::MIN_POSITIVE),
                    |k| partners.distance[k] as f64,
                );
                vec![(st, g0, dist)]
            }
            None => partners
                .of(self.node)
                .map(|k| {
                    (BlendState::begin(&cx, self.node, partners.partner[k], 0.0), self.g, partners.distance[k] as f64)
                })
                .collect(),
        };
        let horizons = index.horizons;
        let last = horizons[horizons.len() - 1];
        let w = self.options.weights;
        let mut candidates = 0;
        let mut best: Option<BlendCandidate> = None;
        for (start, g0, dist) in starts {
            let gs0 = start.gs;
            let (sn, cs) = gs0.theta.sin_cos();
            let cost_of = |target: f64| -> Option<f64> {
                let mut feature = [0f32; FEATURE];
                let mut st = start;
                let mut k = 0;
                for f in 1..=last {
                    st = st.advance(&cx, weight_towards(st.lambda, target, fps))?;
                    if f == horizons[k] {
                        // Blend coordinates to the frame shown's captured ones: gs0^-1.
                        let (a, b) = (st.p[iu] - gs0.t[0], st.p[iv] - gs0.t[1]);
                        let local = [cs * a - sn * b, sn * a + cs * b];
                        feature[4 * k] = (local[0] - origin[0]) as f32;
                        feature[4 * k + 1] = (local[1] - origin[1]) as f32;
                        let h = st.facing(&motion) + gs0.theta;
                        if h.is_finite() {
                            feature[4 * k + 2] = h.cos() as f32;
                            feature[4 * k + 3] = h.sin() as f32;
                        }
                        k += 1;
                    }
                }
                let shown = if target >= 0.5 { motion.gait[st.b as usize] } else { motion.gait[st.a as usize] };
                Some(
                    feature_cost(&index, &motion, origin, 0, goal, &feature, gait_mismatch(gait, shown), &w)
                        + w.realism * (target - start.lambda).abs() * dist,
                )
            };
            let grid: Vec<(f64, Option<f64>)> = (0..=WEIGHT_STEPS)
                .map(|i| i as f64 / WEIGHT_STEPS as f64)
                .filter(|&t| t > 0.0 || start.lambda > 0.0)
                .map(|t| (t, cost_of(t)))
                .collect();
            candidates += grid.len();
            let Some(i) = (0..grid.len())
                .filter(|&i| grid[i].1.is_some())
                .min_by(|&x, &y| grid[x].1.unwrap().total_cmp(&grid[y].1.unwrap()))
            else {
                continue;
            };
            let (mut target, mut cost) = (grid[i].0, grid[i].1.unwrap_or(f64::INFINITY));
            if i > 0
                && i + 1 < grid.len()
                && let (Some(c0), Some(c2)) = (grid[i - 1].1, grid[i + 1].1)
            {
                let (t0, t2) = (grid[i - 1].0, grid[i + 1].0);
                let h = t2 - target;
                let curvature = c0 - 2.0 * cost + c2;
                if curvature > 0.0 && (target - t0 - h).abs() < 1e-12 {
                    let t = (target + h * (c0 - c2) / (2.0 * curvature)).clamp(t0, t2);
                    candidates += 1;
                    if let Some(c) = cost_of(t).filter(|c| *c < cost) {
                        (target, cost) = (t, c);
                    }
                }
            }
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(BlendCandidate { start, g0, target, cost, candidates: 0 });
            }
        }
        self.angles = memo.into_inner();
        if self.angles.len() > ANGLE_CACHE {
            self.angles.clear();
        }
        best.map(|b| BlendCandidate { candidates, ..b })
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

/// Weights compared per blend before the parabolic refinement: 0, 1/4, ..., 1.
const WEIGHT_STEPS: usize = 4;
/// Frame-pair angles kept between decisions at most (then forgotten).
const ANGLE_CACHE: usize = 1 << 20;

/// A blend a decision may play: from `start` (placed by `g0`) towards weight `target`.
#[derive(Debug, Clone, Copy)]
struct BlendCandidate {
    start: BlendState,
    g0: PlaneMotion,
    target: f64,
    cost: f64,
    /// Weights compared.
    candidates: usize,
}

/// Eq. 2.3's angle between frames `a` and `b`, computed once.
fn cached_angle(memo: &RefCell<HashMap<(u32, u32), f64>>, s: &surfcap_mesh::Subject, a: u32, b: u32) -> f64 {
    if let Some(x) = memo.borrow().get(&(a, b)) {
        return *x;
    }
    let x = frame_angle(s, a, b);
    memo.borrow_mut().insert((a, b), x);
    x
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

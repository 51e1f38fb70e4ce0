//! A live session of the interactive controller, as a page or a game host plays it: the
//! controller steered step by step, every transition it chooses blended on a worker thread (the
//! newest first, frame by frame, published as the frames are made), each blended frame's
//! stand-in ready at once ([`super::display_blend`]), and every answer as the JSON the play
//! page of `surfcap play` reads (`surfcap_view::play` documents the protocol and why decisions
//! are made on the server).
//!
//! [`LiveSession::start`] sets a session up on a prepared subject (the controller's moves, the
//! captured frames as one compact stream, kept in the derived cache); [`LiveSession::step`]
//! advances it under an input, [`LiveSession::blend`] and [`LiveSession::blend_from`] give a
//! chosen transition's frames as a compact stream, [`LiveSession::restart`] starts again.

use std::collections::HashMap;
use std::sync::mpsc;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use surfcap_formats::stream::{StreamOptions, encode_stream};
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_mesh::{Sequence, Subject, Topology};
use surfcap_motion::walk_sequence::WalkModel;
use surfcap_pipeline::PoseDistances;

use super::captured_stream::{KEY_INTERVAL, captured_stream};
use super::display_blend::{DisplayMix, display_blend};
use super::future_trajectory::FEATURE;
use super::transition_blend::{BlendTimes, TransitionBlender};
use super::{Controller, ControllerOptions, Gait, Goal, Input, Move};
use crate::Prepared;
use crate::error::{Error, Result};

/// What a player asks for one step: a ground direction (the subject's two ground axes, length
/// 0 to stop up to 1 for the gait's full speed), walk or run, and the seconds since the last
/// step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveAsk {
    pub direction: [f64; 2],
    pub run: bool,
    pub dt: f64,
}

/// A blend on its way: being made (the frames made so far, of how many), made (its frames), or
/// failed (why).
#[derive(Clone)]
enum BlendState {
    Pending,
    Making(Vec<Arc<Vec<f32>>>, usize),
    Ready(Vec<Arc<Vec<f32>>>),
    Failed(String),
}

/// The blends asked for, by id, and the id of each (source, destination) frame pair.
#[derive(Default)]
struct BlendTable {
    by_id: HashMap<u64, BlendState>,
    by_pair: HashMap<(u32, u32), u64>,
    /// Each blend's stand-ins, frame by frame (empty when the pair is not a transition).
    stand_ins: HashMap<u64, Arc<Vec<DisplayMix>>>,
}

/// Timings of the blends made (seconds), for the info route.
#[derive(Default)]
struct BlendClock {
    /// Each blend: from asked to made and coded.
    made: Vec<f64>,
    /// Each blend: from asked to its first frame.
    first: Vec<f64>,
    /// Each blend: from asked to started (waiting behind other blends).
    waited: Vec<f64>,
    times: BlendTimes,
    coding: f64,
}

/// The transitions blended so far.
#[derive(Default)]
struct Blends {
    state: Mutex<BlendTable>,
    changed: Condvar,
    clock: Mutex<BlendClock>,
}

/// The controller's walk as the page sees it.
struct Session {
    controller: Controller,
    /// The placement of the last captured frame shown (a transition's frames are placed by it).
    placement: PlaneMotion,
    /// Frames shown of the transition playing (its blended frames' index).
    in_blend: usize,
    last_input: Option<Input>,
    /// The transition the last decision chose, if it chose one.
    chosen: Option<(u32, u32)>,
}

/// A live session on a prepared subject (see the module doc).
pub struct LiveSession {
    prep: Prepared,
    options: ControllerOptions,
    session: Mutex<Session>,
    stream: Arc<Vec<u8>>,
    blends: Arc<Blends>,
    jobs: Mutex<mpsc::Sender<(u64, u32, u32, Instant)>>,
    distances: Arc<PoseDistances>,
    bits: u32,
    info: serde_json::Value,
    walk_speed: f64,
    run_speed: f64,
    moves: usize,
    precompute: f64,
    coding: f64,
    stream_cached: bool,
}

impl LiveSession {
    /// A session on `prep`: the controller's moves precomputed, the captured frames coded as
    /// one compact stream of `bits` per coordinate (8 to 16, what the play page decodes; read
    /// from the derived cache when there), the pose distances the blends need, and the blending
    /// thread started.
    pub fn start(prep: Prepared, bits: u32) -> Result<Self> {
        if !(8..=16).contains(&bits) {
            return Err(Error::Request(format!("{bits} bits per coordinate: expected 8 to 16")));
        }
        let t0 = Instant::now();
        let controller = Controller::new(&prep, ControllerOptions::default())?;
        let precompute = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let (stream, cached) = captured_stream(&prep, bits)?;
        let coding = t1.elapsed().as_secs_f64();
        let distances = prep.pipe.chain_distances()?.value;
        let mut session = Self::new(prep, controller, distances, Arc::new(stream), precompute, coding, bits)?;
        session.stream_cached = cached;
        Ok(session)
    }

    fn new(
        prep: Prepared,
        controller: Controller,
        distances: Arc<PoseDistances>,
        stream: Arc<Vec<u8>>,
        precompute: f64,
        coding: f64,
        bits: u32,
    ) -> Result<Self> {
        let s = prep.subject();
        let motion = controller.motion().clone();
        let walk_speed = motion
            .typical_speed(Gait::Walk)
            .or_else(|| motion.typical_speed(Gait::Run))
            .unwrap_or_else(|| motion.fastest());
        let run_speed = motion.typical_speed(Gait::Run).unwrap_or_else(|| motion.fastest()).max(walk_speed);
        let moves = controller.index().to.len() + controller.index().continues.iter().filter(|c| **c).count();
        let (start, _) = controller.current();
        let (iu, iv, _) = plane_axes(s.up_axis);
        let index = s.frame_index();
        let info = serde_json::json!({
            "subject": s.name,
            "fps": s.fps,
            "up": s.up_axis.as_str(),
            "ground_axes": [iu, iv],
            "units": s.units.symbol(),
            "metres_per_unit": s.units.metres_per_unit,
            "vertices": s.topology().n_vertices(),
            "frames": s.n_frames(),
            "sequences": s.sequences().iter().enumerate().map(|(k, q)| serde_json::json!({
                "name": q.name, "first": index.range(k).start, "frames": q.n_frames(),
            })).collect::<Vec<_>>(),
            "start": { "frame": start, "label": index.label(start as usize) },
            "gaits": Gait::ALL.iter().filter(|g| motion.has(**g)).map(|g| g.name()).collect::<Vec<_>>(),
            "walk_speed": walk_speed,
            "run_speed": run_speed,
            "height": motion.height,
            "moves": moves,
            "precompute_seconds": precompute,
            "stream": { "bytes": stream.len(), "bits": bits, "coding_seconds": coding },
            "decision_interval": ControllerOptions::default().decision_interval,
        });
        let blends = Arc::new(Blends::default());
        let (tx, rx) = mpsc::channel::<(u64, u32, u32, Instant)>();
        let worker = BlendWorker {
            blender: TransitionBlender::new(s).map_err(|e| Error::Request(format!("{}: {e}", s.name)))?,
            subject: Arc::new(s.clone()),
            model: prep.model.clone(),
            distances: distances.clone(),
            blends: blends.clone(),
        };
        std::thread::Builder::new()
            .name("blend".into())
            .spawn(move || {
                // The newest transition chosen first: an older one's frames may be past already
                // (its stand-ins were shown), and it is made when nothing newer waits.
                let mut waiting = Vec::new();
                while let Ok(job) = rx.recv() {
                    waiting.push(job);
                    waiting.extend(rx.try_iter());
                    while let Some(job) = waiting.pop() {
                        worker.make(job);
                        waiting.extend(rx.try_iter());
                    }
                }
            })
            .map_err(|e| Error::Request(format!("cannot start the blending thread: {e}")))?;
        let placement = controller.current().1;
        Ok(LiveSession {
            options: ControllerOptions::default(),
            session: Mutex::new(Session { controller, placement, in_blend: 0, last_input: None, chosen: None }),
            prep,
            stream,
            blends,
            jobs: Mutex::new(tx),
            distances,
            bits,
            info,
            walk_speed,
            run_speed,
            moves,
            precompute,
            coding,
            stream_cached: false,
        })
    }

    /// The controller's input for what the page asks.
    fn input(&self, ask: &LiveAsk) -> Input {
        let [x, y] = ask.direction;
        let amount = x.hypot(y).min(1.0);
        if amount < 1e-3 {
            return Input::stop();
        }
        let speed = if ask.run { self.run_speed } else { self.walk_speed } * amount;
        let v = [x / x.hypot(y) * speed, y / x.hypot(y) * speed];
        let input = Input::velocity(v);
        if ask.run { input.with_gait(Gait::Run) } else { input }
    }

    /// The blend id of transition `from` -> `to`, asking the worker for it (and making its
    /// stand-ins) the first time.
    fn blend_id(&self, from: u32, to: u32) -> u64 {
        let mut st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(&id) = st.by_pair.get(&(from, to)) {
            return id;
        }
        let id = st.by_pair.len() as u64;
        st.by_pair.insert((from, to), id);
        st.by_id.insert(id, BlendState::Pending);
        let mixes = display_blend(self.prep.subject(), &self.prep.model, &self.distances.values, from, to);
        st.stand_ins.insert(id, Arc::new(mixes.unwrap_or_default()));
        drop(st);
        let sent = self.jobs.lock().unwrap_or_else(|e| e.into_inner()).send((id, from, to, Instant::now()));
        if sent.is_err() {
            let mut st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
            st.by_id.insert(id, BlendState::Failed("the blending thread stopped".into()));
        }
        id
    }

    /// Frame `k`'s stand-in of blend `id` as JSON for the page.
    fn stand_in(&self, id: u64, k: usize) -> serde_json::Value {
        let st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
        match st.stand_ins.get(&id).and_then(|m| m.get(k)) {
            Some(m) => serde_json::json!({
                "a": m.a, "b": m.b, "lambda": m.lambda,
                "ga": [m.ga.theta, m.ga.t[0], m.ga.t[1]], "gb": [m.gb.theta, m.gb.t[0], m.gb.t[1]],
            }),
            None => serde_json::Value::Null,
        }
    }

    /// Waits (up to 60 s) until blend `id` is made or has at least `from + 1` frames, and
    /// returns its state then.
    fn wait_for(&self, id: u64, from: usize) -> Result<BlendState, String> {
        let mut st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
        let deadline = Instant::now() + std::time::Duration::from_secs(60);
        loop {
            let state =
                st.by_id.get(&id).cloned().ok_or_else(|| {
                    format!("no blend {id}: the controller has chosen {} transitions", st.by_pair.len())
                })?;
            match state {
                BlendState::Failed(why) => return Err(why),
                BlendState::Making(ref f, _) if f.len() > from => return Ok(state),
                BlendState::Ready(..) => return Ok(state),
                _ => {}
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(format!("blend {id} is still being made after 60 s"));
            }
            st = self.blends.changed.wait_timeout(st, deadline - now).unwrap_or_else(|e| e.into_inner()).0;
        }
    }

    /// Blended frames as a compact stream (the coding time is counted in the info).
    fn code(&self, name: &str, frames: &[Arc<Vec<f32>>]) -> Result<Vec<u8>, String> {
        let t = Instant::now();
        let frames: Vec<Vec<f32>> = frames.iter().map(|f| f.to_vec()).collect();
        let coded = code_frames(self.prep.subject(), name, &frames, self.bits);
        self.blends.clock.lock().unwrap_or_else(|e| e.into_inner()).coding += t.elapsed().as_secs_f64();
        coded
    }

    fn label(&self, f: u32) -> String {
        self.prep.subject().frame_index().label(f as usize)
    }

    /// A point of the walk model's future of frame `u` (`d`: offset on the ground axes from
    /// its centre) placed by `g`.
    fn placed(&self, g: &PlaneMotion, u: u32, d: [f32; 2]) -> [f64; 3] {
        let (iu, iv, _) = plane_axes(self.prep.subject().up_axis);
        let mut p = self.prep.model.centres[u as usize];
        p[iu] += f64::from(d[0]);
        p[iv] += f64::from(d[1]);
        g.apply_point(p)
    }
}

/// Blends transitions on its own thread.
struct BlendWorker {
    blender: TransitionBlender,
    subject: Arc<Subject>,
    model: Arc<WalkModel>,
    distances: Arc<PoseDistances>,
    blends: Arc<Blends>,
}

/// `frames` (each the subject's vertex count) as a compact stream named `name`. Its topology is
/// one placeholder triangle: the page draws the captured stream's triangles.
fn code_frames(s: &Subject, name: &str, frames: &[Vec<f32>], bits: u32) -> Result<Vec<u8>, String> {
    let n = s.topology().n_vertices();
    if frames.is_empty() || n < 3 {
        return Err(format!("{name}: {} frames of {n} vertices", frames.len()));
    }
    let topo = Topology::new(n, vec![[0, 1, 2]], None).map_err(|e| format!("{name}: {e}"))?;
    let seq = Sequence::new(name.to_string(), n, frames.concat()).map_err(|e| format!("{name}: {e}"))?;
    let blend = Subject::new("blend", topo, vec![seq], s.fps, s.up_axis, s.units.clone())
        .map_err(|e| format!("{name}: {e}"))?;
    Ok(encode_stream(&blend, &StreamOptions { bits, max_error: None, key_interval: KEY_INTERVAL }).0)
}

impl BlendWorker {
    /// Transition `from` -> `to` played by Blend as offline synthesis plays it
    /// (`surfcap_motion::walk_sequence`, thesis Algorithm 3) with `from` unmoved: its frames
    /// after `from` (the last one is `to`, placed), published one by one as they are made (the
    /// routes code them when they are asked for).
    fn make(&self, (id, from, to, asked): (u64, u32, u32, Instant)) {
        let started = asked.elapsed().as_secs_f64();
        let s = &self.subject;
        let name = format!("{}->{}", s.frame_index().label(from as usize), s.frame_index().label(to as usize));
        let mut made: Vec<Arc<Vec<f32>>> = Vec::new();
        let mut first = None;
        let blended = self.blender.blend(s, &self.model, &self.distances.values, (from, to), |k, total, frame| {
            if k == 0 {
                first = Some(asked.elapsed().as_secs_f64());
            }
            made.push(Arc::new(frame));
            let mut st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
            st.by_id.insert(id, BlendState::Making(made.clone(), total));
            self.blends.changed.notify_all();
            true
        });
        let state = match blended {
            Ok((0, _)) => BlendState::Failed(format!("blending {name}: not a transition of the walk model")),
            Ok((_, times)) => {
                let mut clock = self.blends.clock.lock().unwrap_or_else(|e| e.into_inner());
                clock.times.add(&times);
                clock.made.push(asked.elapsed().as_secs_f64());
                clock.first.extend(first);
                clock.waited.push(started);
                BlendState::Ready(made)
            }
            Err(e) => BlendState::Failed(format!("blending {name}: {e}")),
        };
        let mut st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
        st.by_id.insert(id, state);
        self.blends.changed.notify_all();
    }
}

impl LiveSession {
    /// Moves the controller chooses among (transitions and clip continuations).
    pub fn moves(&self) -> usize {
        self.moves
    }

    /// The prepared subject the session plays.
    pub fn prepared(&self) -> &Prepared {
        &self.prep
    }

    /// Seconds the controller's moves took to precompute, and the captured stream to code (or
    /// read), and whether it was read from the cache.
    pub fn set_up_seconds(&self) -> (f64, f64, bool) {
        (self.precompute, self.coding, self.stream_cached)
    }

    /// The subject and the session as JSON for the page (name, fps, unit, up and ground axes,
    /// the start frame, the sequences, the gaits and their speeds, the stream, and the
    /// blends made so far with their timings).
    pub fn info(&self) -> serde_json::Value {
        let mut info = self.info.clone();
        let clock = self.blends.clock.lock().unwrap_or_else(|e| e.into_inner());
        let at = |v: &[f64], q: f64| {
            let mut t = v.to_vec();
            t.sort_by(f64::total_cmp);
            t.get(((t.len() as f64 - 1.0) * q).round() as usize).map(|s| s * 1e3)
        };
        let (m, f, w) = (&clock.made, &clock.first, &clock.waited);
        let tm = &clock.times;
        info["blends_made"] = serde_json::json!({
            "count": m.len(), "p50_ms": at(m, 0.5), "p99_ms": at(m, 0.99),
            "first_frame_p50_ms": at(f, 0.5), "first_frame_p99_ms": at(f, 0.99),
            "waited_p50_ms": at(w, 0.5), "waited_p99_ms": at(w, 0.99),
            "frames": tm.frames,
            "seconds": { "placements": tm.placements, "factorise": tm.factorise, "solve": tm.solve, "coding": clock.coding },
        });
        info
    }

    /// Every captured frame as one compact stream.
    pub fn captured_stream(&self) -> Arc<Vec<u8>> {
        self.stream.clone()
    }

    /// Advances the controller by `ask.dt` under the asked input: the frames that fell due with
    /// their placement, the decisions, the transitions chosen (their blends started), what
    /// cannot be followed, the predicted and desired trajectories, as JSON; an error is a
    /// message for the user.
    pub fn step(&self, ask: &LiveAsk) -> Result<serde_json::Value, String> {
        let input = self.input(ask);
        let t0 = Instant::now();
        let mut session = self.session.lock().unwrap_or_else(|e| e.into_inner());
        let notes = (session.last_input != Some(input)).then(Vec::new);
        let mut notes = notes;
        session.last_input = Some(input);
        // Steps of at most one output frame each, so that the controller's placement after a
        // step is the one of the frame it showed.
        let h = 0.999 / self.prep.model.fps;
        let mut remaining = ask.dt;
        let (mut frames, mut decisions, mut blends) = (Vec::new(), Vec::new(), Vec::new());
        loop {
            let dt = remaining.min(h);
            remaining -= dt;
            let step = session.controller.step(&input, dt).map_err(|e| e.to_string())?;
            if let Some(n) = notes.as_mut() {
                n.extend(step.cannot_follow.iter().cloned());
            }
            for d in &step.decisions {
                session.chosen = match d.chosen {
                    Move::Continue => None,
                    Move::Transition { from, to, .. } => Some((from, to)),
                };
                let chosen = match d.chosen {
                    Move::Continue => serde_json::json!("continue"),
                    Move::Transition { from, to, .. } => {
                        // Every transition chosen is listed (also one blended before, which a
                        // new page has not fetched yet).
                        let id = self.blend_id(from, to);
                        blends.push(serde_json::json!({ "id": id, "from": self.label(from), "to": self.label(to) }));
                        serde_json::json!({ "from": self.label(from), "to": self.label(to), "blend": id })
                    }
                };
                decisions.push(serde_json::json!({
                    "time": d.time, "frame": self.label(d.frame), "chosen": chosen, "cost": d.cost,
                    "candidates": d.candidates, "ms": d.seconds * 1e3,
                }));
            }
            for f in &step.frames {
                let transition = f.transition.map(|(u, v)| [self.label(u), self.label(v)]);
                let frame = match f.frame {
                    Some(v) => {
                        session.placement = session.controller.current().1;
                        session.in_blend = 0;
                        serde_json::json!({ "frame": v, "label": self.label(v) })
                    }
                    None => {
                        let (u, v) = f.transition.ok_or("a blended frame outside a transition")?;
                        let id = self.blend_id(u, v);
                        let k = session.in_blend;
                        session.in_blend += 1;
                        serde_json::json!({
                            "blend": id, "k": k, "stand_in": self.stand_in(id, k),
                            "label": format!("{} -> {} ({})", self.label(u), self.label(v), k + 1),
                        })
                    }
                };
                let g = session.placement;
                let mut frame = frame;
                frame["theta"] = g.theta.into();
                frame["t"] = serde_json::json!(g.t);
                frame["centre"] = serde_json::json!(f.centre);
                frame["transition"] = serde_json::json!(transition);
                frames.push(frame);
            }
            if remaining <= 0.0 {
                break;
            }
        }
        let c = &session.controller;
        let (node, g) = c.current();
        let index = c.index();
        // The walk model's future of what plays now: the transition chosen from this frame, or
        // the clip going on.
        let per = FEATURE;
        let feature = session
            .chosen
            .filter(|(from, _)| *from == node)
            .and_then(|(from, to)| index.leaving(from).find(|&k| index.to[k] == to))
            .map(|k| index.feature(k))
            .unwrap_or_else(|| &index.continuation[node as usize * per..(node as usize + 1) * per]);
        let here = g.apply_point(self.prep.model.centres[node as usize]);
        let predicted: Vec<[f64; 3]> =
            std::iter::once(here).chain(feature.chunks_exact(4).map(|q| self.placed(&g, node, [q[0], q[1]]))).collect();
        let (iu, iv, _) = plane_axes(self.prep.subject().up_axis);
        let goal = match input.goal {
            Goal::Velocity(v) => v,
            Goal::Target(_) => [0.0, 0.0],
        };
        let desired: Vec<[f64; 3]> = (0..=3)
            .map(|k| {
                let t = k as f64 / 3.0;
                let mut p = here;
                p[iu] += goal[0] * t;
                p[iv] += goal[1] * t;
                p
            })
            .collect();
        let (transitions, realism) = c.transitions();
        Ok(serde_json::json!({
            "frames": frames,
            "decisions": decisions,
            "blends": blends,
            "cannot_follow": notes,
            "predicted": predicted,
            "desired": desired,
            "asked_speed": goal[0].hypot(goal[1]),
            "transitions": transitions,
            "realism": realism,
            "server_ms": t0.elapsed().as_secs_f64() * 1e3,
        }))
    }

    /// Blend `id`'s frames as a compact stream, once they are all made (waits up to 60 s).
    pub fn blend(&self, id: u64) -> Result<Arc<Vec<u8>>, String> {
        let frames = match self.wait_for(id, usize::MAX)? {
            BlendState::Ready(f) => f,
            _ => return Err(format!("blend {id} is not made")),
        };
        let name = {
            let st = self.blends.state.lock().unwrap_or_else(|e| e.into_inner());
            let pair = st.by_pair.iter().find(|(_, i)| **i == id).map(|(p, _)| *p);
            pair.map_or(format!("blend {id}"), |(u, v)| format!("{}->{}", self.label(u), self.label(v)))
        };
        Ok(Arc::new(self.code(&name, &frames)?))
    }

    /// Blend `id`'s frames from frame `from` on that are made so far (waits for at least one),
    /// as a compact stream, and the transition's number of frames.
    pub fn blend_from(&self, id: u64, from: usize) -> Result<(Vec<u8>, usize), String> {
        let (frames, total) = match self.wait_for(id, from)? {
            BlendState::Ready(f) => {
                let n = f.len();
                (f, n)
            }
            BlendState::Making(f, total) => (f, total),
            _ => return Err(format!("blend {id} is not made")),
        };
        if from >= frames.len() {
            return Err(format!("blend {id} has {} frames: none from frame {from}", frames.len()));
        }
        Ok((self.code(&format!("blend {id} from {from}"), &frames[from..])?, total))
    }

    /// Starts the controller again from its start frame.
    pub fn restart(&self) -> Result<(), String> {
        let mut session = self.session.lock().unwrap_or_else(|e| e.into_inner());
        let (index, motion) = (session.controller.index().clone(), session.controller.motion().clone());
        let controller =
            Controller::with_index(&self.prep, index, motion, self.options.clone()).map_err(|e| e.to_string())?;
        let placement = controller.current().1;
        *session = Session { controller, placement, in_blend: 0, last_input: None, chosen: None };
        Ok(())
    }
}

//! An interactive controller on the essential graph: a captured character steered live by a
//! stream of inputs (a ground velocity and facing, or a target point, and an optional gait),
//! as games steer motion-captured characters with motion matching (Clavet, GDC 2016; Holden's
//! open Motion-Matching), here on 4D surface captures: the moves are the graph's edges, their
//! futures are predicted by the walk model, and transitions are played with Blend as offline
//! synthesis plays them (thesis 3.4, Algorithms 2-3).
//!
//! - [`frame_motion`]: heading, speed and gait of every captured frame.
//! - [`future_trajectory`]: the precomputed future-trajectory feature of every move (continue
//!   the clip, or a transition into a frame the walk can go on from: no move enters a dead
//!   end), grouped by source frame (the index; why not a k-d tree: that file's doc).
//! - [`desired_trajectory`]: the trajectory an input asks for over the next second.
//! - [`move_choice`]: one decision, the move whose predicted future best matches the asked one
//!   plus its realism cost.
//! - [`parametric_blend`]: a partner clip of the same kind mixed into the clip played at a
//!   continuous weight (Casas et al. 2012), for speeds and turn rates between the captured
//!   ones; a decision compares it with the graph's moves.
//! - [`transition_blend`]: Blend of one chosen transition, frame by frame in playing order,
//!   with the mesh's symbolic factorisation made once per subject (for a live player).
//! - [`display_blend`]: the stand-in a page draws at once for each of those frames (the two
//!   placed captured frames mixed linearly, eq. 2.23) until the exact frame arrives.
//! - [`live_controller`]: [`Controller::new`] (`&Prepared`, [`ControllerOptions`]) and
//!   [`Controller::step`] (`&Input`, `dt`) returning the frames to show and the decisions
//!   made ([`Step`]), deciding at least every 0.1 s, and saying when an input cannot be
//!   followed with the data (no run clip, no idle, no turn, too fast).
//! - [`live_session`]: a controller played live ([`live_session::LiveSession`]): steps under a
//!   player's input, each chosen transition blended on a worker thread as the frames are asked
//!   for, the answers as the JSON of `surfcap play`'s page.
//!
//! `surfcap-bench play` measures a decision's latency; `surfcap eval play` measures how well
//! scripted inputs are followed, against offline path following on the same trajectories.

pub mod captured_stream;
pub mod desired_trajectory;
pub mod display_blend;
pub mod frame_motion;
pub mod future_trajectory;
pub mod live_controller;
pub mod live_session;
pub mod move_choice;
pub mod parametric_blend;
pub mod transition_blend;

pub use frame_motion::{FrameMotion, Gait};
pub use future_trajectory::FutureTrajectories;
pub use live_controller::{BlendChoice, Controller, ControllerOptions, Decision, Goal, Input, ShownFrame, Step};
pub use move_choice::{MatchWeights, Move};
pub use parametric_blend::BlendPartners;

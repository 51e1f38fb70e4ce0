//! One decision of the controller: the move (continue the clip, or take a transition from one
//! of the frames about to be shown) whose predicted future trajectory best matches the asked
//! one, plus its realism cost (motion matching's search, Clavet 2016, over the essential
//! graph's moves instead of every frame).
//!
//! Cost of a move leaving frame `s`, `j` frames from now, with feature `F`
//! ([`super::future_trajectory`]) against the asked trajectory `D` expressed in the same
//! coordinates (relative to frame s's centre), summed over the horizons `h`:
//!
//! `w_p |F_pos(h) - D_pos(j + h)|^2 / height^2 + w_f |F_dir(h) - D_dir(j + h)|^2`
//!
//! (the facing term where both have a direction; where the asked trajectory has one and the
//! move's future stands, [`STANDING_FACING`]), plus `w_r` times the transition's
//! realism (its edge weight over the median transition's; 0 for continuing the clip), plus
//! `w_g` when the move's destination frame does not show an asked gait (or stands while the
//! input asks to move). The scan is linear over
//! the moves of the next frames (the index is the graph's adjacency; see
//! [`super::future_trajectory`]); ties go to the earlier candidate, so a decision is the same
//! whatever the thread count.

use serde::Serialize;

use super::frame_motion::{FrameMotion, Gait};
use super::future_trajectory::{FEATURE, FutureTrajectories, HORIZONS};

/// Weights of the terms of a move's cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MatchWeights {
    /// Squared position error, per squared subject height.
    pub position: f64,
    /// Squared difference of unit facing vectors (2 at opposite facings).
    pub facing: f64,
    /// Realism: transition edge weight over the median transition weight.
    pub realism: f64,
    /// A move into a frame that does not show the asked gait.
    pub gait: f64,
}

impl Default for MatchWeights {
    /// A quarter of the subject's height off at one horizon costs as much as facing 60 degrees
    /// off there (1); a median transition a third of that, so the clip is left only for a
    /// better future; the wrong gait as much as being a height off.
    fn default() -> Self {
        MatchWeights { position: 16.0, facing: 1.0, realism: 0.3, gait: 16.0 }
    }
}

/// A move the controller can make.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "move", rename_all = "lowercase")]
pub enum Move {
    /// Play the clip on as captured until the next decision.
    Continue,
    /// Play `after` frames of the clip, then the transition `from` -> `to` (global frames)
    /// of edge weight `weight` (its realism cost, thesis eq. 3.2).
    Transition { after: usize, from: u32, to: u32, weight: f64 },
}

/// The asked trajectory in the coordinates where the current frame is unmoved: one sample per
/// output frame from now (sample 0 now), positions on the ground plane and facings (`NaN`: none).
#[derive(Debug, Clone)]
pub struct LocalGoal {
    pub positions: Vec<[f64; 2]>,
    pub facing: Vec<f64>,
}

/// The decision: the move, its cost and how many moves were compared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    pub chosen: Move,
    pub cost: f64,
    pub candidates: usize,
}

/// The frames about to be shown, from which moves may leave: `ahead[j]` is shown `j` frames
/// from now (`ahead[0]` is the frame shown now), each with its ground centre.
pub struct Ahead<'a> {
    pub frames: &'a [u32],
    pub centres: &'a [[f64; 2]],
}

/// What the input asks of the destination frame's gait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GaitAsked {
    /// Nothing.
    Any,
    /// This gait.
    Exactly(Gait),
    /// Any gait but idle: the input asks to move (a standing frame would stall a walk that has
    /// to turn first: from a stand the data sets off only the way the body faces).
    Moving,
}

/// The best move from the frames `ahead` for the asked trajectory `goal` (which must hold
/// samples up to `ahead.len() - 1 +` the last horizon); `gait` what the input asks of the gait.
pub fn choose_move(
    index: &FutureTrajectories,
    motion: &FrameMotion,
    ahead: &Ahead<'_>,
    goal: &LocalGoal,
    gait: GaitAsked,
    w: &MatchWeights,
) -> Choice {
    let score = |j: usize, feature: &[f32], dest: u32| -> f64 {
        feature_cost(
            index,
            motion,
            ahead.centres[j],
            j,
            goal,
            feature,
            gait_mismatch(gait, motion.gait[dest as usize]),
            w,
        )
    };
    debug_assert_eq!(FEATURE, 4 * HORIZONS.len());
    let u = ahead.frames[0];
    let mut best = Choice { chosen: Move::Continue, cost: f64::INFINITY, candidates: 0 };
    if index.continues[u as usize] {
        best.cost = score(0, index.continuation(u), u);
        best.candidates = 1;
    }
    for (j, &s) in ahead.frames.iter().enumerate() {
        for k in index.leaving(s) {
            let realism = index.realism[k] as f64;
            let to = index.to[k];
            let cost = score(j, index.feature(k), to) + w.realism * realism;
            best.candidates += 1;
            if cost < best.cost {
                best.cost = cost;
                best.chosen = Move::Transition { after: j, from: s, to, weight: realism * index.median_weight };
            }
        }
    }
    best
}

/// The facing term of a future that stands (has no heading) where the asked trajectory has a
/// direction: the mean of `|u - d|^2` over every unit facing `u`, i.e. as if it faced 90
/// degrees off. Without it a future that stops pays no facing error while every walk that
/// does not yet face the asked way pays one, and a turn asked while walking was answered by
/// stopping (and, from a stand the data sets off only the way the body faces, staying).
pub const STANDING_FACING: f64 = 2.0;

/// Whether a destination showing `shown` misses what the input asks of the gait.
pub fn gait_mismatch(gait: GaitAsked, shown: Gait) -> bool {
    match gait {
        GaitAsked::Any => false,
        GaitAsked::Exactly(g) => shown != g,
        GaitAsked::Moving => shown == Gait::Idle,
    }
}

/// The matching cost of a predicted future `feature` (the layout of
/// [`super::future_trajectory`], relative to `origin`, the centre of the frame it leaves
/// `j` frames from now) against `goal`, plus the gait term when `wrong_gait` (the module
/// doc's cost without the realism term).
#[allow(clippy::too_many_arguments)]
pub fn feature_cost(
    index: &FutureTrajectories,
    motion: &FrameMotion,
    origin: [f64; 2],
    j: usize,
    goal: &LocalGoal,
    feature: &[f32],
    wrong_gait: bool,
    w: &MatchWeights,
) -> f64 {
    let inv_h2 = 1.0 / (motion.height * motion.height);
    let mut cost = 0.0;
    for (k, &h) in index.horizons.iter().enumerate() {
        let at = (j + h).min(goal.positions.len() - 1);
        let d = goal.positions[at];
        let f = &feature[4 * k..4 * k + 4];
        let (du, dv) = (f[0] as f64 - (d[0] - origin[0]), f[1] as f64 - (d[1] - origin[1]));
        cost += w.position * (du * du + dv * dv) * inv_h2;
        let df = goal.facing[at];
        if df.is_finite() {
            if f[2] != 0.0 || f[3] != 0.0 {
                let (a, b) = (f[2] as f64 - df.cos(), f[3] as f64 - df.sin());
                cost += w.facing * (a * a + b * b);
            } else {
                // Standing where a direction is asked: no better than any facing.
                cost += w.facing * STANDING_FACING;
            }
        }
    }
    if wrong_gait {
        cost += w.gait;
    }
    cost
}

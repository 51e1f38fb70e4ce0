//! Parametric blending: the controller plays a clip A with a partner clip B of the same kind
//! mixed in at a continuous weight `w`, to reach speeds and turn rates between theirs (the
//! parametric motion spaces of Casas, Tejera, Guillemaut and Hilton, "4D parametric motion
//! graphs for interactive animation", I3D 2012: temporally aligned sequences of one motion,
//! such as a walk and a jog, interpolated with a weight that maps to speed or direction;
//! thesis 6.7 writes the blend as `Y_w = (1 - w) Y_1 + w Y_2`).
//!
//! **Which pairs qualify.** Frame `a` of A and frame `b` of B (another sequence) are partners
//! when both travel (walk or run, [`super::frame_motion`]; a stand has no speed or direction to
//! interpolate), both can go on for ever (the dead-end analysis), the subject travels (its
//! transitions are re-placed by Algorithm 2; a subject kept where it was captured has no
//! track to blend), and `b` is B's frame nearest to `a` in pose distance (the distance matrix
//! the graph was built from), with that distance at most [`PARTNER_SPREAD`] times the median
//! of every travelling frame's nearest such distance. At most [`PARTNERS`] partner clips are
//! kept per frame, the nearest. A walk and a jog, or a straight walk and a turning walk, pair
//! up; a walk and a stand do not.
//!
//! **Phase alignment.** The nearest pose is the same phase of the gait cycle (the feet where
//! they are). While a blend plays, each output frame advances A by one frame as captured and
//! B by 0, 1 or 2 frames, whichever lands nearest in pose to A's new frame: an online dynamic
//! time warping of B onto A on the same frame distances, with the step sizes of the thesis's
//! slope constraint (2.5.2, eq. 2.53-2.54). B is thus played at A's cadence, so that its feet
//! stay in phase with A's; a B that would reach a frame the walk cannot go on from ends the
//! blend. (Casas et al. align each motion space once, offline; the online warp needs no
//! cycle annotation and serves clips that do not loop.)
//!
//! **The blended centre track** is Algorithm 2's rigid part (thesis 3.4.1,
//! `surfcap_motion::blend::blend_placements_from`, from which the walk model predicts every
//! transition's track) with the weight `lambda` free to change from one output frame to the
//! next: at each frame B's moved frame is rotated onto A's by `(1 - lambda) theta` and A's
//! by `-lambda theta` (theta: eq. 2.3's angle between the two moved frames), both are moved so
//! their centres meet at P, and P advances by the lambda-weighted mix of the two clips' own
//! steps (B's step being its motion between the frames the warp plays). At a constant weight
//! on a one-to-one warp this is `blend_placements_from` with `Lambda::Constant`, to rounding
//! (tested). **Poses** are the non-linear interpolation of the two moved frames (thesis eq.
//! 2.45-2.49), as Blend interpolates.
//!
//! The weight follows the controller's target at most [`WEIGHT_PER_SECOND`] per second, so
//! a change of weight is a short cross-fade, not a jump.

use surfcap_geometry::motion_plane_alignment::{PlaneMotion, motion_plane_alignment, plane_axes};
use surfcap_mesh::Subject;
use surfcap_motion::walk_sequence::{Step as EdgeStep, WalkModel};

use super::frame_motion::{FrameMotion, Gait};
use super::future_trajectory::FutureTrajectories;

/// Partner clips kept per frame, the nearest in pose.
pub const PARTNERS: usize = 3;
/// A partner's pose distance may be up to this many times the median nearest partner distance.
pub const PARTNER_SPREAD: f64 = 1.5;
/// The blend weight changes by at most this much per second (a full change in a quarter
/// of a second).
pub const WEIGHT_PER_SECOND: f64 = 4.0;

/// The partner frames of every frame (rows by frame, as the moves are stored).
#[derive(Debug, Clone, Default)]
pub struct BlendPartners {
    offsets: Vec<usize>,
    /// Partner frame (global).
    pub partner: Vec<u32>,
    /// Its pose distance over the median nearest partner distance (the realism unit of a
    /// blend: changing the weight fully costs this many times the realism weight).
    pub distance: Vec<f32>,
    /// The median nearest partner distance (the unit of `distance`).
    pub median: f64,
    /// Why no frame has a partner, when none has.
    pub none_because: Option<String>,
}

impl BlendPartners {
    /// The partners of every frame of `s` (see the module doc); `d` the distance matrix
    /// (row-major over global frames) the graph was built from.
    pub fn new(
        s: &Subject,
        model: &WalkModel,
        motion: &FrameMotion,
        index: &FutureTrajectories,
        d: &[f64],
    ) -> BlendPartners {
        let n = model.centres.len();
        let none =
            |why: String| BlendPartners { offsets: vec![0; n + 1], none_because: Some(why), ..Default::default() };
        if model.placement() != surfcap_motion::subject_placement::Placement::Aligned {
            return none(format!(
                "{} does not travel (its transitions keep the frames where they were captured), so a blend has no track",
                s.name
            ));
        }
        let fi = s.frame_index();
        let usable = |f: usize| index.live[f] && index.continues[f] && motion.gait[f] != Gait::Idle;
        // Per frame: the nearest usable frame of every other sequence.
        let rows: Vec<Vec<(f64, u32)>> = (0..n)
            .map(|a| {
                if !usable(a) {
                    return Vec::new();
                }
                let qa = fi.locate(a).map(|x| x.0);
                let mut best: Vec<(f64, u32)> = (0..fi.n_sequences())
                    .filter(|&q| Some(q) != qa)
                    .filter_map(|q| {
                        fi.range(q)
                            .filter(|&b| usable(b))
                            .map(|b| (d[a * n + b], b as u32))
                            .filter(|x| x.0.is_finite())
                            .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                    })
                    .collect();
                best.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
                best.truncate(PARTNERS);
                best
            })
            .collect();
        let mut nearest: Vec<f64> = rows.iter().filter_map(|r| r.first().map(|x| x.0)).collect();
        if nearest.is_empty() {
            return none(format!(
                "{} has no two travelling clips that can go on (a walk and a jog, or a straight and a turning walk)",
                s.name
            ));
        }
        nearest.sort_by(f64::total_cmp);
        let median = nearest[nearest.len() / 2].max(f64::MIN_POSITIVE);
        let mut out = BlendPartners { offsets: vec![0], median, ..Default::default() };
        for r in rows {
            for (dist, b) in r {
                if dist <= PARTNER_SPREAD * median {
                    out.partner.push(b);
                    out.distance.push((dist / median) as f32);
                }
            }
            out.offsets.push(out.partner.len());
        }
        out
    }

    /// The rows of frame `a`'s partners.
    pub fn of(&self, a: u32) -> std::ops::Range<usize> {
        self.offsets[a as usize]..self.offsets[a as usize + 1]
    }

    /// Frames with at least one partner.
    pub fn frames_with_partners(&self) -> usize {
        self.offsets.windows(2).filter(|w| w[1] > w[0]).count()
    }

    /// The clip pairs that qualify: (sequence of A, sequence of B, frames of A with a partner
    /// in B), sorted by sequence.
    pub fn pairs(&self, s: &Subject) -> Vec<(String, String, usize)> {
        let fi = s.frame_index();
        let names = |f: u32| fi.locate(f as usize).map_or(0, |x| x.0);
        let mut counts = std::collections::BTreeMap::<(usize, usize), usize>::new();
        for a in 0..self.offsets.len().saturating_sub(1) {
            for k in self.of(a as u32) {
                *counts.entry((names(a as u32), names(self.partner[k]))).or_default() += 1;
            }
        }
        let seq = s.sequences();
        counts.into_iter().map(|((qa, qb), c)| (seq[qa].name.clone(), seq[qb].name.clone(), c)).collect()
    }
}

/// The state of a blend after an output frame: A's and B's frames shown, the weight, the two
/// segments' placements (in the coordinates of A's frame where the blend began) and P.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendState {
    pub a: u32,
    pub b: u32,
    pub lambda: f64,
    pub gs: PlaneMotion,
    pub gd: PlaneMotion,
    /// The blended centre (P of Algorithm 2; vertically the lambda-mix of the two centres).
    pub p: [f64; 3],
}

/// What a blend needs of the subject: the walk model (centres, steps), the distance matrix
/// (the warp) and eq. 2.3's angle between two captured frames.
pub struct BlendContext<'a> {
    pub model: &'a WalkModel,
    pub index: &'a FutureTrajectories,
    pub d: &'a [f64],
    pub angle: &'a dyn Fn(u32, u32) -> f64,
}

/// The frame after `f` as captured and the placement change of that step (a looping clip's
/// wrap moves it), when the walk can go on from it.
fn next_frame(cx: &BlendContext<'_>, f: u32) -> Option<(u32, Option<PlaneMotion>)> {
    let (v, step) = cx.model.next(f)?;
    if !cx.index.live[v as usize] {
        return None;
    }
    Some((
        v,
        match step {
            EdgeStep::Wrap(w) => Some(*w),
            _ => None,
        },
    ))
}

impl BlendState {
    /// A blend beginning at A's frame `a` (shown, weight `lambda`) with partner frame `b`,
    /// in the coordinates where `a` is unmoved.
    pub fn begin(cx: &BlendContext<'_>, a: u32, b: u32, lambda: f64) -> BlendState {
        let up = cx.model.up;
        let id = PlaneMotion::identity(up);
        let mut s = BlendState { a, b, lambda, gs: id, gd: id, p: cx.model.centres[a as usize] };
        s.align(cx, lambda);
        s
    }

    /// Algorithm 2's per-frame move: the two frames turned towards each other by the weight
    /// and their centres brought to P.
    fn align(&mut self, cx: &BlendContext<'_>, lambda: f64) {
        let up = cx.model.up;
        let (iu, iv, iw) = plane_axes(up);
        let (cs, cd) = (cx.model.centres[self.a as usize], cx.model.centres[self.b as usize]);
        let theta = surfcap_motion::blend::wrap_angle((cx.angle)(self.a, self.b) + self.gs.theta - self.gd.theta);
        let (cn, cm) = (self.gs.apply_point(cs), self.gd.apply_point(cd));
        let p = self.p;
        self.gs = PlaneMotion::about(-lambda * theta, cn, [p[iu] - cn[iu], p[iv] - cn[iv]], up).after(&self.gs);
        self.gd = PlaneMotion::about((1.0 - lambda) * theta, cm, [p[iu] - cm[iu], p[iv] - cm[iv]], up).after(&self.gd);
        self.lambda = lambda;
        self.p[iw] = (1.0 - lambda) * self.gs.apply_point(cs)[iw] + lambda * self.gd.apply_point(cd)[iw];
    }

    /// The partner frame B plays next: 0, 1 or 2 frames on from `self.b`, nearest in pose to
    /// A's next frame `a2` (ties to one frame on), with the placement change of the frames
    /// stepped over; `None` when B cannot go on.
    fn next_partner(&self, cx: &BlendContext<'_>, a2: u32) -> Option<(u32, PlaneMotion)> {
        let n = cx.model.centres.len();
        let id = PlaneMotion::identity(cx.model.up);
        let (b1, w1) = next_frame(cx, self.b)?;
        let g1 = w1.unwrap_or(id);
        let mut best = (cx.d[a2 as usize * n + b1 as usize], b1, g1);
        let hold = cx.d[a2 as usize * n + self.b as usize];
        if let Some((b2, w2)) = next_frame(cx, b1).filter(|x| cx.index.continues[x.0 as usize]) {
            let c = cx.d[a2 as usize * n + b2 as usize];
            if c < best.0 {
                best = (c, b2, w2.map_or(g1, |w| g1.after(&w)));
            }
        }
        if hold < best.0 && cx.index.continues[self.b as usize] {
            best = (hold, self.b, id);
        }
        cx.index.continues[best.1 as usize].then_some((best.1, best.2))
    }

    /// The next output frame at weight `lambda` (the step to it is taken at the current
    /// weight, as Algorithm 2 advances P); `None` when A or B cannot go on.
    pub fn advance(&self, cx: &BlendContext<'_>, lambda: f64) -> Option<BlendState> {
        let (iu, iv, _) = plane_axes(cx.model.up);
        let (a2, wa) = next_frame(cx, self.a)?;
        let (b2, wb) = self.next_partner(cx, a2)?;
        let c = &cx.model.centres;
        let gs2 = wa.map_or(self.gs, |w| self.gs.after(&w));
        let gd2 = self.gd.after(&wb);
        let step = |g: &PlaneMotion, g2: &PlaneMotion, f: u32, f2: u32| {
            let (x, y) = (g.apply_point(c[f as usize]), g2.apply_point(c[f2 as usize]));
            [y[iu] - x[iu], y[iv] - x[iv]]
        };
        let (sa, sb) = (step(&self.gs, &gs2, self.a, a2), step(&self.gd, &gd2, self.b, b2));
        let mut next = BlendState { a: a2, b: b2, lambda: self.lambda, gs: gs2, gd: gd2, p: self.p };
        next.p[iu] += (1.0 - self.lambda) * sa[0] + self.lambda * sb[0];
        next.p[iv] += (1.0 - self.lambda) * sa[1] + self.lambda * sb[1];
        next.align(cx, lambda);
        Some(next)
    }

    /// The blended body's facing (radians, in the blend's coordinates): the two moved frames'
    /// headings mixed by the weight the shorter way round (`NaN` when neither has one).
    pub fn facing(&self, motion: &FrameMotion) -> f64 {
        let ha = motion.heading[self.a as usize] - self.gs.theta;
        let hb = motion.heading[self.b as usize] - self.gd.theta;
        match (ha.is_finite(), hb.is_finite()) {
            (true, true) => ha + self.lambda * surfcap_motion::blend::wrap_angle(hb - ha),
            (true, false) => ha,
            (false, true) => hb,
            _ => f64::NAN,
        }
    }

    /// The blended ground speed (subject units per second): the weight's mix of the two
    /// frames' speeds.
    pub fn speed(&self, motion: &FrameMotion) -> f64 {
        (1.0 - self.lambda) * motion.speed[self.a as usize] + self.lambda * motion.speed[self.b as usize]
    }
}

/// The weight one frame later, going from `from` towards `target` at [`WEIGHT_PER_SECOND`].
pub fn weight_towards(from: f64, target: f64, fps: f64) -> f64 {
    let most = WEIGHT_PER_SECOND / fps;
    let w = from + (target - from).clamp(-most, most);
    // Land exactly on the ends so that a blend ramped out is the clip again.
    if (w - target).abs() < 1e-9 { target } else { w }
}

/// Eq. 2.3's angle aligning captured frame `b` onto captured frame `a` of `s`.
pub fn frame_angle(s: &Subject, a: u32, b: u32) -> f64 {
    match (s.frame(a as usize), s.frame(b as usize)) {
        (Some(pa), Some(pb)) => motion_plane_alignment(pa, pb, None, s.up_axis).0.theta,
        _ => 0.0,
    }
}

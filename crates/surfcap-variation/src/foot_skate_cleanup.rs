//! Foot-skate clean-up of varied motions, after Kovar, Schreiner and Gleicher 2002 ("Footskate
//! cleanup for motion capture editing", SCA 2002), on meshes instead of skeletons.
//!
//! Varied leg poses placed on a path made for the captured ones let the planted feet drift
//! (`surfcap eval vary`: 6-10x the captures' foot sliding on CMU clips). Kovar et al. (sec. 3-5)
//! pin each footplant at one place, move the root and solve the legs' IK to reach the pins, and
//! blend the adjustments in and out over the frames around each plant. Here the root is moved
//! along the ground and the legs are deformed in the gradient domain instead of by IK:
//!
//! 1. **Plants** (Kovar sec. 3, "footplant constraints"): the planted vertices of every frame
//!    step come from the shared contact detector (surfcap-geometry's `ground_contacts` and
//!    `planted_contacts`, the group root motion and the foot-sliding measure keep still). A
//!    planted vertex belongs to the foot of the leg part holding it; the steps where a foot has
//!    planted vertices, runs closer than [`FootSkateParams::gap_steps`] merged when the foot
//!    came back down where it left ([`FootSkateParams::rejoin_distance`]), are its plants:
//!    by default every step the detector plants, as the measure counts them (with
//!    [`FootSkateParams::lift_speed`] set, steps at a plant's ends moving faster are taken
//!    for the foot lifting off or landing and left out).
//!    A plant covers frames `a..=b` (its first step's first frame to its last step's second).
//! 2. **Pins** (Kovar sec. 4: one position per constraint): every vertex planted at frame f of
//!    a plant is pinned, along the ground, where it is at the plant's middle frame
//!    `m = (a + b) / 2`: `y_v = p_v(m)`. The foot is moved rigidly along the ground to meet its
//!    pins: the weighted 2D Procrustes fit (translation, and with [`FootSkateParams::fit_turn`]
//!    the rotation about the up axis; weights the contact weights) of `p_v(f) -> y_v` over the
//!    planted vertices of frame f, about their weighted centroid `c_f`:
//!    `T_f(x) = c_f + R(theta_f) (x - c_f) + t_f`. A rigid foot keeps
//!    its shape: only the leg above it bends. Frames of a plant without a planted vertex take
//!    the fit interpolated between their neighbours.
//! 3. **Blending** (Kovar sec. 5: adjustments blended over adjacent frames): before a plant's
//!    first frame and after its last, over [`FootSkateParams::blend_seconds`], the correction is
//!    faded with a smoothstep, `(alpha theta, alpha t)`; between two plants of one foot closer
//!    than twice that, it is interpolated from one plant's end to the next one's start. The
//!    correction is therefore continuous at every plant boundary: nothing pops.
//! 4. **Legs in the gradient domain** (thesis eq. 2.48 with positional constraints): the
//!    displacement `d` of the frame's vertices minimises `sum_m area_m |G_m d|^2` (the change of
//!    every triangle's gradient, G and the areas of the rest pose, so one factorisation serves
//!    every frame), i.e. `L d = 0` on the free vertices, with hard constraints: `d = T_f(x) - x`
//!    on the feet (every leg vertex within [`FootSkateParams::foot_height`] x the subject's
//!    height of the leg's lowest rest vertex), `d = 0` everywhere outside the legs and on the
//!    top [`FootSkateParams::hip_fraction`] of each leg (the hip: legs that are separate meshes,
//!    as KayKit's, stay attached). Only the two ground coordinates are solved: the correction
//!    is along the ground, heights are kept. The free block `L_II` (leg vertices between foot and
//!    hip) is factorised once per subject ([`FootSkateCleanup::new`]); each frame is one sparse
//!    solve with two right-hand sides, `L_II d_I = -L_IC d_C`, frames in parallel.
//!    **4b. Every planted vertex pinned** (with [`FootSkateParams::vertex_pins`], on by
//!    default): a rigid foot cannot follow a planted sole that rolls, turns or changes shape
//!    under it, and what it leaves is what the sliding measure counts (on the KayKit walks'
//!    variants most of the sliding left after the rigid move: `surfcap eval vary`,
//!    docs/results/variation.md). So each planted vertex of a plant's frame is then moved the
//!    rest of the way to its pin, `e_v = y_v - T_f(p_v(f)) - r_f` (at most
//!    [`FootSkateParams::pin_reach`] x the subject's height; a vertex further off is let
//!    go of, not dragged through the foot), faded out around the plant as the correction is;
//!    the other movable leg vertices (feet and free ones) follow in the gradient domain, the
//!    hips and the body held: `L_FF e_F = -L_FP e_P`, factorised per frame since the pinned
//!    set changes from frame to frame.
//! 5. **The root** (Kovar sec. 4, with [`FootSkateParams::move_root`], on by default): the
//!    whole mesh is moved along the ground by `r_f`, on every frame where a foot is planted the
//!    planted feet's mean pull (a foot's pull: its vertices' mean displacement by `T_f`),
//!    bridged and faded between plants as the corrections are (step 3). The feet's constraints
//!    in step 4 become what is left, `T_f(x) - x - r_f` on their plants, faded the same way:
//!    a foot alone on the ground is reached by moving the body, without bending its leg; two
//!    planted feet bend their legs only by how far their pulls differ; a foot in the air moves
//!    with the body.
//!    **5b. Pins carried by the root** (with [`FootSkateParams::carry_pins`] and the root
//!    moved; off by default, see the field): pinned where each foot is at its plant's middle frame in the
//!    motion as given, two plants in double support are a stride plus what the feet slid
//!    between the two middles apart, and the legs stretch to span it (`surfcap eval vary`'s
//!    world-frame edge distortion on CMU walks); a foot leaving a plant is also pulled far
//!    back to its pin. So each plant `P` is pinned where its foot comes down with the body
//!    moved so far, `y_v + s_P` with `s_P = r_a - pull(a)` at its first frame `a`, and the
//!    body then moves on with the planted feet frame by frame: `r_{f+1} = r_f + mean_k
//!    (pull_k(f+1) - pull_k(f) + e_k(f) / (blend + 1))` over the feet planted at both frames,
//!    `e_k = pull_k + s_P - r` what foot k's leg still has to reach (drained into the body, so
//!    a leg bent in double support straightens after it); held where no foot stays planted.
//!    A variant whose stride differs from its path's travel then covers its own stride's
//!    distance: the body drifts from the path it was placed on (the report's
//!    `largest_body_shift`) while the legs keep their lengths (`largest_leg_correction`).
//! 6. **Turned, not slanted, legs** (with [`FootSkateParams::keep_edges`]): step 4's
//!    displacement is along the ground only, so a foot pulled by `delta` under a held hip
//!    slants its leg: a shear of about `delta / L` over the leg's length `L`, which stretches
//!    the leg's diagonal edges by half that to first order. A leg turned about its hip moves
//!    as much along the ground and also up or down across its width. That height part is
//!    solved in the gradient domain as well (thesis eq. 2.48 with a target gradient): `h`
//!    minimises `sum_m area_m |G_m h - t_m|^2` with `t_m` the height gradient that makes the
//!    triangle's change of gradient antisymmetric in its up-and-ground parts (an
//!    infinitesimal rotation), `t_m = -(d d_u / d x_up, d d_w / d x_up)` along the ground
//!    axes, and `h = 0` on the feet, the hips and the body: `L_II h_I = (G^T D t)_I`, one
//!    more solve with the same factorisation. The feet keep their heights (their contacts
//!    stay where they were).
//! 7. **Passes**: pinning changes which contacts move together, so the planted groups the
//!    shared detector finds on the output partly differ from those pinned; the clean-up
//!    detects and pins again on its own output, [`FootSkateParams::passes`] times in all.
//!
//! 8. **Legs bent, not stretched** ([`FootSkateParams::stretch_iterations`]): step 4's solve
//!    keeps every leg triangle's gradient, so a leg whose foot is pulled further than it
//!    reaches is sheared and stretched (two feet pinned a stride and a slide apart in double
//!    support). A few as-rigid-as-possible local/global iterations (Sorkine and Alexa 2007)
//!    follow on the free leg vertices (and on a planted foot's vertices that are not pinned),
//!    the pinned vertices, the other feet, the hips and the body held: each triangle's target
//!    is its rotation now times its stretch before the clean-up, one solve per iteration. A
//!    leg then straightens or bends at the knee where it can instead of stretching.
//!
//! **In-place clips** (authored with the root pinned, e.g. the KayKit clips): there the ground
//! moves under the character and a planted foot slides backwards at the walking speed. Pinning
//! it in place would stop the walk; the clean-up instead works on the frames moved by the
//! ground's travel (`ground`, per frame, e.g. the root motion the source's own contacts give)
//! and takes it away again afterwards: the feet are pinned to the moving ground.
//!
//! Deterministic: every frame's solve is independent and the fits are sums in a fixed order, so
//! the result does not depend on the thread count.

use faer::Mat;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Matrix3;
use rayon::prelude::*;
use serde::Serialize;
use surfcap_geometry::deformation_gradient::triangle_polar_factors;
use surfcap_geometry::foot_sliding::foot_sliding;
use surfcap_geometry::gradient_operator::GradientOperator;
use surfcap_geometry::ground_contacts::{ContactParams, GroundContact, ground_contacts};
use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_geometry::root_motion_from_contacts::planted_contacts;
use surfcap_linalg::{NumericLlt, SymbolicLlt};
use surfcap_mesh::{Topology, UpAxis};

use crate::error::{Error, Result};

/// Settings of the clean-up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FootSkateParams {
    /// A foot is the leg's vertices within this fraction of the subject's height above the
    /// leg's lowest vertex in the rest pose (0.06: 10 cm for a 1.75 m person, sole to ankle).
    pub foot_height: f64,
    /// The top fraction of each leg's rest height range that stays put (the hip).
    pub hip_fraction: f64,
    /// The correction fades in before and out after each plant over this long (0.15 s: 5 frames
    /// at 30 fps, 4 at 25).
    pub blend_seconds: f64,
    /// Runs of planted steps of one foot this many steps apart or less are one plant.
    pub gap_steps: usize,
    /// Runs closer than `gap_steps` join only when the foot's vertex mean moved at most this
    /// fraction of the subject's height between them (0.05: 9 cm for a 1.75 m person; a
    /// step's stride is several times that).
    pub rejoin_distance: f64,
    /// When set, steps at the ends of a plant whose planted vertices move faster than this
    /// many subject heights per second are taken for the foot lifting off or landing and are
    /// not pinned. Unset (the default), a plant is every step the shared contact detector
    /// plants, the steps the foot-sliding measure counts: trimmed at 1.0 heights per second,
    /// such ends stayed planted for the measure and kept 1-2 m/s of sliding on the KayKit
    /// runs' variants (`surfcap eval vary`, docs/results/variation.md).
    pub lift_speed: Option<f64>,
    /// Detections and clean-ups in turn: each pass detects the plants of the previous one's
    /// output with the shared detector and pins them (pinning changes which contacts move
    /// together, so the measure's planted groups after a pass partly differ from the ones
    /// pinned). At least 1; 3 by default: with the legs bent as rigidly as possible (step 8)
    /// two passes left up to 0.2 m/s of sliding on KayKit variants, three pinned it
    /// (`surfcap eval vary`, docs/results/variation.md).
    pub passes: usize,
    /// Fit the foot's turn about the up axis as well as its translation (off by default: on
    /// a CMU walk's variants the turn fitted to a small planted patch moved a foot by up to
    /// 0.68 m, while the translation alone pins the planted vertices within 3 mm on average).
    pub fit_turn: bool,
    /// Move the whole body along the ground with the planted feet (Kovar sec. 4's root
    /// adjustment; the module doc's step 5), so that one planted foot is reached without
    /// bending its leg and two only bend for how far their pulls differ. On by default: on the
    /// KayKit walks and runs it lowers the delivered frames' edge distortion on every clip
    /// (`surfcap eval vary`). Off, the hips stay where they are and the legs alone reach the
    /// pins (the command line's `--hold-hips`).
    pub move_root: bool,
    /// Turn the legs instead of shearing them (the module doc's step 6): the height
    /// displacement whose gradient makes every leg triangle's change of gradient a rotation
    /// to first order, so a foot pulled along the ground swings its leg about the hip
    /// rather than slanting it (slanting stretches the leg's diagonal edges by about the
    /// pull over the leg's length). Off by default: it lowers a bent leg's strain by a third
    /// in the unit test, but with the root moved (the default) a leg bends only in double
    /// support, and its effect on `surfcap eval vary` is not measured.
    pub keep_edges: bool,
    /// Pin every planted vertex at its own place (the module doc's step 4b) after the foot's
    /// rigid move: what the rigid fit leaves (a planted sole that rolls, turns or changes
    /// shape under it) is taken away vertex by vertex, the rest of the leg following in the
    /// gradient domain. On by default: on the KayKit walks and runs most of the sliding left
    /// after the rigid fit was not a motion of the foot as a whole but of its planted
    /// vertices against each other (`surfcap eval vary`, docs/results/variation.md). Off, the
    /// foot is only moved rigidly.
    pub vertex_pins: bool,
    /// With [`FootSkateParams::move_root`]: pin each plant where its foot comes down, as the
    /// body has been moved so far, and move the body on with the planted feet step by step
    /// (the module doc's step 5b), instead of pinning every plant where the foot is at its
    /// middle frame in the motion as given. A variant whose stride differs from its path's
    /// travel then covers its own stride's distance instead of stretching its legs between two
    /// pins a stride and a slide apart, and a swinging foot is never dragged back to a pin
    /// (`surfcap eval vary`, docs/results/variation.md). Off by default: the body then drifts
    /// from the path it was placed on, by 2.6 m over a 4.5 m CMU walk, where thesis 6.8's
    /// variants follow their source's path (its sampled displacements drift 0.2-1.1 m).
    pub carry_pins: bool,
    /// The farthest a planted vertex is moved to its own pin beyond the foot's rigid move, as
    /// a fraction of the subject's height (step 4b).
    pub pin_reach: f64,
    /// Local/global iterations that bend rather than stretch the legs (the module doc's step
    /// 8, Sorkine and Alexa 2007's as-rigid-as-possible energy with each triangle's stretch
    /// before the clean-up as its rest state); 0 turns them off. 3 by default: pinned where
    /// each foot is at its plant's middle frame, two planted feet can be a stride and a slide
    /// apart, and step 4's solve spans that by shearing the legs (`surfcap eval vary`: the
    /// delivered frames' edge distortion 4-33% above the sampled poses', docs/results/
    /// variation.md).
    pub stretch_iterations: usize,
    /// The shared contact detection's thresholds.
    #[serde(skip)]
    pub contact: ContactParams,
}

impl Default for FootSkateParams {
    fn default() -> Self {
        FootSkateParams {
            foot_height: 0.06,
            hip_fraction: 0.1,
            blend_seconds: 0.15,
            gap_steps: 2,
            rejoin_distance: 0.05,
            lift_speed: None,
            passes: 3,
            fit_turn: false,
            move_root: true,
            keep_edges: false,
            vertex_pins: true,
            carry_pins: false,
            pin_reach: 0.02,
            stretch_iterations: 3,
            contact: ContactParams::default(),
        }
    }
}

/// What a clean-up did to one motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CleanupReport {
    /// Plants found (over all feet).
    pub plants: usize,
    /// Foot sliding (surfcap-geometry's `foot_sliding`, subject units per second, on the
    /// moving ground when one was given) before and after the clean-up.
    pub sliding_before: f64,
    pub sliding_after: f64,
    /// Contact-weighted mean distance along the ground of the planted vertices from their
    /// position at their plant's middle frame, over every planted vertex and frame: before the
    /// clean-up (how far the pins had to pull) and after (what is left: the pins' actual drift).
    pub pinned_drift_before: f64,
    pub pinned_drift_after: f64,
    /// The largest such distance after the clean-up.
    pub pinned_drift_after_max: f64,
    /// The largest displacement of a vertex by the clean-up.
    pub largest_correction: f64,
    /// The largest shift of the whole body along the ground (the root's, step 5; 0 with the
    /// hips held).
    pub largest_body_shift: f64,
    /// The largest displacement of a vertex against the body's shift of its frame: how far
    /// the clean-up bent a leg or moved a foot, the swinging ones included.
    pub largest_leg_correction: f64,
}

/// The factorised leg deformation of one subject (see the module doc).
pub struct FootSkateCleanup {
    up: UpAxis,
    n_vertices: usize,
    /// The subject's height (extent of the rest pose along the up axis).
    height: f64,
    params: FootSkateParams,
    /// Per vertex, the leg (index into the feet sets given) it belongs to, if any.
    leg_of: Vec<Option<u32>>,
    /// Per leg, its foot vertices (moved rigidly).
    feet: Vec<Vec<u32>>,
    /// Per vertex, its index among the free unknowns.
    free: Vec<Option<usize>>,
    n_free: usize,
    /// L_IC restricted to foot columns: (free row, foot vertex, value).
    coupling: Vec<(usize, u32, f64)>,
    symbolic: Option<SymbolicLlt>,
    numeric: Option<NumericLlt>,
    /// The rest pose's hat-function gradients and areas of the triangles with a free vertex
    /// (for [`FootSkateParams::keep_edges`]): (vertices, gradients, area).
    leg_triangles: Vec<([u32; 3], [[f64; 3]; 3], f64)>,
    /// The Laplacian among the legs' movable vertices (feet and free), duplicates merged:
    /// (row, column, value), for the per-vertex pins' solve (module doc, step 4b).
    movable_laplacian: Vec<(u32, u32, f64)>,
    /// The rest pose, and the rest gradient of the coordinates on each of `leg_triangles`
    /// (step 8).
    rest: Vec<f32>,
    leg_rest_gradients: Vec<Matrix3<f64>>,
}

impl std::fmt::Debug for FootSkateCleanup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FootSkateCleanup")
            .field("n_vertices", &self.n_vertices)
            .field("feet", &self.feet.iter().map(Vec::len).collect::<Vec<_>>())
            .field("free", &self.n_free)
            .finish()
    }
}

/// Factorises the `count` x `count` sub-Laplacian whose lower triangle is `lower`, with a
/// diagonal shift of 1e-9 of its mean diagonal (a free piece touching no constraint, such as a
/// loose fragment of a leg, then stays put); `None` when it cannot be factorised.
fn factorise_shifted(mut lower: Vec<Triplet<usize, usize, f64>>, count: usize) -> Option<(SymbolicLlt, NumericLlt)> {
    let d: f64 = lower.iter().filter(|t| t.row == t.col).map(|t| t.val).sum::<f64>() / count.max(1) as f64;
    lower.extend((0..count).map(|k| Triplet::new(k, k, 1e-9 * d.max(f64::MIN_POSITIVE))));
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(count, count, &lower).ok()?;
    let symbolic = SymbolicLlt::new(mat.symbolic()).ok()?;
    let numeric = symbolic.factorize(mat.as_ref()).ok()?;
    Some((symbolic, numeric))
}

fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A rigid correction along the ground: rotation `theta` about `centre`, then translation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Correction {
    theta: f64,
    t: [f64; 2],
    /// The rotation centre, relative to the foot's vertex mean of the frame.
    r: [f64; 2],
}

impl Correction {
    /// The mean displacement of the points it moves, `t - (R - I) r` (the points' mean lies
    /// at `-r` from the rotation centre).
    fn mean_shift(self) -> [f64; 2] {
        let (s, c) = self.theta.sin_cos();
        let (x, y) = (-self.r[0], -self.r[1]);
        [self.t[0] + (c * x - s * y - x), self.t[1] + (s * x + c * y - y)]
    }
    fn scaled(self, a: f64) -> Correction {
        Correction { theta: a * self.theta, t: [a * self.t[0], a * self.t[1]], r: self.r }
    }
    fn lerp(a: Correction, b: Correction, s: f64) -> Correction {
        let l = |x: f64, y: f64| (1.0 - s) * x + s * y;
        Correction {
            theta: l(a.theta, b.theta),
            t: [l(a.t[0], b.t[0]), l(a.t[1], b.t[1])],
            r: [l(a.r[0], b.r[0]), l(a.r[1], b.r[1])],
        }
    }
}

impl FootSkateCleanup {
    /// Factorises the leg deformation of `topology` in its rest pose `rest` (`[n][3]`); `legs`
    /// are the legs' vertex sets (e.g. the body parts named `leg*`), disjoint or not (a vertex
    /// is given to the first leg holding it).
    pub fn new(
        topology: &Topology,
        rest: &[f32],
        up: UpAxis,
        legs: &[Vec<u32>],
        params: FootSkateParams,
    ) -> Result<Self> {
        let n = topology.n_vertices();
        if params.passes == 0 {
            return Err(Error::Invalid("0 clean-up passes: expected at least 1".into()));
        }
        if let Some(l) = params.lift_speed.filter(|l| l.is_nan() || *l <= 0.0) {
            return Err(Error::Invalid(format!("a lift-off speed of {l} heights per second: expected more than 0")));
        }
        if rest.len() != 3 * n {
            return Err(Error::Invalid(format!(
                "a rest pose of {} coordinates: expected 3 x {n} vertices",
                rest.len()
            )));
        }
        let (axis, sign) = up.axis_and_sign();
        let h = |v: usize| sign * rest[3 * v + axis] as f64;
        let (lo, hi) = (0..n).map(h).fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
        let height = (hi - lo).max(0.0);
        let mut leg_of = vec![None; n];
        for (k, leg) in legs.iter().enumerate() {
            for &v in leg {
                let slot = leg_of.get_mut(v as usize).ok_or_else(|| {
                    Error::Invalid(format!("leg {k}: vertex {v} is not a vertex of the mesh (expected 0 to {})", n - 1))
                })?;
                slot.get_or_insert(k as u32);
            }
        }
        // Foot, hip and free vertices of every leg.
        let mut feet = vec![Vec::new(); legs.len()];
        let mut free = vec![None; n];
        let mut n_free = 0;
        for (k, foot) in feet.iter_mut().enumerate() {
            let members: Vec<usize> = (0..n).filter(|&v| leg_of[v] == Some(k as u32)).collect();
            let (llo, lhi) = members.iter().map(|&v| h(v)).fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
            let foot_top = llo + params.foot_height * height;
            let hip = lhi - params.hip_fraction * (lhi - llo);
            for v in members {
                if h(v) <= foot_top {
                    foot.push(v as u32);
                } else if h(v) < hip {
                    free[v] = Some(n_free);
                    n_free += 1;
                }
            }
        }
        let op = GradientOperator::new(topology, rest);
        let is_foot = {
            let mut m = vec![false; n];
            for f in &feet {
                for &v in f {
                    m[v as usize] = true;
                }
            }
            m
        };
        let mut lower = Vec::new();
        let mut coupling = Vec::new();
        for t in op.laplacian_triplets() {
            let Some(i) = free[t.row] else { continue };
            match free[t.col] {
                Some(j) if i >= j => lower.push(Triplet::new(i, j, t.val)),
                Some(_) => {}
                None if is_foot[t.col] => coupling.push((i, t.col as u32, t.val)),
                None => {}
            }
        }
        // Merge the coupling's duplicates in a fixed order.
        coupling.sort_by_key(|c| (c.0, c.1));
        coupling.dedup_by(|b, a| {
            if (a.0, a.1) == (b.0, b.1) {
                a.2 += b.2;
                true
            } else {
                false
            }
        });
        let (symbolic, numeric) = if n_free > 0 {
            let d: f64 = lower.iter().filter(|t| t.row == t.col).map(|t| t.val).sum::<f64>() / n_free as f64;
            // A free piece touching no constraint (a loose fragment of a leg) stays put.
            lower.extend((0..n_free).map(|k| Triplet::new(k, k, 1e-9 * d.max(f64::MIN_POSITIVE))));
            let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n_free, n_free, &lower)
                .map_err(|e| Error::Invalid(format!("assembling the legs' Laplacian: {e:?}")))?;
            let symbolic = SymbolicLlt::new(mat.symbolic())
                .map_err(|e| Error::Invalid(format!("ordering the legs' Laplacian: {e:?}")))?;
            let numeric = symbolic
                .factorize(mat.as_ref())
                .map_err(|e| Error::Invalid(format!("factorising the legs' Laplacian: {e:?}")))?;
            (Some(symbolic), Some(numeric))
        } else {
            (None, None)
        };
        let movable = |v: usize| is_foot[v] || free[v].is_some();
        let mut movable_laplacian: Vec<(u32, u32, f64)> = op
            .laplacian_triplets()
            .into_iter()
            .filter(|t| movable(t.row) && movable(t.col))
            .map(|t| (t.row as u32, t.col as u32, t.val))
            .collect();
        movable_laplacian.sort_by_key(|c| (c.0, c.1));
        movable_laplacian.dedup_by(|b, a| {
            if (a.0, a.1) == (b.0, b.1) {
                a.2 += b.2;
                true
            } else {
                false
            }
        });
        let leg_triangles: Vec<([u32; 3], [[f64; 3]; 3], f64)> = topology
            .triangles()
            .iter()
            .zip(op.basis.iter().zip(&op.areas))
            .filter(|(t, _)| t.iter().any(|&v| movable(v as usize)))
            .map(|(t, (g, &area))| (*t, [0, 1, 2].map(|k| [g[k][0], g[k][1], g[k][2]]), area))
            .collect();
        let leg_rest_gradients = leg_triangles
            .iter()
            .map(|(t, g, _)| {
                let mut m = Matrix3::zeros();
                for k in 0..3 {
                    let v = t[k] as usize;
                    for (d, gd) in g[k].iter().enumerate() {
                        for c in 0..3 {
                            m[(d, c)] += gd * rest[3 * v + c] as f64;
                        }
                    }
                }
                m
            })
            .collect();
        Ok(FootSkateCleanup {
            leg_triangles,
            leg_rest_gradients,
            rest: rest.to_vec(),
            movable_laplacian,
            up,
            n_vertices: n,
            height,
            params,
            leg_of,
            feet,
            free,
            n_free,
            coupling,
            symbolic,
            numeric,
        })
    }

    /// The feet found (vertex sets, one per leg).
    pub fn feet(&self) -> &[Vec<u32>] {
        &self.feet
    }

    /// The height displacement of the free leg vertices (the module doc's step 6) that turns
    /// the legs for the ground displacement `d` (per vertex, along the ground axes `u`, `w`):
    /// the least-squares solution of `grad h = t` on the leg triangles, `t = (-dd_u/dx_up,
    /// -dd_w/dx_up)` along the ground axes and 0 along the up axis, with `h = 0` on the feet,
    /// the hips and the body. With it the displacement's gradient on a triangle is, to first
    /// order, antisymmetric (an infinitesimal rotation) in its up-and-ground parts: a slanting
    /// leg turns instead. One solve with the factorised `L_II`, right-hand side the divergence
    /// `G^T D t` at the free vertices.
    fn turn_heights(&self, d: &[[f64; 2]], u: usize, w: usize) -> Vec<f64> {
        let (Some(sym), Some(num)) = (&self.symbolic, &self.numeric) else { return Vec::new() };
        let (axis, _) = self.up.axis_and_sign();
        let mut rhs = Mat::<f64>::zeros(self.n_free, 1);
        for (t, g, area) in &self.leg_triangles {
            // d(d_c)/d(x_up) for the two ground components c.
            let (mut du, mut dw) = (0.0, 0.0);
            for k in 0..3 {
                let dv = d[t[k] as usize];
                du += g[k][axis] * dv[0];
                dw += g[k][axis] * dv[1];
            }
            let mut target = [0.0; 3];
            target[u] = -du;
            target[w] = -dw;
            for k in 0..3 {
                if let Some(i) = self.free[t[k] as usize] {
                    rhs[(i, 0)] += area * (0..3).map(|r| target[r] * g[k][r]).sum::<f64>();
                }
            }
        }
        sym.solve_in_place(num, rhs.as_mut());
        (0..self.n_free).map(|i| rhs[(i, 0)]).collect()
    }

    /// Step 8: the free leg vertices of `q` (the frame as cleaned) moved so that every leg
    /// triangle keeps the stretch it had in `before` (the frame before the clean-up) under its
    /// rotation in `q`, the feet, the hips, the body and the vertices `held` (this frame's
    /// pinned vertices, sorted) held: as-rigid-as-possible local/global iterations (Sorkine
    /// and Alexa 2007), each a Poisson solve for the update `delta`,
    /// `L_II delta_I = (G^T D (G~ - G q))_I` with `G~_m = G_rest,m (R_m S_m)^T`, `R_m` the
    /// polar rotation of the triangle from rest to `q`, `S_m` its stretch from rest to
    /// `before` (thesis eq. 2.48's system). Without `held`, `I` is the free set and `L_II` is
    /// factorised once; with it, `I` also takes the other vertices of every leg holding a
    /// pinned vertex (its planted foot's sole rolls with the pins instead of being dragged
    /// rigidly), less `held`, factorised for this frame.
    fn keep_leg_stretch(&self, before: &[f32], q: &mut [f32], held: &[u32]) {
        let (Some(sym), Some(num)) = (&self.symbolic, &self.numeric) else { return };
        let is_held = |v: usize| held.binary_search(&(v as u32)).is_ok();
        let own: Option<(Vec<Option<usize>>, usize, SymbolicLlt, NumericLlt)> = if !held.is_empty() {
            // The feet holding a pinned vertex: their other vertices bend with the leg.
            let planted: Vec<u32> = held.iter().filter_map(|&v| self.leg_of[v as usize]).collect();
            let in_planted_foot = |v: usize| {
                self.leg_of[v]
                    .is_some_and(|k| planted.contains(&k) && self.feet[k as usize].binary_search(&(v as u32)).is_ok())
            };
            let mut index = vec![None; self.n_vertices];
            let mut count = 0;
            for (v, slot) in index.iter_mut().enumerate() {
                if (self.free[v].is_some() || in_planted_foot(v)) && !is_held(v) {
                    *slot = Some(count);
                    count += 1;
                }
            }
            if count == 0 {
                return;
            }
            let lower: Vec<Triplet<usize, usize, f64>> = self
                .movable_laplacian
                .iter()
                .filter_map(|&(r, c, l)| {
                    let (i, j) = (index[r as usize]?, index[c as usize]?);
                    (i >= j).then(|| Triplet::new(i, j, l))
                })
                .collect();
            let Some((symbolic, numeric)) = factorise_shifted(lower, count) else { return };
            Some((index, count, symbolic, numeric))
        } else {
            None
        };
        let (index, count, sym, num) = match &own {
            Some((index, count, s, n)) => (index.as_slice(), *count, s, n),
            None => (self.free.as_slice(), self.n_free, sym, num),
        };
        // Each triangle's stretch before the clean-up, the same for every iteration.
        let stretch: Vec<Option<Matrix3<f64>>> = self
            .leg_triangles
            .iter()
            .map(|(t, _, area)| {
                let moving = *area != 0.0 && t.iter().any(|&v| index[v as usize].is_some());
                if moving { triangle_polar_factors(&self.rest, before, t).map(|(_, s)| s) } else { None }
            })
            .collect();
        for _ in 0..self.params.stretch_iterations {
            let mut rhs = Mat::<f64>::zeros(count, 3);
            for (((t, g, area), rest_gradient), st) in
                self.leg_triangles.iter().zip(&self.leg_rest_gradients).zip(&stretch)
            {
                let Some(st) = st else { continue };
                let Some((r, _)) = triangle_polar_factors(&self.rest, q, t) else { continue };
                let mut e = rest_gradient * (r * st).transpose();
                for k in 0..3 {
                    let v = t[k] as usize;
                    for (d, gd) in g[k].iter().enumerate() {
                        for c in 0..3 {
                            e[(d, c)] -= gd * q[3 * v + c] as f64;
                        }
                    }
                }
                for k in 0..3 {
                    if let Some(i) = index[t[k] as usize] {
                        for c in 0..3 {
                            rhs[(i, c)] += area * (0..3).map(|d| g[k][d] * e[(d, c)]).sum::<f64>();
                        }
                    }
                }
            }
            sym.solve_in_place(num, rhs.as_mut());
            for (v, slot) in index.iter().enumerate() {
                if let Some(i) = slot {
                    for c in 0..3 {
                        q[3 * v + c] += rhs[(*i, c)] as f32;
                    }
                }
            }
        }
    }

    /// The displacement that takes each pinned vertex the rest of its way (`pins`: vertex and
    /// what is left along the ground axes, sorted by vertex) and bends the legs' other movable
    /// vertices (feet and free) with them, the hips and the body held: `L_FF e_F = -L_FP e_P`
    /// over this frame's free set F (the movable vertices not pinned), factorised per frame
    /// (the pinned set changes from frame to frame). Returns (vertex, displacement) for the
    /// movable vertices; empty without pins.
    fn vertex_pin_displacement(&self, pins: &[(u32, [f64; 2])]) -> Vec<(u32, [f64; 2])> {
        if pins.is_empty() {
            return Vec::new();
        }
        let n = self.n_vertices;
        let pinned: std::collections::HashMap<u32, [f64; 2]> = pins.iter().copied().collect();
        let mut index = vec![usize::MAX; n];
        let mut order = Vec::new();
        for (v, slot) in index.iter_mut().enumerate() {
            let movable = self.free[v].is_some()
                || self.leg_of[v].is_some_and(|k| self.feet[k as usize].binary_search(&(v as u32)).is_ok());
            if movable && !pinned.contains_key(&(v as u32)) {
                *slot = order.len();
                order.push(v as u32);
            }
        }
        let mut out: Vec<(u32, [f64; 2])> = pins.to_vec();
        if order.is_empty() {
            return out;
        }
        let mut lower = Vec::new();
        let mut rhs = Mat::<f64>::zeros(order.len(), 2);
        for &(r, c, l) in &self.movable_laplacian {
            let i = index[r as usize];
            if i == usize::MAX {
                continue;
            }
            match (index[c as usize], pinned.get(&c)) {
                (j, _) if j != usize::MAX && i >= j => lower.push(Triplet::new(i, j, l)),
                (j, _) if j != usize::MAX => {}
                (_, Some(e)) => {
                    rhs[(i, 0)] -= l * e[0];
                    rhs[(i, 1)] -= l * e[1];
                }
                _ => {}
            }
        }
        if let Some((symbolic, numeric)) = factorise_shifted(lower, order.len()) {
            symbolic.solve_in_place(&numeric, rhs.as_mut());
            out.extend(order.iter().enumerate().map(|(i, &v)| (v, [rhs[(i, 0)], rhs[(i, 1)]])));
        }
        out
    }

    /// The cleaned-up frames of a motion (`frames[f]` of `[n][3]`, at `fps`) and what was done.
    /// `ground`, when given, is per frame the ground's travel along the two ground axes (the
    /// module doc's in-place clips): the feet are pinned to it.
    ///
    /// [`FootSkateParams::passes`] passes: the report's plants, sliding before and drift before
    /// are the first pass's, its sliding after and drift after the last's (drift from the last
    /// pass's pins), its largest correction the largest displacement of a vertex over all.
    pub fn clean(
        &self,
        frames: &[Vec<f32>],
        fps: f64,
        ground: Option<&[[f64; 2]]>,
    ) -> Result<(Vec<Vec<f32>>, CleanupReport)> {
        let (mut out, first) = self.clean_once(frames, fps, ground)?;
        let mut report = first;
        for _ in 1..self.params.passes {
            let (next, r) = self.clean_once(&out, fps, ground)?;
            out = next;
            report.sliding_after = r.sliding_after;
            report.pinned_drift_after = r.pinned_drift_after;
            report.pinned_drift_after_max = r.pinned_drift_after_max;
        }
        // The body's shift of a frame: the displacement of a vertex outside the legs (they all
        // move by it).
        let body = self.leg_of.iter().position(Option::is_none);
        let (mut largest, mut shift, mut leg) = (0.0f64, 0.0f64, 0.0f64);
        for (a, b) in frames.iter().zip(&out) {
            let disp = |v: usize| -> [f64; 3] { [0, 1, 2].map(|k| (b[3 * v + k] - a[3 * v + k]) as f64) };
            let s = body.map_or([0.0; 3], disp);
            shift = shift.max(s[0].hypot(s[1]).hypot(s[2]));
            for v in 0..self.n_vertices {
                let d = disp(v);
                largest = largest.max(d[0].hypot(d[1]).hypot(d[2]));
                leg = leg.max((d[0] - s[0]).hypot(d[1] - s[1]).hypot(d[2] - s[2]));
            }
        }
        report.largest_correction = largest;
        report.largest_body_shift = shift;
        report.largest_leg_correction = leg;
        Ok((out, report))
    }

    /// One pass of [`FootSkateCleanup::clean`].
    fn clean_once(
        &self,
        frames: &[Vec<f32>],
        fps: f64,
        ground: Option<&[[f64; 2]]>,
    ) -> Result<(Vec<Vec<f32>>, CleanupReport)> {
        let n = self.n_vertices;
        if let Some(f) = frames.iter().position(|p| p.len() != 3 * n) {
            return Err(Error::Invalid(format!(
                "frame {f} has {} coordinates: expected 3 x {n} vertices",
                frames[f].len()
            )));
        }
        if let Some(g) = ground
            && g.len() != frames.len()
        {
            return Err(Error::Invalid(format!(
                "a ground travel of {} frames for a motion of {}: expected one offset per frame",
                g.len(),
                frames.len()
            )));
        }
        let (u, w, _) = plane_axes(self.up);
        let (up_axis, _) = self.up.axis_and_sign();
        let nf = frames.len();
        // Frames on the moving ground.
        let moved: Vec<Vec<f32>> = frames
            .iter()
            .enumerate()
            .map(|(f, p)| {
                let mut p = p.clone();
                if let Some(g) = ground {
                    for q in p.chunks_exact_mut(3) {
                        q[u] += g[f][0] as f32;
                        q[w] += g[f][1] as f32;
                    }
                }
                p
            })
            .collect();
        let flat: Vec<f32> = moved.iter().flatten().copied().collect();
        let fps = fps.max(f64::MIN_POSITIVE);
        let contacts = ground_contacts(&flat, n, fps, self.up, &self.params.contact);
        let planted = planted_contacts(&flat, n, fps, self.up, &contacts, &self.params.contact);
        let xy = |f: usize, v: u32| -> [f64; 2] {
            let p = &moved[f];
            [p[3 * v as usize + u] as f64, p[3 * v as usize + w] as f64]
        };
        let blend = ((self.params.blend_seconds * fps).round() as usize).max(1);
        // Per foot: plants (frame ranges with their planted vertices per frame) and per-frame
        // corrections.
        let legs = self.feet.len();
        let mut corrections: Vec<Vec<Correction>> = vec![vec![Correction::default(); nf]; legs];
        let mut active: Vec<Vec<bool>> = vec![vec![false; nf]; legs];
        // (foot, frame range, per frame the planted vertices with weights), for the report.
        let mut plants: Vec<(usize, usize, usize, Vec<Vec<GroundContact>>)> = Vec::new();
        for (k, corr) in corrections.iter_mut().enumerate() {
            let steps: Vec<Vec<GroundContact>> = planted
                .iter()
                .map(|s| s.iter().filter(|c| self.leg_of[c.vertex as usize] == Some(k as u32)).copied().collect())
                .collect();
            let centroid = |f: usize| -> [f64; 2] {
                let foot = &self.feet[k];
                let s = foot.iter().fold([0.0; 2], |a, &v| {
                    let p = xy(f, v);
                    [a[0] + p[0], a[1] + p[1]]
                });
                let c = foot.len().max(1) as f64;
                [s[0] / c, s[1] / c]
            };
            let on: Vec<usize> = (0..steps.len()).filter(|&s| !steps[s].is_empty()).collect();
            let mut runs: Vec<(usize, usize)> = Vec::new();
            // Two runs are one plant only when the foot came back down where it left: a
            // foot that moved further (the next footfall) starts a plant of its own.
            let rejoin = self.params.rejoin_distance * self.height;
            for s in on {
                match runs.last_mut() {
                    Some(r)
                        if s - r.1 <= self.params.gap_steps + 1 && {
                            let (p, q) = (centroid(r.1 + 1), centroid(s));
                            (p[0] - q[0]).hypot(p[1] - q[1]) <= rejoin
                        } =>
                    {
                        r.1 = s
                    }
                    _ => runs.push((s, s)),
                }
            }
            // A foot lifting off (or landing) fast is not planted: the ends of a run whose
            // planted vertices move faster than the lift speed are left out.
            let lift = self.params.lift_speed.map_or(f64::INFINITY, |l| l * self.height);
            let speed = |st: usize| {
                let (mut sum, mut wt) = (0.0, 0.0);
                for c in &steps[st] {
                    let (p, q) = (xy(st, c.vertex), xy(st + 1, c.vertex));
                    sum += c.weight.max(1e-6) * (q[0] - p[0]).hypot(q[1] - p[1]);
                    wt += c.weight.max(1e-6);
                }
                if wt > 0.0 { fps * sum / wt } else { 0.0 }
            };
            let runs: Vec<(usize, usize)> = runs
                .into_iter()
                .filter_map(|(mut s0, mut s1)| {
                    while s0 <= s1 && speed(s0) > lift {
                        s0 += 1;
                    }
                    while s1 > s0 && speed(s1) > lift {
                        s1 -= 1;
                    }
                    (s0 <= s1 && speed(s0) <= lift).then_some((s0, s1))
                })
                .collect();
            for (s0, s1) in runs {
                let (a, b) = (s0, s1 + 1);
                let m = (a + b) / 2;
                // Planted vertices of every frame of the plant: those of the steps it belongs to.
                let per_frame: Vec<Vec<GroundContact>> = (a..=b)
                    .map(|f| {
                        let mut v: Vec<GroundContact> = Vec::new();
                        for s in [f.checked_sub(1), Some(f)].into_iter().flatten() {
                            if s < s0 || s > s1 {
                                continue;
                            }
                            for c in &steps[s] {
                                match v.iter_mut().find(|x| x.vertex == c.vertex) {
                                    Some(x) => x.weight = x.weight.max(c.weight),
                                    None => v.push(*c),
                                }
                            }
                        }
                        v.sort_by_key(|c| c.vertex);
                        v
                    })
                    .collect();
                let mut fits: Vec<Option<Correction>> = per_frame
                    .iter()
                    .enumerate()
                    .map(|(i, vs)| {
                        let f = a + i;
                        fit(vs, |v| xy(f, v), |v| xy(m, v), self.params.fit_turn).map(|(theta, c, t)| {
                            let g = centroid(f);
                            Correction { theta, t, r: [c[0] - g[0], c[1] - g[1]] }
                        })
                    })
                    .collect();
                fill_gaps(&mut fits);
                for (i, c) in fits.into_iter().enumerate() {
                    corr[a + i] = c.unwrap_or_default();
                    active[k][a + i] = true;
                }
                plants.push((k, a, b, per_frame));
            }
        }
        // The root's shift (Kovar sec. 4): on every frame where a foot is planted, the planted
        // feet's mean pull; between plants bridged and faded as the corrections are. The feet
        // then only need what is left of their pull (their correction less the shift).
        let mut root = vec![[0.0f64; 2]; nf];
        // Per plant, the shift of its pins (step 5b): 0 unless the pins are carried.
        let mut carried = vec![[0.0f64; 2]; plants.len()];
        if self.params.move_root && self.params.carry_pins {
            // Step 5b: each plant is pinned where its foot comes down, as the body has been
            // moved so far; the body then moves on with the planted feet, step by step: by
            // their mean change of pull, plus a share of what the legs still have to reach
            // (drained into the body, so a leg bent in double support straightens after it).
            let mut plant_at = vec![vec![None; nf]; legs];
            for (i, (k, a, b, _)) in plants.iter().enumerate() {
                for slot in &mut plant_at[*k][*a..=*b] {
                    *slot = Some(i);
                }
            }
            let drain = 1.0 / (blend + 1) as f64;
            for f in 0..nf {
                for (k, at) in plant_at.iter().enumerate() {
                    if let Some(i) = at[f]
                        && plants[i].1 == f
                    {
                        let p = corrections[k][f].mean_shift();
                        carried[i] = [root[f][0] - p[0], root[f][1] - p[1]];
                    }
                }
                if f + 1 == nf {
                    break;
                }
                let (mut sum, mut count) = ([0.0; 2], 0.0);
                for (k, at) in plant_at.iter().enumerate() {
                    if let (Some(i), Some(j)) = (at[f], at[f + 1])
                        && i == j
                    {
                        let (p0, p1) = (corrections[k][f].mean_shift(), corrections[k][f + 1].mean_shift());
                        let e = [p0[0] + carried[i][0] - root[f][0], p0[1] + carried[i][1] - root[f][1]];
                        sum = [sum[0] + p1[0] - p0[0] + drain * e[0], sum[1] + p1[1] - p0[1] + drain * e[1]];
                        count += 1.0;
                    }
                }
                root[f + 1] =
                    if count > 0.0 { [root[f][0] + sum[0] / count, root[f][1] + sum[1] / count] } else { root[f] };
            }
            for (k, at) in plant_at.iter().enumerate() {
                for f in 0..nf {
                    if let Some(i) = at[f] {
                        let c = &mut corrections[k][f];
                        c.t = [c.t[0] + carried[i][0] - root[f][0], c.t[1] + carried[i][1] - root[f][1]];
                    }
                }
            }
        } else if self.params.move_root {
            let on: Vec<bool> = (0..nf).map(|f| active.iter().any(|a| a[f])).collect();
            for (f, r) in root.iter_mut().enumerate() {
                let (mut sum, mut count) = ([0.0; 2], 0.0);
                for (corr, a) in corrections.iter().zip(&active) {
                    if a[f] {
                        let d = corr[f].mean_shift();
                        sum = [sum[0] + d[0], sum[1] + d[1]];
                        count += 1.0;
                    }
                }
                if count > 0.0 {
                    *r = [sum[0] / count, sum[1] / count];
                }
            }
            bridge_and_fade(&mut root, &on, blend, lerp2, |x, a| [a * x[0], a * x[1]], add2);
            for (corr, a) in corrections.iter_mut().zip(&active) {
                for f in 0..nf {
                    if a[f] {
                        corr[f].t = [corr[f].t[0] - root[f][0], corr[f].t[1] - root[f][1]];
                    }
                }
            }
        }
        // Fades and bridges between plants.
        for (corr, on) in corrections.iter_mut().zip(&active) {
            bridge_and_fade(corr, on, blend, Correction::lerp, Correction::scaled, |c, x| Correction {
                theta: c.theta + x.theta,
                t: [c.t[0] + x.t[0], c.t[1] + x.t[1]],
                r: x.r,
            });
        }
        // Per-vertex pins (step 4b): what the rigid move leaves of each planted vertex's way to
        // its pin, on the plant's frames, faded out around them as the corrections are.
        let foot_means: Vec<Vec<[f64; 2]>> = self
            .feet
            .iter()
            .map(|foot| {
                (0..nf)
                    .map(|f| {
                        let g = foot.iter().fold([0.0; 2], |a, &v| {
                            let q = xy(f, v);
                            [a[0] + q[0], a[1] + q[1]]
                        });
                        let c = foot.len().max(1) as f64;
                        [g[0] / c, g[1] / c]
                    })
                    .collect()
            })
            .collect();
        // The rigid move of a point `q` of foot k at frame f (before the root's shift).
        let rigid = |k: usize, f: usize, q: [f64; 2]| -> [f64; 2] {
            let c = corrections[k][f];
            let g = foot_means[k][f];
            let centre = [g[0] + c.r[0], g[1] + c.r[1]];
            let (s, co) = c.theta.sin_cos();
            let (x, y) = (q[0] - centre[0], q[1] - centre[1]);
            [centre[0] + co * x - s * y + c.t[0] - q[0], centre[1] + s * x + co * y + c.t[1] - q[1]]
        };
        let mut residuals: Vec<Vec<(u32, [f64; 2])>> = vec![Vec::new(); nf];
        let reach = self.params.pin_reach * self.height;
        if self.params.vertex_pins {
            for (i, (k, a, b, per_frame)) in plants.iter().enumerate() {
                let (k, a, b) = (*k, *a, *b);
                let m = (a + b) / 2;
                let shift = carried[i];
                let of_frame = |f: usize| -> Vec<(u32, [f64; 2])> {
                    per_frame[f - a]
                        .iter()
                        .map(|c| {
                            let (q, y) = (xy(f, c.vertex), xy(m, c.vertex));
                            let d = rigid(k, f, q);
                            let y = [y[0] + shift[0], y[1] + shift[1]];
                            let r = [y[0] - q[0] - d[0] - root[f][0], y[1] - q[1] - d[1] - root[f][1]];
                            // Bounded: a vertex far from its pin is let go of rather than
                            // dragged through the foot.
                            let scale = (reach / r[0].hypot(r[1]).max(f64::MIN_POSITIVE)).min(1.0);
                            (c.vertex, [scale * r[0], scale * r[1]])
                        })
                        .collect()
                };
                for (f, frame) in residuals.iter_mut().enumerate().take(b + 1).skip(a) {
                    frame.extend(of_frame(f));
                }
                let fade = |x: usize| smoothstep(1.0 - x as f64 / (blend + 1) as f64);
                let (first, last) = (of_frame(a), of_frame(b));
                for x in 1..=blend {
                    if let Some(f) = a.checked_sub(x).filter(|&f| !active[k][f]) {
                        residuals[f].extend(first.iter().map(|&(v, r)| (v, [fade(x) * r[0], fade(x) * r[1]])));
                    }
                    if let Some(f) = Some(b + x).filter(|&f| f < nf && !active[k][f]) {
                        residuals[f].extend(last.iter().map(|&(v, r)| (v, [fade(x) * r[0], fade(x) * r[1]])));
                    }
                }
            }
            for list in &mut residuals {
                list.sort_by_key(|c| c.0);
                list.dedup_by(|b, a| {
                    if a.0 == b.0 {
                        a.1 = [a.1[0] + b.1[0], a.1[1] + b.1[1]];
                        true
                    } else {
                        false
                    }
                });
            }
        }
        // Per frame: the feet's displacements, then the legs' solve.
        let out: Vec<(Vec<f32>, f64)> = (0..nf)
            .into_par_iter()
            .map(|f| {
                let p = &moved[f];
                let mut d = vec![[0.0f64; 2]; n];
                for (k, foot) in self.feet.iter().enumerate() {
                    let c = corrections[k][f];
                    if c == Correction::default() || foot.is_empty() {
                        continue;
                    }
                    let g = foot.iter().fold([0.0; 2], |a, &v| {
                        let q = xy(f, v);
                        [a[0] + q[0], a[1] + q[1]]
                    });
                    let centre = [g[0] / foot.len() as f64 + c.r[0], g[1] / foot.len() as f64 + c.r[1]];
                    let (s, co) = c.theta.sin_cos();
                    for &v in foot {
                        let q = xy(f, v);
                        let (x, y) = (q[0] - centre[0], q[1] - centre[1]);
                        let moved_to = [centre[0] + co * x - s * y + c.t[0], centre[1] + s * x + co * y + c.t[1]];
                        d[v as usize] = [moved_to[0] - q[0], moved_to[1] - q[1]];
                    }
                }
                let root = root[f];
                if let (Some(sym), Some(num)) = (&self.symbolic, &self.numeric) {
                    let mut rhs = Mat::<f64>::zeros(self.n_free, 2);
                    for &(i, v, l) in &self.coupling {
                        let dv = d[v as usize];
                        rhs[(i, 0)] -= l * dv[0];
                        rhs[(i, 1)] -= l * dv[1];
                    }
                    sym.solve_in_place(num, rhs.as_mut());
                    for (v, slot) in self.free.iter().enumerate() {
                        if let Some(i) = slot {
                            d[v] = [rhs[(*i, 0)], rhs[(*i, 1)]];
                        }
                    }
                }
                let lift = if self.params.keep_edges { self.turn_heights(&d, u, w) } else { Vec::new() };
                for (v, e) in self.vertex_pin_displacement(&residuals[f]) {
                    d[v as usize] = [d[v as usize][0] + e[0], d[v as usize][1] + e[1]];
                }
                let mut q = p.clone();
                for (v, dv) in d.iter().enumerate() {
                    q[3 * v + u] += (dv[0] + root[0]) as f32;
                    q[3 * v + w] += (dv[1] + root[1]) as f32;
                    let dh = self.free[v].and_then(|i| lift.get(i)).copied().unwrap_or(0.0);
                    q[3 * v + up_axis] += dh as f32;
                }
                if d.iter().any(|dv| *dv != [0.0; 2]) {
                    let held: Vec<u32> = residuals[f].iter().map(|r| r.0).collect();
                    self.keep_leg_stretch(p, &mut q, &held);
                }
                let largest = q
                    .chunks_exact(3)
                    .zip(p.chunks_exact(3))
                    .map(|(a, b)| {
                        let e = [0, 1, 2].map(|c| (a[c] - b[c]) as f64);
                        e[0].hypot(e[1]).hypot(e[2])
                    })
                    .fold(0.0, f64::max);
                (q, largest)
            })
            .collect();
        let largest_correction = out.iter().map(|o| o.1).fold(0.0, f64::max);
        let cleaned_moved: Vec<Vec<f32>> = out.into_iter().map(|o| o.0).collect();
        // The pins' drift before and after.
        let (mut before, mut after, mut weight, mut worst) = (0.0, 0.0, 0.0, 0.0f64);
        for (_, a, b, per_frame) in &plants {
            let m = (a + b) / 2;
            for (i, vs) in per_frame.iter().enumerate() {
                let f = a + i;
                for c in vs {
                    let k = c.vertex as usize;
                    let dist = |p: &[Vec<f32>]| {
                        ((p[f][3 * k + u] - p[m][3 * k + u]) as f64).hypot((p[f][3 * k + w] - p[m][3 * k + w]) as f64)
                    };
                    let wt = c.weight.max(1e-6);
                    let x = dist(&cleaned_moved);
                    before += wt * dist(&moved);
                    after += wt * x;
                    weight += wt;
                    worst = worst.max(x);
                }
            }
        }
        let mean = |s: f64| if weight > 0.0 { s / weight } else { 0.0 };
        let slide = |p: &[Vec<f32>]| -> Result<f64> {
            let flat: Vec<f32> = p.iter().flatten().copied().collect();
            let c = ground_contacts(&flat, n, fps, self.up, &self.params.contact);
            Ok(foot_sliding(&flat, n, fps, self.up, &c, &self.params.contact, &[])?.mean_speed)
        };
        let report = CleanupReport {
            plants: plants.len(),
            sliding_before: slide(&moved)?,
            sliding_after: slide(&cleaned_moved)?,
            pinned_drift_before: mean(before),
            pinned_drift_after: mean(after),
            pinned_drift_after_max: worst,
            largest_correction,
            largest_body_shift: 0.0,
            largest_leg_correction: 0.0,
        };
        // Back off the moving ground.
        let cleaned = cleaned_moved
            .into_iter()
            .enumerate()
            .map(|(f, mut p)| {
                if let Some(g) = ground {
                    for q in p.chunks_exact_mut(3) {
                        q[u] -= g[f][0] as f32;
                        q[w] -= g[f][1] as f32;
                    }
                }
                p
            })
            .collect();
        Ok((cleaned, report))
    }
}

/// The weighted rigid fit along the ground of `from(v) -> to(v)` over `vs` (the rotation only
/// when `turn`): (rotation angle,
/// the centre (weighted centroid of `from`), translation); `None` without weight.
fn fit(
    vs: &[GroundContact],
    from: impl Fn(u32) -> [f64; 2],
    to: impl Fn(u32) -> [f64; 2],
    turn: bool,
) -> Option<(f64, [f64; 2], [f64; 2])> {
    let wsum: f64 = vs.iter().map(|c| c.weight.max(1e-6)).sum();
    if vs.is_empty() || wsum <= 0.0 {
        return None;
    }
    let mean = |g: &dyn Fn(u32) -> [f64; 2]| {
        let s = vs.iter().fold([0.0; 2], |a, c| {
            let p = g(c.vertex);
            let wt = c.weight.max(1e-6);
            [a[0] + wt * p[0], a[1] + wt * p[1]]
        });
        [s[0] / wsum, s[1] / wsum]
    };
    let (cf, ct) = (mean(&from), mean(&to));
    let (mut sxx, mut sxy, mut syx, mut syy) = (0.0, 0.0, 0.0, 0.0);
    for c in vs {
        let (p, q) = (from(c.vertex), to(c.vertex));
        let (a, b) = ([p[0] - cf[0], p[1] - cf[1]], [q[0] - ct[0], q[1] - ct[1]]);
        let wt = c.weight.max(1e-6);
        sxx += wt * a[0] * b[0];
        sxy += wt * a[0] * b[1];
        syx += wt * a[1] * b[0];
        syy += wt * a[1] * b[1];
    }
    // A planted patch too small to fix a turn (one vertex, a line) only translates.
    let spread: f64 = vs
        .iter()
        .map(|c| {
            let p = from(c.vertex);
            c.weight.max(1e-6) * ((p[0] - cf[0]).powi(2) + (p[1] - cf[1]).powi(2))
        })
        .sum::<f64>()
        / wsum;
    let theta = if turn && spread > 1e-12 && vs.len() >= 3 { (sxy - syx).atan2(sxx + syy) } else { 0.0 };
    Some((theta, cf, [ct[0] - cf[0], ct[1] - cf[1]]))
}

fn lerp2(a: [f64; 2], b: [f64; 2], s: f64) -> [f64; 2] {
    [(1.0 - s) * a[0] + s * b[0], (1.0 - s) * a[1] + s * b[1]]
}

fn add2(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

/// Fills the frames where `on` is false from the frames where it is true (Kovar sec. 5's
/// blending): between two such frames at most `2 blend + 1` apart, interpolated with a
/// smoothstep; otherwise faded to zero with a smoothstep over `blend` frames from either side
/// (the two fades added where both reach).
fn bridge_and_fade<T: Copy + Default>(
    values: &mut [T],
    on: &[bool],
    blend: usize,
    lerp: impl Fn(T, T, f64) -> T,
    scale: impl Fn(T, f64) -> T,
    add: impl Fn(T, T) -> T,
) {
    let keys: Vec<usize> = (0..values.len()).filter(|&f| on[f]).collect();
    for f in 0..values.len() {
        if on[f] {
            continue;
        }
        let prev = keys.iter().rev().find(|&&k| k < f).copied();
        let next = keys.iter().find(|&&k| k > f).copied();
        values[f] = match (prev, next) {
            (Some(p), Some(q)) if q - p <= 2 * blend + 1 => {
                lerp(values[p], values[q], smoothstep((f - p) as f64 / (q - p) as f64))
            }
            _ => {
                let fade = |d: usize| smoothstep(1.0 - d as f64 / (blend + 1) as f64);
                let mut c = T::default();
                if let Some(p) = prev.filter(|&p| f - p <= blend) {
                    c = scale(values[p], fade(f - p));
                }
                if let Some(q) = next.filter(|&q| q - f <= blend) {
                    c = add(c, scale(values[q], fade(q - f)));
                }
                c
            }
        };
    }
}

/// Missing fits inside a plant interpolated between their neighbours (the ends held).
fn fill_gaps(fits: &mut [Option<Correction>]) {
    let known: Vec<usize> = (0..fits.len()).filter(|&i| fits[i].is_some()).collect();
    if known.is_empty() {
        return;
    }
    for i in 0..fits.len() {
        if fits[i].is_some() {
            continue;
        }
        let p = known.iter().rev().find(|&&k| k < i).copied();
        let q = known.iter().find(|&&k| k > i).copied();
        fits[i] = match (p, q) {
            (Some(p), Some(q)) => Some(Correction::lerp(
                fits[p].expect("known"),
                fits[q].expect("known"),
                (i - p) as f64 / (q - p) as f64,
            )),
            (Some(p), None) => fits[p],
            (None, Some(q)) => fits[q],
            (None, None) => None,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Heights of the rows of a ribbon "body" 2 tall, +y up, 3 vertices a row (x = 0, 0.1,
    /// 0.2): rows 0-7 are the leg (0 and 0.02 the sole, 0.1 the ankle, 1.1 the hip), rows 8-9
    /// the torso.
    const ROWS: [f32; 10] = [0.0, 0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 1.1, 1.5, 2.0];

    fn ribbon() -> (Topology, Vec<f32>, Vec<u32>) {
        let mut tris = Vec::new();
        for r in 0..ROWS.len() as u32 - 1 {
            for c in 0..2u32 {
                let (a, b, d, e) = (3 * r + c, 3 * r + c + 1, 3 * (r + 1) + c, 3 * (r + 1) + c + 1);
                tris.push([a, b, e]);
                tris.push([a, e, d]);
            }
        }
        let rest: Vec<f32> = ROWS.iter().flat_map(|&y| (0..3).flat_map(move |c| [0.1 * c as f32, y, 0.0])).collect();
        (Topology::new(3 * ROWS.len(), tris, None).unwrap(), rest, (0..24).collect())
    }

    /// 30 frames at 30 fps: the body still; the foot (rows 0-2, the rows above it bending
    /// linearly up to the hip) lifted 0.3 in the swing (frames 0-4 and 21-29) and down on the
    /// ground at frames 5-20, where it skates along x at 0.3 per second.
    fn skating(rest: &[f32]) -> Vec<Vec<f32>> {
        (0..30)
            .map(|f| {
                let planted = (5..=20).contains(&f);
                let (dx, lift) = if planted { (0.01 * (f as f32 - 5.0), 0.0) } else { (0.0, 0.3) };
                let mut p = rest.to_vec();
                for (r, &y) in ROWS.iter().enumerate().take(8) {
                    // 1 for the foot, falling to 0 at the hip.
                    let s = if r <= 2 { 1.0 } else { (1.1 - y) / 1.0 };
                    for c in 0..3 {
                        let k = 3 * (3 * r + c);
                        p[k] += s * dx;
                        p[k + 1] += s * lift;
                    }
                }
                p
            })
            .collect()
    }

    #[test]
    fn a_skating_planted_foot_is_pinned_the_rest_barely_moves_and_nothing_pops() {
        let (t, rest, leg) = ribbon();
        // The hips held: the leg alone bends to reach the pin (in the ground's directions
        // only: step 8 is tested below).
        let held = FootSkateParams { move_root: false, stretch_iterations: 0, ..FootSkateParams::default() };
        let c = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[leg], held).unwrap();
        assert_eq!(c.feet(), &[(0..9).collect::<Vec<u32>>()], "the sole and the ankle rows");
        let frames = skating(&rest);
        let (out, report) = c.clean(&frames, 30.0, None).unwrap();
        assert_eq!(report.plants, 1);
        // Pinned: the sole (rows 0-1) stays where it is mid-contact (frame 12) along the
        // ground, on every frame of the contact; before, it drifted 0.3 per second.
        for f in 5..=20 {
            for v in 0..6 {
                let d = (out[f][3 * v] - out[12][3 * v]).abs() + (out[f][3 * v + 2] - out[12][3 * v + 2]).abs();
                assert!(d < 1e-5, "frame {f}, vertex {v}: {d} from its pin");
            }
        }
        assert!(report.pinned_drift_before > 0.03, "{report:?}");
        assert!(report.pinned_drift_after < 1e-5, "{report:?}");
        assert!((report.sliding_before - 0.3).abs() < 1e-3, "{report:?}");
        assert!(report.sliding_after < 1e-3, "{report:?}");
        // The torso and the hip do not move; heights are kept; far from the contact nothing
        // changes; the leg above the foot moves less than the foot.
        for f in 0..30 {
            let moved = |v: usize| {
                ((out[f][3 * v] - frames[f][3 * v]) as f64).hypot((out[f][3 * v + 2] - frames[f][3 * v + 2]) as f64)
            };
            for v in 21..30 {
                assert_eq!(moved(v), 0.0, "frame {f}, vertex {v}");
            }
            for v in 0..30 {
                assert_eq!(out[f][3 * v + 1], frames[f][3 * v + 1], "heights are kept");
            }
            let foot = moved(0);
            for v in 9..21 {
                assert!(moved(v) <= foot + 1e-6, "frame {f}: vertex {v} moved {} > the foot's {foot}", moved(v));
            }
            if f >= 26 {
                assert!(foot < 1e-9, "frame {f} is far from the contact: {foot}");
            }
        }
        // No pop: the correction changes by at most 0.02 from a frame to the next (its largest
        // is 0.08, from the last contact frame back to the middle one), across the contact's
        // edges too.
        let corr = |f: usize| (out[f][0] - frames[f][0]) as f64;
        assert!((report.largest_correction - 0.08).abs() < 1e-4, "{report:?}");
        for f in 0..29 {
            let step = (corr(f + 1) - corr(f)).abs();
            assert!(step <= 0.02, "frames {f} -> {}: the correction jumps by {step}", f + 1);
        }
        // Deterministic, and an in-place clip on a moving ground: pinned to the ground.
        assert_eq!(c.clean(&frames, 30.0, None).unwrap().0, out);
        let ground: Vec<[f64; 2]> = (0..30).map(|f| [-0.01 * (f as f64 - 5.0), 0.0]).collect();
        let (on_ground, r) = c.clean(&frames, 30.0, Some(&ground)).unwrap();
        assert!(r.sliding_before < 1e-3 && r.largest_correction < 1e-4, "the foot is still on that ground: {r:?}");
        assert!(on_ground.iter().flatten().zip(frames.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-4));
        // Bad input is refused by name.
        let e = c.clean(&frames[..3], 30.0, Some(&ground)).unwrap_err();
        assert!(e.to_string().contains("30 frames for a motion of 3"), "{e}");
        let e = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[vec![99]], FootSkateParams::default()).unwrap_err();
        assert!(e.to_string().contains("vertex 99"), "{e}");
    }

    /// Edge lengths of a ribbon frame, in a fixed order.
    fn edge_lengths(t: &Topology, p: &[f32]) -> Vec<f64> {
        let mut out = Vec::new();
        for tri in t.triangles() {
            for k in 0..3 {
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                out.push((0..3).map(|i| ((p[3 * a + i] - p[3 * b + i]) as f64).powi(2)).sum::<f64>().sqrt());
            }
        }
        out
    }

    /// The shared foot-sliding measure (what `surfcap eval vary` judges) of ribbon frames.
    fn measured_sliding(frames: &[Vec<f32>]) -> f64 {
        let flat: Vec<f32> = frames.iter().flatten().copied().collect();
        let p = ContactParams::default();
        let n = frames[0].len() / 3;
        let c = ground_contacts(&flat, n, 30.0, UpAxis::PosY, &p);
        foot_sliding(&flat, n, 30.0, UpAxis::PosY, &c, &p, &[]).unwrap().mean_speed
    }

    #[test]
    fn by_default_every_step_the_measure_plants_is_pinned() {
        let (t, rest, leg) = ribbon();
        // The skating foot of `skating`, but over its last three planted steps (frames 17-20)
        // it slides 0.1 further per frame on the ground: 3.3 units per second, faster than one
        // body height (2) per second, the lift-off speed trimming would take it for.
        let mut frames = skating(&rest);
        for (f, p) in frames.iter_mut().enumerate().take(21).skip(18) {
            let extra = 0.1 * (f as f32 - 17.0);
            for (r, &y) in ROWS.iter().enumerate().take(8) {
                let s = if r <= 2 { 1.0 } else { (1.1 - y) / 1.0 };
                for c in 0..3 {
                    p[3 * (3 * r + c)] += s * extra;
                }
            }
        }
        let before = measured_sliding(&frames);
        assert!(before > 0.6, "the measure counts the fast steps as planted: {before}");
        let clean = |params: FootSkateParams| {
            FootSkateCleanup::new(&t, &rest, UpAxis::PosY, std::slice::from_ref(&leg), params)
                .unwrap()
                .clean(&frames, 30.0, None)
                .unwrap()
                .0
        };
        // Trimmed at the lift-off speed, the fast steps are left as they are and still slide.
        let trimmed = measured_sliding(&clean(FootSkateParams { lift_speed: Some(1.0), ..FootSkateParams::default() }));
        assert!(trimmed > 0.4, "trimmed: {trimmed}");
        // By default the plants are the measure's: every planted step is pinned.
        let shared = clean(FootSkateParams::default());
        let after = measured_sliding(&shared);
        assert!(after < 1e-3, "pinned as the measure plants: {after} (before {before}, trimmed {trimmed})");
        // Two passes are one pass applied to its own output.
        let once = FootSkateParams { passes: 1, ..FootSkateParams::default() };
        let c1 = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, std::slice::from_ref(&leg), once).unwrap();
        let twice = c1.clean(&c1.clean(&frames, 30.0, None).unwrap().0, 30.0, None).unwrap().0;
        assert_eq!(twice, shared);
        // Settings that make no sense are refused by name.
        let e = FootSkateCleanup::new(
            &t,
            &rest,
            UpAxis::PosY,
            std::slice::from_ref(&leg),
            FootSkateParams { passes: 0, ..once },
        )
        .unwrap_err();
        assert!(e.to_string().contains("0 clean-up passes"), "{e}");
        let e =
            FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[leg], FootSkateParams { lift_speed: Some(0.0), ..once })
                .unwrap_err();
        assert!(e.to_string().contains("lift-off speed of 0"), "{e}");
    }

    /// Mean over frames and edges of |l / l0 - 1| against the frames as given.
    fn mean_strain(t: &Topology, given: &[Vec<f32>], out: &[Vec<f32>]) -> f64 {
        let (mut sum, mut count) = (0.0, 0.0);
        for (a, b) in given.iter().zip(out) {
            for (x, y) in edge_lengths(t, a).into_iter().zip(edge_lengths(t, b)) {
                sum += (y / x - 1.0).abs();
                count += 1.0;
            }
        }
        sum / count
    }

    #[test]
    fn turned_legs_reach_the_pins_and_stretch_less_than_slanted_ones() {
        let (t, rest, leg) = ribbon();
        let frames = skating(&rest);
        let run = |keep_edges: bool| {
            // The hips held: the leg alone reaches the pin, so it bends.
            let p =
                FootSkateParams { keep_edges, move_root: false, stretch_iterations: 0, ..FootSkateParams::default() };
            FootSkateCleanup::new(&t, &rest, UpAxis::PosY, std::slice::from_ref(&leg), p)
                .unwrap()
                .clean(&frames, 30.0, None)
                .unwrap()
        };
        let ((slanted, _), (turned, report)) = (run(false), run(true));
        // Pinned as before: the sole stays where it is mid-contact.
        for f in 5..=20 {
            for v in 0..6 {
                let d =
                    (turned[f][3 * v] - turned[12][3 * v]).abs() + (turned[f][3 * v + 2] - turned[12][3 * v + 2]).abs();
                assert!(d < 1e-5, "frame {f}, vertex {v}: {d} from its pin");
            }
        }
        assert!(report.sliding_after < 1e-3, "{report:?}");
        // The feet (rows 0-2), the hip row and the torso keep their heights; the leg between
        // them turns, so it moves up or down.
        let mut lifted = 0.0f32;
        for f in 0..30 {
            for v in (0..9).chain(21..30) {
                assert_eq!(turned[f][3 * v + 1], frames[f][3 * v + 1], "frame {f}, vertex {v}");
            }
            for v in 9..21 {
                lifted = lifted.max((turned[f][3 * v + 1] - frames[f][3 * v + 1]).abs());
            }
        }
        assert!(lifted > 1e-4, "the leg turned: {lifted}");
        // Slanting stretches the leg's diagonal edges to first order in the pull; turning
        // removes that inside the leg, not next to the held foot and hip rows, where the
        // heights are fixed (measured: mean strain 0.0023 turned, 0.0034 slanted).
        let (s, k) = (mean_strain(&t, &frames, &slanted), mean_strain(&t, &frames, &turned));
        assert!(k < 0.75 * s, "mean strain: turned {k}, slanted {s}");
    }

    #[test]
    fn legs_bent_as_rigidly_as_possible_reach_the_pins_and_stretch_less() {
        let (t, rest, leg) = ribbon();
        let frames = skating(&rest);
        let run = |stretch_iterations: usize| {
            let p = FootSkateParams { move_root: false, stretch_iterations, ..FootSkateParams::default() };
            FootSkateCleanup::new(&t, &rest, UpAxis::PosY, std::slice::from_ref(&leg), p)
                .unwrap()
                .clean(&frames, 30.0, None)
                .unwrap()
        };
        let ((sheared, _), (bent, report)) = (run(0), run(3));
        // Pinned as before: the sole stays where it is mid-contact.
        for f in 5..=20 {
            for v in 0..6 {
                let d = (bent[f][3 * v] - bent[12][3 * v]).abs() + (bent[f][3 * v + 2] - bent[12][3 * v + 2]).abs();
                assert!(d < 1e-5, "frame {f}, vertex {v}: {d} from its pin");
            }
        }
        assert!(report.sliding_after < 1e-3, "{report:?}");
        // The hip row and the torso are held where step 4 put them, and so is the foot (rows
        // 0-2) on frames without pins; on frames with pins (the contact, frames 5-20, and the
        // 5 frames of fading on either side) its ankle row, not pinned, bends with the leg.
        for f in 0..30 {
            let foot = if f <= 25 { 0..0 } else { 0..9 };
            for v in foot.chain(21..30) {
                for c in 0..3 {
                    assert_eq!(bent[f][3 * v + c], sheared[f][3 * v + c], "frame {f}, vertex {v}");
                }
            }
        }
        // Measured: mean strain 0.0021 bent, 0.0034 sheared.
        let (s, b) = (mean_strain(&t, &frames, &sheared), mean_strain(&t, &frames, &bent));
        assert!(b < 0.75 * s, "mean strain: bent {b}, sheared {s}");
        assert_eq!(run(3).0, bent, "deterministic");
    }

    #[test]
    fn pinned_vertices_are_held_by_the_rigid_bending_and_the_rest_of_their_foot_bends() {
        let (t, rest, leg) = ribbon();
        let c = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[leg], FootSkateParams::default()).unwrap();
        // The leg's middle rows (free vertices 9-20) pushed sideways: a sheared leg.
        let mut q = rest.clone();
        for v in 9..21 {
            q[3 * v] += 0.05 * (v / 3 - 2) as f32;
        }
        let (mut free, mut held) = (q.clone(), q.clone());
        c.keep_leg_stretch(&rest, &mut free, &[]);
        c.keep_leg_stretch(&rest, &mut held, &[13]);
        assert_eq!(&held[39..42], &q[39..42], "the held vertex 13 stays");
        assert_ne!(&free[39..42], &q[39..42], "unheld, vertex 13 moves");
        for v in 21..30 {
            assert_eq!(&held[3 * v..3 * v + 3], &q[3 * v..3 * v + 3], "vertex {v} is the hip or the torso");
        }
        // Without a pinned vertex the foot (rows 0-2) is held; with one, its other vertices
        // bend with the leg.
        for v in 0..9 {
            assert_eq!(&free[3 * v..3 * v + 3], &q[3 * v..3 * v + 3], "vertex {v} of a foot without pins");
        }
        let mut sole = q.clone();
        c.keep_leg_stretch(&rest, &mut sole, &[0, 1, 2]);
        assert_eq!(&sole[0..9], &q[0..9], "the pinned sole stays");
        assert!((3..9).any(|v| sole[3 * v..3 * v + 3] != q[3 * v..3 * v + 3]), "the rest of that foot bends");
        let strain = |p: &[f32]| mean_strain(&t, std::slice::from_ref(&rest), &[p.to_vec()]);
        assert!(strain(&held) < strain(&q) && strain(&free) < strain(&q), "both stretch less than the sheared leg");
    }

    #[test]
    fn a_planted_sole_turning_under_the_rigid_fit_is_pinned_vertex_by_vertex() {
        let (t, rest, leg) = ribbon();
        // The skating foot of `skating`, whose rows (0-2) also turn about the up axis around
        // their middle column at 0.02 radians a frame while planted (frames 5-20), the rows
        // above following less up to the hip: the rigid fit (a translation) takes the skate
        // away, not the turn, under which the sole's ends slide 0.06 units a second.
        let mut frames = skating(&rest);
        for (f, p) in frames.iter_mut().enumerate() {
            let turn = 0.02 * (f.clamp(5, 20) as f64 - 5.0);
            for (r, &y) in ROWS.iter().enumerate().take(8) {
                let s = if r <= 2 { 1.0 } else { (1.1 - y as f64) / 1.0 };
                let (sn, cs) = (s * turn).sin_cos();
                for c in 0..3 {
                    let k = 3 * (3 * r + c);
                    let x = 0.1 * c as f64 - 0.1;
                    p[k] = (0.1 + x * cs) as f32 + (p[k] - 0.1 * c as f32);
                    p[k + 2] = (-x * sn) as f32;
                }
            }
        }
        let before = measured_sliding(&frames);
        assert!(before > 0.3, "the turning sole skates: {before}");
        let clean = |vertex_pins: bool| {
            let p = FootSkateParams { vertex_pins, ..FootSkateParams::default() };
            let c = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, std::slice::from_ref(&leg), p).unwrap();
            c.clean(&frames, 30.0, None).unwrap().0
        };
        let rigid = measured_sliding(&clean(false));
        let pinned_out = clean(true);
        let pinned = measured_sliding(&pinned_out);
        assert!(rigid > 0.03, "the rigid fit leaves the turn: {rigid} (before {before})");
        assert!(pinned < 1e-3, "pinned vertex by vertex: {pinned} (rigid only {rigid}, before {before})");
        // The sole's vertices stay where they were on every planted frame.
        for f in 5..=20 {
            for v in 0..6 {
                let d = (pinned_out[f][3 * v] - pinned_out[5][3 * v]).abs()
                    + (pinned_out[f][3 * v + 2] - pinned_out[5][3 * v + 2]).abs();
                assert!(d < 1e-4, "frame {f}, vertex {v}: {d} from where it came down");
            }
        }
    }

    /// Two legs: the ribbon (leg A, rows 0-7, and the torso) and a second leg strip B (rows
    /// 0-7, a separate piece 0.5 away along z). The whole body travels along x at 0.3 units a
    /// second, too fast for its steps: A is planted at frames 0-15, B at frames 10-29 (double
    /// support 10-15), a foot in the air lifted 0.3.
    #[allow(clippy::type_complexity)] // (topology, rest, leg vertex sets, frames): a test fixture
    fn two_legs_travelling() -> (Topology, Vec<f32>, Vec<Vec<u32>>, Vec<Vec<f32>>) {
        let (t, mut rest, leg_a) = ribbon();
        let mut tris = t.triangles().to_vec();
        for r in 0..7u32 {
            for c in 0..2u32 {
                let o = 30;
                let (a, b, d, e) = (o + 3 * r + c, o + 3 * r + c + 1, o + 3 * (r + 1) + c, o + 3 * (r + 1) + c + 1);
                tris.push([a, b, e]);
                tris.push([a, e, d]);
            }
        }
        rest.extend(ROWS.iter().take(8).flat_map(|&y| (0..3).flat_map(move |c| [0.1 * c as f32, y, 0.5])));
        let t = Topology::new(54, tris, None).unwrap();
        let legs = vec![leg_a, (30..54).collect()];
        let frames = (0..30)
            .map(|f| {
                let mut p = rest.clone();
                for q in p.chunks_exact_mut(3) {
                    q[0] += 0.01 * f as f32;
                }
                for (offset, planted) in [(0usize, f <= 15), (30, f >= 10)] {
                    if planted {
                        continue;
                    }
                    for (r, &y) in ROWS.iter().enumerate().take(8) {
                        let s = if r <= 2 { 1.0 } else { (1.1 - y) / 1.0 };
                        for c in 0..3 {
                            p[3 * (offset + 3 * r + c) + 1] += s * 0.3;
                        }
                    }
                }
                p
            })
            .collect();
        (t, rest, legs, frames)
    }

    #[test]
    fn carried_pins_let_the_body_follow_its_steps_without_stretching_the_legs_in_double_support() {
        let (t, rest, legs, frames) = two_legs_travelling();
        let run = |carry_pins: bool| {
            let p = FootSkateParams { carry_pins, ..FootSkateParams::default() };
            FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &legs, p).unwrap().clean(&frames, 30.0, None).unwrap()
        };
        let ((carried, report), (midway, _)) = (run(true), run(false));
        let before = measured_sliding(&frames);
        assert!(before > 0.25, "both feet slide with the body: {before}");
        assert!(report.sliding_after < 1e-3 && measured_sliding(&carried) < 1e-3, "{report:?}");
        // Each planted foot stays where it came down.
        for (foot, range) in [(0usize, 0..=15usize), (30, 10..=29)] {
            let first = *range.start();
            for f in range {
                for v in foot..foot + 6 {
                    let d = (carried[f][3 * v] - carried[first][3 * v]).abs();
                    assert!(d < 1e-4, "frame {f}, vertex {v}: {d} from where it came down");
                }
            }
        }
        // The body follows its steps: every frame is the given one moved as a whole, so no
        // edge changes length and the body travels 0.3 less per second. Pinned where each
        // foot is at its plant's middle frame instead, the two pins are a stride and a slide
        // apart and the legs stretch in double support.
        let stretch = |o: &[Vec<f32>]| {
            (0..30)
                .flat_map(|f| {
                    edge_lengths(&t, &frames[f]).into_iter().zip(edge_lengths(&t, &o[f])).map(|(a, b)| (a - b).abs())
                })
                .fold(0.0, f64::max)
        };
        assert!(stretch(&carried) < 1e-4, "carried: {}", stretch(&carried));
        // (measured: edges change by up to 0.0067 pinned midway)
        assert!(stretch(&midway) > 0.005, "pinned midway: {}", stretch(&midway));
        assert!(report.largest_leg_correction < 1e-4 && report.largest_body_shift > 0.25, "{report:?}");
    }

    #[test]
    fn with_the_root_moved_one_planted_foot_is_pinned_without_stretching_the_leg() {
        let (t, rest, leg) = ribbon();
        let moved = FootSkateParams { move_root: true, ..FootSkateParams::default() };
        let c = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[leg], moved).unwrap();
        let frames = skating(&rest);
        let (out, report) = c.clean(&frames, 30.0, None).unwrap();
        // Pinned as with the hips held.
        for f in 5..=20 {
            for v in 0..6 {
                let d = (out[f][3 * v] - out[12][3 * v]).abs() + (out[f][3 * v + 2] - out[12][3 * v + 2]).abs();
                assert!(d < 1e-5, "frame {f}, vertex {v}: {d} from its pin");
            }
        }
        assert!(report.sliding_after < 1e-3, "{report:?}");
        // One foot planted: the whole body moves with it, so no edge changes length (the hips
        // held, the leg stretched: its edges change by up to 0.009).
        for f in 0..30 {
            let (before, after) = (edge_lengths(&t, &frames[f]), edge_lengths(&t, &out[f]));
            for (e, (a, b)) in before.iter().zip(&after).enumerate() {
                assert!((a - b).abs() < 1e-5, "frame {f}, edge {e}: {a} -> {b}");
            }
            for v in 0..30 {
                assert_eq!(out[f][3 * v + 1], frames[f][3 * v + 1], "heights are kept");
            }
        }
        let held = FootSkateParams { move_root: false, ..FootSkateParams::default() };
        let (bent, _) = FootSkateCleanup::new(&t, &rest, UpAxis::PosY, &[(0..24).collect()], held)
            .unwrap()
            .clean(&frames, 30.0, None)
            .unwrap();
        let stretch = |o: &[Vec<f32>]| {
            (0..30)
                .flat_map(|f| {
                    edge_lengths(&t, &frames[f]).into_iter().zip(edge_lengths(&t, &o[f])).map(|(a, b)| (a - b).abs())
                })
                .fold(0.0, f64::max)
        };
        assert!(stretch(&bent) > 0.005, "the held hips make the leg stretch: {}", stretch(&bent));
        // Nothing pops: the body's shift changes by at most 0.02 from a frame to the next.
        for f in 0..29 {
            let step = ((out[f + 1][3 * 29] - frames[f + 1][3 * 29]) - (out[f][3 * 29] - frames[f][3 * 29])).abs();
            assert!(step <= 0.02, "frames {f} -> {}: the body jumps by {step}", f + 1);
        }
    }
}

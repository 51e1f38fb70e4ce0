//! Root motion recovered from ground contacts: the horizontal travel that an "in place" clip
//! (authored with its root pinned, as most game animations are) would have had, found from the
//! feet's contacts with the ground.
//!
//! The thesis uses foot-contact annotations to align locomotion and jumps in time (6.4-6.5:
//! "temporally aligned ... with dynamic time warping guided with feet contact annotation") and
//! notes that mesh data comes without them (2.5.5, 3.2); like its contacts we take them from the
//! feet's height and speed, here from the vertices themselves:
//!
//! 1. **Contacts** ([`crate::ground_contacts`], shared with the foot contacts and foot
//!    sliding): the ground as the 20th percentile of the per-frame lowest vertex height; the
//!    contact vertices of a step f -> f+1 low at both frames (within
//!    [`ContactParams::height`] x the subject's height above the ground) and nearly still
//!    vertically (moving less than [`ContactParams::vertical_speed`] x the subject's height
//!    per second). Horizontal stillness cannot be asked of an in-place clip: there the planted
//!    foot slides backwards at the walking speed; it is what we measure.
//! 2. **The step's translation** is the one that keeps the planted vertices still: minus the
//!    weighted mean horizontal displacement of a group of contact vertices moving together
//!    (the least-squares translation of the ground-plane Procrustes problem over that group;
//!    vertices weighted by how low they are, the sole more than the ankle). Groups form around
//!    the lowest vertices, within the speed tolerance of each other. Which group is planted is
//!    decided over the whole clip, not per step: a swinging foot often grazes the ground (the
//!    mannequin's on CMU walks passes 2 cm above it) with more low vertices than the planted
//!    foot's rolling heel or toes, but it accelerates and brakes within a few frames, while
//!    the planted feet of successive steps move as the body does. Dynamic programming picks
//!    the chain of groups whose translations change least from step to step (squared change
//!    in units of the tolerance, plus one minus each group's share of the step's contact
//!    weight). Tried first and dropped: the component-wise median of the contacts per step
//!    (recovered 30% of a CMU walk's travel: the grazing foot won half the steps).
//! 3. **Flight** (no contact vertex: the flight phase of a run, a jump) continues the last
//!    step's velocity; before any contact the clip stays put.
//! 4. The steps are integrated into one horizontal offset per frame (frame 0 unmoved) and added
//!    to every vertex of the frame ([`apply_root_motion`]).
//!
//! Only the translation is recovered, not a rotation about the up axis: in-place clips remove
//! the root's travel but keep the body's heading (a turning clip turns on the spot), so the
//! heading is already in the vertices, and fitting a rotation to a pivoting planted foot would
//! add its spin to the whole body a second time.

use surfcap_mesh::UpAxis;

pub use crate::ground_contacts::ContactParams;
use crate::ground_contacts::{GroundContact, GroundContacts, ground_contacts};
use crate::motion_plane_alignment::plane_axes;

/// The recovered root motion of a clip.
#[derive(Debug, Clone, PartialEq)]
pub struct RootMotion {
    /// Per frame, the horizontal offset (along the two ground axes of [`plane_axes`], in the
    /// subject's units) to add to every vertex; frame 0 is `[0, 0]`.
    pub offsets: Vec<[f64; 2]>,
    /// Frame steps with contact vertices (the others continued the last velocity).
    pub contact_steps: usize,
    /// The ground height found (along the up axis, signed as the up axis points).
    pub ground: f64,
}

impl RootMotion {
    /// Net horizontal displacement added between the first and last frames.
    pub fn net_displacement(&self) -> f64 {
        let z = self.offsets.last().copied().unwrap_or([0.0; 2]);
        z[0].hypot(z[1])
    }
}

/// Recovers the root motion of one clip, `positions` being `[frames][n_vertices][3]`.
pub fn root_motion_from_contacts(
    positions: &[f32],
    n_vertices: usize,
    fps: f64,
    up: UpAxis,
    params: &ContactParams,
) -> RootMotion {
    let found = ground_contacts(positions, n_vertices, fps, up, params);
    let (candidates, chosen) = planted_track(positions, n_vertices, fps, up, &found, params);
    let mut offsets = vec![[0.0; 2]; found.frames];
    let mut last = [0.0; 2];
    let mut contact_steps = 0;
    for (f, choice) in chosen.iter().enumerate() {
        if let Some(k) = choice {
            last = candidates[f][*k].step;
            contact_steps += 1;
        }
        offsets[f + 1] = [offsets[f][0] + last[0], offsets[f][1] + last[1]];
    }
    RootMotion { offsets, contact_steps, ground: found.ground }
}

/// The planted contacts of a clip: per frame step f -> f+1, the contact vertices of the group
/// that root motion keeps still (steps 2-3 of the module doc), in increasing vertex order;
/// empty for a step without contact. `contacts` are the clip's [`ground_contacts`]. A swinging
/// foot grazing the ground is left out, a sliding planted foot is kept: what
/// [`crate::foot_sliding`] measures.
pub fn planted_contacts(
    positions: &[f32],
    n_vertices: usize,
    fps: f64,
    up: UpAxis,
    contacts: &GroundContacts,
    params: &ContactParams,
) -> Vec<Vec<GroundContact>> {
    let (candidates, chosen) = planted_track(positions, n_vertices, fps, up, contacts, params);
    chosen
        .iter()
        .enumerate()
        .map(|(f, choice)| {
            let Some(k) = choice else { return Vec::new() };
            let mut members: Vec<GroundContact> =
                candidates[f][*k].members.iter().map(|&i| contacts.steps[f][i as usize]).collect();
            members.sort_by_key(|c| c.vertex);
            members
        })
        .collect()
}

/// The groups of every step and the planted one chosen (steps 2-3 of the module doc).
fn planted_track(
    positions: &[f32],
    n_vertices: usize,
    fps: f64,
    up: UpAxis,
    found: &GroundContacts,
    params: &ContactParams,
) -> (Vec<Vec<Candidate>>, Vec<Option<usize>>) {
    let (u, v, _) = plane_axes(up);
    let per_frame = 3 * n_vertices;
    let frames: Vec<&[f32]> = if per_frame == 0 { Vec::new() } else { positions.chunks_exact(per_frame).collect() };
    let still = params.speed * found.subject_height / fps;
    // Contact vertices of every step: (horizontal displacement, weight).
    let contacts: Vec<Vec<([f64; 2], f64)>> = found
        .steps
        .iter()
        .zip(frames.windows(2))
        .map(|(step, pair)| {
            let (a, b) = (pair[0], pair[1]);
            step.iter()
                .map(|c| {
                    let k = c.vertex as usize;
                    ([(b[3 * k + u] - a[3 * k + u]) as f64, (b[3 * k + v] - a[3 * k + v]) as f64], c.weight)
                })
                .collect()
        })
        .collect();
    let candidates: Vec<Vec<Candidate>> = contacts.iter().map(|c| clusters(c, still)).collect();
    let chosen = smoothest_track(&candidates, still);
    (candidates, chosen)
}

/// One group of contact vertices of a step moving together: the translation that keeps them
/// still, their share of the step's contact weight, and their positions in the step's
/// contact list.
#[derive(Debug, Clone)]
struct Candidate {
    step: [f64; 2],
    share: f64,
    members: Vec<u32>,
}

/// Groups a step's contacts by displacement: the lowest ungrouped vertex (largest weight)
/// seeds a group of the contacts within `tolerance` of its displacement; each group's step is
/// minus its members' weighted mean displacement.
fn clusters(contacts: &[([f64; 2], f64)], tolerance: f64) -> Vec<Candidate> {
    let total: f64 = contacts.iter().map(|c| c.1.max(1e-6)).sum();
    let mut left: Vec<(u32, &([f64; 2], f64))> = contacts.iter().enumerate().map(|(i, c)| (i as u32, c)).collect();
    left.sort_by(|a, b| b.1.1.total_cmp(&a.1.1));
    let mut out = Vec::new();
    while let Some(seed) = left.first().map(|c| c.1.0) {
        let (mut sum, mut weight) = ([0.0; 2], 0.0);
        let mut members = Vec::new();
        left.retain(|&(i, (d, w))| {
            let near = (d[0] - seed[0]).hypot(d[1] - seed[1]) <= tolerance;
            if near {
                let w = w.max(1e-6);
                sum = [sum[0] + w * d[0], sum[1] + w * d[1]];
                weight += w;
                members.push(i);
            }
            !near
        });
        out.push(Candidate { step: [-sum[0] / weight, -sum[1] / weight], share: weight / total, members });
    }
    out
}

/// The planted group of every step with contacts (`None` for steps without): the sequence
/// of groups whose steps change least from one contact step to the next (squared change in
/// units of `tolerance`), each group costing 1 - its share. A foot grazing the ground while
/// it swings accelerates and brakes within a few frames, while the planted feet of successive
/// steps move as the body does; dynamic programming over the groups finds the planted chain
/// even where a grazing foot has more low vertices.
fn smoothest_track(candidates: &[Vec<Candidate>], tolerance: f64) -> Vec<Option<usize>> {
    let mut cost: Vec<Vec<f64>> = Vec::with_capacity(candidates.len());
    let mut from: Vec<Vec<usize>> = Vec::with_capacity(candidates.len());
    let mut previous: Option<usize> = None;
    for (f, cs) in candidates.iter().enumerate() {
        let mut c = Vec::with_capacity(cs.len());
        let mut b = Vec::with_capacity(cs.len());
        for x in cs {
            let (best, arg) = match previous {
                None => (0.0, 0),
                Some(p) => candidates[p]
                    .iter()
                    .zip(&cost[p])
                    .enumerate()
                    .map(|(k, (y, cy))| {
                        let d = (x.step[0] - y.step[0]).hypot(x.step[1] - y.step[1]) / tolerance;
                        (cy + d * d, k)
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .expect("a previous contact step has candidates"),
            };
            c.push(best + 1.0 - x.share);
            b.push(arg);
        }
        cost.push(c);
        from.push(b);
        if !cs.is_empty() {
            previous = Some(f);
        }
    }
    let mut chosen = vec![None; candidates.len()];
    let Some(mut f) = previous else { return chosen };
    let mut k = (0..cost[f].len()).min_by(|&a, &b| cost[f][a].total_cmp(&cost[f][b])).expect("candidates");
    loop {
        chosen[f] = Some(k);
        let back = from[f][k];
        match (0..f).rev().find(|&g| !candidates[g].is_empty()) {
            Some(g) => {
                f = g;
                k = back;
            }
            None => break,
        }
    }
    chosen
}

/// Adds the recovered offsets to every vertex of every frame of `positions`
/// (`[frames][n_vertices][3]`, as many frames as `motion` has offsets).
pub fn apply_root_motion(positions: &mut [f32], n_vertices: usize, up: UpAxis, motion: &RootMotion) {
    let (u, v, _) = plane_axes(up);
    if n_vertices == 0 {
        return;
    }
    for (frame, o) in positions.chunks_exact_mut(3 * n_vertices).zip(&motion.offsets) {
        for p in frame.chunks_exact_mut(3) {
            p[u] += o[0] as f32;
            p[v] += o[1] as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-foot walker at 30 fps walking along +x (or in place when `in_place`), +y up: two
    /// feet of 4x4 sole vertices (0.2 x 0.1) and a body column of 10 vertices, 1.8 tall. Each foot
    /// is planted half of the 1 s cycle (the feet alternate, with double support at the switch)
    /// and swings forward 0.1 above the ground the other half; the body moves at `speed`.
    fn walker(frames: usize, speed: f64, in_place: bool) -> (Vec<f32>, usize, Vec<f64>) {
        let fps = 30.0;
        let mut out = Vec::new();
        let mut truth = Vec::new();
        for f in 0..frames {
            let t = f as f64 / fps;
            let body = speed * t;
            truth.push(body);
            let shift = if in_place { body } else { 0.0 };
            let mut push = |p: [f64; 3]| out.extend([(p[0] - shift) as f32, p[1] as f32, p[2] as f32]);
            for (foot, phase) in [(0usize, 0.0), (1, 0.5)] {
                // Position of the foot: planted for phase in [0, 0.55), swinging otherwise.
                let c = (t + phase).rem_euclid(1.0);
                let cycles = (t + phase).div_euclid(1.0);
                // Each foot advances one stride (the body's travel in a cycle) per cycle.
                let base = (cycles - phase) * speed;
                let (x, y) = if c < 0.55 {
                    (base, 0.0)
                } else {
                    let s = (c - 0.55) / 0.45;
                    (base + speed * s, 0.1 * (std::f64::consts::PI * s).sin())
                };
                let z = if foot == 0 { -0.15 } else { 0.15 };
                for i in 0..4 {
                    for j in 0..4 {
                        push([x + 0.2 * i as f64 / 3.0, y + 0.002 * j as f64, z + 0.1 * j as f64 / 3.0]);
                    }
                }
            }
            for k in 0..10 {
                push([body, 0.9 + 0.1 * k as f64, 0.0]);
            }
        }
        (out, 42, truth)
    }

    #[test]
    fn an_in_place_walker_travels_as_the_walking_one() {
        let (speed, frames) = (1.2, 121);
        let (positions, nv, truth) = walker(frames, speed, true);
        let m = root_motion_from_contacts(&positions, nv, 30.0, UpAxis::PosY, &ContactParams::default());
        assert_eq!(m.offsets.len(), frames);
        assert!(m.ground.abs() < 1e-6, "ground {}", m.ground);
        for (f, (o, t)) in m.offsets.iter().zip(&truth).enumerate() {
            assert!((o[0] - t).abs() < 0.02 * t.max(0.5), "frame {f}: recovered {} for {t}", o[0]);
            assert!(o[1].abs() < 1e-6, "frame {f}: sideways {}", o[1]);
        }
        assert!((m.net_displacement() - truth[frames - 1]).abs() < 0.02 * truth[frames - 1]);
        // Applied, the planted foot stays still: the walker is the travelling one.
        let mut moved = positions.clone();
        apply_root_motion(&mut moved, nv, UpAxis::PosY, &m);
        let (walking, _, _) = walker(frames, speed, false);
        let worst = moved.iter().zip(&walking).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(worst < 0.05, "largest vertex difference {worst}");
    }

    #[test]
    fn a_walker_that_already_travels_gets_no_more_travel_and_flight_keeps_the_velocity() {
        let (positions, nv, _) = walker(61, 1.0, false);
        let m = root_motion_from_contacts(&positions, nv, 30.0, UpAxis::PosY, &ContactParams::default());
        assert!(m.net_displacement() < 0.02, "{}", m.net_displacement());
        // Flight: lift every vertex of frames 30..40 of the in-place walker; the recovered track
        // goes on at the speed it had.
        let (mut positions, nv, truth) = walker(61, 1.0, true);
        for f in 30..40 {
            for p in positions[f * 3 * nv..(f + 1) * 3 * nv].chunks_exact_mut(3) {
                p[1] += 0.5;
            }
        }
        let m = root_motion_from_contacts(&positions, nv, 30.0, UpAxis::PosY, &ContactParams::default());
        assert!(m.contact_steps < 60 - 9);
        assert!((m.offsets[60][0] - truth[60]).abs() < 0.05 * truth[60], "{} vs {}", m.offsets[60][0], truth[60]);
    }

    #[test]
    fn other_up_axes_and_empty_clips() {
        // The walker with +z up (y -> z, z -> -y) recovers the same travel along x.
        let (positions, nv, truth) = walker(61, 1.0, true);
        let turned: Vec<f32> = positions.chunks_exact(3).flat_map(|p| [p[0], -p[2], p[1]]).collect();
        let m = root_motion_from_contacts(&turned, nv, 30.0, UpAxis::PosZ, &ContactParams::default());
        assert!((m.offsets[60][0] - truth[60]).abs() < 0.02 * truth[60]);
        let none = root_motion_from_contacts(&[], 0, 30.0, UpAxis::PosY, &ContactParams::default());
        assert!(none.offsets.is_empty() && none.net_displacement() == 0.0);
    }
}

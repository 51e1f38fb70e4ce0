//! Temporal pre-alignment of a sequence to a reference sequence (thesis 6.4 and 6.5.2: the
//! sequences of one motion type are "temporally aligned to a reference sequence with dynamic
//! time warping guided with feet contact annotation", after Müller 2007), with the DTW of
//! [`crate::dtw`] (thesis 2.5.2, eq. 2.50-2.54).
//!
//! - **Frame cost** of reference frame i against other frame j: the mean per-vertex Euclidean
//!   distance between the two rigidly aligned poses, divided by the median of that distance
//!   over all (i, j) (so the cost is unit-free, as Algorithm 1 scales D by its median), plus
//!   `contact_weight` times the contact mismatch, the mean over the feet of
//!   |c_i - c_j| (contact signals in [0, 1], surfcap-geometry's `foot_contacts`): at weight 1
//!   a frame with every foot planted matched to one with every foot in the air costs as much
//!   as a pose difference of the median.
//! - **Warp**: slope-constrained DTW over the full cost matrix (eq. 2.53-2.54, the first step
//!   read as PAPER-NOTES says: up to p - 1 straight steps may open the path), endpoints pinned
//!   (first frame to first frame, last to last, the boundary condition of 2.5.2). The DP
//!   minimises the summed cost; [`SequenceAlignment::cost`] is that sum over the path length
//!   (eq. 2.50).
//! - **Time map**: for each reference frame i, the mean of the other frames the path matches
//!   to it, a fractional frame time t_i in the other sequence; a moving average of radius
//!   [`TimeAlignmentParams::smoothing`] (edges repeated) takes out the stairs of the path's
//!   straight runs; then t_0 = 0 and t_last = n_other - 1 are pinned. The path is monotone, so
//!   the means are non-decreasing, and so are their moving averages: the map is monotone
//!   without further repair.
//!
//! A sequence re-timed to the reference ([`resample_poses`] at the map's times) has the
//! reference's frame count; [`TimeMap::inverse`] brings anything sampled on the reference's
//! frames (e.g. a variant) back to the other sequence's own timing.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use surfcap_geometry::rotation_log_exp::{exp_rotation, log_rotation};

use crate::dtw::{DtwTables, Slope, dtw_fill};
use crate::error::{Error, Result};

/// Per-frame contact vectors of the reference and of the other sequence (`[frame][foot]`, each
/// in [0, 1], e.g. surfcap-geometry's `FootContacts::by_frame`).
pub type ContactPair<'a> = (&'a [Vec<f64>], &'a [Vec<f64>]);

/// A rigid placement: rotation, then translation.
pub type Placement = (Matrix3<f64>, Vector3<f64>);

/// Parameters of [`align_sequences`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeAlignmentParams {
    /// Slope constraint p of the DTW (`None`: unconstrained). Default 3, as the transitions'
    /// (thesis 2.5.5): one sequence may run at most 3 times as fast as the other anywhere.
    pub slope: Slope,
    /// Weight of the contact mismatch against the median-scaled pose distance (default 1).
    pub contact_weight: f64,
    /// Radius of the moving average over the time map (default 1: three frames).
    pub smoothing: usize,
}

impl Default for TimeAlignmentParams {
    fn default() -> Self {
        TimeAlignmentParams { slope: Some(3), contact_weight: 1.0, smoothing: 1 }
    }
}

/// For each frame of a reference sequence, a fractional frame time in another sequence:
/// non-decreasing, the first 0 and the last the other sequence's last frame (an integer).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeMap {
    times: Vec<f64>,
}

impl TimeMap {
    /// A time map from its times, checked: at least one, finite, non-decreasing, the first 0
    /// and the last a whole frame.
    pub fn new(times: Vec<f64>) -> Result<TimeMap> {
        let bad = |reason: String| Err(Error::TimeMap { reason });
        let (Some(&first), Some(&last)) = (times.first(), times.last()) else { return bad("no times".into()) };
        if let Some(i) = times.iter().position(|t| !t.is_finite()) {
            return bad(format!("time {i} is {}", times[i]));
        }
        if let Some(i) = (1..times.len()).find(|&i| times[i] < times[i - 1]) {
            return bad(format!("time {i} ({}) is before time {} ({})", times[i], i - 1, times[i - 1]));
        }
        if first != 0.0 || last.fract() != 0.0 {
            return bad(format!("runs from {first} to {last}, expected from 0 to a whole frame"));
        }
        Ok(TimeMap { times })
    }

    /// The uniform map of `n_reference` frames onto `n_other` (both at least 1).
    pub fn linear(n_reference: usize, n_other: usize) -> TimeMap {
        let last = n_other.saturating_sub(1) as f64;
        let times = (0..n_reference.max(1))
            .map(|i| if n_reference > 1 { last * i as f64 / (n_reference - 1) as f64 } else { 0.0 })
            .collect();
        TimeMap { times }
    }

    /// One time per reference frame.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Frames of the reference sequence.
    pub fn reference_frames(&self) -> usize {
        self.times.len()
    }

    /// Frames of the other sequence (its last frame + 1).
    pub fn other_frames(&self) -> usize {
        *self.times.last().expect("a time map has times") as usize + 1
    }

    /// The inverse map: for each frame j of the other sequence, the reference time s_j with
    /// t(s_j) = j, t linear between reference frames. Where t stays at j over a stretch of
    /// reference time (the other sequence holding a frame) s_j is the stretch's middle;
    /// where t steps over j, s_j is found on that step. Non-decreasing, from 0 to the
    /// reference's last frame.
    pub fn inverse(&self) -> TimeMap {
        let t = &self.times;
        let n = t.len();
        let (m, last) = (self.other_frames(), (n - 1) as f64);
        if n == 1 {
            return TimeMap { times: vec![0.0; m] };
        }
        // The first reference time where t reaches y (t non-decreasing, linear between frames).
        let first_at = |y: f64| -> f64 {
            let i = t.partition_point(|&x| x < y);
            if i == 0 {
                0.0
            } else if i == n {
                last
            } else {
                (i - 1) as f64 + (y - t[i - 1]) / (t[i] - t[i - 1])
            }
        };
        // The last reference time where t is still at most y.
        let last_at = |y: f64| -> f64 {
            let i = t.partition_point(|&x| x <= y);
            if i == 0 {
                0.0
            } else if i == n {
                last
            } else {
                (i - 1) as f64 + (y - t[i - 1]) / (t[i] - t[i - 1])
            }
        };
        let mut times: Vec<f64> = (0..m).map(|j| 0.5 * (first_at(j as f64) + last_at(j as f64))).collect();
        times[0] = 0.0;
        times[m - 1] = last;
        for j in 1..m {
            times[j] = times[j].max(times[j - 1]);
        }
        TimeMap { times }
    }
}

/// The result of [`align_sequences`].
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceAlignment {
    /// Reference frame -> time in the other sequence.
    pub time_map: TimeMap,
    /// The DTW path as (reference frame, other frame) pairs, from (0, 0) to both last frames.
    pub path: Vec<(usize, usize)>,
    /// Summed frame cost over the path divided by its length (eq. 2.50), in the module doc's
    /// units (1 = the median pose distance).
    pub cost: f64,
    /// The median mean-per-vertex distance that scaled the pose costs (the poses' units).
    pub distance_scale: f64,
}

/// Checks that every frame has `expected` numbers.
fn check_poses(frames: &[&[f32]], which: &'static str, expected: usize) -> Result<()> {
    match frames.iter().position(|f| f.len() != expected) {
        Some(frame) => Err(Error::PoseSize { which, frame, len: frames[frame].len(), expected }),
        None => Ok(()),
    }
}

fn check_contacts(c: &[Vec<f64>], which: &'static str, frames: usize, feet: usize) -> Result<()> {
    if c.len() != frames {
        return Err(Error::ContactSize { which, frame: None, len: c.len(), expected: frames });
    }
    match c.iter().position(|v| v.len() != feet) {
        Some(f) => Err(Error::ContactSize { which, frame: Some(f), len: c[f].len(), expected: feet }),
        None => Ok(()),
    }
}

/// Aligns `other` to `reference` in time (see the module doc). Frames are rigidly aligned
/// poses, `[vertices][3]` each, all of one size; `contacts` are optional per-frame contact
/// vectors of both sequences (one value per foot in [0, 1], as many feet in both). The cost
/// matrix is computed one reference frame per task in parallel; the result does not depend on
/// the thread count.
pub fn align_sequences(
    reference: &[&[f32]],
    other: &[&[f32]],
    contacts: Option<ContactPair<'_>>,
    params: &TimeAlignmentParams,
) -> Result<SequenceAlignment> {
    let (Some(first), false) = (reference.first(), other.is_empty()) else {
        return Err(Error::NoFrames { which: if reference.is_empty() { "reference" } else { "other" } });
    };
    let size = first.len();
    if size == 0 || !size.is_multiple_of(3) {
        return Err(Error::PoseSize { which: "reference", frame: 0, len: size, expected: 3 * (size / 3).max(1) });
    }
    check_poses(reference, "reference", size)?;
    check_poses(other, "other", size)?;
    if let Some((a, b)) = contacts {
        let feet = a.first().map_or(0, Vec::len);
        check_contacts(a, "reference", reference.len(), feet)?;
        check_contacts(b, "other", other.len(), feet)?;
    }
    if !(params.contact_weight >= 0.0 && params.contact_weight.is_finite()) {
        return Err(Error::Parameter {
            name: "contact weight",
            value: params.contact_weight,
            expected: "a finite number >= 0",
        });
    }
    let (n, m, nv) = (reference.len(), other.len(), size / 3);
    let mut d: Vec<f64> = vec![0.0; n * m];
    d.par_chunks_mut(m).zip(reference.par_iter()).for_each(|(row, a)| {
        for (x, b) in row.iter_mut().zip(other) {
            let sum: f64 = a
                .chunks_exact(3)
                .zip(b.chunks_exact(3))
                .map(|(p, q)| {
                    let (dx, dy, dz) = ((p[0] - q[0]) as f64, (p[1] - q[1]) as f64, (p[2] - q[2]) as f64);
                    (dx * dx + dy * dy + dz * dz).sqrt()
                })
                .sum();
            *x = sum / nv as f64;
        }
    });
    let mut sorted = d.clone();
    let mid = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(mid, f64::total_cmp).1;
    let scale = if median > 0.0 { median } else { 1.0 };
    let mismatch = |i: usize, j: usize| -> f64 {
        match contacts {
            Some((a, b)) if !a[i].is_empty() => {
                a[i].iter().zip(&b[j]).map(|(x, y)| (x - y).abs()).sum::<f64>() / a[i].len() as f64
            }
            _ => 0.0,
        }
    };
    let w = params.contact_weight;
    let cost = |i: usize, j: usize| d[i * m + j] / scale + w * mismatch(i, j);
    let mut t = DtwTables::default();
    dtw_fill(n, m, cost, params.slope, &mut t);
    let (total, len) = t.at(n - 1, m - 1);
    if !total.is_finite() {
        return Err(Error::NoWarp { reference: n, other: m, slope: params.slope.unwrap_or(0) });
    }
    let path = t.path_to(n - 1, m - 1);
    let time_map = time_map_from_path(&path, n, m, params.smoothing);
    Ok(SequenceAlignment { time_map, path, cost: total / len as f64, distance_scale: median })
}

/// The time map of a monotone path from (0, 0) to (n - 1, m - 1) (see the module doc).
fn time_map_from_path(path: &[(usize, usize)], n: usize, m: usize, smoothing: usize) -> TimeMap {
    let mut sum = vec![0.0; n];
    let mut count = vec![0usize; n];
    for &(i, j) in path {
        sum[i] += j as f64;
        count[i] += 1;
    }
    let means: Vec<f64> = sum.iter().zip(&count).map(|(s, &c)| s / c.max(1) as f64).collect();
    let r = smoothing as isize;
    let mut times: Vec<f64> = (0..n as isize)
        .map(|i| (-r..=r).map(|k| means[(i + k).clamp(0, n as isize - 1) as usize]).sum::<f64>() / (2 * r + 1) as f64)
        .collect();
    times[0] = 0.0;
    times[n - 1] = (m - 1) as f64;
    TimeMap { times }
}

/// The neighbouring frames and weight of time `t` in `frames` frames, or the error naming it.
fn bracket(index: usize, t: f64, frames: usize) -> Result<(usize, usize, f64)> {
    if !(t >= 0.0 && t <= (frames - 1) as f64) {
        return Err(Error::TimeOutside { index, time: t, frames });
    }
    let a = (t.floor() as usize).min(frames - 1);
    let b = (a + 1).min(frames - 1);
    Ok((a, b, t - a as f64))
}

/// Poses at fractional frame `times` of `frames` (all of one size): linear between the two
/// neighbouring frames (a whole time gives that frame exactly). Output frames are made in
/// parallel.
pub fn resample_poses(frames: &[&[f32]], times: &[f64]) -> Result<Vec<Vec<f32>>> {
    let Some(first) = frames.first() else { return Err(Error::NoFrames { which: "resampled" }) };
    check_poses(frames, "resampled", first.len())?;
    let brackets: Vec<(usize, usize, f64)> =
        times.iter().enumerate().map(|(i, &t)| bracket(i, t, frames.len())).collect::<Result<_>>()?;
    Ok(brackets
        .par_iter()
        .map(|&(a, b, w)| {
            if w == 0.0 {
                return frames[a].to_vec();
            }
            let w = w as f32;
            frames[a].iter().zip(frames[b]).map(|(x, y)| x + w * (y - x)).collect()
        })
        .collect())
}

/// Rigid placements (rotation, translation) at fractional frame `times`: the translation
/// linear between the neighbouring frames, the rotation along the geodesic between them
/// (R_a exp(w log(R_a^T R_b)), with surfcap-geometry's rotation log/exp).
pub fn resample_placements(placements: &[Placement], times: &[f64]) -> Result<Vec<Placement>> {
    if placements.is_empty() {
        return Err(Error::NoFrames { which: "resampled" });
    }
    times
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            let (a, b, w) = bracket(i, t, placements.len())?;
            let ((ra, ta), (rb, tb)) = (placements[a], placements[b]);
            if w == 0.0 {
                return Ok((ra, ta));
            }
            let r = ra * exp_rotation(&(w * log_rotation(&(ra.transpose() * rb))));
            Ok((r, ta + w * (tb - ta)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 12-vertex pose along a curve that never repeats, at phase `s`.
    fn pose(s: f64) -> Vec<f32> {
        (0..12)
            .flat_map(|k| {
                let k = k as f64;
                [(0.3 * s + k).sin(), (0.17 * s * (1.0 + 0.1 * k)).cos(), 0.05 * s + 0.1 * k].map(|x| x as f32)
            })
            .collect()
    }

    /// The other sequence's phase at its frame j: 60 frames over the reference's 40, slow then
    /// fast (a known non-linear re-timing), and its inverse.
    fn g(j: f64) -> f64 {
        39.0 * (j / 59.0).powf(1.4)
    }
    fn g_inv(s: f64) -> f64 {
        59.0 * (s / 39.0).powf(1.0 / 1.4)
    }

    #[test]
    fn a_known_non_linear_re_timing_is_recovered_within_a_frame() {
        let reference: Vec<Vec<f32>> = (0..40).map(|i| pose(i as f64)).collect();
        let other: Vec<Vec<f32>> = (0..60).map(|j| pose(g(j as f64))).collect();
        let r: Vec<&[f32]> = reference.iter().map(Vec::as_slice).collect();
        let o: Vec<&[f32]> = other.iter().map(Vec::as_slice).collect();
        let a = align_sequences(&r, &o, None, &TimeAlignmentParams::default()).unwrap();
        let t = a.time_map.times();
        assert_eq!((t.len(), t[0], t[39], a.time_map.other_frames()), (40, 0.0, 59.0, 60));
        assert!(t.windows(2).all(|w| w[1] >= w[0]));
        for (i, &ti) in t.iter().enumerate() {
            assert!((ti - g_inv(i as f64)).abs() <= 1.0, "reference frame {i}: {ti} vs {}", g_inv(i as f64));
        }
        // The inverse maps the other's frames back onto the reference's times.
        let inv = a.time_map.inverse();
        assert_eq!((inv.reference_frames(), inv.times()[59]), (60, 39.0));
        for (j, &s) in inv.times().iter().enumerate() {
            assert!((s - g(j as f64)).abs() <= 1.0, "other frame {j}: {s} vs {}", g(j as f64));
        }
        // Re-timed to the reference, the other sequence is close to it: much closer than
        // uniformly stretched.
        let err = |frames: &[Vec<f32>]| -> f64 {
            frames
                .iter()
                .zip(&reference)
                .map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs() as f64).sum::<f64>())
                .sum()
        };
        let aligned = err(&resample_poses(&o, t).unwrap());
        let uniform = err(&resample_poses(&o, TimeMap::linear(40, 60).times()).unwrap());
        assert!(aligned < 0.3 * uniform, "aligned {aligned} vs uniform {uniform}");
    }

    #[test]
    fn contacts_steer_the_warp_where_poses_cannot() {
        // Identical poses everywhere: only the contacts say that the other sequence's foot
        // lands at frame 14 where the reference's lands at frame 5.
        let still = vec![0.0f32; 9];
        let r: Vec<&[f32]> = vec![&still; 20];
        let o: Vec<&[f32]> = vec![&still; 20];
        let step = |at: usize| (0..20).map(|f| vec![if f >= at { 1.0 } else { 0.0 }]).collect::<Vec<_>>();
        let (cr, co) = (step(5), step(14));
        let a = align_sequences(&r, &o, Some((&cr, &co)), &TimeAlignmentParams { smoothing: 0, ..Default::default() })
            .unwrap();
        let t = a.time_map.times();
        assert!((t[5] - 14.0).abs() <= 0.5 && t[4] < 14.0, "{t:?}");
        let plain = align_sequences(&r, &o, None, &TimeAlignmentParams::default()).unwrap();
        assert_eq!(plain.time_map, TimeMap::linear(20, 20));
    }

    #[test]
    fn time_maps_invert_and_bad_input_is_named() {
        // A map that holds other frame 2 for three reference frames and skips over frame 4.
        let m = TimeMap::new(vec![0.0, 1.0, 2.0, 2.0, 2.0, 3.0, 5.0, 6.0]).unwrap();
        let inv = m.inverse();
        assert_eq!(inv.times(), &[0.0, 1.0, 3.0, 5.0, 5.5, 6.0, 7.0]);
        assert_eq!(TimeMap::linear(3, 5).inverse(), TimeMap::linear(5, 3));
        assert!(TimeMap::new(vec![0.0, 2.0, 1.0]).unwrap_err().to_string().contains("time 2 (1) is before time 1 (2)"));
        assert!(TimeMap::new(vec![0.0, 1.5]).is_err() && TimeMap::new(vec![]).is_err());
        let a = vec![0.0f32; 6];
        let b = vec![0.0f32; 9];
        let e = align_sequences(&[&a], &[&a, &b], None, &TimeAlignmentParams::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "other frame 1: 9 numbers, expected 6 (3 per vertex, as the reference's first frame)"
        );
        let c = vec![vec![0.0, 1.0]];
        let e = align_sequences(&[&a], &[&a], Some((&c, &[vec![1.0]])), &TimeAlignmentParams::default()).unwrap_err();
        assert_eq!(e.to_string(), "other contacts at frame 0: 1 values, expected 2");
        let long: Vec<&[f32]> = vec![&a; 10];
        let e = align_sequences(&[&a, &a], &long, None, &TimeAlignmentParams::default()).unwrap_err();
        assert!(matches!(e, Error::NoWarp { reference: 2, other: 10, slope: 3 }), "{e}");
        let e = resample_poses(&[&a, &a], &[0.5, 1.5]).unwrap_err();
        assert_eq!(e.to_string(), "time 1.5 (entry 1) is outside the 2 frames given (expected 0 to 1)");
    }

    #[test]
    fn resampling_interpolates_poses_and_placements() {
        let (a, b) = (vec![0.0f32, 1.0, 2.0], vec![2.0f32, 3.0, 4.0]);
        let out = resample_poses(&[&a, &b], &[0.0, 0.25, 1.0]).unwrap();
        assert_eq!(out, vec![a.clone(), vec![0.5, 1.5, 2.5], b.clone()]);
        let r = |angle: f64| exp_rotation(&Vector3::new(0.0, angle, 0.0));
        let p = [(r(0.2), Vector3::new(0.0, 0.0, 0.0)), (r(1.0), Vector3::new(2.0, 0.0, -4.0))];
        let out = resample_placements(&p, &[0.5, 1.0]).unwrap();
        assert!((out[0].0 - r(0.6)).norm() < 1e-12);
        assert!((out[0].1 - Vector3::new(1.0, 0.0, -2.0)).norm() < 1e-12);
        assert_eq!(out[1], p[1]);
    }
}

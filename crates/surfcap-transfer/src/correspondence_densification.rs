//! Temporal correspondence densification (thesis 5.5.1, eq. 5.4-5.10; CVPR 2017 sec. 4.1):
//! from a few user key-pose pairs between two matching training sequences (a source walk and a
//! target walk), a dense frame-to-frame correspondence.
//!
//! 1. **Association cost** (eq. 5.4-5.9). Per body part k, a Bayesian linear regression
//!    `y = M x + e` (eq. 5.4-5.7, [`BayesianLinearRegression`]) is fitted on the key pairs'
//!    part coefficients; `P^k_ij` (eq. 5.8) is the predictive density's kernel of target pose j
//!    at source pose i, and the cost of associating source frame i with target frame j is
//!    `C[i][j] = -log prod_k P^k_ij = sum_k |y_j - mu_i|^2 / (2 v_i)` (eq. 5.9 as a sum of
//!    negative logs). See [`association_costs`].
//! 2. **Dense map** (eq. 5.10). The least-cost path through C (the sum of C over the path's
//!    nodes, as in Müller 2007's DTW) that is continuous (steps (1, 0), (0, 1), (1, 1)),
//!    monotone, has at most `max_straight` (3) consecutive source-only or target-only steps,
//!    and runs through every key pair. See [`constrained_path`].
//!
//! Choices where the thesis is vague, and why:
//!
//! - **Scale of the noise variance.** The thesis sets `s^2 = 0.01` on PCA coefficients whose unit
//!   it never gives (they are in the mesh's length unit times whatever the vertex count does to
//!   the components). So 0.01 is made relative: each part's coefficients are, per sequence and
//!   per side, centred on the sequence's mean pose and divided by one scalar, their RMS over all
//!   frames and coefficients. A part's coefficient then has a mean square of 1, and `s^2 = 0.01`
//!   means a noise standard deviation of 10% of the part's typical coefficient, whatever the
//!   units, the mesh size or the subject's height. One scalar per part (not per coefficient) keeps
//!   the PCA geometry isotropic, which the isotropic noise and predictive covariance of eq. 5.5
//!   and 5.7 assume; whitening each coefficient would blow the near-zero trailing components up
//!   to the size of the first. A part that does not move in a sequence (RMS below 1e-9 of its
//!   coefficients' magnitude) is left at zero: it then costs the same for every pair. Measured
//!   on the KayKit test (`tests/densify_real_data.rs`): the mean frame error moves by under 0.1
//!   frame for `s^2` from 0.001 to 1; one scalar per side for all parts together (a still part
//!   then votes less) was no better on the walks and worse on `Cheer` (0.50 and 0.61 against
//!   0.48 and 0.52 frames).
//! - **Intercept.** Eq. 5.4 has no intercept, which is right only when both sequences' poses are
//!   centred on corresponding mean poses. PCA coefficients are centred over a whole training
//!   set, not over one sequence, and with `Span::Keys` only part of the sequences correspond, so
//!   the source input gets a constant 1 appended (`y = M [x; 1] + e`, the same N(0, 1) prior on
//!   the extra column of M). After the scaling above, the constant is on the coefficients'
//!   scale, so the prior treats it like any other input.
//! - **Predictive variance.** Eq. 5.7's `x^T A^-1 x` vanishes at x = 0 (the sequence's mean pose
//!   after centring) and eq. 5.8 would divide by zero; as PAPER-NOTES.md says, the variance of an
//!   observed y, `x^T A^-1 x + s^2` ([`Predictive::Observation`]), is used.
//! - **Normalisation of eq. 5.8.** `P^k_ij` is the unnormalised Gaussian kernel, as printed: the
//!   `log((2 pi v_i)^(q/2))` term would only add a per-source-frame constant, which, since every
//!   path visits each source frame at least once, changes nothing but how much a path prefers
//!   to repeat a source frame of small variance.
//! - **Path cost.** Eq. 5.10 sums over a map `phi` of the source frames, but the steps the text
//!   allows (source-only, target-only, diagonal) make a path of nodes, several of which may share
//!   a source frame; the cost is the sum over the path's nodes, as in Müller's DTW. All costs are
//!   non-negative, so among paths between the same nodes a shorter (more diagonal) one is
//!   preferred when the poses leave the choice open.
//! - **"At most 3 vertical or horizontal consecutive nodes in a row".** Read as at most
//!   `max_straight` = 3 consecutive *steps* of the same straight kind (a run of 3 source-only
//!   steps visits 4 nodes in a column); the literal "3 nodes" is `max_straight = 2`. A
//!   source-only run followed by a target-only run is two runs: the limit is on each kind. The
//!   limit bounds the local slope of the map between 1/(max_straight + 1) and max_straight + 1
//!   over any stretch, so sequences played up to 4 times faster or slower can still be matched.
//! - **Before the first and after the last key** ([`Span`]). The thesis propagates the keys "to
//!   the rest of the sequence" and defines `phi` on every source frame, which is what
//!   [`Span::Ends`] (the default) does: the path starts at the first frames (0, 0) and ends at
//!   the last frames (F_s - 1, F_t - 1), i.e. the matching sequences correspond end to end.
//!   [`Span::Keys`] only spans the first to the last key pair, for sequences whose ends do not
//!   correspond (a walk that starts from standstill against one already walking).
//! - **Keys** may be given in any order; they are sorted by source frame and repeats dropped.
//!   Key pairs whose order differs between the two sequences cannot lie on a monotone path and
//!   are refused by name, as is a gap between two consecutive keys (or a key and an end) that no
//!   path with the straight-step limit can cross.
//!
//! The dynamic programme runs key to key over the rectangle between consecutive keys only
//! (memory: 12 bytes of back-pointers per cell of those rectangles, at most F_s x F_t), carrying
//! the cost of each arrival state (diagonal, or a source-only or target-only run of length r)
//! across a key, so the path found is the global optimum through all keys, not a chain of local
//! ones. Ties are broken by a fixed order of states, and the cost matrix's rows are computed in
//! parallel with each entry summed over parts in part order: the result is the same whatever
//! the thread count.

use faer::{Mat, MatRef};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_learn::bayesian_linear_regression::{BayesianLinearRegression, Predictive};

use crate::error::{Error, Result};

/// The thesis's noise variance `s^2` of eq. 5.4 (relative to each part's RMS coefficient here).
pub const DEFAULT_NOISE_VARIANCE: f64 = 0.01;
/// The thesis's limit on consecutive source-only or target-only steps.
pub const DEFAULT_MAX_STRAIGHT: usize = 3;

/// Which stretch of the two sequences the dense map covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Span {
    /// From the first frames (0, 0) to the last frames (F_s - 1, F_t - 1) through every key:
    /// the two sequences correspond end to end (the thesis's map of every source frame).
    #[default]
    Ends,
    /// From the first key pair to the last one only: frames outside are left unmatched.
    Keys,
}

/// Options of [`densify`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DensifyOptions {
    /// Noise variance `s^2` of eq. 5.4, on coefficients scaled to an RMS of 1 per part and
    /// sequence (module documentation). Default [`DEFAULT_NOISE_VARIANCE`].
    pub noise_variance: f64,
    /// At most this many consecutive source-only, or target-only, steps. Default
    /// [`DEFAULT_MAX_STRAIGHT`]; 0 allows only diagonal steps.
    pub max_straight: usize,
    /// The stretch the path covers. Default [`Span::Ends`].
    pub span: Span,
}

impl Default for DensifyOptions {
    fn default() -> Self {
        DensifyOptions { noise_variance: DEFAULT_NOISE_VARIANCE, max_straight: DEFAULT_MAX_STRAIGHT, span: Span::Ends }
    }
}

/// A dense correspondence between a source and a target sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Densified {
    /// The path's nodes `(source frame, target frame)`, in order: each step advances the source,
    /// the target or both by one frame.
    pub pairs: Vec<(usize, usize)>,
    /// Sum of the association cost over the path's nodes (eq. 5.10's minimum).
    pub cost: f64,
    /// The key pairs the path runs through, sorted by source frame, repeats dropped.
    pub keys: Vec<(usize, usize)>,
    /// Frames of the source sequence.
    pub source_frames: usize,
    /// Frames of the target sequence.
    pub target_frames: usize,
}

impl Densified {
    /// For each source frame, the mean of the target frames the path pairs it with (one, or a
    /// few after target-only steps); `None` for a source frame outside the path (only with
    /// [`Span::Keys`]).
    pub fn target_of_source(&self) -> Vec<Option<f64>> {
        let mut sum = vec![(0.0f64, 0usize); self.source_frames];
        for &(i, j) in &self.pairs {
            sum[i].0 += j as f64;
            sum[i].1 += 1;
        }
        sum.into_iter().map(|(s, n)| (n > 0).then(|| s / n as f64)).collect()
    }
}

/// Densifies the key pairs between two matching sequences (thesis 5.5.1): the association cost
/// matrix of [`association_costs`], then the constrained least-cost path of
/// [`constrained_path`].
///
/// `source_parts[k]` holds the source sequence's coefficients of part k (F_s x m_k, one row per
/// frame), `target_parts[k]` the target's (F_t x m'_k), the parts in the same order on both
/// sides. `keys` are `(source frame, target frame)` pairs, 0-based.
pub fn densify(
    source_parts: &[Mat<f64>],
    target_parts: &[Mat<f64>],
    keys: &[(usize, usize)],
    opts: &DensifyOptions,
) -> Result<Densified> {
    let costs = association_costs(source_parts, target_parts, keys, opts.noise_variance)?;
    constrained_path(costs.as_ref(), keys, opts.max_straight, opts.span)
}

/// The association cost matrix C (F_s x F_t) of eq. 5.8-5.9: `C[(i, j)]` is `-log P_ij`, the sum
/// over parts of `|y_j - mu_i|^2 / (2 v_i)`, where `mu_i` and `v_i` are the predictive mean and
/// variance at source frame i of part k's Bayesian linear regression fitted on the key pairs
/// (module documentation: coefficients centred and scaled to an RMS of 1 per part and sequence,
/// an intercept, the observation variance). Finite and non-negative; for a heat map of the
/// matching.
pub fn association_costs(
    source_parts: &[Mat<f64>],
    target_parts: &[Mat<f64>],
    keys: &[(usize, usize)],
    noise_variance: f64,
) -> Result<Mat<f64>> {
    if !(noise_variance.is_finite() && noise_variance > 0.0) {
        return Err(Error::Invalid(format!("noise variance {noise_variance}: expected a finite number > 0")));
    }
    let (fs, ft) = check_parts(source_parts, target_parts)?;
    let keys = checked_keys(keys, fs, ft)?;
    // Per part: the predictive mean (F_s x q) and variance (F_s) at every source frame, and the
    // scaled target coefficients (F_t x q).
    let mut models = Vec::with_capacity(source_parts.len());
    for (x, y) in source_parts.iter().zip(target_parts) {
        let xs = scaled(x.as_ref(), true);
        let ys = scaled(y.as_ref(), false);
        let kx = Mat::from_fn(keys.len(), xs.ncols(), |r, c| xs[(keys[r].0, c)]);
        let ky = Mat::from_fn(keys.len(), ys.ncols(), |r, c| ys[(keys[r].1, c)]);
        let blr = BayesianLinearRegression::fit(kx.as_ref(), ky.as_ref(), noise_variance, Predictive::Observation)?;
        let mut mean = Mat::zeros(fs, ys.ncols());
        let mut var = vec![0.0; fs];
        let mut row = vec![0.0; xs.ncols()];
        for i in 0..fs {
            for (c, r) in row.iter_mut().enumerate() {
                *r = xs[(i, c)];
            }
            let (mu, v) = blr.predict(&row)?;
            for (c, m) in mu.into_iter().enumerate() {
                mean[(i, c)] = m;
            }
            var[i] = v;
        }
        models.push((mean, var, ys));
    }
    let rows: Vec<Vec<f64>> = (0..fs)
        .into_par_iter()
        .map(|i| {
            (0..ft)
                .map(|j| {
                    models
                        .iter()
                        .map(|(mean, var, ys)| {
                            let r2: f64 = (0..ys.ncols()).map(|c| (ys[(j, c)] - mean[(i, c)]).powi(2)).sum();
                            0.5 * r2 / var[i]
                        })
                        .sum()
                })
                .collect()
        })
        .collect();
    if let Some((i, j)) = (0..fs).flat_map(|i| (0..ft).map(move |j| (i, j))).find(|&(i, j)| !rows[i][j].is_finite()) {
        return Err(Error::Invalid(format!(
            "association cost of source frame {i} and target frame {j} is {}: expected a finite number (coefficients \
             too large for f64?)",
            rows[i][j]
        )));
    }
    Ok(Mat::from_fn(fs, ft, |i, j| rows[i][j]))
}

/// The least-cost path through a cost matrix `costs` (F_s x F_t; rows are source frames,
/// columns target frames) of eq. 5.10: steps (1, 0), (0, 1) and (1, 1), at most `max_straight`
/// consecutive (1, 0) steps and at most `max_straight` consecutive (0, 1) steps, through every
/// key pair, over the stretch `span` says. Its cost is the sum of `costs` over its nodes.
///
/// Errors name the key pairs at fault: out of range, in a different order in the two
/// sequences, or too far apart in one sequence for the other's frames with the straight-step
/// limit (also between a key and the first or last frames with [`Span::Ends`]).
pub fn constrained_path(
    costs: MatRef<'_, f64>,
    keys: &[(usize, usize)],
    max_straight: usize,
    span: Span,
) -> Result<Densified> {
    let (fs, ft) = (costs.nrows(), costs.ncols());
    if fs == 0 || ft == 0 {
        return Err(Error::Invalid(format!(
            "cost matrix of {fs} source x {ft} target frames: expected at least one frame on each side"
        )));
    }
    for j in 0..ft {
        for i in 0..fs {
            let c = costs[(i, j)];
            if !c.is_finite() {
                return Err(Error::Invalid(format!(
                    "cost of source frame {i} and target frame {j} is {c}: expected a finite number"
                )));
            }
        }
    }
    let keys = checked_keys(keys, fs, ft)?;
    for w in keys.windows(2) {
        let ((a, b), (c, d)) = (w[0], w[1]);
        if d < b {
            return Err(Error::Invalid(format!(
                "key pairs ({a}, {b}) and ({c}, {d}) are in a different order in the two sequences: source frame {c} \
                 comes after {a}, so its target frame must come at or after {b}, not at {d} (a dense map is monotone)"
            )));
        }
    }
    // Waypoints: the keys, and with Span::Ends the first and last frames.
    let mut points: Vec<Waypoint> = keys.iter().map(|&k| Waypoint { at: k, key: true }).collect();
    if span == Span::Ends {
        if points[0].at != (0, 0) {
            points.insert(0, Waypoint { at: (0, 0), key: false });
        }
        if points[points.len() - 1].at != (fs - 1, ft - 1) {
            points.push(Waypoint { at: (fs - 1, ft - 1), key: false });
        }
    }
    // A run never exceeds the larger sequence's steps, so a larger limit changes nothing: clamp
    // it (exact) to keep the state count bounded.
    let s = max_straight.min(fs.max(ft) - 1);
    let states = 2 * s + 1;
    let mut init = vec![f64::INFINITY; states];
    init[0] = costs[(points[0].at.0, points[0].at.1)];
    let mut segments = Vec::with_capacity(points.len().saturating_sub(1));
    for w in points.windows(2) {
        let seg = segment(costs, w[0].at, w[1].at, &init, s);
        if seg.end.iter().all(|c| c.is_infinite()) {
            let (di, dj) = (w[1].at.0 - w[0].at.0, w[1].at.1 - w[0].at.1);
            return Err(Error::Invalid(format!(
                "no path from {} to {} with at most {max_straight} source-only or target-only steps in a row: they are \
                 {di} source and {dj} target frames apart (move a key pair, or raise max_straight)",
                w[0].describe(fs, ft),
                w[1].describe(fs, ft)
            )));
        }
        init = seg.end.clone();
        segments.push(seg);
    }
    let (mut state, cost) = argmin(&init, 0..states);
    // Back-track through the segments, last to first.
    let mut pairs = vec![points[points.len() - 1].at];
    for seg in segments.iter().rev() {
        let (mut li, mut lj) = (seg.h - 1, seg.w - 1);
        while (li, lj) != (0, 0) {
            let bp = &seg.back[li * seg.w + lj];
            if state == 0 {
                state = bp[0] as usize;
                li -= 1;
                lj -= 1;
            } else if state <= s {
                state = if state == 1 { bp[1] as usize } else { state - 1 };
                li -= 1;
            } else {
                state = if state == s + 1 { bp[2] as usize } else { state - 1 };
                lj -= 1;
            }
            pairs.push((seg.from.0 + li, seg.from.1 + lj));
        }
    }
    pairs.reverse();
    Ok(Densified { pairs, cost, keys, source_frames: fs, target_frames: ft })
}

/// A point the path must pass: a user's key pair, or a sequence end with [`Span::Ends`].
#[derive(Debug, Clone, Copy)]
struct Waypoint {
    at: (usize, usize),
    key: bool,
}

impl Waypoint {
    fn describe(&self, fs: usize, ft: usize) -> String {
        let (i, j) = self.at;
        match (self.key, self.at) {
            (true, _) => format!("key pair ({i}, {j})"),
            (false, (0, 0)) => "the first frames (0, 0)".to_string(),
            _ => format!("the last frames ({}, {})", fs - 1, ft - 1),
        }
    }
}

/// The dynamic programme over the rectangle from `from` to `to` (both included).
struct Segment {
    from: (usize, usize),
    h: usize,
    w: usize,
    /// Per cell: the arrival state before a diagonal step, before a first source-only step,
    /// before a first target-only step (longer runs come from the run one shorter).
    back: Vec<[u32; 3]>,
    /// Cost of each arrival state at `to`.
    end: Vec<f64>,
}

/// Arrival states: 0 after a diagonal step (or at the start), `r` in 1..=s after a run of r
/// source-only steps, `s + r` after a run of r target-only steps. `init` is the cost of each
/// state at `from`, which already counts `from`'s own cost.
fn segment(costs: MatRef<'_, f64>, from: (usize, usize), to: (usize, usize), init: &[f64], s: usize) -> Segment {
    let (h, w) = (to.0 - from.0 + 1, to.1 - from.1 + 1);
    let states = 2 * s + 1;
    let mut back = vec![[0u32; 3]; h * w];
    let mut prev = vec![f64::INFINITY; w * states];
    let mut cur = vec![f64::INFINITY; w * states];
    let mut here = vec![f64::INFINITY; states];
    for li in 0..h {
        for lj in 0..w {
            let at = lj * states;
            if (li, lj) == (0, 0) {
                cur[at..at + states].copy_from_slice(init);
                continue;
            }
            let c = costs[(from.0 + li, from.1 + lj)];
            here.fill(f64::INFINITY);
            let bp = &mut back[li * w + lj];
            if li > 0 && lj > 0 {
                let p = &prev[(lj - 1) * states..lj * states];
                let (k, v) = argmin(p, 0..states);
                here[0] = c + v;
                bp[0] = k as u32;
            }
            if li > 0 && s > 0 {
                // Source-only step from (li - 1, lj): a new run after a diagonal or a target run.
                let p = &prev[at..at + states];
                let (k, v) = argmin(p, std::iter::once(0).chain(s + 1..states));
                here[1] = c + v;
                bp[1] = k as u32;
                for r in 2..=s {
                    here[r] = c + p[r - 1];
                }
            }
            if lj > 0 && s > 0 {
                // Target-only step from (li, lj - 1), in the current row.
                let p = &cur[(lj - 1) * states..lj * states];
                let (k, v) = argmin(p, 0..s + 1);
                here[s + 1] = c + v;
                bp[2] = k as u32;
                for r in 2..=s {
                    here[s + r] = c + p[s + r - 1];
                }
            }
            cur[at..at + states].copy_from_slice(&here);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let end = prev[(w - 1) * states..w * states].to_vec();
    Segment { from, h, w, back, end }
}

/// The first state of least cost among `among` (infinite when all are).
fn argmin(costs: &[f64], among: impl Iterator<Item = usize>) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for k in among {
        if costs[k] < best.1 {
            best = (k, costs[k]);
        }
    }
    best
}

/// Checks the parts' shapes and values; returns (F_s, F_t).
fn check_parts(source: &[Mat<f64>], target: &[Mat<f64>]) -> Result<(usize, usize)> {
    if source.is_empty() || source.len() != target.len() {
        return Err(Error::Invalid(format!(
            "{} source parts and {} target parts: expected the same parts (at least one), in the same order, on \
             both sides",
            source.len(),
            target.len()
        )));
    }
    let mut frames = [0; 2];
    for (side, (name, parts)) in [("source", source), ("target", target)].into_iter().enumerate() {
        let f = parts[0].nrows();
        if f == 0 {
            return Err(Error::Invalid(format!("{name} part 0 has no frames: expected at least 1")));
        }
        for (k, m) in parts.iter().enumerate() {
            if m.nrows() != f {
                return Err(Error::Invalid(format!(
                    "{name} part {k} has {} frames: expected {f} as part 0 (one row per frame of the sequence)",
                    m.nrows()
                )));
            }
            if m.ncols() == 0 {
                return Err(Error::Invalid(format!("{name} part {k} has no coefficients: expected at least 1")));
            }
            for c in 0..m.ncols() {
                for i in 0..f {
                    if !m[(i, c)].is_finite() {
                        return Err(Error::Invalid(format!(
                            "{name} part {k}, frame {i}, coefficient {c} is {}: expected a finite number",
                            m[(i, c)]
                        )));
                    }
                }
            }
        }
        frames[side] = f;
    }
    Ok((frames[0], frames[1]))
}

/// Range-checks the keys; returns them sorted by (source, target) frame without repeats.
fn checked_keys(keys: &[(usize, usize)], fs: usize, ft: usize) -> Result<Vec<(usize, usize)>> {
    if keys.is_empty() {
        return Err(Error::Invalid("no key pairs: expected at least one (source frame, target frame) pair".into()));
    }
    for (n, &(i, j)) in keys.iter().enumerate() {
        if i >= fs {
            return Err(Error::Invalid(format!("key pair {n} ({i}, {j}): source frame {i}: expected 0 to {}", fs - 1)));
        }
        if j >= ft {
            return Err(Error::Invalid(format!("key pair {n} ({i}, {j}): target frame {j}: expected 0 to {}", ft - 1)));
        }
    }
    let mut sorted = keys.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    Ok(sorted)
}

/// A part's coefficients centred on the sequence's mean and divided by their RMS (module
/// documentation), with a column of ones appended when `intercept`.
fn scaled(m: MatRef<'_, f64>, intercept: bool) -> Mat<f64> {
    let (f, d) = (m.nrows(), m.ncols());
    let mean: Vec<f64> = (0..d).map(|c| (0..f).map(|i| m[(i, c)]).sum::<f64>() / f as f64).collect();
    let n = (f * d) as f64;
    let centred_ms = (0..d).map(|c| (0..f).map(|i| (m[(i, c)] - mean[c]).powi(2)).sum::<f64>()).sum::<f64>() / n;
    let raw_ms = (0..d).map(|c| (0..f).map(|i| m[(i, c)].powi(2)).sum::<f64>()).sum::<f64>() / n;
    let rms = centred_ms.sqrt();
    // A part still in this sequence: its differences are rounding, not motion; keep it at 0.
    let scale = if rms > 1e-9 * raw_ms.sqrt() && rms > 0.0 { 1.0 / rms } else { 0.0 };
    Mat::from_fn(f, d + usize::from(intercept), |i, c| if c < d { (m[(i, c)] - mean[c]) * scale } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth, non-repeating pose track of `dims` coefficients at time `t`.
    fn pose(t: f64, dims: usize) -> Vec<f64> {
        (0..dims).map(|d| (0.37 * t * (d + 1) as f64 + d as f64).sin() + 0.05 * t).collect()
    }

    fn track(times: &[f64], dims: usize, map: impl Fn(&[f64]) -> Vec<f64>) -> Mat<f64> {
        let rows: Vec<Vec<f64>> = times.iter().map(|&t| map(&pose(t, dims))).collect();
        let cols = rows[0].len();
        Mat::from_fn(times.len(), cols, |i, c| rows[i][c])
    }

    /// Source frames i at time i; target frame j at time warp(j).
    fn warped_pair(fs: usize, ft: usize, warp: impl Fn(f64) -> f64) -> (Vec<Mat<f64>>, Vec<Mat<f64>>) {
        let ts: Vec<f64> = (0..fs).map(|i| i as f64).collect();
        let tt: Vec<f64> = (0..ft).map(|j| warp(j as f64)).collect();
        // Two parts; the target's coefficients are a linear map of the source's (other
        // dimensions, other scale), as for the same motion on another body.
        let src = vec![track(&ts, 3, |p| p.to_vec()), track(&ts, 2, |p| p.to_vec())];
        let tgt = vec![
            track(&tt, 3, |p| vec![2.0 * p[0] - p[1], 0.5 * p[2] + p[0], p[1] - 3.0 * p[2], p[0] + p[1] + p[2]]),
            track(&tt, 2, |p| vec![10.0 * p[0] + 5.0, -20.0 * p[1]]),
        ];
        (src, tgt)
    }

    fn max_run(pairs: &[(usize, usize)]) -> (usize, usize) {
        let (mut src, mut tgt, mut rs, mut rt) = (0, 0, 0, 0);
        for w in pairs.windows(2) {
            let (di, dj) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
            assert!(matches!((di, dj), (1, 0) | (0, 1) | (1, 1)), "step {:?} -> {:?}", w[0], w[1]);
            rs = if (di, dj) == (1, 0) { rs + 1 } else { 0 };
            rt = if (di, dj) == (0, 1) { rt + 1 } else { 0 };
            src = src.max(rs);
            tgt = tgt.max(rt);
        }
        (src, tgt)
    }

    #[test]
    fn a_known_time_warp_is_recovered_exactly() {
        // Target frame j shows the source's time 1.5 j: 31 source frames, 21 target frames.
        let (src, tgt) = warped_pair(31, 21, |j| 1.5 * j);
        let keys = [(0, 0), (9, 6), (21, 14), (30, 20)];
        let d = densify(&src, &tgt, &keys, &DensifyOptions::default()).unwrap();
        // Every node is within half a frame of the warp (the closer of two neighbours), and every
        // even target frame, which shows a source frame exactly, is paired with that frame.
        for &(i, j) in &d.pairs {
            assert!((i as f64 - 1.5 * j as f64).abs() <= 0.5 + 1e-12, "pair ({i}, {j}) is off the warp");
        }
        let exact: Vec<(usize, usize)> = (0..21).filter(|j| j % 2 == 0).map(|j| (3 * j / 2, j)).collect();
        for p in &exact {
            assert!(d.pairs.contains(p), "{p:?} missing from {:?}", d.pairs);
        }
        assert_eq!((d.pairs[0], *d.pairs.last().unwrap()), ((0, 0), (30, 20)));
        let cost: f64 = {
            let c = association_costs(&src, &tgt, &keys, 0.01).unwrap();
            d.pairs.iter().map(|&(i, j)| c[(i, j)]).sum()
        };
        assert!((cost - d.cost).abs() <= 1e-9 * cost.max(1.0), "{cost} vs {}", d.cost);
        assert!(d.cost.is_finite() && d.cost >= 0.0);
    }

    #[test]
    fn the_cost_matrix_is_the_regressions_association_cost_summed_over_parts() {
        let (src, tgt) = warped_pair(12, 10, |j| 1.1 * j);
        let keys = [(0, 0), (5, 4), (11, 9)];
        let c = association_costs(&src, &tgt, &keys, 0.01).unwrap();
        // By hand, part by part, with the library's association_cost on the scaled coefficients.
        let mut want = Mat::<f64>::zeros(12, 10);
        for (x, y) in src.iter().zip(&tgt) {
            let (xs, ys) = (scaled(x.as_ref(), true), scaled(y.as_ref(), false));
            let kx = Mat::from_fn(3, xs.ncols(), |r, cc| xs[(keys[r].0, cc)]);
            let ky = Mat::from_fn(3, ys.ncols(), |r, cc| ys[(keys[r].1, cc)]);
            let b = BayesianLinearRegression::fit(kx.as_ref(), ky.as_ref(), 0.01, Predictive::Observation).unwrap();
            for i in 0..12 {
                for j in 0..10 {
                    let xi: Vec<f64> = (0..xs.ncols()).map(|cc| xs[(i, cc)]).collect();
                    let yj: Vec<f64> = (0..ys.ncols()).map(|cc| ys[(j, cc)]).collect();
                    want[(i, j)] += b.association_cost(&xi, &yj).unwrap();
                }
            }
        }
        assert!((&c - &want).norm_max() < 1e-9 * want.norm_max());
        // Scaling a part's coefficients (another unit) changes nothing.
        let mut tgt10 = tgt.clone();
        tgt10[1] = &tgt10[1] * faer::Scale(1000.0);
        let c10 = association_costs(&src, &tgt10, &keys, 0.01).unwrap();
        assert!((&c - &c10).norm_max() < 1e-6 * c.norm_max());
        // The same to the bit on one thread.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let c1 = pool.install(|| association_costs(&src, &tgt, &keys, 0.01)).unwrap();
        assert!((0..12).all(|i| (0..10).all(|j| c1[(i, j)].to_bits() == c[(i, j)].to_bits())));
        // A key pair costs little; a wrong pairing a lot.
        assert!(c[(5, 4)] < 0.05 * c[(5, 9)], "{} vs {}", c[(5, 4)], c[(5, 9)]);
    }

    #[test]
    fn the_path_runs_through_every_key_even_a_bad_one() {
        let (src, tgt) = warped_pair(31, 21, |j| 1.5 * j);
        // (12, 4) is off the warp (source 12 is target 8): the path must still pass it.
        let keys = [(30, 20), (12, 4), (0, 0), (12, 4)];
        let d = densify(&src, &tgt, &keys, &DensifyOptions::default()).unwrap();
        assert_eq!(d.keys, vec![(0, 0), (12, 4), (30, 20)]);
        for k in &d.keys {
            assert!(d.pairs.contains(k), "key {k:?} not on the path");
        }
        let (rs, rt) = max_run(&d.pairs);
        assert!(rs <= 3 && rt <= 3, "runs {rs} {rt}");
        // Span::Keys from the first to the last key only.
        let keys = [(6, 4), (24, 16)];
        let opts = DensifyOptions { span: Span::Keys, ..Default::default() };
        let d = densify(&src, &tgt, &keys, &opts).unwrap();
        assert_eq!((d.pairs[0], *d.pairs.last().unwrap()), ((6, 4), (24, 16)));
        let map = d.target_of_source();
        assert!(map[5].is_none() && map[25].is_none() && map[6] == Some(4.0));
        for &(i, j) in &d.pairs {
            assert!((i as f64 - 1.5 * j as f64).abs() <= 1.0, "pair ({i}, {j}) is off the warp");
        }
    }

    #[test]
    fn a_target_that_is_a_stretch_of_the_source_is_placed_by_the_keys_span() {
        // The target plays source times 10 to 30 only, so its mean pose is not the source's:
        // the intercept absorbs the offset, and Span::Keys leaves the unmatched ends out.
        let (src, tgt) = warped_pair(41, 21, |j| j + 10.0);
        let keys = [(12, 2), (20, 10), (28, 18)];
        let d = densify(&src, &tgt, &keys, &DensifyOptions { span: Span::Keys, ..Default::default() }).unwrap();
        assert_eq!(d.pairs, (2..=18).map(|j| (j + 10, j)).collect::<Vec<_>>());
        let map = d.target_of_source();
        assert_eq!((map[11], map[12], map[28], map[29]), (None, Some(2.0), Some(18.0), None));
    }

    #[test]
    fn the_straight_step_limit_holds_and_can_be_infeasible() {
        // A cost matrix that pulls the path along row 0 then down the last column: the limit
        // must cut the runs.
        let (fs, ft) = (12, 12);
        let c = Mat::from_fn(fs, ft, |i, j| if i == 0 || j == ft - 1 { 0.0 } else { 10.0 });
        for s in [0, 1, 2, 3, 5] {
            let d = constrained_path(c.as_ref(), &[(0, 0)], s, Span::Ends).unwrap();
            let (rs, rt) = max_run(&d.pairs);
            assert!(rs <= s && rt <= s, "limit {s}: runs {rs} {rt}");
            let sum: f64 = d.pairs.iter().map(|&(i, j)| c[(i, j)]).sum();
            assert_eq!(sum, d.cost);
        }
        // Unlimited: the zero-cost L beats the diagonal (10 nodes at 10); its corner is cut by
        // a diagonal step (ties go to the diagonal), so 22 nodes, not 23.
        let d = constrained_path(c.as_ref(), &[(0, 0)], 100, Span::Ends).unwrap();
        assert_eq!(d.cost, 0.0);
        assert_eq!(d.pairs.len(), 22);
        assert!(d.pairs.contains(&(0, 10)) && d.pairs.contains(&(1, 11)) && !d.pairs.contains(&(0, 11)));
        // s = 3 by hand: the best path alternates 3 straight steps with one diagonal; cheaper
        // than the plain diagonal's 100.
        let d3 = constrained_path(c.as_ref(), &[(0, 0)], 3, Span::Ends).unwrap();
        assert!(d3.cost < 100.0 && d3.cost > 0.0, "{}", d3.cost);
        // Keys 2 source frames apart and 12 target frames apart: 12 target steps with at most 2
        // diagonals in between cannot keep runs of 3.
        let c = Mat::<f64>::zeros(20, 20);
        let e = constrained_path(c.as_ref(), &[(5, 2), (7, 14)], 3, Span::Keys).unwrap_err().to_string();
        assert!(e.contains("no path from key pair (5, 2) to key pair (7, 14)") && e.contains("max_straight"), "{e}");
        // 2 apart against 11 is still feasible: T T T D T T T D T T T.
        assert!(constrained_path(c.as_ref(), &[(5, 2), (7, 13)], 3, Span::Keys).is_ok());
        // With Span::Ends a key too far from the first frames is named against them.
        let e = constrained_path(c.as_ref(), &[(0, 10)], 3, Span::Ends).unwrap_err().to_string();
        assert!(e.contains("from the first frames (0, 0) to key pair (0, 10)"), "{e}");
        let e = constrained_path(c.as_ref(), &[(19, 5)], 3, Span::Ends).unwrap_err().to_string();
        assert!(e.contains("from key pair (19, 5) to the last frames (19, 19)"), "{e}");
    }

    /// Every path from `at` to `end` with the steps and the run limit, by enumeration.
    fn brute_force(
        c: &Mat<f64>,
        at: (usize, usize),
        end: (usize, usize),
        s: usize,
        path: &mut Vec<(usize, usize)>,
        best: &mut f64,
        keys: &[(usize, usize)],
    ) {
        path.push(at);
        if at == end {
            let (rs, rt) = max_run(path);
            if rs <= s && rt <= s && keys.iter().all(|k| path.contains(k)) {
                *best = best.min(path.iter().map(|&(i, j)| c[(i, j)]).sum());
            }
        } else {
            for (di, dj) in [(1, 1), (1, 0), (0, 1)] {
                let next = (at.0 + di, at.1 + dj);
                if next.0 <= end.0 && next.1 <= end.1 {
                    brute_force(c, next, end, s, path, best, keys);
                }
            }
        }
        path.pop();
    }

    #[test]
    fn the_path_is_the_optimum_of_an_exhaustive_search() {
        // Pseudo-random costs (a fixed linear congruential stream), several limits and keys.
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as f64 / (1u64 << 31) as f64
        };
        for (fs, ft) in [(7, 6), (6, 8), (5, 5)] {
            let c = Mat::from_fn(fs, ft, |_, _| next());
            for s in [0, 1, 2, 3] {
                for keys in [vec![(0, 0)], vec![(2, 3)], vec![(1, 1), (4, 3)]] {
                    let mut best = f64::INFINITY;
                    brute_force(&c, (0, 0), (fs - 1, ft - 1), s, &mut Vec::new(), &mut best, &keys);
                    match constrained_path(c.as_ref(), &keys, s, Span::Ends) {
                        Ok(d) => {
                            assert!(
                                (d.cost - best).abs() < 1e-12,
                                "{fs}x{ft} s={s} keys {keys:?}: {} vs {best}",
                                d.cost
                            );
                            let (rs, rt) = max_run(&d.pairs);
                            assert!(rs <= s && rt <= s);
                            let sum: f64 = d.pairs.iter().map(|&(i, j)| c[(i, j)]).sum();
                            assert!((sum - d.cost).abs() < 1e-12);
                        }
                        Err(e) => assert!(best.is_infinite(), "{fs}x{ft} s={s} keys {keys:?}: {e}, but {best} exists"),
                    }
                }
            }
        }
    }

    #[test]
    fn keys_in_a_different_order_and_bad_input_are_refused_by_name() {
        let (src, tgt) = warped_pair(31, 21, |j| 1.5 * j);
        let opts = DensifyOptions::default();
        let e = densify(&src, &tgt, &[(0, 0), (20, 5), (10, 12)], &opts).unwrap_err().to_string();
        assert!(e.contains("key pairs (10, 12) and (20, 5) are in a different order"), "{e}");
        let e = densify(&src, &tgt, &[(0, 0), (31, 5)], &opts).unwrap_err().to_string();
        assert!(e.contains("key pair 1 (31, 5): source frame 31: expected 0 to 30"), "{e}");
        let e = densify(&src, &tgt, &[(3, 21)], &opts).unwrap_err().to_string();
        assert!(e.contains("target frame 21: expected 0 to 20"), "{e}");
        let e = densify(&src, &tgt, &[], &opts).unwrap_err().to_string();
        assert!(e.contains("no key pairs"), "{e}");
        let e = densify(&src, &tgt[..1], &[(0, 0)], &opts).unwrap_err().to_string();
        assert!(e.contains("2 source parts and 1 target parts"), "{e}");
        let mut bad = src.clone();
        bad[1] = Mat::zeros(30, 2);
        let e = densify(&bad, &tgt, &[(0, 0)], &opts).unwrap_err().to_string();
        assert!(e.contains("source part 1 has 30 frames: expected 31"), "{e}");
        let mut nan = tgt.clone();
        nan[0][(3, 1)] = f64::NAN;
        let e = densify(&src, &nan, &[(0, 0)], &opts).unwrap_err().to_string();
        assert!(e.contains("target part 0, frame 3, coefficient 1 is NaN"), "{e}");
        let o = DensifyOptions { noise_variance: 0.0, ..opts };
        assert!(densify(&src, &tgt, &[(0, 0)], &o).unwrap_err().to_string().contains("noise variance 0"));
    }

    #[test]
    fn still_parts_single_frames_and_diagonal_only_paths_stay_finite() {
        // A part that does not move on either side costs nothing and breaks nothing.
        let (mut src, mut tgt) = warped_pair(10, 10, |j| j);
        src.push(Mat::from_fn(10, 3, |_, c| c as f64));
        tgt.push(Mat::from_fn(10, 2, |_, c| 7.0 + c as f64));
        let d = densify(&src, &tgt, &[(4, 4)], &DensifyOptions { max_straight: 0, ..Default::default() }).unwrap();
        assert_eq!(d.pairs, (0..10).map(|i| (i, i)).collect::<Vec<_>>());
        assert!(d.cost.is_finite());
        // One frame against three: two target-only steps.
        let c = Mat::from_fn(1, 3, |_, j| j as f64);
        let d = constrained_path(c.as_ref(), &[(0, 1)], 3, Span::Ends).unwrap();
        assert_eq!(d.pairs, vec![(0, 0), (0, 1), (0, 2)]);
        assert_eq!(d.cost, 3.0);
        // A single key with Span::Keys is the whole path.
        let d = constrained_path(c.as_ref(), &[(0, 1)], 3, Span::Keys).unwrap();
        assert_eq!((d.pairs, d.cost), (vec![(0, 1)], 1.0));
        // Diagonal only and unequal lengths: infeasible, named.
        let c = Mat::<f64>::zeros(4, 5);
        let e = constrained_path(c.as_ref(), &[(0, 0)], 0, Span::Ends).unwrap_err().to_string();
        assert!(e.contains("to the last frames (3, 4)"), "{e}");
        let mut c = Mat::<f64>::zeros(4, 4);
        c[(1, 1)] = f64::INFINITY;
        assert!(constrained_path(c.as_ref(), &[(0, 0)], 3, Span::Ends).unwrap_err().to_string().contains("inf"));
    }
}

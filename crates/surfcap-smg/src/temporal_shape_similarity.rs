//! Temporal shape similarity and the optimal transition between two sequences (Huang et al. 2009,
//! section 3.2, eq. 3-5).
//!
//! With `S(i, j)` the frame-to-frame shape similarity of eq. 2-3 (`crate::shape_similarity`),
//! the similarity of an `n`-frame window of X centred at `i` with one of Y centred at `j` is the
//! triangularly weighted mean (eq. 4)
//!
//! `S'(i, j, n) = sum over k of S(i + k, j + k) w(k)`, `k = -(n-1)/2 ... (n-1)/2`,
//! `w'(k) = min(k + (n+1)/2, -k + (n+1)/2)`, `w = w' / sum w'`,
//!
//! and the transition from X to Y is the window (i, j, n) of least `S'` (eq. 5). Here a window is
//! held by its first frames `(i0, j0)`: with `m = k + (n-1)/2 = 0 ... n-1` the weights are
//! `min(m + 1, n - m)`, whole numbers for even `n` too (PAPER-NOTES: the centre is then half way
//! between two frames). The switch happens at the window's centre (the paper: `x[i] -> y[j] + 1`,
//! no blending): X plays to frame `i0 + ceil(n/2) - 1` and Y starts at `j0 + ceil(n/2)`, which is
//! `i -> j + 1` for odd `n` and the frames either side of the half-way centre for even `n`.
//!
//! Choices the paper leaves open:
//! - The window sizes searched (the "adaptive window") are a range given by the caller; the
//!   default is 3 frames (the least that holds motion: one frame each side of the centre) to one
//!   second of frames.
//! - A sequence with itself (a self-transition, the paper's loops in cyclic motion): the jump
//!   goes back, to a window that ends before the X window starts (`j0 + n <= i0`). A window
//!   matched against itself costs 0 and is no transition, and since `S` is symmetric a forward
//!   jump costs the same as the backward one; only the backward one makes a loop (a forward jump
//!   skips frames the walk could simply play).
//! - Ties go to the smaller window, then the earlier frames (deterministic).

use std::ops::Range;

use crate::error::{Error, Result};

/// The shortest transition window: 3 frames, one each side of the centre, the least that holds
/// motion. A 1-frame window matches a frame with itself and the "transition" it makes maps a
/// frame onto itself, so a walk through it freezes; the paper's windows start at 3.
pub const MIN_WINDOW: usize = 3;

/// The normalised weights `w(m)`, `m = 0 ... n-1`, of an `n`-frame window (eq. 4).
pub fn window_weights(n: usize) -> Vec<f64> {
    let w: Vec<f64> = (0..n).map(|m| (m + 1).min(n - m) as f64).collect();
    let total: f64 = w.iter().sum();
    w.into_iter().map(|x| x / total).collect()
}

/// `S'` of the window of `n` frames starting at global frames `i0` and `j0` (eq. 4), with `s` the
/// row-major `frames x frames` similarity matrix.
pub fn window_similarity(s: &[f64], frames: usize, i0: usize, j0: usize, weights: &[f64]) -> f64 {
    weights.iter().enumerate().map(|(m, w)| s[(i0 + m) * frames + j0 + m] * w).sum()
}

/// The optimal transition from one sequence to another (eq. 5).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Transition {
    /// First frames of the matched windows, within their sequences.
    pub window_x: usize,
    pub window_y: usize,
    /// Window length `n` (the transition length).
    pub length: usize,
    /// `S'` of the window.
    pub cost: f64,
    /// The last frame of X played and the first frame of Y played, within their sequences.
    pub last_x: usize,
    pub first_y: usize,
}

/// The window `(i0, j0, n)` of least `S'` between X (global frames `x`) and Y (global frames
/// `y`) over window lengths `lengths`; `None` when no window fits (sequences shorter than the
/// smallest window, or a sequence with itself too short for two disjoint windows).
pub fn optimal_transition(
    s: &[f64],
    frames: usize,
    x: Range<usize>,
    y: Range<usize>,
    lengths: std::ops::RangeInclusive<usize>,
) -> Result<Option<Transition>> {
    if s.len() != frames * frames {
        return Err(Error::Invalid(format!("a similarity matrix of {} values: expected {frames} x {frames}", s.len())));
    }
    if x.end > frames || y.end > frames || x.start > x.end || y.start > y.end {
        return Err(Error::Invalid(format!("frames {x:?} and {y:?}: expected ranges within 0..{frames}")));
    }
    if *lengths.start() < MIN_WINDOW || lengths.start() > lengths.end() {
        return Err(Error::Invalid(format!(
            "window lengths {lengths:?}: expected a non-empty range of windows of at least {MIN_WINDOW} frames"
        )));
    }
    let same = x == y;
    let mut best: Option<Transition> = None;
    for n in lengths {
        if n > x.len() || n > y.len() {
            break;
        }
        let w = window_weights(n);
        for i0 in x.start..=x.end - n {
            for j0 in y.start..=y.end - n {
                if same && j0 + n > i0 {
                    continue;
                }
                let cost = window_similarity(s, frames, i0, j0, &w);
                if best.is_none_or(|b| cost < b.cost) {
                    let half = n.div_ceil(2);
                    best = Some(Transition {
                        window_x: i0 - x.start,
                        window_y: j0 - y.start,
                        length: n,
                        cost,
                        last_x: i0 - x.start + half - 1,
                        first_y: j0 - y.start + half,
                    });
                }
            }
        }
    }
    Ok(best)
}

/// The `k` best transitions from X to Y: the optimal one of eq. 5, then repeatedly the best
/// window whose switch lies at least `separation` frames away, in X or in Y, from every switch
/// already chosen. `k = 1` is the paper's single transition per connection
/// ([`optimal_transition`]'s answer). More than one is an extension, not in Huang et al.: with
/// one transition per connection a loop can lie where no path between the key frames passes
/// (measured on the CMU mannequin: `surfcap eval smg`), and a second entry point reaches it.
pub fn best_transitions(
    s: &[f64],
    frames: usize,
    x: Range<usize>,
    y: Range<usize>,
    lengths: std::ops::RangeInclusive<usize>,
    k: usize,
    separation: usize,
) -> Result<Vec<Transition>> {
    if k <= 1 {
        return Ok(optimal_transition(s, frames, x, y, lengths)?.into_iter().collect());
    }
    // Validates the arguments and finds the first as eq. 5 does.
    let Some(first) = optimal_transition(s, frames, x.clone(), y.clone(), lengths.clone())? else {
        return Ok(Vec::new());
    };
    // The best window for each switch (last X frame, first Y frame), ties as eq. 5 breaks them.
    let same = x == y;
    let mut best: std::collections::BTreeMap<(usize, usize), Transition> = std::collections::BTreeMap::new();
    for n in lengths {
        if n > x.len() || n > y.len() {
            break;
        }
        let w = window_weights(n);
        let half = n.div_ceil(2);
        for i0 in x.start..=x.end - n {
            for j0 in y.start..=y.end - n {
                if same && j0 + n > i0 {
                    continue;
                }
                let cost = window_similarity(s, frames, i0, j0, &w);
                let t = Transition {
                    window_x: i0 - x.start,
                    window_y: j0 - y.start,
                    length: n,
                    cost,
                    last_x: i0 - x.start + half - 1,
                    first_y: j0 - y.start + half,
                };
                let e = best.entry((t.last_x, t.first_y)).or_insert(t);
                if cost < e.cost {
                    *e = t;
                }
            }
        }
    }
    let mut chosen = vec![first];
    let mut candidates: Vec<Transition> = best.into_values().collect();
    candidates.sort_by(|a, b| {
        a.cost
            .total_cmp(&b.cost)
            .then(a.length.cmp(&b.length))
            .then(a.window_x.cmp(&b.window_x))
            .then(a.window_y.cmp(&b.window_y))
    });
    for t in candidates {
        if chosen.len() >= k {
            break;
        }
        let apart = chosen
            .iter()
            .all(|c| c.last_x.abs_diff(t.last_x) >= separation || c.first_y.abs_diff(t.first_y) >= separation);
        if apart {
            chosen.push(t);
        }
    }
    Ok(chosen)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_triangular_and_sum_to_one() {
        assert_eq!(window_weights(1), vec![1.0]);
        assert_eq!(window_weights(3), vec![0.25, 0.5, 0.25]);
        // Even n: the centre is half way, weights 1 2 2 1 / 6 (PAPER-NOTES, eq. 4).
        let w = window_weights(4);
        assert_eq!(w, vec![1.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0]);
    }

    /// Two sequences of 10 frames in one 20-frame set, with frames 3-5 of X matching frames 6-8
    /// of Y exactly and everything else at distance 1.
    #[test]
    fn the_best_window_and_its_switch_frames_are_found() {
        let f = 20;
        let mut s = vec![1.0; f * f];
        for i in 0..f {
            s[i * f + i] = 0.0;
        }
        for k in 0..3 {
            let (i, j) = (3 + k, 10 + 6 + k);
            s[i * f + j] = 0.0;
            s[j * f + i] = 0.0;
        }
        let t = optimal_transition(&s, f, 0..10, 10..20, 3..=5).unwrap().unwrap();
        assert_eq!((t.window_x, t.window_y, t.length, t.cost), (3, 6, 3, 0.0));
        // Centre x = 4, y = 7: play X to 4, then Y from 8.
        assert_eq!((t.last_x, t.first_y), (4, 8));
        // With itself, the trivial diagonal is excluded.
        let t = optimal_transition(&s, f, 0..10, 0..10, 3..=3).unwrap().unwrap();
        assert!(t.window_y + 3 <= t.window_x && t.cost == 1.0, "{t:?}");
        assert!(optimal_transition(&s, f, 0..4, 0..4, 3..=3).unwrap().is_none(), "no two disjoint windows");
        // k best: the optimal one first, then switches at least 4 frames away.
        let ts = best_transitions(&s, f, 0..10, 10..20, 3..=5, 3, 4).unwrap();
        assert_eq!(ts[0], optimal_transition(&s, f, 0..10, 10..20, 3..=5).unwrap().unwrap());
        assert_eq!(ts.len(), 3);
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            assert!(ts[a].last_x.abs_diff(ts[b].last_x) >= 4 || ts[a].first_y.abs_diff(ts[b].first_y) >= 4);
        }
        assert_eq!(best_transitions(&s, f, 0..10, 10..20, 3..=5, 1, 4).unwrap(), vec![ts[0]]);
        assert!(optimal_transition(&s, f, 0..10, 10..21, 3..=3).unwrap_err().to_string().contains("within 0..20"));
        for short in [1..=5, 2..=2, 0..=3] {
            let e = optimal_transition(&s, f, 0..10, 10..20, short.clone()).unwrap_err().to_string();
            assert!(e.contains("at least 3 frames"), "{short:?}: {e}");
        }
    }
}

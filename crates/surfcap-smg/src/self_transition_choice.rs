//! Self-transitions chosen among the loops a query may play, spanning the sequence's switches
//! and key frames: an extension of eq. 5 (Huang et al. 2009, 3.2-3.3) for sequences that are
//! their own higher-level successors (`X -> X`, the paper's loops in cyclic motion).
//!
//! Eq. 5 takes the window of least `S'` over every `(i, j, n)`. For a self-transition that is
//! the stillest stretch of the clip: on an idle or a punch with held poses, a 3-frame jump
//! between two near-identical frames (on CMU 113_21, standing, `stand:112 -> stand:110`). Two
//! things then go wrong, both measured with `surfcap eval smg`:
//! - the loop is one no query may repeat ([`crate::loop_exclusion`]: shorter than the minimum
//!   length, or below the pose-variation floor), so the sequence has no loop at all;
//! - the loop lies where no path between the key frames passes: a loop helps a path only when
//!   the path can enter the sequence before the loop's switch and leave it after the frame the
//!   loop jumps back to. With one transition per connection (the paper's), a walk entered from
//!   the stand at frame 76 whose loop jumps from 61 to 29 is a dead end for a key frame at 16.
//!
//! So a self-transition is chosen as eq. 5 chooses it, over fewer windows:
//! 1. only windows whose loop may pad time: the frames it plays (`first ..= last`, the frame
//!    jumped to through the last frame played before the jump) are at least the minimum length
//!    and vary at least the floor ([`crate::loop_exclusion::SpanVariation::admits`]);
//! 2. among those, the windows whose loop spans the most of the sequence's **entries** (the
//!    first frames played after the transitions into it, and the start key frames in it: each
//!    must come no later than the loop's last frame, so the path reaches the jump) and
//!    **exits** (the last frames played before the transitions out of it, and the end key
//!    frames in it: each must come no earlier than the frame jumped to, so the path gets there
//!    after the jump). When every one is spanned, every entry of the sequence leads to every
//!    exit, through the loop when the exit comes first;
//! 3. among those, the least `S'` (eq. 4), ties to the smaller window then the earlier frames.
//!
//! With no admissible window, eq. 5's own choice is kept (the plan then reports its loop as
//! excluded).
//!
//! One loop per sequence meets a time only in steps of its length (a spanning loop of the
//! stand is 155 frames), so `k` loops per sequence may be asked: after the spanning one, the
//! admissible windows of least `S'` whose loops lie inside the first's span (so every path
//! through the sequence can play them: they share its frames) and whose switches lie at least
//! `separation` frames from those chosen, as
//! [`crate::temporal_shape_similarity::best_transitions`] separates them.

use std::ops::Range;

use crate::error::Result;
use crate::loop_exclusion::SpanVariation;
use crate::temporal_shape_similarity::{Transition, best_transitions, window_similarity, window_weights};

/// What a self-transition's loop must span, within the sequence: frames the path arrives at
/// (each no later than the loop's last frame) and frames it must get to (each no earlier than
/// the frame the loop jumps to).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Span {
    pub entries: Vec<usize>,
    pub exits: Vec<usize>,
}

impl Span {
    /// How many of the entries and exits a loop jumping from `last` back to `first` spans.
    pub fn spanned(&self, first: usize, last: usize) -> usize {
        self.entries.iter().filter(|&&e| e <= last).count() + self.exits.iter().filter(|&&o| o >= first).count()
    }
}

/// The `k` self-transitions of the sequence at global frames `x` (see the module
/// documentation), with `s` the row-major `frames x frames` similarity, `admissible` the pose
/// variation of `x`'s runs of frames under the loop rule, and `span` in frames within `x`.
#[allow(clippy::too_many_arguments)]
pub fn spanning_self_transitions(
    s: &[f64],
    frames: usize,
    x: Range<usize>,
    lengths: std::ops::RangeInclusive<usize>,
    admissible: &SpanVariation,
    span: &Span,
    k: usize,
    separation: usize,
) -> Result<Vec<Transition>> {
    // Validates the arguments (and gives eq. 5's choice when no loop may pad time).
    let literal = best_transitions(s, frames, x.clone(), x.clone(), lengths.clone(), 1, separation)?;
    // The best window for each switch (last frame played, first frame after the jump).
    let mut best: std::collections::BTreeMap<(usize, usize), Transition> = std::collections::BTreeMap::new();
    for n in lengths {
        if n > x.len() {
            break;
        }
        let w = window_weights(n);
        let half = n.div_ceil(2);
        for i0 in x.start..=x.end - n {
            for j0 in x.start..=x.end - n {
                if j0 + n > i0 {
                    break;
                }
                let (last_x, first_y) = (i0 - x.start + half - 1, j0 - x.start + half);
                if !admissible.admits(first_y, last_x) {
                    continue;
                }
                let cost = window_similarity(s, frames, i0, j0, &w);
                let t = Transition { window_x: i0 - x.start, window_y: j0 - x.start, length: n, cost, last_x, first_y };
                let e = best.entry((last_x, first_y)).or_insert(t);
                if cost < e.cost {
                    *e = t;
                }
            }
        }
    }
    if best.is_empty() {
        return Ok(literal);
    }
    let mut candidates: Vec<(usize, Transition)> =
        best.into_values().map(|t| (span.spanned(t.first_y, t.last_x), t)).collect();
    candidates.sort_by(|(sa, a), (sb, b)| {
        sb.cmp(sa)
            .then(a.cost.total_cmp(&b.cost))
            .then(a.length.cmp(&b.length))
            .then(a.window_x.cmp(&b.window_x))
            .then(a.window_y.cmp(&b.window_y))
    });
    let first = candidates[0].1;
    let mut chosen: Vec<Transition> = vec![first];
    // The others by cost alone, inside the first's span.
    candidates.sort_by(|(_, a), (_, b)| {
        a.cost
            .total_cmp(&b.cost)
            .then(a.length.cmp(&b.length))
            .then(a.window_x.cmp(&b.window_x))
            .then(a.window_y.cmp(&b.window_y))
    });
    for (_, t) in candidates {
        if chosen.len() >= k.max(1) {
            break;
        }
        let inside = first.first_y <= t.first_y && t.last_x <= first.last_x;
        let apart = chosen
            .iter()
            .all(|c| c.last_x.abs_diff(t.last_x) >= separation || c.first_y.abs_diff(t.first_y) >= separation);
        if inside && apart {
            chosen.push(t);
        }
    }
    Ok(chosen)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loop_exclusion::{LoopFilter, LoopRule};
    use crate::path_optimisation::{plan_paths, plan_paths_excluding};
    use crate::surface_motion_graph::{GraphInput, LoopChoice, build_graph, build_graph_choosing};

    /// One 40-frame sequence: frames 0-29 a motion cycling every 12 frames (dissimilarity 0.1
    /// per frame of phase apart, plus 0.01), frames 30-39 one held pose (0.001 apart, the
    /// phase of frame 29 to the others).
    fn cyclic_then_still() -> (Vec<f64>, usize) {
        let n = 40;
        let phase = |f: usize| if f < 30 { f % 12 } else { 29 % 12 };
        let mut s = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                if a == b {
                    continue;
                }
                s[a * n + b] = if a >= 30 && b >= 30 {
                    0.001
                } else {
                    let d = phase(a).abs_diff(phase(b));
                    0.1 * d.min(12 - d) as f64 + 0.01
                };
            }
        }
        (s, n)
    }

    #[test]
    fn the_self_transition_is_an_admissible_loop_spanning_the_key_frames() {
        let (s, n) = cyclic_then_still();
        let seqs: Vec<std::ops::Range<usize>> = std::iter::once(0..n).collect();
        let filter = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        // Eq. 5 alone: 3 frames of the held pose, a loop too short and too still to play.
        let literal = best_transitions(&s, n, 0..n, 0..n, 3..=3, 1, 0).unwrap()[0];
        assert!(literal.window_x >= 30 && literal.window_y >= 30 && literal.cost < 0.01, "{literal:?}");
        let admissible = filter.span_variation(0);
        assert!(!admissible.admits(literal.first_y, literal.last_x));
        // Spanning the start key frame 26 and the end key frame 3: the cycle two periods back.
        let span = Span { entries: vec![26], exits: vec![3] };
        let t = spanning_self_transitions(&s, n, 0..n, 3..=3, &admissible, &span, 1, 0).unwrap();
        assert_eq!(t.len(), 1);
        let t = t[0];
        assert_eq!((t.window_x, t.window_y, t.length, t.last_x, t.first_y), (25, 1, 3, 26, 3), "{t:?}");
        assert!((t.cost - 0.01).abs() < 1e-12 && admissible.admits(t.first_y, t.last_x));
        assert_eq!(span.spanned(t.first_y, t.last_x), 2);
        // Nothing to span: the cheapest admissible loop, one period back.
        let free = spanning_self_transitions(&s, n, 0..n, 3..=3, &admissible, &Span::default(), 1, 0).unwrap()[0];
        assert_eq!(free.last_x - free.first_y + 1, 12, "{free:?}");
        // Three loops: the spanning one, then the cheapest inside it, switches 5 frames apart.
        let three = spanning_self_transitions(&s, n, 0..n, 3..=3, &admissible, &span, 3, 5).unwrap();
        assert_eq!(three.len(), 3);
        assert_eq!(three[0], t);
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let (x, y) = (three[a], three[b]);
            assert!(x.last_x.abs_diff(y.last_x) >= 5 || x.first_y.abs_diff(y.first_y) >= 5, "{three:?}");
        }
        for u in &three[1..] {
            assert!(t.first_y <= u.first_y && u.last_x <= t.last_x && u.cost <= t.cost + 1e-12, "{u:?}");
            assert!(admissible.admits(u.first_y, u.last_x));
        }
        // No admissible loop at all (a minimum longer than the clip): eq. 5's own choice.
        let none = LoopFilter::new(LoopRule { min_frames: 41, variation_floor: 1.0 }, &s, &seqs).unwrap();
        let kept = spanning_self_transitions(&s, n, 0..n, 3..=3, &none.span_variation(0), &span, 1, 0).unwrap();
        assert_eq!(kept, vec![literal]);
    }

    /// The paper's graph joins frame 26 to frame 3 by no path (its loop jumps inside the held
    /// pose); the graph with the loop chosen joins them, and its loop may be played.
    #[test]
    fn key_frames_the_papers_self_transition_leaves_apart_are_joined() {
        let (s, n) = cyclic_then_still();
        let seqs: Vec<std::ops::Range<usize>> = std::iter::once(0..n).collect();
        let ground: Vec<[f64; 2]> = (0..n).map(|f| [0.1 * f as f64, 0.0]).collect();
        let input = GraphInput {
            sequences: &seqs,
            similarity: &s,
            ground: &ground,
            connections: &[(0, 0)],
            key_frames: &[26, 3],
            lengths: 3..=3,
            per_connection: 1,
            separation: 0,
        };
        let paper = build_graph(&input).unwrap();
        let e = plan_paths(&paper, 26, 3, 1000).err().unwrap();
        assert!(e.to_string().contains("no path from frame 26 to frame 3"), "{e}");
        let filter = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        let g = build_graph_choosing(&input, &LoopChoice { filter: &filter, key_pairs: &[(26, 3)], per_sequence: 1 })
            .unwrap();
        assert_eq!(g.transitions.len(), 1);
        let plan = plan_paths_excluding(&g, 26, 3, 1000, &filter).unwrap();
        assert_eq!((plan.walks(), plan.loops_in_graph(), plan.excluded_loops().len()), (1, 1, 0));
    }
}

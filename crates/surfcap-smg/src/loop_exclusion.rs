//! Excluded loops: which elementary cycles of the surface motion graph may pad time.
//!
//! The path optimisation (4.2) repeats loops to meet a target time. A loop of a few frames, or
//! one whose frames are all the same pose, meets any time by stuttering: on the Vlasic crane the
//! self-transition `crane:6 -> crane:4` makes a 3-frame loop of near-still standing, and a 10 s
//! target played it 41 times. Huang et al.'s loops are cyclic motions (walk, jog) and in-place
//! actions (stand, hit) of whole cycles. A loop is excluded, and the plan never repeats it, when
//! - it plays fewer frames per repetition than the **minimum length**
//!   ([`LoopRule::min_frames`], 10 frames by default: a third of a second at 30 fps, shorter
//!   than any human motion cycle; the paper's loops are whole cycles of 20 frames and more), or
//! - its **pose variation** is below the **floor** ([`LoopRule::variation_floor`]): the largest
//!   shape dissimilarity (eq. 2) between any two of the frames it plays, divided by the typical
//!   frame-to-frame dissimilarity of the sequences those frames belong to (the median of eq. 2
//!   between consecutive frames). Dissimilarities of one capture are compared with each other,
//!   so the measure needs no unit and no tuning per data set. The default floor, 1, excludes a
//!   loop whose frames differ among themselves by less than the data usually changes in a
//!   single frame: a pose held still, its differences the capture's noise. On the crane, any 3
//!   consecutive frames span 0.5-1.4 typical steps and any 10 span 0.9-1.9 (the shape
//!   histograms' distances saturate at about twice a step); the still start `crane:4-6` spans
//!   0.54.
//!
//! The frames a loop plays are those its edges add: a sub-sequence from `p` to `q` adds
//! `p+1 ..= q`, a transition adds the frame it switches to
//! ([`crate::surface_motion_graph`]).

use std::ops::Range;

use crate::error::{Error, Result};
use crate::surface_motion_graph::{EdgeKind, SurfaceMotionGraph};

pub use surfcap_mesh::reachability::LoopRule;

/// Why a loop may not pad time.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Exclusion {
    /// It plays fewer frames than the minimum length.
    TooShort { frames: usize, minimum: usize },
    /// Its frames' pose variation is below the floor.
    TooStill { variation: f64, floor: f64 },
}

impl Exclusion {
    /// The reason's name, as in reports (`too_short`, `too_still`).
    pub fn kind(&self) -> &'static str {
        match self {
            Exclusion::TooShort { .. } => "too_short",
            Exclusion::TooStill { .. } => "too_still",
        }
    }
}

impl std::fmt::Display for Exclusion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Exclusion::TooShort { frames, minimum } => {
                write!(f, "{frames} frame(s), shorter than the minimum length of {minimum}")
            }
            Exclusion::TooStill { variation, floor } => write!(
                f,
                "pose variation {variation:.2} typical frame steps, below the pose-variation floor of {floor}"
            ),
        }
    }
}

/// A loop of the graph that may not pad time.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ExcludedLoop {
    /// Its edges, as the path optimisation enumerates them.
    pub edges: Vec<usize>,
    /// The global frames one repetition plays, in order.
    pub frames: Vec<usize>,
    /// Its pose variation (see the module documentation).
    pub variation: f64,
    pub why: Exclusion,
}

/// The global frames one repetition of `cycle` (edge indices) plays.
pub fn loop_frames(g: &SurfaceMotionGraph, cycle: &[usize]) -> Vec<usize> {
    let mut out = Vec::new();
    for &e in cycle {
        let edge = &g.edges[e];
        let (from, to) = (g.nodes[edge.from], g.nodes[edge.to]);
        match edge.kind {
            EdgeKind::Segment { .. } => out.extend(from + 1..=to),
            EdgeKind::Transition { .. } => out.push(to),
        }
    }
    out
}

/// Judges loops against a [`LoopRule`] with the shape dissimilarities of the frames.
pub struct LoopFilter<'a> {
    rule: LoopRule,
    similarity: &'a [f64],
    frames: usize,
    sequences: &'a [Range<usize>],
    /// Median dissimilarity between consecutive frames, per sequence (0 for a 1-frame one).
    steps: Vec<f64>,
}

impl<'a> LoopFilter<'a> {
    /// `similarity` is the `frames x frames` matrix of eq. 2 the graph was built from, and
    /// `sequences` its sequences' global frames.
    pub fn new(rule: LoopRule, similarity: &'a [f64], sequences: &'a [Range<usize>]) -> Result<Self> {
        let frames = sequences.iter().map(|s| s.end).max().unwrap_or(0);
        if similarity.len() < frames * frames || !(rule.variation_floor.is_finite() && rule.variation_floor >= 0.0) {
            return Err(Error::Invalid(format!(
                "excluded loops: a similarity of {} numbers for {frames} frames and a pose-variation floor of {}: \
                 expected {frames} x {frames} numbers and a floor >= 0",
                similarity.len(),
                rule.variation_floor
            )));
        }
        let n = (similarity.len() as f64).sqrt().round() as usize;
        let steps = sequences
            .iter()
            .map(|s| {
                let mut d: Vec<f64> = (s.start..s.end.saturating_sub(1)).map(|f| similarity[f * n + f + 1]).collect();
                d.sort_by(f64::total_cmp);
                if d.is_empty() { 0.0 } else { d[d.len() / 2] }
            })
            .collect();
        Ok(LoopFilter { rule, similarity, frames: n, sequences, steps })
    }

    pub fn rule(&self) -> LoopRule {
        self.rule
    }

    /// The pose variation of the frames `played`: their largest pairwise dissimilarity over
    /// the median frame-to-frame dissimilarity of their sequences (infinite when those never
    /// change, so a floor never excludes them by this measure).
    pub fn variation(&self, played: &[usize]) -> f64 {
        let n = self.frames;
        let mut range: f64 = 0.0;
        for (i, &a) in played.iter().enumerate() {
            for &b in &played[i + 1..] {
                range = range.max(self.similarity[a * n + b]);
            }
        }
        let mut steps: Vec<f64> = played
            .iter()
            .filter_map(|&f| self.sequences.iter().position(|s| s.contains(&f)))
            .map(|k| self.steps[k])
            .collect();
        steps.sort_by(f64::total_cmp);
        steps.dedup();
        let step = if steps.is_empty() { 0.0 } else { steps[steps.len() / 2] };
        if step > 0.0 { range / step } else { f64::INFINITY }
    }

    /// The pose variation of every run of consecutive frames of sequence `k` (the frames a
    /// self-transition's loop plays: `first ..= last` within the sequence), as a table read in
    /// constant time ([`SpanVariation::of`]): the same measure as [`LoopFilter::variation`],
    /// the largest dissimilarity of a run built from those of its two shorter runs.
    pub fn span_variation(&self, k: usize) -> SpanVariation {
        let s = self.sequences.get(k).cloned().unwrap_or(0..0);
        let (len, n) = (s.len(), self.frames);
        let mut range = vec![0.0; len * len];
        for d in 1..len {
            for a in 0..len - d {
                let b = a + d;
                let here = self.similarity[(s.start + a) * n + s.start + b];
                range[a * len + b] = here.max(range[(a + 1) * len + b]).max(range[a * len + b - 1]);
            }
        }
        SpanVariation { len, range, step: self.steps.get(k).copied().unwrap_or(0.0), rule: self.rule }
    }

    /// Why `cycle` may not pad time, or `None` when it may.
    pub fn judge(&self, g: &SurfaceMotionGraph, cycle: &[usize]) -> Option<ExcludedLoop> {
        let frames = loop_frames(g, cycle);
        let variation = self.variation(&frames);
        let why = if frames.len() < self.rule.min_frames {
            Exclusion::TooShort { frames: frames.len(), minimum: self.rule.min_frames }
        } else if variation < self.rule.variation_floor {
            Exclusion::TooStill { variation, floor: self.rule.variation_floor }
        } else {
            return None;
        };
        Some(ExcludedLoop { edges: cycle.to_vec(), frames, variation, why })
    }

    /// The loops that may pad time, and those excluded with why.
    pub fn partition(&self, g: &SurfaceMotionGraph, loops: Vec<Vec<usize>>) -> (Vec<Vec<usize>>, Vec<ExcludedLoop>) {
        let mut kept = Vec::new();
        let mut excluded = Vec::new();
        for c in loops {
            match self.judge(g, &c) {
                None => kept.push(c),
                Some(x) => excluded.push(x),
            }
        }
        (kept, excluded)
    }
}

/// The pose variation of the runs of consecutive frames of one sequence
/// ([`LoopFilter::span_variation`]).
pub struct SpanVariation {
    len: usize,
    /// Largest dissimilarity among frames `a ..= b`, at `a * len + b`.
    range: Vec<f64>,
    step: f64,
    rule: LoopRule,
}

impl SpanVariation {
    /// The pose variation of frames `first ..= last` (within the sequence): infinite when the
    /// sequence never changes, as [`LoopFilter::variation`] has it; 0 for a run outside it.
    pub fn of(&self, first: usize, last: usize) -> f64 {
        if first > last || last >= self.len {
            return 0.0;
        }
        let r = self.range[first * self.len + last];
        if self.step > 0.0 { r / self.step } else { f64::INFINITY }
    }

    /// Whether the loop playing frames `first ..= last` may pad time: the rule's minimum
    /// length and pose-variation floor, as [`LoopFilter::judge`] applies them.
    pub fn admits(&self, first: usize, last: usize) -> bool {
        first <= last && last - first + 1 >= self.rule.min_frames && self.of(first, last) >= self.rule.variation_floor
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface_motion_graph::Edge;

    /// One sequence of `n` frames whose consecutive frames differ by 1 except inside `still`
    /// (0.01 there), every pair by the sum of its steps; a transition `to <- from` closing a
    /// loop.
    fn case(
        n: usize,
        still: Range<usize>,
        from: usize,
        to: usize,
    ) -> (SurfaceMotionGraph, Vec<f64>, Vec<Range<usize>>) {
        let step = |f: usize| if still.contains(&f) && still.contains(&(f + 1)) { 0.01 } else { 1.0 };
        let mut s = vec![0.0; n * n];
        for a in 0..n {
            for b in a + 1..n {
                let d: f64 = (a..b).map(step).sum();
                s[a * n + b] = d;
                s[b * n + a] = d;
            }
        }
        let seg = |from, to, frames| Edge {
            from,
            to,
            kind: EdgeKind::Segment { sequence: 0 },
            frames,
            distance: 0.0,
            cost: 0.0,
        };
        // Nodes: 0, to, from, n - 1.
        let nodes = vec![0, to, from, n - 1];
        let edges = vec![
            seg(0, 1, to),
            seg(1, 2, from - to),
            seg(2, 3, n - 1 - from),
            Edge {
                from: 2,
                to: 1,
                kind: EdgeKind::Transition { from_sequence: 0, to_sequence: 0, window: 3 },
                frames: 1,
                distance: 0.0,
                cost: 0.1,
            },
        ];
        let g = SurfaceMotionGraph { nodes, edges, transitions: Vec::new(), missing: Vec::new() };
        (g, s, std::iter::once(0..n).collect())
    }

    #[test]
    fn a_short_loop_is_excluded_by_its_length() {
        let (g, s, seqs) = case(30, 0..0, 6, 4);
        let f = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        assert_eq!(loop_frames(&g, &[1, 3]), vec![5, 6, 4]);
        let x = f.judge(&g, &[1, 3]).unwrap();
        assert_eq!(x.why, Exclusion::TooShort { frames: 3, minimum: 10 });
        assert!(x.why.to_string().contains("minimum length of 10"), "{}", x.why);
        // Every loop allowed: kept.
        let all = LoopFilter::new(LoopRule::all(), &s, &seqs).unwrap();
        assert!(all.judge(&g, &[1, 3]).is_none());
    }

    #[test]
    fn a_long_loop_of_a_held_pose_is_excluded_by_its_variation() {
        // Frames 5..=25 hold one pose (20 of the 79 steps): a 20-frame loop over them barely
        // varies.
        let (g, s, seqs) = case(80, 5..26, 24, 5);
        let f = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        let x = f.judge(&g, &[1, 3]).unwrap();
        assert_eq!(x.frames.len(), 20);
        assert!(matches!(x.why, Exclusion::TooStill { variation, .. } if variation < 0.5), "{:?}", x.why);
        // The same loop over moving frames is kept.
        let (g, s, seqs) = case(80, 0..0, 24, 5);
        let f = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        assert!(f.judge(&g, &[1, 3]).is_none());
        let (kept, excluded) = f.partition(&g, vec![vec![1, 3]]);
        assert_eq!((kept.len(), excluded.len()), (1, 0));
    }

    /// The table of runs gives every run's variation as the loop filter measures the frames.
    #[test]
    fn span_variation_agrees_with_the_filter() {
        let (_, s, seqs) = case(30, 8..20, 6, 4);
        let f = LoopFilter::new(LoopRule::default(), &s, &seqs).unwrap();
        let t = f.span_variation(0);
        for first in 0..30 {
            for last in first..30 {
                let played: Vec<usize> = (first..=last).collect();
                assert!((t.of(first, last) - f.variation(&played)).abs() < 1e-12, "{first}..={last}");
                let long = last - first + 1 >= 10;
                assert_eq!(t.admits(first, last), long && f.variation(&played) >= 1.0, "{first}..={last}");
            }
        }
        assert_eq!((t.of(5, 4), t.of(3, 30)), (0.0, 0.0));
    }

    #[test]
    fn a_bad_floor_or_similarity_is_refused() {
        let (_, s, seqs) = case(10, 0..0, 6, 4);
        let e = LoopFilter::new(LoopRule { min_frames: 3, variation_floor: f64::NAN }, &s, &seqs).err().unwrap();
        assert!(e.to_string().contains("pose-variation floor"), "{e}");
        let e = LoopFilter::new(LoopRule::default(), &s[..50], &seqs).err().unwrap();
        assert!(e.to_string().contains("10 x 10"), "{e}");
    }
}

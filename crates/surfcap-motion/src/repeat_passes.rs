//! Repeats in a walk (thesis 6.1: endless motion that does not repeat itself):
//! which play of its frames each run of original frames is, so that a walk looping over the
//! same captured frames can show a substitute (a learned variant of those frames, thesis 6.6)
//! on each repetition instead of the same poses again.
//!
//! Readings (ours; the thesis motivates variation by synthesis but does not say how a walk picks
//! its variants):
//! - A run is a maximal stretch of the walk joined by successive-frame steps (between two
//!   transitions). It is played whole from one pass, so a substitute never switches inside a run
//!   (a substitute deviates a little from its frames: switching mid-run would jump).
//! - The pass of a run is 0 when none of its frames was shown earlier in the walk, else one more
//!   than the largest pass of the earlier runs that share a frame with it. Two plays of one
//!   frame thus always have different passes: a walk playing `walk:10..40` five times plays
//!   passes 0, 1, 2, 3, 4, and a run that overlaps two earlier ones does not reuse either's pass.
//! - A transition blends the frames of the passes of the runs it leaves and enters: its source
//!   segment (which may reach past the run's last frame) from the leaving run's pass, its
//!   destination segment from the entering run's, so each junction meets the poses actually
//!   shown on either side.

/// A substitute for a captured frame: its positions (the subject's vertex count, in the
/// captured frame's coordinates, i.e. following about the same path) and the number of the
/// variant it comes from, recorded per output frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Substitute<'a> {
    pub variant: u32,
    pub positions: &'a [f32],
}

/// Where a walk's frames come from on each pass.
pub trait FrameSource {
    /// What to show for global frame `frame` on pass `pass` of its run (0: the first time the
    /// walk shows these frames); `None` shows the captured frame.
    fn substitute(&self, pass: usize, frame: u32) -> Option<Substitute<'_>>;
}

/// Every frame as captured, on every pass: a walk played as Algorithm 3 has it.
#[derive(Debug, Clone, Copy, Default)]
pub struct Captured;

impl FrameSource for Captured {
    fn substitute(&self, _: usize, _: u32) -> Option<Substitute<'_>> {
        None
    }
}

/// How one output frame of a walk was played.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FramePlay {
    /// For an original frame, how many times the walk showed this captured frame before (0 the
    /// first time); 0 for a blended frame.
    pub earlier: u32,
    /// The variant shown for the frame's `FrameMix::from` and `FrameMix::to` (the same for an
    /// original frame); `None` for the captured frame.
    pub from: Option<u32>,
    pub to: Option<u32>,
}

impl FramePlay {
    /// An original frame shown before in the walk.
    pub fn is_repeat(&self) -> bool {
        self.earlier > 0
    }

    /// A frame made (at least in part) from a substitute.
    pub fn is_variant(&self) -> bool {
        self.from.is_some() || self.to.is_some()
    }
}

/// The pass of every node of `walk` (see the module's readings); `is_transition(k)` says
/// whether the step from `walk[k]` to `walk[k + 1]` is a transition (which ends a run).
pub fn run_passes(walk: &[u32], is_transition: impl Fn(usize) -> bool) -> Vec<usize> {
    let mut last_pass: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    let mut out = Vec::with_capacity(walk.len());
    let mut start = 0;
    for k in 1..=walk.len() {
        if k < walk.len() && !is_transition(k - 1) {
            continue;
        }
        let run = &walk[start..k];
        let pass = run.iter().filter_map(|f| last_pass.get(f)).map(|p| p + 1).max().unwrap_or(0);
        for &f in run {
            last_pass.insert(f, pass);
        }
        out.extend(std::iter::repeat_n(pass, run.len()));
        start = k;
    }
    out
}

/// For every node of `walk`, how many times the walk showed that frame before.
pub fn earlier_plays(walk: &[u32]) -> Vec<u32> {
    let mut seen: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    walk.iter()
        .map(|&f| {
            let n = seen.entry(f).or_insert(0);
            *n += 1;
            *n - 1
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk over frames `runs`, each run ending with a transition.
    fn walk_of(runs: &[std::ops::RangeInclusive<u32>]) -> (Vec<u32>, Vec<usize>) {
        let mut walk = Vec::new();
        let mut breaks = Vec::new();
        for r in runs {
            walk.extend(r.clone());
            breaks.push(walk.len() - 1);
        }
        (walk, breaks)
    }

    #[test]
    fn a_loop_gets_a_new_pass_each_time_and_overlaps_never_share_a_pass() {
        let (walk, breaks) = walk_of(&[10..=40, 10..=40, 10..=40]);
        let passes = run_passes(&walk, |k| breaks.contains(&k));
        assert_eq!(passes[0], 0);
        assert_eq!(passes[31], 1);
        assert_eq!(passes[62], 2);
        assert!(passes[..31].iter().all(|&p| p == 0) && passes[62..].iter().all(|&p| p == 2));
        // Overlaps: B shares frames with A, C only with B: C must not play B's pass again.
        let (walk, breaks) = walk_of(&[0..=10, 8..=20, 18..=30, 100..=105]);
        let passes = run_passes(&walk, |k| breaks.contains(&k));
        let at = |node: usize| passes[node];
        assert_eq!((at(0), at(11), at(24), at(37)), (0, 1, 2, 0));
        let earlier = earlier_plays(&walk);
        assert_eq!(earlier.iter().filter(|&&e| e > 0).count(), 3 + 3);
        assert_eq!(earlier[11..14], [1, 1, 1]);
        assert_eq!(earlier[14], 0);
        // Without transitions the walk is one run.
        assert!(run_passes(&[1, 2, 3], |_| false).iter().all(|&p| p == 0));
        assert!(run_passes(&[], |_| true).is_empty());
    }
}

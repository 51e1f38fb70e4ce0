//! The one error type of surfcap-motion.

/// What can fail in the motion layer: playing a walk (a step that is not an edge of the graph, a
/// transition whose Blend fails), reading a walk model back from its cached rows, following a
/// path (thesis 3.5.1) and the timed-walk searches (thesis 3.5.2). Variants carry the frames,
/// rows and counts they name; a failed Poisson solve keeps the geometry error as its source.
#[derive(Debug, Clone, thiserror::Error)]
pub enum Error {
    /// A walk without a single node.
    #[error("the walk has no nodes")]
    EmptyWalk,
    /// Step `at` (frame `from` -> `to`) is neither successive frames nor a transition of the
    /// graph.
    #[error(
        "step {at} of the walk, frame {from} -> {to}, is neither a successive-frame step nor a transition of the graph"
    )]
    NotAnEdge { at: usize, from: u32, to: u32 },
    /// A substitute frame (a variant played in a captured frame's stead) whose size is not the
    /// subject's.
    #[error(
        "variant {variant} of frame {frame} (played on pass {pass}) has {numbers} numbers, expected {expected} (3 per vertex of the subject)"
    )]
    SubstituteSize { frame: String, pass: usize, variant: u32, numbers: usize, expected: usize },
    /// The Blend of a transition failed (its Poisson system, the source: not repeated here, as
    /// error printers show the chain).
    #[error("blending a transition")]
    Poisson(#[from] surfcap_geometry::Error),

    /// Walk-model rows: a count of numbers that is not a multiple of 3.
    #[error("{numbers} numbers: expected rows of 3")]
    RowsNotTriples { numbers: usize },
    /// Walk-model rows: `value` at row `row` should be a frame of the subject (0..`frames`).
    #[error("row {row}: {value} is not a frame of the subject (expected 0 to {})", .frames.saturating_sub(1))]
    RowNotAFrame { row: usize, value: f64, frames: usize },
    /// Walk-model rows: `value` at row `row` should count rows that follow.
    #[error("row {row}: {value} is not a count of the rows that follow")]
    RowNotACount { row: usize, value: f64 },
    /// Walk-model rows: a track header at row `row` with only `left` rows left.
    #[error("row {row}: a track header needs 3 rows, {left} left")]
    TrackHeaderCutShort { row: usize, left: usize },
    /// Walk-model rows: the track `from` -> `to` at row `row` has fewer centres than it says, or
    /// a non-finite end placement.
    #[error("row {row}: the track {from} -> {to} is cut short or not finite")]
    TrackCutShort { row: usize, from: u32, to: u32 },
    /// Walk-model rows: the track `from` -> `to` at row `row` has a non-finite centre.
    #[error("row {row}: the track {from} -> {to} has a non-finite centre")]
    TrackNonFiniteCentre { row: usize, from: u32, to: u32 },

    /// A curve with a NaN or infinite coordinate.
    #[error("the curve has a non-finite coordinate")]
    CurveNonFinite,
    /// A curve with fewer than two distinct points (in the coordinates that count).
    #[error("the curve needs at least two distinct points")]
    CurveTooShort,
    /// Path search parameters: the window must be a positive arc length and `max_frames`
    /// positive.
    #[error("window {window} / {max_frames} frames: expected a positive arc length and frame count")]
    PathSearchParameters { window: f64, max_frames: usize },
    /// The given start frame (`sequence:frame`) is excluded by the restriction at the curve's
    /// start.
    #[error("the start frame {frame} is not allowed by the restriction at the curve's start")]
    StartNotAllowed { frame: String },
    /// The given start frame (`sequence:frame`) leads only to the end of a sequence: no walk
    /// long enough for a curve leaves it.
    #[error(
        "the start frame {frame} is a dead end: every way on from it ends at the last frame of a sequence, with no transition onward; give an earlier --start or leave it out"
    )]
    StartIsDeadEnd { frame: String },
    /// No frame may start the path.
    #[error("no frame can start the path: the restrictions exclude every start frame")]
    NoStartFrame,
    /// The restrictions leave no way on from `frame` (`sequence:frame`), `travelled` of
    /// `length` along the curve (the search only uses frames that can go on, so nothing else
    /// stops a walk).
    #[error(
        "the walk is stuck at {frame} after {travelled:.2} of {length:.2} along the curve: the motion types allowed there (--tags) have no transition from it"
    )]
    PathStuck { frame: String, travelled: f64, length: f64 },
    /// The walk used more than its frame budget (`frames`) and covered only `travelled` of
    /// `length` along the curve.
    #[error(
        "the walk stalls: {frames} frames cover only {travelled:.2} of {length:.2} along the curve (do the allowed motions travel?)"
    )]
    PathStalls { frames: usize, travelled: f64, length: f64 },

    /// A matrix whose size does not match the frames it is for: `what` holds `len` numbers
    /// where `expected` were expected.
    #[error("{what}: {len} numbers, expected {expected} for {frames} frames")]
    MatrixSize { what: &'static str, len: usize, expected: usize, frames: usize },
    /// A matrix entry that is not a number the algorithm can use (NaN, negative...).
    #[error("{what}: entry ({row}, {col}) is {value}, expected {expected}")]
    MatrixEntry { what: &'static str, row: usize, col: usize, value: f64, expected: &'static str },
    /// A parameter outside its domain (NaN included).
    #[error("{name} {value}: expected {expected}")]
    Parameter { name: &'static str, value: f64, expected: &'static str },
    /// Text for [`crate::edge_weights::Alpha`] that is not a finite number > 0. The message
    /// leaves the text out: a command-line parser names the option and the value itself.
    #[error("expected a finite number > 0")]
    AlphaText { text: String },

    /// Time alignment: the `which` sequence ("reference" or "other") has no frames.
    #[error("the {which} sequence has no frames")]
    NoFrames { which: &'static str },
    /// Time alignment or resampling: frame `frame` of the `which` sequence holds `len` numbers
    /// where `expected` (those of the reference's first frame, a multiple of 3) were expected.
    #[error("{which} frame {frame}: {len} numbers, expected {expected} (3 per vertex, as the reference's first frame)")]
    PoseSize { which: &'static str, frame: usize, len: usize, expected: usize },
    /// Time alignment: the contact vectors of the `which` sequence: `len` where `expected`
    /// (one per frame, each with as many feet as the reference's first) were expected, at
    /// `frame` (`None`: the count of vectors).
    #[error("{which} contacts{}: {len} values, expected {expected}", .frame.map(|f| format!(" at frame {f}")).unwrap_or_default())]
    ContactSize { which: &'static str, frame: Option<usize>, len: usize, expected: usize },
    /// Time alignment: no warp of `reference` frames onto `other` frames satisfies the slope
    /// constraint `slope`.
    #[error(
        "no time warp of the {reference} reference frames onto the {other} other frames keeps to the slope constraint p = {slope} (the lengths may differ by a factor of p at most)"
    )]
    NoWarp { reference: usize, other: usize, slope: usize },
    /// A time map that is not one: `reason` says what is wrong.
    #[error("time map: {reason}")]
    TimeMap { reason: String },
    /// Resampling at time `time` (entry `index` of the times), outside the `frames` frames
    /// given (0 to frames - 1).
    #[error("time {time} (entry {index}) is outside the {frames} frames given (expected 0 to {})", .frames.saturating_sub(1))]
    TimeOutside { index: usize, time: f64, frames: usize },

    /// A timed-walk endpoint outside the graph's frames (0..`frames`).
    #[error("frame {frame} is not in the graph (expected 0 to {})", .frames.saturating_sub(1))]
    FrameNotInGraph { frame: u32, frames: usize },
    /// No walk from `from` to `to` (both `sequence:frame`) has a duration between `shortest`
    /// and `longest` frames, the widest range searched: twice the `asked` duration or the asked
    /// duration plus two of the graph's longest transitions (`longest_edge` frames), whichever
    /// is longer.
    #[error(
        "no walk from {from} to {to} lasts between {shortest} and {longest} frames (the search tries durations up to twice the {asked} asked, or {asked} plus two of the longest transition's {longest_edge} frames, whichever is longer)"
    )]
    NoWalkWithDuration { from: String, to: String, shortest: usize, longest: usize, asked: usize, longest_edge: usize },
    /// `to` cannot be reached from `from` at all (both `sequence:frame`), whatever the duration.
    #[error("no walk leads from {from} to {to} in the graph, whatever its duration{why}")]
    Unreachable { from: String, to: String, why: String },

    /// A shortest-path tree (row `root`) names `pred` as the predecessor of `node`, but the
    /// sparse graph has no edge `pred` -> `node` (rows from another graph, or damaged).
    #[error(
        "tree of source frame {root}: frame {pred} -> {node} is not an edge of the sparse graph (rows from another graph?)"
    )]
    TreeEdgeMissing { root: usize, pred: u32, node: usize },
    /// A shortest-path tree row (of `root`) with `len` entries where the graph has `frames`.
    #[error("tree of source frame {root}: {len} predecessors, expected {frames} (one per frame of the graph)")]
    TreeRowSize { root: usize, len: usize, frames: usize },
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::Error;

    #[test]
    fn messages_are_the_ones_callers_know() {
        let stuck = Error::PathStuck { frame: "walk:7".into(), travelled: 1.234, length: 10.0 };
        assert_eq!(
            stuck.to_string(),
            "the walk is stuck at walk:7 after 1.23 of 10.00 along the curve: the motion types allowed there (--tags) have no transition from it"
        );
        let row = Error::RowNotAFrame { row: 3, value: 40.0, frames: 30 };
        assert_eq!(row.to_string(), "row 3: 40 is not a frame of the subject (expected 0 to 29)");
        let outside = Error::FrameNotInGraph { frame: 30, frames: 30 };
        assert_eq!(outside.to_string(), "frame 30 is not in the graph (expected 0 to 29)");
        let none = Error::NoWalkWithDuration {
            from: "a:1".into(),
            to: "b:2".into(),
            shortest: 1,
            longest: 414,
            asked: 200,
            longest_edge: 107,
        };
        assert_eq!(
            none.to_string(),
            "no walk from a:1 to b:2 lasts between 1 and 414 frames (the search tries durations up to twice the 200 asked, or 200 plus two of the longest transition's 107 frames, whichever is longer)"
        );
    }
}

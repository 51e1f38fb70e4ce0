//! Why no walk of the essential graph meets a distance-and-time target within its tolerance
//! (`crate::timed_walk`), in the surface motion graph's words: the reasons carry the same names
//! (`too_short`, `too_near`, `no_loop`, `too_fast`, `too_slow`, `granularity`) and the same
//! meaning as `surfcap_smg::path_optimisation::Unreachable`, so reports and tables of the two
//! engines count them alike.
//!
//! Each reason is a proof from the graph, not a guess: the shortest walk in frames, the least
//! distance of any walk, whether the walks between the two frames can repeat a cycle at all,
//! and the least and greatest distance of the walks of every duration within the time
//! tolerance (exact: a layered search per duration).

/// Why no walk between two frames meets a (distance, time) target within its tolerance.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Unreachable {
    /// Every walk between the frames takes more frames than the target allows.
    TooShort { shortest_frames: f64 },
    /// Every walk travels farther than the target allows (its least-distance walk already does).
    TooNear { shortest_distance: f64 },
    /// No cycle can be repeated between the frames: every walk has a fixed length.
    NoLoop,
    /// The target asks for a speed (units per frame) above what every walk of the durations
    /// allowed travels: `fastest` is the greatest distance per frame among them.
    TooFast { needed: f64, fastest: f64 },
    /// ... or below: every walk of the durations allowed travels more (no in-place loop slow
    /// enough); `slowest` is the least distance per frame among them.
    TooSlow { needed: f64, slowest: f64 },
    /// Cycles exist, but their durations do not combine to any duration within the tolerance,
    /// or the walks of each duration miss the distance on either side.
    Granularity,
}

/// The reasons' names, in the order they are checked (the surface motion graph's).
pub const REASONS: [&str; 6] = ["too_short", "too_near", "no_loop", "too_fast", "too_slow", "granularity"];

impl Unreachable {
    /// The reason's name, as in reports (`too_short`, `too_near`, `no_loop`, `too_fast`,
    /// `too_slow`, `granularity`).
    pub fn kind(&self) -> &'static str {
        match self {
            Unreachable::TooShort { .. } => REASONS[0],
            Unreachable::TooNear { .. } => REASONS[1],
            Unreachable::NoLoop => REASONS[2],
            Unreachable::TooFast { .. } => REASONS[3],
            Unreachable::TooSlow { .. } => REASONS[4],
            Unreachable::Granularity => REASONS[5],
        }
    }
}

impl std::fmt::Display for Unreachable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unreachable::TooShort { shortest_frames } => {
                write!(f, "too short: every walk takes at least {shortest_frames} frames")
            }
            Unreachable::TooNear { shortest_distance } => {
                write!(f, "too near: every walk travels at least {shortest_distance:.3} units")
            }
            Unreachable::NoLoop => write!(f, "no loop between the key frames: every walk has a fixed length"),
            Unreachable::TooFast { needed, fastest } => write!(
                f,
                "too fast: needs {needed:.4} units per frame, the fastest walk of that duration travels {fastest:.4}"
            ),
            Unreachable::TooSlow { needed, slowest } => write!(
                f,
                "too slow: needs {needed:.4} units per frame, the slowest walk of that duration travels {slowest:.4} (no in-place loop)"
            ),
            Unreachable::Granularity => {
                write!(f, "no whole number of loop repetitions lands within the tolerance")
            }
        }
    }
}

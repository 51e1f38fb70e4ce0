//! The words both synthesis engines use when a distance-and-time or duration target cannot be
//! met, and which loops may pad time: the surface motion graph (Huang et al. 2009, 4.2: its
//! path optimisation, `surfcap_smg::path_optimisation`) and the essential graph's timed
//! searches (thesis 3.5.2, `surfcap_motion::timed_walk`). One type, so reports and tables of
//! the two engines name and count the reasons alike.
//!
//! Each engine proves its reason from its graph (its shortest walk in frames, its least
//! distance, whether a cycle lies between the two frames, the speeds its loops or walks can
//! reach, whether whole numbers of repetitions land within the tolerance); a target missed
//! without such a proof is reported as missed, never as unreachable.

/// Why no walk between two frames meets a (distance, time) target within its tolerance.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Unreachable {
    /// Every walk between the frames takes more frames than the target allows.
    TooShort { shortest_frames: f64 },
    /// Every walk travels farther than the target allows (its least-distance walk already does).
    TooNear { shortest_distance: f64 },
    /// No loop can be repeated between the frames: every walk has a fixed length.
    NoLoop,
    /// The target asks for a speed (units per frame) above the greatest the graph offers:
    /// the surface motion graph compares the speed needed over the frames its loops add with
    /// its fastest loop; the essential graph compares the target's mean speed with the
    /// fastest of its walks of the durations allowed.
    TooFast { needed: f64, fastest: f64 },
    /// ... or below the least: no loop slow enough (no in-place loop).
    TooSlow { needed: f64, slowest: f64 },
    /// The speed is in range, but no whole number of loop repetitions lands within the
    /// tolerance.
    Granularity,
}

/// The reasons' names, in the order the engines check them.
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

impl Unreachable {
    /// The reason in words, lengths and speeds in `unit` (the subject's symbol, `m`; "units"
    /// only when its size is unknown): "too fast: needs 0.0119 m per frame, ...".
    pub fn in_unit(&self, unit: &str) -> String {
        match self {
            Unreachable::TooShort { shortest_frames } => {
                format!("too short: every walk takes at least {shortest_frames} frames")
            }
            Unreachable::TooNear { shortest_distance } => {
                format!("too near: every walk travels at least {shortest_distance:.3} {unit}")
            }
            Unreachable::NoLoop => "no loop between the key frames: every walk has a fixed length".to_string(),
            Unreachable::TooFast { needed, fastest } => {
                format!("too fast: needs {needed:.4} {unit} per frame, the fastest the graph offers is {fastest:.4}")
            }
            Unreachable::TooSlow { needed, slowest } => format!(
                "too slow: needs {needed:.4} {unit} per frame, the slowest the graph offers is {slowest:.4} (no in-place loop)"
            ),
            Unreachable::Granularity => "no whole number of loop repetitions lands within the tolerance".to_string(),
        }
    }
}

/// In "units": reports that know the subject's unit use [`Unreachable::in_unit`].
impl std::fmt::Display for Unreachable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.in_unit("units"))
    }
}

/// Which loops may pad time: none playing fewer frames per repetition than `min_frames`, none
/// whose poses vary less than `variation_floor` typical frame steps (the largest pose
/// dissimilarity among the loop's frames over the median dissimilarity between successive
/// frames of their sequences). A loop of a few frames, or of a held pose, meets any time by
/// stuttering; Huang et al.'s loops are whole cycles of motion.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LoopRule {
    /// The fewest frames a loop plays per repetition.
    pub min_frames: usize,
    /// The least pose variation, in typical frame steps.
    pub variation_floor: f64,
}

impl Default for LoopRule {
    /// 10 frames (a third of a second at 30 fps, shorter than any human motion cycle) and 1
    /// typical frame step (a loop that changes less than the data does in one frame holds a
    /// pose).
    fn default() -> Self {
        LoopRule { min_frames: 10, variation_floor: 1.0 }
    }
}

impl LoopRule {
    /// Every loop allowed: the graph as the paper builds it.
    pub fn all() -> Self {
        LoopRule { min_frames: 0, variation_floor: 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_order_and_messages_carry_the_numbers() {
        let all = [
            Unreachable::TooShort { shortest_frames: 3.0 },
            Unreachable::TooNear { shortest_distance: 1.5 },
            Unreachable::NoLoop,
            Unreachable::TooFast { needed: 0.5, fastest: 0.25 },
            Unreachable::TooSlow { needed: 0.01, slowest: 0.02 },
            Unreachable::Granularity,
        ];
        assert_eq!(all.iter().map(Unreachable::kind).collect::<Vec<_>>(), REASONS);
        assert_eq!(all[0].to_string(), "too short: every walk takes at least 3 frames");
        assert!(all[3].to_string().starts_with("too fast: needs 0.5000 units per frame"));
        assert!(all[3].in_unit("m").starts_with("too fast: needs 0.5000 m per frame"));
        let json = serde_json::to_value(&all[4]).unwrap();
        assert_eq!(json["reason"], "too_slow");
        assert_eq!(json["slowest"], 0.02);
        assert_eq!(LoopRule::default(), LoopRule { min_frames: 10, variation_floor: 1.0 });
    }
}

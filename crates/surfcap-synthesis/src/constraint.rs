//! Soft constraints and how closely a synthesised walk met them (the reports' `constraints`):
//! a path's largest centre error against its curve (thesis 3.5.1), a key pose's time (3.5.2),
//! a distance and a duration (Huang et al. 2009's reach query). A constraint missed by more
//! than its tolerance is reported, never an error: the animation is still written, and a front
//! end decides ([`ConstraintsMissed`]: the command line's `--strict` exits with code 3).

use serde::{Deserialize, Serialize};

use crate::words::{count_of, fmt_number, fmt_percent};

/// A soft constraint and how closely the walk met it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Constraint {
    pub name: String,
    /// `frames`, or the subject's length unit (`m`, `cm`, ... or `arbitrary`).
    pub unit: String,
    pub asked: f64,
    pub achieved: f64,
    /// How far from the request: |achieved - asked|, or for a path its largest centre error.
    pub error: f64,
    /// `error` as a fraction of the asked length or duration (a path's: its curve length);
    /// `None` for a key's time, which is a position in the output, not a length.
    pub relative_error: Option<f64>,
    pub tolerance: f64,
    pub missed: bool,
}

impl Constraint {
    pub fn new(
        name: impl Into<String>,
        unit: impl Into<String>,
        asked: f64,
        achieved: f64,
        error: f64,
        tolerance: f64,
    ) -> Self {
        Constraint {
            name: name.into(),
            unit: unit.into(),
            asked,
            achieved,
            error,
            relative_error: None,
            tolerance,
            missed: error > tolerance,
        }
    }

    /// One line for people: `distance: 3.02 m (asked 3, error 0.02 m)`, `missed` added when it
    /// was (what the viewer shows beside a synthesis output). The error has its unit, and a
    /// path's says it is the largest distance of the centre from the curve.
    pub fn summary(&self) -> String {
        let missed = if self.missed { ", missed" } else { "" };
        let error = if self.name == "path" { "largest centre error" } else { "error" };
        format!(
            "{}: {} {} (asked {}, {error} {} {}{missed})",
            self.name,
            fmt_number(self.achieved),
            self.unit,
            fmt_number(self.asked),
            fmt_number(self.error),
            self.unit
        )
    }

    /// The warning a front end shows for a missed constraint: what was asked, achieved, the
    /// error and the tolerance (the command line adds the options that set it).
    pub fn missed_text(&self) -> String {
        let relative = self.relative_error.map(|r| format!(", {} of the asked", fmt_percent(r))).unwrap_or_default();
        format!(
            "constraint {} missed: asked {}, achieved {} (error {} {}{relative}, tolerance {}",
            self.name,
            fmt_number(self.asked),
            fmt_number(self.achieved),
            fmt_number(self.error),
            self.unit,
            fmt_number(self.tolerance)
        )
    }

    /// Sets `relative_error` to the error over `size` (the asked length or duration), when it
    /// is positive.
    pub fn relative_to(mut self, size: f64) -> Self {
        self.relative_error = (size > 0.0).then(|| self.error / size);
        self
    }
}

/// How closely constraints must be met before they count as missed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Tolerances {
    /// A distance (reach's distance, a path's largest centre error) missed by more than this,
    /// in the subject's units; default 10% of the asked distance or of the curve's length.
    pub distance: Option<f64>,
    /// A timing (a key's time, reach's duration) missed by more than this many frames; default
    /// 10, Huang et al.'s timing scale.
    pub frames: Option<usize>,
}

impl Tolerances {
    /// The distance tolerance for a constraint of size `asked`.
    pub fn distance(&self, asked: f64) -> f64 {
        self.distance.unwrap_or(0.1 * asked.abs())
    }

    /// The timing tolerance, frames.
    pub fn frames(&self) -> f64 {
        self.frames.unwrap_or(10) as f64
    }
}

/// Constraints that were missed: the outcome a front end may treat as a failure (the command
/// line's `--strict` exits with code 3 for it, after the animation and its report are written).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConstraintsMissed(pub usize);

impl ConstraintsMissed {
    /// `Err` with the number of missed constraints, when any was.
    pub fn check(constraints: &[Constraint]) -> Result<(), ConstraintsMissed> {
        match constraints.iter().filter(|c| c.missed).count() {
            0 => Ok(()),
            n => Err(ConstraintsMissed(n)),
        }
    }
}

impl std::fmt::Display for ConstraintsMissed {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let n = self.0;
        write!(f, "{} missed (--strict; the animation and its report were written)", count_of(n, "constraint"))
    }
}

impl std::error::Error for ConstraintsMissed {}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line beside a synthesis output gives the error's unit, and a path's error says it is
    /// the largest.
    #[test]
    fn the_summary_gives_the_error_with_its_unit() {
        let path = Constraint::new("path", "m", 15.0, 15.2, 0.112, 1.5);
        assert_eq!(path.summary(), "path: 15.2 m (asked 15, largest centre error 0.112 m)");
        let time = Constraint::new("time", "frames", 90.0, 95.0, 5.0, 10.0);
        assert_eq!(time.summary(), "time: 95 frames (asked 90, error 5 frames)");
    }
}

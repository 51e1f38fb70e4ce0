//! Which graph over the frames (thesis 3.3).

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

/// The essential graph (union of all shortest-path trees, thesis 3.3.2) or Kovar's motion graph
/// (local minima of the transition cost, the baseline of 3.3.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GraphKind {
    Essential,
    Motion,
}

impl GraphKind {
    pub fn name(self) -> &'static str {
        match self {
            GraphKind::Essential => "essential",
            GraphKind::Motion => "motion",
        }
    }
}

impl fmt::Display for GraphKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for GraphKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "essential" => Ok(GraphKind::Essential),
            "motion" => Ok(GraphKind::Motion),
            _ => Err(crate::Error::Parameter {
                name: "graph kind",
                value: format!("{s:?}"),
                expected: "expected essential or motion",
            }),
        }
    }
}

//! Which graph over the frames (thesis 3.3).

use std::fmt;
use std::str::FromStr;

use serde::{Serialize, Serializer};
use surfcap_motion::sparse_essential_graph::DEFAULT_K;

/// The essential graph (union of all shortest-path trees, thesis 3.3.2), the sparse essential
/// graph (the same union on the graph of every frame's `k` cheapest transitions plus the
/// original edges: scales to tens of thousands of frames) or Kovar's motion
/// graph (local minima of the transition cost, the baseline of 3.3.3).
///
/// Written (in reports, cache keys) and read as `essential`, `motion` and
/// `sparse-essential:K`; `sparse-essential` alone reads as k =
/// [`surfcap_motion::sparse_essential_graph::DEFAULT_K`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GraphKind {
    Essential,
    Motion,
    SparseEssential { k: usize },
}

impl GraphKind {
    /// The kind without its parameters.
    pub fn name(self) -> &'static str {
        match self {
            GraphKind::Essential => "essential",
            GraphKind::Motion => "motion",
            GraphKind::SparseEssential { .. } => "sparse-essential",
        }
    }

    /// The sparse essential graph with the default k.
    pub fn sparse_essential() -> Self {
        GraphKind::SparseEssential { k: DEFAULT_K }
    }
}

impl fmt::Display for GraphKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GraphKind::SparseEssential { k } => write!(f, "sparse-essential:{k}"),
            other => f.write_str(other.name()),
        }
    }
}

/// As its `Display` form, so a cache key holds k and a report reads as the option.
impl Serialize for GraphKind {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl FromStr for GraphKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        let bad = || crate::Error::Parameter {
            name: "graph kind",
            value: format!("{s:?}"),
            expected: "expected essential, sparse-essential, sparse-essential:K (K >= 1 transitions kept per frame) or motion",
        };
        match s {
            "essential" => Ok(GraphKind::Essential),
            "motion" => Ok(GraphKind::Motion),
            "sparse-essential" => Ok(GraphKind::sparse_essential()),
            _ => match s.strip_prefix("sparse-essential:").map(str::parse::<usize>) {
                Some(Ok(k)) if k >= 1 => Ok(GraphKind::SparseEssential { k }),
                _ => Err(bad()),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_and_read_alike() {
        for kind in [GraphKind::Essential, GraphKind::Motion, GraphKind::SparseEssential { k: 8 }] {
            assert_eq!(kind.to_string().parse::<GraphKind>().unwrap(), kind);
            assert_eq!(serde_json::to_value(kind).unwrap(), serde_json::Value::String(kind.to_string()));
        }
        assert_eq!(serde_json::to_string(&GraphKind::Essential).unwrap(), "\"essential\"", "cache keys unchanged");
        assert_eq!("sparse-essential".parse::<GraphKind>().unwrap(), GraphKind::SparseEssential { k: DEFAULT_K });
        for bad in ["sparse-essential:0", "sparse-essential:x", "sparse", "Essential"] {
            let e = bad.parse::<GraphKind>().unwrap_err().to_string();
            assert!(e.contains("sparse-essential:K"), "{bad}: {e}");
        }
    }
}

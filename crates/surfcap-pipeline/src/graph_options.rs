//! A graph's parameters (thesis 3.3) from the options every front end offers (`--kind`, `--k`,
//! `--alpha`, `--slope`, `--l-min`, `--l-max` on the command line, the same keywords in Python):
//! segment bounds defaulted from the subject's looping clips ([`Pipeline::segment_bounds`]),
//! `k` merged into the graph kind, and both checked, so that every front end refuses the same
//! requests with the same messages.

use surfcap_motion::dtw::Slope;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::transition_table::TableParams;

use crate::error::{Error, Result};
use crate::graph_kind::GraphKind;
use crate::pipeline::{GraphParams, Pipeline, check_table};

/// A graph as the options ask for it; unset bounds and `k` take their defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphOptions {
    pub kind: GraphKind,
    /// Transitions kept per frame by the sparse essential graph.
    pub k: Option<usize>,
    pub alpha: Alpha,
    pub slope: Slope,
    pub l_min: Option<usize>,
    pub l_max: Option<usize>,
}

/// A transition table's parameters: `l_min` and `l_max` default to `bounds` (shortest, longest
/// segment, frames), and must satisfy 1 <= l-min <= l-max.
pub fn table_params(
    slope: Slope,
    l_min: Option<usize>,
    l_max: Option<usize>,
    bounds: (usize, usize),
) -> Result<TableParams> {
    let p = TableParams { l_min: l_min.unwrap_or(bounds.0), l_max: l_max.unwrap_or(bounds.1), slope };
    check_table(&p)?;
    Ok(p)
}

impl GraphKind {
    /// The kind with `k` transitions kept per frame: only the sparse essential graph takes a
    /// `k`, and a kind that already names one (`sparse-essential:K`) must agree with it.
    pub fn with_k(self, k: Option<usize>) -> Result<GraphKind> {
        match (self, k) {
            (kind, None) => Ok(kind),
            (GraphKind::SparseEssential { k }, Some(given)) => {
                if self != GraphKind::sparse_essential() && k != given {
                    return Err(Error::Request(format!("--k {given}: the graph kind already says k = {k}")));
                }
                Ok(GraphKind::SparseEssential { k: given })
            }
            (kind, Some(given)) => {
                Err(Error::Request(format!("--k {given}: only with --kind sparse-essential (the graph is {kind})")))
            }
        }
    }
}

impl GraphOptions {
    /// The parameters for `pipe`'s subject: segment bounds that fit its clips unless given.
    pub fn params_for(&self, pipe: &Pipeline) -> Result<GraphParams> {
        Ok(GraphParams {
            table: table_params(self.slope, self.l_min, self.l_max, pipe.segment_bounds())?,
            kind: self.kind.with_k(self.k)?,
            alpha: self.alpha,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_goes_only_with_the_sparse_graph_and_bounds_default_and_are_checked() {
        assert_eq!(GraphKind::sparse_essential().with_k(Some(8)).unwrap(), GraphKind::SparseEssential { k: 8 });
        assert_eq!(GraphKind::SparseEssential { k: 8 }.with_k(Some(8)).unwrap(), GraphKind::SparseEssential { k: 8 });
        let e = GraphKind::SparseEssential { k: 8 }.with_k(Some(9)).unwrap_err().to_string();
        assert_eq!(e, "--k 9: the graph kind already says k = 8");
        let e = GraphKind::Essential.with_k(Some(9)).unwrap_err().to_string();
        assert_eq!(e, "--k 9: only with --kind sparse-essential (the graph is essential)");
        assert_eq!(GraphKind::Motion.with_k(None).unwrap(), GraphKind::Motion);
        let p = table_params(Some(3), None, Some(20), (10, 60)).unwrap();
        assert_eq!((p.l_min, p.l_max, p.slope), (10, 20, Some(3)));
        let e = table_params(None, Some(30), Some(20), (10, 60)).unwrap_err().to_string();
        assert_eq!(e, "segment lengths 30..20: expected 1 <= l-min <= l-max");
    }
}

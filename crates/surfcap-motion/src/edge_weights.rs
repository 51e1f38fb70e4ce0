//! Edge weights of the complete digraph over all frames (thesis 3.3.2, Algorithm 1,
//! eq. 3.2-3.3): the realism of going from frame i to frame j, E_ij = D_ij + alpha L_ij, the
//! optimal transition's normalised deformation cost plus alpha times its duration; successive
//! frames of a sequence cost alpha (no deformation, one time unit).
//!
//! Scale of D: our pose distance (eq. 2.13) sums over triangles, so D grows with the mesh
//! resolution (about 3,000 on the 20,000-triangle Vlasic crane, against path costs of 2 to 7 in
//! the thesis's Fig. 3.8-3.10, whose alpha range 0.01-0.2 presumes D of order one). D is
//! therefore divided by the median finite D of the subject: a typical transition's deformation
//! costs 1, and alpha reads the same on every subject (how much one frame of duration weighs
//! against a typical transition's deformation). The scale is kept in `EdgeWeights::d_scale`.
//!
//! Reading of eq. 3.2 (same sequence, i < j: E_ij = min(alpha (j - i), D_ij + alpha L_ij)): the
//! value alpha (j - i) is exactly the cost of the chain of successive-frame edges from i to j,
//! which the graph always holds. So a same-sequence pair gets a transition edge only when the
//! transition is strictly cheaper than playing the original frames; otherwise no edge, and
//! shortest paths go through the chain at the same cost. This keeps the essential graph free of
//! "skip" edges that only duplicate original playback (equal-cost ties otherwise decided by
//! rounding).
//!
//! alpha itself is an [`Alpha`]: a finite number > 0, checked once where it is made (parsed
//! from the command line or a file, or built from a number), so nothing below checks it again.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize};
use surfcap_mesh::FrameIndex;

use crate::error::{Error, Result};
use crate::transition_table::TransitionTable;

/// The tolerance alpha of eq. 3.2-3.3 between a transition's deformation and its duration: a
/// finite number > 0 (a larger alpha gives a denser graph: `graph build` measures the density).
///
/// Made by [`Alpha::new`] (from a number), [`FromStr`] (from text: usable as a clap value
/// parser) or [`Deserialize`] (from a file), each refusing 0, negative numbers, NaN and
/// infinity; serialised as the bare number (so cache keys and reports hold the number as
/// before), and shown as the number.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
#[serde(transparent)]
pub struct Alpha(f64);

impl Alpha {
    /// `value` as an alpha, or [`Error::Parameter`] ("alpha 0: expected a positive number")
    /// when it is not a finite number > 0.
    pub fn new(value: f64) -> Result<Alpha> {
        if value.is_finite() && value > 0.0 {
            Ok(Alpha(value))
        } else {
            Err(Error::Parameter { name: "alpha", value, expected: "a positive number" })
        }
    }

    /// The number.
    pub fn get(self) -> f64 {
        self.0
    }
}

impl fmt::Display for Alpha {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

/// Text (surrounding blanks ignored) that is a finite number > 0; otherwise
/// [`Error::AlphaText`], whose message ("expected a finite number > 0") leaves the text to the
/// caller (clap names the option and the value).
impl FromStr for Alpha {
    type Err = Error;
    fn from_str(s: &str) -> Result<Alpha> {
        match s.trim().parse::<f64>() {
            Ok(x) => Alpha::new(x).map_err(|_| Error::AlphaText { text: s.to_string() }),
            Err(_) => Err(Error::AlphaText { text: s.to_string() }),
        }
    }
}

/// A number, refused (with [`Alpha::new`]'s message) when it is not > 0.
impl<'de> Deserialize<'de> for Alpha {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Alpha, D::Error> {
        Alpha::new(f64::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

/// Dense N x N edge weights (row-major, `f64::INFINITY` where there is no edge; the diagonal
/// has none).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeWeights {
    pub n: usize,
    pub alpha: Alpha,
    /// D was divided by this (the median finite D).
    pub d_scale: f64,
    pub weight: Vec<f64>,
}

impl EdgeWeights {
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.weight[i * self.n + j]
    }

    /// Whether (i, j) is an edge between successive frames of one sequence.
    pub fn is_original(index: &FrameIndex, i: usize, j: usize) -> bool {
        j == i + 1 && index.locate(i).map(|l| l.0) == index.locate(j).map(|l| l.0)
    }
}

/// Algorithm 1 over a transition table. The table must be one of `index`'s frames, with
/// durations and costs that are 0 or more, or infinity (an inconsistent table is an error, not
/// a panic or NaN weights).
pub fn edge_weights(table: &TransitionTable, index: &FrameIndex, alpha: Alpha) -> Result<EdgeWeights> {
    let n = index.len();
    for (what, len) in [("transition costs", table.cost.len()), ("transition durations", table.len.len())] {
        if table.n != n || len != n * n {
            return Err(Error::MatrixSize { what, len, expected: n * n, frames: n });
        }
    }
    if let Some(k) = table.cost.iter().position(|c| c.is_nan() || *c < 0.0) {
        let (row, col, value) = (k / n, k % n, table.cost[k]);
        return Err(Error::MatrixEntry { what: "transition costs", row, col, value, expected: "a cost >= 0 or inf" });
    }
    let mut finite: Vec<f64> = table.cost.iter().copied().filter(|c| c.is_finite()).collect();
    let d_scale = if finite.is_empty() {
        1.0
    } else {
        let mid = finite.len() / 2;
        *finite.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    // All-identical poses (median 0) keep D as it is.
    let d_scale = if d_scale > 0.0 { d_scale } else { 1.0 };
    let mut weight = vec![f64::INFINITY; n * n];
    for (i, out) in weight.chunks_exact_mut(n.max(1)).enumerate().take(n) {
        let row = i * n..(i + 1) * n;
        edge_weight_row(&table.cost[row.clone()], &table.len[row], i, index, alpha, d_scale, out);
    }
    Ok(EdgeWeights { n, alpha, d_scale, weight })
}

/// Row `i` of Algorithm 1's weights (the one definition: [`edge_weights`] calls it for every
/// row), from row `i` of the transition table's costs and durations, into `out` (N entries,
/// `f64::INFINITY` where there is no edge). `d_scale` is the median finite cost of the whole
/// table ([`EdgeWeights::d_scale`]); a caller reading the table a block of rows at a time finds
/// it first. The row is not checked (see [`edge_weights`] for a checked table).
///
/// # Panics
/// When `cost_row`, `len_row` and `out` are not all `index.len()` long or `i` is not a frame of
/// `index` (a caller's mistake, not bad data).
pub fn edge_weight_row(
    cost_row: &[f64],
    len_row: &[u32],
    i: usize,
    index: &FrameIndex,
    alpha: Alpha,
    d_scale: f64,
    out: &mut [f64],
) {
    let alpha = alpha.get();
    let n = index.len();
    assert!(cost_row.len() == n && len_row.len() == n && out.len() == n, "rows of {n} frames");
    let (s, _) = index.locate(i).expect("row of a frame of the index");
    let same = index.range(s);
    for (j, w) in out.iter_mut().enumerate() {
        if i == j {
            *w = f64::INFINITY;
            continue;
        }
        let transition = cost_row[j] / d_scale + alpha * len_row[j] as f64;
        *w = if same.contains(&j) && j == i + 1 {
            alpha
        } else if same.contains(&j) && j > i {
            if transition < alpha * (j - i) as f64 { transition } else { f64::INFINITY }
        } else {
            transition
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn algorithm_1() {
        // Two sequences of 3 frames; every transition costs D = 0.5 (the median: 1 once
        // scaled) with L = 2, except 0 -> 4 (D = 0.25).
        let index = FrameIndex::new([3, 3]);
        let n = 6;
        let mut cost = vec![0.5; n * n];
        cost[4] = 0.25;
        let t = TransitionTable { n, cost, len: vec![2; n * n], li: vec![1; n * n], lj: vec![1; n * n] };
        let alpha = |a| Alpha::new(a).unwrap();
        let e = edge_weights(&t, &index, alpha(0.1)).unwrap();
        assert_eq!(e.at(0, 1), 0.1, "successive frames");
        assert_eq!(e.d_scale, 0.5);
        assert!(e.at(0, 2).is_infinite(), "1.2 > 0.2: the original chain is cheaper");
        assert!((e.at(2, 0) - 1.2).abs() < 1e-12, "backwards in a sequence: a transition");
        assert!((e.at(0, 4) - 0.7).abs() < 1e-12, "across sequences");
        assert!(e.at(3, 3).is_infinite());
        let e = edge_weights(&t, &index, alpha(1.0)).unwrap();
        assert!(e.at(0, 2).is_infinite(), "3 > 2");
        assert!(EdgeWeights::is_original(&index, 1, 2) && !EdgeWeights::is_original(&index, 2, 3));
        // Row by row, the same numbers.
        let mut out = vec![0.0; n];
        for i in 0..n {
            edge_weight_row(
                &t.cost[i * n..(i + 1) * n],
                &t.len[i * n..(i + 1) * n],
                i,
                &index,
                alpha(1.0),
                e.d_scale,
                &mut out,
            );
            assert_eq!(out.as_slice(), &e.weight[i * n..(i + 1) * n]);
        }
    }

    /// alpha is a finite number > 0 however it is made: from a number, from text (the command
    /// line's message) or from a file; it is written and shown as the bare number.
    #[test]
    fn alpha_is_a_positive_finite_number() {
        for bad in [0.0, -0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = Alpha::new(bad).unwrap_err();
            assert!(matches!(e, Error::Parameter { name: "alpha", .. }), "{bad}: {e:?}");
        }
        assert_eq!(Alpha::new(0.0).unwrap_err().to_string(), "alpha 0: expected a positive number");
        assert_eq!(Alpha::new(0.05).unwrap().get(), 0.05);
        for bad in ["0", "nan", "-1", "inf", "abc", ""] {
            assert_eq!(bad.parse::<Alpha>().unwrap_err().to_string(), "expected a finite number > 0", "{bad:?}");
        }
        assert_eq!(" 0.2 ".parse::<Alpha>().unwrap(), Alpha::new(0.2).unwrap());
        let a = Alpha::new(0.05).unwrap();
        assert_eq!(format!("{a} {a:.3}"), "0.05 0.050");
        assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&0.05f64).unwrap());
        assert_eq!(serde_json::from_str::<Alpha>("0.05").unwrap(), a);
        let e = serde_json::from_str::<Alpha>("0").unwrap_err().to_string();
        assert!(e.starts_with("alpha 0: expected a positive number"), "{e}");
        assert!(serde_json::from_str::<Alpha>("\"0.05\"").is_err());
    }
}

//! Dynamic time warping between a source window and a destination window (thesis 2.5.2,
//! eq. 2.50-2.54), with continuity, monotonicity, boundary conditions and the slope constraint.
//!
//! The grid has a row per source frame and a column per destination frame; cell (k, l) costs
//! d(source k, destination l). A path starts at (0, 0) and ends at (rows-1, cols-1).
//!
//! Slope constraint p (PAPER-NOTES on eq. 2.53-2.54): a predecessor route of (k, l) is one
//! diagonal step followed by q - 1 straight steps (q = 1..p), vertical or horizontal, and the cost
//! of every cell on the route is added; so no more than p - 1 straight steps follow each other.
//! The path may also begin with up to p - 1 straight steps from (0, 0) ([`FirstStep::Straight`],
//! surfcap's reading of the words of 2.5.2, the default); read literally from g(1, 1), eq. 2.53
//! makes every path begin with a diagonal step ([`FirstStep::Diagonal`], offered to reproduce the
//! thesis's tables under that reading). p = 1 allows only the diagonal (linear warping, equal
//! lengths); p = infinity is the 3-neighbour DTW of eq. 2.52 under either reading.
//! eq. 2.51 starts at g(0, 0) = d(0, 0) (the printed "- 1" is a typo, PAPER-NOTES).
//!
//! The dynamic programme minimises the summed cost (eq. 2.52-2.54) and records the path length
//! L; the normalised cost of eq. 2.50 is that sum divided by L ([`Normalisation::SumThenDivide`],
//! surfcap's reading, the default). Minimising the ratio exactly is a different, costlier
//! problem ([`Normalisation::ExactRatio`], module `exact_ratio`: the path length becomes a second
//! index of the DP), offered to show what eq. 2.55 read as the least ratio changes.

mod exact_ratio;

/// Slope constraint: `Some(p)` with p >= 1, or `None` for unconstrained (p = infinity).
pub type Slope = Option<usize>;

/// How a slope-constrained path may leave (0, 0) (PAPER-NOTES on eq. 2.53-2.54).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum FirstStep {
    /// Up to p - 1 straight steps before the first diagonal (the words of 2.5.2: at most p - 1
    /// straight steps in a row anywhere); surfcap's reading.
    #[default]
    Straight,
    /// A diagonal step first (eq. 2.53 read literally from g(1, 1)).
    Diagonal,
}

impl FirstStep {
    /// The name used on the command line and in result files: "surfcap" or "literal".
    pub fn name(self) -> &'static str {
        match self {
            FirstStep::Straight => "surfcap",
            FirstStep::Diagonal => "literal",
        }
    }
}

/// How the DP turns a path's summed cost into the normalised cost of eq. 2.50 (PAPER-NOTES on
/// eq. 2.55 vs 2.50).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Normalisation {
    /// Minimise the summed cost, then divide the best path's sum by its length L (surfcap's).
    #[default]
    SumThenDivide,
    /// Minimise the ratio sum / L exactly over the warping paths.
    ExactRatio,
}

impl Normalisation {
    /// The name used on the command line and in result files: "surfcap" or "exact".
    pub fn name(self) -> &'static str {
        match self {
            Normalisation::SumThenDivide => "surfcap",
            Normalisation::ExactRatio => "exact",
        }
    }
}

/// A reading of the DTW: how its path may start and how its cost is normalised. A
/// [`FirstStep`] alone converts into the reading with surfcap's normalisation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct DtwReading {
    pub first_step: FirstStep,
    pub normalisation: Normalisation,
}

impl From<FirstStep> for DtwReading {
    fn from(first_step: FirstStep) -> Self {
        DtwReading { first_step, normalisation: Normalisation::default() }
    }
}

/// Step recorded for warp recovery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    Start,
    /// One diagonal step then q - 1 vertical steps (source advances).
    Vertical(u16),
    /// One diagonal step then q - 1 horizontal steps (destination advances).
    Horizontal(u16),
    /// p = infinity: single steps.
    Diagonal1,
    Down1,
    Right1,
}

impl Step {
    /// Walks this step back from cell (k, l): pushes the cells it covers onto `out` (from (k, l)
    /// backwards) and returns the cell it came from and how many cells it covered, or `None` at
    /// the start, after pushing the straight run back to (0, 0).
    fn trace_back(self, k: usize, l: usize, out: &mut Vec<(usize, usize)>) -> Option<(usize, usize, usize)> {
        match self {
            Step::Start => {
                out.push((k, l));
                // Initial straight run back to (0, 0).
                out.extend((0..k).rev().map(|r| (r, l)));
                out.extend((0..l).rev().map(|c| (0, c)));
                None
            }
            Step::Vertical(q) => {
                let q = q as usize;
                out.extend((0..q).map(|r| (k - r, l)));
                Some((k - q, l - 1, q))
            }
            Step::Horizontal(q) => {
                let q = q as usize;
                out.extend((0..q).map(|r| (k, l - r)));
                Some((k - 1, l - q, q))
            }
            Step::Diagonal1 => {
                out.push((k, l));
                Some((k - 1, l - 1, 1))
            }
            Step::Down1 => {
                out.push((k, l));
                Some((k - 1, l, 1))
            }
            Step::Right1 => {
                out.push((k, l));
                Some((k, l - 1, 1))
            }
        }
    }
}

/// Dynamic-programming tables of one grid: summed cost and path length of the best path from
/// (0, 0) to every cell (f64::INFINITY where no path satisfies the constraints).
#[derive(Debug, Clone, Default)]
pub struct DtwTables {
    pub rows: usize,
    pub cols: usize,
    pub cost: Vec<f64>,
    pub len: Vec<u32>,
    steps: Vec<Step>,
    /// The exact-ratio DP's layers (`None` after a plain fill).
    layers: Option<exact_ratio::Layers>,
}

impl DtwTables {
    /// Summed cost and length at cell (k, l).
    pub fn at(&self, k: usize, l: usize) -> (f64, u32) {
        let i = k * self.cols + l;
        (self.cost[i], self.len[i])
    }

    /// The warping path to cell (k, l) as (source offset, destination offset) pairs, from (0, 0).
    pub fn path_to(&self, k: usize, l: usize) -> Vec<(usize, usize)> {
        if let Some(layers) = &self.layers {
            return layers.path_to(self.cols, k, l, self.len[k * self.cols + l]);
        }
        let mut out = Vec::new();
        let (mut k, mut l) = (k, l);
        while let Some((pk, pl, _)) = self.steps[k * self.cols + l].trace_back(k, l, &mut out) {
            (k, l) = (pk, pl);
        }
        out.reverse();
        out
    }
}

/// Fills `t` for a `rows x cols` grid whose cell costs are `d(k, l)` (surfcap's first step).
pub fn dtw_fill(rows: usize, cols: usize, d: impl Fn(usize, usize) -> f64, slope: Slope, t: &mut DtwTables) {
    dtw_fill_from(rows, cols, d, slope, FirstStep::Straight, t)
}

/// [`dtw_fill`] with a reading of the DTW (a [`FirstStep`] or a [`DtwReading`]); the first step
/// matters only for a finite slope. Under [`Normalisation::ExactRatio`], `t.at(k, l)` is the
/// (sum, L) of the path of least sum / L.
pub fn dtw_fill_from(
    rows: usize,
    cols: usize,
    d: impl Fn(usize, usize) -> f64,
    slope: Slope,
    reading: impl Into<DtwReading>,
    t: &mut DtwTables,
) {
    let reading = reading.into();
    let first = reading.first_step;
    if reading.normalisation == Normalisation::ExactRatio {
        exact_ratio::fill(rows, cols, d, slope, first, t);
        return;
    }
    t.layers = None;
    let n = rows * cols;
    t.rows = rows;
    t.cols = cols;
    t.cost.clear();
    t.cost.resize(n, f64::INFINITY);
    t.len.clear();
    t.len.resize(n, 0);
    t.steps.clear();
    t.steps.resize(n, Step::Start);
    if n == 0 {
        return;
    }
    let idx = |k: usize, l: usize| k * cols + l;
    // Initial straight runs from (0, 0): at most p - 1 steps (any number when p = infinity),
    // none when the first step must be the diagonal.
    let run = match (slope, first) {
        (None, _) => usize::MAX,
        (Some(_), FirstStep::Diagonal) => 0,
        (Some(p), FirstStep::Straight) => p.saturating_sub(1),
    };
    t.cost[0] = d(0, 0);
    t.len[0] = 1;
    for k in 1..rows.min(run.saturating_add(1)) {
        t.cost[idx(k, 0)] = t.cost[idx(k - 1, 0)] + d(k, 0);
        t.len[idx(k, 0)] = k as u32 + 1;
    }
    for l in 1..cols.min(run.saturating_add(1)) {
        t.cost[idx(0, l)] = t.cost[idx(0, l - 1)] + d(0, l);
        t.len[idx(0, l)] = l as u32 + 1;
    }
    for k in 1..rows {
        for l in 1..cols {
            let here = d(k, l);
            let mut best = f64::INFINITY;
            let mut best_len = 0u32;
            let mut best_step = Step::Start;
            match slope {
                None => {
                    for (pk, pl, step) in
                        [(k - 1, l - 1, Step::Diagonal1), (k - 1, l, Step::Down1), (k, l - 1, Step::Right1)]
                    {
                        let c = t.cost[idx(pk, pl)] + here;
                        if c < best {
                            best = c;
                            best_len = t.len[idx(pk, pl)] + 1;
                            best_step = step;
                        }
                    }
                }
                Some(p) => {
                    // q = 1: the diagonal.
                    let mut vsum = here;
                    let mut hsum = here;
                    for q in 1..=p.max(1) {
                        if q > 1 {
                            if k >= q {
                                vsum += d(k - q + 1, l);
                            }
                            if l >= q {
                                hsum += d(k, l - q + 1);
                            }
                        }
                        if k >= q {
                            let c = t.cost[idx(k - q, l - 1)] + vsum;
                            if c < best {
                                best = c;
                                best_len = t.len[idx(k - q, l - 1)] + q as u32;
                                best_step = Step::Vertical(q as u16);
                            }
                        }
                        if q > 1 && l >= q {
                            let c = t.cost[idx(k - 1, l - q)] + hsum;
                            if c < best {
                                best = c;
                                best_len = t.len[idx(k - 1, l - q)] + q as u32;
                                best_step = Step::Horizontal(q as u16);
                            }
                        }
                        if k < q && l < q {
                            break;
                        }
                    }
                }
            }
            t.cost[idx(k, l)] = best;
            t.len[idx(k, l)] = best_len;
            t.steps[idx(k, l)] = best_step;
        }
    }
}

/// One warped transition: normalised cost (eq. 2.50), path length L, and the path as pairs of
/// global frames (source, destination).
#[derive(Debug, Clone, PartialEq)]
pub struct Warp {
    pub cost: f64,
    pub len: usize,
    pub path: Vec<(usize, usize)>,
}

/// DTW between source frames `src .. src + li` and destination frames `dst_end + 1 - lj ..= dst_end`
/// of an N x N distance matrix.
pub fn dtw_window(d: &[f64], n: usize, src: usize, li: usize, dst_end: usize, lj: usize, slope: Slope) -> Option<Warp> {
    dtw_window_from(d, n, src, li, dst_end, lj, slope, FirstStep::Straight)
}

/// [`dtw_window`] with a reading of the DTW (a [`FirstStep`] or a [`DtwReading`]).
#[allow(clippy::too_many_arguments)]
pub fn dtw_window_from(
    d: &[f64],
    n: usize,
    src: usize,
    li: usize,
    dst_end: usize,
    lj: usize,
    slope: Slope,
    first: impl Into<DtwReading>,
) -> Option<Warp> {
    let dst = (dst_end + 1).checked_sub(lj)?;
    if src + li > n || dst_end >= n || li == 0 || lj == 0 {
        return None;
    }
    let mut t = DtwTables::default();
    dtw_fill_from(li, lj, |k, l| d[(src + k) * n + dst + l], slope, first, &mut t);
    let (c, len) = t.at(li - 1, lj - 1);
    if !c.is_finite() {
        return None;
    }
    let path = t.path_to(li - 1, lj - 1).into_iter().map(|(k, l)| (src + k, dst + l)).collect();
    Some(Warp { cost: c / len as f64, len: len as usize, path })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every monotone, continuous path with the slope rule, by brute force.
    fn brute(rows: usize, cols: usize, d: &dyn Fn(usize, usize) -> f64, p: usize) -> f64 {
        brute_from(rows, cols, d, p, FirstStep::Straight)
    }

    /// [`brute`] with the reading of the first step: a diagonal first starts as if p - 1 straight
    /// steps had just been taken.
    fn brute_from(rows: usize, cols: usize, d: &dyn Fn(usize, usize) -> f64, p: usize, first: FirstStep) -> f64 {
        struct Grid<'a> {
            rows: usize,
            cols: usize,
            p: usize,
            d: &'a dyn Fn(usize, usize) -> f64,
        }
        fn go(g: &Grid, k: usize, l: usize, run_v: usize, run_h: usize) -> f64 {
            let here = (g.d)(k, l);
            if k == g.rows - 1 && l == g.cols - 1 {
                return here;
            }
            let mut best = f64::INFINITY;
            if k + 1 < g.rows && l + 1 < g.cols {
                best = best.min(go(g, k + 1, l + 1, 0, 0));
            }
            if k + 1 < g.rows && run_v + 1 < g.p && run_h == 0 {
                best = best.min(go(g, k + 1, l, run_v + 1, 0));
            }
            if l + 1 < g.cols && run_h + 1 < g.p && run_v == 0 {
                best = best.min(go(g, k, l + 1, 0, run_h + 1));
            }
            here + best
        }
        let run = if first == FirstStep::Diagonal { p.saturating_sub(1) } else { 0 };
        go(&Grid { rows, cols, p, d }, 0, 0, run, 0)
    }

    #[test]
    fn matches_brute_force_for_every_slope() {
        let d = |k: usize, l: usize| (((k * 7 + l * 13) % 11) as f64 + 0.5) * (1.0 + ((k + 2 * l) % 3) as f64);
        for p in 1..=4 {
            for (rows, cols) in [(1, 1), (3, 3), (4, 6), (6, 4), (5, 5), (2, 7)] {
                let mut t = DtwTables::default();
                dtw_fill(rows, cols, d, Some(p), &mut t);
                let want = brute(rows, cols, &d, p);
                let (got, len) = t.at(rows - 1, cols - 1);
                assert!(
                    (got - want).abs() < 1e-9 || (got.is_infinite() && want.is_infinite()),
                    "p={p} {rows}x{cols}: {got} vs {want}"
                );
                if got.is_finite() {
                    let path = t.path_to(rows - 1, cols - 1);
                    assert_eq!(path.len(), len as usize);
                    assert_eq!(path[0], (0, 0));
                    assert_eq!(*path.last().unwrap(), (rows - 1, cols - 1));
                    let sum: f64 = path.iter().map(|&(k, l)| d(k, l)).sum();
                    assert!((sum - got).abs() < 1e-9);
                    for w in path.windows(2) {
                        let (dk, dl) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
                        assert!(dk <= 1 && dl <= 1 && dk + dl >= 1, "continuity and monotonicity");
                    }
                }
            }
        }
        // p = 1: only equal lengths are reachable.
        let mut t = DtwTables::default();
        dtw_fill(4, 5, d, Some(1), &mut t);
        assert!(t.at(3, 4).0.is_infinite());
        assert!(t.at(3, 3).0.is_finite());
    }

    #[test]
    fn unconstrained_allows_any_run_and_the_slope_does_not() {
        // Zero cost only along six horizontal steps then a diagonal.
        let d = |k: usize, l: usize| if (k == 0 && l < 7) || (k == 1 && l == 7) { 0.0 } else { 1.0 };
        let mut t = DtwTables::default();
        dtw_fill(2, 8, d, None, &mut t);
        assert_eq!(t.at(1, 7), (0.0, 8));
        dtw_fill(2, 8, d, Some(3), &mut t);
        assert!(t.at(1, 7).0 > 0.0);
        let diag = |k: usize, l: usize| (k as f64 - l as f64).abs();
        dtw_fill(6, 6, diag, None, &mut t);
        assert_eq!(t.at(5, 5), (0.0, 6));
    }

    #[test]
    fn the_literal_first_step_starts_diagonally_and_the_default_is_unchanged() {
        // Zero cost along one horizontal step then a diagonal: the cheapest path under surfcap's
        // reading; the literal reading of eq. 2.53 must take the diagonal first and pays 1.
        let d = |k: usize, l: usize| if (k, l) == (0, 0) || (k, l) == (0, 1) || (k, l) == (1, 2) { 0.0 } else { 1.0 };
        let mut t = DtwTables::default();
        dtw_fill(2, 3, d, Some(2), &mut t);
        assert_eq!(t.at(1, 2), (0.0, 3));
        assert_eq!(t.path_to(1, 2), [(0, 0), (0, 1), (1, 2)]);
        dtw_fill_from(2, 3, d, Some(2), FirstStep::Diagonal, &mut t);
        assert_eq!(t.at(1, 2), (1.0, 3));
        assert_eq!(t.path_to(1, 2), [(0, 0), (1, 1), (1, 2)]);
        assert!(t.at(0, 1).0.is_infinite() && t.at(1, 0).0.is_infinite(), "no straight first step");
        // The default is surfcap's reading, cell for cell; both readings match their brute force.
        let g = |k: usize, l: usize| (((k * 7 + l * 13) % 11) as f64 + 0.5) * (1.0 + ((k + 2 * l) % 3) as f64);
        let mut s = DtwTables::default();
        for p in 1..=4 {
            for (rows, cols) in [(1, 1), (3, 3), (4, 6), (6, 4), (5, 5), (2, 7)] {
                dtw_fill(rows, cols, g, Some(p), &mut t);
                dtw_fill_from(rows, cols, g, Some(p), FirstStep::Straight, &mut s);
                assert_eq!((&t.cost, &t.len), (&s.cost, &s.len));
                dtw_fill_from(rows, cols, g, Some(p), FirstStep::Diagonal, &mut s);
                let want = brute_from(rows, cols, &g, p, FirstStep::Diagonal);
                let got = s.at(rows - 1, cols - 1).0;
                assert!((got - want).abs() < 1e-9 || (got.is_infinite() && want.is_infinite()), "p={p} {rows}x{cols}");
            }
        }
        // Without a slope constraint (eq. 2.52) both readings are the 3-neighbour DTW.
        dtw_fill_from(2, 3, d, None, FirstStep::Diagonal, &mut t);
        assert_eq!(t.at(1, 2).0, 0.0);
        // The window form passes the reading on.
        let m: Vec<f64> = (0..25).map(|k| d(k / 5, k % 5)).collect();
        assert_eq!(dtw_window_from(&m, 5, 0, 2, 2, 3, Some(2), FirstStep::Straight).unwrap().cost, 0.0);
        assert_eq!(dtw_window_from(&m, 5, 0, 2, 2, 3, Some(2), FirstStep::Diagonal).unwrap().cost, 1.0 / 3.0);
    }
}

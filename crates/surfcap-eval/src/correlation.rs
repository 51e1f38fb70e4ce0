//! Pearson correlation (thesis eq. 2.18) and distance correlation (Székely et al. 2007,
//! thesis eq. 2.19-2.22).

use rayon::prelude::*;

/// Pearson correlation coefficient of two samples of equal length (0 when either is constant).
pub fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len()) as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let (u, v) = (a - mx, b - my);
        sxy += u * v;
        sxx += u * u;
        syy += v * v;
    }
    if sxx == 0.0 || syy == 0.0 { 0.0 } else { sxy / (sxx * syy).sqrt() }
}

/// Row means of a_ij = |x_i - x_j| for every i, in O(P log P) by sorting.
fn abs_diff_row_means(x: &[f64]) -> Vec<f64> {
    let p = x.len();
    let mut order: Vec<usize> = (0..p).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let sorted: Vec<f64> = order.iter().map(|&k| x[k]).collect();
    let total: f64 = sorted.iter().sum();
    let mut out = vec![0.0; p];
    let mut prefix = 0.0;
    for (rank, (&k, &v)) in order.iter().zip(&sorted).enumerate() {
        // sum_j |v - x_j| = v * rank - prefix + (total - prefix - v) - v * (p - rank - 1)
        let below = v * rank as f64 - prefix;
        let above = (total - prefix - v) - v * (p - rank - 1) as f64;
        out[k] = (below + above) / p as f64;
        prefix += v;
    }
    out
}

/// Squared distance covariance V^2(x, y) (eq. 2.21) without forming the P x P matrices:
/// sum A_ij B_ij = sum a_ij b_ij - 2 P sum_i a_i. b_i. + P^2 a.. b.. (A, B double-centred).
/// The first sum is O(P^2), computed in parallel rows with fixed-order sums.
fn dcov2(x: &[f64], y: &[f64], ax: &[f64], by: &[f64]) -> f64 {
    let p = x.len();
    let cross: f64 = (0..p)
        .into_par_iter()
        .map(|i| {
            let (xi, yi) = (x[i], y[i]);
            x.iter().zip(y).map(|(xj, yj)| (xi - xj).abs() * (yi - yj).abs()).sum::<f64>()
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    let pf = p as f64;
    let (ma, mb) = (ax.iter().sum::<f64>() / pf, by.iter().sum::<f64>() / pf);
    let rows: f64 = ax.iter().zip(by).map(|(a, b)| a * b).sum();
    (cross - 2.0 * pf * rows + pf * pf * ma * mb) / (pf * pf)
}

/// Distance correlation R(x, y) (eq. 2.22) in [0, 1]; 0 if either sample is constant.
pub fn distance_correlation(x: &[f64], y: &[f64]) -> f64 {
    let (ax, ay) = (abs_diff_row_means(x), abs_diff_row_means(y));
    let vxy = dcov2(x, y, &ax, &ay).max(0.0);
    let vxx = dcov2(x, x, &ax, &ax);
    let vyy = dcov2(y, y, &ay, &ay);
    if vxx <= 0.0 || vyy <= 0.0 {
        return 0.0;
    }
    (vxy / (vxx * vyy).sqrt()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition, with the P x P matrices formed.
    fn naive_dcor(x: &[f64], y: &[f64]) -> f64 {
        let p = x.len();
        let centred = |v: &[f64]| {
            let a: Vec<Vec<f64>> = (0..p).map(|i| (0..p).map(|j| (v[i] - v[j]).abs()).collect()).collect();
            let row: Vec<f64> = a.iter().map(|r| r.iter().sum::<f64>() / p as f64).collect();
            let all = row.iter().sum::<f64>() / p as f64;
            (0..p).map(|i| (0..p).map(|j| a[i][j] - row[i] - row[j] + all).collect::<Vec<f64>>()).collect::<Vec<_>>()
        };
        let (a, b) = (centred(x), centred(y));
        let v = |a: &Vec<Vec<f64>>, b: &Vec<Vec<f64>>| {
            (0..p).map(|i| (0..p).map(|j| a[i][j] * b[i][j]).sum::<f64>()).sum::<f64>() / (p * p) as f64
        };
        (v(&a, &b) / (v(&a, &a) * v(&b, &b)).sqrt()).sqrt()
    }

    #[test]
    fn matches_the_definition_and_the_thesis_example() {
        let x: Vec<f64> = (-10..=10).map(|v| v as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| v * v).collect();
        assert!(pearson(&x, &y).abs() < 1e-12, "Pearson of x and x^2 on a symmetric range is 0");
        let d = distance_correlation(&x, &y);
        assert!((d - naive_dcor(&x, &y)).abs() < 1e-12);
        // The thesis quotes "nearly 0.5" for this example.
        assert!((d - 0.5).abs() < 0.05, "{d}");
        assert!((distance_correlation(&x, &x) - 1.0).abs() < 1e-12);
        let z: Vec<f64> = x.iter().map(|v| 3.0 * v + 1.0).collect();
        assert!((pearson(&x, &z) - 1.0).abs() < 1e-12);
    }
}

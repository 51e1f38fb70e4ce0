//! The Mantel test and Mantel correlogram (thesis 2.3.2, Fig. 2.5-2.6).
//!
//! Reading: the thesis describes permuting "samples within one of the distance variable sets";
//! entries of a distance matrix are not exchangeable, so, as in Mantel (1967) and Legendre &
//! Legendre, we permute the *objects* (the frames): the same permutation is applied to the rows
//! and the columns of one matrix, and the Pearson correlation of the condensed matrices is
//! recomputed. The p-value is (1 + #{r_perm >= r_obs}) / (1 + permutations).
//!
//! The correlogram splits the pairs into classes of ground-truth distance (equal-count classes)
//! and, in each class, correlates the two distances over the pairs of that class; the 95%
//! limits about the null hypothesis are the 2.5% and 97.5% quantiles of that correlation after
//! shuffling the second distance within the class.
//!
//! Randomness: permutation k uses a ChaCha8 stream seeded with (seed, k), so the result is the
//! same for a given seed whatever the number of threads.

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::correlation::pearson;
use crate::pair_index;

/// Result of a Mantel test.
#[derive(Debug, Clone, PartialEq)]
pub struct MantelResult {
    /// Pearson correlation of the two condensed matrices.
    pub r: f64,
    /// (1 + count of permutations with r_perm >= r) / (1 + permutations).
    pub p_value: f64,
    /// How many permuted correlations reached r.
    pub exceed: usize,
    pub permutations: usize,
    /// Mean and standard deviation of the permuted correlations.
    pub null_mean: f64,
    pub null_std: f64,
}

fn rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// Mantel test of condensed matrices `x` and `y` over `n` objects.
pub fn mantel(n: usize, x: &[f64], y: &[f64], permutations: usize, seed: u64) -> MantelResult {
    let r = pearson(x, y);
    let perm_r: Vec<f64> = (0..permutations)
        .into_par_iter()
        .map(|k| {
            let mut perm: Vec<usize> = (0..n).collect();
            perm.shuffle(&mut rng(seed, k as u64));
            let yp: Vec<f64> = (0..n)
                .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let (a, b) = (perm[i].min(perm[j]), perm[i].max(perm[j]));
                    y[pair_index(n, a, b)]
                })
                .collect();
            pearson(x, &yp)
        })
        .collect();
    let exceed = perm_r.iter().filter(|&&v| v >= r).count();
    let m = perm_r.iter().sum::<f64>() / permutations.max(1) as f64;
    let var = perm_r.iter().map(|v| (v - m).powi(2)).sum::<f64>() / permutations.max(1) as f64;
    MantelResult {
        r,
        p_value: (1 + exceed) as f64 / (1 + permutations) as f64,
        exceed,
        permutations,
        null_mean: m,
        null_std: var.sqrt(),
    }
}

/// One distance class of a correlogram (serialised with these field names in the
/// `eval pose-metric` report).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CorrelogramClass {
    /// Range of the reference (ground-truth) distance in this class.
    pub lo: f64,
    pub hi: f64,
    pub pairs: usize,
    /// Correlation of the reference with the tested distance over the class's pairs.
    pub r: f64,
    /// 2.5% and 97.5% quantiles of the correlation with the tested distance shuffled in the class.
    pub null_lo: f64,
    pub null_hi: f64,
}

/// Mantel correlogram of `tested` against `reference` in `classes` equal-count classes of the
/// reference distance.
pub fn correlogram(
    reference: &[f64],
    tested: &[f64],
    classes: usize,
    permutations: usize,
    seed: u64,
) -> Vec<CorrelogramClass> {
    let mut order: Vec<usize> = (0..reference.len()).collect();
    order.sort_by(|&a, &b| reference[a].total_cmp(&reference[b]));
    let classes = classes.clamp(1, order.len().max(1));
    (0..classes)
        .map(|c| {
            let a = c * order.len() / classes;
            let b = (c + 1) * order.len() / classes;
            let idx = &order[a..b];
            let x: Vec<f64> = idx.iter().map(|&k| reference[k]).collect();
            let y: Vec<f64> = idx.iter().map(|&k| tested[k]).collect();
            let r = pearson(&x, &y);
            let mut null: Vec<f64> = (0..permutations)
                .into_par_iter()
                .map(|k| {
                    let mut yp = y.clone();
                    yp.shuffle(&mut rng(seed ^ ((c as u64) << 32), k as u64));
                    pearson(&x, &yp)
                })
                .collect();
            null.sort_by(f64::total_cmp);
            let q = |f: f64| if null.is_empty() { 0.0 } else { null[((null.len() - 1) as f64 * f).round() as usize] };
            CorrelogramClass {
                lo: x.first().copied().unwrap_or(0.0),
                hi: x.last().copied().unwrap_or(0.0),
                pairs: idx.len(),
                r,
                null_lo: q(0.025),
                null_hi: q(0.975),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize, f: impl Fn(f64) -> f64) -> Vec<f64> {
        let v: Vec<f64> = (0..n).map(|i| f(i as f64)).collect();
        (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| (v[i] - v[j]).abs()).collect()
    }

    #[test]
    fn related_matrices_are_significant_and_unrelated_ones_are_not() {
        let n = 30;
        let x = points(n, |t| t);
        let y = points(n, |t| t * 1.5 + (t * 7.0).sin());
        let m = mantel(n, &x, &y, 999, 1);
        assert!(m.r > 0.9 && m.p_value <= 0.002, "{m:?}");
        let mut r = rng(42, 0);
        let noise: Vec<f64> = (0..n).map(|_| rand::Rng::random::<f64>(&mut r)).collect();
        let z = points(n, |t| noise[t as usize]);
        let m = mantel(n, &x, &z, 999, 1);
        assert!(m.p_value > 0.01, "{m:?}");
        // Same seed, same result.
        assert_eq!(mantel(n, &x, &z, 200, 5), mantel(n, &x, &z, 200, 5));
    }

    #[test]
    fn correlogram_classes_cover_all_pairs() {
        let n = 25;
        let x = points(n, |t| t);
        let y = points(n, |t| t + (t * 3.0).cos());
        let c = correlogram(&x, &y, 5, 99, 2);
        assert_eq!(c.iter().map(|k| k.pairs).sum::<usize>(), x.len());
        assert!(c.windows(2).all(|w| w[0].hi <= w[1].lo));
        assert!(c.iter().all(|k| k.null_lo <= k.null_hi));
    }
}

//! Variants of a blend of two learnt motions at any weight (thesis 6.7).
//!
//! The model is trained with the pair's non-linear blends at a few weights W (6.7: W = {0.5}
//! was enough), so the latent space holds a ladder of learnt trajectories `X_0 = X_a`,
//! `X_w` for w in W, `X_1 = X_b`. For a requested weight `w*`, the two learnt trajectories
//! around it, `w1 <= w* <= w2`, each give a variant (HMC around a *learnt* trajectory: the
//! thesis found sampling around an interpolated one degenerate), and the two are interpolated
//! in the latent space,
//!
//! ```text
//! X~_{w*} = (w* - w2) / (w1 - w2) X~^l_{w1} + (w* - w1) / (w2 - w1) X~^m_{w2}
//! ```
//!
//! with `m` drawn at random for each `l` (seeded). Frames come from the reconstruction GP and
//! the stitching as for any variant; the timing is interpolated between the two bounding
//! sequences' time maps with the same proportions.

use rand_free::pick;
use serde::Serialize;
use surfcap_geometry::rotation_log_exp::{exp_rotation, log_rotation};
use surfcap_learn::Mat;
use surfcap_transfer::pose_representation::Placement;

use crate::error::{Error, Result};
use crate::motion_preparation::SequenceOrigin;
use crate::variation_model::VariationModel;
use crate::variation_sampling::{
    ChainSummary, LatentVariants, SamplingOptions, Variant, place_variant, sample_latent_variants,
    variants_from_latents,
};

/// A learnt trajectory on the blend ladder of a pair: its weight and sequence index.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rung {
    pub w: f64,
    pub sequence: usize,
}

/// The learnt trajectories between `a` (w = 0) and `b` (w = 1), sorted by weight: the two
/// sequences and every learnt blend of them (a blend of b and a at w counts at 1 - w).
pub fn blend_ladder(model: &VariationModel, a: &str, b: &str) -> Result<Vec<Rung>> {
    let ia = model.sequence_index(a)?;
    let ib = model.sequence_index(b)?;
    if ia == ib {
        return Err(Error::Invalid(format!("blend of {a:?} with itself: expected two different sequences")));
    }
    let mut ladder = vec![Rung { w: 0.0, sequence: ia }, Rung { w: 1.0, sequence: ib }];
    for (j, s) in model.sequences.iter().enumerate() {
        if let SequenceOrigin::Blend { a: x, b: y, w } = &s.origin {
            if x == a && y == b {
                ladder.push(Rung { w: *w, sequence: j });
            } else if x == b && y == a {
                ladder.push(Rung { w: 1.0 - w, sequence: j });
            }
        }
    }
    ladder.sort_by(|p, q| p.w.total_cmp(&q.w));
    ladder.dedup_by(|p, q| p.w == q.w);
    Ok(ladder)
}

/// The two rungs around `w` (equal when `w` is on a rung).
pub fn bounding_rungs(ladder: &[Rung], w: f64) -> Result<(Rung, Rung)> {
    if !(0.0..=1.0).contains(&w) {
        return Err(Error::Invalid(format!("blend weight {w}: expected a value in [0, 1]")));
    }
    if let Some(r) = ladder.iter().find(|r| r.w == w) {
        return Ok((*r, *r));
    }
    let i = ladder.iter().position(|r| r.w > w).unwrap_or(ladder.len() - 1).max(1);
    Ok((ladder[i - 1], ladder[i]))
}

/// The per-part latent interpolation of two trajectories with the weights of `w` between the
/// rungs `r1` and `r2`.
pub fn interpolate_latents(x1: &[Mat<f64>], x2: &[Mat<f64>], r1: Rung, r2: Rung, w: f64) -> Vec<Mat<f64>> {
    let (c1, c2) = rung_weights(r1, r2, w);
    x1.iter().zip(x2).map(|(p, q)| Mat::from_fn(p.nrows(), p.ncols(), |i, j| c1 * p[(i, j)] + c2 * q[(i, j)])).collect()
}

fn rung_weights(r1: Rung, r2: Rung, w: f64) -> (f64, f64) {
    if r1.w == r2.w { (1.0, 0.0) } else { ((w - r2.w) / (r1.w - r2.w), (w - r1.w) / (r2.w - r1.w)) }
}

/// The timing of the blend at `w` between two rungs: own frame count and time map
/// interpolated with the rungs' weights.
pub fn interpolated_timing(model: &VariationModel, r1: Rung, r2: Rung, w: f64) -> (usize, Vec<f64>) {
    let (c1, c2) = rung_weights(r1, r2, w);
    let (s1, s2) = (&model.sequences[r1.sequence], &model.sequences[r2.sequence]);
    let own = ((c1 * s1.own_frames as f64 + c2 * s2.own_frames as f64).round() as usize).max(2);
    let span = |n: usize| (n - 1).max(1) as f64;
    let mut times: Vec<f64> = s1
        .times
        .iter()
        .zip(&s2.times)
        .map(|(t1, t2)| (c1 * t1 / span(s1.own_frames) + c2 * t2 / span(s2.own_frames)) * (own - 1) as f64)
        .collect();
    crate::motion_preparation::pin_ends(&mut times, own);
    (own, times)
}

/// The path of the blend at `w` between two rungs: per reference frame the two rungs'
/// placements interpolated with the rungs' weights (translation lerp, rotation along the
/// geodesic).
pub fn interpolated_path(model: &VariationModel, r1: Rung, r2: Rung, w: f64) -> Vec<Placement> {
    let (_, c2) = rung_weights(r1, r2, w);
    let (p1, p2) = (&model.sequences[r1.sequence].path, &model.sequences[r2.sequence].path);
    p1.iter()
        .zip(p2)
        .map(|(a, b)| Placement {
            rotation: a.rotation * exp_rotation(&(log_rotation(&(a.rotation.transpose() * b.rotation)) * c2)),
            translation: a.translation * (1.0 - c2) + b.translation * c2,
        })
        .collect()
}

/// What [`sample_blend_variants`] did.
#[derive(Debug, Clone, Serialize)]
pub struct BlendSampling {
    pub a: String,
    pub b: String,
    pub w: f64,
    /// The learnt rungs around `w`.
    pub lower: Rung,
    pub upper: Rung,
    /// For each variant, the variant of the upper rung paired with it.
    pub pairing: Vec<usize>,
    pub chains: Vec<ChainSummary>,
}

/// `count` variants of the blend of `a` and `b` at weight `w` (6.7).
pub fn sample_blend_variants(
    model: &VariationModel,
    a: &str,
    b: &str,
    w: f64,
    count: usize,
    seed: u64,
    opts: &SamplingOptions,
) -> Result<(Vec<Variant>, BlendSampling)> {
    let ladder = blend_ladder(model, a, b)?;
    let (r1, r2) = bounding_rungs(&ladder, w)?;
    let (lower, mut chains) = sample_latent_variants(model, r1.sequence, count, seed, opts)?;
    let (upper, pairing) = if r1 == r2 {
        (lower.clone(), (0..count).collect())
    } else {
        let (upper, c2) = sample_latent_variants(model, r2.sequence, count, seed, opts)?;
        chains.extend(c2);
        (upper, (0..count).map(|l| pick(seed, l, count)).collect::<Vec<_>>())
    };
    let (own, times) = interpolated_timing(model, r1, r2, w);
    let start = model.sequences[model.sequence_index(a)?].first_placement;
    let path = interpolated_path(model, r1, r2, w);
    let place = |aligned: &[Vec<f32>], displacements: &[[f64; 6]]| {
        place_variant(model, opts.path, aligned, displacements, &start, &path, &times, own)
    };
    let latents: LatentVariants =
        lower.iter().zip(&pairing).map(|(x1, &m)| interpolate_latents(x1, &upper[m], r1, r2, w)).collect();
    let learnt =
        interpolate_latents(&model.learnt_latents(r1.sequence)?, &model.learnt_latents(r2.sequence)?, r1, r2, w);
    let variants = variants_from_latents(model, latents, &learnt, opts, place)?;
    Ok((variants, BlendSampling { a: a.into(), b: b.into(), w, lower: r1, upper: r2, pairing, chains }))
}

/// The random pairing of 6.7 ("select two variants randomly"), seeded, without an RNG crate:
/// variant `l` of the lower rung is paired with this variant of the upper one.
mod rand_free {
    use crate::variation_sampling::mix_seed;

    pub fn pick(seed: u64, l: usize, count: usize) -> usize {
        (mix_seed(mix_seed(seed ^ 0x6a09_e667_f3bc_c908).wrapping_add(l as u64)) % count as u64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounding_rungs_pick_the_neighbours() {
        let ladder = [Rung { w: 0.0, sequence: 0 }, Rung { w: 0.5, sequence: 2 }, Rung { w: 1.0, sequence: 1 }];
        let (a, b) = bounding_rungs(&ladder, 0.25).unwrap();
        assert_eq!((a.sequence, b.sequence), (0, 2));
        let (a, b) = bounding_rungs(&ladder, 0.75).unwrap();
        assert_eq!((a.sequence, b.sequence), (2, 1));
        let (a, b) = bounding_rungs(&ladder, 0.5).unwrap();
        assert_eq!((a.sequence, b.sequence), (2, 2));
        let (a, b) = bounding_rungs(&ladder, 1.0).unwrap();
        assert_eq!((a.sequence, b.sequence), (1, 1));
        assert!(bounding_rungs(&ladder, 1.5).is_err());
    }

    #[test]
    fn latent_interpolation_follows_the_thesis_weights() {
        let x1 = vec![Mat::from_fn(2, 1, |_, _| 0.0)];
        let x2 = vec![Mat::from_fn(2, 1, |_, _| 4.0)];
        let r1 = Rung { w: 0.0, sequence: 0 };
        let r2 = Rung { w: 0.5, sequence: 1 };
        let x = interpolate_latents(&x1, &x2, r1, r2, 0.25);
        assert!((x[0][(0, 0)] - 2.0).abs() < 1e-12);
        let x = interpolate_latents(&x1, &x2, r1, r2, 0.5);
        assert!((x[0][(1, 0)] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn pairing_is_seeded_and_in_range() {
        let p: Vec<usize> = (0..20).map(|l| pick(3, l, 5)).collect();
        assert!(p.iter().all(|&m| m < 5));
        assert_eq!(p, (0..20).map(|l| pick(3, l, 5)).collect::<Vec<_>>());
        assert!(p.iter().any(|&m| m != p[0]));
    }
}

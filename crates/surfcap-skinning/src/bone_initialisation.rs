//! Initial bones by rigid clustering: Smooth Skinning Decomposition with Rigid Bones (Le and
//! Deng 2012) starts its alternation from a clustering of the vertices in which each cluster
//! moves with one rigid transform per frame (their initialisation, a k-means whose "centres"
//! are rigid motions). Here:
//!
//! 1. seeds by farthest-point sampling of the vertices' trajectories (positions over up to
//!    [`MAX_INIT_FRAMES`] evenly spaced frames; the first seed drawn from the seed's ChaCha8
//!    stream), each vertex labelled with its nearest seed;
//! 2. rounds of: fit each cluster's rigid transform per frame (unit-weight Procrustes, see
//!    [`crate::rigid_bone_fit`]), then move each vertex to the cluster whose transforms
//!    reproduce its trajectory best;
//! 3. a cluster left with fewer than [`MIN_BONE_VERTICES`] vertices takes over the part of the
//!    worst-fitting cluster nearest that cluster's worst-fitting vertex (a split), so that every
//!    bone ends with vertices.
//!
//! Deterministic: every choice breaks ties by the lower index, sums run in vertex order.

use nalgebra::{DMatrix, Vector3};
use rand::Rng;
use rand::SeedableRng;
use rayon::prelude::*;

use crate::rigid_bone_fit::{BoneTransform, RigidFitSums};

/// Frames the clustering looks at (evenly spaced); the alternation then uses every frame.
pub const MAX_INIT_FRAMES: usize = 64;

/// A bone needs this many vertices for its rigid transforms to be defined.
pub const MIN_BONE_VERTICES: usize = 4;

/// Evenly spaced frame indices, at most `max` of `n`.
pub fn sample_frames(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    let mut v: Vec<usize> = (0..max).map(|k| k * (n - 1) / (max - 1)).collect();
    v.dedup();
    v
}

/// Vertex `i`'s position at frame column block `t` of `frames` (V x 3T, column-major).
#[inline]
fn at(frames: &DMatrix<f64>, i: usize, t: usize) -> Vector3<f64> {
    Vector3::new(frames[(i, 3 * t)], frames[(i, 3 * t + 1)], frames[(i, 3 * t + 2)])
}

/// Labels (bone of each vertex) of `n_bones` rigid clusters.
pub fn rigid_clusters(
    rest: &[Vector3<f64>],
    frames: &DMatrix<f64>,
    n_bones: usize,
    rounds: usize,
    seed: u64,
) -> Vec<usize> {
    let nv = rest.len();
    let n_frames = frames.ncols() / 3;
    let ts = sample_frames(n_frames, MAX_INIT_FRAMES);
    // Trajectory distance between two vertices over the sampled frames.
    let dist2 =
        |a: usize, b: usize| -> f64 { ts.iter().map(|&t| (at(frames, a, t) - at(frames, b, t)).norm_squared()).sum() };

    // 1. Farthest-point seeds.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let first = rng.random_range(0..nv);
    let mut seeds = vec![first];
    let mut nearest: Vec<(f64, usize)> = (0..nv).into_par_iter().map(|i| (dist2(i, first), 0)).collect();
    while seeds.len() < n_bones {
        let far = (0..nv).max_by(|&a, &b| nearest[a].0.total_cmp(&nearest[b].0).then(b.cmp(&a))).unwrap_or(0);
        if nearest[far].0 <= 0.0 {
            break; // fewer distinct trajectories than bones
        }
        let s = seeds.len();
        seeds.push(far);
        nearest.par_iter_mut().enumerate().for_each(|(i, n)| {
            let d = dist2(i, far);
            if d < n.0 {
                *n = (d, s);
            }
        });
    }
    let mut labels: Vec<usize> = nearest.iter().map(|n| n.1).collect();
    let n_bones = seeds.len();

    // 2. Rigid k-means rounds. The sampled frames as a V x 3Ts matrix, so that every vertex's
    // fit error to every cluster comes from one matrix product (see `fit_errors`).
    let sub = DMatrix::from_fn(nv, 3 * ts.len(), |i, c| frames[(i, 3 * ts[c / 3] + c % 3)]);
    for _ in 0..rounds {
        let fits = cluster_transforms(rest, frames, &ts, &labels, n_bones);
        let errs = fit_errors(rest, &sub, &fits, n_bones);
        let mut new: Vec<usize> = errs
            .iter()
            .map(|e| (0..n_bones).min_by(|&a, &b| e[a].total_cmp(&e[b]).then(a.cmp(&b))).unwrap_or(0))
            .collect();
        // 3. Every bone keeps enough vertices: split the worst cluster for each one short.
        for _ in 0..2 * n_bones {
            let mut count = vec![0usize; n_bones];
            new.iter().for_each(|&l| count[l] += 1);
            let Some(short) = (0..n_bones).find(|&j| count[j] < MIN_BONE_VERTICES) else { break };
            let mut cluster_err = vec![0.0f64; n_bones];
            for i in 0..nv {
                cluster_err[new[i]] += errs[i][new[i]];
            }
            let Some(big) = (0..n_bones)
                .filter(|&j| count[j] >= 2 * MIN_BONE_VERTICES)
                .max_by(|&a, &b| cluster_err[a].total_cmp(&cluster_err[b]).then(b.cmp(&a)))
            else {
                break; // nothing left to split: fewer bones end up used
            };
            let members: Vec<usize> = (0..nv).filter(|&i| new[i] == big).collect();
            let worst = *members
                .iter()
                .max_by(|&&a, &&b| errs[a][big].total_cmp(&errs[b][big]).then(b.cmp(&a)))
                .unwrap_or(&members[0]);
            let centre = members.iter().fold(Vector3::zeros(), |s, &i| s + rest[i]) / members.len() as f64;
            let mut moved = 0;
            for &i in &members {
                if (rest[i] - rest[worst]).norm_squared() < (rest[i] - centre).norm_squared() {
                    new[i] = short;
                    moved += 1;
                }
            }
            if moved < MIN_BONE_VERTICES {
                // The split did not separate enough: take the nearest members to the worst vertex.
                let mut by_dist = members.clone();
                by_dist.sort_by(|&a, &b| {
                    (rest[a] - rest[worst])
                        .norm_squared()
                        .total_cmp(&(rest[b] - rest[worst]).norm_squared())
                        .then(a.cmp(&b))
                });
                for &i in by_dist.iter().take(members.len() / 2) {
                    new[i] = short;
                }
            }
        }
        let changed = new != labels;
        labels = new;
        if !changed {
            break;
        }
    }
    labels
}

/// `errs[i][j] = sum_t || M_j^t p_i - v_i^t ||^2` over the sampled frames (`sub`, V x 3Ts),
/// expanded as `p~^T (sum_t M_j^tT M_j^t) p~ - 2 p~ . (sum_t M_j^tT v_i^t) + sum_t |v_i^t|^2`
/// with `M = [R | T]` and `p~ = (p, 1)`: the middle sums for every vertex and cluster are one
/// matrix product.
fn fit_errors(rest: &[Vector3<f64>], sub: &DMatrix<f64>, fits: &[BoneTransform], n_bones: usize) -> Vec<Vec<f64>> {
    let nt = sub.ncols() / 3;
    let mut mbig = DMatrix::zeros(3 * nt, 4 * n_bones);
    let mut h = vec![[0.0f64; 16]; n_bones];
    for k in 0..nt {
        for j in 0..n_bones {
            let b = &fits[k * n_bones + j];
            let mut m = [[0.0; 4]; 3];
            for (r, row) in m.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().take(3).enumerate() {
                    *x = b.rotation[(r, c)];
                }
                row[3] = b.translation[r];
                for (c, &x) in row.iter().enumerate() {
                    mbig[(3 * k + r, 4 * j + c)] = x;
                }
            }
            for a in 0..4 {
                for c in 0..4 {
                    h[j][a * 4 + c] += m[0][a] * m[0][c] + m[1][a] * m[1][c] + m[2][a] * m[2][c];
                }
            }
        }
    }
    const BLOCK: usize = 512;
    let nv = rest.len();
    let blocks: Vec<DMatrix<f64>> = (0..nv.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let lo = b * BLOCK;
            sub.rows(lo, (lo + BLOCK).min(nv) - lo) * &mbig
        })
        .collect();
    (0..nv)
        .into_par_iter()
        .map(|i| {
            let pt = [rest[i].x, rest[i].y, rest[i].z, 1.0];
            let vv: f64 = sub.row(i).iter().map(|x| x * x).sum();
            let cm = &blocks[i / BLOCK];
            let row = i % BLOCK;
            (0..n_bones)
                .map(|j| {
                    let mut quad = 0.0;
                    for a in 0..4 {
                        for c in 0..4 {
                            quad += pt[a] * h[j][a * 4 + c] * pt[c];
                        }
                    }
                    let lin: f64 = (0..4).map(|c| pt[c] * cm[(row, 4 * j + c)]).sum();
                    (quad - 2.0 * lin + vv).max(0.0)
                })
                .collect()
        })
        .collect()
}

/// Each cluster's unit-weight rigid transform at each of the frames `ts`, `[k][bone]`.
fn cluster_transforms(
    rest: &[Vector3<f64>],
    frames: &DMatrix<f64>,
    ts: &[usize],
    labels: &[usize],
    n_bones: usize,
) -> Vec<BoneTransform> {
    ts.par_iter()
        .flat_map_iter(|&t| {
            let mut sums = vec![RigidFitSums::default(); n_bones];
            for (i, &l) in labels.iter().enumerate() {
                sums[l].add(&rest[i], &at(frames, i, t), 1.0);
            }
            sums.into_iter().map(|s| s.solve().unwrap_or_else(BoneTransform::identity)).collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_frames_are_even_and_include_the_ends() {
        assert_eq!(sample_frames(5, 64), vec![0, 1, 2, 3, 4]);
        let s = sample_frames(1000, 64);
        assert_eq!(s.len(), 64);
        assert_eq!((s[0], s[63]), (0, 999));
    }

    #[test]
    fn two_rigid_parts_are_found() {
        // Two blocks of 20 points; the second rotates about z over the frames, the first stays.
        let rest: Vec<Vector3<f64>> = (0..40)
            .map(|i| Vector3::new((i % 20) as f64 * 0.1, if i < 20 { 0.0 } else { 1.0 }, (i % 3) as f64 * 0.2))
            .collect();
        let n_frames = 8;
        let frames = DMatrix::from_fn(40, 3 * n_frames, |i, c| {
            let (t, r) = (c / 3, c % 3);
            let p = rest[i];
            let q = if i < 20 {
                p
            } else {
                let a = t as f64 * 0.2;
                Vector3::new(a.cos() * p.x - a.sin() * p.y, a.sin() * p.x + a.cos() * p.y, p.z)
            };
            q[r]
        });
        let labels = rigid_clusters(&rest, &frames, 2, 10, 7);
        assert!(labels[..20].iter().all(|&l| l == labels[0]));
        assert!(labels[20..].iter().all(|&l| l == labels[20]));
        assert_ne!(labels[0], labels[20]);
        assert_eq!(labels, rigid_clusters(&rest, &frames, 2, 10, 7), "same seed, same clusters");
    }
}

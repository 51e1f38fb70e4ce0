//! Pose interpolation (thesis 2.4): linear (eq. 2.23) and non-linear, gradient-domain
//! (eq. 2.45-2.49).
//!
//! Both start by aligning pose j onto pose i with the motion-plane alignment (eq. 2.3-2.5).
//! Non-linear: per triangle, the deformation gradient J (i -> j, eq. 2.6) is split as J = R S;
//! the interpolated gradient is T(lambda) = exp(lambda log R) ((1 - lambda) I + lambda S)
//! (eq. 2.45) or exp(lambda log R) exp(lambda log S) (eq. 2.46); pose i's gradients deformed by
//! T are integrated by the Poisson system of pose i (eq. 2.47-2.48). The same is done from pose
//! j with its own gradient J^-1 (j -> i) at 1 - lambda, and the two are blended with
//! (1 - lambda, lambda) (eq. 2.49). Each one-sided solution has one free translation per
//! connected component: every component is pinned to the linearly interpolated centroid of that
//! component before blending (PAPER-NOTES).
//!
//! Convention: with gradients stored as G_m = sum grad(phi_k) v_k^T (rows = derivative axis),
//! a deformation v -> T v changes them to G_m T^T; the thesis's "T G_m" (eq. 2.47) is the
//! same operation written on the transposed gradient.
//!
//! Precompute/solve split: [`NonlinearInterpolator::new`] factorises both Poisson systems and
//! decomposes every triangle's gradient once; [`NonlinearInterpolator::at`] is per-lambda work.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use surfcap_mesh::{Topology, UpAxis};

use crate::deformation_gradient::deformation_polar_factors;
use crate::error::Result;
use crate::motion_plane_alignment::motion_plane_alignment;
use crate::poisson_reconstruction::{PoissonPattern, PoissonSolver};
use crate::rotation_log_exp::{exp_rotation, log_rotation};

/// How the stretch factor S is interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StretchInterpolation {
    /// eq. 2.45: (1 - lambda) I + lambda S.
    Linear,
    /// eq. 2.46: exp(lambda log S).
    Log,
}

impl std::str::FromStr for StretchInterpolation {
    type Err = crate::pose_distance::UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "linear" => Ok(StretchInterpolation::Linear),
            "log" => Ok(StretchInterpolation::Log),
            _ => Err(crate::pose_distance::UnknownName { given: s.to_string(), expected: "linear or log" }),
        }
    }
}

/// Pose j moved onto pose i by the motion-plane alignment.
pub fn align_onto(pi: &[f32], pj: &[f32], up: UpAxis) -> Vec<f32> {
    let (m, _) = motion_plane_alignment(pi, pj, None, up);
    let mut out = pj.to_vec();
    m.apply(&mut out);
    out
}

/// eq. 2.23 after alignment: (1 - lambda) v_i + lambda v_j.
pub fn linear_interpolation(pi: &[f32], pj_aligned: &[f32], lambda: f64) -> Vec<f32> {
    pi.iter().zip(pj_aligned).map(|(&a, &b)| ((1.0 - lambda) * a as f64 + lambda * b as f64) as f32).collect()
}

/// One side's per-triangle data: log R, S, and the pose's own gradients.
struct Side {
    solver: PoissonSolver,
    log_r: Vec<Vector3<f64>>,
    s: Vec<Matrix3<f64>>,
    grads: Vec<Matrix3<f64>>,
    centroids: Vec<Vector3<f64>>,
}

fn side(pattern: &Arc<PoissonPattern>, topology: &Topology, from: &[f32], to: &[f32]) -> Result<Side> {
    let solver = PoissonSolver::with_pattern(pattern.clone(), topology, from)?;
    let grads = solver.operator().gradients(from);
    let mut log_r = Vec::with_capacity(topology.n_triangles());
    let mut s = Vec::with_capacity(topology.n_triangles());
    for rs in deformation_polar_factors(topology, from, to) {
        // A zero-area triangle (in either pose) has no deformation gradient: it keeps its
        // gradient (identity deformation); it has zero area, so it does not weigh in L anyway.
        let (r, st) = rs.unwrap_or((Matrix3::identity(), Matrix3::identity()));
        log_r.push(log_rotation(&r));
        s.push(st);
    }
    let centroids = solver.component_centroids(from);
    Ok(Side { solver, log_r, s, grads, centroids })
}

/// S^t for a symmetric positive (semi-)definite S: exp(t log S) through its eigen-decomposition
/// (eigenvalues floored at 1e-12 so that a degenerate stretch stays finite).
fn sym_power(s: &Matrix3<f64>, t: f64) -> Matrix3<f64> {
    let e = s.symmetric_eigen();
    let d = e.eigenvalues.map(|x| (t * x.max(1e-12).ln()).exp());
    e.eigenvectors * Matrix3::from_diagonal(&d) * e.eigenvectors.transpose()
}

impl Side {
    /// Solution of this side at parameter `t` (0 = this pose), with components pinned to
    /// `centroids`.
    fn at(&self, t: f64, stretch: StretchInterpolation, centroids: &[Vector3<f64>]) -> Vec<f32> {
        let targets: Vec<Matrix3<f64>> = (0..self.grads.len())
            .map(|m| {
                let r = exp_rotation(&(self.log_r[m] * t));
                let s = match stretch {
                    StretchInterpolation::Linear => Matrix3::identity() * (1.0 - t) + self.s[m] * t,
                    StretchInterpolation::Log => sym_power(&self.s[m], t),
                };
                self.grads[m] * (r * s).transpose()
            })
            .collect();
        self.solver.solve(&targets, centroids)
    }
}

/// Factorised, decomposed data for interpolating one pair of poses many times.
pub struct NonlinearInterpolator {
    pi: Vec<f32>,
    pj: Vec<f32>,
    from_i: Side,
    from_j: Side,
}

impl NonlinearInterpolator {
    /// `pj` is aligned onto `pi` (motion plane) first.
    pub fn new(topology: &Topology, pi: &[f32], pj: &[f32], up: UpAxis) -> Result<Self> {
        Self::with_pattern(&Arc::new(PoissonPattern::new(topology)?), topology, pi, pj, up)
    }

    /// As [`NonlinearInterpolator::new`], reusing the topology's symbolic factorisation (for
    /// callers that interpolate many pairs of one mesh, such as Blend).
    pub fn with_pattern(
        pattern: &Arc<PoissonPattern>,
        topology: &Topology,
        pi: &[f32],
        pj: &[f32],
        up: UpAxis,
    ) -> Result<Self> {
        let pj = align_onto(pi, pj, up);
        Self::as_placed(pattern, topology, pi, &pj)
    }

    /// As [`NonlinearInterpolator::with_pattern`] without the alignment: the two poses are
    /// interpolated where they are (for a subject kept in its captured placement, whose frames
    /// already share one).
    pub fn as_placed(pattern: &Arc<PoissonPattern>, topology: &Topology, pi: &[f32], pj: &[f32]) -> Result<Self> {
        // The two sides are independent: factorise them on two threads; one symbolic
        // factorisation serves both poses (same topology).
        let (from_i, from_j) = rayon::join(|| side(pattern, topology, pi, pj), || side(pattern, topology, pj, pi));
        let (from_i, from_j) = (from_i?, from_j?);
        Ok(NonlinearInterpolator { pi: pi.to_vec(), pj: pj.to_vec(), from_i, from_j })
    }

    /// Pose j after alignment onto pose i.
    pub fn aligned_target(&self) -> &[f32] {
        &self.pj
    }

    /// The interpolated pose at `lambda` (eq. 2.49).
    pub fn at(&self, lambda: f64, stretch: StretchInterpolation) -> Vec<f32> {
        let centroids: Vec<Vector3<f64>> = self
            .from_i
            .centroids
            .iter()
            .zip(&self.from_j.centroids)
            .map(|(a, b)| a * (1.0 - lambda) + b * lambda)
            .collect();
        let vi = self.from_i.at(lambda, stretch, &centroids);
        let vj = self.from_j.at(1.0 - lambda, stretch, &centroids);
        vi.iter().zip(&vj).map(|(&a, &b)| ((1.0 - lambda) * a as f64 + lambda * b as f64) as f32).collect()
    }

    /// Linear interpolation (eq. 2.23) of the same aligned pair.
    pub fn linear(&self, lambda: f64) -> Vec<f32> {
        linear_interpolation(&self.pi, &self.pj, lambda)
    }
}

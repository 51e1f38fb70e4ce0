//! Motion-plane alignment (thesis eq. 2.2-2.5): the rotation about the up axis and the
//! translation in the ground plane that best align pose j onto pose i, in closed form, with
//! per-vertex weights.
//!
//! Notes on the reading:
//! - eq. 2.3 is written as tan^-1 of a ratio; we use atan2 of numerator and denominator, which
//!   gives the minimiser in every quadrant (the ratio alone can pick the maximiser, theta + pi).
//! - the residual of eq. 2.2 is taken over full 3D positions (the vertical coordinate cannot be
//!   aligned by a ground-plane motion but is part of the pose), as in Kovar et al.'s point-cloud
//!   metric that eq. 2.2 adapts.
//! - the up axis comes from the subject: the "x, z" of the thesis are the two other axes.

use nalgebra::{Matrix3, Vector3};
use surfcap_mesh::UpAxis;

/// Horizontal coordinate indices (u, v) and the vertical index for an up axis; the map
/// (u, v) -> (u cos + v sin, -u sin + v cos) is the rotation about the up axis by theta
/// (for +y up, u = x and v = z as in eq. 2.3-2.5).
pub fn plane_axes(up: UpAxis) -> (usize, usize, usize) {
    match up.axis_and_sign().0 {
        0 => (1, 2, 0),
        1 => (0, 2, 1),
        _ => (0, 1, 2),
    }
}

/// A rigid motion of the ground plane: rotation `theta` about the up axis, then translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneMotion {
    pub theta: f64,
    /// Translation along the (u, v) horizontal axes (x0, z0 of eq. 2.4-2.5 for +y up).
    pub t: [f64; 2],
    pub up: UpAxis,
}

impl PlaneMotion {
    pub fn identity(up: UpAxis) -> Self {
        PlaneMotion { theta: 0.0, t: [0.0; 2], up }
    }

    /// The rotation as a 3x3 matrix acting on column vectors.
    pub fn rotation(&self) -> Matrix3<f64> {
        rotation_about_up(self.up, self.theta)
    }

    /// Move(S, theta, C, T) of the thesis (Algorithms 2-3): rotation by `theta` about the up axis
    /// through `centre`, then the ground-plane translation `t`.
    pub fn about(theta: f64, centre: [f64; 3], t: [f64; 2], up: UpAxis) -> Self {
        let (iu, iv, _) = plane_axes(up);
        let (s, c) = theta.sin_cos();
        let (cu, cv) = (centre[iu], centre[iv]);
        PlaneMotion { theta, t: [cu - (cu * c + cv * s) + t[0], cv - (-cu * s + cv * c) + t[1]], up }
    }

    /// `self` after `first`: x -> self(first(x)).
    pub fn after(&self, first: &PlaneMotion) -> PlaneMotion {
        let (s, c) = self.theta.sin_cos();
        let [u, v] = first.t;
        PlaneMotion {
            theta: self.theta + first.theta,
            t: [u * c + v * s + self.t[0], -u * s + v * c + self.t[1]],
            up: self.up,
        }
    }

    /// The motion applied to one point.
    pub fn apply_point(&self, p: [f64; 3]) -> [f64; 3] {
        let (iu, iv, _) = plane_axes(self.up);
        let (s, c) = self.theta.sin_cos();
        let mut q = p;
        q[iu] = p[iu] * c + p[iv] * s + self.t[0];
        q[iv] = -p[iu] * s + p[iv] * c + self.t[1];
        q
    }

    /// Applies the motion to `[n][3]` positions in place.
    pub fn apply(&self, positions: &mut [f32]) {
        let (iu, iv, _) = plane_axes(self.up);
        let (s, c) = self.theta.sin_cos();
        for p in positions.chunks_exact_mut(3) {
            let (u, v) = (p[iu] as f64, p[iv] as f64);
            p[iu] = (u * c + v * s + self.t[0]) as f32;
            p[iv] = (-u * s + v * c + self.t[1]) as f32;
        }
    }
}

/// Rotation by `theta` about the up axis in the convention of [`plane_axes`].
pub fn rotation_about_up(up: UpAxis, theta: f64) -> Matrix3<f64> {
    let (iu, iv, iw) = plane_axes(up);
    let (s, c) = theta.sin_cos();
    let mut m = Matrix3::zeros();
    m[(iu, iu)] = c;
    m[(iu, iv)] = s;
    m[(iv, iu)] = -s;
    m[(iv, iv)] = c;
    m[(iw, iw)] = 1.0;
    m
}

/// The motion minimising sum_k w_k |p_i(k) - T p_j(k)|^2 (eq. 2.3-2.5) and that minimum
/// (eq. 2.2). `weights` of `None` means all ones. Positions are `[n][3]`.
pub fn motion_plane_alignment(pi: &[f32], pj: &[f32], weights: Option<&[f64]>, up: UpAxis) -> (PlaneMotion, f64) {
    let (iu, iv, iw) = plane_axes(up);
    let n = pi.len() / 3;
    let w = |k: usize| weights.map_or(1.0, |w| w[k]);
    let mut sw = 0.0;
    let mut mi = [0.0f64; 2];
    let mut mj = [0.0f64; 2];
    for k in 0..n {
        let wk = w(k);
        sw += wk;
        mi[0] += wk * pi[3 * k + iu] as f64;
        mi[1] += wk * pi[3 * k + iv] as f64;
        mj[0] += wk * pj[3 * k + iu] as f64;
        mj[1] += wk * pj[3 * k + iv] as f64;
    }
    if sw <= 0.0 {
        return (PlaneMotion::identity(up), 0.0);
    }
    for m in [&mut mi, &mut mj] {
        m[0] /= sw;
        m[1] /= sw;
    }
    let (mut num, mut den, mut hi, mut hj, mut vert) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let wk = w(k);
        let (ui, vi) = (pi[3 * k + iu] as f64 - mi[0], pi[3 * k + iv] as f64 - mi[1]);
        let (uj, vj) = (pj[3 * k + iu] as f64 - mj[0], pj[3 * k + iv] as f64 - mj[1]);
        num += wk * (ui * vj - vi * uj);
        den += wk * (ui * uj + vi * vj);
        hi += wk * (ui * ui + vi * vi);
        hj += wk * (uj * uj + vj * vj);
        let dy = pi[3 * k + iw] as f64 - pj[3 * k + iw] as f64;
        vert += wk * dy * dy;
    }
    let theta = num.atan2(den);
    let (s, c) = theta.sin_cos();
    let t = [mi[0] - (mj[0] * c + mj[1] * s), mi[1] - (-mj[0] * s + mj[1] * c)];
    let residual = (hi + hj - 2.0 * (num * num + den * den).sqrt()).max(0.0) + vert;
    (PlaneMotion { theta, t, up }, residual)
}

/// Full 3D Procrustes: rotation R, translation t and optional uniform scale s minimising
/// sum_k w_k |p_i(k) - (s R p_j(k) + t)|^2 (Kabsch/Umeyama, det R = +1).
pub fn procrustes(
    pi: &[f32],
    pj: &[f32],
    weights: Option<&[f64]>,
    with_scale: bool,
) -> (Matrix3<f64>, Vector3<f64>, f64) {
    let n = pi.len() / 3;
    let w = |k: usize| weights.map_or(1.0, |w| w[k]);
    let p = |a: &[f32], k: usize| Vector3::new(a[3 * k] as f64, a[3 * k + 1] as f64, a[3 * k + 2] as f64);
    let sw: f64 = (0..n).map(w).sum();
    if sw <= 0.0 {
        return (Matrix3::identity(), Vector3::zeros(), 1.0);
    }
    let ci = (0..n).map(|k| p(pi, k) * w(k)).sum::<Vector3<f64>>() / sw;
    let cj = (0..n).map(|k| p(pj, k) * w(k)).sum::<Vector3<f64>>() / sw;
    let mut h = Matrix3::zeros();
    let mut var_j = 0.0;
    for k in 0..n {
        let (a, b) = (p(pi, k) - ci, p(pj, k) - cj);
        h += w(k) * a * b.transpose();
        var_j += w(k) * b.norm_squared();
    }
    // R maximises tr(R^T H): the rotation factor of H's polar decomposition.
    let (r, s_sym) = crate::polar_decomposition::polar_decomposition(&h);
    let scale = if with_scale && var_j > 0.0 { s_sym.trace() / var_j } else { 1.0 };
    let t = ci - scale * r * cj;
    (r, t, scale)
}

#[cfg(test)]
mod tests {
    #[test]
    fn composition_and_move_about_a_centre() {
        let up = UpAxis::PosY;
        let a = PlaneMotion { theta: 0.7, t: [1.0, -2.0], up };
        let b = PlaneMotion { theta: -2.1, t: [0.3, 0.5], up };
        let p = [0.4, 1.5, -0.8];
        let ab = a.after(&b).apply_point(p);
        let seq = a.apply_point(b.apply_point(p));
        for k in 0..3 {
            assert!((ab[k] - seq[k]).abs() < 1e-12);
        }
        let c = [2.0, 7.0, 3.0];
        let m = PlaneMotion::about(1.1, c, [0.5, -0.25], up);
        let q = m.apply_point(c);
        assert!((q[0] - 2.5).abs() < 1e-12 && (q[1] - 7.0).abs() < 1e-12 && (q[2] - 2.75).abs() < 1e-12);
        let mut f = vec![p[0] as f32, p[1] as f32, p[2] as f32];
        m.apply(&mut f);
        let r = m.apply_point(p);
        assert!((f[0] as f64 - r[0]).abs() < 1e-6 && (f[2] as f64 - r[2]).abs() < 1e-6);
    }

    use super::*;

    fn pose() -> Vec<f32> {
        vec![0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 1.0, 2.0, -1.0, 0.3, 0.7, 0.2, 1.5, -1.0]
    }

    #[test]
    fn recovers_a_ground_plane_motion_for_every_up_axis_and_angle() {
        for up in [UpAxis::PosY, UpAxis::PosZ, UpAxis::PosX, UpAxis::NegY] {
            for theta in [0.0, 0.5, 2.0, 3.1, -2.5] {
                let pi = pose();
                let mut pj = pi.clone();
                // pj = M^-1 pi, so that aligning pj onto pi must find M.
                let m = PlaneMotion { theta, t: [0.3, -1.2], up };
                let r = m.rotation();
                let (iu, iv, _) = plane_axes(up);
                for q in pj.chunks_exact_mut(3) {
                    q[iu] -= m.t[0] as f32;
                    q[iv] -= m.t[1] as f32;
                    let v = r.transpose() * Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64);
                    q.copy_from_slice(&[v.x as f32, v.y as f32, v.z as f32]);
                }
                let (found, residual) = motion_plane_alignment(&pi, &pj, None, up);
                let dtheta = (found.theta - theta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                assert!(dtheta.abs() < 1e-5, "{up:?} {theta}: {}", found.theta);
                assert!(residual < 1e-9, "{residual}");
                let mut back = pj.clone();
                found.apply(&mut back);
                for (a, b) in back.iter().zip(&pi) {
                    assert!((a - b).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn procrustes_recovers_rotation_translation_scale() {
        let pi = pose();
        let r = crate::rotation_log_exp::exp_rotation(&Vector3::new(0.4, -1.1, 2.0));
        let pj: Vec<f32> = pi
            .chunks_exact(3)
            .flat_map(|q| {
                let v = (r.transpose()
                    * (Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64) - Vector3::new(1.0, 2.0, 3.0)))
                    / 2.0;
                [v.x as f32, v.y as f32, v.z as f32]
            })
            .collect();
        let (rr, t, s) = procrustes(&pi, &pj, None, true);
        assert!((rr - r).norm() < 1e-5 && (s - 2.0).abs() < 1e-5 && (t - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-5);
    }
}

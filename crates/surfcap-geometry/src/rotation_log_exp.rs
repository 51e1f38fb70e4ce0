//! Rotation logarithm and exponential on SO(3), exact for every angle in [0, pi].
//!
//! thesis eq. 2.1 and 2.13 use (1/sqrt 2) ||log R||_F, which is the rotation angle of R; eq. 2.45
//! needs exp(lambda log R). The logarithm goes through a unit quaternion (nalgebra's
//! trace-branching conversion), so it stays exact near pi where the axis-from-antisymmetric-part
//! formula breaks down (PAPER-NOTES: "near pi the axis is ill-defined but the angle is not").

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// Rotation angle of `r` in [0, pi] (equals (1/sqrt 2) ||log r||_F), from atan2 of the
/// antisymmetric and symmetric parts: accurate at 0 and at pi alike.
pub fn rotation_angle(r: &Matrix3<f64>) -> f64 {
    let s = 0.5 * Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]).norm();
    let c = 0.5 * (r.trace() - 1.0);
    s.atan2(c)
}

/// log of a rotation as an axis-angle vector (angle in [0, pi]).
pub fn log_rotation(r: &Matrix3<f64>) -> Vector3<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r));
    let (mut w, mut v) = (q.w, q.imag());
    if w < 0.0 {
        w = -w;
        v = -v;
    }
    let n = v.norm();
    // angle = 2 atan2(n, w); factor = angle / n, with its limit 2 / w as n -> 0.
    let factor = if n < 1e-8 { 2.0 / w * (1.0 - n * n / (3.0 * w * w)) } else { 2.0 * n.atan2(w) / n };
    v * factor
}

/// exp of an axis-angle vector (Rodrigues' formula, series-safe near zero).
pub fn exp_rotation(w: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::new(*w).into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_exp_round_trip_for_all_angles_including_pi() {
        let axes = [Vector3::x(), Vector3::new(1.0, -2.0, 0.5).normalize(), Vector3::new(0.0, 1.0, 1.0).normalize()];
        for a in axes {
            for angle in [0.0, 1e-12, 1e-6, 0.3, 1.0, 3.0, std::f64::consts::PI - 1e-9, std::f64::consts::PI] {
                let r = exp_rotation(&(a * angle));
                assert!((rotation_angle(&r) - angle).abs() < 1e-9, "angle {angle}");
                let w = log_rotation(&r);
                assert!((w.norm() - angle).abs() < 1e-9, "log norm at {angle}");
                let back = exp_rotation(&w);
                assert!((back - r).norm() < 1e-9, "exp(log) at {angle}");
            }
        }
    }
}

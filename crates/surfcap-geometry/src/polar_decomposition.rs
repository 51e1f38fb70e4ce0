//! Polar decomposition T = R S with R a rotation (det R = +1) and S symmetric.
//!
//! thesis eq. 2.8-2.12 derive it from the eigen-decomposition of T^T T and then divide R by
//! det(R) to land in SO(3). Dividing by det(R) = -1 turns R into -R, a rotation by pi composed
//! with the reflection, and makes S = -S far from the identity; we use the standard fix instead:
//! from the SVD T = U diag(s) V^T, flip the singular direction of the smallest singular value when
//! det(U V^T) < 0, which gives the rotation nearest to T (R = U D V^T, S = V D diag(s) V^T,
//! D = diag(1, 1, -1)). Both give det R = +1; this one is continuous as T crosses a reflection
//! and exact (to rounding) for near-singular T. (Eq. 2.7 as printed averages R with R^T; the
//! iteration that converges averages with R^-T; the SVD route avoids iterations altogether.)

use nalgebra::Matrix3;

/// R (rotation) and S (symmetric) with T = R S.
pub fn polar_decomposition(t: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let svd = t.svd(true, true);
    let (Some(mut u), Some(v_t)) = (svd.u, svd.v_t) else {
        // nalgebra always returns both factors when asked; keep a total function anyway.
        return (Matrix3::identity(), *t);
    };
    let mut s = svd.singular_values;
    if (u * v_t).determinant() < 0.0 {
        // Smallest singular value: flip its direction.
        let k = s.imin();
        u.column_mut(k).neg_mut();
        s[k] = -s[k];
    }
    let r = u * v_t;
    let sym = v_t.transpose() * Matrix3::from_diagonal(&s) * v_t;
    (r, sym)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(t: Matrix3<f64>) {
        let (r, s) = polar_decomposition(&t);
        assert!((r.determinant() - 1.0).abs() < 1e-12, "det R = {}", r.determinant());
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
        assert!((s - s.transpose()).norm() < 1e-12 * (1.0 + t.norm()));
        assert!((r * s - t).norm() < 1e-12 * (1.0 + t.norm()), "RS != T");
    }

    #[test]
    fn exact_for_general_singular_and_reflected_matrices() {
        check(Matrix3::new(1.0, 0.2, 0.0, -0.3, 2.0, 0.5, 0.1, 0.0, 0.7));
        check(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0)); // singular
        check(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1e-14)); // near-singular
        check(Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0)); // reflection
        check(Matrix3::new(0.0, -2.0, 0.0, 3.0, 0.0, 0.0, 0.0, 0.0, -0.5)); // rotation x reflection
        // A pure rotation is its own polar factor.
        let r0 = crate::rotation_log_exp::exp_rotation(&nalgebra::Vector3::new(0.3, -1.0, 2.0));
        let (r, s) = polar_decomposition(&r0);
        assert!((r - r0).norm() < 1e-12 && (s - Matrix3::identity()).norm() < 1e-12);
    }
}

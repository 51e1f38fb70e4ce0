//! Sparse Cholesky factorisation A = L Lᵀ of a symmetric positive definite matrix (faer), split
//! as faer and libigl split it: [`SymbolicLlt::new`] computes the fill-reducing ordering and the
//! elimination tree of a sparsity pattern once; [`SymbolicLlt::factorize`] computes the numeric
//! factor of any matrix of that pattern; [`SymbolicLlt::solve_in_place`] does the two triangular
//! solves. Only the lower triangle of a matrix is read.
//!
//! Everything runs sequentially (`Par::Seq`): on the project's 2-core machine faer's parallel
//! sparse solve was about 40 times slower than the sequential one; callers that have several
//! right-hand sides in flight run them side by side on threads of their own.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, factorize_symbolic_cholesky};
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// The symbolic Cholesky factorisation of a sparsity pattern, shared by every matrix of it.
pub struct SymbolicLlt {
    symbolic: SymbolicCholesky<usize>,
}

/// The numeric Cholesky factor of one matrix, for the [`SymbolicLlt`] that made it.
pub struct NumericLlt {
    values: Vec<f64>,
}

impl NumericLlt {
    /// Stored entries of the factor (8 bytes each, plus their row indices in the symbolic part).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

impl SymbolicLlt {
    /// The ordering and elimination tree of `pattern`'s lower triangle.
    pub fn new(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, FaerError> {
        let symbolic = factorize_symbolic_cholesky(pattern, Side::Lower, Default::default(), Default::default())?;
        Ok(SymbolicLlt { symbolic })
    }

    /// The numeric factor of `mat`, whose pattern is the one this was made from (lower triangle
    /// read, no regularisation).
    pub fn factorize(&self, mat: SparseColMatRef<'_, usize, f64>) -> Result<NumericLlt, LltError> {
        let mut values = vec![0.0f64; self.symbolic.len_val()];
        let scratch = self.symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        self.symbolic.factorize_numeric_llt::<f64>(
            &mut values,
            mat,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(scratch)),
            Default::default(),
        )?;
        Ok(NumericLlt { values })
    }

    /// Overwrites every column b of `rhs` with A⁻¹ b, A the matrix `numeric` factors.
    pub fn solve_in_place(&self, numeric: &NumericLlt, rhs: MatMut<'_, f64>) {
        let scratch = self.symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq);
        LltRef::<'_, usize, f64>::new(&self.symbolic, &numeric.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(scratch)),
        );
    }
}

#[cfg(test)]
mod tests {
    use faer::Mat;
    use faer::sparse::{SparseColMat, Triplet};

    use super::*;

    /// The 1D Laplacian plus the identity (tridiagonal 3, -1): one pattern, two matrices, and
    /// A x = b solved to round-off for both.
    #[test]
    fn one_pattern_factors_two_matrices_and_solves_them() {
        let n = 6;
        let matrix = |diag: f64| {
            let mut t = Vec::new();
            for i in 0..n {
                t.push(Triplet::new(i, i, diag));
                if i + 1 < n {
                    t.push(Triplet::new(i + 1, i, -1.0));
                }
            }
            SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap()
        };
        let a = matrix(3.0);
        let symbolic = SymbolicLlt::new(a.symbolic()).unwrap();
        for diag in [3.0, 5.0] {
            let a = matrix(diag);
            let numeric = symbolic.factorize(a.as_ref()).unwrap();
            assert!(!numeric.is_empty());
            let x: Vec<f64> = (0..n).map(|i| i as f64 - 2.0).collect();
            let b: Vec<f64> = (0..n)
                .map(|i| {
                    let left = if i > 0 { -x[i - 1] } else { 0.0 };
                    let right = if i + 1 < n { -x[i + 1] } else { 0.0 };
                    diag * x[i] + left + right
                })
                .collect();
            let mut rhs = Mat::<f64>::from_fn(n, 1, |i, _| b[i]);
            symbolic.solve_in_place(&numeric, rhs.as_mut());
            for i in 0..n {
                assert!((rhs[(i, 0)] - x[i]).abs() < 1e-12, "{diag}: x[{i}] = {}", rhs[(i, 0)]);
            }
        }
    }

    #[test]
    fn a_matrix_that_is_not_positive_definite_is_an_error() {
        let t = [Triplet::new(0, 0, 1.0), Triplet::new(1, 0, 2.0), Triplet::new(1, 1, 1.0)];
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &t).unwrap();
        let symbolic = SymbolicLlt::new(a.symbolic()).unwrap();
        assert!(symbolic.factorize(a.as_ref()).is_err());
    }
}

//! Dense matrix helpers shared by the learning algorithms: checked construction from row-major
//! data, serde for `faer::Mat` (as `{rows, cols, data}` row-major), `.npy` save/load (f64,
//! C order) so fitted models open in numpy, Cholesky with adaptive jitter, and the
//! AVX-512 upper-state clearing that keeps libm calls fast after faer kernels.

use std::path::Path;

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, MatRef, Side};
use npyz::WriterBuilder;
use serde::{Deserialize, Serialize};

use crate::error::{LearnError, Result};

/// A matrix from row-major data, checking the size and that every value is finite.
pub fn from_rows(rows: usize, cols: usize, data: &[f64]) -> Result<Mat<f64>> {
    if data.len() != rows * cols {
        return Err(LearnError::Dimension(format!(
            "{} values for a {rows} x {cols} matrix: expected {}",
            data.len(),
            rows * cols
        )));
    }
    check_finite_slice(data, "matrix")?;
    Ok(Mat::from_fn(rows, cols, |i, j| data[i * cols + j]))
}

/// Row-major copy of a matrix.
pub fn to_rows(m: MatRef<'_, f64>) -> Vec<f64> {
    let mut out = Vec::with_capacity(m.nrows() * m.ncols());
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            out.push(m[(i, j)]);
        }
    }
    out
}

/// Error unless every entry is finite; `what` names the input in the message.
pub fn check_finite(m: MatRef<'_, f64>, what: &str) -> Result<()> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(LearnError::NonFinite(format!("{what}[{i}, {j}] = {}", m[(i, j)])));
            }
        }
    }
    Ok(())
}

/// Error unless every value is finite.
pub fn check_finite_slice(v: &[f64], what: &str) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(k) => Err(LearnError::NonFinite(format!("{what}[{k}] = {}", v[k]))),
        None => Ok(()),
    }
}

/// Serde for `faer::Mat<f64>`: `#[serde(with = "crate::matrix::serde_mat")]`.
pub mod serde_mat {
    use super::*;

    #[derive(Serialize, Deserialize)]
    struct Dense {
        rows: usize,
        cols: usize,
        data: Vec<f64>,
    }

    pub fn serialize<S: serde::Serializer>(m: &Mat<f64>, s: S) -> std::result::Result<S::Ok, S::Error> {
        Dense { rows: m.nrows(), cols: m.ncols(), data: to_rows(m.as_ref()) }.serialize(s)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Mat<f64>, D::Error> {
        let x = Dense::deserialize(d)?;
        from_rows(x.rows, x.cols, &x.data).map_err(serde::de::Error::custom)
    }
}

/// Serde for `Vec<faer::Mat<f64>>`.
pub mod serde_mats {
    use super::*;

    #[derive(Serialize, Deserialize)]
    struct Wrap(#[serde(with = "super::serde_mat")] Mat<f64>);

    pub fn serialize<S: serde::Serializer>(m: &[Mat<f64>], s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(m.len()))?;
        for x in m {
            seq.serialize_element(&Wrap(x.clone()))?;
        }
        seq.end()
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Vec<Mat<f64>>, D::Error> {
        Ok(Vec::<Wrap>::deserialize(d)?.into_iter().map(|w| w.0).collect())
    }
}

/// Writes `m` as a C-order `<f8` `.npy` array of shape `[rows, cols]`, through a temporary file
/// in the same folder renamed at the end (an interrupted write leaves no half-written file).
pub fn save_npy(path: &Path, m: MatRef<'_, f64>) -> Result<()> {
    let io = |source| LearnError::Io { path: path.display().to_string(), source };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let write = || -> std::io::Result<()> {
        let file = std::fs::File::create(&tmp)?;
        let shape = [m.nrows() as u64, m.ncols() as u64];
        let mut w = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&shape)
            .writer(std::io::BufWriter::new(file))
            .begin_nd()?;
        w.extend(to_rows(m))?;
        w.finish()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })
}

/// Reads a 2-D (or 1-D, as one column) `.npy` array of `f64` or `f32` values.
pub fn load_npy(path: &Path) -> Result<Mat<f64>> {
    let io = |source| LearnError::Io { path: path.display().to_string(), source };
    let bytes = std::fs::read(path).map_err(io)?;
    let npy = npyz::NpyFile::new(&bytes[..]).map_err(io)?;
    let shape = npy.shape().to_vec();
    let fortran = npy.order() == npyz::Order::Fortran;
    let (rows, cols) = match shape.as_slice() {
        [n] => (*n as usize, 1),
        [r, c] => (*r as usize, *c as usize),
        s => return Err(LearnError::Dimension(format!("{}: shape {s:?}: expected 1 or 2 axes", path.display()))),
    };
    let data: Vec<f64> = match npy.dtype() {
        npyz::DType::Plain(t) if t.type_char() == npyz::TypeChar::Float && t.size_field() == 4 => {
            npy.into_vec::<f32>().map_err(io)?.into_iter().map(f64::from).collect()
        }
        _ => npy.into_vec::<f64>().map_err(io)?,
    };
    if fortran {
        check_finite_slice(&data, "npy")?;
        if data.len() != rows * cols {
            return Err(LearnError::Dimension(format!("{}: truncated array", path.display())));
        }
        return Ok(Mat::from_fn(rows, cols, |i, j| data[j * rows + i]));
    }
    from_rows(rows, cols, &data)
}

/// A Cholesky factor with the jitter that had to be added to the diagonal.
pub struct Factor {
    pub llt: faer::linalg::solvers::Llt<f64>,
    /// Jitter added to every diagonal entry (0 when none was needed).
    pub jitter: f64,
}

impl Factor {
    /// log |K + jitter I| = 2 sum log L_ii.
    pub fn log_det(&self) -> f64 {
        let l = self.llt.L();
        (0..l.nrows()).map(|i| l[(i, i)].ln()).sum::<f64>() * 2.0
    }

    /// K^-1 (the full inverse, used by the gradient trace terms).
    pub fn inverse(&self) -> Mat<f64> {
        self.llt.inverse()
    }

    /// K^-1 B.
    pub fn solve(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        use faer::linalg::solvers::Solve;
        self.llt.solve(b)
    }
}

/// Largest jitter tried, relative to the mean diagonal.
pub const MAX_RELATIVE_JITTER: f64 = 1e-2;

/// Cholesky of the symmetric matrix `k` (lower triangle used) with adaptive jitter: none first,
/// then 1e-10 times the mean diagonal, growing tenfold up to [`MAX_RELATIVE_JITTER`]; a matrix
/// that still fails is an error, never a panic.
pub fn cholesky_jitter(k: MatRef<'_, f64>, what: &str) -> Result<Factor> {
    let n = k.nrows();
    if n != k.ncols() {
        return Err(LearnError::Dimension(format!("{what}: {} x {} is not square", n, k.ncols())));
    }
    if n == 0 {
        return Err(LearnError::Invalid(format!("{what}: empty matrix")));
    }
    let mean_diag = (0..n).map(|i| k[(i, i)]).sum::<f64>() / n as f64;
    if !mean_diag.is_finite() {
        return Err(LearnError::NonFinite(format!("{what}: diagonal mean {mean_diag}")));
    }
    if let Ok(llt) = k.llt(Side::Lower) {
        return Ok(Factor { llt, jitter: 0.0 });
    }
    let scale = mean_diag.abs().max(f64::MIN_POSITIVE);
    let mut rel = 1e-10;
    let mut kj = k.to_owned();
    let mut added = 0.0;
    while rel <= MAX_RELATIVE_JITTER * 1.0001 {
        let jitter = rel * scale;
        for i in 0..n {
            kj[(i, i)] += jitter - added;
        }
        added = jitter;
        if let Ok(llt) = kj.llt(Side::Lower) {
            return Ok(Factor { llt, jitter });
        }
        rel *= 10.0;
    }
    Err(LearnError::NotPositiveDefinite(format!(
        "{what} ({n} x {n}) after a jitter of {:e} times its mean diagonal {mean_diag:e}",
        MAX_RELATIVE_JITTER
    )))
}

/// `a * b` on the calling thread: for the small products of per-step work (HMC), where
/// spreading a few-hundred-row product over threads costs more than it saves.
pub fn matmul_seq(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(out.as_mut(), faer::Accum::Replace, a, b, 1.0, faer::Par::Seq);
    out
}

/// Eigen-decomposition of the symmetric matrix `a` (lower triangle read) on the calling
/// thread: eigenvalues ascending and the eigenvectors as columns. faer's parallel
/// decomposition gives eigenvectors that differ in the last bits with the thread count; the
/// project's results must not.
pub fn symmetric_eigen_seq(a: MatRef<'_, f64>, what: &str) -> Result<(Mat<f64>, Vec<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{ComputeEigenvectors, self_adjoint_evd, self_adjoint_evd_scratch};
    let n = a.nrows();
    let mut u = Mat::zeros(n, n);
    let mut s = faer::diag::Diag::zeros(n);
    let par = faer::Par::Seq;
    let mut buf = MemBuffer::new(self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::Yes, par, Default::default()));
    self_adjoint_evd(a, s.as_mut(), Some(u.as_mut()), par, MemStack::new(&mut buf), Default::default())
        .map_err(|e| LearnError::Decomposition(format!("{what}: {e:?}")))?;
    let values = (0..n).map(|i| s[i]).collect();
    Ok((u, values))
}

/// Thin SVD of `a` (m x n) on the calling thread, for the same reason as
/// [`symmetric_eigen_seq`]: singular values descending, `U` (m x k) and `V` (n x k), k = min(m, n).
pub fn thin_svd_seq(a: MatRef<'_, f64>, what: &str) -> Result<(Mat<f64>, Vec<f64>, Mat<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::svd::{ComputeSvdVectors, svd, svd_scratch};
    let (m, n) = a.shape();
    let k = m.min(n);
    let mut u = Mat::zeros(m, k);
    let mut v = Mat::zeros(n, k);
    let mut s = faer::diag::Diag::zeros(k);
    let par = faer::Par::Seq;
    let thin = ComputeSvdVectors::Thin;
    let mut buf = MemBuffer::new(svd_scratch::<f64>(m, n, thin, thin, par, Default::default()));
    svd(a, s.as_mut(), Some(u.as_mut()), Some(v.as_mut()), par, MemStack::new(&mut buf), Default::default())
        .map_err(|e| LearnError::Decomposition(format!("{what}: {e:?}")))?;
    let values = (0..k).map(|i| s[i]).collect();
    Ok((u, values, v))
}

/// Column means of the rows of `y` (N x D).
pub fn column_means(y: MatRef<'_, f64>) -> Vec<f64> {
    let n = y.nrows().max(1) as f64;
    (0..y.ncols()).map(|j| (0..y.nrows()).map(|i| y[(i, j)]).sum::<f64>() / n).collect()
}

/// `y` with `mean` subtracted from every row.
pub fn centred(y: MatRef<'_, f64>, mean: &[f64]) -> Mat<f64> {
    Mat::from_fn(y.nrows(), y.ncols(), |i, j| y[(i, j)] - mean[j])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_round_trip_and_serde() {
        let m = from_rows(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.npy");
        save_npy(&p, m.as_ref()).unwrap();
        let back = load_npy(&p).unwrap();
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file left");
        assert!(save_npy(&dir.path().join("missing/m.npy"), m.as_ref()).is_err());
        assert_eq!(to_rows(back.as_ref()), to_rows(m.as_ref()));
        #[derive(Serialize, Deserialize)]
        struct W(#[serde(with = "serde_mat")] Mat<f64>);
        let s = serde_json::to_string(&W(m.clone())).unwrap();
        let w: W = serde_json::from_str(&s).unwrap();
        assert_eq!(to_rows(w.0.as_ref()), to_rows(m.as_ref()));
        assert!(serde_json::from_str::<W>(r#"{"rows":2,"cols":2,"data":[1.0]}"#).is_err());
    }

    #[test]
    fn jitter_rescues_a_singular_matrix_and_fails_cleanly_on_an_indefinite_one() {
        // Rank one: needs jitter.
        let k = Mat::from_fn(3, 3, |i, j| ((i + 1) * (j + 1)) as f64);
        let f = cholesky_jitter(k.as_ref(), "rank one").unwrap();
        assert!(f.jitter > 0.0);
        let bad = from_rows(2, 2, &[1.0, 0.0, 0.0, -1.0]).unwrap();
        assert!(matches!(cholesky_jitter(bad.as_ref(), "indefinite"), Err(LearnError::NotPositiveDefinite(_))));
        assert!(from_rows(1, 2, &[1.0, f64::NAN]).is_err());
    }
}

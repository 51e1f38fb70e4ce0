//! Frame-to-frame shape similarity (Huang et al. 2009, eq. 2): the Euclidean distance between
//! two frames' coarse shape histograms, minimised over the 360 rotations by whole degrees about
//! the vertical axis,
//!
//! `s(i, j) = min over alpha in {0..359} of || H(i, 0) - H(j, alpha) ||`,
//!
//! where `H(j, alpha)` is frame j's high-resolution histogram shifted by alpha degrees in azimuth
//! and re-binned to the coarse azimuth bins (`crate::shape_histogram`).
//!
//! Computing all 360 distances for every pair directly costs 360 x (coarse bins) per pair. With
//! `||a - b||^2 = ||a||^2 + ||b||^2 - 2 a.b` the squared distance splits into frame i's norm,
//! frame j's norm at each shift (computed once per frame: 360 values), and the correlation
//! `C(alpha) = sum over (r, phi, theta) of U_i(theta) h_j(theta + alpha)` where `U_i` is frame i's
//! coarse histogram spread back over the fine azimuth bins: a circular cross-correlation in
//! theta, summed over the (r, phi) rings. Its discrete Fourier transform is the ring sum of
//! `conj(FFT(U_i)) FFT(h_j)`, so a pair costs one multiply-accumulate per ring and frequency and
//! one inverse FFT of 360 points, instead of 360 full histogram distances. The transforms of each
//! frame are computed once. Exactly equal to the direct formula up to rounding (tested).
//!
//! The minimum is over shifts of frame j, as the paper writes it. Re-binning makes `s(i, j)` and
//! `s(j, i)` differ slightly (a shift that is not a multiple of the coarse bin width splits mass
//! differently between coarse bins); the paper calls the similarity symmetric, so the matrix is
//! made symmetric by computing `s(i, j)` for `i < j` only and mirroring it. The diagonal is 0.
//!
//! Frames are histogrammed on one voxel lattice and with one radial normalisation for the whole
//! frame set ([`frame_histograms`]), so their histograms are comparable.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use surfcap_mesh::UpAxis;

use crate::error::{Error, Result};
use crate::shape_histogram::{FINE_AZIMUTH, HistogramBins, ShapeHistogram, centre_and_radius, shape_histogram};
use crate::volume_voxelisation::inside_voxels;

/// One frame's mesh: `positions` [V * 3], `triangles` indexing them.
#[derive(Debug, Clone, Copy)]
pub struct FrameMesh<'a> {
    pub positions: &'a [f32],
    pub triangles: &'a [[u32; 3]],
}

/// Parameters of the histograms of a frame set.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HistogramParams {
    pub bins: HistogramBins,
    /// Voxels along the largest extent of the frame set's frames (their bounding boxes' largest
    /// side, over every frame): the voxel size is that extent divided by this.
    pub resolution: usize,
}

impl Default for HistogramParams {
    fn default() -> Self {
        HistogramParams { bins: HistogramBins::default(), resolution: 64 }
    }
}

/// The high-resolution histograms of a frame set, made comparable: one lattice, one `r_max`.
#[derive(Debug, Clone)]
pub struct FrameHistograms {
    pub histograms: Vec<ShapeHistogram>,
    pub voxel_size: f64,
    pub r_max: f64,
    pub params: HistogramParams,
    pub up: UpAxis,
}

/// Histograms every frame (in parallel; the result does not depend on the thread count).
pub fn frame_histograms(frames: &[FrameMesh<'_>], up: UpAxis, params: HistogramParams) -> Result<FrameHistograms> {
    if frames.is_empty() {
        return Err(Error::Invalid("no frames to histogram".into()));
    }
    if params.resolution < 4 {
        return Err(Error::Invalid(format!("resolution {}: expected at least 4 voxels", params.resolution)));
    }
    let mut extent = 0.0f64;
    for (f, m) in frames.iter().enumerate() {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in m.positions.chunks_exact(3) {
            for a in 0..3 {
                let x = f64::from(p[a]);
                if !x.is_finite() {
                    return Err(Error::Invalid(format!("frame {f}: a coordinate is {x}: expected a number")));
                }
                lo[a] = lo[a].min(x);
                hi[a] = hi[a].max(x);
            }
        }
        for a in 0..3 {
            extent = extent.max(hi[a] - lo[a]);
        }
    }
    if extent.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Invalid("every frame is a single point: nothing to voxelise".into()));
    }
    let h = extent / params.resolution as f64;
    let voxels = frames
        .par_iter()
        .enumerate()
        .map(|(f, m)| inside_voxels(m.positions, m.triangles, h).map_err(|e| Error::Invalid(format!("frame {f}: {e}"))))
        .collect::<Result<Vec<_>>>()?;
    let r_max = voxels.iter().filter_map(|v| centre_and_radius(v).map(|(_, r)| r)).fold(0.0, f64::max);
    if r_max.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Invalid(format!(
            "no frame encloses more than one voxel of {h}: are the meshes closed surfaces?"
        )));
    }
    let histograms =
        voxels.par_iter().map(|v| shape_histogram(v, up, r_max, params.bins)).collect::<Result<Vec<_>>>()?;
    Ok(FrameHistograms { histograms, voxel_size: h, r_max, params, up })
}

/// What each frame contributes to eq. 2, computed once.
struct Prepared {
    /// `||H(i, 0)||^2`.
    norm0: f64,
    /// `||H(i, alpha)||^2` for every alpha.
    norms: Vec<f64>,
    /// Per ring: FFT of the coarse histogram spread over the fine bins (`U_i`).
    coarse_spectrum: Vec<Complex<f64>>,
    /// Per ring: FFT of the fine histogram (`h_i`).
    fine_spectrum: Vec<Complex<f64>>,
}

fn prepare(h: &ShapeHistogram, azimuth: usize, fft: &Arc<dyn RealToComplex<f64>>) -> Prepared {
    let width = FINE_AZIMUTH / azimuth;
    let rings = h.radial * h.polar;
    let bins = FINE_AZIMUTH / 2 + 1;
    let mut norms = vec![0.0; FINE_AZIMUTH];
    let mut norm0 = 0.0;
    let mut coarse_spectrum = Vec::with_capacity(rings * bins);
    let mut fine_spectrum = Vec::with_capacity(rings * bins);
    let mut window = vec![0.0; FINE_AZIMUTH];
    let mut input = fft.make_input_vec();
    let mut out = fft.make_output_vec();
    let mut scratch = fft.make_scratch_vec();
    for ring in 0..rings {
        let fine = &h.values[ring * FINE_AZIMUTH..(ring + 1) * FINE_AZIMUTH];
        // S(t) = sum of the `width` fine bins from t: the coarse bin c of H(i, alpha) is
        // S(width c + alpha).
        for (t, w) in window.iter_mut().enumerate() {
            *w = (0..width).map(|u| fine[(t + u) % FINE_AZIMUTH]).sum();
        }
        for (alpha, n) in norms.iter_mut().enumerate() {
            *n += (0..azimuth).map(|c| window[(width * c + alpha) % FINE_AZIMUTH].powi(2)).sum::<f64>();
        }
        for (t, x) in input.iter_mut().enumerate() {
            let c = window[width * (t / width)];
            *x = c;
            if t % width == 0 {
                norm0 += c * c;
            }
        }
        // Planned lengths match the vectors made by the plan: the transform cannot fail.
        let _ = fft.process_with_scratch(&mut input, &mut out, &mut scratch);
        coarse_spectrum.extend_from_slice(&out);
        input.copy_from_slice(fine);
        let _ = fft.process_with_scratch(&mut input, &mut out, &mut scratch);
        fine_spectrum.extend_from_slice(&out);
    }
    Prepared { norm0, norms, coarse_spectrum, fine_spectrum }
}

/// The full `F x F` matrix of eq. 2 (row-major, symmetric, zero diagonal), rows in parallel.
pub fn shape_similarity_matrix(set: &FrameHistograms) -> Result<Vec<f64>> {
    let azimuth = set.params.bins.azimuth;
    if azimuth == 0 || !FINE_AZIMUTH.is_multiple_of(azimuth) {
        return Err(Error::Invalid(format!("{azimuth} azimuth bins: expected a divisor of 360")));
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(FINE_AZIMUTH);
    let ifft = planner.plan_fft_inverse(FINE_AZIMUTH);
    let prepared: Vec<Prepared> = set.histograms.par_iter().map(|h| prepare(h, azimuth, &fft)).collect();
    let n = prepared.len();
    let bins = FINE_AZIMUTH / 2 + 1;
    let rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut row = vec![0.0; n];
            let mut spectrum = ifft.make_input_vec();
            let mut corr = ifft.make_output_vec();
            let mut scratch = ifft.make_scratch_vec();
            let a = &prepared[i];
            for (j, out) in row.iter_mut().enumerate().skip(i + 1) {
                let b = &prepared[j];
                spectrum.iter_mut().for_each(|s| *s = Complex::new(0.0, 0.0));
                for (u, f) in a.coarse_spectrum.chunks_exact(bins).zip(b.fine_spectrum.chunks_exact(bins)) {
                    for k in 0..bins {
                        spectrum[k] += u[k].conj() * f[k];
                    }
                }
                // A real signal's spectrum has real first and middle terms; rounding may leave
                // tiny imaginary parts, which the inverse transform refuses.
                spectrum[0].im = 0.0;
                spectrum[bins - 1].im = 0.0;
                let _ = ifft.process_with_scratch(&mut spectrum, &mut corr, &mut scratch);
                let mut best = f64::INFINITY;
                for (alpha, c) in corr.iter().enumerate() {
                    let d2 = a.norm0 + b.norms[alpha] - 2.0 * c / FINE_AZIMUTH as f64;
                    best = best.min(d2);
                }
                *out = best.max(0.0).sqrt();
            }
            row
        })
        .collect();
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        for j in i + 1..n {
            m[i * n + j] = rows[i][j];
            m[j * n + i] = rows[i][j];
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 2 computed the slow way: shift, re-bin, distance, for every alpha.
    fn direct(a: &ShapeHistogram, b: &ShapeHistogram, azimuth: usize) -> f64 {
        let width = FINE_AZIMUTH / azimuth;
        let rings = a.radial * a.polar;
        let coarse = |h: &ShapeHistogram, alpha: usize| -> Vec<f64> {
            (0..rings)
                .flat_map(|r| {
                    (0..azimuth).map(move |c| {
                        (0..width).map(|u| h.values[r * FINE_AZIMUTH + (width * c + u + alpha) % FINE_AZIMUTH]).sum()
                    })
                })
                .collect()
        };
        let h0 = coarse(a, 0);
        (0..FINE_AZIMUTH)
            .map(|alpha| coarse(b, alpha).iter().zip(&h0).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min)
    }

    fn random_histogram(seed: u64, radial: usize, polar: usize) -> ShapeHistogram {
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut values: Vec<f64> = (0..radial * polar * FINE_AZIMUTH)
            .map(|_| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((x >> 33) % 1000) as f64
            })
            .collect();
        let s: f64 = values.iter().sum();
        values.iter_mut().for_each(|v| *v /= s);
        ShapeHistogram { radial, polar, values, voxels: 1 }
    }

    #[test]
    fn the_fft_form_equals_the_direct_formula() {
        let bins = HistogramBins { radial: 2, polar: 3, azimuth: 40 };
        let histograms: Vec<_> = (0..4).map(|s| random_histogram(s, 2, 3)).collect();
        let set = FrameHistograms {
            histograms: histograms.clone(),
            voxel_size: 1.0,
            r_max: 1.0,
            params: HistogramParams { bins, resolution: 64 },
            up: UpAxis::PosY,
        };
        let m = shape_similarity_matrix(&set).unwrap();
        for i in 0..4 {
            assert_eq!(m[i * 4 + i], 0.0);
            for j in i + 1..4 {
                let d = direct(&histograms[i], &histograms[j], 40);
                assert!((m[i * 4 + j] - d).abs() < 1e-12, "{i} {j}: {} vs {d}", m[i * 4 + j]);
                assert_eq!(m[i * 4 + j], m[j * 4 + i]);
            }
        }
    }

    #[test]
    fn a_rotated_frame_is_found_at_zero_distance() {
        // Frame 1 is frame 0 rotated by 27 degrees: eq. 2 undoes the rotation exactly.
        let a = random_histogram(7, 2, 2);
        let mut b = a.clone();
        for ring in 0..4 {
            for t in 0..FINE_AZIMUTH {
                b.values[ring * FINE_AZIMUTH + (t + 27) % FINE_AZIMUTH] = a.values[ring * FINE_AZIMUTH + t];
            }
        }
        let c = random_histogram(8, 2, 2);
        let set = FrameHistograms {
            histograms: vec![a, b, c],
            voxel_size: 1.0,
            r_max: 1.0,
            params: HistogramParams { bins: HistogramBins { radial: 2, polar: 2, azimuth: 40 }, resolution: 64 },
            up: UpAxis::PosY,
        };
        let m = shape_similarity_matrix(&set).unwrap();
        assert!(m[1] < 1e-9, "{}", m[1]);
        assert!(m[2] > 1e-3 && m[5] > 1e-3);
    }
}

//! The volume-sampling spherical shape histogram of one frame (Huang et al. 2009, section 3.1
//! steps 2-4): the inside voxels ([`crate::volume_voxelisation`]) in spherical coordinates
//! `(r, phi, theta)` about their centre of mass, accumulated into bins and divided by the number
//! of voxels.
//!
//! Choices the paper leaves open, made explicit here:
//! - Bins. The paper sets `(Δr, Δφ, Δθ) = (10, 20, 40)` "for the coarse histogram". These are
//!   read as bin counts, not sizes: 20 polar bins over 180° and 40 azimuth bins over 360° are
//!   both 9° wide, and with 40° azimuth bins (as sizes) the 1° rotation search would compare
//!   histograms of only 9 azimuth bins. The high-resolution histogram keeps the radial and polar
//!   bins and has 360 azimuth bins of 1°, so a rotation by a whole number of degrees is a cyclic
//!   shift ([`crate::shape_similarity`] re-bins it to 40).
//! - Angles. `phi` is the angle from the subject's up axis (0 to 180°), `theta` the azimuth about
//!   it (0 to 360°) from a fixed horizontal axis; the rotation search of eq. 2 is about the
//!   vertical axis, as the paper says, so the up axis must be the subject's.
//! - Radial normalisation. Radii are divided by one `r_max` for the whole frame set (the largest
//!   distance of an inside voxel from its frame's centre of mass, over every frame), so the
//!   histogram keeps the subject's size: an arm stretched out moves mass to the outer bins, which
//!   a per-frame normalisation would undo. A voxel at exactly `r_max` falls in the last bin.
//! - Voxel size. A parameter of the caller (the frame set's largest extent divided by a
//!   resolution, see [`crate::shape_similarity::FrameHistograms`]); the paper does not give it.

use surfcap_mesh::UpAxis;

use crate::error::{Error, Result};
use crate::volume_voxelisation::Voxels;

/// Bin counts of the histograms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct HistogramBins {
    pub radial: usize,
    pub polar: usize,
    /// Azimuth bins of the coarse histogram compared in eq. 2 (must divide 360).
    pub azimuth: usize,
}

impl Default for HistogramBins {
    /// The paper's (10, 20, 40).
    fn default() -> Self {
        HistogramBins { radial: 10, polar: 20, azimuth: 40 }
    }
}

/// Azimuth bins of the high-resolution histogram: one per degree.
pub const FINE_AZIMUTH: usize = 360;

/// A frame's high-resolution histogram: `values[(r * polar + phi) * 360 + theta]`, summing to 1
/// (or all zero for a frame with no inside voxel).
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeHistogram {
    pub radial: usize,
    pub polar: usize,
    pub values: Vec<f64>,
    /// Inside voxels counted.
    pub voxels: usize,
}

/// The centre of mass of the inside voxels and their largest distance from it.
pub fn centre_and_radius(voxels: &Voxels) -> Option<([f64; 3], f64)> {
    let n = voxels.count();
    if n == 0 {
        return None;
    }
    let mut c = [0.0; 3];
    for p in voxels.centres() {
        for a in 0..3 {
            c[a] += p[a];
        }
    }
    let c = c.map(|x| x / n as f64);
    let r = voxels.centres().map(|p| dist(p, c)).fold(0.0, f64::max);
    Some((c, r))
}

fn dist(p: [f64; 3], c: [f64; 3]) -> f64 {
    ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt()
}

/// A right-handed frame (east, north, up) with `up` the subject's up axis.
fn frame(up: UpAxis) -> [[f64; 3]; 3] {
    let (axis, sign) = up.axis_and_sign();
    let mut u = [0.0; 3];
    u[axis] = sign;
    // East: the first coordinate axis not along up; north = up x east.
    let e = if u[0] == 0.0 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let n = [u[1] * e[2] - u[2] * e[1], u[2] * e[0] - u[0] * e[2], u[0] * e[1] - u[1] * e[0]];
    [e, n, u]
}

/// The high-resolution histogram of `voxels` (see the module documentation).
pub fn shape_histogram(voxels: &Voxels, up: UpAxis, r_max: f64, bins: HistogramBins) -> Result<ShapeHistogram> {
    if bins.radial == 0 || bins.polar == 0 || bins.azimuth == 0 || !FINE_AZIMUTH.is_multiple_of(bins.azimuth) {
        return Err(Error::Invalid(format!(
            "histogram bins {} x {} x {}: expected positive counts, the azimuth one dividing 360",
            bins.radial, bins.polar, bins.azimuth
        )));
    }
    if !(r_max.is_finite() && r_max > 0.0) {
        return Err(Error::Invalid(format!("largest radius {r_max}: expected a positive length")));
    }
    let mut values = vec![0.0; bins.radial * bins.polar * FINE_AZIMUTH];
    let Some((c, _)) = centre_and_radius(voxels) else {
        return Ok(ShapeHistogram { radial: bins.radial, polar: bins.polar, values, voxels: 0 });
    };
    let [e, n, u] = frame(up);
    let mut count = 0usize;
    for p in voxels.centres() {
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let (x, y, z) = (
            d[0] * e[0] + d[1] * e[1] + d[2] * e[2],
            d[0] * n[0] + d[1] * n[1] + d[2] * n[2],
            d[0] * u[0] + d[1] * u[1] + d[2] * u[2],
        );
        let r = (x * x + y * y + z * z).sqrt();
        let ri = ((r / r_max * bins.radial as f64) as usize).min(bins.radial - 1);
        let phi = if r > 0.0 { (z / r).clamp(-1.0, 1.0).acos() } else { 0.0 };
        let pi = ((phi / std::f64::consts::PI * bins.polar as f64) as usize).min(bins.polar - 1);
        let theta = y.atan2(x).rem_euclid(std::f64::consts::TAU);
        let ti = ((theta.to_degrees()) as usize).min(FINE_AZIMUTH - 1);
        values[(ri * bins.polar + pi) * FINE_AZIMUTH + ti] += 1.0;
        count += 1;
    }
    for v in &mut values {
        *v /= count as f64;
    }
    Ok(ShapeHistogram { radial: bins.radial, polar: bins.polar, values, voxels: count })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume_voxelisation::inside_voxels;

    /// A closed box [x0, x1] x [y0, y1] x [z0, z1].
    fn cuboid(lo: [f32; 3], hi: [f32; 3]) -> (Vec<f32>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for z in [lo[2], hi[2]] {
            for y in [lo[1], hi[1]] {
                for x in [lo[0], hi[0]] {
                    p.extend([x, y, z]);
                }
            }
        }
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        (p, quads.iter().flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect())
    }

    #[test]
    fn the_histogram_sums_to_one_and_a_long_box_lies_along_its_azimuth() {
        // A box long in x, up +z: its mass is at azimuth 0 and 180 degrees, polar about 90.
        let (p, t) = cuboid([-2.0, -0.25, -0.25], [2.0, 0.25, 0.25]);
        let v = inside_voxels(&p, &t, 0.05).unwrap();
        let (_, r) = centre_and_radius(&v).unwrap();
        let h = shape_histogram(&v, UpAxis::PosZ, r, HistogramBins::default()).unwrap();
        assert!((h.values.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let mut by_theta = vec![0.0; 360];
        for (i, x) in h.values.iter().enumerate() {
            by_theta[i % 360] += x;
        }
        let near = |a: usize| {
            by_theta
                .iter()
                .enumerate()
                .filter(|(t, _)| {
                    (*t as i64 - a as i64).rem_euclid(360).min((a as i64 - *t as i64).rem_euclid(360)) <= 20
                })
                .map(|(_, x)| x)
                .sum::<f64>()
        };
        assert!(near(0) + near(180) > 0.8, "{} + {}", near(0), near(180));
        // Up +y instead: the same box now lies at polar 90 still (x is horizontal either way).
        let h = shape_histogram(&v, UpAxis::PosY, r, HistogramBins::default()).unwrap();
        assert!((h.values.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let e = shape_histogram(&v, UpAxis::PosZ, r, HistogramBins { azimuth: 7, ..Default::default() }).unwrap_err();
        assert!(e.to_string().contains("dividing 360"), "{e}");
    }

    #[test]
    fn frames_are_right_handed() {
        for up in [UpAxis::PosX, UpAxis::NegX, UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ] {
            let [e, n, u] = frame(up);
            let cross = [e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2], e[0] * n[1] - e[1] * n[0]];
            assert_eq!(cross, u, "{up:?}");
        }
    }
}

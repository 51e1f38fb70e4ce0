//! Simulated tracking drift of the benchmark textures: a smooth tangential
//! warp of the atlas per frame, known exactly, so the optical flow's end-point error can be
//! measured and aligned textures compared with the truth.
//!
//! Frame k's displacement `d_k` (texels, x right, y down) is, per component, a sum of a few
//! seeded sinusoids of low spatial frequency whose phases drift linearly over the frames:
//!
//! `d_k^c(x, y) = sum_j a_j sin(2 pi (f_j^x x / W + f_j^y y / H) + phi_j + rho_j k)`
//!
//! the first wave of each component of zero spatial frequency (the whole atlas sliding), the
//! others of 0.5 to 2 cycles across the texture. The amplitudes of a component add up to
//! `max / sqrt(2)`, so `|d_k(x)| <= max` everywhere. A frame samples the source texture `T` at
//! the displaced point: `frame_k(x) = T(x + d_k(x))`, i.e. `warp_direct(T, d_k)`
//! ([`crate::flow_field`]).
//!
//! **The ground-truth flow** between two frames, [`DriftModel::true_flow`]`(from, to)`, is the
//! `w` with `frame_from(x) = frame_to(x + w(x))`, the convention of
//! [`crate::flow_field::warp_direct`]: `warp_direct(frame_to, w) ~ frame_from` (the flow that
//! aligns `frame_to` to the reference `frame_from`). Since both sample `T`, `y = x + w(x)` solves
//! `y + d_to(y) = x + d_from(x)`, found by the fixed-point iteration
//! `y <- x + d_from(x) - d_to(y)` (a contraction: `|grad d| <= 2 pi max f / W`, 0.03 at 1024
//! texels with the defaults).

use rand::Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::flow_field::FlowField;

/// One sinusoid of a displacement component.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DriftWave {
    /// Texels.
    pub amplitude: f64,
    /// Cycles across the texture's width and height.
    pub frequency: [f64; 2],
    /// Radians at frame 0.
    pub phase: f64,
    /// Radians per frame.
    pub rate: f64,
}

/// The per-frame displacement fields of a generated sequence.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DriftModel {
    pub width: usize,
    pub height: usize,
    /// Waves of the horizontal component.
    pub u: Vec<DriftWave>,
    /// Waves of the vertical component.
    pub v: Vec<DriftWave>,
}

fn waves(rng: &mut impl Rng, count: usize, max: f64) -> Vec<DriftWave> {
    let weights: Vec<f64> = (0..count).map(|_| rng.random_range(0.5..1.0)).collect();
    let total: f64 = weights.iter().sum();
    weights
        .iter()
        .enumerate()
        .map(|(j, w)| {
            let frequency = if j == 0 {
                [0.0, 0.0]
            } else {
                let f = rng.random_range(0.5..2.0);
                let angle = rng.random_range(0.0..std::f64::consts::TAU);
                [f * angle.cos(), f * angle.sin()]
            };
            let rate = rng.random_range(0.03..0.1) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            DriftWave {
                amplitude: max / std::f64::consts::SQRT_2 * w / total,
                frequency,
                phase: rng.random_range(0.0..std::f64::consts::TAU),
                rate,
            }
        })
        .collect()
}

fn component(waves: &[DriftWave], k: f64, x: f64, y: f64, w: f64, h: f64) -> f64 {
    waves
        .iter()
        .map(|q| {
            q.amplitude
                * (std::f64::consts::TAU * (q.frequency[0] * x / w + q.frequency[1] * y / h) + q.phase + q.rate * k)
                    .sin()
        })
        .sum()
}

impl DriftModel {
    /// A seeded model of `waves` sinusoids per component, displacements at most `max` texels.
    pub fn random(
        width: usize,
        height: usize,
        max: f64,
        waves_per_component: usize,
        rng: &mut impl Rng,
    ) -> Result<DriftModel> {
        if !(max.is_finite() && max >= 0.0) || waves_per_component == 0 || width == 0 || height == 0 {
            return Err(Error::Invalid(format!(
                "drift: expected a finite maximum >= 0, at least one wave and a positive size, got {max}, {waves_per_component}, {width}x{height}"
            )));
        }
        let u = waves(rng, waves_per_component, max);
        let v = waves(rng, waves_per_component, max);
        Ok(DriftModel { width, height, u, v })
    }

    /// The displacement of frame `k` at texel coordinates (x, y).
    pub fn at(&self, k: usize, x: f64, y: f64) -> [f64; 2] {
        let (w, h) = (self.width as f64, self.height as f64);
        [component(&self.u, k as f64, x, y, w, h), component(&self.v, k as f64, x, y, w, h)]
    }

    /// The largest `|d|` the model can reach (the amplitudes' bound).
    pub fn bound(&self) -> f64 {
        let a = |w: &[DriftWave]| w.iter().map(|q| q.amplitude.abs()).sum::<f64>();
        (a(&self.u).powi(2) + a(&self.v).powi(2)).sqrt()
    }

    /// `d_k` at every texel: `frame_k = warp_direct(T, d_k)`.
    pub fn displacement(&self, k: usize) -> FlowField {
        self.field(|x, y| self.at(k, x, y))
    }

    fn field(&self, f: impl Fn(f64, f64) -> [f64; 2] + Sync) -> FlowField {
        let (w, h) = (self.width, self.height);
        let mut u = vec![0.0f32; w * h];
        let mut v = vec![0.0f32; w * h];
        u.par_chunks_mut(w).zip(v.par_chunks_mut(w)).enumerate().for_each(|(y, (ru, rv))| {
            for x in 0..w {
                let d = f(x as f64, y as f64);
                ru[x] = d[0] as f32;
                rv[x] = d[1] as f32;
            }
        });
        FlowField { width: w, height: h, u, v }
    }

    /// The flow `w` with `frame_from(x) = frame_to(x + w(x))` (before illumination, blur and
    /// noise), i.e. `warp_direct(frame_to, w) ~ frame_from`; see the module documentation.
    pub fn true_flow(&self, from: usize, to: usize) -> FlowField {
        self.field(|x, y| {
            let df = self.at(from, x, y);
            let goal = [x + df[0], y + df[1]];
            let mut p = goal;
            for _ in 0..50 {
                let dt = self.at(to, p[0], p[1]);
                let next = [goal[0] - dt[0], goal[1] - dt[1]];
                let change = (next[0] - p[0]).abs().max((next[1] - p[1]).abs());
                p = next;
                if change < 1e-9 {
                    break;
                }
            }
            [p[0] - x, p[1] - y]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn model(w: usize, max: f64) -> DriftModel {
        DriftModel::random(w, w, max, 3, &mut rand_chacha::ChaCha8Rng::seed_from_u64(5)).unwrap()
    }

    #[test]
    fn displacements_stay_within_the_maximum_and_move_smoothly() {
        let m = model(64, 3.0);
        assert!(m.bound() <= 3.0 + 1e-12);
        let mut largest = 0.0f64;
        for k in 0..100 {
            let d = m.displacement(k);
            for i in 0..d.u.len() {
                largest = largest.max(((d.u[i] as f64).powi(2) + (d.v[i] as f64).powi(2)).sqrt());
            }
        }
        assert!(largest <= 3.0 + 1e-5, "{largest}");
        assert!(largest > 1.0, "drift is a few texels, not nothing: {largest}");
        // From one frame to the next the field changes by at most 0.1 rad of phase per wave.
        let (a, b) = (m.displacement(10), m.displacement(11));
        let step = a.u.iter().zip(&b.u).map(|(p, q)| (p - q).abs()).fold(0.0f32, f32::max);
        assert!(step < 0.1 * 3.0, "{step}");
    }

    #[test]
    fn the_true_flow_composes_the_two_displacements() {
        let m = model(128, 3.0);
        let w = m.true_flow(3, 40);
        for &(x, y) in &[(0usize, 0usize), (17, 90), (127, 127), (64, 5)] {
            let i = y * 128 + x;
            let (fx, fy) = (x as f64 + w.u[i] as f64, y as f64 + w.v[i] as f64);
            let dt = m.at(40, fx, fy);
            let df = m.at(3, x as f64, y as f64);
            assert!((fx + dt[0] - x as f64 - df[0]).abs() < 1e-4);
            assert!((fy + dt[1] - y as f64 - df[1]).abs() < 1e-4);
        }
        // The flow from a frame to itself is zero.
        let zero = m.true_flow(7, 7);
        assert!(zero.u.iter().chain(&zero.v).all(|v| v.abs() < 1e-6));
    }

    #[test]
    fn the_model_round_trips_through_json_exactly() {
        let m = model(32, 2.5);
        let back: DriftModel = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
        assert_eq!(back.displacement(9), m.displacement(9));
    }
}

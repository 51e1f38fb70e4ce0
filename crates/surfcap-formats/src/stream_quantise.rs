//! Uniform quantisation of vertex positions in a bounding box, the first stage of the compact
//! stream (`stream.rs`): each coordinate axis of the box over every frame is cut into
//! `2^bits - 1` equal steps and a coordinate becomes the integer of its nearest grid value,
//! `q = round((x - min) / step)`, read back as `x' = min + q * step`. The largest error of a
//! coordinate is half a step, of a vertex half the cell's diagonal. Fixed-rate grid quantisation
//! of positions is what Draco's and meshoptimizer's position codecs use too; the box is the
//! whole animation's, so a vertex that stands still keeps one integer in every frame.
//!
//! Reading back computes `min + q * step` in f64 and rounds to f32 once: the JavaScript
//! decoder (`web/stream_decode.js`) does the same with `Math.fround`, so both decoders give the
//! same bits.

/// The grid: origin, step per axis (0 on a flat axis: every coordinate is its origin) and the
/// bits per coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Quantiser {
    pub min: [f64; 3],
    pub step: [f64; 3],
    pub bits: u32,
}

/// The fewest and most bits per coordinate the stream takes.
pub const MIN_BITS: u32 = 4;
pub const MAX_BITS: u32 = 30;

impl Quantiser {
    /// The grid of `bits` per coordinate over the box of `positions` (`[n * 3]`, any frames).
    pub fn over(positions: &[f32], bits: u32) -> Quantiser {
        let bits = bits.clamp(MIN_BITS, MAX_BITS);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in positions.chunks_exact(3) {
            for a in 0..3 {
                lo[a] = lo[a].min(f64::from(p[a]));
                hi[a] = hi[a].max(f64::from(p[a]));
            }
        }
        let levels = f64::from((1u32 << bits) - 1);
        let mut step = [0.0; 3];
        for a in 0..3 {
            if !lo[a].is_finite() {
                lo[a] = 0.0;
            } else if hi[a] > lo[a] {
                step[a] = (hi[a] - lo[a]) / levels;
            }
        }
        Quantiser { min: lo, step, bits }
    }

    /// The fewest bits (from [`MIN_BITS`] to [`MAX_BITS`]) whose largest vertex error, half the
    /// cell's diagonal, is at most `max_error` (in the positions' units); [`MAX_BITS`] when none
    /// is.
    pub fn for_error(positions: &[f32], max_error: f64) -> Quantiser {
        let mut q = Quantiser::over(positions, MIN_BITS);
        while q.max_error() > max_error && q.bits < MAX_BITS {
            q = Quantiser::over(positions, q.bits + 1);
        }
        q
    }

    /// The largest distance between a point in the box and its grid value: half the diagonal of
    /// a cell (a flat axis adds nothing).
    pub fn max_error(&self) -> f64 {
        self.step.iter().map(|s| (s / 2.0).powi(2)).sum::<f64>().sqrt()
    }

    /// The grid integers of `p` (`[n * 3]`, interleaved as the positions), clamped to the grid.
    pub fn quantise(&self, p: &[f32]) -> Vec<u32> {
        let top = f64::from((1u32 << self.bits) - 1);
        p.chunks_exact(3)
            .flat_map(|v| {
                (0..3).map(move |a| {
                    if self.step[a] == 0.0 {
                        0
                    } else {
                        ((f64::from(v[a]) - self.min[a]) / self.step[a]).round().clamp(0.0, top) as u32
                    }
                })
            })
            .collect()
    }

    /// The positions of grid integers `q` (`[n * 3]`).
    pub fn dequantise(&self, q: &[u32]) -> Vec<f32> {
        q.chunks_exact(3)
            .flat_map(|v| (0..3).map(move |a| (self.min[a] + f64::from(v[a]) * self.step[a]) as f32))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bits_keep_every_point_within_half_a_cell() {
        let p: Vec<f32> = (0..300).map(|i| ((i as f32) * 0.37).sin() * 2.0 + (i % 3) as f32).collect();
        let q = Quantiser::over(&p, 16);
        let back = q.dequantise(&q.quantise(&p));
        for (v, w) in p.chunks_exact(3).zip(back.chunks_exact(3)) {
            let d = (0..3).map(|a| f64::from(v[a] - w[a]).powi(2)).sum::<f64>().sqrt();
            assert!(d <= q.max_error() * 1.0001 + 1e-7, "{d} > {}", q.max_error());
        }
        // The box's corners are grid points.
        assert!(q.quantise(&p).iter().all(|&x| x < 65536));
    }

    #[test]
    fn a_target_error_picks_the_fewest_bits_that_meet_it_and_a_flat_axis_costs_nothing() {
        // x over [0, 1], y and z flat.
        let p = [0.0f32, 5.0, 5.0, 1.0, 5.0, 5.0];
        let q = Quantiser::for_error(&p, 0.001);
        // Half a step of 1 / (2^b - 1) <= 0.001 first holds at b = 9.
        assert_eq!(q.bits, 9);
        assert!(q.max_error() <= 0.001 && Quantiser::over(&p, 8).max_error() > 0.001);
        assert_eq!(q.dequantise(&q.quantise(&p)), p.to_vec());
    }
}

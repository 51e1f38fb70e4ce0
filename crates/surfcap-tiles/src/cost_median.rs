//! The exact median of the transition table's finite costs, streamed over its tiles: Algorithm 1
//! (thesis 3.3) divides D by its median, a statistic of the whole table that no tile knows.
//!
//! Two passes of radix selection over the costs' bit patterns (non-negative doubles order as
//! their bits): the first counts the values per top 16 bits, the second the chosen bucket's
//! values per the low 48 bits (kept as a sorted list, only that bucket's). Memory: 0.5 MB of
//! counts and one bucket, whatever the table's size. The median is the element of rank
//! floor(m / 2) of the m finite costs, as `edge_weights` takes it (`select_nth_unstable` at
//! m / 2), so the one-machine and tiled weights are the same bits.

/// First pass: counts per top 16 bits.
pub struct MedianPass1 {
    pub counts: Vec<u64>,
}

impl Default for MedianPass1 {
    fn default() -> Self {
        MedianPass1 { counts: vec![0; 1 << 16] }
    }
}

impl MedianPass1 {
    pub fn add(&mut self, values: &[f64]) {
        for &c in values {
            if c.is_finite() && c >= 0.0 {
                self.counts[(c.to_bits() >> 48) as usize] += 1;
            }
        }
    }

    /// Number of finite costs seen.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// The bucket holding rank `r` and the rank inside it.
    pub fn bucket_of(&self, r: u64) -> (u16, u64) {
        let mut seen = 0u64;
        for (b, &c) in self.counts.iter().enumerate() {
            if seen + c > r {
                return (b as u16, r - seen);
            }
            seen += c;
        }
        unreachable!("rank below the total")
    }
}

/// Second pass: the values of one bucket.
pub struct MedianPass2 {
    pub bucket: u16,
    pub values: Vec<f64>,
}

impl MedianPass2 {
    pub fn add(&mut self, values: &[f64]) {
        for &c in values {
            if c.is_finite() && c >= 0.0 && (c.to_bits() >> 48) as u16 == self.bucket {
                self.values.push(c);
            }
        }
    }

    /// The value of rank `r` inside the bucket.
    pub fn select(mut self, r: u64) -> f64 {
        let r = r as usize;
        *self.values.select_nth_unstable_by(r, f64::total_cmp).1
    }
}

/// Median of the finite costs given by `pass` (called twice with the visitor of each pass), as
/// `surfcap_motion::edge_weights` takes it: 1 when there are none or the median is 0.
pub fn finite_cost_median<E>(mut pass: impl FnMut(&mut dyn FnMut(&[f64])) -> Result<(), E>) -> Result<f64, E> {
    let mut p1 = MedianPass1::default();
    pass(&mut |v| p1.add(v))?;
    let m = p1.total();
    if m == 0 {
        return Ok(1.0);
    }
    let (bucket, rank) = p1.bucket_of(m / 2);
    let mut p2 = MedianPass2 { bucket, values: Vec::new() };
    pass(&mut |v| p2.add(v))?;
    let d = p2.select(rank);
    Ok(if d > 0.0 { d } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streamed_median_equals_the_selection_over_everything() {
        let mut seed = 3u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for len in [1usize, 2, 7, 1000, 4097] {
            let values: Vec<f64> = (0..len)
                .map(|k| if k % 5 == 0 { f64::INFINITY } else { next() * 10f64.powi((k % 7) as i32 - 3) })
                .collect();
            let mut finite: Vec<f64> = values.iter().copied().filter(|c| c.is_finite()).collect();
            let expected = if finite.is_empty() {
                1.0
            } else {
                let mid = finite.len() / 2;
                *finite.select_nth_unstable_by(mid, f64::total_cmp).1
            };
            // Fed in uneven pieces, as tiles are.
            let got = finite_cost_median::<()>(|visit| {
                for piece in values.chunks(13) {
                    visit(piece);
                }
                Ok(())
            })
            .unwrap();
            assert_eq!(got.to_bits(), expected.to_bits(), "{len}");
        }
        assert_eq!(
            finite_cost_median::<()>(|visit| {
                visit(&[f64::INFINITY]);
                Ok(())
            })
            .unwrap(),
            1.0
        );
    }
}

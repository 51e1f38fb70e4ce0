//! Prediction of a frame's grid integers (`stream_quantise.rs`) and the residuals the compact
//! stream (`stream.rs`) stores, as bytes ready for its entropy coder.
//!
//! Three predictions, the encoder keeping per frame the one whose coded frame is smallest:
//! - **key**: from the previous vertex of the same frame in index order (the first from 0),
//!   so the frame decodes on its own (sequence starts and seek points);
//! - **previous**: the same vertex in the previous frame (delta coding, the usual "predict from
//!   the previous frame" of mesh-sequence codecs);
//! - **linear**: the same vertex extrapolated at constant velocity from the two previous frames,
//!   `2 q[f-1] - q[f-2]` (second-order delta; wins on smooth motion, loses on jerky motion).
//!
//! Residuals `r = q - prediction` are stored coordinate plane by plane (every x, then every y,
//! then every z: neighbouring values of one axis are alike, which the entropy coder exploits),
//! each zig-zag mapped to an unsigned number (`0, -1, 1, -2, ... -> 0, 1, 2, 3, ...`) and written
//! as an unsigned LEB128 varint (7 bits a byte, high bit set when more follow), so small
//! residuals take one byte whatever the quantisation's bits.

/// How a frame is predicted (its code in the stream's frame chunk).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prediction {
    Key = 0,
    Previous = 1,
    Linear = 2,
}

impl Prediction {
    pub fn from_code(c: u8) -> Option<Prediction> {
        Some(match c {
            0 => Prediction::Key,
            1 => Prediction::Previous,
            2 => Prediction::Linear,
            _ => return None,
        })
    }

    /// How many earlier frames it needs.
    pub fn history(self) -> usize {
        self as usize
    }
}

fn predicted(kind: Prediction, a: usize, i: usize, cur: &[u32], prev: &[&[u32]]) -> i64 {
    let at = |q: &[u32], i: usize| i64::from(q[3 * i + a]);
    match kind {
        Prediction::Key => {
            if i == 0 {
                0
            } else {
                at(cur, i - 1)
            }
        }
        Prediction::Previous => at(prev[0], i),
        Prediction::Linear => 2 * at(prev[0], i) - at(prev[1], i),
    }
}

/// The residual bytes of frame `q` (`[n * 3]` grid integers) predicted by `kind` from `prev`
/// (the previous frames, most recent first: at least [`Prediction::history`] of them).
pub fn encode_residuals(kind: Prediction, q: &[u32], prev: &[&[u32]]) -> Vec<u8> {
    let n = q.len() / 3;
    let mut out = Vec::with_capacity(q.len() + q.len() / 4);
    for a in 0..3 {
        for i in 0..n {
            let r = i64::from(q[3 * i + a]) - predicted(kind, a, i, q, prev);
            let mut z = ((r << 1) ^ (r >> 63)) as u64;
            loop {
                let b = (z & 0x7f) as u8;
                z >>= 7;
                if z == 0 {
                    out.push(b);
                    break;
                }
                out.push(b | 0x80);
            }
        }
    }
    out
}

/// Frame `n` vertices' grid integers back from residual bytes: the inverse of
/// [`encode_residuals`]. An error says what is wrong (the caller names the file and frame):
/// bytes ending inside a number, bytes left over, or a value off the grid of `bits`.
pub fn decode_residuals(
    kind: Prediction,
    bytes: &[u8],
    n: usize,
    bits: u32,
    prev: &[&[u32]],
) -> Result<Vec<u32>, String> {
    let top = (1i64 << bits) - 1;
    let mut q = vec![0u32; n * 3];
    let mut pos = 0usize;
    for a in 0..3 {
        for i in 0..n {
            let mut z = 0u64;
            let mut shift = 0;
            loop {
                let Some(&b) = bytes.get(pos) else {
                    return Err(format!("the residuals end at byte {pos}, inside vertex {i}'s coordinate {a}"));
                };
                pos += 1;
                if shift > 56 {
                    return Err(format!("byte {pos}: a residual longer than 9 bytes"));
                }
                z |= u64::from(b & 0x7f) << shift;
                shift += 7;
                if b & 0x80 == 0 {
                    break;
                }
            }
            let r = ((z >> 1) as i64) ^ -((z & 1) as i64);
            let v = predicted(kind, a, i, &q, prev).saturating_add(r);
            if !(0..=top).contains(&v) {
                return Err(format!("vertex {i} coordinate {a}: {v} is off the {bits}-bit grid"));
            }
            q[3 * i + a] = v as u32;
        }
    }
    if pos != bytes.len() {
        return Err(format!("{} bytes after the last residual", bytes.len() - pos));
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_prediction_round_trips_and_smooth_motion_is_cheapest_linearly() {
        let frame = |f: u32| -> Vec<u32> { (0..90).map(|i| 1000 + 7 * i + 40 * f).collect() };
        let (f0, f1, f2) = (frame(0), frame(1), frame(2));
        for kind in [Prediction::Key, Prediction::Previous, Prediction::Linear] {
            let prev: Vec<&[u32]> = vec![&f1, &f0];
            let b = encode_residuals(kind, &f2, &prev);
            assert_eq!(decode_residuals(kind, &b, 30, 16, &prev).unwrap(), f2, "{kind:?}");
        }
        // Constant velocity: the linear residuals are all zero, one byte each.
        let lin = encode_residuals(Prediction::Linear, &f2, &[&f1, &f0]);
        assert!(lin.iter().all(|&b| b == 0) && lin.len() == 90);
        // A residual of 40 zig-zags to 80: one byte; the key frame's first value takes two.
        assert!(encode_residuals(Prediction::Previous, &f2, &[&f1]).iter().all(|&b| b == 80));
        assert_eq!(encode_residuals(Prediction::Key, &f0, &[])[..2], [0xd0, 0x0f]);
    }

    #[test]
    fn corrupt_residuals_are_refused_with_the_reason() {
        let f = vec![5u32; 6];
        let b = encode_residuals(Prediction::Key, &f, &[]);
        assert!(decode_residuals(Prediction::Key, &b[..b.len() - 1], 2, 16, &[]).unwrap_err().contains("end at byte"));
        let mut long = b.clone();
        long.push(0);
        assert!(decode_residuals(Prediction::Key, &long, 2, 16, &[]).unwrap_err().contains("after the last"));
        assert!(decode_residuals(Prediction::Key, &b, 2, 2, &[]).unwrap_err().contains("off the 2-bit grid"));
    }
}

//! The two compressions of USD's binary crate format (`.usdc`), as Pixar's `usd-core` writes
//! and reads them since crate version 0.4.0 (OpenUSD `pxr/base/tf/fastCompression` and
//! `pxr/usd/sdf/integerCoding`; not from a paper):
//!
//! - **Fast compression**: one byte giving the number of chunks (0 for a buffer under LZ4's
//!   ~2 GB input limit, the only case written here) followed by one raw LZ4 block
//!   (`lz4_flex`'s block format is LZ4's).
//! - **Integer coding** of 32-bit integer arrays (the structural sections' indices): each
//!   value becomes its difference from the previous one (the first from 0); the most common
//!   difference is written once as an `i32`, then two bits per value in little-endian order
//!   within each byte (0: the common difference, 1: an `i8`, 2: an `i16`, 3: an `i32` follows),
//!   then the differences that are not the common one, in order, at those widths. The coded
//!   bytes are then fast-compressed; in a file, a coded array is its compressed size (`u64`)
//!   followed by the compressed bytes.

use surfcap_mesh::error::{Result, err};

/// LZ4's largest input for one block (`LZ4_MAX_INPUT_SIZE`): larger buffers would need chunks.
const LZ4_MAX_INPUT: usize = 0x7E00_0000;

/// `bytes` fast-compressed: a 0 chunk count, then one LZ4 block.
pub fn fast_compress(bytes: &[u8]) -> std::io::Result<Vec<u8>> {
    if bytes.len() > LZ4_MAX_INPUT {
        return Err(std::io::Error::other(format!(
            "a usdc structural section of {} bytes: over LZ4's one-block limit of {LZ4_MAX_INPUT} bytes",
            bytes.len()
        )));
    }
    let mut out = Vec::with_capacity(bytes.len() / 2 + 16);
    out.push(0u8);
    out.extend_from_slice(&lz4_flex::block::compress(bytes));
    Ok(out)
}

/// Undoes `fast_compress`: `what` names the data for errors; `max_len` bounds the output
/// (what the caller knows the data's size to be at most).
pub fn fast_decompress(bytes: &[u8], max_len: usize, what: &str) -> Result<Vec<u8>> {
    let Some((&chunks, block)) = bytes.split_first() else {
        return Err(err!(Truncated, "{what}: empty compressed buffer"));
    };
    if chunks != 0 {
        return Err(err!(
            Unsupported,
            "{what}: compressed in {chunks} chunks (data over 2 GB): not read by surfcap (convert the file with usd-core's usdcat to .usda)"
        ));
    }
    // LZ4 expands at most ~255 times: a bound that keeps a corrupt size from allocating much.
    let cap = max_len.min(block.len().saturating_mul(255).saturating_add(16));
    let mut out = vec![0u8; cap];
    let n = lz4_flex::block::decompress_into(block, &mut out)
        .map_err(|e| err!(Syntax, "{what}: LZ4 data does not decompress ({e})"))?;
    out.truncate(n);
    Ok(out)
}

/// The byte count of the two-bit codes of `n` values.
fn codes_len(n: usize) -> usize {
    (n * 2).div_ceil(8)
}

/// `values` integer-coded (before fast compression).
pub fn encode_ints(values: &[i32]) -> Vec<u8> {
    if values.is_empty() {
        return Vec::new();
    }
    // The most common difference (ties: the larger, as usd-core picks).
    let mut counts: std::collections::HashMap<i32, usize> = std::collections::HashMap::new();
    let (mut common, mut common_count) = (0i32, 0usize);
    let mut prev = 0i32;
    for &v in values {
        let d = v.wrapping_sub(prev);
        let c = counts.entry(d).or_default();
        *c += 1;
        if *c > common_count || (*c == common_count && d > common) {
            common = d;
            common_count = *c;
        }
        prev = v;
    }
    let mut out = Vec::with_capacity(4 + codes_len(values.len()) + values.len());
    out.extend_from_slice(&common.to_le_bytes());
    let codes_at = out.len();
    out.resize(codes_at + codes_len(values.len()), 0);
    let mut prev = 0i32;
    for (i, &v) in values.iter().enumerate() {
        let d = v.wrapping_sub(prev);
        prev = v;
        let code: u8 = if d == common {
            0
        } else if let Ok(x) = i8::try_from(d) {
            out.push(x as u8);
            1
        } else if let Ok(x) = i16::try_from(d) {
            out.extend_from_slice(&x.to_le_bytes());
            2
        } else {
            out.extend_from_slice(&d.to_le_bytes());
            3
        };
        out[codes_at + i / 4] |= code << (2 * (i % 4));
    }
    out
}

/// Undoes `encode_ints` for `n` values.
pub fn decode_ints(coded: &[u8], n: usize, what: &str) -> Result<Vec<i32>> {
    if n == 0 {
        return Ok(Vec::new());
    }
    let short = || err!(Truncated, "{what}: integer coding ends before its {n} values");
    let head = coded.get(..4).ok_or_else(short)?;
    let common = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    let codes = coded.get(4..4 + codes_len(n)).ok_or_else(short)?;
    let mut rest = &coded[4 + codes_len(n)..];
    let mut take = |k: usize| -> Result<&[u8]> {
        let (a, b) = rest.split_at_checked(k).ok_or_else(short)?;
        rest = b;
        Ok(a)
    };
    let mut out = Vec::with_capacity(n);
    let mut prev = 0i32;
    for i in 0..n {
        let d = match (codes[i / 4] >> (2 * (i % 4))) & 3 {
            0 => common,
            1 => i32::from(take(1)?[0] as i8),
            2 => {
                let b = take(2)?;
                i32::from(i16::from_le_bytes([b[0], b[1]]))
            }
            _ => {
                let b = take(4)?;
                i32::from_le_bytes([b[0], b[1], b[2], b[3]])
            }
        };
        prev = prev.wrapping_add(d);
        out.push(prev);
    }
    Ok(out)
}

/// `values` integer-coded and fast-compressed, as a file holds them: compressed size, bytes.
pub fn compressed_ints(values: &[i32]) -> std::io::Result<Vec<u8>> {
    let c = fast_compress(&encode_ints(values))?;
    let mut out = Vec::with_capacity(8 + c.len());
    out.extend_from_slice(&(c.len() as u64).to_le_bytes());
    out.extend_from_slice(&c);
    Ok(out)
}

/// Undoes `fast_compress(encode_ints(..))` for `n` values.
pub fn decompress_ints(bytes: &[u8], n: usize, what: &str) -> Result<Vec<i32>> {
    let coded = fast_decompress(bytes, 4 + codes_len(n) + 4 * n, what)?;
    decode_ints(&coded, n, what)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_coding_round_trips_every_width() {
        let v = vec![0, 1, 2, 3, 4, 5, 200, -40000, 7, 7, 7, i32::MAX, i32::MIN, -1, 3];
        let coded = encode_ints(&v);
        // Most common difference 1 (five times): stored first.
        assert_eq!(&coded[..4], &1i32.to_le_bytes());
        // 0 differs by 0 from the start (an i8: code 1), 1, 2, 3 by the common 1 (code 0).
        assert_eq!(coded[4], 1);
        assert_eq!(decode_ints(&coded, v.len(), "t").unwrap(), v);
        let c = compressed_ints(&v).unwrap();
        let n = u64::from_le_bytes(c[..8].try_into().unwrap()) as usize;
        assert_eq!(n, c.len() - 8);
        assert_eq!(decompress_ints(&c[8..], v.len(), "t").unwrap(), v);
    }

    #[test]
    fn truncated_coding_is_an_error() {
        let coded = encode_ints(&[5, 1000, 100000]);
        let e = decode_ints(&coded[..coded.len() - 1], 3, "PATHS").unwrap_err();
        assert!(e.to_string().contains("PATHS"), "{e}");
        assert!(fast_decompress(&[1, 2, 3], 10, "TOKENS").is_err());
        assert!(fast_decompress(&[], 10, "TOKENS").is_err());
    }

    #[test]
    fn fast_compression_round_trips() {
        let b: Vec<u8> = (0..5000u32).map(|i| (i % 7) as u8).collect();
        let c = fast_compress(&b).unwrap();
        assert_eq!(c[0], 0);
        assert!(c.len() < b.len() / 4);
        assert_eq!(fast_decompress(&c, b.len(), "t").unwrap(), b);
    }
}

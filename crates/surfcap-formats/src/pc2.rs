//! PC2 point cache (Blender, Maya, 3ds Max, Houdini): a 32-byte header
//! (`"POINTCACHE2\0"`, version 1, point count, start frame, sample rate, sample count) followed by
//! `samples x points x 3` little-endian f32. No crate is maintained for it; the format is tiny.

use std::io::Write;

use surfcap_mesh::error::{Location, Result, err};

const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";

/// A point cache: frames of `n_points` positions.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCache {
    pub n_points: usize,
    pub start_frame: f32,
    /// Frames between samples (1.0 = every frame).
    pub sample_rate: f32,
    /// `[samples][points][3]`.
    pub positions: Vec<f32>,
}

impl PointCache {
    pub fn n_samples(&self) -> usize {
        self.positions.len().checked_div(3 * self.n_points).unwrap_or(0)
    }
}

pub fn write_pc2(w: &mut (impl Write + ?Sized), n_points: usize, positions: &[f32]) -> std::io::Result<()> {
    let samples = positions.len().checked_div(3 * n_points).unwrap_or(0);
    let mut out = Vec::with_capacity(32 + positions.len() * 4);
    out.extend_from_slice(SIGNATURE);
    out.extend_from_slice(&1i32.to_le_bytes());
    out.extend_from_slice(&(n_points as i32).to_le_bytes());
    out.extend_from_slice(&0f32.to_le_bytes());
    out.extend_from_slice(&1f32.to_le_bytes());
    out.extend_from_slice(&(samples as i32).to_le_bytes());
    for x in positions {
        out.extend_from_slice(&x.to_le_bytes());
    }
    w.write_all(&out)
}

pub fn parse_pc2(b: &[u8]) -> Result<PointCache> {
    if b.is_empty() {
        return Err(err!(Empty, "empty file: expected a PC2 point cache"));
    }
    if b.len() < 32 {
        return Err(
            err!(Truncated, "file is {} bytes: a PC2 header needs 32", b.len()).at(Location::Byte(b.len() as u64))
        );
    }
    if &b[..12] != SIGNATURE {
        return Err(err!(Syntax, "no 'POINTCACHE2' signature: expected a PC2 file").at(Location::Byte(0)));
    }
    let i32_at = |k: usize| i32::from_le_bytes(b[k..k + 4].try_into().unwrap());
    let f32_at = |k: usize| f32::from_le_bytes(b[k..k + 4].try_into().unwrap());
    let (version, n_points, start, rate, samples) = (i32_at(12), i32_at(16), f32_at(20), f32_at(24), i32_at(28));
    if version != 1 {
        return Err(err!(Unsupported, "PC2 version {version}: expected 1").at(Location::Byte(12)));
    }
    if n_points <= 0 || samples < 0 {
        return Err(
            err!(Shape, "{n_points} points, {samples} samples: expected positive counts").at(Location::Byte(16))
        );
    }
    // Checked: both counts come from the file (the fuzzer found a header whose product overflows).
    let need = (n_points as u64).checked_mul(samples as u64).and_then(|n| n.checked_mul(12)).unwrap_or(u64::MAX);
    let have = (b.len() - 32) as u64;
    if need > have {
        return Err(err!(
            Truncated,
            "header declares {samples} samples of {n_points} points ({need} bytes) but the file holds {have}"
        )
        .at(Location::Byte(b.len() as u64)));
    }
    if need < have {
        return Err(err!(Shape, "{} bytes after the last sample: expected the file to end", have - need)
            .at(Location::Byte(32 + need)));
    }
    let positions: Vec<f32> = b[32..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    if let Some(k) = positions.iter().position(|x| !x.is_finite()) {
        let per = 3 * n_points as usize;
        return Err(err!(NonFinite, "point {} has a non-finite coordinate", (k % per) / 3).at(Location::Frame(k / per)));
    }
    Ok(PointCache { n_points: n_points as usize, start_frame: start, sample_rate: rate, positions })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::error::ErrorKind;

    #[test]
    fn round_trip_and_errors() {
        let p: Vec<f32> = (0..18).map(|i| i as f32 * 0.5).collect();
        let mut b = Vec::new();
        write_pc2(&mut b, 3, &p).unwrap();
        let c = parse_pc2(&b).unwrap();
        assert_eq!((c.n_points, c.n_samples()), (3, 2));
        assert_eq!(c.positions, p);
        assert_eq!(parse_pc2(&b[..b.len() - 2]).unwrap_err().kind, ErrorKind::Truncated);
        assert_eq!(parse_pc2(&b[..10]).unwrap_err().kind, ErrorKind::Truncated);
        assert_eq!(parse_pc2(b"").unwrap_err().kind, ErrorKind::Empty);
        let mut bad = b.clone();
        bad[0] = b'X';
        assert_eq!(parse_pc2(&bad).unwrap_err().kind, ErrorKind::Syntax);
        let mut nan = b.clone();
        nan[32 + 4 * 10..32 + 4 * 11].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse_pc2(&nan).unwrap_err();
        assert_eq!((e.kind, e.location), (ErrorKind::NonFinite, Some(Location::Frame(1))));
    }
}

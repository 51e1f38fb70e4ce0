//! The compact stream (`.scstream`): a subject's animation in a few bytes per vertex per frame,
//! for long animations played in a browser or sent over a network, where glb's morph targets
//! (12 bytes per vertex per frame, uncompressed) are too large. Layout in `docs/formats.md`.
//!
//! Coding, in three stages, each in its own file:
//! 1. **quantisation** (`stream_quantise.rs`): every coordinate on a uniform grid over the whole
//!    animation's bounding box, 16 bits per coordinate by default, or the fewest bits meeting a
//!    target error;
//! 2. **prediction** (`stream_predict.rs`): each frame from the previous one or extrapolated from
//!    the two previous ones (whichever codes smaller), with a key frame predicted within itself at
//!    every sequence start and every `key_interval` frames, so a player can seek;
//!    residuals zig-zag varints, coordinate plane by plane;
//! 3. **entropy coding**: deflate (zlib framing, RFC 1950/1951, at its best compression) per
//!    frame. Chosen because every browser decodes it natively and fast
//!    (`DecompressionStream('deflate')`), so the JavaScript decoder (`web/stream_decode.js`) is
//!    a hundred lines of integer arithmetic with no entropy decoder of its own; a range or rANS
//!    coder with a context model would compress the residuals further but needs a decoder in
//!    JavaScript or WebAssembly running per frame, which this format avoids.
//!
//! The frames decode to the grid values exactly: the error against the source is the
//! quantisation's alone (at most half a grid cell's diagonal per vertex), and the Rust and
//! JavaScript decoders give the same bits.
//!
//! Carried: topology (triangles), every sequence's name, frames and frame labels, the fps, up
//! axis and units. Not carried: UVs and joints (a stream is geometry to play; the subject keeps
//! the rest).

use std::io::{Read, Write};
use std::path::Path;

use flate2::Compression;
use flate2::read::ZlibDecoder;
use flate2::write::ZlibEncoder;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::stream_predict::{Prediction, decode_residuals, encode_residuals};
use crate::stream_quantise::Quantiser;
use surfcap_mesh::error::{Location, Result, err};
use surfcap_mesh::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

/// The first 8 bytes: the format's name and version 1.
pub const MAGIC: &[u8; 8] = b"SCSTRM\x00\x01";

/// How to code a stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamOptions {
    /// Bits per coordinate (4 to 30); ignored when `max_error` is given.
    pub bits: u32,
    /// The largest vertex error allowed, in the subject's units: the fewest bits meeting it.
    pub max_error: Option<f64>,
    /// A key frame every this many frames of a sequence (and at its start); at least 1.
    pub key_interval: usize,
}

impl Default for StreamOptions {
    fn default() -> Self {
        StreamOptions { bits: 16, max_error: None, key_interval: 60 }
    }
}

/// One sequence as the header lists it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct StreamSequence {
    pub name: String,
    pub frames: usize,
    pub labels: Vec<FrameLabel>,
}

/// The stream's JSON header.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct StreamHeader {
    pub name: String,
    pub fps: f64,
    pub up_axis: UpAxis,
    pub units: Units,
    pub vertices: usize,
    pub triangles: usize,
    pub bits: u32,
    /// The grid's origin and step per axis (`stream_quantise::Quantiser`).
    pub min: [f64; 3],
    pub step: [f64; 3],
    pub key_interval: usize,
    pub sequences: Vec<StreamSequence>,
}

/// What writing a stream made: its size, each frame's coded size and prediction.
#[derive(Debug, Clone)]
pub struct StreamSummary {
    pub bytes: usize,
    /// Bytes of the header, topology and frame table (everything but the frames).
    pub header_bytes: usize,
    pub frame_bytes: Vec<usize>,
    pub predictions: Vec<Prediction>,
    pub quantiser: Quantiser,
}

fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut e = ZlibEncoder::new(Vec::with_capacity(bytes.len() / 2), Compression::best());
    e.write_all(bytes).expect("writing to memory");
    e.finish().expect("writing to memory")
}

/// Codes `subject` as a stream; returns the bytes and what they hold.
pub fn encode_stream(subject: &Subject, opts: &StreamOptions) -> (Vec<u8>, StreamSummary) {
    let all: Vec<f32> = subject.sequences().iter().flat_map(|s| s.positions().iter().copied()).collect();
    let q = match opts.max_error {
        Some(e) => Quantiser::for_error(&all, e),
        None => Quantiser::over(&all, opts.bits),
    };
    drop(all);
    let key_interval = opts.key_interval.max(1);
    let topo = subject.topology();
    let header = StreamHeader {
        name: subject.name.clone(),
        fps: subject.fps,
        up_axis: subject.up_axis,
        units: subject.units.clone(),
        vertices: topo.n_vertices(),
        triangles: topo.n_triangles(),
        bits: q.bits,
        min: q.min,
        step: q.step,
        key_interval,
        sequences: subject
            .sequences()
            .iter()
            .map(|s| StreamSequence { name: s.name.clone(), frames: s.n_frames(), labels: s.labels.clone() })
            .collect(),
    };
    // Every frame's chunk: its prediction's code, then its deflated residuals; frames are coded
    // in parallel and kept in order, so the bytes do not depend on the thread count.
    let mut chunks: Vec<(Prediction, Vec<u8>)> = Vec::with_capacity(subject.n_frames());
    for s in subject.sequences() {
        let grid: Vec<Vec<u32>> = (0..s.n_frames()).into_par_iter().map(|f| q.quantise(s.frame(f))).collect();
        let coded: Vec<(Prediction, Vec<u8>)> = (0..s.n_frames())
            .into_par_iter()
            .map(|f| {
                let since_key = f % key_interval;
                let mut candidates = vec![Prediction::Key];
                if since_key >= 1 {
                    candidates.push(Prediction::Previous);
                }
                if since_key >= 2 {
                    candidates.push(Prediction::Linear);
                }
                candidates
                    .into_iter()
                    .map(|kind| {
                        let prev: Vec<&[u32]> = (1..=kind.history()).map(|k| &grid[f - k][..]).collect();
                        (kind, zlib(&encode_residuals(kind, &grid[f], &prev)))
                    })
                    .min_by_key(|(kind, b)| (b.len(), *kind as u8))
                    .expect("a key frame is always a candidate")
            })
            .collect();
        chunks.extend(coded);
    }
    let header_json = serde_json::to_vec(&header).expect("the header serialises");
    let indices: Vec<u8> = topo.triangles().iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let topology = zlib(&indices);
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(header_json.len() as u32).to_le_bytes());
    out.extend_from_slice(&header_json);
    out.extend_from_slice(&(topology.len() as u32).to_le_bytes());
    out.extend_from_slice(&topology);
    out.extend_from_slice(&(chunks.len() as u32).to_le_bytes());
    for (_, c) in &chunks {
        out.extend_from_slice(&(c.len() as u32 + 1).to_le_bytes());
    }
    let header_bytes = out.len();
    for (kind, c) in &chunks {
        out.push(*kind as u8);
        out.extend_from_slice(c);
    }
    let summary = StreamSummary {
        bytes: out.len(),
        header_bytes,
        frame_bytes: chunks.iter().map(|(_, c)| c.len() + 1).collect(),
        predictions: chunks.iter().map(|(k, _)| *k).collect(),
        quantiser: q,
    };
    (out, summary)
}

/// Writes `subject` as a stream to `w`.
pub fn write_stream(w: &mut dyn Write, subject: &Subject, opts: &StreamOptions) -> std::io::Result<StreamSummary> {
    let (bytes, summary) = encode_stream(subject, opts);
    w.write_all(&bytes)?;
    Ok(summary)
}

/// A parsed stream: its header, triangles, and where each frame's chunk lies.
#[derive(Debug, Clone)]
pub struct StreamFile<'a> {
    pub header: StreamHeader,
    pub triangles: Vec<[u32; 3]>,
    /// Each frame's chunk (prediction code then deflated residuals) and its byte offset.
    chunks: Vec<(usize, &'a [u8])>,
}

fn u32_at(b: &[u8], pos: usize, what: &str) -> Result<u32> {
    b.get(pos..pos + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]])).ok_or_else(|| {
        err!(Truncated, "the stream ends at byte {} before {what} (4 bytes)", b.len()).at(Location::Byte(pos as u64))
    })
}

fn slice<'a>(b: &'a [u8], pos: usize, len: usize, what: &str) -> Result<&'a [u8]> {
    b.get(pos..pos.saturating_add(len)).ok_or_else(|| {
        err!(Truncated, "{what}: {len} bytes declared, the stream ends at byte {}", b.len())
            .at(Location::Byte(pos as u64))
    })
}

fn inflate(b: &[u8], limit: usize, what: &str, pos: usize) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    ZlibDecoder::new(b)
        .take(limit as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| err!(Syntax, "{what}: not a zlib (deflate) block: {e}").at(Location::Byte(pos as u64)))?;
    if out.len() > limit {
        return Err(err!(Shape, "{what}: inflates past the {limit} bytes it can hold").at(Location::Byte(pos as u64)));
    }
    Ok(out)
}

impl<'a> StreamFile<'a> {
    /// Reads the header, topology and frame table of stream bytes (errors say the byte offset
    /// and what was expected).
    pub fn parse(b: &'a [u8]) -> Result<StreamFile<'a>> {
        if b.len() < 8 || &b[..8] != MAGIC {
            let found = String::from_utf8_lossy(&b[..b.len().min(8)]).into_owned();
            return Err(err!(Syntax, "starts with {found:?}: expected a surfcap stream (SCSTRM, version 1)"));
        }
        let hl = u32_at(b, 8, "the header's length")? as usize;
        let header: StreamHeader = serde_json::from_slice(slice(b, 12, hl, "the header")?)
            .map_err(|e| err!(Syntax, "the header: {e}: expected the stream's JSON header").at(Location::Byte(12)))?;
        let levels_ok = (crate::stream_quantise::MIN_BITS..=crate::stream_quantise::MAX_BITS).contains(&header.bits);
        if !levels_ok || header.vertices == 0 || !header.fps.is_finite() || header.fps <= 0.0 {
            return Err(err!(
                Metadata,
                "the header: {} bits, {} vertices, {} fps: expected 4 to 30 bits, vertices and a positive rate",
                header.bits,
                header.vertices,
                header.fps
            ));
        }
        let mut pos = 12 + hl;
        let tl = u32_at(b, pos, "the topology's length")? as usize;
        let raw = inflate(slice(b, pos + 4, tl, "the topology")?, header.triangles * 12, "the topology", pos + 4)?;
        if raw.len() != header.triangles * 12 {
            return Err(err!(
                Shape,
                "the topology: {} bytes: expected {} triangles of three u32",
                raw.len(),
                header.triangles
            )
            .at(Location::Byte(pos as u64 + 4)));
        }
        let ix: Vec<u32> = raw.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let triangles: Vec<[u32; 3]> = ix.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        pos += 4 + tl;
        let n = u32_at(b, pos, "the frame count")? as usize;
        let declared: usize = header.sequences.iter().map(|s| s.frames).sum();
        if n != declared {
            return Err(err!(Shape, "{n} frames in the table, the header's sequences have {declared}")
                .at(Location::Byte(pos as u64)));
        }
        for s in &header.sequences {
            if s.labels.len() != s.frames {
                return Err(err!(
                    Metadata,
                    "sequence {:?}: {} labels for {} frames: expected one per frame",
                    s.name,
                    s.labels.len(),
                    s.frames
                ));
            }
        }
        pos += 4;
        let table = slice(b, pos, n.saturating_mul(4), "the frame table")?;
        let mut at = pos + 4 * n;
        let mut chunks = Vec::with_capacity(n);
        for (k, len) in table.chunks_exact(4).enumerate() {
            let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
            if len == 0 {
                return Err(err!(Syntax, "frame {k}: an empty chunk").at(Location::Byte(at as u64)));
            }
            chunks.push((at, slice(b, at, len, &format!("frame {k}"))?));
            at += len;
        }
        if at != b.len() {
            return Err(err!(Syntax, "{} bytes after the last frame", b.len() - at).at(Location::Byte(at as u64)));
        }
        Ok(StreamFile { header, triangles, chunks })
    }

    /// The grid the positions are on.
    pub fn quantiser(&self) -> Quantiser {
        Quantiser { min: self.header.min, step: self.header.step, bits: self.header.bits }
    }

    /// Every frame's positions, sequence after sequence (`[frames * vertices * 3]`).
    pub fn decode(&self) -> Result<Vec<f32>> {
        let n = self.header.vertices;
        let q = self.quantiser();
        let mut out = Vec::with_capacity(self.chunks.len() * n * 3);
        let mut global = 0usize;
        for s in &self.header.sequences {
            let mut history: Vec<Vec<u32>> = Vec::new();
            for f in 0..s.frames {
                let (pos, chunk) = self.chunks[global];
                let at = |e: String| {
                    err!(Syntax, "frame {}:{f}: {e}", s.name).at(Location::Byte(pos as u64)).at_frame(global)
                };
                let kind = Prediction::from_code(chunk[0])
                    .ok_or_else(|| at(format!("prediction {}: expected 0 (key), 1 or 2", chunk[0])))?;
                if kind.history() > history.len().min(f % self.header.key_interval.max(1)) {
                    return Err(at(format!(
                        "{kind:?} prediction needs {} earlier frames since the key frame",
                        kind.history()
                    )));
                }
                let raw = inflate(&chunk[1..], n * 3 * 10, &format!("frame {}:{f}", s.name), pos + 1)?;
                let prev: Vec<&[u32]> = history.iter().rev().take(kind.history()).map(|v| &v[..]).collect();
                let grid = decode_residuals(kind, &raw, n, self.header.bits, &prev).map_err(at)?;
                out.extend(q.dequantise(&grid));
                history.push(grid);
                if history.len() > 2 {
                    history.remove(0);
                }
                global += 1;
            }
        }
        Ok(out)
    }

    /// The stream as a subject (positions on the grid, no UVs).
    pub fn to_subject(&self) -> Result<Subject> {
        let positions = self.decode()?;
        let h = &self.header;
        let topo = Topology::new(h.vertices, self.triangles.clone(), None)?;
        let stride = h.vertices * 3;
        let mut start = 0;
        let mut sequences = Vec::with_capacity(h.sequences.len());
        for s in &h.sequences {
            let p = positions[start..start + s.frames * stride].to_vec();
            start += s.frames * stride;
            sequences.push(Sequence::new(&s.name, h.vertices, p)?.with_labels(s.labels.clone())?);
        }
        Subject::new(&h.name, topo, sequences, h.fps, h.up_axis, h.units.clone())
    }
}

/// Reads a `.scstream` file as a subject (errors name the file).
pub fn read_stream(path: &Path) -> Result<Subject> {
    let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
    StreamFile::parse(&bytes).and_then(|s| s.to_subject()).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wave(frames: usize) -> Subject {
        let topo = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let mut p = Vec::new();
        for f in 0..frames {
            let t = f as f32 / 30.0;
            p.extend([t.sin(), 0.0, 0.0, 1.0, t, 0.0, 0.0, 1.0 + t * t, 0.0, 0.0, 0.0, 1.0 - 0.5 * t]);
        }
        let seq = Sequence::new("walk", 4, p).unwrap();
        Subject::new("wave", topo, vec![seq], 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    #[test]
    fn a_stream_decodes_to_the_grid_within_its_error_and_is_deterministic() {
        let s = wave(75);
        let opts = StreamOptions { key_interval: 30, ..Default::default() };
        let (bytes, summary) = encode_stream(&s, &opts);
        assert_eq!(summary.frame_bytes.len(), 75);
        assert_eq!(summary.predictions[0], Prediction::Key);
        assert_eq!(summary.predictions[30], Prediction::Key);
        let back = StreamFile::parse(&bytes).unwrap().to_subject().unwrap();
        assert_eq!(back.topology().triangles(), s.topology().triangles());
        assert_eq!((back.fps, back.up_axis, &back.units), (30.0, UpAxis::PosY, &Units::metres()));
        let e = summary.quantiser.max_error();
        for (a, b) in s.sequences()[0].positions().chunks_exact(3).zip(back.sequences()[0].positions().chunks_exact(3))
        {
            let d = (0..3).map(|k| f64::from(a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
            assert!(d <= e * 1.0001 + 1e-7, "{d} > {e}");
        }
        assert_eq!(encode_stream(&s, &opts).0, bytes);
        // A target error picks its bits.
        let (_, coarse) = encode_stream(&s, &StreamOptions { max_error: Some(0.01), ..opts });
        assert!(coarse.quantiser.max_error() <= 0.01 && coarse.quantiser.bits < 16);
    }

    #[test]
    fn damaged_streams_are_refused_with_where_and_why() {
        let (bytes, _) = encode_stream(&wave(5), &StreamOptions::default());
        let msg = |b: &[u8]| StreamFile::parse(b).and_then(|s| s.decode()).unwrap_err().to_string();
        assert!(msg(b"PLY").contains("expected a surfcap stream"));
        assert!(msg(&bytes[..bytes.len() - 3]).contains("the stream ends"), "{}", msg(&bytes[..bytes.len() - 3]));
        let mut extra = bytes.clone();
        extra.push(0);
        assert!(msg(&extra).contains("after the last frame"));
        // A prediction code that does not exist, in the last frame.
        let (_, summary) = encode_stream(&wave(5), &StreamOptions::default());
        let mut bad = bytes.clone();
        bad[bytes.len() - summary.frame_bytes[4]] = 7;
        assert!(msg(&bad).contains("prediction 7"), "{}", msg(&bad));
    }
}

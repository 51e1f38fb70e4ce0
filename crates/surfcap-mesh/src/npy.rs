//! NumPy `.npy` arrays: the header is parsed by `npyz`; the data is decoded here in chunks
//! straight into a vector of exactly the right size, so a 240 MB position array costs 240 MB.
//!
//! Readers accept C-order arrays of the numeric types that hold the values losslessly enough
//! for their use (float32/float64 for positions, unsigned/signed integers for indices), in either
//! byte order; anything else is an error naming the file and what was expected.

use std::io::{Read, Write};
use std::path::Path;

use npyz::{DType, Endianness, TypeChar, WriterBuilder};

use crate::error::{Error, Location, Result, err};

/// An n-dimensional array in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray<T> {
    pub shape: Vec<usize>,
    pub data: Vec<T>,
}

/// Element types the readers can produce.
pub trait NpyElement: Sized + Copy + Default {
    /// Human description of the accepted dtypes, for errors.
    const EXPECTED: &'static str;
    /// Whether a stored dtype can be read as `Self`.
    fn accepts(kind: TypeChar, size: u64) -> bool;
    /// Decodes one little-endian item of the stored dtype; `None` if its value does not fit.
    fn decode(kind: TypeChar, bytes: &[u8]) -> Option<Self>;
}

fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    u64::from_le_bytes(a)
}

fn le_i64(b: &[u8]) -> i64 {
    let shift = 64 - 8 * b.len() as u32;
    ((le_u64(b) << shift) as i64) >> shift
}

impl NpyElement for f32 {
    const EXPECTED: &'static str = "float32 ('<f4') or float64 ('<f8')";
    fn accepts(kind: TypeChar, size: u64) -> bool {
        kind == TypeChar::Float && (size == 4 || size == 8)
    }
    fn decode(_: TypeChar, b: &[u8]) -> Option<f32> {
        Some(match b.len() {
            4 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            _ => f64::from_le_bytes(b.try_into().ok()?) as f32,
        })
    }
}

impl NpyElement for f64 {
    const EXPECTED: &'static str = "float64 ('<f8') or float32 ('<f4')";
    fn accepts(kind: TypeChar, size: u64) -> bool {
        kind == TypeChar::Float && (size == 4 || size == 8)
    }
    fn decode(_: TypeChar, b: &[u8]) -> Option<f64> {
        Some(match b.len() {
            4 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes(b.try_into().ok()?),
        })
    }
}

impl NpyElement for u32 {
    const EXPECTED: &'static str = "an integer type ('<u4', '<i4', '<i8', ...)";
    fn accepts(kind: TypeChar, size: u64) -> bool {
        matches!(kind, TypeChar::Int | TypeChar::Uint) && matches!(size, 1 | 2 | 4 | 8)
    }
    fn decode(kind: TypeChar, b: &[u8]) -> Option<u32> {
        match kind {
            TypeChar::Uint => u32::try_from(le_u64(b)).ok(),
            _ => u32::try_from(le_i64(b)).ok(),
        }
    }
}

impl NpyElement for u8 {
    const EXPECTED: &'static str = "uint8 ('|u1')";
    fn accepts(kind: TypeChar, size: u64) -> bool {
        kind == TypeChar::Uint && size == 1
    }
    fn decode(_: TypeChar, b: &[u8]) -> Option<u8> {
        Some(b[0])
    }
}

/// Counts bytes consumed, to know where the header ends.
struct Counting<R> {
    inner: R,
    count: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count += n as u64;
        Ok(n)
    }
}

/// Fills `buf` as far as the reader allows; returns how many bytes were read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Largest header accepted: a format-1 header's limit, six times what NumPy reads by default.
const MAX_HEADER: u64 = 65_535;
/// Deepest bracket nesting accepted in a header.
const MAX_NESTING: usize = 4;

/// Where and how an array's data is stored, from its checked header.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyLayout {
    pub shape: Vec<usize>,
    /// Byte offset of the first element.
    pub data_start: u64,
    /// Bytes per element.
    pub item: usize,
    kind: TypeChar,
    swap: bool,
}

/// Reads an array from `reader`, whose total length is `total_len` bytes.
pub fn parse_npy<T: NpyElement>(reader: impl Read, total_len: u64) -> Result<NpyArray<T>> {
    let mut r = Counting { inner: reader, count: 0 };
    let layout = npy_layout::<T, _>(&mut r, total_len)?;
    let n = layout.shape.iter().product::<usize>();
    let data = decode_elements::<T>(&mut r, &layout, n, 0)?;
    Ok(NpyArray { shape: layout.shape, data })
}

/// Decodes `n` elements from `r` (positioned at element `first`) as stored per `layout`.
fn decode_elements<T: NpyElement>(r: &mut impl Read, layout: &NpyLayout, n: usize, first: usize) -> Result<Vec<T>> {
    let item = layout.item;
    let mut data = Vec::with_capacity(n);
    let mut chunk = vec![0u8; item * n.min(65536)];
    let mut done = 0usize;
    while done < n {
        let m = (n - done).min(65536);
        let buf = &mut chunk[..m * item];
        r.read_exact(buf).map_err(|e| {
            err!(Truncated, "cannot read array data: {e}")
                .at(Location::Byte(layout.data_start + ((first + done) * item) as u64))
        })?;
        for (k, b) in buf.chunks_exact_mut(item).enumerate() {
            if layout.swap {
                b.reverse();
            }
            let v = T::decode(layout.kind, b)
                .ok_or_else(|| err!(DType, "element {} does not fit: expected {}", first + done + k, T::EXPECTED))?;
            data.push(v);
        }
        done += m;
    }
    Ok(data)
}

/// Reads and checks the header of an array whose total length is `total_len` bytes, leaving
/// `reader` at the first element: shape, dtype accepted as `T`, C order, data size matching.
fn npy_layout<T: NpyElement, R: Read>(reader: &mut Counting<R>, total_len: u64) -> Result<NpyLayout> {
    if total_len == 0 {
        return Err(err!(Empty, "empty file: expected a .npy array"));
    }
    // Check the declared header length against the file size before npyz allocates a buffer
    // of that length (a damaged length field would otherwise ask for gigabytes; found by the
    // fuzzer, see fuzz/FINDINGS.md).
    let start = reader.count;
    let mut prefix = [0u8; 12];
    let got = read_up_to(reader, &mut prefix).map_err(|e| err!(Io, "cannot read: {e}"))?;
    const MAGIC: &[u8; 6] = b"\x93NUMPY";
    if got < 10 || &prefix[..6] != MAGIC {
        return Err(if got < 10 && prefix[..got.min(6)] == MAGIC[..got.min(6)] {
            err!(Truncated, "file ends inside the .npy header")
        } else {
            err!(Syntax, "no .npy magic string: expected a NumPy array file")
        });
    }
    let (len_bytes, header_len) = match prefix[6] {
        1 => (2u64, u16::from_le_bytes([prefix[8], prefix[9]]) as u64),
        2 | 3 if got >= 12 => (4, u32::from_le_bytes([prefix[8], prefix[9], prefix[10], prefix[11]]) as u64),
        2 | 3 => return Err(err!(Truncated, "file ends inside the .npy header")),
        v => {
            return Err(err!(Unsupported, ".npy format version {v}: expected 1, 2 or 3"));
        }
    };
    if 8 + len_bytes + header_len > total_len {
        return Err(err!(
            Truncated,
            "header declares {header_len} bytes of header but the file has only {total_len} bytes"
        ));
    }
    // The header is a Python dict literal that npyz parses with a backtracking grammar: each
    // level of nested brackets can double its work (a 200-byte header ran for minutes; found by
    // the fuzzer, see fuzz/FINDINGS.md). NumPy writes at most four levels (a structured dtype's
    // subarray shape) and, by default, reads headers of at most 10,000 bytes.
    if header_len > MAX_HEADER {
        return Err(
            err!(Unsupported, "header of {header_len} bytes: expected at most {MAX_HEADER}").at(Location::Byte(8))
        );
    }
    // The prefix may already hold more than a (tiny) header: those bytes are data, kept in order.
    let mut head = prefix[..got].to_vec();
    head.resize(((8 + len_bytes + header_len) as usize).max(got), 0);
    read_up_to(reader, &mut head[got..]).map_err(|e| err!(Io, "cannot read: {e}")).and_then(|n| {
        if got + n < head.len() { Err(err!(Truncated, "file ends inside the .npy header")) } else { Ok(()) }
    })?;
    let mut depth = 0usize;
    for (k, &b) in head.iter().enumerate().skip((8 + len_bytes) as usize) {
        match b {
            b'{' | b'[' | b'(' => depth += 1,
            b'}' | b']' | b')' => depth = depth.saturating_sub(1),
            _ => {}
        }
        if depth > MAX_NESTING {
            return Err(err!(Syntax, "header nests brackets deeper than {MAX_NESTING}: expected a NumPy header dict")
                .at(Location::Byte(k as u64)));
        }
    }
    let mut r = Counting { inner: std::io::Cursor::new(head).chain(&mut *reader), count: 0 };
    let header = npyz::NpyHeader::from_reader(&mut r).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => err!(Truncated, "file ends inside the .npy header"),
        _ => err!(Syntax, "not a valid .npy header: {e}"),
    })?;
    let data_start = start + r.count;
    let DType::Plain(ts) = header.dtype() else {
        return Err(err!(DType, "structured dtype {}: expected {}", header.dtype().descr(), T::EXPECTED));
    };
    if !T::accepts(ts.type_char(), ts.size_field()) {
        return Err(err!(DType, "dtype '{ts}': expected {}", T::EXPECTED));
    }
    if header.order() == npyz::Order::Fortran && header.shape().len() > 1 {
        return Err(err!(Shape, "array is in Fortran order: expected C order (save np.ascontiguousarray(a))"));
    }
    let item = ts.size_field() as usize;
    let shape: Vec<usize> = header.shape().iter().map(|&d| d as usize).collect();
    let n = header.shape().iter().try_fold(1u64, |a, &d| a.checked_mul(d));
    let bytes_needed = n.and_then(|n| n.checked_mul(item as u64));
    let available = total_len.saturating_sub(data_start);
    let shape_text = format!("{:?}", header.shape());
    let Some(bytes_needed) = bytes_needed else {
        return Err(err!(Shape, "shape {shape_text} is too large"));
    };
    if bytes_needed > available {
        return Err(err!(
            Truncated,
            "header declares shape {shape_text} of '{ts}' ({bytes_needed} bytes of data) but the file holds only {available}"
        )
        .at(Location::Byte(total_len)));
    }
    if bytes_needed < available {
        return Err(err!(
            Shape,
            "{} bytes after the data of shape {shape_text}: expected the file to end there",
            available - bytes_needed
        )
        .at(Location::Byte(data_start + bytes_needed)));
    }
    let (kind, swap) = (ts.type_char(), ts.endianness() == Endianness::Big && item > 1);
    Ok(NpyLayout { shape, data_start, item, kind, swap })
}

/// Reads a `.npy` file; errors name the file.
pub fn read_npy<T: NpyElement>(path: &Path) -> Result<NpyArray<T>> {
    let f = crate::regular_file::open_regular_file(path)?;
    let len = f.metadata().map_err(|e| Error::io(path, "read .npy file size", e))?.len();
    parse_npy(std::io::BufReader::with_capacity(1 << 16, f), len).map_err(|e| e.in_file(path))
}

/// Reads only rows `rows` of the first axis of a `.npy` file (each row the product of the other
/// axes), seeking to them: memory is that of the rows, not the file. Returns the file's whole
/// shape and the rows' elements; errors name the file.
pub fn read_npy_rows<T: NpyElement>(path: &Path, rows: std::ops::Range<usize>) -> Result<(Vec<usize>, Vec<T>)> {
    use std::io::{Seek, SeekFrom};
    let f = crate::regular_file::open_regular_file(path)?;
    let len = f.metadata().map_err(|e| Error::io(path, "read .npy file size", e))?.len();
    let mut r = Counting { inner: std::io::BufReader::with_capacity(1 << 16, f), count: 0 };
    let layout = npy_layout::<T, _>(&mut r, len).map_err(|e| e.in_file(path))?;
    let first_axis = layout.shape.first().copied().unwrap_or(1);
    if rows.start > rows.end || rows.end > first_axis {
        return Err(
            err!(Shape, "rows {}..{} of an array of {first_axis}: out of range", rows.start, rows.end).in_file(path)
        );
    }
    let row_len: usize = layout.shape.iter().skip(1).product();
    let first = rows.start * row_len;
    let mut inner = r.inner;
    inner
        .seek(SeekFrom::Start(layout.data_start + (first * layout.item) as u64))
        .map_err(|e| Error::io(path, "seek in .npy file", e))?;
    let data = decode_elements::<T>(&mut inner, &layout, rows.len() * row_len, first).map_err(|e| e.in_file(path))?;
    Ok((layout.shape, data))
}

/// Checks an array's shape against a pattern where `None` means any length.
pub fn expect_shape<T>(a: &NpyArray<T>, pattern: &[Option<usize>], what: &str) -> Result<()> {
    let ok = a.shape.len() == pattern.len() && a.shape.iter().zip(pattern).all(|(&d, p)| p.is_none_or(|p| p == d));
    if ok {
        return Ok(());
    }
    let want: Vec<String> = pattern.iter().map(|p| p.map_or("*".into(), |d| d.to_string())).collect();
    Err(err!(Shape, "shape {:?}: expected {what} of shape [{}]", a.shape, want.join(", ")))
}

/// Writes a C-order array (`f32` as `<f4`, `u32` as `<u4`, `u8` as `|u1`).
pub fn write_npy<T: npyz::AutoSerialize + Copy>(w: impl Write, shape: &[usize], data: &[T]) -> std::io::Result<()> {
    debug_assert_eq!(shape.iter().product::<usize>(), data.len());
    let shape: Vec<u64> = shape.iter().map(|&d| d as u64).collect();
    let mut writer = npyz::WriteOptions::new().default_dtype().shape(&shape).writer(w).begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorKind;

    fn bytes<T: npyz::AutoSerialize + Copy>(shape: &[usize], data: &[T]) -> Vec<u8> {
        let mut v = Vec::new();
        write_npy(&mut v, shape, data).unwrap();
        v
    }

    fn parse<T: NpyElement>(b: &[u8]) -> Result<NpyArray<T>> {
        parse_npy(b, b.len() as u64)
    }

    #[test]
    fn round_trips_and_converts() {
        let a = bytes(&[2, 3], &[1.5f32, 2., 3., 4., 5., 6.]);
        let back = parse::<f32>(&a).unwrap();
        assert_eq!(back.shape, vec![2, 3]);
        assert_eq!(back.data[5], 6.0);
        let d = bytes(&[2], &[0.25f64, -1.0]);
        assert_eq!(parse::<f32>(&d).unwrap().data, vec![0.25, -1.0]);
        let i = bytes(&[3], &[0i64, 7, 9]);
        assert_eq!(parse::<u32>(&i).unwrap().data, vec![0, 7, 9]);
        let neg = bytes(&[1], &[-1i32]);
        assert_eq!(parse::<u32>(&neg).unwrap_err().kind, ErrorKind::DType);
    }

    #[test]
    fn reads_big_endian() {
        let mut a = bytes(&[2], &[1.5f32, -2.0]);
        let at = a.windows(3).position(|w| w == b"<f4").unwrap();
        a[at] = b'>';
        let n = a.len();
        a[n - 8..n - 4].copy_from_slice(&1.5f32.to_be_bytes());
        a[n - 4..].copy_from_slice(&(-2.0f32).to_be_bytes());
        assert_eq!(parse::<f32>(&a).unwrap().data, vec![1.5, -2.0]);
    }

    #[test]
    fn bad_files_are_errors() {
        let a = bytes(&[4, 3], &[0f32; 12]);
        assert_eq!(parse::<f32>(&a[..a.len() - 1]).unwrap_err().kind, ErrorKind::Truncated);
        assert_eq!(parse::<f32>(&a[..20]).unwrap_err().kind, ErrorKind::Truncated);
        assert_eq!(parse::<f32>(&[]).unwrap_err().kind, ErrorKind::Empty);
        assert_eq!(parse::<f32>(b"not numpy at all, sorry").unwrap_err().kind, ErrorKind::Syntax);
        let mut long = a.clone();
        long.push(0);
        assert_eq!(parse::<f32>(&long).unwrap_err().kind, ErrorKind::Shape);
        let ints = bytes(&[2], &[1i32, 2]);
        let e = parse::<f32>(&ints).unwrap_err();
        assert_eq!(e.kind, ErrorKind::DType);
        assert!(e.to_string().contains("expected float32"), "{e}");
        let arr = parse::<f32>(&a).unwrap();
        assert!(expect_shape(&arr, &[None, Some(3)], "positions").is_ok());
        assert_eq!(expect_shape(&arr, &[None, None, Some(3)], "positions").unwrap_err().kind, ErrorKind::Shape);
    }
}

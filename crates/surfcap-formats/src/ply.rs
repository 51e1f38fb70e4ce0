//! Stanford PLY: ascii, binary little-endian and binary big-endian.
//!
//! Reads the `vertex` element's `x y z` (any scalar type) and the `face` element's
//! `vertex_indices` (or `vertex_index`) list, fan-triangulating polygons; every other element
//! and property is parsed and skipped. Errors name the header or data line (ascii) or the byte
//! offset and element (binary).
//!
//! Hand-written rather than `ply-rs-bw`: surfcap needs the line or byte of every error, a
//! truncation report that says how much is missing, and no allocation driven by a header's
//! claimed counts before the data is there.

use std::io::Write;
use std::path::Path;

use surfcap_mesh::error::{Error, Location, Result, err};
use surfcap_mesh::topology::{Topology, check_triangle};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug, Clone)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    kind: PropKind,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

/// Vertices and triangles read from a PLY file.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyMesh {
    pub positions: Vec<f32>,
    pub triangles: Vec<[u32; 3]>,
}

impl PlyMesh {
    pub fn n_vertices(&self) -> usize {
        self.positions.len() / 3
    }

    pub fn topology(&self) -> Result<Topology> {
        if self.triangles.is_empty() {
            return Err(err!(Empty, "no faces: expected a 'face' element with triangles"));
        }
        Topology::new(self.n_vertices(), self.triangles.clone(), None)
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the data, and the number of header lines.
    data_start: usize,
    lines: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header> {
    if bytes.is_empty() {
        return Err(err!(Empty, "empty file: expected a PLY header starting with 'ply'"));
    }
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err!(Truncated, "header has no 'end_header' line").at_line(line_no + 1));
        };
        line_no += 1;
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let line = std::str::from_utf8(raw).map_err(|_| err!(Syntax, "header line is not text").at_line(line_no))?;
        let mut t = line.split_ascii_whitespace();
        let keyword = t.next().unwrap_or("");
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(err!(Syntax, "first line is {line:?}: expected 'ply'").at_line(1));
            }
            continue;
        }
        match keyword {
            "format" => {
                format = Some(match (t.next(), t.next()) {
                    (Some("ascii"), Some("1.0")) => Format::Ascii,
                    (Some("binary_little_endian"), Some("1.0")) => Format::BinaryLe,
                    (Some("binary_big_endian"), Some("1.0")) => Format::BinaryBe,
                    _ => {
                        return Err(err!(
                            Syntax,
                            "{line:?}: expected 'format ascii|binary_little_endian|binary_big_endian 1.0'"
                        )
                        .at_line(line_no));
                    }
                })
            }
            "comment" | "obj_info" | "" => {}
            "element" => {
                let (Some(name), Some(count), None) = (t.next(), t.next(), t.next()) else {
                    return Err(err!(Syntax, "{line:?}: expected 'element <name> <count>'").at_line(line_no));
                };
                let count = count
                    .parse()
                    .map_err(|_| err!(Syntax, "element count {count:?}: expected a whole number").at_line(line_no))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err!(Syntax, "property before any element").at_line(line_no));
                };
                let parts: Vec<&str> = t.collect();
                let bad = || {
                    err!(
                        Syntax,
                        "{line:?}: expected 'property <type> <name>' or 'property list <count type> <item type> <name>'"
                    )
                    .at_line(line_no)
                };
                let prop = match parts.as_slice() {
                    ["list", c, i, name] => {
                        let (Some(count), Some(item)) = (Scalar::parse(c), Scalar::parse(i)) else {
                            return Err(bad());
                        };
                        if !count.is_integer() {
                            return Err(
                                err!(Syntax, "list count type {c:?}: expected an integer type").at_line(line_no)
                            );
                        }
                        Property { name: name.to_string(), kind: PropKind::List { count, item } }
                    }
                    [ty, name] => {
                        let Some(s) = Scalar::parse(ty) else {
                            return Err(bad());
                        };
                        Property { name: name.to_string(), kind: PropKind::Scalar(s) }
                    }
                    _ => return Err(bad()),
                };
                el.props.push(prop);
            }
            "end_header" => break,
            other => return Err(err!(Syntax, "unknown header keyword {other:?}").at_line(line_no)),
        }
    }
    let format = format.ok_or_else(|| err!(Syntax, "header has no 'format' line").at_line(line_no))?;
    Ok(Header { format, elements, data_start: pos, lines: line_no })
}

/// Where the reader is, for error messages.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Cursor<'_> {
    fn read(&mut self, s: Scalar, what: &dyn Fn() -> String) -> Result<f64> {
        let n = s.size();
        let Some(b) = self.bytes.get(self.pos..self.pos + n) else {
            return Err(err!(
                Truncated,
                "file ends while reading {}: expected {} more bytes",
                what(),
                self.pos + n - self.bytes.len()
            )
            .at(Location::Byte(self.bytes.len() as u64)));
        };
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.big_endian {
            a[..n].reverse();
        }
        Ok(match s {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

/// Values of one element instance, as the reader sees them.
struct Instance {
    scalars: Vec<f64>,
    list: Vec<f64>,
}

/// Parses a PLY file's bytes.
pub fn parse_ply(bytes: &[u8]) -> Result<PlyMesh> {
    let header = parse_header(bytes)?;
    let vertex_el = header
        .elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| err!(Syntax, "no 'vertex' element in the header").at_line(header.lines))?;
    let ve = &header.elements[vertex_el];
    let coord = |c: &str| {
        ve.props
            .iter()
            .position(|p| p.name == c && matches!(p.kind, PropKind::Scalar(_)))
            .ok_or_else(|| err!(Syntax, "vertex element has no scalar property {c:?}").at_line(header.lines))
    };
    let xyz = [coord("x")?, coord("y")?, coord("z")?];
    let n_vertices = usize::try_from(ve.count)
        .ok()
        .filter(|&n| n <= u32::MAX as usize)
        .ok_or_else(|| err!(Unsupported, "{} vertices exceed the 32-bit index limit", ve.count))?;
    let face_list = |e: &Element| {
        e.props.iter().position(|p| {
            matches!(p.kind, PropKind::List { .. }) && (p.name == "vertex_indices" || p.name == "vertex_index")
        })
    };

    let mut mesh = PlyMesh { positions: Vec::new(), triangles: Vec::new() };
    let mut inst = Instance { scalars: Vec::new(), list: Vec::new() };
    // ascii state
    let text_lines = &bytes[header.data_start..];
    let mut ascii_lines = text_lines.split(|&b| b == b'\n').enumerate();
    let mut cursor = Cursor { bytes, pos: header.data_start, big_endian: header.format == Format::BinaryBe };

    for el in &header.elements {
        let is_vertex = el.name == "vertex";
        let face_prop = if el.name == "face" { face_list(el) } else { None };
        if el.name == "face" && face_prop.is_none() {
            return Err(err!(Syntax, "face element has no 'vertex_indices' list property").at_line(header.lines));
        }
        if el.props.is_empty() {
            // Nothing to read (and nothing stored in the file) for such an element.
            continue;
        }
        let remaining = bytes.len().saturating_sub(cursor.pos) as u64;
        if header.format != Format::Ascii && el.count > remaining {
            // Every instance takes at least one byte: fail now rather than loop over a huge count.
            return Err(err!(
                Truncated,
                "header declares {} {} elements but only {remaining} bytes of data remain",
                el.count,
                el.name
            )
            .at(Location::Byte(cursor.pos as u64)));
        }
        for k in 0..el.count {
            let mut line_of_instance = 0;
            match header.format {
                Format::Ascii => {
                    let (idx, line) = loop {
                        match ascii_lines.next() {
                            Some((i, l)) => {
                                let l = l.strip_suffix(b"\r").unwrap_or(l);
                                if !l.iter().all(|b| b.is_ascii_whitespace()) {
                                    break (i, l);
                                }
                            }
                            None => {
                                return Err(err!(Truncated, "file ends before {} {k} of {}", el.name, el.count)
                                    .at_line(header.lines + text_lines.split(|&b| b == b'\n').count()));
                            }
                        }
                    };
                    line_of_instance = header.lines + idx + 1;
                    let text =
                        std::str::from_utf8(line).map_err(|_| err!(Syntax, "not text").at_line(line_of_instance))?;
                    read_ascii_instance(el, text, &mut inst).map_err(|e| e.at_line(line_of_instance))?;
                }
                Format::BinaryLe | Format::BinaryBe => {
                    let start = cursor.pos;
                    read_binary_instance(el, k, &mut cursor, &mut inst)
                        .map_err(|e| e.at(Location::Byte(start as u64)))?;
                }
            }
            let at = |e: Error| {
                if line_of_instance > 0 { e.at_line(line_of_instance) } else { e.at(Location::Byte(cursor.pos as u64)) }
            };
            if is_vertex {
                for &c in &xyz {
                    let x = inst.scalars[c] as f32;
                    if !x.is_finite() {
                        return Err(at(err!(NonFinite, "vertex {k} has coordinate {x}: expected a finite number")));
                    }
                    mesh.positions.push(x);
                }
            } else if face_prop.is_some() {
                if inst.list.len() < 3 {
                    return Err(at(err!(
                        DegenerateFace,
                        "face {k} has {} corners: expected at least 3",
                        inst.list.len()
                    )));
                }
                let corners = &inst.list;
                let get = |v: f64| -> Result<u32> {
                    if v < 0.0 || v >= n_vertices as f64 {
                        return Err(match n_vertices {
                            0 => err!(IndexOutOfRange, "face {k} uses vertex {v}: the file has no vertices"),
                            1 => err!(IndexOutOfRange, "face {k} uses vertex {v}: expected 0 (the only vertex)"),
                            n => err!(IndexOutOfRange, "face {k} uses vertex {v}: expected 0 to {} (0-based)", n - 1),
                        });
                    }
                    Ok(v as u32)
                };
                let first = get(corners[0]).map_err(at)?;
                for j in 1..corners.len() - 1 {
                    let t = [first, get(corners[j]).map_err(at)?, get(corners[j + 1]).map_err(at)?];
                    check_triangle(&t, n_vertices).map_err(|e| at(err!(DegenerateFace, "face {k}: {}", e.message)))?;
                    mesh.triangles.push(t);
                }
            }
        }
    }
    if mesh.positions.len() != 3 * n_vertices {
        return Err(err!(Shape, "read {} vertices, header declares {n_vertices}", mesh.positions.len() / 3));
    }
    // Data after the last element the header declares means the header's counts are wrong (a
    // face count of 5 in a file holding 984): refuse rather than read part of the mesh. Trailing
    // whitespace (a final newline) is accepted.
    let counts = || {
        let c: Vec<String> = header.elements.iter().map(|e| format!("{} {}", e.count, e.name)).collect();
        c.join(", ")
    };
    if header.format == Format::Ascii {
        if let Some((i, _)) = ascii_lines.find(|(_, l)| !l.iter().all(|b| b.is_ascii_whitespace())) {
            return Err(err!(
                Shape,
                "data after the last element: the header declares {}, and the file holds more",
                counts()
            )
            .at_line(header.lines + i + 1));
        }
    } else if let Some(k) = bytes[cursor.pos..].iter().position(|b| !b.is_ascii_whitespace()) {
        let extra = bytes.len() - cursor.pos;
        return Err(err!(
            Shape,
            "{extra} bytes of data after the last element: the header declares {}, and the file holds more",
            counts()
        )
        .at(Location::Byte((cursor.pos + k) as u64)));
    }
    Ok(mesh)
}

fn read_ascii_instance(el: &Element, line: &str, inst: &mut Instance) -> Result<()> {
    inst.scalars.clear();
    inst.list.clear();
    let mut tokens = line.split_ascii_whitespace();
    let mut next = |what: &str| -> Result<f64> {
        let t = tokens.next().ok_or_else(|| err!(Syntax, "{} line ends before {what}", el.name))?;
        t.parse::<f64>().map_err(|_| err!(Syntax, "{t:?} is not a number: expected {what}"))
    };
    for p in &el.props {
        match p.kind {
            PropKind::Scalar(_) => {
                let v = next(&format!("property {:?}", p.name))?;
                inst.scalars.push(v);
            }
            PropKind::List { .. } => {
                let n = next(&format!("the length of list {:?}", p.name))?;
                if n < 0.0 || n.fract() != 0.0 || n > 1e6 {
                    return Err(err!(Syntax, "list length {n}: expected a small whole number"));
                }
                inst.scalars.push(f64::NAN);
                for _ in 0..n as usize {
                    let v = next(&format!("an item of list {:?}", p.name))?;
                    inst.list.push(v);
                }
            }
        }
    }
    if let Some(extra) = tokens.next() {
        return Err(err!(Syntax, "unexpected {extra:?} after the {} properties of {}", el.props.len(), el.name));
    }
    Ok(())
}

fn read_binary_instance(el: &Element, k: u64, c: &mut Cursor, inst: &mut Instance) -> Result<()> {
    inst.scalars.clear();
    inst.list.clear();
    for p in &el.props {
        let what = || format!("property {:?} of {} {k} of {}", p.name, el.name, el.count);
        match p.kind {
            PropKind::Scalar(s) => {
                let v = c.read(s, &what)?;
                inst.scalars.push(v);
            }
            PropKind::List { count, item } => {
                let n = c.read(count, &what)?;
                if n < 0.0 {
                    return Err(err!(Syntax, "{}: negative list length {n}", what()));
                }
                inst.scalars.push(f64::NAN);
                for _ in 0..n as usize {
                    let v = c.read(item, &what)?;
                    inst.list.push(v);
                }
            }
        }
    }
    Ok(())
}

/// Reads and parses a PLY file; errors name the file.
pub fn read_ply(path: &Path) -> Result<PlyMesh> {
    let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
    parse_ply(&bytes).map_err(|e| e.in_file(path))
}

/// Writes one frame as PLY: binary little-endian (float x y z, uchar/int face lists) or ascii.
pub fn write_ply(
    w: &mut (impl Write + ?Sized),
    topology: &Topology,
    positions: &[f32],
    ascii: bool,
) -> std::io::Result<()> {
    let nv = positions.len() / 3;
    let nf = topology.n_triangles();
    let format = if ascii { "ascii" } else { "binary_little_endian" };
    let mut out = Vec::with_capacity(200 + nv * 12 + nf * 13);
    write!(
        out,
        "ply\nformat {format} 1.0\ncomment written by surfcap\nelement vertex {nv}\nproperty float x\n\
         property float y\nproperty float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )?;
    if ascii {
        for p in positions.chunks_exact(3) {
            writeln!(out, "{} {} {}", p[0], p[1], p[2])?;
        }
        for t in topology.triangles() {
            writeln!(out, "3 {} {} {}", t[0], t[1], t[2])?;
        }
    } else {
        for x in positions {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for t in topology.triangles() {
            out.push(3);
            for &i in t {
                out.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
    }
    w.write_all(&out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::error::ErrorKind;

    fn tetra() -> (Topology, Vec<f32>) {
        let t = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        (t, vec![0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.5])
    }

    #[test]
    fn round_trips_binary_and_ascii() {
        let (t, p) = tetra();
        for ascii in [false, true] {
            let mut buf = Vec::new();
            write_ply(&mut buf, &t, &p, ascii).unwrap();
            let m = parse_ply(&buf).unwrap();
            assert_eq!(m.positions, p);
            assert_eq!(m.topology().unwrap(), t);
        }
    }

    #[test]
    fn reads_big_endian_quads_and_extra_properties() {
        let mut b = b"ply\r\nformat binary_big_endian 1.0\r\nelement vertex 4\r\nproperty double x\r\nproperty double y\r\n\
property double z\r\nproperty uchar red\r\nelement face 1\r\nproperty uchar flags\r\nproperty list uchar uint vertex_index\r\n\
element edge 1\r\nproperty int a\r\nend_header\r\n"
            .to_vec();
        for (i, v) in [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]].iter().enumerate() {
            for x in v {
                b.extend_from_slice(&f64::to_be_bytes(*x));
            }
            b.push(i as u8);
        }
        b.push(7);
        b.push(4);
        for i in 0u32..4 {
            b.extend_from_slice(&i.to_be_bytes());
        }
        b.extend_from_slice(&5i32.to_be_bytes());
        let m = parse_ply(&b).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[6..9], [1., 1., 0.]);
    }

    /// A header that declares fewer faces than the file holds is an error at
    /// the first byte (binary) or line (ascii) past the declared data; a final newline is fine.
    #[test]
    fn data_after_the_declared_elements_is_an_error() {
        let (t, p) = tetra();
        let mut buf = Vec::new();
        write_ply(&mut buf, &t, &p, false).unwrap();
        let header_len = buf.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        let mut short = buf.clone();
        let at = short.windows(14).position(|w| w == b"element face 4").unwrap();
        short[at + 13] = b'1';
        let end_of_first_face = header_len + 4 * 12 + 13;
        let e = parse_ply(&short).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "byte {end_of_first_face}: 39 bytes of data after the last element: the header declares 4 vertex, 1 face, \
                 and the file holds more"
            )
        );
        buf.extend_from_slice(b"\n");
        assert!(parse_ply(&buf).is_ok(), "a trailing newline is not data");

        let mut ascii = Vec::new();
        write_ply(&mut ascii, &t, &p, true).unwrap();
        let text = String::from_utf8(ascii).unwrap().replacen("element face 4", "element face 3", 1) + "\n\n";
        let e = parse_ply(text.as_bytes()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 18: data after the last element: the header declares 4 vertex, 3 face, and the file holds more"
        );
    }

    /// "expected 0..494 (0-based)" for 494 vertices; the last valid index is 493.
    #[test]
    fn out_of_range_face_indices_name_the_last_valid_one() {
        let ply = |nv: usize, face: &str| {
            let mut t = format!(
                "ply\nformat ascii 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            );
            t.push_str(&"0 0 0\n".repeat(nv));
            t.push_str(face);
            parse_ply(t.as_bytes()).unwrap_err().to_string()
        };
        assert_eq!(ply(494, "3 0 1 494\n"), "line 504: face 0 uses vertex 494: expected 0 to 493 (0-based)");
        assert_eq!(ply(1, "3 0 0 1\n"), "line 11: face 0 uses vertex 1: expected 0 (the only vertex)");
        assert_eq!(ply(0, "3 0 1 2\n"), "line 10: face 0 uses vertex 0: the file has no vertices");
    }

    #[test]
    fn truncated_binary_names_the_element_and_offset() {
        let (t, p) = tetra();
        let mut buf = Vec::new();
        write_ply(&mut buf, &t, &p, false).unwrap();
        for cut in [buf.len() - 1, buf.len() - 30, buf.len() - 60] {
            let e = parse_ply(&buf[..cut]).unwrap_err();
            assert_eq!(e.kind, ErrorKind::Truncated, "{e}");
            assert!(matches!(e.location, Some(Location::Byte(_))), "{e}");
        }
        let e = parse_ply(&buf[..20]).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Truncated);
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let cases: &[(&str, ErrorKind, usize)] = &[
            ("0 0 0\n1 0 0\n0 1\n3 0 1 2\n", ErrorKind::Syntax, 12),
            ("0 0 0\n1 0 0\n0 1 nan\n3 0 1 2\n", ErrorKind::NonFinite, 12),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", ErrorKind::IndexOutOfRange, 13),
            ("0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n", ErrorKind::DegenerateFace, 13),
            ("0 0 0\n1 0 0\n0 1 0\n", ErrorKind::Truncated, 13),
        ];
        for (data, kind, line) in cases {
            let e = parse_ply(format!("{head}{data}").as_bytes()).unwrap_err();
            assert_eq!((e.kind, e.location.clone()), (*kind, Some(Location::Line(*line))), "{data:?}: {e}");
        }
        assert_eq!(parse_ply(b"").unwrap_err().kind, ErrorKind::Empty);
        assert_eq!(parse_ply(b"plx\n").unwrap_err().kind, ErrorKind::Syntax);
        let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n").unwrap_err();
        assert_eq!(e.kind, ErrorKind::Syntax);
    }
}

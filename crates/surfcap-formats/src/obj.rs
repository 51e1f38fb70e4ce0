//! Wavefront OBJ: the subset surface-capture pipelines write.
//!
//! Reads `v` (3 coordinates, optional w or vertex colour ignored), `vt`, `vn` (parsed, not kept),
//! `f` with `a`, `a/b`, `a//c` or `a/b/c` corners, negative (relative) indices, polygons
//! fan-triangulated from their first corner, `#` comments, CRLF line ends. Other statements
//! (`o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`) are ignored. Every error names the line.
//!
//! Hand-written rather than `tobj`: tobj's errors carry no line number, and surfcap needs one
//! in every message (and only needs positions, faces and UVs).

use std::io::Write;
use std::path::Path;

use surfcap_mesh::error::{Result, err};
use surfcap_mesh::topology::{Topology, UvAtlas, check_triangle};

/// The content of one OBJ file.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjMesh {
    /// `[vertices][3]`.
    pub positions: Vec<f32>,
    /// Fan-triangulated faces, 0-based.
    pub triangles: Vec<[u32; 3]>,
    /// 1-based line of the `f` statement each triangle came from.
    pub triangle_lines: Vec<usize>,
    pub texcoords: Vec<[f32; 2]>,
    /// Per-corner texture coordinate indices, when every face corner has one.
    pub uv_corners: Option<Vec<[u32; 3]>>,
}

impl ObjMesh {
    pub fn n_vertices(&self) -> usize {
        self.positions.len() / 3
    }

    /// The topology of this mesh (faces and UVs), checked.
    pub fn topology(&self) -> Result<Topology> {
        if self.n_vertices() == 0 {
            return Err(err!(Empty, "no vertices ('v' lines): expected a triangle mesh"));
        }
        if self.triangles.is_empty() {
            return Err(err!(Empty, "no faces ('f' lines): expected a triangle mesh"));
        }
        let uv = self.uv_corners.as_ref().map(|c| UvAtlas { coords: self.texcoords.clone(), corners: c.clone() });
        Topology::new(self.n_vertices(), self.triangles.clone(), uv)
    }
}

/// Parses OBJ text. `bytes` need not be valid UTF-8 outside comments.
pub fn parse_obj(bytes: &[u8]) -> Result<ObjMesh> {
    let mut mesh = ObjMesh {
        positions: Vec::new(),
        triangles: Vec::new(),
        triangle_lines: Vec::new(),
        texcoords: Vec::new(),
        uv_corners: Some(Vec::new()),
    };
    let mut n_normals = 0usize;
    let mut corners: Vec<(u32, Option<u32>)> = Vec::with_capacity(8);
    let mut saw_face = false;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let raw = match raw.iter().position(|&b| b == b'#') {
            Some(k) => &raw[..k],
            None => raw,
        };
        let line = std::str::from_utf8(raw)
            .map_err(|_| err!(Syntax, "not valid UTF-8 text: expected an OBJ statement").at_line(line_no))?;
        let mut tokens = line.split_ascii_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut xyz = [0f32; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let tok = tokens
                        .next()
                        .ok_or_else(|| err!(Syntax, "'v' has {k} coordinates: expected 3 (x y z)").at_line(line_no))?;
                    *c = parse_coordinate(tok).map_err(|e| e.at_line(line_no))?;
                }
                mesh.positions.extend_from_slice(&xyz);
            }
            "vt" => {
                let u = tokens.next().ok_or_else(|| err!(Syntax, "'vt' without coordinates").at_line(line_no))?;
                let u = parse_coordinate(u).map_err(|e| e.at_line(line_no))?;
                let v = match tokens.next() {
                    Some(t) => parse_coordinate(t).map_err(|e| e.at_line(line_no))?,
                    None => 0.0,
                };
                mesh.texcoords.push([u, v]);
            }
            "vn" => {
                for k in 0..3 {
                    let tok = tokens
                        .next()
                        .ok_or_else(|| err!(Syntax, "'vn' has {k} components: expected 3").at_line(line_no))?;
                    parse_coordinate(tok).map_err(|e| e.at_line(line_no))?;
                }
                n_normals += 1;
            }
            "f" => {
                saw_face = true;
                corners.clear();
                let nv = mesh.positions.len() / 3;
                for tok in tokens.by_ref() {
                    corners
                        .push(parse_corner(tok, nv, mesh.texcoords.len(), n_normals).map_err(|e| e.at_line(line_no))?);
                }
                if corners.len() < 3 {
                    return Err(err!(DegenerateFace, "face has {} corners: expected at least 3", corners.len())
                        .at_line(line_no));
                }
                for k in 1..corners.len() - 1 {
                    let t = [corners[0].0, corners[k].0, corners[k + 1].0];
                    check_triangle(&t, nv).map_err(|e| e.at_line(line_no))?;
                    mesh.triangles.push(t);
                    mesh.triangle_lines.push(line_no);
                    match (&mut mesh.uv_corners, corners[0].1, corners[k].1, corners[k + 1].1) {
                        (Some(uv), Some(a), Some(b), Some(c)) => uv.push([a, b, c]),
                        (uv, ..) => *uv = None,
                    }
                }
            }
            _ => {}
        }
    }
    if !saw_face || mesh.texcoords.is_empty() {
        mesh.uv_corners = None;
    }
    Ok(mesh)
}

fn parse_coordinate(tok: &str) -> Result<f32> {
    let x: f32 = tok.parse().map_err(|_| err!(Syntax, "{tok:?} is not a number: expected a coordinate"))?;
    if !x.is_finite() {
        return Err(err!(NonFinite, "coordinate {tok:?} is not finite: expected a finite number"));
    }
    Ok(x)
}

/// Resolves a 1-based (or negative, relative) OBJ index to 0-based.
fn resolve_index(tok: &str, count: usize, what: &str) -> Result<u32> {
    let i: i64 = tok.parse().map_err(|_| err!(Syntax, "{tok:?} is not an integer: expected a {what} index"))?;
    let resolved = if i > 0 {
        i - 1
    } else if i < 0 {
        count as i64 + i
    } else {
        return Err(err!(IndexOutOfRange, "{what} index 0: OBJ indices start at 1 (or are negative)"));
    };
    if resolved < 0 || resolved >= count as i64 {
        let defined = match (count, what) {
            (1, _) => format!("1 {what} is"),
            (_, "vertex") => format!("{count} vertices are"),
            _ => format!("{count} {what}s are"),
        };
        return Err(err!(IndexOutOfRange, "{what} index {i} out of range: {defined} defined before this line"));
    }
    Ok(resolved as u32)
}

fn parse_corner(tok: &str, nv: usize, nvt: usize, nvn: usize) -> Result<(u32, Option<u32>)> {
    if tok.matches('/').count() > 2 {
        return Err(err!(Syntax, "face corner {tok:?}: expected v, v/vt, v//vn or v/vt/vn"));
    }
    let mut parts = tok.split('/');
    let v = resolve_index(parts.next().unwrap_or(""), nv, "vertex")?;
    let vt = match parts.next() {
        Some("") | None => None,
        Some(t) => Some(resolve_index(t, nvt, "texture coordinate")?),
    };
    if let Some(n) = parts.next().filter(|s| !s.is_empty()) {
        resolve_index(n, nvn, "normal")?;
    }
    Ok((v, vt))
}

/// Reads and parses an OBJ file; errors name the file.
pub fn read_obj(path: &Path) -> Result<ObjMesh> {
    let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(err!(Empty, "empty file: expected an OBJ mesh").in_file(path));
    }
    parse_obj(&bytes).map_err(|e| e.in_file(path))
}

/// Writes one frame as OBJ text (with `vt` and `f v/vt` when the topology has UVs).
pub fn write_obj(w: &mut (impl Write + ?Sized), topology: &Topology, positions: &[f32]) -> std::io::Result<()> {
    let mut buf = String::with_capacity(positions.len() * 12 + topology.n_triangles() * 24);
    use std::fmt::Write as _;
    buf.push_str("# written by surfcap\n");
    for p in positions.chunks_exact(3) {
        // `{}` on f32 prints the shortest text that reads back to the same f32.
        let _ = writeln!(buf, "v {} {} {}", p[0], p[1], p[2]);
    }
    match topology.uv() {
        Some(uv) => {
            for t in &uv.coords {
                let _ = writeln!(buf, "vt {} {}", t[0], t[1]);
            }
            for (t, c) in topology.triangles().iter().zip(&uv.corners) {
                let _ =
                    writeln!(buf, "f {}/{} {}/{} {}/{}", t[0] + 1, c[0] + 1, t[1] + 1, c[1] + 1, t[2] + 1, c[2] + 1);
            }
        }
        None => {
            for t in topology.triangles() {
                let _ = writeln!(buf, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
            }
        }
    }
    w.write_all(buf.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::error::{ErrorKind, Location};

    #[test]
    fn reads_the_usual_statements() {
        let text = "# cube corner\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0 1.0\r\nv 0 1 0 0.5 0.5 0.5\r\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng grp\nusemtl m\ns off\n\
                    f 1/1/1 2/2/1 3/3/1 4/4/1 # a quad\n";
        let m = parse_obj(text.as_bytes()).unwrap();
        assert_eq!(m.n_vertices(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.triangle_lines, vec![14, 14]);
        assert_eq!(m.uv_corners, Some(vec![[0, 1, 2], [0, 2, 3]]));
        assert_eq!(m.topology().unwrap().n_triangles(), 2);
    }

    #[test]
    fn negative_indices_are_relative() {
        let m = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4//1 -1 -2\n");
        // The second face refers to a normal that does not exist.
        let e = m.unwrap_err();
        assert_eq!(e.kind, ErrorKind::IndexOutOfRange);
        assert_eq!(e.location, Some(Location::Line(6)));
        let m = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -1 -2\n").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 3, 2]]);
        assert_eq!(m.uv_corners, None);
    }

    #[test]
    fn bad_input_names_the_line() {
        let cases: &[(&str, ErrorKind, usize)] = &[
            ("v 0 0 0\nv 1 0\n", ErrorKind::Syntax, 2),
            ("v 0 0 0\nv 1 0 nan\n", ErrorKind::NonFinite, 2),
            ("v 0 0 0\nv 1 0 inf\n", ErrorKind::NonFinite, 2),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ErrorKind::IndexOutOfRange, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ErrorKind::IndexOutOfRange, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", ErrorKind::IndexOutOfRange, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n", ErrorKind::DegenerateFace, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", ErrorKind::DegenerateFace, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", ErrorKind::Syntax, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", ErrorKind::Syntax, 4),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2/1 3/1\n", ErrorKind::IndexOutOfRange, 4),
        ];
        for (text, kind, line) in cases {
            let e = parse_obj(text.as_bytes()).unwrap_err();
            assert_eq!((e.kind, e.location.clone()), (*kind, Some(Location::Line(*line))), "{text:?}: {e}");
        }
    }

    /// Not "494 vertexs": counts name their items in the plural (or singular).
    #[test]
    fn out_of_range_indices_count_what_is_defined() {
        let msg = |t: &[u8]| parse_obj(t).unwrap_err().to_string();
        assert_eq!(
            msg(b"v 0 0 0\nv 1 0 0\nf 1 2 3\n"),
            "line 3: vertex index 3 out of range: 2 vertices are defined before this line"
        );
        assert_eq!(
            msg(b"v 0 0 0\nf 1 2 3\n"),
            "line 2: vertex index 2 out of range: 1 vertex is defined before this line"
        );
        assert_eq!(
            msg(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nf 1/1 2/2 3/3\n"),
            "line 6: texture coordinate index 3 out of range: 2 texture coordinates are defined before this line"
        );
    }

    #[test]
    fn meshes_without_faces_have_no_topology() {
        assert_eq!(parse_obj(b"v 0 0 0\n").unwrap().topology().unwrap_err().kind, ErrorKind::Empty);
        assert_eq!(parse_obj(b"\n").unwrap().topology().unwrap_err().kind, ErrorKind::Empty);
    }

    #[test]
    fn write_then_read_is_exact() {
        let m = parse_obj(b"v 0.1 0.2 0.3\nv 1e-7 -3.5 2\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
        let topo = m.topology().unwrap();
        let mut out = Vec::new();
        write_obj(&mut out, &topo, &m.positions).unwrap();
        let back = parse_obj(&out).unwrap();
        assert_eq!(back.positions, m.positions);
        assert_eq!(back.topology().unwrap(), topo);
    }
}

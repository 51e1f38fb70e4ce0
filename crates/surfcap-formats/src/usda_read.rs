//! USD import from `.usda` text: the subset of the USDA grammar that DCC tools
//! and surfcap's own writer (`usda.rs`) use for animated meshes. Not from the thesis: the
//! thesis's captures (chapter 5's data included) are per-frame meshes of one topology, which a
//! time-sampled USD `Mesh` holds directly, one sequence per mesh.
//!
//! Read: the `#usda 1.0` header and the layer metadata `timeCodesPerSecond`, `framesPerSecond`,
//! `upAxis` (`"Y"`/`"Z"`), `metersPerUnit`, `startTimeCode`; nested `def`/`over` prims of type
//! `Xform`, `Scope`, `Mesh` or no type (any other type and every `class` is skipped with its
//! braces, so a mesh inside it is not read); on each `Mesh`: `faceVertexCounts`,
//! `faceVertexIndices`, `orientation`, `points` as a default value and/or `points.timeSamples`,
//! `primvars:surfcap:synthetic.timeSamples` (frame labels, as surfcap writes them),
//! `velocities` / `velocities.timeSamples` (units per second, on a mesh of one topology) and the UVs
//! `primvars:st` (+ `primvars:st:indices`, `faceVarying` or `vertex` interpolation). Every other
//! attribute, relationship, `variantSet` and metadata block `( ... )` is skipped token by token
//! (strings with escapes, triple-quoted strings, `#`, `//` and `/* */` comments, nested brackets).
//! The parser is iterative (no recursion, so deep nesting cannot overflow the stack) and never
//! sizes a buffer from a number in the file: every array grows with the values actually read.
//!
//! Choices where USD leaves room (each also said in the code):
//! - Polygons are fan-triangulated from their first corner, `(v0, vk, vk+1)`: exact for the
//!   convex quads and n-gons DCC tools write; a concave polygon may get a fold (surfcap works on
//!   triangles; a user who needs a better triangulation triangulates in the DCC tool).
//!   `orientation = "leftHanded"` flips every triangle so surfcap's counter-clockwise convention
//!   holds.
//! - When a mesh has both a default `points` and `points.timeSamples`, the samples are the frames
//!   (USD itself answers every time query from the samples then).
//! - Frames are the time samples in time order. A time must be a whole number of frames from the
//!   layer's `startTimeCode` (0 when not authored) and the samples must be consecutive: a gap
//!   would change the timing silently (frame k shown at k / fps), so it is refused.
//! - The frame rate is `timeCodesPerSecond`, else `framesPerSecond` (USD's own fallback). When
//!   neither is authored USD would assume 24; surfcap's import asks for `--fps` instead of
//!   guessing, as for every other source, so none is returned.
//! - USD's `upAxis` is only `Y` or `Z`. surfcap writes a subject with another up axis as
//!   `upAxis = "Y"` and a root `xformOp:transform` turning that axis onto +Y, the points keeping
//!   the subject's coordinates: such a transform (exactly one of surfcap's five) gives the up axis
//!   back. Any other transform is ignored with a note: the points are read in the mesh's own
//!   coordinates.
//! - `metersPerUnit` 1, 0.01, 0.001 and 0.0254 become the units `m`, `cm`, `mm`, `in`; another
//!   value keeps its scale under the name `<value> m`.
//! - Each mesh becomes one sequence named after its prim path: the path below the single root
//!   prim (when there is one), without a last component `mesh` (surfcap writes
//!   `/<subject>/<sequence>/mesh`), so surfcap's own files give their sequences back by name.
//!   Two meshes mapped to the same name keep their full paths.
//! - One subject has one topology: meshes with different face counts, indices, point counts or
//!   UVs are refused with both prims named (frame sets, where every frame has its own topology,
//!   come from Alembic meshes whose faces change and from frame folders; USD stages of
//!   different meshes are not read as one).
//! - Binary crate files (`PXR-USDC`) are read by `usd_crate_read.rs`, which reads the same
//!   subset into the same meshes and checks them with this module's functions.

use std::path::Path;

use surfcap_mesh::error::{Error, Result, err};
use surfcap_mesh::subject::{FrameLabel, Units, UpAxis};
use surfcap_mesh::topology::{Topology, UvAtlas};

/// One `Mesh` prim read from a stage: one sequence of the subject.
#[derive(Debug, Clone)]
pub struct UsdaMesh {
    /// The prim path, such as `/knight/knight_Walking_A/mesh`.
    pub path: String,
    /// The sequence name derived from the path (see the module documentation).
    pub name: String,
    pub topology: Topology,
    /// `[frames * vertices * 3]`, frames in time order.
    pub positions: Vec<f32>,
    /// The time code of each frame.
    pub times: Vec<f64>,
    /// From `primvars:surfcap:synthetic.timeSamples` when present.
    pub labels: Option<Vec<FrameLabel>>,
    /// When the faces are time-sampled and change between frames (per-frame reconstructions):
    /// every frame's own topology and points, in time order; `topology` and `positions` then
    /// hold the first frame only. Such a mesh imports as a frame set.
    pub varying: Option<Vec<(Topology, Vec<f32>)>>,
    /// From `velocities` on a mesh of one topology: `[frames * vertices * 3]`, units per second.
    pub velocities: Option<Vec<f32>>,
}

impl UsdaStage {
    /// The first pair of meshes whose topologies differ (or a mesh whose faces change between
    /// frames), as the error of an import that needs one topology.
    pub fn topology_mismatch(&self) -> Option<Error> {
        if let Some(m) = self.meshes.iter().find(|m| m.varying.is_some()) {
            return Some(err!(
                TopologyMismatch,
                "Mesh <{}>: its faces change between frames (time-sampled faceVertexCounts/faceVertexIndices): a varying-topology mesh imports as a frame set",
                m.path
            ));
        }
        let first = self.meshes.first()?;
        self.meshes[1..].iter().find_map(|m| {
            first.topology.first_difference(&m.topology).map(|d| {
                err!(
                    TopologyMismatch,
                    "meshes <{}> and <{}> differ in topology ({d}): one subject needs one topology (import them separately, or as a frame set: -o x.frames)",
                    first.path,
                    m.path
                )
            })
        })
    }
}

/// Everything read from a `.usda` stage.
#[derive(Debug, Clone)]
pub struct UsdaStage {
    /// Every mesh, in file order; all share one topology.
    pub meshes: Vec<UsdaMesh>,
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
    /// What was ignored or assumed (transforms, dropped UVs, skipped prims holding meshes).
    pub notes: Vec<String>,
}

/// Reads a `.usda` file (errors name the file).
pub fn read_usda(path: &Path) -> Result<UsdaStage> {
    let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
    parse_usda(&bytes).map_err(|e| e.in_file(path))
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Ident,
    Number,
    Str,
    /// `<...>` path or `@...@` asset.
    Other,
    Punct(u8),
    Eof,
}

#[derive(Debug, Clone, Copy)]
struct Token {
    kind: Kind,
    start: usize,
    end: usize,
    line: usize,
    col: usize,
}

struct Lexer<'a> {
    s: &'a [u8],
    pos: usize,
    line: usize,
    line_start: usize,
    peeked: Option<Token>,
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_'
}

fn is_ident_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

impl<'a> Lexer<'a> {
    fn at(&self, i: usize) -> u8 {
        self.s.get(i).copied().unwrap_or(0)
    }

    fn error(&self, t: &Token, msg: impl std::fmt::Display) -> Error {
        err!(Syntax, "column {}: {msg}", t.col).at_line(t.line)
    }

    fn newline(&mut self) {
        self.line += 1;
        self.line_start = self.pos;
    }

    fn skip_space(&mut self) -> Result<()> {
        loop {
            let c = self.at(self.pos);
            if c == b'\n' {
                self.pos += 1;
                self.newline();
            } else if c == b' ' || c == b'\t' || c == b'\r' || c == b';' {
                // `;` may separate statements on one line in USDA.
                self.pos += 1;
            } else if c == b'#' || (c == b'/' && self.at(self.pos + 1) == b'/') {
                while self.pos < self.s.len() && self.s[self.pos] != b'\n' {
                    self.pos += 1;
                }
            } else if c == b'/' && self.at(self.pos + 1) == b'*' {
                let line = self.line;
                self.pos += 2;
                loop {
                    if self.pos >= self.s.len() {
                        return Err(err!(Syntax, "comment /* never closed: expected */").at_line(line));
                    }
                    if self.s[self.pos] == b'*' && self.at(self.pos + 1) == b'/' {
                        self.pos += 2;
                        break;
                    }
                    self.pos += 1;
                    if self.s[self.pos - 1] == b'\n' {
                        self.newline();
                    }
                }
            } else {
                return Ok(());
            }
        }
    }

    fn lex(&mut self) -> Result<Token> {
        self.skip_space()?;
        let start = self.pos;
        let (line, col) = (self.line, start - self.line_start + 1);
        let mk = |kind, end| Token { kind, start, end, line, col };
        if start >= self.s.len() {
            return Ok(mk(Kind::Eof, start));
        }
        let c = self.s[start];
        let next = self.at(start + 1);
        if is_ident_start(c) {
            let mut i = start + 1;
            loop {
                let d = self.at(i);
                if is_ident_char(d) {
                    i += 1;
                } else if (d == b':' || d == b'.') && is_ident_start(self.at(i + 1)) {
                    // Namespaced names (`primvars:st`) and suffixes (`points.timeSamples`).
                    i += 2;
                } else {
                    break;
                }
            }
            self.pos = i;
            return Ok(mk(Kind::Ident, i));
        }
        if c.is_ascii_digit()
            || ((c == b'-' || c == b'+') && (next.is_ascii_digit() || next == b'.' || next.is_ascii_alphabetic()))
            || (c == b'.' && next.is_ascii_digit())
        {
            let mut i = start + 1;
            loop {
                let d = self.at(i);
                if d.is_ascii_alphanumeric()
                    || d == b'.'
                    || ((d == b'-' || d == b'+') && matches!(self.at(i - 1), b'e' | b'E'))
                {
                    i += 1;
                } else {
                    break;
                }
            }
            self.pos = i;
            return Ok(mk(Kind::Number, i));
        }
        if c == b'"' || c == b'\'' {
            let triple = self.at(start + 1) == c && self.at(start + 2) == c;
            let mut i = start + if triple { 3 } else { 1 };
            loop {
                if i >= self.s.len() {
                    let t = mk(Kind::Str, i);
                    return Err(self.error(&t, "string never closed: expected a closing quote"));
                }
                let d = self.s[i];
                if d == b'\\' {
                    i += 2;
                    continue;
                }
                if d == b'\n' {
                    if !triple {
                        let t = mk(Kind::Str, i);
                        return Err(self.error(&t, "string runs past the end of the line: expected a closing quote"));
                    }
                    self.pos = i + 1;
                    self.newline();
                }
                if d == c && (!triple || (self.at(i + 1) == c && self.at(i + 2) == c)) {
                    i += if triple { 3 } else { 1 };
                    break;
                }
                i += 1;
            }
            self.pos = i;
            return Ok(mk(Kind::Str, i));
        }
        if c == b'<' || c == b'@' {
            let close = if c == b'<' { b'>' } else { b'@' };
            let triple = c == b'@' && self.at(start + 1) == b'@' && self.at(start + 2) == b'@';
            let mut i = start + if triple { 3 } else { 1 };
            loop {
                if i >= self.s.len() || (self.s[i] == b'\n' && !triple) {
                    let t = mk(Kind::Other, i);
                    return Err(self.error(&t, format!("{} never closed: expected {}", c as char, close as char)));
                }
                if self.s[i] == b'\n' {
                    self.pos = i + 1;
                    self.newline();
                }
                if self.s[i] == close && (!triple || (self.at(i + 1) == b'@' && self.at(i + 2) == b'@')) {
                    i += if triple { 3 } else { 1 };
                    break;
                }
                i += 1;
            }
            self.pos = i;
            return Ok(mk(Kind::Other, i));
        }
        if b"()[]{}=,:&".contains(&c) {
            self.pos = start + 1;
            return Ok(mk(Kind::Punct(c), start + 1));
        }
        let t = mk(Kind::Other, start + 1);
        Err(self.error(
            &t,
            format!(
                "unexpected character {:?}",
                String::from_utf8_lossy(&self.s[start..]).chars().next().unwrap_or('?')
            ),
        ))
    }

    fn peek(&mut self) -> Result<Token> {
        if let Some(t) = self.peeked {
            return Ok(t);
        }
        let t = self.lex()?;
        self.peeked = Some(t);
        Ok(t)
    }

    fn next(&mut self) -> Result<Token> {
        let t = self.peek()?;
        self.peeked = None;
        Ok(t)
    }

    fn text(&self, t: &Token) -> &'a str {
        std::str::from_utf8(&self.s[t.start..t.end]).unwrap_or("?")
    }

    fn describe(&self, t: &Token) -> String {
        match t.kind {
            Kind::Eof => "the end of the file".into(),
            _ => {
                let s = self.text(t);
                let short: String = s.chars().take(40).collect();
                format!("{short:?}")
            }
        }
    }

    fn expect_punct(&mut self, p: u8, what: &str) -> Result<Token> {
        let t = self.next()?;
        if t.kind != Kind::Punct(p) {
            return Err(self.error(&t, format!("{what}: expected `{}`, found {}", p as char, self.describe(&t))));
        }
        Ok(t)
    }

    fn eat_punct(&mut self, p: u8) -> Result<bool> {
        if self.peek()?.kind == Kind::Punct(p) {
            self.next()?;
            return Ok(true);
        }
        Ok(false)
    }

    fn is_ident(&mut self, word: &str) -> Result<bool> {
        let t = self.peek()?;
        Ok(t.kind == Kind::Ident && self.text(&t) == word)
    }

    /// Skips one value: a single token, or a bracketed group with everything nested in it.
    fn skip_value(&mut self) -> Result<()> {
        let t = self.next()?;
        match t.kind {
            Kind::Punct(b'(' | b'[' | b'{') => self.skip_rest_of_group(t),
            Kind::Eof => Err(self.error(&t, "expected a value, found the end of the file")),
            Kind::Punct(_) => Err(self.error(&t, format!("expected a value, found {}", self.describe(&t)))),
            _ => Ok(()),
        }
    }

    /// Skips to the bracket closing `open` (already read), iteratively.
    fn skip_rest_of_group(&mut self, open: Token) -> Result<()> {
        let mut stack: Vec<Token> = vec![open];
        while let Some(top) = stack.last().copied() {
            let t = self.next()?;
            match t.kind {
                Kind::Punct(b'(' | b'[' | b'{') => stack.push(t),
                Kind::Punct(c @ (b')' | b']' | b'}')) => {
                    let want = closer(self.s[top.start]);
                    if c != want {
                        return Err(self.error(
                            &t,
                            format!(
                                "found `{}`: expected `{}` closing the `{}` of line {}",
                                c as char, want as char, self.s[top.start] as char, top.line
                            ),
                        ));
                    }
                    stack.pop();
                }
                Kind::Eof => {
                    return Err(self.error(
                        &t,
                        format!(
                            "file ends: expected `{}` closing the `{}` of line {}",
                            closer(self.s[top.start]) as char,
                            self.s[top.start] as char,
                            top.line
                        ),
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<(T, Token)> {
        let t = self.next()?;
        if t.kind != Kind::Number && t.kind != Kind::Ident {
            return Err(self.error(&t, format!("{what}: expected a number, found {}", self.describe(&t))));
        }
        let s = self.text(&t);
        match s.parse::<T>() {
            Ok(v) => Ok((v, t)),
            Err(_) => Err(self.error(&t, format!("{what}: expected a number, found {}", self.describe(&t)))),
        }
    }

    fn float(&mut self, what: &str) -> Result<f32> {
        let (v, t): (f32, _) = self.number(what)?;
        if !v.is_finite() {
            return Err(
                err!(NonFinite, "column {}: {what}: {} is not a finite number", t.col, self.text(&t)).at_line(t.line)
            );
        }
        Ok(v)
    }

    fn float64(&mut self, what: &str) -> Result<(f64, Token)> {
        let (v, t): (f64, _) = self.number(what)?;
        if !v.is_finite() {
            return Err(
                err!(NonFinite, "column {}: {what}: {} is not a finite number", t.col, self.text(&t)).at_line(t.line)
            );
        }
        Ok((v, t))
    }

    fn index(&mut self, what: &str) -> Result<u32> {
        let (v, t): (i64, _) = self.number(what)?;
        u32::try_from(v).map_err(|_| self.error(&t, format!("{what}: {v} is not an index: expected 0 to {}", u32::MAX)))
    }

    fn string(&mut self, what: &str) -> Result<String> {
        let t = self.next()?;
        if t.kind != Kind::Str {
            return Err(self.error(&t, format!("{what}: expected a quoted string, found {}", self.describe(&t))));
        }
        let s = self.text(&t);
        let q = if s.starts_with("\"\"\"") || s.starts_with("'''") { 3 } else { 1 };
        Ok(s.get(q..s.len().saturating_sub(q)).unwrap_or("").to_string())
    }

    /// `[ item, item, ... ]` (a trailing comma allowed), calling `item` for each.
    fn array(&mut self, what: &str, mut item: impl FnMut(&mut Self) -> Result<()>) -> Result<()> {
        self.expect_punct(b'[', what)?;
        loop {
            if self.eat_punct(b']')? {
                return Ok(());
            }
            item(self)?;
            if !self.eat_punct(b',')? {
                self.expect_punct(b']', what)?;
                return Ok(());
            }
        }
    }

    fn int_array(&mut self, what: &str) -> Result<Vec<u32>> {
        let mut v = Vec::new();
        self.array(what, |l| {
            v.push(l.index(what)?);
            Ok(())
        })?;
        Ok(v)
    }

    /// `[(x, y, z), ...]` flattened, or `[(u, v), ...]` with `n = 2`.
    fn tuple_array(&mut self, what: &str, n: usize) -> Result<Vec<f32>> {
        let mut v = Vec::new();
        self.array(what, |l| {
            l.expect_punct(b'(', what)?;
            for k in 0..n {
                if k > 0 {
                    l.expect_punct(b',', what)?;
                }
                v.push(l.float(what)?);
            }
            l.expect_punct(b')', what).map(|_| ())
        })?;
        Ok(v)
    }

    /// `{ time: value, ... }`, calling `value` for each sample.
    fn time_samples(&mut self, what: &str, mut value: impl FnMut(&mut Self, f64, Token) -> Result<()>) -> Result<()> {
        self.expect_punct(b'{', what)?;
        loop {
            if self.eat_punct(b'}')? {
                return Ok(());
            }
            let (t, tok) = self.float64(&format!("{what}: time"))?;
            self.expect_punct(b':', what)?;
            value(self, t, tok)?;
            if !self.eat_punct(b',')? {
                self.expect_punct(b'}', what)?;
                return Ok(());
            }
        }
    }

    /// A `( ... )` metadata block (the `(` already read): every entry skipped, the string value
    /// of each key in `keys` returned.
    fn metadata(&mut self, keys: &[&str]) -> Result<Vec<(String, String)>> {
        let mut found = Vec::new();
        loop {
            let t = self.peek()?;
            match t.kind {
                Kind::Punct(b')') => {
                    self.next()?;
                    return Ok(found);
                }
                Kind::Ident if keys.contains(&self.text(&t)) => {
                    self.next()?;
                    if self.eat_punct(b'=')? {
                        if self.peek()?.kind == Kind::Str {
                            found.push((self.text(&t).to_string(), self.string("metadata")?));
                        } else {
                            self.skip_value()?;
                        }
                    }
                }
                Kind::Eof => return Err(self.error(&t, "file ends: expected `)` closing a metadata block")),
                Kind::Punct(b'=' | b',' | b':' | b'&') | Kind::Ident => {
                    self.next()?;
                }
                _ => self.skip_value()?,
            }
        }
    }
}

fn closer(open: u8) -> u8 {
    match open {
        b'(' => b')',
        b'[' => b']',
        _ => b'}',
    }
}

/// What a `Mesh` prim said, before it is checked.
#[derive(Default)]
pub(crate) struct MeshAcc {
    pub(crate) counts: Option<(Vec<u32>, usize)>,
    pub(crate) indices: Option<(Vec<u32>, usize)>,
    /// `faceVertexCounts.timeSamples` / `faceVertexIndices.timeSamples`: (time, value, line).
    pub(crate) counts_samples: Option<Vec<(f64, Vec<u32>, usize)>>,
    pub(crate) indices_samples: Option<Vec<(f64, Vec<u32>, usize)>>,
    pub(crate) points: Option<(Vec<f32>, usize)>,
    pub(crate) samples: Option<Vec<(f64, Vec<f32>, usize)>>,
    /// `velocities` (default value) and `velocities.timeSamples`.
    pub(crate) velocities: Option<(Vec<f32>, usize)>,
    pub(crate) velocity_samples: Option<Vec<(f64, Vec<f32>, usize)>>,
    pub(crate) labels: Option<Vec<(f64, u32, usize)>>,
    pub(crate) st: Option<(Vec<f32>, usize)>,
    pub(crate) st_interpolation: Option<String>,
    pub(crate) st_indices: Option<Vec<u32>>,
    pub(crate) left_handed: bool,
}

struct Prim {
    path: String,
    line: usize,
    mesh: Option<MeshAcc>,
}

/// Column-vector rotations surfcap writes for up axes USD cannot state (see `usda.rs`),
/// as the row-vector matrix USD stores (the transpose).
pub(crate) fn surfcap_up_rotation(m: &[f64; 16]) -> Option<UpAxis> {
    let table: [(UpAxis, [[i8; 3]; 3]); 4] = [
        (UpAxis::NegZ, [[1, 0, 0], [0, 0, -1], [0, 1, 0]]),
        (UpAxis::PosX, [[0, -1, 0], [1, 0, 0], [0, 0, 1]]),
        (UpAxis::NegX, [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]),
        (UpAxis::NegY, [[1, 0, 0], [0, -1, 0], [0, 0, -1]]),
    ];
    let last_ok = m[3] == 0.0 && m[7] == 0.0 && m[11] == 0.0 && m[12..] == [0.0, 0.0, 0.0, 1.0];
    if !last_ok {
        return None;
    }
    table.iter().find(|(_, r)| (0..3).all(|i| (0..3).all(|j| m[i * 4 + j] == f64::from(r[j][i])))).map(|(u, _)| *u)
}

/// Reads the dictionary of `customLayerData = { ... }` (after the `=`): the value of
/// `string surfcap_units`, every other entry skipped.
fn custom_units(lx: &mut Lexer<'_>) -> Result<Option<String>> {
    let open = lx.next()?;
    if open.kind != Kind::Punct(b'{') {
        return Err(lx.error(&open, format!("customLayerData: expected `{{`, found {}", lx.describe(&open))));
    }
    let mut found = None;
    loop {
        let t = lx.next()?;
        match t.kind {
            Kind::Punct(b'}') => return Ok(found),
            Kind::Eof => return Err(lx.error(&t, "file ends: expected `}` closing customLayerData")),
            Kind::Ident => {
                // `type name = value`; the name may be quoted.
                let ty = lx.text(&t).to_string();
                let name_token = lx.next()?;
                let name = match name_token.kind {
                    Kind::Ident => lx.text(&name_token).to_string(),
                    Kind::Str => lx.text(&name_token).trim_matches(|c| c == '"' || c == '\'').to_string(),
                    _ => {
                        return Err(lx.error(
                            &name_token,
                            format!("customLayerData: expected an entry name, found {}", lx.describe(&name_token)),
                        ));
                    }
                };
                if !lx.eat_punct(b'=')? {
                    let t = lx.peek()?;
                    return Err(lx.error(&t, format!("customLayerData: {name}: expected `=`")));
                }
                if ty == "string" && name == "surfcap_units" {
                    found = Some(unescape(&lx.string("surfcap_units")?));
                } else {
                    lx.skip_value()?;
                }
            }
            _ => {
                return Err(
                    lx.error(&t, format!("customLayerData: expected `type name = value`, found {}", lx.describe(&t)))
                );
            }
        }
    }
}

/// A USD string's escapes (`\\"`, `\\\\`, `\\n`, `\\t`) resolved; another escaped character
/// stands for itself.
fn unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some(other) => out.push(other),
            None => out.push('\\'),
        }
    }
    out
}

pub(crate) fn units_of(m: f64) -> Units {
    let name = match m {
        1.0 => "m".to_string(),
        0.01 => "cm".to_string(),
        0.001 => "mm".to_string(),
        0.0254 => "in".to_string(),
        _ => format!("{m} m"),
    };
    Units { name, metres_per_unit: Some(m) }
}

/// Parses a `.usda` stage held in memory (errors carry the line; the caller adds the file).
pub fn parse_usda(bytes: &[u8]) -> Result<UsdaStage> {
    if bytes.starts_with(b"PXR-USDC") {
        return crate::usd_crate_read::parse_usdc(bytes);
    }
    if bytes.is_empty() {
        return Err(err!(Empty, "empty file: expected a USD text stage starting with `#usda 1.0`"));
    }
    let first_line_end = bytes.iter().position(|&b| b == b'\n').unwrap_or(bytes.len());
    let first = String::from_utf8_lossy(&bytes[..first_line_end]);
    let version = first.trim_end().strip_prefix("#usda ").map(str::trim);
    if version.is_none_or(|v| !v.starts_with("1.")) {
        let shown: String = first.chars().take(40).collect();
        return Err(err!(Syntax, "found {shown:?}: expected the USD text header `#usda 1.0`").at_line(1));
    }
    let mut lx = Lexer { s: bytes, pos: first_line_end, line: 1, line_start: 0, peeked: None };

    let mut tcps = None;
    let mut fps = None;
    let mut up_axis = None;
    let mut units = None;
    let mut units_name: Option<String> = None;
    let mut start = 0.0f64;
    let mut notes = Vec::new();

    // Layer metadata.
    if lx.eat_punct(b'(')? {
        loop {
            let t = lx.peek()?;
            match t.kind {
                Kind::Punct(b')') => {
                    lx.next()?;
                    break;
                }
                Kind::Eof => return Err(lx.error(&t, "file ends: expected `)` closing the layer metadata")),
                Kind::Ident => {
                    lx.next()?;
                    let key = lx.text(&t);
                    if !lx.eat_punct(b'=')? {
                        continue;
                    }
                    match key {
                        "timeCodesPerSecond" | "framesPerSecond" => {
                            let (v, vt) = lx.float64(key)?;
                            if v <= 0.0 {
                                return Err(err!(Metadata, "column {}: {key} = {v}: expected a positive rate", vt.col)
                                    .at_line(vt.line));
                            }
                            if key == "timeCodesPerSecond" { tcps = Some(v) } else { fps = Some(v) }
                        }
                        "startTimeCode" => start = lx.float64(key)?.0,
                        "metersPerUnit" => {
                            let (v, vt) = lx.float64(key)?;
                            if v <= 0.0 {
                                return Err(err!(
                                    Metadata,
                                    "column {}: metersPerUnit = {v}: expected a positive length",
                                    vt.col
                                )
                                .at_line(vt.line));
                            }
                            units = Some(units_of(v));
                        }
                        "customLayerData" => units_name = custom_units(&mut lx)?.or(units_name),
                        "upAxis" => {
                            let line = lx.peek()?.line;
                            let v = lx.string("upAxis")?;
                            up_axis = Some(match v.as_str() {
                                "Y" => UpAxis::PosY,
                                "Z" => UpAxis::PosZ,
                                _ => return Err(err!(Metadata, "upAxis {v:?}: expected \"Y\" or \"Z\"").at_line(line)),
                            });
                        }
                        _ => lx.skip_value()?,
                    }
                }
                _ => lx.skip_value()?,
            }
        }
    }
    // USD's own fallback: time codes per second default to the frames per second.
    let rate = tcps.or(fps);
    // surfcap's own name for the units (`customLayerData.surfcap_units`) with the layer's scale.
    if let Some(name) = units_name {
        units = Some(Units { name, metres_per_unit: units.and_then(|u: Units| u.metres_per_unit) });
    }

    let mut meshes: Vec<UsdaMesh> = Vec::new();
    let mut stack: Vec<Prim> = Vec::new();
    let mut roots = 0usize;
    let mut root_up: Option<UpAxis> = None;
    loop {
        let t = lx.peek()?;
        if t.kind == Kind::Eof {
            if let Some(p) = stack.last() {
                return Err(
                    lx.error(&t, format!("file ends inside prim <{}> of line {}: expected `}}`", p.path, p.line))
                );
            }
            break;
        }
        if t.kind == Kind::Punct(b'}') && !stack.is_empty() {
            lx.next()?;
            let p = stack.pop().unwrap_or(Prim { path: String::new(), line: 0, mesh: None });
            if let Some(m) = p.mesh {
                meshes.push(finish_mesh(&p.path, p.line, m, start, &mut notes)?);
            }
            continue;
        }
        let word = if t.kind == Kind::Ident { lx.text(&t) } else { "" };
        if matches!(word, "def" | "over" | "class") {
            lx.next()?;
            let mut ty = "";
            if lx.peek()?.kind == Kind::Ident {
                let tt = lx.next()?;
                ty = lx.text(&tt);
            }
            let name_tok = lx.peek()?;
            let name = lx.string(&format!("{word} {ty}: prim name"))?;
            if name.is_empty() || name.contains('/') {
                return Err(lx.error(&name_tok, format!("prim name {name:?}: expected an identifier")));
            }
            if lx.eat_punct(b'(')? {
                lx.metadata(&[])?;
            }
            let open = lx.expect_punct(b'{', &format!("prim \"{name}\""))?;
            let parent = stack.last().map(|p| p.path.as_str()).unwrap_or("");
            let path = format!("{parent}/{name}");
            let in_mesh = stack.last().is_some_and(|p| p.mesh.is_some());
            if stack.is_empty() && word != "class" {
                roots += 1;
            }
            if word == "class" || !matches!(ty, "" | "Xform" | "Scope" | "Mesh") || in_mesh {
                // Abstract classes, other prim types and prims nested in a mesh are skipped whole.
                lx.skip_rest_of_group(open)?;
                if word != "class" && ty != "Mesh" && !ty.is_empty() {
                    notes.push(format!(
                        "prim <{path}> of type {ty} (line {}) skipped with everything under it",
                        open.line
                    ));
                }
                continue;
            }
            stack.push(Prim { path, line: t.line, mesh: (ty == "Mesh").then(MeshAcc::default) });
            continue;
        }
        if stack.is_empty() {
            return Err(lx.error(&t, format!("found {}: expected a prim (`def`, `over` or `class`)", lx.describe(&t))));
        }
        if word == "variantSet" {
            lx.next()?;
            while lx.peek()?.kind != Kind::Punct(b'{') {
                let u = lx.next()?;
                if u.kind == Kind::Eof || u.kind == Kind::Punct(b'}') {
                    return Err(lx.error(&u, "variantSet: expected `{`"));
                }
            }
            let open = lx.next()?;
            lx.skip_rest_of_group(open)?;
            notes.push(format!("variantSet at line {} skipped (variants are not read)", t.line));
            continue;
        }
        let depth = stack.len();
        let prim = stack.last_mut().ok_or_else(|| err!(Syntax, "no prim"))?;
        property(&mut lx, prim, depth == 1, &mut root_up, &mut notes)?;
    }
    if meshes.is_empty() {
        return Err(err!(Empty, "no Mesh prim with points in this stage: expected at least one `def Mesh`"));
    }
    name_meshes(&mut meshes, roots);
    if root_up.is_some() && up_axis == Some(UpAxis::PosY) {
        up_axis = root_up;
    }
    Ok(UsdaStage { meshes, fps: rate, up_axis, units, notes })
}

/// Names the meshes after their paths: below the single root prim (when `roots` is 1), without a
/// last `mesh` component; two meshes mapped to one name keep their full paths.
pub(crate) fn name_meshes(meshes: &mut [UsdaMesh], roots: usize) {
    let mut names: Vec<String> = meshes
        .iter()
        .map(|m| {
            let mut parts: Vec<&str> = m.path.split('/').filter(|s| !s.is_empty()).collect();
            if roots == 1 && parts.len() > 1 {
                parts.remove(0);
            }
            if parts.len() > 1 && parts.last() == Some(&"mesh") {
                parts.pop();
            }
            parts.join("/")
        })
        .collect();
    let mut uses: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    for n in &names {
        *uses.entry(n.clone()).or_default() += 1;
    }
    for (n, m) in names.iter_mut().zip(meshes.iter()) {
        if uses[n.as_str()] > 1 {
            *n = m.path.trim_start_matches('/').to_string();
        }
    }
    for (m, n) in meshes.iter_mut().zip(names) {
        m.name = n;
    }
}

/// One property statement of `prim`: read when it is one of a mesh's, skipped otherwise.
fn property(
    lx: &mut Lexer,
    prim: &mut Prim,
    is_root: bool,
    root_up: &mut Option<UpAxis>,
    notes: &mut Vec<String>,
) -> Result<()> {
    const QUALIFIERS: [&str; 9] =
        ["custom", "uniform", "varying", "config", "prepend", "append", "delete", "add", "reorder"];
    loop {
        let q = lx.peek()?;
        if q.kind != Kind::Ident || !QUALIFIERS.contains(&lx.text(&q)) {
            break;
        }
        lx.next()?;
    }
    let t = lx.next()?;
    if t.kind != Kind::Ident {
        return Err(lx.error(
            &t,
            format!("found {}: expected a property, a prim (`def`, `over`, `class`) or `}}`", lx.describe(&t)),
        ));
    }
    let is_rel = lx.text(&t) == "rel";
    if !is_rel && lx.eat_punct(b'[')? {
        lx.expect_punct(b']', "array type")?;
    }
    let name = if lx.peek()?.kind == Kind::Punct(b'=') {
        // `reorder nameChildren = [...]`: no type.
        lx.text(&t)
    } else {
        let n = lx.next()?;
        if n.kind != Kind::Ident {
            return Err(
                lx.error(&n, format!("property of type {}: expected its name, found {}", lx.text(&t), lx.describe(&n)))
            );
        }
        lx.text(&n)
    };
    if lx.eat_punct(b'=')? {
        let line = lx.peek()?.line;
        let none = lx.is_ident("None")?;
        match (&mut prim.mesh, name) {
            (_, _) if none => lx.skip_value()?,
            (Some(m), "faceVertexCounts") => m.counts = Some((lx.int_array(name)?, line)),
            (Some(m), "faceVertexIndices") => m.indices = Some((lx.int_array(name)?, line)),
            (Some(m), "points") => m.points = Some((lx.tuple_array(name, 3)?, line)),
            (Some(m), "velocities") => m.velocities = Some((lx.tuple_array(name, 3)?, line)),
            (Some(m), "primvars:st") => m.st = Some((lx.tuple_array(name, 2)?, line)),
            (Some(m), "primvars:st:indices") => m.st_indices = Some(lx.int_array(name)?),
            (Some(m), "orientation") => m.left_handed = lx.string(name)? == "leftHanded",
            (Some(m), "faceVertexCounts.timeSamples" | "faceVertexIndices.timeSamples") => {
                let mut v = Vec::new();
                lx.time_samples(name, |l, time, tok| {
                    v.push((time, l.int_array(name)?, tok.line));
                    Ok(())
                })?;
                if name.starts_with("faceVertexCounts") {
                    m.counts_samples = Some(v);
                } else {
                    m.indices_samples = Some(v);
                }
            }
            (Some(m), "points.timeSamples" | "velocities.timeSamples") => {
                let mut v = Vec::new();
                lx.time_samples(name, |l, time, tok| {
                    v.push((time, l.tuple_array(name, 3)?, tok.line));
                    Ok(())
                })?;
                if name.starts_with("points") {
                    m.samples = Some(v);
                } else {
                    m.velocity_samples = Some(v);
                }
            }
            (Some(m), "primvars:surfcap:synthetic.timeSamples") => {
                let mut v = Vec::new();
                lx.time_samples(name, |l, time, tok| {
                    let (x, xt): (i64, _) = l.number(name)?;
                    let x = u32::try_from(x).ok().filter(|&x| x <= 1).ok_or_else(|| {
                        l.error(
                            &xt,
                            format!("{name}: label {x} at time {time}: expected 0 (original) or 1 (synthetic)"),
                        )
                    })?;
                    v.push((time, x, tok.line));
                    Ok(())
                })?;
                m.labels = Some(v);
            }
            (None, "xformOp:transform") => {
                let mut v = Vec::new();
                lx.expect_punct(b'(', name)?;
                for r in 0..4 {
                    if r > 0 {
                        lx.expect_punct(b',', name)?;
                    }
                    lx.expect_punct(b'(', name)?;
                    for c in 0..4 {
                        if c > 0 {
                            lx.expect_punct(b',', name)?;
                        }
                        v.push(lx.float64(name)?.0);
                    }
                    lx.expect_punct(b')', name)?;
                }
                lx.expect_punct(b')', name)?;
                let m: [f64; 16] = v.try_into().unwrap_or([0.0; 16]);
                match surfcap_up_rotation(&m) {
                    Some(u) if is_root => *root_up = Some(u),
                    _ => notes.push(format!(
                        "the transform of <{}> (line {line}) is ignored: points are read in the mesh's own coordinates",
                        prim.path
                    )),
                }
            }
            _ => {
                if name.starts_with("xformOp:") && name != "xformOp:transform" {
                    notes.push(format!(
                        "{name} of <{}> (line {line}) is ignored: points are read in the mesh's own coordinates",
                        prim.path
                    ));
                }
                lx.skip_value()?
            }
        }
    } else if is_rel && lx.peek()?.kind == Kind::Punct(b'=') {
        lx.next()?;
        lx.skip_value()?;
    }
    if lx.eat_punct(b'(')? {
        let found = lx.metadata(&["interpolation"])?;
        if let (Some(m), "primvars:st") = (&mut prim.mesh, name) {
            m.st_interpolation = found.into_iter().next().map(|(_, v)| v);
        }
    }
    Ok(())
}

/// Checks a mesh and turns it into a sequence: frames by time, fan-triangulated faces, labels.
pub(crate) fn finish_mesh(
    path: &str,
    line: usize,
    mut m: MeshAcc,
    start: f64,
    notes: &mut Vec<String>,
) -> Result<UsdaMesh> {
    let missing = |what: &str| err!(Syntax, "Mesh <{path}> has no {what}").at_line(line);
    // Frames.
    let mut frames: Vec<(f64, Vec<f32>, usize)> = match (m.samples.take(), m.points.take()) {
        (Some(s), _) if !s.is_empty() => s,
        (_, Some((p, l))) => vec![(0.0, p, l)],
        _ => return Err(missing("points: expected `points = [...]` or `points.timeSamples = { ... }`")),
    };
    frames.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (k, (t, _, l)) in frames.iter().enumerate() {
        if (t - start).fract() != 0.0 {
            return Err(err!(Syntax, "points.timeSamples: time {t} is not a whole frame from startTimeCode {start}")
                .at_line(*l));
        }
        if k > 0 {
            let prev = frames[k - 1].0;
            if *t == prev {
                return Err(err!(Syntax, "points.timeSamples: time {t} appears twice").at_line(*l));
            }
            if *t != prev + 1.0 {
                return Err(err!(
                    Syntax,
                    "points.timeSamples: time {t} follows {prev}: expected {} (every frame sampled; resample the animation to one sample per frame)",
                    prev + 1.0
                )
                .at_line(*l));
            }
        }
    }
    let n_points = frames[0].1.len() / 3;
    if m.counts_samples.is_some() || m.indices_samples.is_some() {
        if m.velocities.is_some() || m.velocity_samples.is_some() {
            notes.push(format!("velocities of <{path}> are ignored: its faces are time-sampled"));
        }
        return varying_mesh(path, line, m, frames, notes);
    }
    for (t, p, l) in &frames {
        if p.len() / 3 != n_points {
            return Err(err!(
                TopologyMismatch,
                "Mesh <{path}>: points at time {t} has {} points: expected {n_points} (as at time {})",
                p.len() / 3,
                frames[0].0
            )
            .at_line(*l));
        }
    }
    if n_points == 0 {
        return Err(err!(Empty, "Mesh <{path}> has no points").at_line(frames[0].2));
    }
    let (counts, counts_line) =
        m.counts.ok_or_else(|| missing("faceVertexCounts: expected an int[] of polygon sizes"))?;
    let (indices, indices_line) =
        m.indices.ok_or_else(|| missing("faceVertexIndices: expected an int[] of polygon corners"))?;
    let topology = polygon_topology(
        path,
        line,
        (&counts, counts_line),
        (&indices, indices_line),
        n_points,
        m.left_handed,
        m.st,
        (m.st_interpolation.as_deref(), m.st_indices.as_ref()),
        notes,
    )?;
    let labels = frame_labels(path, line, m.labels, &frames)?;
    let velocities = frame_velocities(path, m.velocities, m.velocity_samples, &frames)?;
    let times = frames.iter().map(|f| f.0).collect();
    let mut positions = Vec::new();
    for (_, p, _) in frames {
        if positions.is_empty() {
            positions = p;
        } else {
            positions.extend_from_slice(&p);
        }
    }
    Ok(UsdaMesh {
        path: path.to_string(),
        name: String::new(),
        topology,
        positions,
        times,
        labels,
        varying: None,
        velocities,
    })
}

/// A mesh's velocities, one per point per frame (`[frames * points * 3]`, units per second):
/// `velocities.timeSamples` with a sample at every frame's time (USD's value at a time between
/// samples is not what the writer meant: refused), else the default `velocities` at every
/// frame, else none.
fn frame_velocities(
    path: &str,
    default: Option<(Vec<f32>, usize)>,
    samples: Option<Vec<(f64, Vec<f32>, usize)>>,
    frames: &[(f64, Vec<f32>, usize)],
) -> Result<Option<Vec<f32>>> {
    let n_points = frames[0].1.len() / 3;
    let check = |v: &[f32], t: f64, l: usize| -> Result<()> {
        if v.len() / 3 != n_points {
            return Err(err!(
                Shape,
                "Mesh <{path}>: velocities at time {t} has {} values: expected one per point ({n_points})",
                v.len() / 3
            )
            .at_line(l));
        }
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(err!(NonFinite, "Mesh <{path}>: velocities at time {t}: point {} has {x}", i / 3).at_line(l));
        }
        Ok(())
    };
    let mut out = Vec::with_capacity(frames.len() * n_points * 3);
    match (samples.filter(|s| !s.is_empty()), default) {
        (Some(s), _) => {
            for (t, _, l) in frames {
                let (_, v, vl) = s.iter().find(|x| x.0 == *t).ok_or_else(|| {
                    err!(Syntax, "Mesh <{path}>: velocities.timeSamples has no sample at time {t}: expected one per points sample")
                        .at_line(*l)
                })?;
                check(v, *t, *vl)?;
                out.extend_from_slice(v);
            }
        }
        (None, Some((v, l))) => {
            check(&v, frames[0].0, l)?;
            for _ in frames {
                out.extend_from_slice(&v);
            }
        }
        (None, None) => return Ok(None),
    }
    Ok(Some(out))
}

/// The fan-triangulated topology of one set of faces (`counts`, `indices`) over `n_points`
/// points, checked, with its UVs when `uv_source` fits the faces.
#[allow(clippy::too_many_arguments)]
fn polygon_topology(
    path: &str,
    line: usize,
    (counts, counts_line): (&[u32], usize),
    (indices, indices_line): (&[u32], usize),
    n_points: usize,
    left_handed: bool,
    uv_source: Option<(Vec<f32>, usize)>,
    (st_interpolation, st_indices): (Option<&str>, Option<&Vec<u32>>),
    notes: &mut Vec<String>,
) -> Result<Topology> {
    // Faces.
    let mut total: usize = 0;
    for (f, &c) in counts.iter().enumerate() {
        if c < 3 {
            return Err(err!(DegenerateFace, "faceVertexCounts: polygon {f} has {c} vertices: expected 3 or more")
                .at_line(counts_line));
        }
        total = total.saturating_add(c as usize);
        if total > indices.len() {
            break;
        }
    }
    if total != indices.len() {
        return Err(err!(
            Shape,
            "faceVertexIndices has {} entries: faceVertexCounts (line {counts_line}) adds up to {}",
            indices.len(),
            if total > indices.len() { "more".to_string() } else { total.to_string() }
        )
        .at_line(indices_line));
    }
    if let Some((k, &v)) = indices.iter().enumerate().find(|(_, v)| **v as usize >= n_points) {
        return Err(err!(
            IndexOutOfRange,
            "faceVertexIndices: index {v} at position {k}: expected 0 to {} (the mesh has {n_points} points)",
            n_points - 1
        )
        .at_line(indices_line));
    }
    // Fan triangulation, keeping for each triangle corner its face-varying position.
    let mut tris = Vec::new();
    let mut corners_fv = Vec::new();
    let mut base = 0usize;
    for &c in counts {
        let c = c as usize;
        for k in 1..c - 1 {
            let mut fv = [base, base + k, base + k + 1];
            if left_handed {
                fv.swap(1, 2);
            }
            tris.push(fv.map(|i| indices[i]));
            corners_fv.push(fv);
        }
        base += c;
    }
    if let Some(k) = tris.iter().position(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        let t = tris[k];
        return Err(err!(
            DegenerateFace,
            "faceVertexIndices: triangle {k} of the fan triangulation is ({}, {}, {}): a polygon repeats a vertex",
            t[0],
            t[1],
            t[2]
        )
        .at_line(indices_line));
    }
    let uv = uv_source.and_then(|(st, st_line)| {
        let coords: Vec<[f32; 2]> = st.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let interp = st_interpolation.unwrap_or("faceVarying");
        let lookup = |i: usize| -> Option<u32> {
            let j = match st_indices {
                Some(ix) => *ix.get(i)? as usize,
                None => i,
            };
            (j < coords.len()).then_some(j as u32)
        };
        let corners: Option<Vec<[u32; 3]>> = match interp {
            "faceVarying" => {
                corners_fv.iter().map(|fv| Some([lookup(fv[0])?, lookup(fv[1])?, lookup(fv[2])?])).collect()
            }
            "vertex" | "varying" => tris
                .iter()
                .map(|t| Some([lookup(t[0] as usize)?, lookup(t[1] as usize)?, lookup(t[2] as usize)?]))
                .collect(),
            _ => None,
        };
        if corners.is_none() {
            notes.push(format!(
                "primvars:st of <{path}> (line {st_line}) does not fit its {interp} interpolation: UVs dropped"
            ));
        }
        corners.map(|corners| UvAtlas { coords, corners })
    });
    Topology::new(n_points, tris, uv).map_err(|mut e: Error| {
        e.message = format!("Mesh <{path}>: {}", e.message);
        e.at_line(line)
    })
}

/// One label per frame from `primvars:surfcap:synthetic.timeSamples`, when present.
fn frame_labels(
    path: &str,
    line: usize,
    labels: Option<Vec<(f64, u32, usize)>>,
    frames: &[(f64, Vec<f32>, usize)],
) -> Result<Option<Vec<FrameLabel>>> {
    Ok(match labels {
        None => None,
        Some(mut ls) => Some({
            // Sorted by time (stable: a repeated time keeps its last sample, as USD does), then
            // looked up by binary search: linear in the frames, whatever their number.
            ls.sort_by(|a, b| a.0.total_cmp(&b.0));
            frames
                .iter()
                .map(|(t, _, l)| match ls.partition_point(|x| x.0 <= *t).checked_sub(1).map(|i| &ls[i]).filter(|x| x.0 == *t) {
                    Some(x) => Ok(if x.1 == 1 { FrameLabel::Synthetic } else { FrameLabel::Original }),
                    None => Err(err!(
                        Metadata,
                        "primvars:surfcap:synthetic.timeSamples of <{path}> has no sample at time {t} (points sample at line {l}): expected one label per frame"
                    )
                    .at_line(ls.first().map(|x| x.2).unwrap_or(line))),
                })
                .collect::<Result<Vec<_>>>()?
        }),
    })
}

/// A mesh whose faces are time-sampled: each frame's faces are the latest sample at or before
/// its time (USD holds an array value until the next sample; before the first sample, the
/// first, or the default value when there is one), with that frame's own point count. Frames
/// whose faces all agree make an ordinary mesh; otherwise every frame keeps its own topology
/// (`UsdaMesh::varying`). UVs are dropped with a note then: a face-varying `st` written once
/// cannot fit faces that change.
fn varying_mesh(
    path: &str,
    line: usize,
    m: MeshAcc,
    frames: Vec<(f64, Vec<f32>, usize)>,
    notes: &mut Vec<String>,
) -> Result<UsdaMesh> {
    let missing = |what: &str| err!(Syntax, "Mesh <{path}> has no {what}").at_line(line);
    let held = |samples: &Option<Vec<(f64, Vec<u32>, usize)>>,
                default: &Option<(Vec<u32>, usize)>,
                what: &str|
     -> Result<Vec<(f64, Vec<u32>, usize)>> {
        let mut v: Vec<(f64, Vec<u32>, usize)> = samples.clone().unwrap_or_default();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        if v.is_empty() {
            let (d, l) = default.clone().ok_or_else(|| missing(what))?;
            v.push((f64::NEG_INFINITY, d, l));
        }
        Ok(v)
    };
    let counts = held(&m.counts_samples, &m.counts, "faceVertexCounts: expected an int[] of polygon sizes")?;
    let indices = held(&m.indices_samples, &m.indices, "faceVertexIndices: expected an int[] of polygon corners")?;
    let at = |v: &[(f64, Vec<u32>, usize)], t: f64| v.partition_point(|x| x.0 <= t).saturating_sub(1);
    let labels = frame_labels(path, line, m.labels.clone(), &frames)?;
    let mut per_frame: Vec<(Topology, Vec<f32>)> = Vec::with_capacity(frames.len());
    let mut built: Vec<((usize, usize, usize), Topology)> = Vec::new();
    for (t, p, l) in &frames {
        let n_points = p.len() / 3;
        if n_points == 0 {
            return Err(err!(Empty, "Mesh <{path}> has no points at time {t}").at_line(*l));
        }
        let key = (at(&counts, *t), at(&indices, *t), n_points);
        let topology = match built.iter().find(|(k, _)| *k == key) {
            Some((_, topo)) => topo.clone(),
            None => {
                let (c, i) = (&counts[key.0], &indices[key.1]);
                let topo = polygon_topology(
                    path,
                    line,
                    (&c.1, c.2),
                    (&i.1, i.2),
                    n_points,
                    m.left_handed,
                    None,
                    (None, None),
                    notes,
                )
                .map_err(|mut e| {
                    e.message = format!("at time {t}: {}", e.message);
                    e
                })?;
                built.push((key, topo.clone()));
                topo
            }
        };
        per_frame.push((topology, p.clone()));
    }
    if m.st.is_some() {
        notes.push(format!("primvars:st of <{path}> is dropped: its faces are time-sampled"));
    }
    let times: Vec<f64> = frames.iter().map(|f| f.0).collect();
    let same = per_frame.windows(2).all(|w| w[0].0 == w[1].0);
    let (topology, first) = per_frame[0].clone();
    if same {
        let positions = per_frame.into_iter().flat_map(|(_, p)| p).collect();
        return Ok(UsdaMesh {
            path: path.to_string(),
            name: String::new(),
            topology,
            positions,
            times,
            labels,
            varying: None,
            velocities: None,
        });
    }
    Ok(UsdaMesh {
        path: path.to_string(),
        name: String::new(),
        topology,
        positions: first,
        times,
        labels,
        varying: Some(per_frame),
        velocities: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::error::{ErrorKind, Location};
    use surfcap_mesh::subject::{Sequence, Subject};

    /// Velocities come back per frame from `velocities.timeSamples`, a default value answers every
    /// frame, and a sample with the wrong count or a missing time is refused with its line.
    #[test]
    fn velocities_are_read_per_frame_and_checked() {
        let stage = |v: &str| {
            format!(
                "#usda 1.0\n(\n    timeCodesPerSecond = 30\n)\ndef Mesh \"m\"\n{{\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points.timeSamples = {{\n        0: [(0, 0, 0), (1, 0, 0), (0, 1, 0)],\n        1: [(0, 0, 1), (1, 0, 1), (0, 1, 1)],\n    }}\n{v}}}\n"
            )
        };
        let read = |v: &str| parse_usda(stage(v).as_bytes());
        let samples = "    vector3f[] velocities.timeSamples = {\n        0: [(0, 0, 30), (0, 0, 30), (0, 0, 30)],\n        1: [(0, 0, 30), (0, 0, 30), (0, 0, 31)],\n    }\n";
        let m = &read(samples).unwrap().meshes[0];
        let v = m.velocities.as_ref().unwrap();
        assert_eq!(v.len(), 18);
        assert_eq!((v[2], v[17]), (30.0, 31.0));
        let m = &read("    vector3f[] velocities = [(1, 2, 3), (1, 2, 3), (1, 2, 3)]\n").unwrap().meshes[0];
        assert_eq!(m.velocities.as_ref().unwrap()[15..], [1.0, 2.0, 3.0]);
        assert!(read("").unwrap().meshes[0].velocities.is_none());
        let e = read(
            "    vector3f[] velocities.timeSamples = {\n        0: [(0, 0, 30)],\n        1: [(0, 0, 30)],\n    }\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 14") && e.contains("expected one per point (3)"), "{e}");
        let e = read(
            "    vector3f[] velocities.timeSamples = {\n        0: [(0, 0, 30), (0, 0, 30), (0, 0, 30)],\n    }\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("no sample at time 1"), "{e}");
    }

    /// The units' name comes back from `customLayerData` with the layer's scale, escapes and
    /// all; a stage without it keeps the name `metersPerUnit` gives.
    #[test]
    fn the_units_name_rides_in_the_custom_layer_data() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seq = Sequence::new("s", 3, vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        for units in [
            Units { name: "model units (\"not\" metres; a\\b)".into(), metres_per_unit: None },
            Units { name: "metres".into(), metres_per_unit: Some(1.0) },
            Units { name: "0.5 m".into(), metres_per_unit: Some(0.5) },
        ] {
            let s = Subject::new("t", topo.clone(), vec![seq.clone()], 30.0, UpAxis::PosY, units.clone()).unwrap();
            let mut text = Vec::new();
            crate::usda::write_usda(&mut text, &s).unwrap();
            assert_eq!(parse_usda(&text).unwrap().units, Some(units));
        }
        let plain =
            b"#usda 1.0\n(\n    metersPerUnit = 0.01\n)\ndef Mesh \"m\" {\n    int[] faceVertexCounts = [3]\n    \
            int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}\n";
        assert_eq!(parse_usda(plain).unwrap().units.unwrap().name, "cm");
        let bad = b"#usda 1.0\n(\n    customLayerData = { string surfcap_units }\n)\n";
        let e = parse_usda(bad).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("surfcap_units: expected `=`"), "{e}");
    }

    const HAND: &str = r#"#usda 1.0
(
    doc = """A "hand" written
    stage (with ) and ] inside"""
    customLayerData = { string note = "x \" ) }" dictionary d = { int a = 1 } }
    framesPerSecond = 12
    timeCodesPerSecond = 25   # the rate that counts
    metersPerUnit = 0.01
    upAxis = "Z"
    startTimeCode = 1
)

def Xform "root" (
    kind = "component"
)
{
    def Camera "cam" { float focalLength = 50 def Mesh "hidden" { } }
    over "empty" { }
    def Mesh "quad" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        uniform token subdivisionScheme = "none"
        int[] faceVertexCounts = [4, 3]
        int[] faceVertexIndices = [0, 1, 2, 3, 1, 4, 2]
        float3[] extent
        rel material:binding = </root/mat>
        custom string note = "a } b" (doc = "(nested (parens))")
        point3f[] points = [(9, 9, 9), (9, 9, 9), (9, 9, 9), (9, 9, 9), (9, 9, 9)]
        point3f[] points.timeSamples = {
            2: [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0.5, 0)],
            1: [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0.25, 0)],
            // a comment between samples
            3: [(0, 0, 1e-3), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, -0.5, 0)],
        }
        int primvars:surfcap:synthetic.timeSamples = { 1: 0, 2: 1, 3: 0 }
    }
}
"#;

    #[test]
    fn a_hand_written_stage_is_read_with_quads_fanned_and_frames_by_time() {
        let s = parse_usda(HAND.as_bytes()).unwrap();
        assert_eq!(s.fps, Some(25.0));
        assert_eq!(s.up_axis, Some(UpAxis::PosZ));
        assert_eq!(s.units, Some(Units { name: "cm".into(), metres_per_unit: Some(0.01) }));
        assert_eq!(s.meshes.len(), 1, "the mesh under the Camera is skipped");
        assert!(s.notes.iter().any(|n| n.contains("Camera")), "{:?}", s.notes);
        let m = &s.meshes[0];
        assert_eq!((m.path.as_str(), m.name.as_str()), ("/root/quad", "quad"));
        assert_eq!(m.topology.triangles(), &[[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
        assert_eq!(m.times, [1.0, 2.0, 3.0]);
        assert_eq!(m.positions.len(), 3 * 5 * 3);
        assert_eq!(&m.positions[12..15], &[2.0, 0.25, 0.0]);
        assert_eq!(&m.positions[27..30], &[2.0, 0.5, 0.0]);
        assert_eq!(m.positions[32], 1e-3);
        assert_eq!(m.labels, Some(vec![FrameLabel::Original, FrameLabel::Synthetic, FrameLabel::Original]));
    }

    #[test]
    fn left_handed_faces_are_flipped_and_a_default_is_one_frame() {
        let t = "#usda 1.0\ndef Mesh \"m\" {\n uniform token orientation = \"leftHanded\"\n int[] faceVertexCounts = [3]\n int[] faceVertexIndices = [0, 1, 2]\n point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n}\n";
        let s = parse_usda(t.as_bytes()).unwrap();
        assert_eq!(s.meshes[0].topology.triangles(), &[[0, 2, 1]]);
        assert_eq!(s.meshes[0].times, [0.0]);
        assert_eq!(s.meshes[0].name, "m");
        assert_eq!(s.fps, None);
    }

    #[test]
    fn surfcaps_own_usda_reads_back_to_the_bit() {
        let uv = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5]],
            corners: vec![[0, 1, 2], [1, 3, 2]],
        };
        let topo = Topology::new(4, vec![[0, 1, 2], [1, 3, 2]], Some(uv)).unwrap();
        let p = |k: f32| -> Vec<f32> {
            (0..12).map(|i| (i as f32 * 0.1 + k).sin() * 1e3 + 1.0 / 3.0).collect::<Vec<f32>>()
        };
        let a = Sequence::new("walk", 4, [p(0.0), p(1.0), p(2.0)].concat())
            .unwrap()
            .with_labels(vec![FrameLabel::Original, FrameLabel::Synthetic, FrameLabel::Original])
            .unwrap();
        let b = Sequence::new("run", 4, p(5.0)).unwrap();
        for up in [UpAxis::PosY, UpAxis::PosZ, UpAxis::NegZ, UpAxis::PosX, UpAxis::NegX, UpAxis::NegY] {
            let s =
                Subject::new("knight", topo.clone(), vec![a.clone(), b.clone()], 30.0, up, Units::parse("mm")).unwrap();
            let mut out = Vec::new();
            crate::usda::write_usda(&mut out, &s).unwrap();
            let r = parse_usda(&out).unwrap();
            assert_eq!((r.fps, r.up_axis), (Some(30.0), Some(up)));
            assert_eq!(r.units, Some(Units::parse("mm")));
            assert!(r.notes.is_empty(), "{:?}", r.notes);
            assert_eq!(r.meshes.len(), 2);
            for (m, q) in r.meshes.iter().zip(s.sequences()) {
                assert_eq!(m.name, q.name);
                assert_eq!(&m.topology, s.topology());
                assert!(m.positions == q.positions());
                assert_eq!(m.labels.as_deref(), Some(&q.labels[..]));
            }
        }
    }

    fn error(text: &str) -> Error {
        parse_usda(text.as_bytes()).unwrap_err()
    }

    const MESH: &str = "#usda 1.0\n(\n    startTimeCode = 0\n)\ndef Xform \"r\" {\n  def Mesh \"a\" {\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points.timeSamples = {\n      0: [(0,0,0),(1,0,0),(0,1,0)],\n      1: [(0,0,0),(1,0,0),(0,1,0)],\n    }\n  }\n}\n";

    #[test]
    fn bad_stages_name_the_line_and_what_was_expected() {
        assert!(parse_usda(MESH.as_bytes()).is_ok());
        let e = error(&MESH.replace("1: [", "2.5: ["));
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::Syntax, Some(Location::Line(11))), "{e}");
        assert!(e.to_string().contains("time 2.5 is not a whole frame"), "{e}");
        let e = error(&MESH.replace("1: [", "3: ["));
        assert!(e.to_string().contains("line 11: points.timeSamples: time 3 follows 0: expected 1"), "{e}");
        let e = error(&MESH.replace("[0, 1, 2]", "[0, 1, 9]"));
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::IndexOutOfRange, Some(Location::Line(8))), "{e}");
        assert!(e.message.contains("index 9 at position 2: expected 0 to 2"), "{e}");
        let e = error(&MESH.replace("[3]", "[4]"));
        assert_eq!(e.kind, ErrorKind::Shape, "{e}");
        let e = error(&MESH.replace("[3]", "[2, 1]"));
        assert_eq!(e.kind, ErrorKind::DegenerateFace, "{e}");
        let e = error(&MESH.replace("(0,1,0)],\n    }", "(0,nan,0)],\n    }"));
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::NonFinite, Some(Location::Line(11))), "{e}");
        let e = error(&MESH.replace("(1,0,0),(0,1,0)],\n    }", "(1,0,0)],\n    }"));
        assert_eq!(e.kind, ErrorKind::TopologyMismatch, "{e}");
        let e = error(&MESH[..MESH.len() - 3]);
        assert!(e.to_string().contains("file ends inside prim </r> of line 5"), "{e}");
        let e = error(&MESH.replace("(0,0,0),(1,0,0),(0,1,0)],\n    }", "(0,0,0),(1,0,0),(0,1,0)],\n    ]"));
        assert!(e.to_string().contains("line 12: column 5"), "{e}");
        let e = error(&MESH.replace("startTimeCode = 0", "upAxis = \"X\""));
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::Metadata, Some(Location::Line(3))), "{e}");
        // A crate file's header cut short: the crate reader's error.
        let e = error("PXR-USDC\0\0\0\0");
        assert_eq!(e.kind, ErrorKind::Truncated);
        assert!(e.message.contains("88-byte header"), "{e}");
        let e = error("#sdf 1.4.32\n");
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::Syntax, Some(Location::Line(1))), "{e}");
        let e = error("#usda 1.0\ndef Xform \"r\" {\n string s = \"never closed\n}\n");
        assert!(e.to_string().contains("line 3: column 13: string runs past"), "{e}");
        let e = error("#usda 1.0\ndef Xform \"r\" { }\n");
        assert_eq!(e.kind, ErrorKind::Empty);
        let no_faces = "#usda 1.0\ndef Mesh \"m\" {\n point3f[] points = [(0,0,0)]\n}\n";
        assert!(error(no_faces).to_string().contains("line 2: Mesh </m> has no faceVertexCounts"));
        let labels =
            MESH.replace("    }\n  }", "    }\n    int primvars:surfcap:synthetic.timeSamples = { 0: 2 }\n  }");
        assert!(
            error(&labels).to_string().contains("label 2 at time 0: expected 0 (original) or 1"),
            "{}",
            error(&labels)
        );
    }

    /// Faces time-sampled and changing (per-frame reconstructions): every frame keeps its own
    /// topology, a face sample held until the next; faces sampled but never changing are one.
    #[test]
    fn time_sampled_faces_give_each_frame_its_topology() {
        let text = "#usda 1.0\ndef Mesh \"m\" {\n  int[] faceVertexCounts.timeSamples = { 0: [3], 1: [3, 3] }\n  \
                    int[] faceVertexIndices.timeSamples = { 0: [0, 1, 2], 1: [0, 1, 2, 0, 2, 3] }\n  \
                    point3f[] points.timeSamples = {\n    0: [(0,0,0),(1,0,0),(0,1,0)],\n    \
                    1: [(0,0,0),(1,0,0),(1,1,0),(0,1,0)],\n    2: [(0,0,1),(1,0,1),(1,1,1),(0,1,1)],\n  }\n}\n";
        let s = parse_usda(text.as_bytes()).unwrap();
        let frames = s.meshes[0].varying.as_ref().expect("faces change");
        let tris: Vec<usize> = frames.iter().map(|(t, _)| t.n_triangles()).collect();
        assert_eq!(tris, [1, 2, 2]);
        assert_eq!(frames[2].1[2], 1.0);
        assert!(s.topology_mismatch().unwrap().to_string().contains("imports as a frame set"));
        let steady = text.replace("1: [3, 3] }", "1: [3] }").replace("1: [0, 1, 2, 0, 2, 3] }", "1: [0, 1, 2] }");
        let steady = steady.replace("1: [(0,0,0),(1,0,0),(1,1,0),(0,1,0)]", "1: [(0,0,0),(1,0,0),(1,1,0)]");
        let steady = steady.replace("2: [(0,0,1),(1,0,1),(1,1,1),(0,1,1)]", "2: [(0,0,1),(1,0,1),(1,1,1)]");
        let s = parse_usda(steady.as_bytes()).unwrap();
        assert!(s.meshes[0].varying.is_none() && s.meshes[0].positions.len() == 27);
        let bad = text.replace("1: [0, 1, 2, 0, 2, 3] }", "1: [0, 1, 2, 0, 2, 9] }");
        let e = parse_usda(bad.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("at time 1") && e.contains("index 9"), "{e}");
    }

    #[test]
    fn meshes_of_different_topology_are_refused_naming_both() {
        let b = MESH.replace("  }\n}\n", "  }\n  def Mesh \"b\" {\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 2, 1]\n    point3f[] points = [(0,0,0),(1,0,0),(0,1,0)]\n  }\n}\n");
        let e = parse_usda(b.as_bytes()).unwrap().topology_mismatch().unwrap();
        assert_eq!(e.kind, ErrorKind::TopologyMismatch);
        assert!(e.message.contains("</r/a>") && e.message.contains("</r/b>"), "{e}");
        let same = b.replace("[0, 2, 1]", "[0, 1, 2]");
        let s = parse_usda(same.as_bytes()).unwrap();
        assert_eq!(s.meshes.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(), ["a", "b"]);
        assert_eq!(s.meshes[1].times, [0.0]);
    }

    #[test]
    fn deep_nesting_and_long_input_do_not_overflow() {
        let deep = format!(
            "#usda 1.0\ndef Xform \"r\" {{\n custom int x = {}{}\n}}\n",
            "[".repeat(100_000),
            "]".repeat(100_000)
        );
        assert_eq!(error(&deep).kind, ErrorKind::Empty);
        let mut prims = String::from("#usda 1.0\n");
        for _ in 0..20_000 {
            prims.push_str("def Xform \"x\" {\n");
        }
        assert!(error(&prims).to_string().contains("file ends inside prim"));
    }
}

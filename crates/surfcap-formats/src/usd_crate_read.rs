//! USD import from binary crate files (`.usdc`, versions 0.4.0 to 0.14.0: what usd-core 20.x to
//! 26.x writes, and surfcap's `usd_crate_write.rs`; the format is described in `usd_crate.rs`).
//! The stage is read as the `.usda` reader (`usda_read.rs`) reads text, with the same
//! subset and the same choices: layer metadata (`timeCodesPerSecond`, `framesPerSecond`,
//! `startTimeCode`, `metersPerUnit`, `upAxis`, `customLayerData.surfcap_units`), prims of type
//! `Xform`, `Scope`, `Mesh` or no type walked from the root in `primChildren` order (classes and
//! other types skipped with everything under them, with a note), and on each `Mesh`
//! `faceVertexCounts`, `faceVertexIndices` (default or time-sampled), `orientation`, `points`,
//! `velocities`, `primvars:st` (+ `:indices`, `interpolation`) and `primvars:surfcap:synthetic`;
//! the meshes are then checked and named by the text reader's own functions.
//!
//! Integer arrays may be compressed (usd-core compresses those of 16 values and more); `point3f`,
//! `vector3f` and `texCoord2f` arrays are stored raw, so points come back to the bit. Every
//! offset and count read from the file is checked against the file's size before use, and every
//! error names the section, prim or attribute concerned.

use std::collections::HashMap;

use crate::usd_crate::{ValueRep, spec, ty};
use crate::usd_crate_compress::{decompress_ints, fast_decompress};
use crate::usda_read::{MeshAcc, UsdaMesh, UsdaStage, finish_mesh, name_meshes, surfcap_up_rotation, units_of};
use surfcap_mesh::error::{Error, Location, Result, err};
use surfcap_mesh::subject::{Units, UpAxis};

/// Whether `u32::MAX`: the end of a field set.
const END_OF_SET: u32 = u32::MAX;

/// A crate file held in memory, its tokens and strings read.
struct Crate<'a> {
    b: &'a [u8],
    minor: u8,
    tokens: Vec<String>,
    strings: Vec<u32>,
}

fn truncated(what: &str, at: u64, len: u64, size: usize) -> Error {
    err!(Truncated, "{what}: {len} bytes at byte {at} run past the end of the file ({size} bytes)")
}

/// Reads little-endian numbers from a slice, naming `what` when it runs out.
struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
    what: &'a str,
}

impl<'a> Cur<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.b.len());
        let Some(end) = end else {
            return Err(err!(Truncated, "{}: ends before {n} more bytes at its byte {}", self.what, self.pos));
        };
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap_or_default()))
    }
    fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap_or_default()))
    }
    /// A count of items of `item` bytes each that must fit in what is left.
    fn count(&mut self, item: usize) -> Result<usize> {
        let n = self.u64()?;
        let left = (self.b.len() - self.pos) as u64;
        if item > 0 && n.saturating_mul(item as u64) > left {
            return Err(err!(
                Truncated,
                "{}: {n} items of {item} bytes do not fit in the {left} bytes left",
                self.what
            ));
        }
        Ok(n as usize)
    }
    /// An integer-coded, compressed array of `n` values.
    fn ints(&mut self, n: usize, what: &str) -> Result<Vec<i32>> {
        let len = self.u64()?;
        let left = (self.b.len() - self.pos) as u64;
        if len > left {
            return Err(err!(Truncated, "{}: {what}: {len} compressed bytes, {left} left", self.what));
        }
        decompress_ints(self.take(len as usize)?, n, &format!("{} {what}", self.what))
    }
}

impl<'a> Crate<'a> {
    fn cur_at(&self, at: u64, what: &'a str) -> Result<Cur<'a>> {
        if at > self.b.len() as u64 {
            return Err(truncated(what, at, 0, self.b.len()));
        }
        Ok(Cur { b: self.b, pos: at as usize, what })
    }

    fn token(&self, i: u64, what: &str) -> Result<&str> {
        self.tokens
            .get(i as usize)
            .map(String::as_str)
            .ok_or_else(|| err!(Syntax, "{what}: token {i} out of range: the file has {} tokens", self.tokens.len()))
    }

    fn token_value(&self, rep: ValueRep, what: &str) -> Result<String> {
        if rep.ty() != ty::TOKEN || rep.is_array() || !rep.is_inlined() {
            return Err(wrong_type(rep, what, "a token"));
        }
        Ok(self.token(rep.payload(), what)?.to_string())
    }

    fn string_value(&self, rep: ValueRep, what: &str) -> Result<String> {
        match rep.ty() {
            ty::TOKEN => self.token_value(rep, what),
            ty::STRING if rep.is_inlined() => {
                let t = self.strings.get(rep.payload() as usize).ok_or_else(|| {
                    err!(Syntax, "{what}: string {} out of range: the file has {}", rep.payload(), self.strings.len())
                })?;
                Ok(self.token(u64::from(*t), what)?.to_string())
            }
            _ => Err(wrong_type(rep, what, "a string")),
        }
    }

    fn double(&self, rep: ValueRep, what: &str) -> Result<f64> {
        if rep.is_array() {
            return Err(wrong_type(rep, what, "a number"));
        }
        let p = rep.payload();
        Ok(match (rep.ty(), rep.is_inlined()) {
            // usd-core inlines a double that a float holds exactly, as the float's bits.
            (ty::DOUBLE | ty::FLOAT, true) => f64::from(f32::from_bits(p as u32)),
            (ty::INT, true) => f64::from(p as u32 as i32),
            (ty::DOUBLE, false) => {
                let b = self.cur_at(p, "a double value")?.take(8)?;
                f64::from_le_bytes(b.try_into().unwrap_or_default())
            }
            _ => return Err(wrong_type(rep, what, "a number")),
        })
    }

    /// A `TokenVector` (`primChildren`, `properties`) or a `token[]`.
    fn tokens(&self, rep: ValueRep, what: &str) -> Result<Vec<String>> {
        let mut c = match (rep.ty(), rep.is_array()) {
            (ty::TOKEN_VECTOR, false) => {
                let mut c = self.cur_at(rep.payload(), "a token list")?;
                let n = c.count(4)?;
                (c, n)
            }
            (ty::TOKEN, true) => self.array(rep, 4, what)?,
            _ => return Err(wrong_type(rep, what, "a list of names")),
        };
        (0..c.1).map(|_| Ok(self.token(u64::from(c.0.u32()?), what)?.to_string())).collect()
    }

    /// An uncompressed array's element reader and count (the count's width and a rank before it
    /// depend on the version).
    fn array(&self, rep: ValueRep, item: usize, what: &'a str) -> Result<(Cur<'a>, usize)> {
        if rep.payload() == 0 {
            return Ok((Cur { b: &[], pos: 0, what }, 0));
        }
        let mut c = self.cur_at(rep.payload(), what)?;
        if self.minor < 5 {
            c.u32()?; // rank, always 1
        }
        let n = if self.minor < 7 { u64::from(c.u32()?) } else { c.u64()? };
        let left = (self.b.len() - c.pos) as u64;
        if n.saturating_mul(item as u64) > left {
            return Err(err!(Truncated, "{what}: an array of {n} values does not fit in the {left} bytes left"));
        }
        Ok((c, n as usize))
    }

    /// A float vector array of `dim` components (`point3f[]`, `vector3f[]`, `texCoord2f[]`...).
    fn floats(&self, rep: ValueRep, dim: usize, what: &str) -> Result<Vec<f32>> {
        let want = if dim == 3 { ty::VEC3F } else { ty::VEC2F };
        if rep.ty() != want || !rep.is_array() || rep.is_compressed() {
            return Err(wrong_type(rep, what, if dim == 3 { "a float3 array" } else { "a float2 array" }));
        }
        let (mut c, n) = self.array(rep, 4 * dim, "a float array")?;
        let b = c.take(n * 4 * dim)?;
        Ok(b.chunks_exact(4).map(|x| f32::from_le_bytes([x[0], x[1], x[2], x[3]])).collect())
    }

    /// An `int[]` (possibly compressed), as the text reader keeps it.
    fn ints(&self, rep: ValueRep, what: &str) -> Result<Vec<u32>> {
        if !matches!(rep.ty(), ty::INT | ty::UINT) || !rep.is_array() {
            return Err(wrong_type(rep, what, "an int array"));
        }
        let (mut c, n) = self.array(rep, if rep.is_compressed() { 0 } else { 4 }, "an int array")?;
        if rep.is_compressed() {
            // At most 4 + n/4 + 4n coded bytes: n is bounded by the file's size.
            if n > 4 * self.b.len() {
                return Err(err!(Truncated, "{what}: a compressed array of {n} ints is larger than the file allows"));
            }
            return Ok(c.ints(n, what)?.into_iter().map(|x| x as u32).collect());
        }
        Ok(c.take(4 * n)?.chunks_exact(4).map(|x| u32::from_le_bytes([x[0], x[1], x[2], x[3]])).collect())
    }

    /// Time samples: (time, value) in file order.
    fn time_samples(&self, rep: ValueRep, what: &str) -> Result<Vec<(f64, ValueRep)>> {
        if rep.ty() != ty::TIME_SAMPLES || rep.is_inlined() {
            return Err(wrong_type(rep, what, "time samples"));
        }
        let mut c = self.cur_at(rep.payload(), "time samples")?;
        let skip = |c: &mut Cur| -> Result<()> {
            let start = c.pos as u64;
            let off = c.u64()?;
            c.pos = start
                .checked_add(off)
                .filter(|&p| p <= self.b.len() as u64)
                .ok_or_else(|| err!(Truncated, "{what}: time samples point past the end of the file"))?
                as usize;
            Ok(())
        };
        skip(&mut c)?;
        let times_rep = ValueRep(c.u64()?);
        skip(&mut c)?;
        let n = c.count(8)?;
        let reps: Vec<ValueRep> = (0..n).map(|_| c.u64().map(ValueRep)).collect::<Result<_>>()?;
        let times: Vec<f64> = match (times_rep.ty(), times_rep.is_array()) {
            (ty::DOUBLE_VECTOR, false) => {
                let mut t = self.cur_at(times_rep.payload(), "sample times")?;
                let k = t.count(8)?;
                t.take(8 * k)?.chunks_exact(8).map(|x| f64::from_le_bytes(x.try_into().unwrap_or_default())).collect()
            }
            (ty::DOUBLE, true) => {
                let (mut t, k) = self.array(times_rep, 8, "sample times")?;
                t.take(8 * k)?.chunks_exact(8).map(|x| f64::from_le_bytes(x.try_into().unwrap_or_default())).collect()
            }
            _ => return Err(wrong_type(times_rep, &format!("{what} (its times)"), "a list of doubles")),
        };
        if times.len() != reps.len() {
            return Err(err!(Syntax, "{what}: {} times for {} values", times.len(), reps.len()));
        }
        Ok(times.into_iter().zip(reps).collect())
    }

    /// The string `key` of a dictionary (`customLayerData`), when present.
    fn dictionary_string(&self, rep: ValueRep, key: &str, what: &str) -> Result<Option<String>> {
        if rep.ty() != ty::DICTIONARY || rep.is_inlined() {
            return Err(wrong_type(rep, what, "a dictionary"));
        }
        let mut c = self.cur_at(rep.payload(), "a dictionary")?;
        let n = c.count(20)?;
        for _ in 0..n {
            let k = self.string_value(ValueRep::inlined(ty::STRING, c.u32()?), what)?;
            let start = c.pos as u64;
            let off = c.u64()?;
            c.pos = start
                .checked_add(off)
                .filter(|&p| p <= self.b.len() as u64)
                .ok_or_else(|| err!(Truncated, "{what}: a dictionary value points past the end of the file"))?
                as usize;
            let v = ValueRep(c.u64()?);
            if k == key {
                return Ok(Some(self.string_value(v, &format!("{what}.{key}"))?));
            }
        }
        Ok(None)
    }

    fn matrix4d(&self, rep: ValueRep, what: &str) -> Result<[f64; 16]> {
        let mut m = [0.0; 16];
        match (rep.ty(), rep.is_inlined(), rep.is_array()) {
            // usd-core inlines a diagonal matrix of small integers: one i8 per diagonal entry.
            (ty::MATRIX4D, true, false) => {
                for (i, b) in (rep.payload() as u32).to_le_bytes().iter().enumerate() {
                    m[i * 5] = f64::from(*b as i8);
                }
            }
            (ty::MATRIX4D, false, false) => {
                let b = self.cur_at(rep.payload(), "a matrix")?.take(128)?;
                for (x, c) in m.iter_mut().zip(b.chunks_exact(8)) {
                    *x = f64::from_le_bytes(c.try_into().unwrap_or_default());
                }
            }
            _ => return Err(wrong_type(rep, what, "a matrix4d")),
        }
        Ok(m)
    }
}

fn wrong_type(rep: ValueRep, what: &str, expected: &str) -> Error {
    err!(
        Syntax,
        "{what}: a value of crate type {}{}: expected {expected}",
        rep.ty(),
        if rep.is_array() { " (array)" } else { "" }
    )
}

/// One spec: its kind and fields.
struct Spec {
    kind: u8,
    fields: Vec<(String, ValueRep)>,
}

impl Spec {
    fn get(&self, name: &str) -> Option<ValueRep> {
        self.fields.iter().find(|f| f.0 == name).map(|f| f.1)
    }
}

/// Parses a `.usdc` file held in memory (errors name the section, prim or attribute; the
/// caller adds the file).
pub fn parse_usdc(b: &[u8]) -> Result<UsdaStage> {
    if b.len() < 88 || !b.starts_with(b"PXR-USDC") {
        return Err(err!(Truncated, "a USD crate file needs its 88-byte header starting with `PXR-USDC`"));
    }
    let (major, minor, patch) = (b[8], b[9], b[10]);
    if major != 0 || !(4..=14).contains(&minor) {
        return Err(err!(
            Unsupported,
            "USD crate version {major}.{minor}.{patch}: surfcap reads 0.4.0 to 0.14.0 (convert it with usd-core's `usdcat in.usdc -o out.usda`)"
        ));
    }
    let mut cr = Crate { b, minor, tokens: Vec::new(), strings: Vec::new() };
    let toc_at = u64::from_le_bytes(b[16..24].try_into().unwrap_or_default());
    let mut toc = cr.cur_at(toc_at, "table of contents")?;
    let n_sections = toc.count(32)?;
    let mut sections: HashMap<String, (u64, u64)> = HashMap::new();
    for _ in 0..n_sections {
        let name = toc.take(16)?;
        let name: String = name.iter().take_while(|&&c| c != 0).map(|&c| c as char).collect();
        let (start, size) = (toc.u64()?, toc.u64()?);
        if start.checked_add(size).is_none_or(|e| e > b.len() as u64) {
            return Err(truncated(&format!("section {name}"), start, size, b.len()));
        }
        sections.insert(name, (start, size));
    }
    let section = |name: &'static str| -> Result<Cur<'_>> {
        let (start, size) = *sections
            .get(name)
            .ok_or_else(|| err!(Syntax, "no {name} section in the table of contents: not a USD crate file"))?;
        Ok(Cur { b: &b[..(start + size) as usize], pos: start as usize, what: name })
    };

    // TOKENS: count, sizes, then the NUL-terminated names, compressed.
    let mut c = section("TOKENS")?;
    let n = c.count(1)?;
    let raw_len = c.u64()?;
    let comp_len = c.u64()?;
    let comp = c.take(usize::try_from(comp_len).unwrap_or(usize::MAX))?;
    let raw = fast_decompress(comp, usize::try_from(raw_len).unwrap_or(usize::MAX), "TOKENS")?;
    cr.tokens = raw.split(|&x| x == 0).take(n).map(|t| String::from_utf8_lossy(t).into_owned()).collect();
    if cr.tokens.len() != n {
        return Err(err!(Syntax, "TOKENS: {} names for a count of {n}", cr.tokens.len()));
    }
    let mut c = section("STRINGS")?;
    let n = c.count(4)?;
    cr.strings = (0..n).map(|_| c.u32()).collect::<Result<_>>()?;

    let mut c = section("FIELDS")?;
    let n = c.count(0)?;
    if n > 8 * b.len() {
        return Err(err!(Syntax, "FIELDS: {n} fields do not fit in the file"));
    }
    let names = c.ints(n, "field names")?;
    let reps_len = c.u64()?;
    let reps = fast_decompress(c.take(usize::try_from(reps_len).unwrap_or(usize::MAX))?, 8 * n, "FIELDS values")?;
    if reps.len() != 8 * n {
        return Err(err!(Syntax, "FIELDS: {} bytes of values for {n} fields", reps.len()));
    }
    let fields: Vec<(String, ValueRep)> = names
        .iter()
        .zip(reps.chunks_exact(8))
        .map(|(&t, r)| {
            Ok((
                cr.token(t as u32 as u64, "FIELDS")?.to_string(),
                ValueRep(u64::from_le_bytes(r.try_into().unwrap_or_default())),
            ))
        })
        .collect::<Result<_>>()?;

    let mut c = section("FIELDSETS")?;
    let n = c.count(0)?;
    if n > 8 * b.len() {
        return Err(err!(Syntax, "FIELDSETS: {n} entries do not fit in the file"));
    }
    let fieldsets: Vec<u32> = c.ints(n, "field sets")?.into_iter().map(|x| x as u32).collect();

    // PATHS: the tree in depth-first order.
    let mut c = section("PATHS")?;
    let n_paths = c.count(0)?;
    let n_enc = c.count(0)?;
    if n_paths > 8 * b.len() || n_enc > n_paths {
        return Err(err!(Syntax, "PATHS: {n_enc} encoded paths for {n_paths} paths"));
    }
    let path_ix = c.ints(n_enc, "path indices")?;
    let elem = c.ints(n_enc, "element names")?;
    let jumps = c.ints(n_enc, "jumps")?;
    let mut paths: Vec<Option<String>> = vec![None; n_paths];
    let mut stack: Vec<(usize, Option<String>)> = vec![(0, None)];
    let mut visits = 0usize;
    while let Some((mut cur, mut parent)) = stack.pop() {
        loop {
            let this = cur;
            cur += 1;
            visits += 1;
            if this >= n_enc || visits > n_enc {
                return Err(err!(Syntax, "PATHS: the path tree's jumps leave its {n_enc} entries"));
            }
            let path = match &parent {
                None => "/".to_string(),
                Some(pp) => {
                    let t = elem[this];
                    let name = cr.token(u64::from(t.unsigned_abs()), "PATHS")?;
                    if t < 0 {
                        format!("{pp}.{name}")
                    } else if pp == "/" {
                        format!("/{name}")
                    } else {
                        format!("{pp}/{name}")
                    }
                }
            };
            let slot = paths
                .get_mut(path_ix[this] as u32 as usize)
                .ok_or_else(|| err!(Syntax, "PATHS: path index {} out of range ({n_paths} paths)", path_ix[this]))?;
            *slot = Some(path.clone());
            let j = jumps[this];
            let (has_child, has_sibling) = (j > 0 || j == -1, j >= 0);
            if has_child {
                if has_sibling {
                    stack.push((this + j as usize, parent.clone()));
                }
                parent = Some(path);
            }
            if !has_child && !has_sibling {
                break;
            }
        }
    }

    let mut c = section("SPECS")?;
    let n = c.count(0)?;
    if n > 8 * b.len() {
        return Err(err!(Syntax, "SPECS: {n} specs do not fit in the file"));
    }
    let spec_paths = c.ints(n, "spec paths")?;
    let spec_sets = c.ints(n, "spec field sets")?;
    let spec_kinds = c.ints(n, "spec kinds")?;
    let mut specs: HashMap<String, Spec> = HashMap::new();
    for k in 0..n {
        let path = paths
            .get(spec_paths[k] as u32 as usize)
            .and_then(|p| p.clone())
            .ok_or_else(|| err!(Syntax, "SPECS: spec {k} names path {} that the PATHS section lacks", spec_paths[k]))?;
        let mut fs = Vec::new();
        let mut i = spec_sets[k] as u32 as usize;
        loop {
            let f = *fieldsets
                .get(i)
                .ok_or_else(|| err!(Syntax, "SPECS: the field set of <{path}> runs past FIELDSETS' end"))?;
            if f == END_OF_SET {
                break;
            }
            fs.push(fields.get(f as usize).cloned().ok_or_else(|| {
                err!(Syntax, "FIELDSETS: field {f} of <{path}> out of range ({} fields)", fields.len())
            })?);
            i += 1;
        }
        specs.insert(path, Spec { kind: spec_kinds[k] as u8, fields: fs });
    }
    stage(&cr, &specs)
}

/// Error locations: a crate file has no lines (the text reader's functions mark line 0).
fn without_line(mut e: Error) -> Error {
    if matches!(e.location, Some(Location::Line(0))) {
        e.location = None;
    }
    e
}

/// The stage from the specs: layer metadata, then every mesh found walking the prims.
fn stage(cr: &Crate, specs: &HashMap<String, Spec>) -> Result<UsdaStage> {
    let root = specs
        .get("/")
        .filter(|s| s.kind == spec::PSEUDO_ROOT)
        .ok_or_else(|| err!(Syntax, "no pseudo-root spec </>: not a USD layer"))?;
    let mut rates = (None, None);
    let mut start = 0.0;
    let mut up_axis = None;
    let mut units: Option<Units> = None;
    let mut units_name = None;
    for (name, rep) in &root.fields {
        let what = format!("layer metadata {name}");
        match name.as_str() {
            "timeCodesPerSecond" | "framesPerSecond" => {
                let v = cr.double(*rep, &what)?;
                if v.is_nan() || v <= 0.0 {
                    return Err(err!(Metadata, "{name} = {v}: expected a positive rate"));
                }
                if name == "timeCodesPerSecond" { rates.0 = Some(v) } else { rates.1 = Some(v) }
            }
            "startTimeCode" => start = cr.double(*rep, &what)?,
            "metersPerUnit" => {
                let v = cr.double(*rep, &what)?;
                if v.is_nan() || v <= 0.0 {
                    return Err(err!(Metadata, "metersPerUnit = {v}: expected a positive length"));
                }
                units = Some(units_of(v));
            }
            "upAxis" => {
                let v = cr.string_value(*rep, &what)?;
                up_axis = Some(match v.as_str() {
                    "Y" => UpAxis::PosY,
                    "Z" => UpAxis::PosZ,
                    _ => return Err(err!(Metadata, "upAxis {v:?}: expected \"Y\" or \"Z\"")),
                });
            }
            "customLayerData" => units_name = cr.dictionary_string(*rep, "surfcap_units", &what)?.or(units_name),
            _ => {}
        }
    }
    if let Some(name) = units_name {
        units = Some(Units { name, metres_per_unit: units.and_then(|u| u.metres_per_unit) });
    }
    let mut notes = Vec::new();
    let mut meshes: Vec<UsdaMesh> = Vec::new();
    let mut root_up = None;
    let children = |path: &str, s: &Spec| -> Result<Vec<String>> {
        let Some(rep) = s.get("primChildren") else { return Ok(Vec::new()) };
        let names = cr.tokens(rep, &format!("<{path}> primChildren"))?;
        Ok(names.iter().map(|n| if path == "/" { format!("/{n}") } else { format!("{path}/{n}") }).collect())
    };
    let mut roots = 0;
    // Depth-first in primChildren order, as the prims appear in text.
    let mut stack: Vec<(String, usize)> = children("/", root)?.into_iter().rev().map(|p| (p, 1)).collect();
    while let Some((path, depth)) = stack.pop() {
        let Some(s) = specs.get(&path).filter(|s| s.kind == spec::PRIM) else {
            return Err(err!(Syntax, "prim <{path}> is listed as a child but has no prim spec"));
        };
        let specifier = s.get("specifier").map(|r| r.payload()).unwrap_or(0);
        let ty = match s.get("typeName") {
            Some(r) => cr.token_value(r, &format!("<{path}> typeName"))?,
            None => String::new(),
        };
        if specifier == 2 {
            continue; // a class
        }
        if depth == 1 {
            roots += 1;
        }
        if !matches!(ty.as_str(), "" | "Xform" | "Scope" | "Mesh") {
            notes.push(format!("prim <{path}> of type {ty} skipped with everything under it"));
            continue;
        }
        let props = match s.get("properties") {
            Some(r) => cr.tokens(r, &format!("<{path}> properties"))?,
            None => Vec::new(),
        };
        if ty == "Mesh" {
            let line_free = |e| without_line(e);
            let acc = mesh_properties(cr, specs, &path, &props).map_err(line_free)?;
            meshes.push(finish_mesh(&path, 0, acc, start, &mut notes).map_err(line_free)?);
            // Prims under a mesh are not read, as in text.
            continue;
        }
        for name in &props {
            if !name.starts_with("xformOp:") {
                continue;
            }
            let attr = format!("{path}.{name}");
            let m = match (name.as_str(), specs.get(&attr).and_then(|a| a.get("default"))) {
                ("xformOp:transform", Some(rep)) => Some(cr.matrix4d(rep, &format!("<{attr}>"))?),
                _ => None,
            };
            match m.as_ref().and_then(surfcap_up_rotation) {
                Some(u) if depth == 1 => root_up = Some(u),
                _ => {
                    notes.push(format!("{name} of <{path}> is ignored: points are read in the mesh's own coordinates"))
                }
            }
        }
        stack.extend(children(&path, s)?.into_iter().rev().map(|p| (p, depth + 1)));
    }
    if meshes.is_empty() {
        return Err(err!(Empty, "no Mesh prim with points in this stage: expected at least one Mesh"));
    }
    name_meshes(&mut meshes, roots);
    if root_up.is_some() && up_axis == Some(UpAxis::PosY) {
        up_axis = root_up;
    }
    Ok(UsdaStage { meshes, fps: rates.0.or(rates.1), up_axis, units, notes })
}

/// Time samples as the text reader keeps them: (time, value, line; 0 here).
type Samples<T> = Vec<(f64, Vec<T>, usize)>;

/// What a `Mesh` prim's attributes say, in the text reader's terms.
fn mesh_properties(cr: &Crate, specs: &HashMap<String, Spec>, path: &str, props: &[String]) -> Result<MeshAcc> {
    let mut m = MeshAcc::default();
    for name in props {
        let attr = format!("{path}.{name}");
        let Some(s) = specs.get(&attr) else { continue };
        let what = format!("<{attr}>");
        // A blocked value (`None` in text) is no value.
        let get = |f: &str| s.get(f).filter(|r| r.ty() != 51);
        let collect_f32 = |dim: usize| -> Result<Option<Samples<f32>>> {
            let Some(r) = get("timeSamples") else { return Ok(None) };
            let mut v = Vec::new();
            for (t, rep) in cr.time_samples(r, &what)? {
                if rep.ty() != 51 {
                    v.push((t, cr.floats(rep, dim, &format!("{what} at time {t}"))?, 0));
                }
            }
            Ok(Some(v))
        };
        let collect_int = || -> Result<Option<Samples<u32>>> {
            let Some(r) = get("timeSamples") else { return Ok(None) };
            let mut v = Vec::new();
            for (t, rep) in cr.time_samples(r, &what)? {
                if rep.ty() != 51 {
                    v.push((t, cr.ints(rep, &format!("{what} at time {t}"))?, 0));
                }
            }
            Ok(Some(v))
        };
        match name.as_str() {
            "faceVertexCounts" => {
                m.counts = get("default").map(|r| cr.ints(r, &what)).transpose()?.map(|v| (v, 0));
                m.counts_samples = collect_int()?;
            }
            "faceVertexIndices" => {
                m.indices = get("default").map(|r| cr.ints(r, &what)).transpose()?.map(|v| (v, 0));
                m.indices_samples = collect_int()?;
            }
            "points" => {
                m.points = get("default").map(|r| cr.floats(r, 3, &what)).transpose()?.map(|v| (v, 0));
                m.samples = collect_f32(3)?;
            }
            "velocities" => {
                m.velocities = get("default").map(|r| cr.floats(r, 3, &what)).transpose()?.map(|v| (v, 0));
                m.velocity_samples = collect_f32(3)?;
            }
            "primvars:st" => {
                m.st = get("default").map(|r| cr.floats(r, 2, &what)).transpose()?.map(|v| (v, 0));
                m.st_interpolation =
                    s.get("interpolation").map(|r| cr.token_value(r, &format!("{what} interpolation"))).transpose()?;
            }
            "primvars:st:indices" => m.st_indices = get("default").map(|r| cr.ints(r, &what)).transpose()?,
            "orientation" => {
                m.left_handed =
                    get("default").map(|r| cr.token_value(r, &what)).transpose()?.as_deref() == Some("leftHanded")
            }
            "primvars:surfcap:synthetic" => {
                if let Some(r) = get("timeSamples") {
                    let mut labels = Vec::new();
                    for (t, v) in cr.time_samples(r, &what)? {
                        let x = match (v.ty(), v.is_inlined(), v.is_array()) {
                            (ty::INT | ty::UINT | ty::INT64, true, false) => v.payload() as u32,
                            _ => return Err(wrong_type(v, &format!("{what} at time {t}"), "an int label")),
                        };
                        if x > 1 {
                            return Err(err!(
                                Syntax,
                                "{what} at time {t}: label {x}: expected 0 (original) or 1 (synthetic)"
                            ));
                        }
                        labels.push((t, x, 0));
                    }
                    m.labels = Some(labels);
                }
            }
            _ => {}
        }
    }
    Ok(m)
}

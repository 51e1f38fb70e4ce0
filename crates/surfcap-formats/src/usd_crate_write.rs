//! USD export as a binary crate file (`.usdc`, version 0.8.0; the format is described in
//! `usd_crate.rs`): the same stage as the `.usda` writer (`usda.rs`) writes, prim for prim and
//! field for field: one `Xform` per sequence under the subject's root `Xform`, each holding one
//! `Mesh` whose `points`, `velocities` (units per second, `vertex_velocity.rs`), `extent` and
//! frame labels (`primvars:surfcap:synthetic`) are time-sampled once per frame from time code
//! 0; `faceVertexCounts`/`faceVertexIndices`, UVs (`primvars:st` + indices) when the template
//! has them; the layer's `upAxis`, `metersPerUnit`, `timeCodesPerSecond`, `framesPerSecond`,
//! `startTimeCode`/`endTimeCode` and the units' name in `customLayerData.surfcap_units`.
//!
//! Floats are stored as the f32 bits the subject holds, so a reader gets them back to the bit.
//! Arrays are written uncompressed (the crate format compresses only integer and scalar float
//! arrays, never the `point3f` arrays that make up almost all of a capture); the structural
//! sections are integer-coded and LZ4-compressed as the format requires
//! (`usd_crate_compress.rs`). The writer streams: every value's place is planned first (the
//! header points at the sections after them), then the frames are written one at a time,
//! velocities computed as they go, so memory stays at one frame besides the subject.

use std::collections::HashMap;
use std::io::Write;

use crate::usd_crate::{VERSION, ValueRep, spec, ty};
use crate::usd_crate_compress::{compressed_ints, fast_compress};
use crate::usda::{prim_name, up_rotation};
use crate::vertex_velocity::frame_velocity;
use surfcap_mesh::subject::{FrameLabel, Subject, UpAxis};

/// What fills one planned place in the value data.
enum Blob {
    Bytes(Vec<u8>),
    /// A `point3f[]` of sequence `.0`'s frame `.1`.
    Points(usize, usize),
    /// A `vector3f[]` of the velocities of sequence `.0`'s frame `.1`.
    Velocities(usize, usize),
}

struct PathNode {
    token: u32,
    is_property: bool,
    children: Vec<usize>,
}

/// The stage being planned: tokens, fields, specs, paths, and where every value goes.
struct Plan {
    tokens: Vec<String>,
    token_ix: HashMap<String, u32>,
    strings: Vec<u32>,
    string_ix: HashMap<u32, u32>,
    fields: Vec<(u32, ValueRep)>,
    fieldsets: Vec<u32>,
    paths: Vec<PathNode>,
    specs: Vec<(u32, u32, u8)>,
    blobs: Vec<(u64, Blob)>,
    /// The next free byte of the value data.
    end: u64,
}

const HEADER_LEN: u64 = 88;

fn le_u64(n: usize) -> [u8; 8] {
    (n as u64).to_le_bytes()
}

impl Plan {
    fn new() -> Self {
        let mut p = Plan {
            tokens: Vec::new(),
            token_ix: HashMap::new(),
            strings: Vec::new(),
            string_ix: HashMap::new(),
            fields: Vec::new(),
            fieldsets: Vec::new(),
            paths: Vec::new(),
            specs: Vec::new(),
            blobs: Vec::new(),
            end: HEADER_LEN,
        };
        // Token 0 is the pseudo-root's empty element name: a property's token is stored negated,
        // so no property may have index 0.
        let root = p.token("");
        p.paths.push(PathNode { token: root, is_property: false, children: Vec::new() });
        p
    }

    fn token(&mut self, s: &str) -> u32 {
        if let Some(&i) = self.token_ix.get(s) {
            return i;
        }
        let i = self.tokens.len() as u32;
        self.tokens.push(s.to_string());
        self.token_ix.insert(s.to_string(), i);
        i
    }

    fn string(&mut self, s: &str) -> u32 {
        let t = self.token(s);
        if let Some(&i) = self.string_ix.get(&t) {
            return i;
        }
        let i = self.strings.len() as u32;
        self.strings.push(t);
        self.string_ix.insert(t, i);
        i
    }

    /// Plans a value of `len` bytes at the next 8-byte boundary; returns its offset.
    fn place(&mut self, len: u64, blob: Blob) -> u64 {
        let at = self.end.next_multiple_of(8);
        self.end = at + len;
        self.blobs.push((at, blob));
        at
    }

    fn bytes(&mut self, b: Vec<u8>) -> u64 {
        self.place(b.len() as u64, Blob::Bytes(b))
    }

    fn double(&mut self, v: f64) -> ValueRep {
        let at = self.bytes(v.to_le_bytes().to_vec());
        ValueRep::at(ty::DOUBLE, at)
    }

    fn token_value(&mut self, s: &str) -> ValueRep {
        ValueRep::inlined(ty::TOKEN, self.token(s))
    }

    fn token_list(&mut self, names: &[&str]) -> Vec<u8> {
        let mut b = le_u64(names.len()).to_vec();
        for n in names {
            b.extend_from_slice(&self.token(n).to_le_bytes());
        }
        b
    }

    /// A `token[]` value (an array).
    fn token_array(&mut self, names: &[&str]) -> ValueRep {
        let b = self.token_list(names);
        ValueRep::array_at(ty::TOKEN, self.bytes(b))
    }

    /// A list of names (`primChildren`, `properties`).
    fn token_vector(&mut self, names: &[&str]) -> ValueRep {
        let b = self.token_list(names);
        ValueRep::at(ty::TOKEN_VECTOR, self.bytes(b))
    }

    fn int_array(&mut self, v: impl ExactSizeIterator<Item = u32>) -> ValueRep {
        let mut b = le_u64(v.len()).to_vec();
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
        ValueRep::array_at(ty::INT, self.bytes(b))
    }

    fn float_array(&mut self, ty: u8, dim: usize, v: &[f32]) -> ValueRep {
        let mut b = le_u64(v.len() / dim).to_vec();
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
        ValueRep::array_at(ty, self.bytes(b))
    }

    /// Time samples: the times (shared by a sequence's attributes) and one value per time.
    fn time_samples(&mut self, times: ValueRep, values: &[ValueRep]) -> ValueRep {
        // Each part is preceded by the offset to it from there (8: it follows at once).
        let mut b = Vec::with_capacity(40 + 8 * values.len());
        b.extend_from_slice(&8i64.to_le_bytes());
        b.extend_from_slice(&times.0.to_le_bytes());
        b.extend_from_slice(&8i64.to_le_bytes());
        b.extend_from_slice(&le_u64(values.len()));
        for v in values {
            b.extend_from_slice(&v.0.to_le_bytes());
        }
        ValueRep::at(ty::TIME_SAMPLES, self.bytes(b))
    }

    fn path(&mut self, parent: usize, name: &str, is_property: bool) -> usize {
        let token = self.token(name);
        let i = self.paths.len();
        self.paths.push(PathNode { token, is_property, children: Vec::new() });
        self.paths[parent].children.push(i);
        i
    }

    fn spec(&mut self, path: usize, kind: u8, fields: Vec<(&str, ValueRep)>) {
        let set = self.fieldsets.len() as u32;
        for (name, rep) in fields {
            let t = self.token(name);
            self.fieldsets.push(self.fields.len() as u32);
            self.fields.push((t, rep));
        }
        self.fieldsets.push(u32::MAX);
        self.specs.push((path as u32, set, kind));
    }

    /// An attribute spec `name` on prim `prim` of type `type_name`.
    fn attribute(&mut self, prim: usize, name: &str, type_name: &str, mut fields: Vec<(&str, ValueRep)>) {
        let p = self.path(prim, name, true);
        fields.insert(0, ("typeName", self.token_value(type_name)));
        self.spec(p, spec::ATTRIBUTE, fields);
    }

    /// The `PATHS` section's three arrays: path index, element token (negated for properties)
    /// and the jump to the next sibling (-1: child only, 0: sibling only, -2: neither), in
    /// depth-first order.
    fn path_tree(&self) -> (Vec<i32>, Vec<i32>, Vec<i32>) {
        let n = self.paths.len();
        let mut size = vec![1usize; n];
        // Children always come after their parent: sizes accumulate from the end.
        for i in (0..n).rev() {
            let s: usize = self.paths[i].children.iter().map(|&c| size[c]).sum();
            size[i] += s;
        }
        let (mut ix, mut tok, mut jump) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        // (node, has a next sibling)
        let mut stack = vec![(0usize, false)];
        while let Some((node, has_sibling)) = stack.pop() {
            let p = &self.paths[node];
            ix.push(node as i32);
            tok.push(if p.is_property { -(p.token as i32) } else { p.token as i32 });
            let has_child = !p.children.is_empty();
            jump.push(match (has_child, has_sibling) {
                (true, true) => size[node] as i32,
                (true, false) => -1,
                (false, true) => 0,
                (false, false) => -2,
            });
            let k = p.children.len();
            for (j, &c) in p.children.iter().enumerate().rev() {
                stack.push((c, j + 1 < k));
            }
        }
        (ix, tok, jump)
    }
}

/// Writes `subject` as a `.usdc` stage.
pub fn write_usdc(w: &mut dyn Write, subject: &Subject) -> std::io::Result<()> {
    let topo = subject.topology();
    let mut p = Plan::new();
    let root_name = prim_name(&subject.name, &mut Vec::new());
    let mut taken = Vec::new();
    let seq_names: Vec<String> = subject.sequences().iter().map(|s| prim_name(&s.name, &mut taken)).collect();
    let last = subject.sequences().iter().map(|s| s.n_frames()).max().unwrap_or(1).saturating_sub(1);

    // The pseudo-root: layer metadata.
    let mut meta = vec![("defaultPrim", p.token_value(&root_name))];
    {
        // customLayerData = { string surfcap_units = "..." }: a one-entry dictionary.
        let key = p.string("surfcap_units");
        let value = ValueRep::inlined(ty::STRING, p.string(&subject.units.name));
        let mut b = le_u64(1).to_vec();
        b.extend_from_slice(&key.to_le_bytes());
        b.extend_from_slice(&8i64.to_le_bytes());
        b.extend_from_slice(&value.0.to_le_bytes());
        meta.push(("customLayerData", ValueRep::at(ty::DICTIONARY, p.bytes(b))));
    }
    let doc = format!("written by surfcap {}", env!("CARGO_PKG_VERSION"));
    meta.push(("documentation", ValueRep::inlined(ty::STRING, p.string(&doc))));
    meta.push(("endTimeCode", p.double(last as f64)));
    meta.push(("framesPerSecond", p.double(subject.fps)));
    if let Some(m) = subject.units.metres_per_unit {
        meta.push(("metersPerUnit", p.double(m)));
    }
    meta.push(("startTimeCode", p.double(0.0)));
    meta.push(("timeCodesPerSecond", p.double(subject.fps)));
    meta.push(("upAxis", p.token_value(if subject.up_axis == UpAxis::PosZ { "Z" } else { "Y" })));
    meta.push(("primChildren", p.token_vector(&[&root_name])));
    p.spec(0, spec::PSEUDO_ROOT, meta);

    // The root Xform, with the rotation that puts the subject's up axis on +Y when USD cannot
    // state it.
    let root = p.path(0, &root_name, false);
    let rotation = up_rotation(subject.up_axis);
    let names: Vec<&str> = seq_names.iter().map(String::as_str).collect();
    let mut fields = vec![
        ("specifier", ValueRep::inlined(ty::SPECIFIER, 0)),
        ("typeName", p.token_value("Xform")),
        ("primChildren", p.token_vector(&names)),
    ];
    if rotation.is_some() {
        fields.push(("properties", p.token_vector(&["xformOp:transform", "xformOpOrder"])));
    }
    p.spec(root, spec::PRIM, fields);
    if let Some([r0, r1, r2]) = rotation {
        // USD multiplies row vectors: the matrix is the transpose of the column-vector rotation.
        let mut b = Vec::with_capacity(128);
        for ((a, bb), c) in r0.iter().zip(&r1).zip(&r2) {
            for v in [f64::from(*a), f64::from(*bb), f64::from(*c), 0.0] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        for v in [0.0f64, 0.0, 0.0, 1.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let m = ValueRep::at(ty::MATRIX4D, p.bytes(b));
        p.attribute(root, "xformOp:transform", "matrix4d", vec![("default", m)]);
        let order = p.token_array(&["xformOp:transform"]);
        let uniform = ValueRep::inlined(ty::VARIABILITY, 1);
        p.attribute(root, "xformOpOrder", "token[]", vec![("variability", uniform), ("default", order)]);
    }

    // Topology and UVs, shared by every sequence's mesh.
    let counts = p.int_array(std::iter::repeat_n(3u32, topo.n_triangles()));
    let indices = p.int_array(topo.triangles().iter().flatten().copied().collect::<Vec<_>>().into_iter());
    let uv = topo.uv().map(|uv| {
        let st: Vec<f32> = uv.coords.iter().flatten().copied().collect();
        let st = p.float_array(ty::VEC2F, 2, &st);
        let ix = p.int_array(uv.corners.iter().flatten().copied().collect::<Vec<_>>().into_iter());
        (st, ix)
    });
    let point_bytes = 8 + 12 * topo.n_vertices() as u64;
    let mut properties = vec![
        "faceVertexCounts",
        "faceVertexIndices",
        "orientation",
        "subdivisionScheme",
        "points",
        "velocities",
        "extent",
        "primvars:surfcap:synthetic",
    ];
    if uv.is_some() {
        properties.extend(["primvars:st", "primvars:st:indices"]);
    }

    for (k, s) in subject.sequences().iter().enumerate() {
        let xf = p.path(root, &seq_names[k], false);
        let fields = vec![
            ("specifier", ValueRep::inlined(ty::SPECIFIER, 0)),
            ("typeName", p.token_value("Xform")),
            ("primChildren", p.token_vector(&["mesh"])),
        ];
        p.spec(xf, spec::PRIM, fields);
        let mesh = p.path(xf, "mesh", false);
        let fields = vec![
            ("specifier", ValueRep::inlined(ty::SPECIFIER, 0)),
            ("typeName", p.token_value("Mesh")),
            ("properties", p.token_vector(&properties)),
        ];
        p.spec(mesh, spec::PRIM, fields);

        let n = s.n_frames();
        let mut times = le_u64(n).to_vec();
        for f in 0..n {
            times.extend_from_slice(&(f as f64).to_le_bytes());
        }
        let times = ValueRep::at(ty::DOUBLE_VECTOR, p.bytes(times));
        let points: Vec<ValueRep> =
            (0..n).map(|f| ValueRep::array_at(ty::VEC3F, p.place(point_bytes, Blob::Points(k, f)))).collect();
        let velocities: Vec<ValueRep> =
            (0..n).map(|f| ValueRep::array_at(ty::VEC3F, p.place(point_bytes, Blob::Velocities(k, f)))).collect();
        let extents: Vec<ValueRep> = (0..n)
            .map(|f| {
                let (lo, hi) = surfcap_mesh::bounding_box(s.frame(f));
                p.float_array(ty::VEC3F, 3, &[lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]])
            })
            .collect();
        let labels: Vec<ValueRep> =
            s.labels.iter().map(|l| ValueRep::inlined(ty::INT, u32::from(*l == FrameLabel::Synthetic))).collect();
        let uniform = ValueRep::inlined(ty::VARIABILITY, 1);
        p.attribute(mesh, "faceVertexCounts", "int[]", vec![("default", counts)]);
        p.attribute(mesh, "faceVertexIndices", "int[]", vec![("default", indices)]);
        let v = p.token_value("rightHanded");
        p.attribute(mesh, "orientation", "token", vec![("variability", uniform), ("default", v)]);
        let v = p.token_value("none");
        p.attribute(mesh, "subdivisionScheme", "token", vec![("variability", uniform), ("default", v)]);
        let v = p.time_samples(times, &points);
        p.attribute(mesh, "points", "point3f[]", vec![("timeSamples", v)]);
        let v = p.time_samples(times, &velocities);
        p.attribute(mesh, "velocities", "vector3f[]", vec![("timeSamples", v)]);
        let v = p.time_samples(times, &extents);
        p.attribute(mesh, "extent", "float3[]", vec![("timeSamples", v)]);
        let v = p.time_samples(times, &labels);
        let constant = p.token_value("constant");
        p.attribute(mesh, "primvars:surfcap:synthetic", "int", vec![("interpolation", constant), ("timeSamples", v)]);
        if let Some((st, ix)) = uv {
            let face_varying = p.token_value("faceVarying");
            p.attribute(mesh, "primvars:st", "texCoord2f[]", vec![("interpolation", face_varying), ("default", st)]);
            p.attribute(mesh, "primvars:st:indices", "int[]", vec![("default", ix)]);
        }
    }

    // The structural sections.
    let mut sections: Vec<(&str, Vec<u8>)> = Vec::new();
    {
        let mut raw = Vec::new();
        for t in &p.tokens {
            raw.extend_from_slice(t.as_bytes());
            raw.push(0);
        }
        let c = fast_compress(&raw)?;
        let mut b = le_u64(p.tokens.len()).to_vec();
        b.extend_from_slice(&le_u64(raw.len()));
        b.extend_from_slice(&le_u64(c.len()));
        b.extend_from_slice(&c);
        sections.push(("TOKENS", b));
    }
    {
        let mut b = le_u64(p.strings.len()).to_vec();
        for s in &p.strings {
            b.extend_from_slice(&s.to_le_bytes());
        }
        sections.push(("STRINGS", b));
    }
    {
        let mut b = le_u64(p.fields.len()).to_vec();
        let names: Vec<i32> = p.fields.iter().map(|f| f.0 as i32).collect();
        b.extend_from_slice(&compressed_ints(&names)?);
        let reps: Vec<u8> = p.fields.iter().flat_map(|f| f.1.0.to_le_bytes()).collect();
        let c = fast_compress(&reps)?;
        b.extend_from_slice(&le_u64(c.len()));
        b.extend_from_slice(&c);
        sections.push(("FIELDS", b));
    }
    {
        let mut b = le_u64(p.fieldsets.len()).to_vec();
        let sets: Vec<i32> = p.fieldsets.iter().map(|&x| x as i32).collect();
        b.extend_from_slice(&compressed_ints(&sets)?);
        sections.push(("FIELDSETS", b));
    }
    {
        let (ix, tok, jump) = p.path_tree();
        let mut b = le_u64(p.paths.len()).to_vec();
        b.extend_from_slice(&le_u64(ix.len()));
        for a in [&ix, &tok, &jump] {
            b.extend_from_slice(&compressed_ints(a)?);
        }
        sections.push(("PATHS", b));
    }
    {
        let mut b = le_u64(p.specs.len()).to_vec();
        let paths: Vec<i32> = p.specs.iter().map(|s| s.0 as i32).collect();
        let sets: Vec<i32> = p.specs.iter().map(|s| s.1 as i32).collect();
        let kinds: Vec<i32> = p.specs.iter().map(|s| i32::from(s.2)).collect();
        for a in [&paths, &sets, &kinds] {
            b.extend_from_slice(&compressed_ints(a)?);
        }
        sections.push(("SPECS", b));
    }
    let mut at = p.end.next_multiple_of(8);
    let mut toc = le_u64(sections.len()).to_vec();
    for (name, b) in &sections {
        let mut n = [0u8; 16];
        n[..name.len()].copy_from_slice(name.as_bytes());
        toc.extend_from_slice(&n);
        toc.extend_from_slice(&at.to_le_bytes());
        toc.extend_from_slice(&(b.len() as u64).to_le_bytes());
        at += b.len() as u64;
    }

    // Bootstrap, values, sections, table of contents.
    let mut head = Vec::with_capacity(HEADER_LEN as usize);
    head.extend_from_slice(b"PXR-USDC");
    head.extend_from_slice(&[VERSION[0], VERSION[1], VERSION[2], 0, 0, 0, 0, 0]);
    head.extend_from_slice(&at.to_le_bytes());
    head.resize(HEADER_LEN as usize, 0);
    w.write_all(&head)?;
    let mut pos = HEADER_LEN;
    let mut frames: Option<(usize, Vec<&[f32]>)> = None;
    let mut buf = Vec::new();
    for (offset, blob) in &p.blobs {
        w.write_all(&vec![0u8; (offset - pos) as usize])?;
        let data: &[u8] = match blob {
            Blob::Bytes(b) => b,
            Blob::Points(k, f) | Blob::Velocities(k, f) => {
                let s = &subject.sequences()[*k];
                let values = if matches!(blob, Blob::Points(..)) {
                    s.frame(*f).to_vec()
                } else {
                    if frames.as_ref().is_none_or(|(j, _)| j != k) {
                        frames = Some((*k, (0..s.n_frames()).map(|f| s.frame(f)).collect()));
                    }
                    let fr = frames.as_ref().map(|(_, v)| v.as_slice()).unwrap_or_default();
                    frame_velocity(fr, *f, subject.fps)
                };
                buf.clear();
                buf.extend_from_slice(&le_u64(values.len() / 3));
                for x in values {
                    buf.extend_from_slice(&x.to_le_bytes());
                }
                &buf
            }
        };
        w.write_all(data)?;
        pos = offset + data.len() as u64;
    }
    w.write_all(&vec![0u8; (p.end.next_multiple_of(8) - pos) as usize])?;
    for (_, b) in &sections {
        w.write_all(b)?;
    }
    w.write_all(&toc)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::usda_read::parse_usda;
    use surfcap_mesh::subject::{Sequence, Units};
    use surfcap_mesh::topology::{Topology, UvAtlas};

    fn subject(up: UpAxis, uv: bool) -> Subject {
        let uv = uv
            .then(|| UvAtlas { coords: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]], corners: vec![[0, 1, 2], [2, 1, 0]] });
        let topo = Topology::new(4, vec![[0, 1, 2], [2, 1, 3]], uv).unwrap();
        let walk: Vec<f32> = (0..5 * 12).map(|i| (i as f32 * 0.37).sin() * 1.1e-3 + i as f32).collect();
        let a = Sequence::new("walk 1", 4, walk).unwrap();
        let b = Sequence::new("walk.1", 4, vec![0.1; 12]).unwrap().with_labels(vec![FrameLabel::Synthetic]).unwrap();
        Subject::new("1st", topo, vec![a, b], 30.0, up, Units { name: "cm \"x\"".into(), metres_per_unit: Some(0.01) })
            .unwrap()
    }

    #[test]
    fn a_usdc_reads_back_as_its_usda() {
        for (up, uv) in [(UpAxis::PosX, true), (UpAxis::PosZ, false), (UpAxis::PosY, true)] {
            let s = subject(up, uv);
            let mut c = Vec::new();
            write_usdc(&mut c, &s).unwrap();
            assert!(c.starts_with(b"PXR-USDC\0\x08\0"));
            let mut t = Vec::new();
            crate::usda::write_usda(&mut t, &s).unwrap();
            let (c, t) = (parse_usda(&c).unwrap(), parse_usda(&t).unwrap());
            assert_eq!((c.fps, c.up_axis), (Some(30.0), Some(up)));
            assert_eq!((c.fps, c.up_axis, &c.units, &c.notes), (t.fps, t.up_axis, &t.units, &t.notes));
            assert_eq!(c.meshes.len(), 2);
            for (a, b) in c.meshes.iter().zip(&t.meshes) {
                assert_eq!((&a.path, &a.name, &a.times, &a.labels), (&b.path, &b.name, &b.times, &b.labels));
                assert!(a.topology.first_difference(&b.topology).is_none());
                assert_eq!(a.topology.uv().is_some(), uv);
                // To the bit: the crate stores the f32s themselves.
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a.positions), bits(&b.positions));
                assert_eq!(bits(a.velocities.as_deref().unwrap()), bits(b.velocities.as_deref().unwrap()));
            }
            let walk = &c.meshes[0];
            assert_eq!(walk.name, "walk_1");
            assert_eq!(bits_of(&walk.positions), bits_of(s.sequences()[0].positions()));
        }
    }

    fn bits_of(v: &[f32]) -> Vec<u32> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn a_damaged_usdc_is_an_error_not_a_panic() {
        let mut c = Vec::new();
        write_usdc(&mut c, &subject(UpAxis::PosY, true)).unwrap();
        // Every truncation and a sweep of flipped bytes: errors, never panics.
        for n in (0..c.len()).step_by(7) {
            assert!(parse_usda(&c[..n.max(8)]).is_err() || n >= c.len());
        }
        for k in (88..c.len()).step_by(13) {
            let mut d = c.clone();
            d[k] ^= 0xA5;
            let _ = parse_usda(&d);
        }
        let mut d = c.clone();
        d[9] = 3;
        let e = parse_usda(&d).unwrap_err();
        assert!(e.message.contains("0.3.0") && e.message.contains("usdcat"), "{e}");
    }
}

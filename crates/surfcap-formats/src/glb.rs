//! glTF 2.0 binary (`.glb`) holding a subject's animation so that it plays in Blender and three.js.
//!
//! Layout: one mesh whose base positions are the first frame; one morph target per frame holding
//! that frame's displacement from the base; one animation per sequence that drives the mesh
//! weights (weight 1 on the frame's target at time `frame / fps`, LINEAR between frames; stored
//! as a sparse accessor, see [`GlbPlan`]).
//! Per-frame labels (original / synthetic), tags and fps are kept in the animation's `extras`
//! (`extras.surfcap`), and the subject's metadata in the root `extras.surfcap`. The mesh keeps the
//! subject's own coordinates; the node carries the rotation that brings the subject's up axis
//! onto glTF's +Y, so viewers show it upright while readers of the mesh data get exact positions.
//!
//! Written with `gltf-json` (typed glTF structs), read back with `gltf`.

use std::io::Write;

use rayon::prelude::*;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use serde_json::{Value, json};

use surfcap_mesh::error::{Result, err};
use surfcap_mesh::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

/// Positions and labels read back from a `.glb` file.
#[derive(Debug, Clone)]
pub struct GlbAnimation {
    pub topology: Topology,
    pub sequences: Vec<Sequence>,
    /// Frame rate, from the file's extras or from its keyframe times.
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
}

/// Quaternion (x, y, z, w) turning `up` onto +Y.
pub(super) fn up_to_y(up: UpAxis) -> Option<json::scene::UnitQuaternion> {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let q = match up {
        UpAxis::PosY => return None,
        UpAxis::PosZ => [-h, 0.0, 0.0, h],
        UpAxis::NegZ => [h, 0.0, 0.0, h],
        UpAxis::PosX => [0.0, 0.0, h, h],
        UpAxis::NegX => [0.0, 0.0, -h, h],
        UpAxis::NegY => [1.0, 0.0, 0.0, 0.0],
    };
    Some(json::scene::UnitQuaternion(q))
}

pub(super) fn raw(v: Value) -> json::Extras {
    Some(serde_json::value::to_raw_value(&v).expect("a serde_json::Value always serialises"))
}

/// The format stores lengths as 32-bit numbers: a `.glb` holds at most this many bytes.
pub const GLB_MAX_BYTES: u64 = u32::MAX as u64;

/// Bytes of the glTF header and the two chunk headers.
pub(super) const HEADERS: u64 = 12 + 8 + 8;

/// One buffer view's data, produced from the subject while the binary chunk is written.
enum Part {
    Indices,
    Base,
    /// Displacement of `frame` of sequence `seq` from the base (a morph target).
    Delta {
        seq: usize,
        frame: usize,
    },
    /// Key times of sequence `seq`, one per frame.
    Times {
        seq: usize,
    },
    /// Sparse weight indices of sequence `seq`: key f sets target `first + f` (element
    /// `f * targets + first + f` of the keys x targets weights).
    KeyTargets {
        seq: usize,
        first: usize,
        targets: usize,
    },
    /// Sparse weight values: 1.0 for each of `n` keys.
    Ones {
        n: usize,
    },
}

/// A `.glb` laid out from the subject's sizes alone: its JSON, and the parts of its binary chunk
/// in file order. The file's size is known (and checked against the format's limit) before a
/// byte is written, and [`GlbPlan::write`] streams the binary chunk from the subject instead of
/// building it in memory: a 10-minute capture of 10,000 vertices is 2 GB of morph targets.
///
/// Layout: one mesh whose base positions are the first frame, one morph target per frame (its
/// displacement from the base), one animation per sequence driving the weights. Each key sets one
/// weight to 1 and the others to 0, so the weights output (keys x targets numbers) is a sparse
/// accessor without a base buffer view (zeros) holding one index and one value per key: the file
/// grows linearly with the frame count, not quadratically. No per-target normals are written
/// (viewers recompute normals), so a frame costs 12 bytes per vertex.
pub struct GlbPlan<'a> {
    subject: &'a Subject,
    /// The JSON chunk, padded with spaces to a multiple of 4 bytes.
    json: Vec<u8>,
    parts: Vec<(Part, u64)>,
    bin_len: u64,
}

impl Part {
    /// Appends this part's little-endian bytes to `out`.
    fn bytes(&self, s: &Subject, out: &mut Vec<u8>) {
        let mut put = |x: [u8; 4]| out.extend_from_slice(&x);
        match *self {
            Part::Indices => s.topology().triangles().iter().flatten().for_each(|i| put(i.to_le_bytes())),
            Part::Base => base(s).iter().for_each(|x| put(x.to_le_bytes())),
            Part::Delta { seq, frame } => {
                let p = s.sequences()[seq].frame(frame);
                p.iter().zip(base(s)).for_each(|(&p, &b)| put((p - b).to_le_bytes()))
            }
            Part::Times { seq } => (0..s.sequences()[seq].n_frames()).for_each(|f| put(key_time(s, f).to_le_bytes())),
            Part::KeyTargets { seq, first, targets } => {
                (0..s.sequences()[seq].n_frames()).for_each(|f| put(((f * targets + first + f) as u32).to_le_bytes()))
            }
            Part::Ones { n } => (0..n).for_each(|_| put(1f32.to_le_bytes())),
        }
    }
}

fn base(s: &Subject) -> &[f32] {
    s.sequences()[0].frame(0)
}

fn key_time(s: &Subject, frame: usize) -> f32 {
    (frame as f64 / s.fps) as f32
}

pub(super) fn accessor(
    view: json::Index<json::buffer::View>,
    count: usize,
    component: json::accessor::ComponentType,
    type_: json::accessor::Type,
    min_max: Option<(Value, Value)>,
) -> json::Accessor {
    let (min, max) = min_max.unzip();
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        extensions: None,
        extras: None,
        type_: Valid(type_),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
    }
}

pub(super) fn vec3_bounds(p: &[f32]) -> (Value, Value) {
    let (lo, hi) = surfcap_mesh::bounding_box(p);
    (json!(lo), json!(hi))
}

/// Bounds of a frame's displacement from the base (glTF requires them on morph targets).
fn delta_bounds(p: &[f32], base: &[f32]) -> (Value, Value) {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for (pv, bv) in p.chunks_exact(3).zip(base.chunks_exact(3)) {
        for k in 0..3 {
            let d = pv[k] - bv[k];
            lo[k] = lo[k].min(d);
            hi[k] = hi[k].max(d);
        }
    }
    (json!(lo), json!(hi))
}

/// The binary chunk being laid out: its parts (of any kind `P`, each producing its bytes when
/// the file is written) in file order, and its length so far.
pub(super) struct Layout<P> {
    pub(super) parts: Vec<(P, u64)>,
    pub(super) len: u64,
}

impl<P> Layout<P> {
    pub(super) fn new() -> Self {
        Layout { parts: Vec::new(), len: 0 }
    }

    /// Reserves `len` bytes for `part` as a new buffer view. Every array here has 4-byte
    /// elements, so views stay 4-byte aligned without padding.
    pub(super) fn view(
        &mut self,
        root: &mut json::Root,
        part: P,
        len: usize,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        self.reserve(root, part, len, len, target)
    }

    /// Reserves `len` bytes of data of any length (an embedded image) as a new view, followed by
    /// zeros up to the next multiple of 4 so that the views after it stay aligned; `part` must
    /// write the padding too.
    pub(super) fn view_padded(
        &mut self,
        root: &mut json::Root,
        part: P,
        len: usize,
    ) -> json::Index<json::buffer::View> {
        self.reserve(root, part, len, len.div_ceil(4) * 4, None)
    }

    fn reserve(
        &mut self,
        root: &mut json::Root,
        part: P,
        len: usize,
        reserved: usize,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let offset = self.len;
        self.len += reserved as u64;
        self.parts.push((part, reserved as u64));
        root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(len),
            byte_offset: Some(USize64(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }
}

/// Weights of `keys` keys over `targets` morph targets, one non-zero (1.0) per key, as a sparse
/// accessor with no base buffer view.
fn sparse_weights(
    keys: usize,
    targets: usize,
    indices: json::Index<json::buffer::View>,
    values: json::Index<json::buffer::View>,
) -> json::Accessor {
    use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type, sparse};
    json::Accessor {
        buffer_view: None,
        byte_offset: None,
        count: USize64::from(keys * targets),
        component_type: Valid(GenericComponentType(ComponentType::F32)),
        extensions: None,
        extras: None,
        type_: Valid(Type::Scalar),
        min: None,
        max: None,
        name: None,
        normalized: false,
        sparse: Some(sparse::Sparse {
            count: USize64::from(keys),
            indices: sparse::Indices {
                buffer_view: indices,
                byte_offset: USize64(0),
                component_type: Valid(IndexComponentType(ComponentType::U32)),
                extensions: None,
                extras: None,
            },
            values: sparse::Values { buffer_view: values, byte_offset: USize64(0), extensions: None, extras: None },
            extensions: None,
            extras: None,
        }),
    }
}

impl<'a> GlbPlan<'a> {
    /// Lays out the file; an error when it would exceed the format's 4 GiB or its sparse weight
    /// indices (32-bit, keys x targets of a sequence) would overflow.
    pub fn new(subject: &'a Subject) -> Result<Self> {
        use json::accessor::{ComponentType, Type};
        use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
        let topo = subject.topology();
        let nv = topo.n_vertices();
        let n_targets = subject.n_frames();
        for s in subject.sequences() {
            if (s.n_frames() as u64) * (n_targets as u64) > u64::from(u32::MAX) + 1 {
                return Err(err!(
                    Unsupported,
                    "sequence {:?}: {} keys x {n_targets} morph targets exceed the 2^32 weights a glb's 32-bit sparse indices address; write fewer frames or --format npy or pc2",
                    s.name,
                    s.n_frames()
                ));
            }
        }
        let mut root = new_root();
        let mut bin = Layout::new();

        let iv = bin.view(&mut root, Part::Indices, 12 * topo.n_triangles(), Some(ElementArrayBuffer));
        let indices = root.push(accessor(iv, topo.n_triangles() * 3, ComponentType::U32, Type::Scalar, None));
        let bv = bin.view(&mut root, Part::Base, 12 * nv, Some(ArrayBuffer));
        let base_acc = root.push(accessor(bv, nv, ComponentType::F32, Type::Vec3, Some(vec3_bounds(base(subject)))));

        let frames: Vec<(usize, usize)> =
            subject.sequences().iter().enumerate().flat_map(|(k, s)| (0..s.n_frames()).map(move |f| (k, f))).collect();
        let bounds: Vec<(Value, Value)> =
            frames.par_iter().map(|&(k, f)| delta_bounds(subject.sequences()[k].frame(f), base(subject))).collect();
        let mut targets = Vec::with_capacity(n_targets);
        let mut names = Vec::with_capacity(n_targets);
        for (&(seq, frame), b) in frames.iter().zip(bounds) {
            let v = bin.view(&mut root, Part::Delta { seq, frame }, 12 * nv, Some(ArrayBuffer));
            let a = root.push(accessor(v, nv, ComponentType::F32, Type::Vec3, Some(b)));
            targets.push(json::mesh::MorphTarget { positions: Some(a), normals: None, tangents: None });
            names.push(format!("{}:{frame}", subject.sequences()[seq].name));
        }
        let mut attributes = std::collections::BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), base_acc);
        let mesh = root.push(json::Mesh {
            extensions: None,
            extras: raw(json!({ "targetNames": names })),
            name: Some(subject.name.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(indices),
                material: None,
                mode: Valid(json::mesh::Mode::Triangles),
                targets: Some(targets),
            }],
            weights: Some(vec![0.0; n_targets]),
        });
        let node = root.push(json::Node {
            mesh: Some(mesh),
            name: Some(subject.name.clone()),
            rotation: up_to_y(subject.up_axis),
            ..Default::default()
        });
        root.push(json::Scene { extensions: None, extras: None, name: None, nodes: vec![node] });
        root.scene = Some(json::Index::new(0));

        let mut first = 0usize;
        let mut seq_meta = Vec::new();
        for (seq, s) in subject.sequences().iter().enumerate() {
            let n = s.n_frames();
            let tv = bin.view(&mut root, Part::Times { seq }, 4 * n, None);
            let (t0, t1) = (key_time(subject, 0), key_time(subject, n - 1));
            let t_acc = root.push(accessor(tv, n, ComponentType::F32, Type::Scalar, Some((json!([t0]), json!([t1])))));
            let kv = bin.view(&mut root, Part::KeyTargets { seq, first, targets: n_targets }, 4 * n, None);
            let ov = bin.view(&mut root, Part::Ones { n }, 4 * n, None);
            let w_acc = root.push(sparse_weights(n, n_targets, kv, ov));
            let labels: Vec<&FrameLabel> = s.labels.iter().collect();
            let meta = json!({
                "sequence": s.name,
                "tags": s.tags,
                "fps": subject.fps,
                "first_target": first,
                "frames": n,
                "frame_labels": labels,
            });
            root.push(json::Animation {
                extensions: None,
                extras: raw(json!({ "surfcap": meta })),
                channels: vec![json::animation::Channel {
                    sampler: json::Index::new(0),
                    target: json::animation::Target {
                        extensions: None,
                        extras: None,
                        node,
                        path: Valid(json::animation::Property::MorphTargetWeights),
                    },
                    extensions: None,
                    extras: None,
                }],
                name: Some(s.name.clone()),
                samplers: vec![json::animation::Sampler {
                    extensions: None,
                    extras: None,
                    input: t_acc,
                    interpolation: Valid(json::animation::Interpolation::Linear),
                    output: w_acc,
                }],
            });
            seq_meta.push(meta);
            first += n;
        }
        root.extras = raw(json!({ "surfcap": {
            "subject": subject.name,
            "fps": subject.fps,
            "up_axis": subject.up_axis.as_str(),
            "units": subject.units,
            "sequences": seq_meta.iter().map(|m| json!({"name": m["sequence"], "frames": m["frames"], "tags": m["tags"]})).collect::<Vec<_>>(),
        }}));
        let json = finish_json(root, bin.len)?;
        let plan = GlbPlan { subject, json, parts: bin.parts, bin_len: bin.len };
        if plan.size() > GLB_MAX_BYTES {
            return Err(err!(
                Unsupported,
                "the glb would be {} bytes ({} frames of {nv} vertices), above the format's limit of {GLB_MAX_BYTES} bytes (4 GiB: its lengths are 32-bit); write fewer frames, or --format npy or pc2",
                plan.size(),
                n_targets
            ));
        }
        Ok(plan)
    }

    /// Size of the file in bytes.
    pub fn size(&self) -> u64 {
        HEADERS + self.json.len() as u64 + self.bin_len
    }

    /// Writes the file, one buffer view at a time.
    pub fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write_container(w, &self.json, &self.parts, |part, buf| part.bytes(self.subject, buf))
    }
}

/// A glTF root with surfcap's asset description.
pub(super) fn new_root() -> json::Root {
    json::Root {
        asset: json::Asset {
            copyright: None,
            extensions: None,
            extras: None,
            generator: Some(format!("surfcap {}", env!("CARGO_PKG_VERSION"))),
            min_version: None,
            version: "2.0".into(),
        },
        ..Default::default()
    }
}

/// Adds the one buffer (the binary chunk, `bin_len` bytes) and serialises the JSON chunk,
/// padded with spaces to a multiple of 4 bytes.
pub(super) fn finish_json(mut root: json::Root, bin_len: u64) -> Result<Vec<u8>> {
    root.push(json::Buffer { byte_length: USize64(bin_len), name: None, uri: None, extensions: None, extras: None });
    let mut json = root.to_vec().map_err(|e| err!(Syntax, "cannot serialise the glTF JSON: {e}"))?;
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    Ok(json)
}

/// Writes a glb: the header, the JSON chunk, then the binary chunk streamed part by part
/// (`bytes(part, buf)` appends a part's bytes; each must fill the view reserved for it).
pub(super) fn write_container<P>(
    w: &mut dyn Write,
    json: &[u8],
    parts: &[(P, u64)],
    mut bytes: impl FnMut(&P, &mut Vec<u8>),
) -> std::io::Result<()> {
    let bin_len: u64 = parts.iter().map(|(_, n)| n).sum();
    let size = HEADERS + json.len() as u64 + bin_len;
    let u32_le = |x: u64| u32::try_from(x).map_err(std::io::Error::other).map(u32::to_le_bytes);
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&u32_le(size)?)?;
    w.write_all(&u32_le(json.len() as u64)?)?;
    w.write_all(b"JSON")?;
    w.write_all(json)?;
    w.write_all(&u32_le(bin_len)?)?;
    w.write_all(b"BIN\0")?;
    let mut buf = Vec::new();
    for (part, len) in parts {
        buf.clear();
        bytes(part, &mut buf);
        debug_assert_eq!(buf.len() as u64, *len, "a part's bytes match its reserved view");
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Bytes of a `.glb` of sequences of `frames` frames of a mesh of `n_vertices` vertices and
/// `n_triangles` triangles, without building it: the binary chunk exactly, the JSON estimated at
/// 320 bytes per frame (a morph target's view, accessor with bounds and name). For refusing a
/// request before doing its work.
pub fn estimated_glb_bytes(n_vertices: usize, n_triangles: usize, frames: &[usize]) -> u64 {
    let total: u64 = frames.iter().map(|&n| n as u64).sum();
    let bin = 12 * n_triangles as u64 + 12 * n_vertices as u64 * (1 + total) + 12 * total;
    HEADERS + bin + 320 * total + 2048
}

/// Writes the subject's sequences as one `.glb` (see [`GlbPlan`]).
pub fn write_glb(w: &mut dyn Write, subject: &Subject) -> std::io::Result<()> {
    GlbPlan::new(subject).map_err(std::io::Error::other)?.write(w)
}

pub(super) fn extras_surfcap(extras: &json::Extras) -> Option<Value> {
    let v: Value = serde_json::from_str(extras.as_ref()?.get()).ok()?;
    v.get("surfcap").cloned()
}

/// Reads a `.glb` with a morph-target animation (as written by [`write_glb`], or any file whose
/// first triangle mesh is animated by weights). Each animation becomes a sequence.
pub fn parse_glb(bytes: &[u8]) -> Result<GlbAnimation> {
    if bytes.is_empty() {
        return Err(err!(Empty, "empty file: expected a glTF binary (.glb)"));
    }
    // The gltf crate's accessor readers trust buffer lengths on some paths; a malformed file must
    // be an error, never a crash.
    match std::panic::catch_unwind(|| decode(bytes)) {
        Ok(r) => r,
        Err(_) => Err(err!(Syntax, "malformed glTF: an accessor does not fit its buffer")),
    }
}

/// Parses a glb whose container and every accessor were checked to fit (see
/// [`check_container`], `check_accessor`), so that reading the accessors cannot run off the
/// binary chunk.
pub(super) fn open_checked(bytes: &[u8]) -> Result<gltf::Gltf> {
    let bytes = check_container(bytes)?;
    let g = gltf::Gltf::from_slice(bytes).map_err(|e| err!(Syntax, "not a valid glTF binary: {e}"))?;
    let blob_len = g.blob.as_deref().map_or(0, <[u8]>::len);
    for a in g.accessors() {
        check_accessor(&a, blob_len)?;
    }
    Ok(g)
}

/// Checks the GLB container (header and chunk lengths) before the gltf crate splits it: its
/// splitter subtracts lengths without checking them (found by the fuzzer, see fuzz/FINDINGS.md).
pub(super) fn check_container(bytes: &[u8]) -> Result<&[u8]> {
    let u32_at = |k: usize| bytes.get(k..k + 4).map(|b| u32::from_le_bytes(b.try_into().unwrap()) as usize);
    if bytes.len() < 20 || &bytes[..4] != b"glTF" {
        return Err(err!(Syntax, "no glTF binary header: expected a .glb file starting with 'glTF'"));
    }
    if u32_at(4) != Some(2) {
        return Err(err!(Unsupported, "glTF binary version {}: expected 2", u32_at(4).unwrap_or(0)));
    }
    let length = u32_at(8).unwrap_or(0);
    if length < 20 || length > bytes.len() {
        return Err(err!(Truncated, "header declares {length} bytes, the file has {}", bytes.len()));
    }
    let json_len = u32_at(12).unwrap_or(0);
    if &bytes[16..20] != b"JSON" || 20 + json_len > length {
        return Err(err!(Syntax, "the first chunk is not a JSON chunk that fits in the file"));
    }
    let bin_at = 20 + json_len.div_ceil(4) * 4;
    if bin_at + 8 <= length {
        let bin_len = u32_at(bin_at).unwrap_or(usize::MAX);
        if bin_len > length - bin_at - 8 {
            return Err(err!(Truncated, "binary chunk of {bin_len} bytes does not fit in the file"));
        }
    }
    Ok(&bytes[..length])
}

/// Checks that `len` bytes at `offset` of `view` lie inside the view and the binary chunk.
fn check_span(view: &gltf::buffer::View, offset: usize, len: Option<usize>, blob_len: usize, what: &str) -> Result<()> {
    if !matches!(view.buffer().source(), gltf::buffer::Source::Bin) {
        return Err(err!(Unsupported, "{what} refers to an external buffer: expected data inside the .glb"));
    }
    let need = len.and_then(|n| n.checked_add(offset));
    let view_end = view.offset().checked_add(view.length());
    match (need, view_end) {
        (Some(n), Some(e)) if n <= view.length() && e <= blob_len => Ok(()),
        _ => Err(err!(Truncated, "{what} does not fit in its buffer view or the binary chunk")),
    }
}

/// Checks that an accessor's data (dense and sparse) lies inside the binary chunk, before any
/// reader touches it.
pub(super) fn check_accessor(a: &gltf::Accessor, blob_len: usize) -> Result<()> {
    let what = format!("accessor {}", a.index());
    let count = a.count();
    if count == 0 {
        return Err(err!(Shape, "{what} has no elements"));
    }
    let elem = a.size();
    match (a.view(), a.sparse()) {
        (None, None) => return Err(err!(Unsupported, "{what} has neither a buffer view nor sparse data")),
        (Some(view), _) => {
            let stride = view.stride().unwrap_or(elem);
            let need = (count - 1).checked_mul(stride).and_then(|n| n.checked_add(elem));
            check_span(&view, a.offset(), need, blob_len, &what)?;
        }
        (None, Some(_)) => {}
    }
    if let Some(sp) = a.sparse() {
        if sp.count() > count {
            return Err(err!(Shape, "{what}: {} sparse values for {count} elements", sp.count()));
        }
        let isz = ix_size(&sp.indices());
        let (ix, vals) = (sp.indices(), sp.values());
        check_span(
            &ix.view(),
            ix.offset(),
            sp.count().checked_mul(isz),
            blob_len,
            &format!("{what}'s sparse indices"),
        )?;
        check_span(
            &vals.view(),
            vals.offset(),
            sp.count().checked_mul(elem),
            blob_len,
            &format!("{what}'s sparse values"),
        )?;
    }
    Ok(())
}

/// The non-zero weights `(target, weight)` of each key of a morph-weights output accessor of
/// `keys` x `targets` numbers, without expanding them all: a sparse float accessor with no base
/// view (as [`GlbPlan`] writes: one weight per key) is read from its indices and values; any other
/// through the gltf reader, one number at a time.
fn key_weights<'b>(
    a: &gltf::Accessor,
    blob: &[u8],
    keys: usize,
    targets: usize,
    dense: impl FnOnce() -> Option<Box<dyn Iterator<Item = f32> + 'b>>,
) -> Result<Vec<Vec<(usize, f32)>>> {
    let what = format!("accessor {}", a.index());
    if targets == 0 || Some(a.count()) != keys.checked_mul(targets) {
        return Err(err!(Shape, "{what}: {} weights for {keys} keyframes and {targets} morph targets", a.count()));
    }
    let mut out = vec![Vec::new(); keys];
    let is_f32 = a.data_type() == gltf::accessor::DataType::F32 && a.dimensions() == gltf::accessor::Dimensions::Scalar;
    if let (None, Some(sp), true) = (a.view(), a.sparse(), is_f32) {
        let (ix, vals) = (sp.indices(), sp.values());
        let at = |view: gltf::buffer::View, offset: usize, k: usize, size: usize| {
            let start = view.offset() + offset + k * size;
            &blob[start..start + size]
        };
        for k in 0..sp.count() {
            let b = at(ix.view(), ix.offset(), k, ix_size(&ix));
            let i = match b.len() {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= a.count() {
                return Err(err!(
                    IndexOutOfRange,
                    "{what}: sparse index {i} (entry {k}): expected below {}",
                    a.count()
                ));
            }
            let w = f32::from_le_bytes(at(vals.view(), vals.offset(), k, 4).try_into().expect("4 bytes"));
            if w != 0.0 {
                out[i / targets].push((i % targets, w));
            }
        }
        return Ok(out);
    }
    let all = dense().ok_or_else(|| err!(Syntax, "{what}: morph weights that cannot be read"))?;
    for (i, w) in all.take(keys * targets).enumerate() {
        if w != 0.0 {
            out[i / targets].push((i % targets, w));
        }
    }
    Ok(out)
}

fn ix_size(ix: &gltf::accessor::sparse::Indices) -> usize {
    match ix.index_type() {
        gltf::accessor::sparse::IndexType::U8 => 1,
        gltf::accessor::sparse::IndexType::U16 => 2,
        gltf::accessor::sparse::IndexType::U32 => 4,
    }
}

/// A morph target's displacements: read in place from the binary chunk when they are plain
/// little-endian f32 triples (as [`GlbPlan`] writes), so reading a long animation costs its file
/// and its positions, not a third copy; decoded by the gltf reader otherwise.
enum Target<'a> {
    Raw { bytes: &'a [u8], stride: usize },
    Decoded(Vec<f32>),
}

impl Target<'_> {
    /// A dense, float, 3-component accessor (its span was checked by [`check_accessor`]).
    fn is_raw(a: &gltf::Accessor) -> bool {
        a.view().is_some()
            && a.sparse().is_none()
            && !a.normalized()
            && a.data_type() == gltf::accessor::DataType::F32
            && a.dimensions() == gltf::accessor::Dimensions::Vec3
    }

    /// Adds `w` times the displacements to `p` (3 floats per vertex).
    fn add_to(&self, p: &mut [f32], w: f32) {
        match self {
            Target::Raw { bytes, stride } => {
                for (v, x) in p.chunks_exact_mut(3).enumerate() {
                    let at = &bytes[v * stride..v * stride + 12];
                    for (k, c) in x.iter_mut().enumerate() {
                        *c += w * f32::from_le_bytes(at[4 * k..4 * k + 4].try_into().expect("4 bytes"));
                    }
                }
            }
            Target::Decoded(t) => p.iter_mut().zip(t).for_each(|(x, d)| *x += w * d),
        }
    }
}

fn decode(bytes: &[u8]) -> Result<GlbAnimation> {
    if let Some(m) = crate::glb_frame_set::frame_set_meta(bytes) {
        let frames: u64 = m["sequences"].as_array().into_iter().flatten().filter_map(|q| q["frames"].as_u64()).sum();
        return Err(err!(
            TopologyMismatch,
            "a frame set ({frames} frames, every frame its own mesh): one topology cannot hold it; it imports as a \
             frame set (-o x.frames)"
        ));
    }
    let g = open_checked(bytes)?;
    let blob = g.blob.as_deref();
    let buffers = |b: gltf::Buffer| match b.source() {
        gltf::buffer::Source::Bin => blob,
        _ => None,
    };
    let (node, mesh) = g
        .nodes()
        .find_map(|n| n.mesh().map(|m| (n, m)))
        .ok_or_else(|| err!(Empty, "no node with a mesh: expected an animated triangle mesh"))?;
    let prim = mesh
        .primitives()
        .find(|p| p.mode() == gltf::mesh::Mode::Triangles)
        .ok_or_else(|| err!(Unsupported, "mesh {:?} has no triangle primitive", mesh.name().unwrap_or("")))?;
    let r = prim.reader(buffers);
    let base: Vec<f32> = r
        .read_positions()
        .ok_or_else(|| err!(Syntax, "triangle primitive has no readable POSITION accessor"))?
        .flatten()
        .collect();
    let nv = base.len() / 3;
    let flat: Vec<u32> = match r.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..nv as u32).collect(),
    };
    if !flat.len().is_multiple_of(3) {
        return Err(err!(Shape, "{} triangle indices: expected a multiple of 3", flat.len()));
    }
    let triangles: Vec<[u32; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let topology = Topology::new(nv, triangles, None)?;
    let mut targets: Vec<Target> = Vec::new();
    for (mt, (p, _, _)) in prim.morph_targets().zip(r.read_morph_targets()) {
        let k = targets.len();
        let t = match (mt.positions(), blob) {
            (Some(a), Some(blob)) if Target::is_raw(&a) => {
                if a.count() != nv {
                    return Err(err!(Shape, "morph target {k} has {} positions, expected {nv}", a.count()));
                }
                let view = a.view().expect("raw targets have a view");
                let stride = view.stride().unwrap_or(12);
                let start = view.offset() + a.offset();
                Target::Raw { bytes: &blob[start..start + (nv - 1) * stride + 12], stride }
            }
            _ => {
                let t: Vec<f32> = p.map(|it| it.flatten().collect()).unwrap_or_else(|| vec![0.0; 3 * nv]);
                if t.len() != 3 * nv {
                    return Err(err!(Shape, "morph target {k} has {} positions, expected {nv}", t.len() / 3));
                }
                Target::Decoded(t)
            }
        };
        targets.push(t);
    }
    let root_meta = extras_surfcap(&g.document.as_json().extras);
    let mut fps = match root_meta.as_ref().map(|m| &m["fps"]) {
        None | Some(serde_json::Value::Null) => None,
        Some(v) => Some(v.as_f64().and_then(|f| surfcap_mesh::subject::check_frame_rate(f).ok()).ok_or_else(|| {
            err!(Metadata, "extras.surfcap.fps = {v}: expected {}", surfcap_mesh::subject::FRAME_RATES_TEXT)
        })?),
    };
    let up_axis = root_meta.as_ref().and_then(|m| m["up_axis"].as_str()).and_then(|s| UpAxis::parse(s).ok());
    let units = root_meta.as_ref().and_then(|m| serde_json::from_value::<Units>(m["units"].clone()).ok());

    let mut sequences = Vec::new();
    for (ai, anim) in g.animations().enumerate() {
        let Some(ch) = anim.channels().find(|c| {
            c.target().node().index() == node.index()
                && c.target().property() == gltf::animation::Property::MorphTargetWeights
        }) else {
            continue;
        };
        let cr = ch.reader(buffers);
        let times: Vec<f32> =
            cr.read_inputs().ok_or_else(|| err!(Syntax, "animation {ai} has no input times"))?.collect();
        let nt = targets.len();
        let dense = || match cr.read_outputs() {
            Some(gltf::animation::util::ReadOutputs::MorphTargetWeights(w)) => {
                Some(Box::new(w.into_f32()) as Box<dyn Iterator<Item = f32>>)
            }
            _ => None,
        };
        let weights = key_weights(&ch.sampler().output(), blob.unwrap_or(&[]), times.len(), nt, dense)
            .map_err(|e| err!(Shape, "animation {ai}: {}", e.message))?;
        if fps.is_none() && times.len() > 1 && times[1] > times[0] {
            fps = Some((1.0 / (times[1] - times[0]) as f64 * 1000.0).round() / 1000.0);
        }
        let mut positions = Vec::with_capacity(times.len() * 3 * nv);
        for key in &weights {
            let start = positions.len();
            positions.extend_from_slice(&base);
            for &(k, w) in key {
                targets[k].add_to(&mut positions[start..], w);
            }
        }
        let name = anim.name().map(str::to_string).unwrap_or_else(|| format!("animation_{ai}"));
        let mut seq = Sequence::new(name, nv, positions)?;
        if let Some(m) = extras_surfcap(anim.extras()) {
            if let Ok(labels) = serde_json::from_value::<Vec<FrameLabel>>(m["frame_labels"].clone()) {
                seq = seq.with_labels(labels)?;
            }
            if let Ok(tags) = serde_json::from_value::<Vec<String>>(m["tags"].clone()) {
                seq = seq.with_tags(tags);
            }
        }
        sequences.push(seq);
    }
    if sequences.is_empty() {
        sequences.push(Sequence::new(mesh.name().unwrap_or("mesh").to_string(), nv, base)?);
    }
    Ok(GlbAnimation { topology, sequences, fps, up_axis, units })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};

    fn subject() -> Subject {
        let t = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let base = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.];
        let mut p = base.to_vec();
        p.extend(base.iter().map(|x| x * 2.0 + 0.5));
        let a = Sequence::new("a", 4, p).unwrap().with_tags(vec!["walk".into()]);
        let b = Sequence::new("b", 4, base.iter().map(|x| x - 1.0).collect())
            .unwrap()
            .with_labels(vec![FrameLabel::Synthetic])
            .unwrap();
        Subject::new("tet", t, vec![a, b], 25.0, UpAxis::PosZ, Units::metres()).unwrap()
    }

    #[test]
    fn round_trips_sequences_labels_and_metadata() {
        let s = subject();
        let mut buf = Vec::new();
        write_glb(&mut buf, &s).unwrap();
        let g = parse_glb(&buf).unwrap();
        assert_eq!(g.fps, Some(25.0));
        assert_eq!(g.up_axis, Some(UpAxis::PosZ));
        assert_eq!(g.topology, *s.topology());
        assert_eq!(g.sequences.len(), 2);
        for (x, y) in g.sequences.iter().zip(s.sequences()) {
            assert_eq!((&x.name, &x.tags, &x.labels), (&y.name, &y.tags, &y.labels));
            // base + (p - base) in f32: within an ulp of the base (bitwise equal for 77% of the
            // crane's coordinates; the others lie closer to zero than the base's precision).
            for (a, b) in x.positions().iter().zip(y.positions()) {
                assert!((a - b).abs() <= 2.4e-7, "{a} vs {b}");
            }
        }
    }

    /// A tetrahedron moving over `frames` frames, in two sequences.
    fn moving(frames: usize) -> Subject {
        let t = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let p = |n: usize, k0: usize| -> Vec<f32> {
            (0..n).flat_map(|f| (0..12).map(move |i| ((k0 + f) as f32 * 0.37 + i as f32).sin())).collect()
        };
        let half = frames / 2;
        let a = Sequence::new("a", 4, p(half, 0)).unwrap();
        let b = Sequence::new("b", 4, p(frames - half, half)).unwrap();
        Subject::new("tet", t, vec![a, b], 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    fn glb_size(frames: usize) -> u64 {
        let mut buf = Vec::new();
        write_glb(&mut buf, &moving(frames)).unwrap();
        buf.len() as u64
    }

    #[test]
    fn size_grows_linearly_with_the_frame_count() {
        // Bytes per added frame, from 100 to 200 and from 1,600 to 3,200 frames. A keys x targets
        // weights array made the second 16 times the first (4 bytes x frames per frame); with one
        // sparse weight per key both are the morph target (48 bytes), its bounds, view,
        // accessor, name, key time and weight, up to the digits of the numbers in the JSON.
        let per_frame = |n: usize| (glb_size(2 * n) - glb_size(n)) as f64 / n as f64;
        let (small, large) = (per_frame(100), per_frame(1600));
        assert!((48.0..600.0).contains(&small), "{small} bytes per frame");
        assert!((large - small).abs() < 0.1 * small, "{small} bytes per frame at 100 frames, {large} at 1,600");
        // The estimate used to refuse requests up front is close to the real size.
        for n in [2, 100, 3200] {
            let (real, est) = (glb_size(n) as f64, estimated_glb_bytes(4, 4, &[n / 2, n - n / 2]) as f64);
            assert!(est >= real && est < 1.5 * real + 4096.0, "{n} frames: {real} bytes, estimated {est}");
        }
    }

    #[test]
    fn weights_are_one_sparse_value_per_key_and_positions_round_trip() {
        let s = moving(300);
        let mut buf = Vec::new();
        write_glb(&mut buf, &s).unwrap();
        let g = gltf::Gltf::from_slice(&buf).unwrap();
        for anim in g.animations() {
            let out = anim.samplers().next().unwrap().output();
            let keys = anim.samplers().next().unwrap().input().count();
            assert!(out.view().is_none(), "weights have no dense base");
            assert_eq!((out.count(), out.sparse().unwrap().count()), (keys * 300, keys));
        }
        let back = parse_glb(&buf).unwrap();
        for (x, y) in back.sequences.iter().zip(s.sequences()) {
            // base + (p - base) in f32: within an ulp of the base (bitwise equal for 77% of the
            // crane's coordinates; the others lie closer to zero than the base's precision).
            for (a, b) in x.positions().iter().zip(y.positions()) {
                assert!((a - b).abs() <= 2.4e-7, "{a} vs {b}");
            }
        }
    }

    /// `glb` with its sparse weights replaced by dense keys x targets arrays, as other tools (and
    /// surfcap before sparse weights) write them.
    fn with_dense_weights(glb: &[u8]) -> Vec<u8> {
        let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let mut doc: Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
        let mut bin = glb[20 + json_len + 8..].to_vec();
        let outputs: Vec<usize> = doc["animations"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a["samplers"][0]["output"].as_u64().unwrap() as usize)
            .collect();
        for o in outputs {
            let acc = doc["accessors"][o].clone();
            let sp = &acc["sparse"];
            let at = |v: &Value| {
                let view = &doc["bufferViews"][v["bufferView"].as_u64().unwrap() as usize];
                view["byteOffset"].as_u64().unwrap_or(0) as usize + v["byteOffset"].as_u64().unwrap_or(0) as usize
            };
            let (ix, vals) = (at(&sp["indices"]), at(&sp["values"]));
            let mut dense = vec![0f32; acc["count"].as_u64().unwrap() as usize];
            for k in 0..sp["count"].as_u64().unwrap() as usize {
                let i = u32::from_le_bytes(bin[ix + 4 * k..ix + 4 * k + 4].try_into().unwrap()) as usize;
                dense[i] = f32::from_le_bytes(bin[vals + 4 * k..vals + 4 * k + 4].try_into().unwrap());
            }
            let views = doc["bufferViews"].as_array_mut().unwrap();
            views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": 4 * dense.len() }));
            let view = views.len() - 1;
            bin.extend(dense.iter().flat_map(|x| x.to_le_bytes()));
            let a = doc["accessors"][o].as_object_mut().unwrap();
            a.remove("sparse");
            a.insert("bufferView".into(), json!(view));
        }
        doc["buffers"][0]["byteLength"] = json!(bin.len());
        let mut text = serde_json::to_vec(&doc).unwrap();
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        for chunk in [&b"glTF"[..], &2u32.to_le_bytes(), &(total as u32).to_le_bytes()] {
            out.extend_from_slice(chunk);
        }
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&text);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }

    #[test]
    fn dense_weights_of_other_writers_read_the_same() {
        let s = moving(40);
        let mut buf = Vec::new();
        write_glb(&mut buf, &s).unwrap();
        let dense = with_dense_weights(&buf);
        assert!(dense.len() > buf.len() + 6000, "the weights are dense now (2 x 20 keys x 40 targets x 4 bytes)");
        let (a, b) = (parse_glb(&buf).unwrap(), parse_glb(&dense).unwrap());
        assert_eq!(a.sequences.len(), 2);
        for (x, y) in a.sequences.iter().zip(&b.sequences) {
            assert_eq!(x.positions(), y.positions());
        }
    }

    #[test]
    fn a_sparse_weight_index_past_the_end_is_an_error() {
        let mut buf = Vec::new();
        write_glb(&mut buf, &moving(6)).unwrap();
        let json_len = u32::from_le_bytes(buf[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&buf[20..20 + json_len]).unwrap();
        let out = doc["animations"][0]["samplers"][0]["output"].as_u64().unwrap() as usize;
        let view = doc["accessors"][out]["sparse"]["indices"]["bufferView"].as_u64().unwrap() as usize;
        let at = 20 + json_len + 8 + doc["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
        buf[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse_glb(&buf).unwrap_err();
        assert!(e.message.contains("sparse index 4294967295 (entry 0): expected below 18"), "{e}");
    }

    /// A frame rate in `extras.surfcap` of the wrong type or out of range is named, not ignored
    /// (the importer adds the file).
    #[test]
    fn a_bad_frame_rate_in_the_extras_is_named() {
        let mut buf = Vec::new();
        write_glb(&mut buf, &moving(3)).unwrap();
        let pattern = b"\"fps\":30.0";
        let places: Vec<usize> = (0..buf.len() - 10).filter(|&k| &buf[k..k + 10] == pattern).collect();
        assert!(!places.is_empty(), "the frame rate in the extras");
        for (same_length, shown) in
            [(&b"\"fps\":-30 "[..], "-30"), (b"\"fps\":\"x\" ", "\"x\""), (b"\"fps\":9e99", "9e+99")]
        {
            let mut bad = buf.clone();
            for &at in &places {
                bad[at..at + 10].copy_from_slice(same_length);
            }
            let e = parse_glb(&bad).unwrap_err().to_string();
            assert!(e.starts_with(&format!("extras.surfcap.fps = {shown}: expected 0.1 to 10000")), "{e}");
        }
    }

    #[test]
    fn damaged_files_are_errors_not_crashes() {
        let mut buf = Vec::new();
        write_glb(&mut buf, &subject()).unwrap();
        assert_eq!(parse_glb(&[]).unwrap_err().kind, surfcap_mesh::ErrorKind::Empty);
        for cut in [12, 40, buf.len() / 2, buf.len() - 8] {
            let e = parse_glb(&buf[..cut]).unwrap_err();
            assert!(!e.message.contains("malformed"), "cut at {cut}: a panic was caught: {e}");
        }
        // Shrink the declared binary chunk: accessors no longer fit.
        let json_len = u32::from_le_bytes(buf[12..16].try_into().unwrap()) as usize;
        let bin_at = 20 + json_len;
        let mut short = buf[..bin_at + 8 + 16].to_vec();
        short[bin_at..bin_at + 4].copy_from_slice(&16u32.to_le_bytes());
        let n = short.len() as u32;
        short[8..12].copy_from_slice(&n.to_le_bytes());
        let e = parse_glb(&short).unwrap_err();
        assert!(!e.message.contains("malformed"), "a panic was caught: {e}");
    }
}

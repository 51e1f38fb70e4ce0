//! glTF 2.0 binary (`.glb`) holding a subject's animation so that it plays in Blender and three.js.
//!
//! Layout: one mesh whose base positions are the first frame; one morph target per frame holding
//! that frame's displacement from the base; one animation per sequence that drives the mesh
//! weights (weight 1 on the frame's target at time `frame / fps`, LINEAR between frames).
//! Per-frame labels (original / synthetic), tags and fps are kept in the animation's `extras`
//! (`extras.surfcap`), and the subject's metadata in the root `extras.surfcap`. The mesh keeps the
//! subject's own coordinates; the node carries the rotation that brings the subject's up axis
//! onto glTF's +Y, so viewers show it upright while readers of the mesh data get exact positions.
//!
//! Written with `gltf-json` (typed glTF structs), read back with `gltf`.

use std::io::Write;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use serde_json::{Value, json};

use crate::error::{Result, err};
use crate::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};
use crate::topology::Topology;

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
fn up_to_y(up: UpAxis) -> Option<json::scene::UnitQuaternion> {
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

fn raw(v: Value) -> json::Extras {
    Some(serde_json::value::to_raw_value(&v).expect("a serde_json::Value always serialises"))
}

struct Bin {
    data: Vec<u8>,
}

impl Bin {
    /// Appends bytes as a new buffer view (4-byte aligned).
    fn view(
        &mut self,
        root: &mut json::Root,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let offset = self.data.len();
        self.data.extend_from_slice(bytes);
        root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn accessor(
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

fn vec3_bounds(p: &[f32]) -> (Value, Value) {
    let (lo, hi) = crate::bounding_box(p);
    (json!(lo), json!(hi))
}

/// Writes the subject's sequences as one `.glb`.
pub fn write_glb(w: &mut dyn Write, subject: &Subject) -> std::io::Result<()> {
    use json::accessor::{ComponentType, Type};
    let topo = subject.topology();
    let nv = topo.n_vertices();
    let mut root = json::Root {
        asset: json::Asset {
            copyright: None,
            extensions: None,
            extras: None,
            generator: Some(format!("surfcap {}", env!("CARGO_PKG_VERSION"))),
            min_version: None,
            version: "2.0".into(),
        },
        ..Default::default()
    };
    let mut bin = Bin { data: Vec::new() };

    let indices: Vec<u8> = topo.triangles().iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    let iv = bin.view(&mut root, &indices, Some(json::buffer::Target::ElementArrayBuffer));
    let indices = root.push(accessor(iv, topo.n_triangles() * 3, ComponentType::U32, Type::Scalar, None));

    let base = subject.sequences()[0].frame(0);
    let bv = bin.view(&mut root, &f32_bytes(base), Some(json::buffer::Target::ArrayBuffer));
    let base_acc = root.push(accessor(bv, nv, ComponentType::F32, Type::Vec3, Some(vec3_bounds(base))));

    let n_targets = subject.n_frames();
    let mut targets = Vec::with_capacity(n_targets);
    let mut names = Vec::with_capacity(n_targets);
    let mut delta = vec![0f32; 3 * nv];
    for s in subject.sequences() {
        for f in 0..s.n_frames() {
            for ((d, p), b) in delta.iter_mut().zip(s.frame(f)).zip(base) {
                *d = p - b;
            }
            let v = bin.view(&mut root, &f32_bytes(&delta), Some(json::buffer::Target::ArrayBuffer));
            let a = root.push(accessor(v, nv, ComponentType::F32, Type::Vec3, Some(vec3_bounds(&delta))));
            targets.push(json::mesh::MorphTarget { positions: Some(a), normals: None, tangents: None });
            names.push(format!("{}:{f}", s.name));
        }
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
    for s in subject.sequences() {
        let n = s.n_frames();
        let times: Vec<f32> = (0..n).map(|f| (f as f64 / subject.fps) as f32).collect();
        let tv = bin.view(&mut root, &f32_bytes(&times), None);
        let t_acc = root.push(accessor(
            tv,
            n,
            ComponentType::F32,
            Type::Scalar,
            Some((json!([times[0]]), json!([times[n - 1]]))),
        ));
        let mut weights = vec![0f32; n * n_targets];
        for f in 0..n {
            weights[f * n_targets + first + f] = 1.0;
        }
        let wv = bin.view(&mut root, &f32_bytes(&weights), None);
        let w_acc = root.push(accessor(wv, n * n_targets, ComponentType::F32, Type::Scalar, None));
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
    while !bin.data.len().is_multiple_of(4) {
        bin.data.push(0);
    }
    root.push(json::Buffer {
        byte_length: USize64::from(bin.data.len()),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    let json_bytes = root.to_vec().map_err(std::io::Error::other)?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: std::borrow::Cow::Owned(json_bytes),
        bin: Some(std::borrow::Cow::Owned(bin.data)),
    };
    glb.to_writer(w).map_err(std::io::Error::other)
}

fn extras_surfcap(extras: &json::Extras) -> Option<Value> {
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

/// Checks the GLB container (header and chunk lengths) before the gltf crate splits it: its
/// splitter subtracts lengths without checking them (found by the fuzzer, see fuzz/FINDINGS.md).
fn check_container(bytes: &[u8]) -> Result<&[u8]> {
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

/// Checks that an accessor's data lies inside the binary chunk, before any reader touches it.
fn check_accessor(a: &gltf::Accessor, blob_len: usize) -> Result<()> {
    let what = || format!("accessor {}", a.index());
    let Some(view) = a.view() else {
        return Err(err!(Unsupported, "{} has no buffer view (sparse-only data is not supported)", what()));
    };
    if !matches!(view.buffer().source(), gltf::buffer::Source::Bin) {
        return Err(err!(Unsupported, "{} refers to an external buffer: expected data inside the .glb", what()));
    }
    let elem = a.size();
    let stride = view.stride().unwrap_or(elem);
    let count = a.count();
    if count == 0 {
        return Err(err!(Shape, "{} has no elements", what()));
    }
    let need =
        (count - 1).checked_mul(stride).and_then(|n| n.checked_add(elem)).and_then(|n| n.checked_add(a.offset()));
    let view_end = view.offset().checked_add(view.length());
    match (need, view_end) {
        (Some(n), Some(e)) if n <= view.length() && e <= blob_len => Ok(()),
        _ => Err(err!(Truncated, "{} does not fit in its buffer view or the binary chunk", what())),
    }
}

fn decode(bytes: &[u8]) -> Result<GlbAnimation> {
    let bytes = check_container(bytes)?;
    let g = gltf::Gltf::from_slice(bytes).map_err(|e| err!(Syntax, "not a valid glTF binary: {e}"))?;
    let blob = g.blob.as_deref();
    let blob_len = blob.map_or(0, <[u8]>::len);
    for a in g.accessors() {
        check_accessor(&a, blob_len)?;
    }
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
    let mut targets: Vec<Vec<f32>> = Vec::new();
    for (p, _, _) in r.read_morph_targets() {
        let t: Vec<f32> = p.map(|it| it.flatten().collect()).unwrap_or_else(|| vec![0.0; 3 * nv]);
        if t.len() != 3 * nv {
            return Err(err!(Shape, "morph target {} has {} positions, expected {nv}", targets.len(), t.len() / 3));
        }
        targets.push(t);
    }
    let root_meta = extras_surfcap(&g.document.as_json().extras);
    let mut fps = root_meta.as_ref().and_then(|m| m["fps"].as_f64());
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
        let weights: Vec<f32> = match cr.read_outputs() {
            Some(gltf::animation::util::ReadOutputs::MorphTargetWeights(w)) => w.into_f32().collect(),
            _ => return Err(err!(Syntax, "animation {ai} has no morph weights")),
        };
        let nt = targets.len();
        if nt == 0 || weights.len() != times.len() * nt {
            return Err(err!(
                Shape,
                "animation {ai}: {} weights for {} keyframes and {nt} morph targets",
                weights.len(),
                times.len()
            ));
        }
        if fps.is_none() && times.len() > 1 && times[1] > times[0] {
            fps = Some((1.0 / (times[1] - times[0]) as f64 * 1000.0).round() / 1000.0);
        }
        let mut positions = Vec::with_capacity(times.len() * 3 * nv);
        for f in 0..times.len() {
            let mut p = base.clone();
            for (k, &w) in weights[f * nt..(f + 1) * nt].iter().enumerate() {
                if w != 0.0 {
                    for (x, d) in p.iter_mut().zip(&targets[k]) {
                        *x += w * d;
                    }
                }
            }
            positions.extend_from_slice(&p);
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
    use crate::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};

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
            assert_eq!(x.positions(), y.positions());
        }
    }

    #[test]
    fn damaged_files_are_errors_not_crashes() {
        let mut buf = Vec::new();
        write_glb(&mut buf, &subject()).unwrap();
        assert_eq!(parse_glb(&[]).unwrap_err().kind, crate::ErrorKind::Empty);
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

//! A frame set (every frame its own vertices and triangles, Huang et al. 2009's input and the
//! surface motion graph's output) as a glTF 2.0 binary that plays in three.js and Blender.
//!
//! Morph targets, which [`super::glb`] uses for a subject, need one vertex count and one index
//! buffer for every frame, which a frame set does not have. Here every frame is its own mesh on
//! its own node, and each sequence's animation shows exactly one of them at a time by animating
//! the nodes' `scale` between (0, 0, 0) and (1, 1, 1) with `STEP` interpolation:
//!
//! - glTF 2.0 has no visibility property; the specification's own implementation note (glTF PR
//!   #2059, after issue #1314) names zero scale as the way to animate visibility, "fluid
//!   simulation where the computed mesh changes shape and changes number of vertices" being its
//!   example. A zero-scale node collapses to a point and draws nothing.
//! - three.js maps `STEP` to `InterpolateDiscrete` (three.js PR #10308) and plays scale 0<->1
//!   (glTF-Sample-Models issue #321 lists it among the viewers that do), and Blender's importer
//!   turns `STEP` keys into `CONSTANT` ones on the object's scale, so both step frame by frame.
//! - `KHR_node_visibility` (ratified in 2025) needs `KHR_animation_pointer` to be animated, which
//!   three.js's GLTFLoader does not read and older Blender releases do not import: it is not
//!   yet the robust choice. Moving hidden frames far away breaks viewers that frame the scene.
//!
//! Layout: a root node (named after the set, turning its up axis onto +Y as the subject writer
//! does) with one child node per sequence, whose children are the sequence's frames, one node
//! and one mesh each (`sequence:frame`; positions and `u32` indices, no normals). Statically
//! only the first sequence and each sequence's frame 0 have scale 1, so a viewer that does not
//! play animations shows one mesh. Animation `s` (named after the sequence) sets every sequence
//! node's scale once (1 for its own, 0 for the others) and steps its frames: frame `k`'s node
//! has keys 0, 1, 0 at frames `k-1`, `k`, `k+1` (1 before a clip's start or after its end
//! holds the first or last key's value). The key times are views into one array of frame times
//! per sequence and the 0/1 values views into one 36-byte array, so a frame costs its own mesh
//! and four bytes of binary data, never a per-frame copy of every key.
//!
//! `extras.surfcap` on the root holds `kind: "frame-set"`, the set's name, fps, up axis,
//! units and per sequence its node, tags and frame labels; [`parse_glb_frame_set`] reads it
//! back exactly (positions and triangles bit for bit; texture coordinates and the
//! correspondence of `remesh-frames` are not kept).

use std::io::Write;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use serde_json::{Value, json};

use super::glb::{
    GLB_MAX_BYTES, HEADERS, Layout, accessor, check_container, finish_json, new_root, open_checked, raw, up_to_y,
    vec3_bounds, write_container,
};
use crate::error::{Result, err};
use crate::frame_set::{FrameSet, FrameSetSequence};
use crate::subject::{FrameLabel, Units, UpAxis};
use crate::topology::Topology;

/// The value of `extras.surfcap.kind` that marks a frame-set glb.
pub const FRAME_SET_KIND: &str = "frame-set";

/// One buffer view's data, produced from the frame set while the binary chunk is written.
enum Part {
    /// The triangles of frame `frame` of sequence `seq`.
    Indices { seq: usize, frame: usize },
    /// Its positions.
    Positions { seq: usize, frame: usize },
    /// Key times of sequence `seq`, one per frame.
    Times { seq: usize },
    /// The scale values 0, 1, 0 (nine floats).
    Visibility,
}

const VISIBILITY: [f32; 9] = [0., 0., 0., 1., 1., 1., 0., 0., 0.];

fn key_time(set: &FrameSet, frame: usize) -> f32 {
    (frame as f64 / set.fps) as f32
}

impl Part {
    fn bytes(&self, set: &FrameSet, out: &mut Vec<u8>) {
        let mut put = |x: [u8; 4]| out.extend_from_slice(&x);
        match *self {
            Part::Indices { seq, frame } => set.sequences()[seq].frames()[frame]
                .topology()
                .triangles()
                .iter()
                .flatten()
                .for_each(|i| put(i.to_le_bytes())),
            Part::Positions { seq, frame } => {
                set.sequences()[seq].frames()[frame].positions().iter().for_each(|x| put(x.to_le_bytes()))
            }
            Part::Times { seq } => {
                (0..set.sequences()[seq].n_frames()).for_each(|f| put(key_time(set, f).to_le_bytes()))
            }
            Part::Visibility => VISIBILITY.iter().for_each(|x| put(x.to_le_bytes())),
        }
    }
}

/// A frame-set `.glb` laid out from the set's sizes (see the module documentation): its JSON and
/// the parts of its binary chunk, written by [`FrameSetGlbPlan::write`] one view at a time.
pub struct FrameSetGlbPlan<'a> {
    set: &'a FrameSet,
    json: Vec<u8>,
    parts: Vec<(Part, u64)>,
}

fn node(name: String, scale: Option<[f32; 3]>, mesh: Option<json::Index<json::Mesh>>) -> json::Node {
    json::Node { mesh, name: Some(name), scale, ..Default::default() }
}

fn channel(
    sampler: usize,
    node: json::Index<json::Node>,
    input: json::Index<json::Accessor>,
    output: json::Index<json::Accessor>,
) -> (json::animation::Channel, json::animation::Sampler) {
    (
        json::animation::Channel {
            sampler: json::Index::new(sampler as u32),
            target: json::animation::Target {
                extensions: None,
                extras: None,
                node,
                path: Valid(json::animation::Property::Scale),
            },
            extensions: None,
            extras: None,
        },
        json::animation::Sampler {
            extensions: None,
            extras: None,
            input,
            interpolation: Valid(json::animation::Interpolation::Step),
            output,
        },
    )
}

impl<'a> FrameSetGlbPlan<'a> {
    /// Lays out the file; an error when a frame has no vertices (glTF accessors hold at least
    /// one element) or the file would exceed the format's 4 GiB.
    pub fn new(set: &'a FrameSet) -> Result<Self> {
        use json::accessor::{ComponentType, Type};
        use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
        let ix = set.frame_index();
        let mut root = new_root();
        let mut bin = Layout::new();
        let vis = bin.view(&mut root, Part::Visibility, 4 * VISIBILITY.len(), None);
        // Scale values: [0, 1, 0] from offset 0, [1, 0] from 12, [0, 1] and [0] from 0, [1] from 12.
        let scales = |root: &mut json::Root, from_one: bool, count: usize| {
            let mut a = accessor(vis, count, ComponentType::F32, Type::Vec3, None);
            a.byte_offset = from_one.then_some(USize64(12));
            root.push(a)
        };
        // The sequence nodes' one key: hidden (only written when there are other sequences).
        let zero = (set.sequences().len() > 1).then(|| scales(&mut root, false, 1));
        let one = scales(&mut root, true, 1);

        let mut frame_nodes: Vec<Vec<json::Index<json::Node>>> = Vec::new();
        for (s, q) in set.sequences().iter().enumerate() {
            let mut nodes = Vec::with_capacity(q.n_frames());
            for (f, frame) in q.frames().iter().enumerate() {
                let name = ix.label(ix.range(s).start + f);
                if frame.n_vertices() == 0 {
                    return Err(err!(Empty, "frame {name} has no vertices: a glb mesh holds at least one"));
                }
                let nt = frame.n_triangles();
                let pv = bin.view(
                    &mut root,
                    Part::Positions { seq: s, frame: f },
                    12 * frame.n_vertices(),
                    Some(ArrayBuffer),
                );
                let bounds = vec3_bounds(frame.positions());
                let positions =
                    root.push(accessor(pv, frame.n_vertices(), ComponentType::F32, Type::Vec3, Some(bounds)));
                // A frame without triangles (points only) is drawn as points.
                let (indices, mode) = if nt == 0 {
                    (None, json::mesh::Mode::Points)
                } else {
                    let iv = bin.view(&mut root, Part::Indices { seq: s, frame: f }, 12 * nt, Some(ElementArrayBuffer));
                    (
                        Some(root.push(accessor(iv, 3 * nt, ComponentType::U32, Type::Scalar, None))),
                        json::mesh::Mode::Triangles,
                    )
                };
                let mut attributes = std::collections::BTreeMap::new();
                attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
                let mesh = root.push(json::Mesh {
                    extensions: None,
                    extras: None,
                    name: Some(name.clone()),
                    primitives: vec![json::mesh::Primitive {
                        attributes,
                        extensions: None,
                        extras: None,
                        indices,
                        material: None,
                        mode: Valid(mode),
                        targets: None,
                    }],
                    weights: None,
                });
                nodes.push(root.push(node(name, (f > 0).then_some([0.0; 3]), Some(mesh))));
            }
            frame_nodes.push(nodes);
        }
        let seq_nodes: Vec<json::Index<json::Node>> = set
            .sequences()
            .iter()
            .enumerate()
            .map(|(s, q)| {
                let mut n = node(q.name.clone(), (s > 0).then_some([0.0; 3]), None);
                n.children = Some(frame_nodes[s].clone());
                root.push(n)
            })
            .collect();
        let mut top = node(set.name.clone(), None, None);
        top.rotation = up_to_y(set.up_axis);
        top.children = Some(seq_nodes.clone());
        let top = root.push(top);
        root.push(json::Scene { extensions: None, extras: None, name: None, nodes: vec![top] });
        root.scene = Some(json::Index::new(0));

        let mut seq_meta = Vec::new();
        for (s, q) in set.sequences().iter().enumerate() {
            let n = q.n_frames();
            let tv = bin.view(&mut root, Part::Times { seq: s }, 4 * n, None);
            // Keys `first..first + count` of the sequence's times.
            let times = |root: &mut json::Root, first: usize, count: usize| {
                let (t0, t1) = (key_time(set, first), key_time(set, first + count - 1));
                let mut a = accessor(tv, count, ComponentType::F32, Type::Scalar, Some((json!([t0]), json!([t1]))));
                a.byte_offset = (first > 0).then_some(USize64(4 * first as u64));
                root.push(a)
            };
            let start = times(&mut root, 0, 1);
            let mut pairs = Vec::with_capacity(seq_nodes.len() + n);
            for (j, &sn) in seq_nodes.iter().enumerate() {
                pairs.push(channel(
                    pairs.len(),
                    sn,
                    start,
                    if j == s { one } else { zero.expect("several sequences") },
                ));
            }
            for (f, &fnode) in frame_nodes[s].iter().enumerate() {
                let first = f.saturating_sub(1);
                let last = (f + 1).min(n - 1);
                let count = last - first + 1;
                let input = if count == 1 { start } else { times(&mut root, first, count) };
                // The values from 1 when the frame's own key is the first, else from 0.
                let output = scales(&mut root, f == 0, count);
                pairs.push(channel(pairs.len(), fnode, input, output));
            }
            let (channels, samplers) = pairs.into_iter().unzip();
            let labels: Vec<&FrameLabel> = q.labels().iter().collect();
            let meta = json!({
                "sequence": q.name,
                "node": seq_nodes[s].value(),
                "tags": q.tags,
                "fps": set.fps,
                "frames": n,
                "frame_labels": labels,
            });
            root.push(json::Animation {
                extensions: None,
                extras: raw(json!({ "surfcap": meta })),
                channels,
                name: Some(q.name.clone()),
                samplers,
            });
            seq_meta.push(meta);
        }
        root.extras = raw(json!({ "surfcap": {
            "kind": FRAME_SET_KIND,
            "frame_set": set.name,
            "fps": set.fps,
            "up_axis": set.up_axis.as_str(),
            "units": set.units,
            "sequences": seq_meta,
        }}));
        let bin_len = bin.len;
        let json = finish_json(root, bin_len)?;
        let plan = FrameSetGlbPlan { set, json, parts: bin.parts };
        if plan.size() > GLB_MAX_BYTES {
            return Err(err!(
                Unsupported,
                "the glb would be {} bytes ({} frames), above the format's limit of {GLB_MAX_BYTES} bytes (4 GiB: its \
                 lengths are 32-bit); write a .frames folder or --format abc",
                plan.size(),
                set.frame_count()
            ));
        }
        Ok(plan)
    }

    /// Size of the file in bytes.
    pub fn size(&self) -> u64 {
        HEADERS + self.json.len() as u64 + self.parts.iter().map(|(_, n)| n).sum::<u64>()
    }

    /// Writes the file, one buffer view at a time.
    pub fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write_container(w, &self.json, &self.parts, |part, buf| part.bytes(self.set, buf))
    }
}

/// Writes a frame set as one `.glb` (see [`FrameSetGlbPlan`]).
pub fn write_glb_frame_set(w: &mut dyn Write, set: &FrameSet) -> std::io::Result<()> {
    FrameSetGlbPlan::new(set).map_err(std::io::Error::other)?.write(w)
}

/// The root `extras.surfcap` of a glb when it marks a frame set (written by
/// [`write_glb_frame_set`]); `None` for any other glb, and for bytes that are not one.
pub fn frame_set_meta(bytes: &[u8]) -> Option<Value> {
    let bytes = check_container(bytes).ok()?;
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().ok()?) as usize;
    let doc: Value = serde_json::from_slice(bytes.get(20..20 + json_len)?).ok()?;
    let meta = doc.get("extras")?.get("surfcap")?.clone();
    (meta["kind"] == FRAME_SET_KIND).then_some(meta)
}

/// Reads a frame-set `.glb` written by [`write_glb_frame_set`] back into a [`FrameSet`]
/// (named `name`): the sequences from `extras.surfcap`, each frame from its node's mesh.
pub fn parse_glb_frame_set(bytes: &[u8], name: &str) -> Result<FrameSet> {
    match std::panic::catch_unwind(|| decode(bytes, name)) {
        Ok(r) => r,
        Err(_) => Err(err!(Syntax, "malformed glTF: an accessor does not fit its buffer")),
    }
}

fn decode(bytes: &[u8], name: &str) -> Result<FrameSet> {
    let meta = frame_set_meta(bytes)
        .ok_or_else(|| err!(Syntax, "not a surfcap frame-set glb: expected extras.surfcap.kind \"frame-set\""))?;
    let g = open_checked(bytes)?;
    let blob = g.blob.as_deref();
    let buffers = |b: gltf::Buffer| match b.source() {
        gltf::buffer::Source::Bin => blob,
        _ => None,
    };
    let fps = meta["fps"].as_f64().ok_or_else(|| err!(Metadata, "extras.surfcap has no fps"))?;
    let up_axis = meta["up_axis"].as_str().map(UpAxis::parse).transpose()?.unwrap_or(UpAxis::PosY);
    let units = serde_json::from_value::<Units>(meta["units"].clone()).unwrap_or_else(|_| Units::arbitrary());
    let metas = meta["sequences"].as_array().ok_or_else(|| err!(Metadata, "extras.surfcap has no sequences"))?;
    let mut sequences = Vec::with_capacity(metas.len());
    for m in metas {
        let seq = m["sequence"].as_str().ok_or_else(|| err!(Metadata, "a sequence without a name"))?;
        let node = m["node"]
            .as_u64()
            .and_then(|k| g.nodes().nth(k as usize))
            .ok_or_else(|| err!(Metadata, "sequence {seq:?}: extras.surfcap names no node of the file"))?;
        let mut frames = Vec::new();
        for (f, child) in node.children().enumerate() {
            let what = format!("frame {seq}:{f}");
            let mesh = child.mesh().ok_or_else(|| err!(Shape, "{what}: its node has no mesh"))?;
            let prim = mesh.primitives().next().ok_or_else(|| err!(Shape, "{what}: its mesh has no primitive"))?;
            let r = prim.reader(buffers);
            let positions: Vec<f32> = r
                .read_positions()
                .ok_or_else(|| err!(Syntax, "{what}: no readable POSITION accessor"))?
                .flatten()
                .collect();
            let flat: Vec<u32> = match (prim.mode(), r.read_indices()) {
                (gltf::mesh::Mode::Points, _) => Vec::new(),
                (gltf::mesh::Mode::Triangles, Some(ix)) => ix.into_u32().collect(),
                _ => return Err(err!(Unsupported, "{what}: expected an indexed triangle mesh")),
            };
            if !flat.len().is_multiple_of(3) {
                return Err(err!(Shape, "{what}: {} triangle indices, expected a multiple of 3", flat.len()));
            }
            let triangles = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let topology = Topology::new(positions.len() / 3, triangles, None).map_err(|e| e.at_frame(f))?;
            frames.push((topology, positions));
        }
        let mut q = FrameSetSequence::from_frames(seq, frames)?;
        if let Ok(tags) = serde_json::from_value::<Vec<String>>(m["tags"].clone()) {
            q = q.with_tags(tags);
        }
        if let Ok(labels) = serde_json::from_value::<Vec<FrameLabel>>(m["frame_labels"].clone()) {
            q = q.with_labels(labels)?;
        }
        sequences.push(q);
    }
    let name = meta["frame_set"].as_str().unwrap_or(name);
    FrameSet::new(name, sequences, fps, up_axis, units)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two frames of different topology (a triangle, then a quad of two triangles) in one
    /// sequence, and a one-frame sequence.
    fn set() -> FrameSet {
        let tri = (Topology::new(3, vec![[0, 1, 2]], None).unwrap(), vec![0., 0., 0., 1., 0., 0., 0., 1., 0.]);
        let quad = (
            Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], None).unwrap(),
            vec![0., 0., 1., 1., 0., 1., 1., 1., 1., 0., 1., 1.],
        );
        let a = FrameSetSequence::from_frames("a", vec![tri.clone(), quad]).unwrap().with_tags(vec!["walk".into()]);
        let b =
            FrameSetSequence::from_frames("b", vec![tri]).unwrap().with_labels(vec![FrameLabel::Synthetic]).unwrap();
        FrameSet::new("pair", vec![a, b], 25.0, UpAxis::PosZ, Units::metres()).unwrap()
    }

    fn json_chunk(glb: &[u8]) -> Value {
        let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice(&glb[20..20 + n]).unwrap()
    }

    #[test]
    fn every_frame_is_a_node_and_each_animation_steps_through_its_own() {
        let s = set();
        let mut buf = Vec::new();
        write_glb_frame_set(&mut buf, &s).unwrap();
        let doc = json_chunk(&buf);
        // Root + 2 sequence nodes + 3 frame nodes; one mesh per frame, with its own counts.
        assert_eq!(doc["nodes"].as_array().unwrap().len(), 6);
        assert_eq!(doc["meshes"].as_array().unwrap().len(), 3);
        let count = |k: &Value| doc["accessors"][k.as_u64().unwrap() as usize]["count"].as_u64().unwrap();
        let prim = |m: usize| &doc["meshes"][m]["primitives"][0];
        assert_eq!((count(&prim(0)["attributes"]["POSITION"]), count(&prim(0)["indices"])), (3, 3));
        assert_eq!((count(&prim(1)["attributes"]["POSITION"]), count(&prim(1)["indices"])), (4, 6));
        assert_eq!(doc["meshes"][1]["name"], "a:1");
        // Frame 0 of each sequence and the first sequence shown when nothing plays.
        let scale = |n: usize| doc["nodes"][n].get("scale").cloned();
        let by_name = |name: &str| doc["nodes"].as_array().unwrap().iter().position(|n| n["name"] == name).unwrap();
        assert_eq!(scale(by_name("a:0")), None);
        assert_eq!(scale(by_name("a:1")), Some(json!([0.0, 0.0, 0.0])));
        assert_eq!(scale(by_name("b")), Some(json!([0.0, 0.0, 0.0])));
        // Animation "a": both sequence nodes set once, then its two frames, STEP, keys 0-1 each.
        let anims = doc["animations"].as_array().unwrap();
        assert_eq!(anims.len(), 2);
        let a = &anims[0];
        assert_eq!(a["name"], "a");
        assert_eq!(a["channels"].as_array().unwrap().len(), 2 + 2);
        for (c, node, keys) in [(0, "a", 1), (1, "b", 1), (2, "a:0", 2), (3, "a:1", 2)] {
            let ch = &a["channels"][c];
            assert_eq!(ch["target"]["path"], "scale");
            assert_eq!(doc["nodes"][ch["target"]["node"].as_u64().unwrap() as usize]["name"], node);
            let sampler = &a["samplers"][ch["sampler"].as_u64().unwrap() as usize];
            assert_eq!(sampler["interpolation"], "STEP");
            assert_eq!((count(&sampler["input"]), count(&sampler["output"])), (keys, keys));
        }
        assert_eq!(anims[1]["channels"].as_array().unwrap().len(), 2 + 1);
        assert_eq!(doc["extras"]["surfcap"]["kind"], FRAME_SET_KIND);
        assert!(frame_set_meta(&buf).is_some());
    }

    #[test]
    fn reads_back_exactly() {
        let s = set();
        let mut buf = Vec::new();
        write_glb_frame_set(&mut buf, &s).unwrap();
        let back = parse_glb_frame_set(&buf, "ignored").unwrap();
        assert_eq!(back, s);
        // A subject's glb is not one; the subject reader refuses this one by what it is.
        let e = super::super::glb::parse_glb(&buf).unwrap_err();
        assert!(e.message.contains("frame set"), "{e}");
    }

    #[test]
    fn damaged_files_are_errors_not_crashes() {
        let mut buf = Vec::new();
        write_glb_frame_set(&mut buf, &set()).unwrap();
        let n = u32::from_le_bytes(buf[12..16].try_into().unwrap()) as usize;
        for cut in [12, 40, 20 + n + 8, buf.len() - 8] {
            let mut short = buf[..cut].to_vec();
            if short.len() >= 12 {
                let len = short.len() as u32;
                short[8..12].copy_from_slice(&len.to_le_bytes());
            }
            if let Err(e) = parse_glb_frame_set(&short, "x") {
                assert!(!e.message.contains("malformed"), "cut at {cut}: a panic was caught: {e}");
            }
        }
    }
}

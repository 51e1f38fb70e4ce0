//! A frame set (every frame its own vertices and triangles, Huang et al. 2009's input and the
//! surface motion graph's output) as a glTF 2.0 binary that plays in three.js and Blender.
//!
//! Morph targets, which [`crate::glb`] uses for a subject, need one vertex count and one index
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
//! back exactly (positions and triangles bit for bit; the correspondence of `remesh-frames` is
//! not kept).
//!
//! Texture coordinates: a frame with a UV atlas gets `TEXCOORD_0`, its vertices split along the
//! atlas's seams ([`surfcap_mesh::UvVertices`]: the frame's own vertices first, in order, then the
//! seam copies); the mesh's `extras.surfcap` holds `vertices` (the frame's own count) and
//! `copies`, an accessor of the vertex each copy repeats (read by surfcap only, so the
//! validator lists it as unused, an info), from which the reader restores the frame's
//! vertices and triangles exactly. glTF puts UV (0, 0) at the image's top-left corner and OBJ
//! (and surfcap) at its bottom-left: `v` is written as `1 - v` and read back the same way
//! (exact for `v >= 0.5`, within 2^-25 below).
//!
//! A texture per frame (thesis Fig. 7.1; [`write_glb_frame_set_textured`]): core glTF cannot
//! switch a material's texture over time, but here every frame is its own mesh, so every frame
//! gets the material of its texture. Each distinct texture of the [`FrameTextures`] that a frame
//! uses is one PNG image embedded in the binary chunk (a buffer view padded to 4 bytes), one
//! texture (one shared sampler: linear, mipmapped, clamped) and one material (`baseColorTexture`,
//! metallic 0, roughness 1); frames that share a texture share its material. The root's
//! `extras.surfcap.textures` then counts them.

use std::io::Write;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use serde_json::{Value, json};

use crate::glb::{
    GLB_MAX_BYTES, HEADERS, Layout, accessor, check_container, finish_json, new_root, open_checked, raw, up_to_y,
    vec3_bounds, write_container,
};
use surfcap_mesh::error::{Result, err};
use surfcap_mesh::frame_set::{Frame, FrameSet, FrameSetSequence};
use surfcap_mesh::frame_textures::FrameTextures;
use surfcap_mesh::subject::{FrameLabel, Subject, Units, UpAxis};
use surfcap_mesh::topology::{Topology, UvAtlas};
use surfcap_mesh::uv_vertices::UvVertices;

/// The value of `extras.surfcap.kind` that marks a frame-set glb.
pub const FRAME_SET_KIND: &str = "frame-set";

/// One buffer view's data, produced from the frame set while the binary chunk is written.
enum Part {
    /// The triangles of frame `frame` of sequence `seq` (over its split vertices when it has UVs).
    Indices { seq: usize, frame: usize },
    /// Its positions (split likewise).
    Positions { seq: usize, frame: usize },
    /// Its texture coordinates, one per split vertex, `v` flipped to glTF's convention.
    Uvs { seq: usize, frame: usize },
    /// The vertex each seam copy repeats.
    Copies { seq: usize, frame: usize },
    /// Texture `k`'s PNG file, padded with zeros to a multiple of 4 bytes.
    Image { k: usize },
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
    fn bytes(&self, set: &FrameSet, textures: Option<&FrameTextures>, out: &mut Vec<u8>) {
        let frame_of = |seq: usize, frame: usize| &set.sequences()[seq].frames()[frame];
        let split = |fr: &Frame| UvVertices::new(fr.topology());
        let mut put = |x: [u8; 4]| out.extend_from_slice(&x);
        match *self {
            Part::Indices { seq, frame } => {
                let fr = frame_of(seq, frame);
                match split(fr) {
                    Some(sp) => sp.triangles.iter().flatten().for_each(|i| put(i.to_le_bytes())),
                    None => fr.topology().triangles().iter().flatten().for_each(|i| put(i.to_le_bytes())),
                }
            }
            Part::Positions { seq, frame } => {
                let fr = frame_of(seq, frame);
                match split(fr) {
                    Some(sp) => sp.positions(fr.positions()).iter().for_each(|x| put(x.to_le_bytes())),
                    None => fr.positions().iter().for_each(|x| put(x.to_le_bytes())),
                }
            }
            Part::Uvs { seq, frame } => {
                let fr = frame_of(seq, frame);
                let (sp, atlas) = (split(fr).expect("a frame with UVs"), fr.topology().uv().expect("UVs"));
                for [u, v] in sp.coords(atlas) {
                    put(u.to_le_bytes());
                    put((1.0 - v).to_le_bytes());
                }
            }
            Part::Copies { seq, frame } => {
                split(frame_of(seq, frame)).expect("a frame with UVs").copies.iter().for_each(|i| put(i.to_le_bytes()))
            }
            Part::Image { k } => {
                let png = &textures.expect("a textured plan").images()[k];
                out.extend_from_slice(png);
                out.resize(out.len() + (4 - png.len() % 4) % 4, 0);
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
    textures: Option<&'a FrameTextures>,
    json: Vec<u8>,
    parts: Vec<(Part, u64)>,
}

/// The images, textures and materials of the textures that some frame uses (see the module
/// documentation): the material of each of `textures`'s images, `None` for one no frame uses.
fn texture_materials(
    root: &mut json::Root,
    bin: &mut Layout<Part>,
    textures: &FrameTextures,
) -> Vec<Option<json::Index<json::Material>>> {
    use json::texture::{MagFilter, MinFilter, WrappingMode};
    let mut used = vec![false; textures.images().len()];
    textures.frames().iter().flatten().for_each(|&t| used[t] = true);
    if !used.contains(&true) {
        return vec![None; used.len()];
    }
    let sampler = root.push(json::texture::Sampler {
        mag_filter: Some(Valid(MagFilter::Linear)),
        min_filter: Some(Valid(MinFilter::LinearMipmapLinear)),
        name: None,
        wrap_s: Valid(WrappingMode::ClampToEdge),
        wrap_t: Valid(WrappingMode::ClampToEdge),
        extensions: None,
        extras: None,
    });
    let mut out = Vec::with_capacity(used.len());
    for (k, png) in textures.images().iter().enumerate() {
        if !used[k] {
            out.push(None);
            continue;
        }
        let view = bin.view_padded(root, Part::Image { k }, png.len());
        let image = root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(format!("texture {k}")),
            uri: None,
            extensions: None,
            extras: None,
        });
        let texture = root.push(json::Texture {
            name: Some(format!("texture {k}")),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        });
        let mut m = json::Material { name: Some(format!("texture {k}")), ..Default::default() };
        m.pbr_metallic_roughness.base_color_texture =
            Some(json::texture::Info { index: texture, tex_coord: 0, extensions: None, extras: None });
        m.pbr_metallic_roughness.metallic_factor = json::material::StrengthFactor(0.0);
        m.pbr_metallic_roughness.roughness_factor = json::material::StrengthFactor(1.0);
        out.push(Some(root.push(m)));
    }
    out
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
        Self::build(set, None)
    }

    /// Lays out the file with a texture per frame (see the module documentation); an error too
    /// when `textures` does not have one index per frame or a textured frame has no UVs.
    pub fn textured(set: &'a FrameSet, textures: &'a FrameTextures) -> Result<Self> {
        textures.check_frames(set.frame_index())?;
        Self::build(set, Some(textures))
    }

    fn build(set: &'a FrameSet, textures: Option<&'a FrameTextures>) -> Result<Self> {
        use json::accessor::{ComponentType, Type};
        use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
        let ix = set.frame_index();
        let mut root = new_root();
        let mut bin = Layout::new();
        let materials = textures.map(|t| texture_materials(&mut root, &mut bin, t)).unwrap_or_default();
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
                let split = UvVertices::new(frame.topology());
                let nv = split.as_ref().map_or(frame.n_vertices(), UvVertices::len);
                let pv = bin.view(&mut root, Part::Positions { seq: s, frame: f }, 12 * nv, Some(ArrayBuffer));
                // The seam copies repeat vertices: the bounds are the frame's own.
                let bounds = vec3_bounds(frame.positions());
                let positions = root.push(accessor(pv, nv, ComponentType::F32, Type::Vec3, Some(bounds)));
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
                let mut extras = None;
                if let Some(sp) = &split {
                    let uv = bin.view(&mut root, Part::Uvs { seq: s, frame: f }, 8 * nv, Some(ArrayBuffer));
                    let uv = root.push(accessor(uv, nv, ComponentType::F32, Type::Vec2, None));
                    attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uv);
                    let copies = (!sp.copies.is_empty()).then(|| {
                        let cv = bin.view(&mut root, Part::Copies { seq: s, frame: f }, 4 * sp.copies.len(), None);
                        root.push(accessor(cv, sp.copies.len(), ComponentType::U32, Type::Scalar, None)).value()
                    });
                    extras = raw(json!({ "surfcap": { "vertices": sp.n_vertices, "copies": copies } }));
                }
                let material = match textures {
                    Some(t) => {
                        if split.is_none() {
                            return Err(err!(
                                Shape,
                                "frame {name} has a texture but no texture coordinates: expected a UV atlas on every \
                                 textured frame"
                            ));
                        }
                        materials[t.frames()[s][f]]
                    }
                    None => None,
                };
                let mesh = root.push(json::Mesh {
                    extensions: None,
                    extras,
                    name: Some(name.clone()),
                    primitives: vec![json::mesh::Primitive {
                        attributes,
                        extensions: None,
                        extras: None,
                        indices,
                        material,
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
        if textures.is_some() {
            // How many textures the frames show, so a reader knows before decoding the frames.
            let n = materials.iter().flatten().count();
            if let Some(x) = root.extras.take() {
                let mut v: Value = serde_json::from_str(x.get()).expect("written above");
                v["surfcap"]["textures"] = n.into();
                root.extras = raw(v);
            }
        }
        let bin_len = bin.len;
        let json = finish_json(root, bin_len)?;
        let plan = FrameSetGlbPlan { set, textures, json, parts: bin.parts };
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
        write_container(w, &self.json, &self.parts, |part, buf| part.bytes(self.set, self.textures, buf))
    }
}

/// Writes a frame set as one `.glb` (see [`FrameSetGlbPlan`]).
pub fn write_glb_frame_set(w: &mut dyn Write, set: &FrameSet) -> std::io::Result<()> {
    FrameSetGlbPlan::new(set).map_err(std::io::Error::other)?.write(w)
}

/// Writes a frame set as one `.glb` in which every frame shows its texture (see the module
/// documentation and [`FrameSetGlbPlan::textured`]).
pub fn write_glb_frame_set_textured(
    w: &mut dyn Write,
    set: &FrameSet,
    textures: &FrameTextures,
) -> std::io::Result<()> {
    FrameSetGlbPlan::textured(set, textures).map_err(std::io::Error::other)?.write(w)
}

/// Writes a subject's animation (one topology, with a UV atlas) as one `.glb` in which every
/// frame shows its texture. Morph targets, which [`crate::glb`] writes for a subject, animate
/// one mesh with one material, and core glTF cannot switch a material's texture over time, so
/// the subject is written as a frame set ([`FrameSet::from_subject`]): a mesh per frame, each
/// with the material of its texture.
///
/// Size: a frame costs its whole mesh, 12 bytes per (split) vertex of positions + 8 of UVs + 12
/// per triangle + 4 per seam copy, against 12 bytes per vertex for a morph target; for the head
/// scan (9,279 vertices, 17,684 triangles, no seam copies: its OBJ repeats seam vertices
/// already) 398 kB a frame instead of 111 kB, before the textures, which then dominate (a PNG
/// of the scan's 1024 x 1024 colour map is about 1 MB; at 128 x 128, 16-20 kB).
pub fn write_glb_subject_textured(
    w: &mut dyn Write,
    subject: &Subject,
    textures: &FrameTextures,
) -> std::io::Result<()> {
    let set = FrameSet::from_subject(subject);
    write_glb_frame_set_textured(w, &set, textures)
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
/// (named `name`): the sequences from `extras.surfcap`, each frame from its node's mesh, with
/// its UV atlas when it has `TEXCOORD_0` (one coordinate per split vertex, `v` flipped back).
pub fn parse_glb_frame_set(bytes: &[u8], name: &str) -> Result<FrameSet> {
    parse_glb_frame_set_textured(bytes, name).map(|(set, _)| set)
}

/// [`parse_glb_frame_set`] with the frames' textures: `Some` when the frames' materials have a
/// base colour texture (every frame must then have one), each distinct embedded image once, in
/// the order of the file's images, with the index of each frame's.
pub fn parse_glb_frame_set_textured(bytes: &[u8], name: &str) -> Result<(FrameSet, Option<FrameTextures>)> {
    match std::panic::catch_unwind(|| decode(bytes, name)) {
        Ok(r) => r,
        Err(_) => Err(err!(Syntax, "malformed glTF: an accessor does not fit its buffer")),
    }
}

/// The glTF image index of the base colour texture of a primitive's material, if any.
fn texture_image(prim: &gltf::Primitive) -> Option<usize> {
    prim.material().pbr_metallic_roughness().base_color_texture().map(|i| i.texture().source().index())
}

/// The bytes of embedded image `k` (a PNG in a buffer view of the binary chunk).
fn image_bytes<'b>(g: &gltf::Gltf, blob: &'b [u8], k: usize) -> Result<&'b [u8]> {
    let im = &g.document.as_json().images[k];
    let view = im
        .buffer_view
        .and_then(|v| g.document.views().nth(v.value()))
        .ok_or_else(|| err!(Unsupported, "image {k} is not embedded in the binary chunk: expected a buffer view"))?;
    if !matches!(view.buffer().source(), gltf::buffer::Source::Bin) {
        return Err(err!(Unsupported, "image {k} refers to an external buffer: expected data inside the .glb"));
    }
    let png = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| blob.get(view.offset()..end))
        .ok_or_else(|| err!(Truncated, "image {k} does not fit in the binary chunk"))?;
    surfcap_mesh::frame_textures::png_size(png, &format!("image {k}"))?;
    Ok(png)
}

/// A frame's vertices and triangles from its split ones (see the module documentation): the
/// first `n` split vertices are the frame's own, each later one repeats `copies[j]`.
fn unsplit(what: &str, mesh: &gltf::Mesh, count: usize, g: &gltf::Gltf, blob: &[u8]) -> Result<(usize, Vec<u32>)> {
    let Some(m) = crate::glb::extras_surfcap(mesh.extras()) else { return Ok((count, Vec::new())) };
    let n =
        m["vertices"].as_u64().map(|n| n as usize).filter(|&n| n > 0 && n <= count).ok_or_else(|| {
            err!(Metadata, "{what}: extras.surfcap.vertices is not a vertex count between 1 and {count}")
        })?;
    let copies: Vec<u32> = match m["copies"].as_u64() {
        None => Vec::new(),
        Some(a) => {
            let acc = g
                .accessors()
                .nth(a as usize)
                .ok_or_else(|| err!(Metadata, "{what}: extras.surfcap.copies names no accessor"))?;
            if acc.data_type() != gltf::accessor::DataType::U32
                || acc.dimensions() != gltf::accessor::Dimensions::Scalar
            {
                return Err(err!(DType, "{what}: the seam copies' accessor is not unsigned 32-bit scalars"));
            }
            let buffers = |b: gltf::Buffer| match b.source() {
                gltf::buffer::Source::Bin => Some(blob),
                _ => None,
            };
            gltf::accessor::Iter::<u32>::new(acc, buffers)
                .ok_or_else(|| err!(Syntax, "{what}: the seam copies' accessor cannot be read"))?
                .collect()
        }
    };
    if copies.len() != count - n {
        return Err(err!(
            Shape,
            "{what}: {} seam copies for {count} vertices of which {n} are the frame's own",
            copies.len()
        ));
    }
    if let Some(&c) = copies.iter().find(|&&c| c as usize >= n) {
        return Err(err!(IndexOutOfRange, "{what}: a seam copy of vertex {c}, expected below {n}"));
    }
    Ok((n, copies))
}

fn decode(bytes: &[u8], name: &str) -> Result<(FrameSet, Option<FrameTextures>)> {
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
    // Per sequence, per frame: the glTF image of the frame's material, if any.
    let mut frame_images: Vec<Vec<Option<usize>>> = Vec::with_capacity(metas.len());
    for m in metas {
        let seq = m["sequence"].as_str().ok_or_else(|| err!(Metadata, "a sequence without a name"))?;
        let node = m["node"]
            .as_u64()
            .and_then(|k| g.nodes().nth(k as usize))
            .ok_or_else(|| err!(Metadata, "sequence {seq:?}: extras.surfcap names no node of the file"))?;
        let mut frames = Vec::new();
        let mut images = Vec::new();
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
            let count = positions.len() / 3;
            if let Some(&i) = flat.iter().find(|&&i| i as usize >= count) {
                return Err(err!(IndexOutOfRange, "{what}: triangle index {i}, expected below {count}"));
            }
            let (n, copies) = unsplit(&what, &mesh, count, &g, blob.unwrap_or(&[]))?;
            let source = |k: u32| if (k as usize) < n { k } else { copies[k as usize - n] };
            let triangles = flat.chunks_exact(3).map(|c| [source(c[0]), source(c[1]), source(c[2])]).collect();
            let uv = match r.read_tex_coords(0) {
                None => None,
                Some(t) => {
                    let coords: Vec<[f32; 2]> = t.into_f32().map(|[u, v]| [u, 1.0 - v]).collect();
                    if coords.len() != count {
                        return Err(err!(Shape, "{what}: {} texture coordinates for {count} vertices", coords.len()));
                    }
                    Some(UvAtlas { coords, corners: flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() })
                }
            };
            let topology = Topology::new(n, triangles, uv).map_err(|e| e.at_frame(f))?;
            let mut positions = positions;
            positions.truncate(3 * n);
            frames.push((topology, positions));
            images.push(texture_image(&prim));
        }
        frame_images.push(images);
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
    let set = FrameSet::new(name, sequences, fps, up_axis, units)?;
    let textures = frame_textures(&g, blob.unwrap_or(&[]), &set, &frame_images)?;
    Ok((set, textures))
}

/// The frames' textures from the image of each frame's material: `None` when no frame has one.
fn frame_textures(
    g: &gltf::Gltf,
    blob: &[u8],
    set: &FrameSet,
    frame_images: &[Vec<Option<usize>>],
) -> Result<Option<FrameTextures>> {
    let used: std::collections::BTreeSet<usize> = frame_images.iter().flatten().flatten().copied().collect();
    if used.is_empty() {
        return Ok(None);
    }
    let ours: std::collections::BTreeMap<usize, usize> = used.iter().enumerate().map(|(i, &k)| (k, i)).collect();
    let images = used.iter().map(|&k| image_bytes(g, blob, k).map(<[u8]>::to_vec)).collect::<Result<Vec<_>>>()?;
    let ix = set.frame_index();
    let mut frames = Vec::with_capacity(frame_images.len());
    for (s, q) in frame_images.iter().enumerate() {
        let mut out = Vec::with_capacity(q.len());
        for (f, im) in q.iter().enumerate() {
            let im = im.ok_or_else(|| {
                err!(
                    Shape,
                    "frame {} has no texture while other frames have one: expected a texture on every frame",
                    ix.label(ix.range(s).start + f)
                )
            })?;
            out.push(ours[&im]);
        }
        frames.push(out);
    }
    FrameTextures::new(images, frames).map(Some)
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
        let e = crate::glb::parse_glb(&buf).unwrap_err();
        assert!(e.message.contains("frame set"), "{e}");
    }

    /// Three frames of a quad whose atlas has a seam at vertex 2 (two coordinates), moving;
    /// then a sequence of one frame: a triangle with its own atlas.
    fn uv_set() -> FrameSet {
        let uv = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.3, 0.7], [0.1, 0.9]],
            corners: vec![[0, 1, 2], [0, 3, 4]],
        };
        let quad = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(uv)).unwrap();
        let p = |dz: f32| vec![0., 0., dz, 1., 0., dz, 1., 1., dz, 0., 1., dz];
        let a =
            FrameSetSequence::from_frames("a", (0..3).map(|f| (quad.clone(), p(f as f32 * 0.1))).collect()).unwrap();
        let tri_uv = UvAtlas { coords: vec![[0.2, 0.2], [0.8, 0.2], [0.5, 0.6]], corners: vec![[0, 1, 2]] };
        let tri = Topology::new(3, vec![[0, 1, 2]], Some(tri_uv)).unwrap();
        let b = FrameSetSequence::from_frames("b", vec![(tri, vec![0., 0., 0., 1., 0., 0., 0., 1., 0.])]).unwrap();
        FrameSet::new("uv", vec![a, b], 25.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    /// Red, blue, then red again for sequence a; green for b.
    fn uv_textures() -> FrameTextures {
        use surfcap_testkit::png_1x1;
        let (red, blue, green) = (png_1x1([255, 0, 0]), png_1x1([0, 0, 255]), png_1x1([0, 255, 0]));
        FrameTextures::one_per_frame(vec![vec![red.clone(), blue, red], vec![green]]).unwrap()
    }

    /// Each corner's texture coordinate, frame by frame.
    fn corner_uvs(set: &FrameSet) -> Vec<Vec<[f32; 2]>> {
        set.sequences()
            .iter()
            .flat_map(|q| q.frames())
            .map(|fr| {
                let uv = fr.topology().uv().unwrap();
                uv.corners.iter().flatten().map(|&c| uv.coords[c as usize]).collect()
            })
            .collect()
    }

    #[test]
    fn textured_frames_round_trip_with_uvs_and_shared_materials() {
        let (s, t) = (uv_set(), uv_textures());
        let mut buf = Vec::new();
        write_glb_frame_set_textured(&mut buf, &s, &t).unwrap();
        let doc = json_chunk(&buf);
        // Three distinct textures: three images, textures and materials; a:0 and a:2 share one.
        for k in ["images", "textures", "materials"] {
            assert_eq!(doc[k].as_array().unwrap().len(), 3, "{k}");
        }
        let material = |m: usize| doc["meshes"][m]["primitives"][0]["material"].as_u64().unwrap();
        assert_eq!((material(0), material(1), material(2), material(3)), (0, 1, 0, 2));
        // The seam vertex is copied once: 5 vertices with UVs, one copy of vertex 2.
        let prim = &doc["meshes"][0]["primitives"][0];
        let count = |k: &Value| doc["accessors"][k.as_u64().unwrap() as usize]["count"].as_u64().unwrap();
        assert_eq!(count(&prim["attributes"]["TEXCOORD_0"]), 5);
        assert_eq!(doc["meshes"][0]["extras"]["surfcap"]["vertices"], 4);

        // Valid glTF with the seam copies' accessor (the head scan in tests/ has no seams).
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("uv.glb");
        std::fs::write(&file, &buf).unwrap();
        surfcap_testkit::validate_glb(std::slice::from_ref(&file));

        let (back, bt) = parse_glb_frame_set_textured(&buf, "x").unwrap();
        assert_eq!(bt.as_ref(), Some(&t));
        for (x, y) in
            back.sequences().iter().flat_map(|q| q.frames()).zip(s.sequences().iter().flat_map(|q| q.frames()))
        {
            assert_eq!(x.positions(), y.positions());
            assert_eq!(x.topology().triangles(), y.topology().triangles());
            assert_eq!(x.topology().n_vertices(), y.topology().n_vertices());
        }
        // v -> 1 - v -> 1 - (1 - v): exact above 0.5, within 2^-25 below.
        for (a, b) in corner_uvs(&back).iter().flatten().zip(corner_uvs(&s).iter().flatten()) {
            assert!((a[0] - b[0]).abs() == 0.0 && (a[1] - b[1]).abs() <= 3e-8, "{a:?} vs {b:?}");
        }
        // Written again from what was read, the file is the same: the split is stable.
        let mut again = Vec::new();
        write_glb_frame_set_textured(&mut again, &back, bt.as_ref().unwrap()).unwrap();
        let (back2, _) = parse_glb_frame_set_textured(&again, "x").unwrap();
        assert_eq!(back2, back);
        // Without textures the UVs are still written, and no material.
        let mut plain = Vec::new();
        write_glb_frame_set(&mut plain, &s).unwrap();
        assert!(json_chunk(&plain).get("materials").is_none());
        let (p, pt) = parse_glb_frame_set_textured(&plain, "x").unwrap();
        assert!(pt.is_none());
        assert_eq!(corner_uvs(&p), corner_uvs(&back));
    }

    #[test]
    fn a_subject_with_textures_is_written_as_a_mesh_per_frame() {
        let s = uv_set();
        let q = &s.sequences()[0];
        let positions: Vec<f32> = q.frames().iter().flat_map(|f| f.positions().iter().copied()).collect();
        let seq = surfcap_mesh::subject::Sequence::new("a", 4, positions).unwrap();
        let subject =
            Subject::new("quad", q.frames()[0].topology().clone(), vec![seq], 25.0, UpAxis::PosY, Units::metres())
                .unwrap();
        let t = FrameTextures::new(uv_textures().images()[..2].to_vec(), vec![vec![0, 1, 1]]).unwrap();
        let mut buf = Vec::new();
        write_glb_subject_textured(&mut buf, &subject, &t).unwrap();
        let (back, bt) = parse_glb_frame_set_textured(&buf, "x").unwrap();
        assert_eq!(back.frame_count(), 3);
        assert_eq!(bt.unwrap().frames(), &[vec![0, 1, 1]]);
        assert_eq!(json_chunk(&buf)["materials"].as_array().unwrap().len(), 2);
    }

    #[test]
    fn textures_that_do_not_fit_the_frames_are_refused_by_name() {
        let t = uv_textures();
        // A frame set without UVs cannot show a texture.
        let e = FrameSetGlbPlan::textured(
            &set(),
            &FrameTextures::new(t.images().to_vec(), vec![vec![0, 1], vec![2]]).unwrap(),
        )
        .err()
        .unwrap();
        assert!(e.message.contains("frame a:0 has a texture but no texture coordinates"), "{e}");
        let e = FrameSetGlbPlan::textured(
            &uv_set(),
            &FrameTextures::new(t.images().to_vec(), vec![vec![0, 1], vec![2]]).unwrap(),
        )
        .err()
        .unwrap();
        assert!(e.message.contains("sequence a: 2 texture indices, expected one per frame (3)"), "{e}");
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

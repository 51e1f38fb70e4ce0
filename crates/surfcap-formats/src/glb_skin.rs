//! glTF 2.0 binary (`.glb`) holding a skinned rig: a mesh with linear blend skinning that
//! engines (Unity, Unreal, Godot, three.js) play as an ordinary skinned character, instead of a
//! morph target per frame.
//!
//! Layout: one mesh (the rest positions, triangles, `JOINTS_0`/`WEIGHTS_0`, and `JOINTS_1`/
//! `WEIGHTS_1` when a vertex has more than four bones) on a node at the scene's root with the
//! skin; one joint node per bone, children of a root node that carries the rotation bringing
//! the subject's up axis onto glTF's +Y (as the morph-target glb does), so the mesh keeps the
//! subject's own coordinates. A bone's bind pose is a translation to its rest centre `c_j`, so
//! its inverse bind matrix is a translation by `-c_j`; one animation per sequence drives every
//! joint's translation and rotation (LINEAR, one key per frame at `frame / fps`).
//! The subject's metadata and each animation's sequence, tags and fps are in `extras.surfcap`.

use std::collections::BTreeMap;
use std::io::Write;

use gltf_json as json;
use json::validation::Checked::Valid;
use serde_json::json;

use super::glb::{Layout, accessor, finish_json, new_root, raw, up_to_y, vec3_bounds, write_container};
use surfcap_mesh::error::{Result, err};
use surfcap_mesh::subject::{Units, UpAxis};
use surfcap_mesh::topology::Topology;

/// One sequence's joint animation: per frame, per joint, its local rotation (unit quaternion
/// x, y, z, w) and translation (under the up-axis root node).
#[derive(Debug, Clone)]
pub struct JointSequence {
    pub name: String,
    pub tags: Vec<String>,
    pub n_frames: usize,
    /// `[frame][joint]` quaternions (x, y, z, w)
    pub rotations: Vec<[f32; 4]>,
    /// `[frame][joint]` translations
    pub translations: Vec<[f32; 3]>,
}

/// A skinned rig to write: mesh, weights, joints and their animations.
#[derive(Debug, Clone)]
pub struct SkinnedGlb<'a> {
    pub name: String,
    pub topology: &'a Topology,
    /// Rest (bind) positions `[vertex][3]`.
    pub rest: Vec<f32>,
    /// Joints per vertex in `joints`/`weights` (4 or 8); unused slots have weight 0.
    pub slots: usize,
    /// `[vertex][slots]` joint indices
    pub joints: Vec<u16>,
    /// `[vertex][slots]` weights, summing to one per vertex
    pub weights: Vec<f32>,
    /// Each joint's bind position (its rest centre).
    pub bind_centres: Vec<[f32; 3]>,
    pub sequences: Vec<JointSequence>,
    pub fps: f64,
    pub up_axis: UpAxis,
    pub units: Units,
    /// Anything else for the root's `extras.surfcap` (the rig's options and errors).
    pub extras: serde_json::Value,
}

impl SkinnedGlb<'_> {
    fn check(&self) -> Result<()> {
        let nv = self.topology.n_vertices();
        let nj = self.bind_centres.len();
        if !(self.slots == 4 || self.slots == 8) {
            return Err(err!(Unsupported, "a glTF skin holds 4 or 8 joints per vertex, not {}", self.slots));
        }
        if self.rest.len() != 3 * nv || self.joints.len() != self.slots * nv || self.weights.len() != self.slots * nv {
            return Err(err!(Unsupported, "skinned glb: rest, joints or weights do not match {nv} vertices"));
        }
        if nj == 0 || nj > usize::from(u16::MAX) {
            return Err(err!(Unsupported, "skinned glb: {nj} joints; expected 1 to {}", u16::MAX));
        }
        if let Some(&j) = self.joints.iter().find(|&&j| usize::from(j) >= nj) {
            return Err(err!(Unsupported, "skinned glb: joint index {j} but only {nj} joints"));
        }
        for s in &self.sequences {
            if s.n_frames == 0 || s.rotations.len() != s.n_frames * nj || s.translations.len() != s.n_frames * nj {
                return Err(err!(
                    Unsupported,
                    "skinned glb: sequence {:?}'s animation does not match {nj} joints",
                    s.name
                ));
            }
        }
        Ok(())
    }
}

fn f32_bytes(v: impl IntoIterator<Item = f32>) -> Vec<u8> {
    v.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// The file's bytes.
pub fn skinned_glb_bytes(g: &SkinnedGlb) -> Result<Vec<u8>> {
    use json::accessor::{ComponentType, Type};
    use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
    g.check()?;
    let nv = g.topology.n_vertices();
    let nj = g.bind_centres.len();
    let mut root = new_root();
    let mut bin: Layout<Vec<u8>> = Layout::new();
    let mut view = |root: &mut json::Root, bytes: Vec<u8>, target: Option<json::buffer::Target>| {
        let n = bytes.len();
        let padded = n.div_ceil(4) * 4;
        let mut b = bytes;
        b.resize(padded, 0);
        if padded == n { bin.view(root, b, n, target) } else { bin.view_padded(root, b, n) }
    };

    let tri: Vec<u8> = g.topology.triangles().iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    let iv = view(&mut root, tri, Some(ElementArrayBuffer));
    let indices = root.push(accessor(iv, g.topology.n_triangles() * 3, ComponentType::U32, Type::Scalar, None));
    let pv = view(&mut root, f32_bytes(g.rest.iter().copied()), Some(ArrayBuffer));
    let positions = root.push(accessor(pv, nv, ComponentType::F32, Type::Vec3, Some(vec3_bounds(&g.rest))));
    let mut attributes = BTreeMap::new();
    attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
    let wide = nj > 256;
    for set in 0..g.slots / 4 {
        let pick = |v: usize| (0..4).map(move |k| v * g.slots + set * 4 + k);
        let jb: Vec<u8> = if wide {
            (0..nv).flat_map(pick).flat_map(|x| g.joints[x].to_le_bytes()).collect()
        } else {
            (0..nv).flat_map(pick).map(|x| g.joints[x] as u8).collect()
        };
        let jv = view(&mut root, jb, Some(ArrayBuffer));
        let comp = if wide { ComponentType::U16 } else { ComponentType::U8 };
        let ja = root.push(accessor(jv, nv, comp, Type::Vec4, None));
        let wv = view(&mut root, f32_bytes((0..nv).flat_map(pick).map(|x| g.weights[x])), Some(ArrayBuffer));
        let wa = root.push(accessor(wv, nv, ComponentType::F32, Type::Vec4, None));
        attributes.insert(Valid(json::mesh::Semantic::Joints(set as u32)), ja);
        attributes.insert(Valid(json::mesh::Semantic::Weights(set as u32)), wa);
    }
    let mesh = root.push(json::Mesh {
        extensions: None,
        extras: None,
        name: Some(g.name.clone()),
        primitives: vec![json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        }],
        weights: None,
    });

    // Joints (nodes 0..nj) under the up-axis root (node nj), then the skinned mesh's node.
    let first_seq = g.sequences.first();
    let joint_nodes: Vec<json::Index<json::Node>> = (0..nj)
        .map(|j| {
            // The joint's pose at the first key, so that the scene is right before animations play.
            let (r, t) =
                first_seq.map_or(([0.0, 0.0, 0.0, 1.0], g.bind_centres[j]), |s| (s.rotations[j], s.translations[j]));
            root.push(json::Node {
                name: Some(format!("bone{j}")),
                rotation: Some(json::scene::UnitQuaternion(r)),
                translation: Some(t),
                ..Default::default()
            })
        })
        .collect();
    let rig_root = root.push(json::Node {
        name: Some(format!("{}_rig", g.name)),
        rotation: up_to_y(g.up_axis),
        children: Some(joint_nodes.clone()),
        ..Default::default()
    });
    let ibm: Vec<f32> = g
        .bind_centres
        .iter()
        .flat_map(|c| [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -c[0], -c[1], -c[2], 1.0])
        .collect();
    let bv = view(&mut root, f32_bytes(ibm), None);
    let ibm_acc = root.push(accessor(bv, nj, ComponentType::F32, Type::Mat4, None));
    let skin = root.push(json::Skin {
        extensions: None,
        extras: None,
        inverse_bind_matrices: Some(ibm_acc),
        joints: joint_nodes.clone(),
        name: Some(g.name.clone()),
        skeleton: Some(rig_root),
    });
    let mesh_node =
        root.push(json::Node { mesh: Some(mesh), skin: Some(skin), name: Some(g.name.clone()), ..Default::default() });
    root.push(json::Scene { extensions: None, extras: None, name: None, nodes: vec![rig_root, mesh_node] });
    root.scene = Some(json::Index::new(0));

    let mut seq_meta = Vec::new();
    for s in &g.sequences {
        let n = s.n_frames;
        let times: Vec<f32> = (0..n).map(|f| (f as f64 / g.fps) as f32).collect();
        let (t0, t1) = (times[0], times[n - 1]);
        let tv = view(&mut root, f32_bytes(times), None);
        let t_acc = root.push(accessor(tv, n, ComponentType::F32, Type::Scalar, Some((json!([t0]), json!([t1])))));
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for (j, &node) in joint_nodes.iter().enumerate() {
            let tr = f32_bytes((0..n).flat_map(|f| s.translations[f * nj + j]));
            let trv = view(&mut root, tr, None);
            let tr_acc = root.push(accessor(trv, n, ComponentType::F32, Type::Vec3, None));
            let rot = f32_bytes((0..n).flat_map(|f| s.rotations[f * nj + j]));
            let rov = view(&mut root, rot, None);
            let ro_acc = root.push(accessor(rov, n, ComponentType::F32, Type::Vec4, None));
            for (out, path) in
                [(tr_acc, json::animation::Property::Translation), (ro_acc, json::animation::Property::Rotation)]
            {
                channels.push(json::animation::Channel {
                    sampler: json::Index::new(samplers.len() as u32),
                    target: json::animation::Target { extensions: None, extras: None, node, path: Valid(path) },
                    extensions: None,
                    extras: None,
                });
                samplers.push(json::animation::Sampler {
                    extensions: None,
                    extras: None,
                    input: t_acc,
                    interpolation: Valid(json::animation::Interpolation::Linear),
                    output: out,
                });
            }
        }
        let meta = json!({ "sequence": s.name, "tags": s.tags, "fps": g.fps, "frames": n });
        root.push(json::Animation {
            extensions: None,
            extras: raw(json!({ "surfcap": meta })),
            channels,
            name: Some(s.name.clone()),
            samplers,
        });
        seq_meta.push(json!({ "name": s.name, "frames": n, "tags": s.tags }));
    }
    root.extras = raw(json!({ "surfcap": {
        "subject": g.name,
        "fps": g.fps,
        "up_axis": g.up_axis.as_str(),
        "units": g.units,
        "sequences": seq_meta,
        "rig": g.extras,
    }}));
    let json = finish_json(root, bin.len)?;
    let mut out = Vec::with_capacity(json.len() + bin.len as usize + 28);
    write_container(&mut out, &json, &bin.parts, |part, buf| buf.extend_from_slice(part))
        .map_err(|e| err!(Unsupported, "the skinned glb is larger than the format's 4 GiB: {e}"))?;
    Ok(out)
}

/// Writes the rig as a `.glb` (see the module's documentation).
pub fn write_skinned_glb(w: &mut dyn Write, g: &SkinnedGlb) -> Result<()> {
    let bytes = skinned_glb_bytes(g)?;
    w.write_all(&bytes).map_err(|e| err!(Io, "writing the skinned glb: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_triangles() -> (Topology, Vec<f32>) {
        let t = Topology::new(4, vec![[0, 1, 2], [2, 1, 3]], None).unwrap();
        (t, vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0])
    }

    #[test]
    fn reads_back_with_the_gltf_crate() {
        let (topo, rest) = two_triangles();
        let g = SkinnedGlb {
            name: "quad".into(),
            topology: &topo,
            rest: rest.clone(),
            slots: 4,
            joints: vec![0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0],
            weights: vec![0.5, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            bind_centres: vec![[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            sequences: vec![JointSequence {
                name: "wave".into(),
                tags: vec![],
                n_frames: 2,
                rotations: vec![[0.0, 0.0, 0.0, 1.0]; 4],
                translations: vec![[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.5, 0.0]],
            }],
            fps: 30.0,
            up_axis: UpAxis::PosZ,
            units: Units::metres(),
            extras: json!({}),
        };
        let bytes = skinned_glb_bytes(&g).unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = g.blob.clone().unwrap();
        let doc = &g.document;
        let skin = doc.skins().next().unwrap();
        assert_eq!(skin.joints().count(), 2);
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(&blob[..]));
        let p: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(p[3], [1.0, 1.0, 0.0]);
        let w: Vec<[f32; 4]> = reader.read_weights(0).unwrap().into_f32().collect();
        assert_eq!(w[0], [0.5, 0.5, 0.0, 0.0]);
        let j: Vec<[u16; 4]> = reader.read_joints(0).unwrap().into_u16().collect();
        assert_eq!(j[2], [1, 0, 0, 0]);
        let anim = doc.animations().next().unwrap();
        assert_eq!(anim.name(), Some("wave"));
        assert_eq!(anim.channels().count(), 4);
        let ibm: Vec<[[f32; 4]; 4]> = skin.reader(|_| Some(&blob[..])).read_inverse_bind_matrices().unwrap().collect();
        assert_eq!(ibm[1][3], [-1.0, -1.0, 0.0, 1.0]);
    }

    #[test]
    fn mismatched_sizes_are_errors() {
        let (topo, rest) = two_triangles();
        let g = SkinnedGlb {
            name: "quad".into(),
            topology: &topo,
            rest,
            slots: 4,
            joints: vec![0; 16],
            weights: vec![0.25; 16],
            bind_centres: vec![[0.0; 3]],
            sequences: vec![JointSequence {
                name: "s".into(),
                tags: vec![],
                n_frames: 2,
                rotations: vec![],
                translations: vec![],
            }],
            fps: 30.0,
            up_axis: UpAxis::PosY,
            units: Units::metres(),
            extras: json!({}),
        };
        assert!(skinned_glb_bytes(&g).unwrap_err().to_string().contains("sequence \"s\""));
    }
}

//! Alembic export: a subject as an Alembic archive in the
//! Ogawa container (`ogawa_write.rs`), the format the studios' tools (Maya, Houdini, Blender,
//! Nuke, Unreal, volumetric-capture editors) exchange animated meshes in. No Rust crate writes
//! Alembic, so the layers above Ogawa (AbcCoreOgawa's objects and properties, AbcGeom's
//! `Xform` and `PolyMesh` schemas) are written here, as the reference library (Alembic 1.8)
//! lays them out; the tests read every file back with that library (PyPI `alembic3d`).
//!
//! What is written:
//! - One `Xform` object per sequence under the archive's top, named after the sequence, holding
//!   one `PolyMesh` object `mesh` (the layout Maya and Blender write: a transform above its
//!   shape), so `/<sequence>/mesh` names the sequence's mesh as in the USD export.
//! - The mesh has homogeneous topology: `.faceIndices` and `.faceCounts` are stored once
//!   (constant properties with one sample per frame, as the reference writer stores a value
//!   set repeatedly), `P` (f32 x 3) has one sample per frame, `.selfBnds` (the frame's box, f64)
//!   too. `.velocities` (f32 x 3, units per second, one sample per frame: the finite
//!   differences of `vertex_velocity.rs`), so renderers draw motion blur; not on a frame set's
//!   meshes, whose vertices do not correspond between frames. Alembic's faces are clockwise (Maya's convention: the reference library and the DCC
//!   importers reverse them), surfcap's counter-clockwise: each triangle `(a, b, c)` is written
//!   `(c, b, a)`, so a reader that reverses the corner order gets `(a, b, c)` back exactly.
//! - UVs, when the topology has them, as the indexed face-varying geometry parameter `uv`
//!   (`.vals` f32 x 2, `.indices` u32, corners in the written face order). surfcap's subjects
//!   carry no normals, so none are written (DCC tools compute them; `N` is optional).
//! - The frame labels as the arbitrary geometry parameter `.arbGeomParams/surfcap_synthetic`:
//!   one u8 per frame (0 original, 1 synthetic), constant scope, time-sampled with the mesh.
//! - One uniform time sampling at the subject's fps starting at time 0, shared by every
//!   sequence (a shorter sequence simply has fewer samples).
//! - Alembic has no up axis or unit: tools assume Y up. A subject whose up axis is not +Y gets
//!   a static matrix on each sequence's `Xform` turning its up axis onto +Y (the points keep the
//!   subject's coordinates, as in the glb and USD exports); the archive's metadata records
//!   `surfcap_up_axis`, `surfcap_units` (the name; `surfcap_metres_per_unit` the scale when
//!   known) and `surfcap_fps` (the rate in its shortest exact
//!   decimal form, since `1 / (1 / fps)` is not always `fps` in floating point) so surfcap's
//!   import gives all three back exactly.
//!
//! Choices where the reference library's internals are not part of any format contract:
//! - Every stored sample starts with a 16-byte key that identifies its content; the reference
//!   library fills it with an MD5 digest and readers only compare keys (to share identical
//!   samples), never recompute them. surfcap writes the first 16 bytes of the BLAKE3 hash of the
//!   sample's bytes (BLAKE3 is already a dependency; equal content gives equal keys, which is
//!   all a reader may rely on). The 32 bytes of object and property hashes (SpookyHash in the
//!   reference) are likewise content hashes made with BLAKE3.
//! - The library version recorded in the archive is 1.8.12 (10812), the version whose layout
//!   this file follows and the tests read with; the AbcCore file version is 0, as there.
//!
//! Memory: the positions are streamed frame by frame from the subject; besides them the writer
//! keeps a few offsets per frame, so time and memory grow linearly with the frame count.

use std::io::{self, Write};

use crate::ogawa_write::{Child, OgawaWriter, write_ogawa};
use crate::vertex_velocity::frame_velocity;
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};
use surfcap_mesh::topology::Topology;

/// The plain-old-data types of Alembic's `PlainOldDataType` that surfcap writes.
#[derive(Clone, Copy)]
enum Pod {
    Bool = 0,
    Uint8 = 1,
    Uint32 = 5,
    Int32 = 6,
    Float32 = 10,
    Float64 = 11,
}

/// The library version stored in the archive (`XXYYZZ`, see the module documentation).
const LIBRARY_VERSION: i32 = 10812;

const MD_POINT: &str = "geoScope=vtx;interpretation=point";
const MD_BOX: &str = "interpretation=box";
/// `.velocities`: a V3f array, as the reference writer's `OV3fArrayProperty` tags it.
const MD_VECTOR: &str = "interpretation=vector";
const MD_POLYMESH: &str = "schema=AbcGeom_PolyMesh_v1;schemaBaseType=AbcGeom_GeomBase_v1";
const MD_POLYMESH_OBJECT: &str =
    "schema=AbcGeom_PolyMesh_v1;schemaBaseType=AbcGeom_GeomBase_v1;schemaObjTitle=AbcGeom_PolyMesh_v1:.geom";
const MD_XFORM: &str = "schema=AbcGeom_Xform_v3";
const MD_XFORM_OBJECT: &str = "schema=AbcGeom_Xform_v3;schemaObjTitle=AbcGeom_Xform_v3:.xform";
const MD_UV: &str = "arrayExtent=1;geoScope=fvr;interpretation=vector;isGeomParam=true;podExtent=2;podName=float32_t";
const MD_LABELS: &str = "arrayExtent=1;geoScope=con;isGeomParam=true;podExtent=1;podName=uint8_t";
/// The name of the frame labels' geometry parameter.
pub const LABELS_PARAM: &str = "surfcap_synthetic";

/// AbcCoreOgawa's map of repeated metadata strings: index 0 is the empty string, 1-254 a
/// stored string of at most 255 bytes, 255 a string written in place.
#[derive(Default)]
struct MetaDataMap {
    strings: Vec<String>,
}

impl MetaDataMap {
    fn index(&mut self, md: &str) -> u8 {
        if md.is_empty() {
            return 0;
        }
        if let Some(i) = self.strings.iter().position(|s| s == md) {
            return (i + 1) as u8;
        }
        if md.len() < 256 && self.strings.len() < 254 {
            self.strings.push(md.to_string());
            return self.strings.len() as u8;
        }
        0xff
    }

    fn bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        for s in &self.strings {
            out.push(s.len() as u8);
            out.extend_from_slice(s.as_bytes());
        }
        out
    }
}

#[derive(Clone, Copy)]
enum Kind {
    Compound,
    Scalar,
    /// `scalar_like`: every sample holds exactly one element.
    Array {
        scalar_like: bool,
    },
}

/// One property's header, as AbcCoreOgawa packs it into its parent compound's header block.
struct PropertyHeader {
    name: String,
    kind: Kind,
    pod: Pod,
    extent: u8,
    metadata: &'static str,
    time_sampling: u32,
    /// Samples the property answers for (frames), whatever was stored.
    samples: u32,
    /// Only the first sample is stored: every frame has the same value.
    constant: bool,
    homogeneous: bool,
}

fn push_hinted(out: &mut Vec<u8>, v: u32, hint: u32) {
    let b = v.to_le_bytes();
    out.extend_from_slice(&b[..[1, 2, 4][hint as usize]]);
}

impl PropertyHeader {
    fn compound(name: &str, metadata: &'static str) -> Self {
        PropertyHeader {
            name: name.into(),
            kind: Kind::Compound,
            pod: Pod::Bool,
            extent: 0,
            metadata,
            time_sampling: 0,
            samples: 0,
            constant: false,
            homogeneous: false,
        }
    }

    /// Appends the packed header: a 32-bit info word (property type, the byte width of the
    /// sizes that follow, POD, time-sampling flag, constancy, homogeneity, extent, metadata
    /// index), then the sample count, the time sampling's index, the name and the metadata.
    fn encode(&self, out: &mut Vec<u8>, md: &mut MetaDataMap) {
        let md_index = md.index(self.metadata);
        let max = (self.metadata.len() as u32).max(self.name.len() as u32).max(self.samples).max(self.time_sampling);
        let hint = if max < 256 {
            0
        } else if max < 65536 {
            1
        } else {
            2
        };
        let mut info = (hint << 2) | (u32::from(md_index) << 20);
        if !matches!(self.kind, Kind::Compound) {
            info |= match self.kind {
                Kind::Scalar => 1,
                Kind::Array { scalar_like } => 2 | u32::from(scalar_like),
                Kind::Compound => 0,
            };
            info |= (self.pod as u32) << 4;
            if self.time_sampling != 0 {
                info |= 0x100;
            }
            // First and last changed sample: (0, 0) for a constant property, else (1, n - 1),
            // the default that needs no explicit pair (every stored sample may differ).
            if self.constant || self.samples <= 1 {
                info |= 0x800;
            }
            if self.homogeneous {
                info |= 0x400;
            }
            info |= u32::from(self.extent) << 12;
            push_hinted(out, info, 2);
            push_hinted(out, self.samples, hint);
            if self.time_sampling != 0 {
                push_hinted(out, self.time_sampling, hint);
            }
        } else {
            push_hinted(out, info, 2);
        }
        push_hinted(out, self.name.len() as u32, hint);
        out.extend_from_slice(self.name.as_bytes());
        if md_index == 0xff {
            push_hinted(out, self.metadata.len() as u32, hint);
            out.extend_from_slice(self.metadata.as_bytes());
        }
    }
}

/// A 16-byte content key (see the module documentation); zeros in the counting pass, where
/// only the byte count matters.
fn key(o: &OgawaWriter<'_>, bytes: &[u8]) -> [u8; 16] {
    let mut k = [0u8; 16];
    if o.writing() {
        k.copy_from_slice(&blake3::hash(bytes).as_bytes()[..16]);
    }
    k
}

/// Gathers the content keys of an object's samples into its 32 bytes of hashes.
struct ObjectHash(blake3::Hasher);

impl ObjectHash {
    fn new() -> Self {
        ObjectHash(blake3::Hasher::new())
    }
    fn add(&mut self, bytes: &[u8]) {
        self.0.update(bytes);
    }
    /// The data hash (the object's properties) then the children's hash (zeros when it has
    /// none), as the reference writer appends them to the child headers.
    fn finish(&self, children: &[[u8; 32]]) -> [u8; 32] {
        let mut out = [0u8; 32];
        out[..16].copy_from_slice(&self.0.finalize().as_bytes()[..16]);
        if !children.is_empty() {
            let mut h = blake3::Hasher::new();
            for c in children {
                h.update(c);
            }
            out[16..].copy_from_slice(&h.finalize().as_bytes()[..16]);
        }
        out
    }
}

/// One stored sample: its key then its bytes.
fn sample(o: &mut OgawaWriter<'_>, bytes: &[u8], hash: &mut ObjectHash) -> io::Result<Child> {
    let k = key(o, bytes);
    hash.add(&k);
    o.data(&[&k, bytes])
}

/// An array property's group: each stored sample then its dimensions (empty: rank 1, counted
/// from the data size).
fn array_group(o: &mut OgawaWriter<'_>, samples: &[Child]) -> io::Result<Child> {
    let children: Vec<Child> = samples.iter().flat_map(|&s| [s, Child::EMPTY_DATA]).collect();
    o.group(&children)
}

/// A compound property's group: its properties' groups then their packed headers.
fn compound_group(
    o: &mut OgawaWriter<'_>,
    props: &[(Child, PropertyHeader)],
    md: &mut MetaDataMap,
) -> io::Result<Child> {
    let mut headers = Vec::new();
    for (_, h) in props {
        h.encode(&mut headers, md);
    }
    let mut children: Vec<Child> = props.iter().map(|(c, _)| *c).collect();
    children.push(o.data(&[&headers])?);
    o.group(&children)
}

fn le_bytes<T: Copy, const N: usize>(values: impl Iterator<Item = T>, to: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    values.flat_map(to).collect()
}

/// The rotation (row-vector convention: `p' = p M`, Imath's) turning `up` onto +Y, or `None`.
fn up_matrix(up: UpAxis) -> Option<[[f64; 3]; 3]> {
    // Rows of R (column-vector, p' = R p) with R up = +Y; Imath's matrix is R transposed.
    let r: [[f64; 3]; 3] = match up {
        UpAxis::PosY => return None,
        UpAxis::PosZ => [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
        UpAxis::NegZ => [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
        UpAxis::PosX => [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        UpAxis::NegX => [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        UpAxis::NegY => [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
    };
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = r[j][i];
        }
    }
    Some(m)
}

/// A valid, unique Alembic object name for `name` among `taken`: not empty, no `/`.
fn object_name(name: &str, taken: &mut Vec<String>) -> String {
    let mut s: String = name.chars().map(|c| if c == '/' { '_' } else { c }).collect();
    if s.is_empty() {
        s.push('_');
    }
    crate::unique_name(s, taken)
}

/// Metadata values cannot hold Alembic's separators `;` and `=`: they are percent-encoded (with
/// `%` itself), as `abc_read::metadata_unescape` reads them back.
pub fn metadata_value(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            ';' => out.push_str("%3B"),
            '=' => out.push_str("%3D"),
            '%' => out.push_str("%25"),
            c => out.push(c),
        }
    }
    out
}

fn object_header(out: &mut Vec<u8>, name: &str, metadata: &str, md: &mut MetaDataMap) {
    push_hinted(out, name.len() as u32, 2);
    out.extend_from_slice(name.as_bytes());
    let i = md.index(metadata);
    out.push(i);
    if i == 0xff {
        push_hinted(out, metadata.len() as u32, 2);
        out.extend_from_slice(metadata.as_bytes());
    }
}

/// One sequence as the writer sees it: each frame's topology and points, and its labels.
struct SequenceView<'a> {
    name: &'a str,
    frames: Vec<(&'a Topology, &'a [f32])>,
    labels: &'a [FrameLabel],
}

impl SequenceView<'_> {
    /// Whether some frame's topology differs from the one before (a frame set's sequence).
    fn varying(&self) -> bool {
        self.frames.windows(2).any(|w| !std::ptr::eq(w[0].0, w[1].0) && w[0].0 != w[1].0)
    }
}

/// The `.geom` compound of one sequence's mesh.
fn polymesh_properties(
    o: &mut OgawaWriter<'_>,
    md: &mut MetaDataMap,
    seq: &SequenceView<'_>,
    fps: f64,
    hash: &mut ObjectHash,
) -> io::Result<Child> {
    let frames = seq.frames.len() as u32;
    let topo = seq.frames[0].0;
    let n = topo.n_vertices();
    let varying = seq.varying();
    let homogeneous_samples = |kind, pod, extent, metadata, constant| PropertyHeader {
        name: String::new(),
        kind,
        pod,
        extent,
        metadata,
        time_sampling: 1,
        samples: frames,
        constant,
        homogeneous: true,
    };
    let mut props = Vec::new();

    // .selfBnds: each frame's box, min then max, as f64.
    let mut bounds = Vec::with_capacity(seq.frames.len());
    for &(_, p) in &seq.frames {
        let mut b =
            [f64::INFINITY, f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for v in p.chunks_exact(3) {
            for a in 0..3 {
                b[a] = b[a].min(f64::from(v[a]));
                b[a + 3] = b[a + 3].max(f64::from(v[a]));
            }
        }
        bounds.push(sample(o, &le_bytes(b.into_iter(), f64::to_le_bytes), hash)?);
    }
    let g = o.group(&bounds)?;
    props.push((
        g,
        PropertyHeader {
            name: ".selfBnds".into(),
            ..homogeneous_samples(Kind::Scalar, Pod::Float64, 6, MD_BOX, false)
        },
    ));

    // P: one sample per frame, streamed.
    let mut points = Vec::with_capacity(seq.frames.len());
    for &(_, p) in &seq.frames {
        let bytes = if o.writing() { le_bytes(p.iter().copied(), f32::to_le_bytes) } else { vec![0; p.len() * 4] };
        points.push(sample(o, &bytes, hash)?);
    }
    let g = array_group(o, &points)?;
    let same_count = seq.frames.iter().all(|(t, _)| t.n_vertices() == n);
    let scalar_like = same_count && n == 1;
    props.push((
        g,
        PropertyHeader {
            name: "P".into(),
            homogeneous: same_count,
            ..homogeneous_samples(Kind::Array { scalar_like }, Pod::Float32, 3, MD_POINT, false)
        },
    ));

    // .velocities: units per second, one sample per frame (`vertex_velocity`), for a sequence
    // of one topology only: a frame set's vertices do not correspond between frames.
    if !varying {
        let positions: Vec<&[f32]> = seq.frames.iter().map(|&(_, p)| p).collect();
        let mut velocities = Vec::with_capacity(seq.frames.len());
        for f in 0..positions.len() {
            let bytes = if o.writing() {
                le_bytes(frame_velocity(&positions, f, fps).into_iter(), f32::to_le_bytes)
            } else {
                vec![0; positions[f].len() * 4]
            };
            velocities.push(sample(o, &bytes, hash)?);
        }
        let g = array_group(o, &velocities)?;
        props.push((
            g,
            PropertyHeader {
                name: ".velocities".into(),
                ..homogeneous_samples(Kind::Array { scalar_like }, Pod::Float32, 3, MD_VECTOR, false)
            },
        ));
    }

    // Topology, faces reversed to Alembic's clockwise order: stored once when every frame
    // shares it; for a frame set's sequence one sample per frame (heterogeneous topology), a
    // frame whose faces equal the previous frame's referring to the blocks already written.
    let face_blocks = |o: &mut OgawaWriter<'_>, t: &Topology, hash: &mut ObjectHash| -> io::Result<(Child, Child)> {
        let tris = t.triangles();
        let indices = le_bytes(tris.iter().flat_map(|t| [t[2], t[1], t[0]]), |v| (v as i32).to_le_bytes());
        let counts = le_bytes(tris.iter().map(|_| 3i32), i32::to_le_bytes);
        Ok((sample(o, &indices, hash)?, sample(o, &counts, hash)?))
    };
    let mut index_samples = Vec::new();
    let mut count_samples = Vec::new();
    let mut previous: Option<(&Topology, (Child, Child))> = None;
    for &(t, _) in if varying { &seq.frames[..] } else { &seq.frames[..1] } {
        let blocks = match previous {
            Some((p, b)) if std::ptr::eq(p, t) || p.triangles() == t.triangles() => {
                hash.add(&key(o, &[]));
                b
            }
            _ => face_blocks(o, t, hash)?,
        };
        index_samples.push(blocks.0);
        count_samples.push(blocks.1);
        previous = Some((t, blocks));
    }
    let same_faces = seq.frames.iter().all(|(t, _)| t.n_triangles() == topo.n_triangles());
    let g = array_group(o, &index_samples)?;
    props.push((
        g,
        PropertyHeader {
            name: ".faceIndices".into(),
            homogeneous: same_faces,
            ..homogeneous_samples(
                Kind::Array { scalar_like: same_faces && topo.n_triangles() * 3 == 1 },
                Pod::Int32,
                1,
                "",
                !varying,
            )
        },
    ));
    let g = array_group(o, &count_samples)?;
    props.push((
        g,
        PropertyHeader {
            name: ".faceCounts".into(),
            homogeneous: same_faces,
            ..homogeneous_samples(
                Kind::Array { scalar_like: same_faces && topo.n_triangles() == 1 },
                Pod::Int32,
                1,
                "",
                !varying,
            )
        },
    ));

    // .arbGeomParams/surfcap_synthetic: one u8 per frame; a value repeated refers to the block
    // already written (as the reference writer shares identical samples).
    let labels: Vec<u8> = seq.labels.iter().map(|l| u8::from(*l == FrameLabel::Synthetic)).collect();
    let constant = labels.windows(2).all(|w| w[0] == w[1]);
    let stored = if constant { &labels[..labels.len().min(1)] } else { &labels[..] };
    let mut blocks: [Option<Child>; 2] = [None, None];
    let mut label_samples = Vec::with_capacity(stored.len());
    for &l in stored {
        let c = match blocks[l as usize] {
            Some(c) => {
                hash.add(&key(o, &[l]));
                c
            }
            None => {
                let c = sample(o, &[l], hash)?;
                blocks[l as usize] = Some(c);
                c
            }
        };
        label_samples.push(c);
    }
    let g = array_group(o, &label_samples)?;
    let arb = compound_group(
        o,
        &[(
            g,
            PropertyHeader {
                name: LABELS_PARAM.into(),
                ..homogeneous_samples(Kind::Array { scalar_like: true }, Pod::Uint8, 1, MD_LABELS, constant)
            },
        )],
        md,
    )?;
    props.push((arb, PropertyHeader::compound(".arbGeomParams", "")));

    // uv: indexed, face-varying, corners in the written (reversed) order; not for a frame set's
    // sequence (one atlas cannot fit faces that change).
    if let Some(uv) = topo.uv().filter(|_| !varying) {
        let vals = le_bytes(uv.coords.iter().flatten().copied(), f32::to_le_bytes);
        let s = sample(o, &vals, hash)?;
        let gv = array_group(o, &[s])?;
        let ix = le_bytes(uv.corners.iter().flat_map(|c| [c[2], c[1], c[0]]), u32::to_le_bytes);
        let s = sample(o, &ix, hash)?;
        let gi = array_group(o, &[s])?;
        let g = compound_group(
            o,
            &[
                (
                    gv,
                    PropertyHeader {
                        name: ".vals".into(),
                        ..homogeneous_samples(
                            Kind::Array { scalar_like: uv.coords.len() == 1 },
                            Pod::Float32,
                            2,
                            MD_UV,
                            true,
                        )
                    },
                ),
                (
                    gi,
                    PropertyHeader {
                        name: ".indices".into(),
                        ..homogeneous_samples(
                            Kind::Array { scalar_like: uv.corners.len() * 3 == 1 },
                            Pod::Uint32,
                            1,
                            "",
                            true,
                        )
                    },
                ),
            ],
            md,
        )?;
        props.push((g, PropertyHeader::compound("uv", MD_UV)));
    }
    compound_group(o, &props, md)
}

/// The `.xform` compound of a static transform: `matrix` (Imath's row-vector layout) or the
/// identity.
fn xform_properties(
    o: &mut OgawaWriter<'_>,
    md: &mut MetaDataMap,
    matrix: Option<[[f64; 3]; 3]>,
    hash: &mut ObjectHash,
) -> io::Result<Child> {
    let one_sample = |name: &str, pod, extent| PropertyHeader {
        name: name.into(),
        kind: Kind::Scalar,
        pod,
        extent,
        metadata: "",
        time_sampling: 0,
        samples: 1,
        constant: true,
        homogeneous: true,
    };
    let mut props = Vec::new();
    let s = sample(o, &[1], hash)?;
    props.push((o.group(&[s])?, one_sample(".inherits", Pod::Bool, 1)));
    if let Some(m) = matrix {
        // One 4x4 matrix operation: type 3 (matrix) << 4, hint 0.
        let s = sample(o, &[0x30], hash)?;
        props.push((o.group(&[s])?, one_sample(".ops", Pod::Uint8, 1)));
        let mut full = [0.0f64; 16];
        for i in 0..3 {
            for j in 0..3 {
                full[4 * i + j] = m[i][j];
            }
        }
        full[15] = 1.0;
        let s = sample(o, &le_bytes(full.into_iter(), f64::to_le_bytes), hash)?;
        props.push((o.group(&[s])?, one_sample(".vals", Pod::Float64, 16)));
        let s = sample(o, &[1], hash)?;
        props.push((o.group(&[s])?, one_sample("isNotConstantIdentity", Pod::Bool, 1)));
    }
    compound_group(o, &props, md)
}

/// What the archive says of the whole animation.
struct ArchiveInfo<'a> {
    name: &'a str,
    fps: f64,
    up_axis: UpAxis,
    units: &'a Units,
}

/// Emits the whole archive; returns the root group.
fn emit(o: &mut OgawaWriter<'_>, info: &ArchiveInfo<'_>, sequences: &[SequenceView<'_>]) -> io::Result<Child> {
    let mut md = MetaDataMap::default();
    let version = o.data(&[&0i32.to_le_bytes()])?;
    let library = o.data(&[&LIBRARY_VERSION.to_le_bytes()])?;
    let matrix = up_matrix(info.up_axis);
    let mut top_children = Vec::new();
    let mut top_headers = Vec::new();
    let mut top_hashes = Vec::new();
    let mut taken = Vec::new();
    let mut max_samples = 0u32;
    for seq in sequences {
        max_samples = max_samples.max(seq.frames.len() as u32);
        // The mesh object: its properties (one compound `.geom`), no children.
        let mut mesh_hash = ObjectHash::new();
        let geom = polymesh_properties(o, &mut md, seq, info.fps, &mut mesh_hash)?;
        let mesh_props = compound_group(o, &[(geom, PropertyHeader::compound(".geom", MD_POLYMESH))], &mut md)?;
        let mesh_hashes = if o.writing() { mesh_hash.finish(&[]) } else { [0; 32] };
        let mesh_data = o.data(&[&mesh_hashes])?;
        let mesh = o.group(&[mesh_props, mesh_data])?;
        // The sequence's Xform above it.
        let mut xform_hash = ObjectHash::new();
        let xform = xform_properties(o, &mut md, matrix, &mut xform_hash)?;
        let xform_props = compound_group(o, &[(xform, PropertyHeader::compound(".xform", MD_XFORM))], &mut md)?;
        let mut headers = Vec::new();
        object_header(&mut headers, "mesh", MD_POLYMESH_OBJECT, &mut md);
        let xform_hashes = if o.writing() { xform_hash.finish(&[mesh_hashes]) } else { [0; 32] };
        let xform_data = o.data(&[&headers, &xform_hashes])?;
        top_children.push(o.group(&[xform_props, mesh, xform_data])?);
        object_header(&mut top_headers, &object_name(seq.name, &mut taken), MD_XFORM_OBJECT, &mut md);
        top_hashes.push(xform_hashes);
    }
    let top_hash = if o.writing() { ObjectHash::new().finish(&top_hashes) } else { [0; 32] };
    let top_data = o.data(&[&top_headers, &top_hash])?;
    let mut top = vec![Child::EMPTY_GROUP];
    top.extend(top_children);
    top.push(top_data);
    let top = o.group(&top)?;

    let archive_md = format!(
        "_ai_Application=surfcap {};_ai_Description={};surfcap_fps={};surfcap_up_axis={};surfcap_units={}",
        env!("CARGO_PKG_VERSION"),
        metadata_value(info.name),
        info.fps,
        info.up_axis.as_str(),
        metadata_value(&info.units.name),
    );
    // The units' scale, when they have one: their name alone may not say it ("0.5 m").
    let archive_md = match info.units.metres_per_unit {
        Some(m) => format!("{archive_md};surfcap_metres_per_unit={m}"),
        None => archive_md,
    };
    let archive_md = o.data(&[archive_md.as_bytes()])?;
    // Time samplings: 0 the identity (the Xforms' one sample), 1 uniform at the subject's fps
    // from time 0. Each: the most samples a property has with it, the time per cycle, the
    // stored times.
    let mut times = Vec::new();
    for (max, per_cycle) in [(u32::from(!sequences.is_empty()), 1.0), (max_samples, 1.0 / info.fps)] {
        times.extend_from_slice(&max.to_le_bytes());
        times.extend_from_slice(&f64::to_le_bytes(per_cycle));
        times.extend_from_slice(&1u32.to_le_bytes());
        times.extend_from_slice(&0f64.to_le_bytes());
    }
    let times = o.data(&[&times])?;
    let md_block = o.data(&[&md.bytes()])?;
    o.group(&[version, library, top, archive_md, times, md_block])
}

fn write_views(w: &mut dyn Write, info: &ArchiveInfo<'_>, views: &[SequenceView<'_>]) -> io::Result<()> {
    if !(info.fps.is_finite() && info.fps > 0.0) {
        return Err(io::Error::other(format!("frame rate {}: expected a positive number", info.fps)));
    }
    write_ogawa(w, |o| emit(o, info, views))
}

/// Writes `subject` as an Alembic (Ogawa) archive.
pub fn write_abc(w: &mut dyn Write, subject: &Subject) -> io::Result<()> {
    let topo = subject.topology();
    let views: Vec<SequenceView<'_>> = subject
        .sequences()
        .iter()
        .map(|q: &Sequence| SequenceView {
            name: &q.name,
            frames: (0..q.n_frames()).map(|f| (topo, q.frame(f))).collect(),
            labels: &q.labels,
        })
        .collect();
    let info = ArchiveInfo { name: &subject.name, fps: subject.fps, up_axis: subject.up_axis, units: &subject.units };
    write_views(w, &info, &views)
}

/// Writes a frame set (every frame its own topology) as an Alembic archive: each sequence a
/// `PolyMesh` of heterogeneous topology, faces and points sampled per frame, as per-frame
/// reconstructions are exchanged; surfcap's import reads it back as a frame set.
pub fn write_abc_frame_set(w: &mut dyn Write, set: &FrameSet) -> io::Result<()> {
    let views: Vec<SequenceView<'_>> = set
        .sequences()
        .iter()
        .map(|q| SequenceView {
            name: &q.name,
            frames: q.frames().iter().map(|f| (f.topology(), f.positions())).collect(),
            labels: q.labels(),
        })
        .collect();
    let info = ArchiveInfo { name: &set.name, fps: set.fps, up_axis: set.up_axis, units: &set.units };
    write_views(w, &info, &views)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::subject::{Units, UpAxis};

    fn tetra_subject(up: UpAxis) -> Subject {
        let topo = Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap();
        let f0 = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut positions = f0.to_vec();
        positions.extend(f0.iter().map(|v| v + 0.5));
        let seq = Sequence::new("walk", 4, positions).unwrap();
        Subject::new("tetra", topo, vec![seq], 30.0, up, Units::metres()).unwrap()
    }

    #[test]
    fn the_archive_is_an_ogawa_tree_with_the_abc_root_layout() {
        let mut out = Vec::new();
        write_abc(&mut out, &tetra_subject(UpAxis::PosZ)).unwrap();
        assert_eq!(&out[..8], b"Ogawa\xff\x00\x01");
        let root = u64::from_le_bytes(out[8..16].try_into().unwrap()) as usize;
        // The root group: version, library version, top object, metadata, time samplings, map.
        assert_eq!(u64::from_le_bytes(out[root..root + 8].try_into().unwrap()), 6);
        let text = String::from_utf8_lossy(&out);
        for s in ["surfcap_up_axis=+z", "surfcap_units=m", MD_POLYMESH_OBJECT, ".faceIndices", LABELS_PARAM, "walk"] {
            assert!(text.contains(s), "{s} missing");
        }
        // Same subject, same bytes.
        let mut again = Vec::new();
        write_abc(&mut again, &tetra_subject(UpAxis::PosZ)).unwrap();
        assert_eq!(out, again);
    }

    #[test]
    fn long_metadata_is_written_in_place_and_the_map_is_bounded() {
        let mut md = MetaDataMap::default();
        assert_eq!(md.index(""), 0);
        assert_eq!(md.index("a=1"), 1);
        assert_eq!(md.index("a=1"), 1);
        assert_eq!(md.index(&"x".repeat(300)), 0xff);
        for k in 0..300 {
            md.index(&format!("k={k}"));
        }
        assert_eq!(md.strings.len(), 254);
        assert_eq!(md.index("new=1"), 0xff);
    }

    #[test]
    fn up_matrices_turn_the_up_axis_onto_y() {
        for (up, v) in [
            (UpAxis::PosZ, [0.0, 0.0, 1.0]),
            (UpAxis::NegZ, [0.0, 0.0, -1.0]),
            (UpAxis::PosX, [1.0, 0.0, 0.0]),
            (UpAxis::NegX, [-1.0, 0.0, 0.0]),
            (UpAxis::NegY, [0.0, -1.0, 0.0]),
        ] {
            let m = up_matrix(up).unwrap();
            // Row vector times matrix.
            let p: Vec<f64> = (0..3).map(|j| (0..3).map(|i| v[i] * m[i][j]).sum()).collect();
            assert_eq!(p, vec![0.0, 1.0, 0.0], "{up:?}");
        }
        assert!(up_matrix(UpAxis::PosY).is_none());
    }

    #[test]
    fn metadata_values_escape_the_separators_and_read_back() {
        for v in ["plain", "a;b=c", "100%", "%3B literal; and %25", "model units (not meters; ~200 tall)"] {
            let e = metadata_value(v);
            assert!(!e.contains(';') && !e.contains('='), "{e}");
            assert_eq!(crate::abc_read::metadata_unescape(&e), v);
        }
    }

    #[test]
    fn object_names_are_valid_and_unique() {
        let mut taken = Vec::new();
        assert_eq!(object_name("a/b", &mut taken), "a_b");
        assert_eq!(object_name("a_b", &mut taken), "a_b_1");
        assert_eq!(object_name("", &mut taken), "_");
    }
}

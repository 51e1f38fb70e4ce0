//! Alembic import (`.abc`): the Abc layer of an Ogawa archive
//! (`ogawa_read.rs`) read as animated meshes. Not from the thesis: its captures are per-frame
//! meshes of one topology, which an Alembic `PolyMesh` with homogeneous topology holds directly.
//!
//! Written from the format as the reference library reads it (github.com/alembic/alembic:
//! `AbcCoreOgawa/ArImpl.cpp`, `OrData.cpp`, `CprData.cpp`, `AprImpl.cpp`, `ReadUtil.cpp`;
//! `AbcGeom/IPolyMesh.cpp`, `IXform.cpp`, `GeometryScope.cpp`) and checked against files written
//! by it (PyPI `alembic3d`, the PyAlembic bindings, in `crates/surfcap-cli/tests/abc_import.rs`).
//! The crate `ogawa-rs` was tried first (to be used only if it read PolyMesh samples
//! correctly): version 0.4.0 read the archive and object tree of a 3-sample quad + triangle
//! mesh under an Xform written by alembic3d 1.8.12.1, then panicked ("attempt to subtract with
//! overflow" in `DataChunk::read_pod_array`) reading its first `P` sample; its source also
//! `assert!`s on schema metadata and allocates buffers from sizes read in the file before
//! checking them, so it is not used.
//!
//! The archive (root group children): 0 the Alembic file version, 1 the library version, 2 the
//! top object's group, 3 the archive metadata, 4 the time samplings, 5 the indexed metadata.
//! An object group: 0 its top compound property, 1..=n its n child objects, last the children's
//! headers (name, metadata) followed by two 16-byte hashes. A compound property group: one child
//! per sub-property, last their headers (a packed `info` word: property type, size hint of the
//! following integers, POD type, extent, whether it has a time sampling, changed-index range,
//! homogeneity, metadata index; then sample count, first/last changed index, time sampling
//! index, name, inline metadata). An array property's sample `i` is data `2i` (a 16-byte key,
//! then the values) and data `2i+1` (its dimensions, empty when one-dimensional); a scalar's is
//! data `i`. Repeated samples are not stored: sample k reads stored sample 0 before the first
//! change and the last stored one after the last change.
//!
//! Read: every `PolyMesh` (and `SubD`, read as its control mesh) at any depth, one sequence
//! each, from its `.geom` compound: `P` (float32 x3, one frame per sample), `.faceIndices`,
//! `.faceCounts`, `uv` (face-varying or per vertex, indexed `.vals`/`.indices` or not), frame
//! labels `.arbGeomParams/surfcap_synthetic` (uint8, one per sample, 0 original / 1 synthetic),
//! `.velocities` (float32 x3 per point, units per second; kept on [`AbcMesh::velocities`] for a
//! mesh of one topology, where vertices correspond between frames); the archive metadata `surfcap_up_axis` and `surfcap_units`; the mesh's time sampling.
//!
//! Choices where Alembic leaves room (each also said in the code):
//! - Alembic's faces are clockwise (Maya's left-handed order): the reference library's users and
//!   every DCC importer reverse each face. surfcap's triangles are counter-clockwise, so each
//!   polygon `c0 .. c(n-1)` is reversed to `c(n-1) .. c0` and fan-triangulated from that first
//!   corner: `(c(n-1), c(n-1-k), c(n-2-k))`. A quad facing +Z stored clockwise seen from +Z
//!   becomes two triangles whose normals point to +Z. Exact for the convex polygons DCC tools
//!   write; a concave polygon may get a fold (triangulate it in the DCC tool).
//! - Frames are the samples of `P` in order. The frame rate comes from P's time sampling:
//!   uniform (1 / time per cycle), cyclic or acyclic with evenly spaced times (within a
//!   millionth of a frame); other times are refused, since surfcap plays frame k at k / fps. A
//!   rate within 1e-9 (relative) of a whole number or of n * 1000/1001 (23.976, 29.97, 59.94)
//!   snaps to that exact value. The default identity sampling (index 0, one second per sample)
//!   means the writer set no rate: none is returned (import then asks for `--fps`), with a note.
//! - Homogeneous topology (later `.faceIndices`/`.faceCounts` samples absent or equal, the
//!   point count unchanged) gives one topology; otherwise every frame keeps its own
//!   ([`AbcFrames::Varying`]), which `import` refuses until frame sets exist.
//! - Up axis: `surfcap_up_axis` when present (surfcap's writer), else +Y, Alembic's convention
//!   (Maya, Houdini and Blender's exporter write Y-up), said in a note. Units: `surfcap_units`
//!   when present, else none (a note). A non-identity Xform above a mesh is ignored with a note
//!   (points are read in the mesh's own coordinates), except the mesh's parent Xform when
//!   `surfcap_up_axis` is present: surfcap's writer puts the up-axis rotation there.
//! - Normals are ignored (surfcap computes its own), UVs that do not fit their scope are dropped,
//!   animated UVs keep the first sample's, other schemas (curves, points, cameras, ...) are
//!   skipped: each with a note. Several meshes must share one topology (one subject).
//! - Sizes: a mesh may repeat a stored sample for many frames at no cost in the file, so the
//!   positions read (and, for a varying mesh, each frame's copy of its triangles) are capped at
//!   16 times the file's length plus 256 MiB, and a sample count above the file's length is
//!   refused: a file asking for more is refused rather than allocating from its numbers.

use std::collections::HashSet;
use std::path::Path;

use crate::ogawa_read::{Child, Ogawa};
use surfcap_mesh::error::{Error, Location, Result, err};
use surfcap_mesh::subject::{FrameLabel, Units, UpAxis};
use surfcap_mesh::topology::{Topology, UvAtlas};

/// The frames of one mesh: one topology for all, or each its own.
#[derive(Debug, Clone)]
pub enum AbcFrames {
    /// Homogeneous topology: `positions` is `[frames * vertices * 3]`.
    Constant { topology: Topology, positions: Vec<f32> },
    /// The topology changes between samples: every frame with its own topology and positions.
    Varying { frames: Vec<AbcFrame> },
}

/// One frame of a varying-topology mesh.
#[derive(Debug, Clone)]
pub struct AbcFrame {
    pub topology: Topology,
    /// `[vertices * 3]`.
    pub positions: Vec<f32>,
    /// The Alembic faces (polygons) of this sample, before triangulation.
    pub faces: usize,
}

/// One `PolyMesh` object: one sequence of the subject.
#[derive(Debug, Clone)]
pub struct AbcMesh {
    /// The object path, such as `/walk/mesh`.
    pub path: String,
    /// The sequence name: the path without its leading `/` and a last component `mesh`.
    pub name: String,
    pub frames: AbcFrames,
    /// The time of each sample, in seconds.
    pub times: Vec<f64>,
    /// The rate of P's time sampling, when it states one.
    pub fps: Option<f64>,
    /// From `.arbGeomParams/surfcap_synthetic` when present.
    pub labels: Option<Vec<FrameLabel>>,
    /// From `.velocities` when present on a mesh of one topology: `[frames * vertices * 3]`,
    /// units per second, as renderers read them for motion blur.
    pub velocities: Option<Vec<f32>>,
}

impl AbcMesh {
    pub fn n_frames(&self) -> usize {
        self.times.len()
    }

    /// The first frame whose topology differs from the previous one's: (frame, faces, faces
    /// before). `None` for a constant mesh.
    pub fn topology_change(&self) -> Option<(usize, usize, usize)> {
        match &self.frames {
            AbcFrames::Constant { .. } => None,
            AbcFrames::Varying { frames } => (1..frames.len())
                .find(|&k| frames[k].topology != frames[k - 1].topology)
                .map(|k| (k, frames[k].faces, frames[k - 1].faces)),
        }
    }
}

/// Everything read from an `.abc` archive.
#[derive(Debug, Clone)]
pub struct AbcArchive {
    /// Every mesh, in depth-first object order; the constant ones share one topology.
    pub meshes: Vec<AbcMesh>,
    pub fps: Option<f64>,
    pub up_axis: Option<UpAxis>,
    pub units: Option<Units>,
    /// What was ignored or assumed.
    pub notes: Vec<String>,
}

/// Reads an `.abc` file (errors name the file).
pub fn read_abc(path: &Path) -> Result<AbcArchive> {
    let bytes = surfcap_mesh::regular_file::read_regular_file(path)?;
    parse_abc(&bytes).map_err(|e| e.in_file(path))
}

/// Alembic's POD types, by their code in a property header.
const POD_NAMES: [&str; 14] = [
    "bool", "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64", "float16", "float32", "float64",
    "string", "wstring",
];
const POD_BYTES: [usize; 14] = [1, 1, 1, 2, 2, 4, 4, 8, 8, 2, 4, 8, 1, 4];
const UINT8: u8 = 1;
const UINT32: u8 = 5;
const INT32: u8 = 6;
const FLOAT32: u8 = 10;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PropKind {
    Compound,
    Scalar,
    Array,
}

/// A property header, with the group holding its samples (or sub-properties).
#[derive(Debug, Clone)]
struct Prop {
    name: String,
    kind: PropKind,
    pod: u8,
    extent: u8,
    samples: u32,
    first_changed: u32,
    last_changed: u32,
    time_sampling: u32,
    metadata: String,
    group: u64,
}

impl Prop {
    /// The stored sample read for sample `k` (repeats are not stored).
    fn stored(&self, k: u32) -> usize {
        if k < self.first_changed || (self.first_changed == 0 && self.last_changed == 0) {
            0
        } else if k >= self.last_changed {
            // Saturating: a damaged range maps to some index, which is then looked up in the
            // sample group and refused when it is not there.
            self.last_changed.saturating_sub(self.first_changed) as usize + 1
        } else {
            (k - self.first_changed) as usize + 1
        }
    }

    fn type_name(&self) -> String {
        format!("{} x{}", POD_NAMES[self.pod as usize], self.extent)
    }
}

/// Reads `key=value;key=value` metadata.
fn meta_get<'m>(metadata: &'m str, key: &str) -> Option<&'m str> {
    metadata.split(';').find_map(|kv| kv.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v))
}

struct TimeSampling {
    time_per_cycle: f64,
    times: Vec<f64>,
}

struct Reader<'a> {
    o: Ogawa<'a>,
    indexed: Vec<String>,
    samplings: Vec<TimeSampling>,
    file_len: u64,
}

fn u32_le(b: &[u8], pos: usize) -> u32 {
    u32::from_le_bytes([b[pos], b[pos + 1], b[pos + 2], b[pos + 3]])
}

/// A little cursor over a data block that names the byte offset in the file on errors.
struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
    base: u64,
    what: &'a str,
}

impl<'a> Cursor<'a> {
    fn need(&self, n: usize, field: &str) -> Result<()> {
        if self.b.len() - self.pos < n {
            return Err(err!(
                Truncated,
                "{}: {field} needs {n} bytes, the block has {} left",
                self.what,
                self.b.len() - self.pos
            )
            .at(Location::Byte(self.base + 8 + self.pos as u64)));
        }
        Ok(())
    }

    fn bytes(&mut self, n: usize, field: &str) -> Result<&'a [u8]> {
        self.need(n, field)?;
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn u8(&mut self, field: &str) -> Result<u8> {
        Ok(self.bytes(1, field)?[0])
    }

    fn u32(&mut self, field: &str) -> Result<u32> {
        Ok(u32_le(self.bytes(4, field)?, 0))
    }

    fn f64(&mut self, field: &str) -> Result<f64> {
        let b = self.bytes(8, field)?;
        Ok(f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
    }

    /// An integer stored in 1, 2 or 4 bytes as the header's size hint says.
    fn hinted(&mut self, hint: u32, field: &str) -> Result<u32> {
        match hint {
            0 => Ok(u32::from(self.u8(field)?)),
            1 => {
                let b = self.bytes(2, field)?;
                Ok(u32::from(u16::from_le_bytes([b[0], b[1]])))
            }
            2 => self.u32(field),
            _ => Err(err!(Syntax, "{}: size hint 3 in a property header: expected 0, 1 or 2", self.what)
                .at(Location::Byte(self.base + 8 + self.pos as u64))),
        }
    }

    fn offset(&self) -> Location {
        Location::Byte(self.base + 8 + self.pos as u64)
    }

    fn done(&self) -> bool {
        self.pos >= self.b.len()
    }
}

impl<'a> Reader<'a> {
    fn string(&self, (pos, b): (u64, &[u8]), what: &str) -> Result<String> {
        String::from_utf8(b.to_vec()).map_err(|_| err!(Syntax, "{what} is not UTF-8 text").at(Location::Byte(pos + 8)))
    }

    fn indexed_metadata(&self, i: usize, what: &str, at: Location) -> Result<String> {
        self.indexed.get(i).cloned().ok_or_else(|| {
            err!(Syntax, "{what}: metadata index {i}, the archive has {} indexed metadata strings", self.indexed.len())
                .at(at)
        })
    }

    /// The child objects of an object group: (name, metadata, group position).
    fn object_children(&self, kids: &[Child], path: &str) -> Result<Vec<(String, String, u64)>> {
        let Some(&Child::Data(hpos)) = kids.last() else { return Ok(Vec::new()) };
        let b = self.o.data(hpos)?;
        if b.len() <= 32 {
            return Ok(Vec::new());
        }
        // The last 32 bytes are the properties' and the children's hashes.
        let what = format!("object headers of {path}");
        let mut c = Cursor { b: &b[..b.len() - 32], pos: 0, base: hpos, what: &what };
        let mut out = Vec::new();
        while !c.done() {
            let n = c.u32("the name size")? as usize;
            let at = c.offset();
            let name = String::from_utf8(c.bytes(n, "the name")?.to_vec())
                .map_err(|_| err!(Syntax, "{what}: an object name is not UTF-8").at(at.clone()))?;
            if name.is_empty() || name.contains('/') {
                return Err(err!(Syntax, "{what}: object name {name:?}: expected a non-empty name without `/`").at(at));
            }
            let mi = c.u8("the metadata index")?;
            let metadata = if mi == 0xff {
                let n = c.u32("the metadata size")? as usize;
                String::from_utf8_lossy(c.bytes(n, "the metadata")?).into_owned()
            } else {
                self.indexed_metadata(mi as usize, &what, c.offset())?
            };
            let i = out.len() + 1;
            let child_path = if path == "/" { format!("/{name}") } else { format!("{path}/{name}") };
            let g = match kids.get(i) {
                Some(Child::Group(g)) if i + 1 < kids.len() => *g,
                _ => {
                    return Err(err!(
                        Syntax,
                        "object {child_path}: the object group has no group for child {i} (expected the object's group before the headers at byte {hpos})"
                    )
                    .at(Location::Byte(hpos)));
                }
            };
            out.push((name, metadata, g));
        }
        Ok(out)
    }

    /// The sub-properties of a compound property group.
    fn properties(&self, group: u64, depth: usize, path: &str) -> Result<Vec<Prop>> {
        let kids = self.o.tree_group(group, depth)?;
        let Some(&Child::Data(hpos)) = kids.last() else { return Ok(Vec::new()) };
        let b = self.o.data(hpos)?;
        let what = format!("property headers of {path}");
        let mut c = Cursor { b, pos: 0, base: hpos, what: &what };
        let mut out = Vec::new();
        while !c.done() {
            let start = c.offset();
            let info = c.u32("the info word")?;
            let kind = match info & 3 {
                0 => PropKind::Compound,
                1 => PropKind::Scalar,
                _ => PropKind::Array,
            };
            let hint = (info >> 2) & 3;
            let (mut pod, mut extent, mut samples, mut first, mut last, mut ts) = (0u8, 0u8, 0, 0, 0, 0);
            if kind != PropKind::Compound {
                pod = ((info >> 4) & 0xf) as u8;
                if pod as usize >= POD_NAMES.len() {
                    return Err(err!(
                        DType,
                        "{what}: unknown POD type {pod} (expected 0 to 13: bool, integers, float16/32/64, string, wstring)"
                    )
                    .at(start));
                }
                extent = ((info >> 12) & 0xff) as u8;
                samples = c.hinted(hint, "the sample count")?;
                if info & 0x200 != 0 {
                    first = c.hinted(hint, "the first changed index")?;
                    last = c.hinted(hint, "the last changed index")?;
                } else if info & 0x800 != 0 {
                    (first, last) = (0, 0);
                } else {
                    (first, last) = (1, samples.saturating_sub(1));
                }
                if info & 0x100 != 0 {
                    ts = c.hinted(hint, "the time sampling index")?;
                }
            }
            let n = c.hinted(hint, "the name size")? as usize;
            let name = String::from_utf8_lossy(c.bytes(n, "the name")?).into_owned();
            let mi = (info >> 20) & 0xff;
            let metadata = if mi == 0xff {
                let n = c.hinted(hint, "the metadata size")? as usize;
                String::from_utf8_lossy(c.bytes(n, "the metadata")?).into_owned()
            } else {
                self.indexed_metadata(mi as usize, &what, start.clone())?
            };
            let prop_path = format!("{path}/{name}");
            if kind != PropKind::Compound && ts as usize >= self.samplings.len() {
                return Err(
                    err!(Syntax, "{prop_path}: time sampling {ts}, the archive has {}", self.samplings.len()).at(start)
                );
            }
            let group = match kids.get(out.len()) {
                Some(Child::Group(g)) if out.len() + 1 < kids.len() => *g,
                _ => {
                    return Err(err!(
                        Syntax,
                        "{prop_path}: the property group has no group for sub-property {} (expected it before the headers)",
                        out.len()
                    )
                    .at(Location::Byte(hpos)));
                }
            };
            out.push(Prop {
                name,
                kind,
                pod,
                extent,
                samples,
                first_changed: first,
                last_changed: last,
                time_sampling: ts,
                metadata,
                group,
            });
        }
        Ok(out)
    }

    fn time_samplings(pos: u64, b: &[u8]) -> Result<Vec<TimeSampling>> {
        let mut c = Cursor { b, pos: 0, base: pos, what: "time samplings" };
        let mut out = Vec::new();
        while !c.done() {
            // The largest sample count using this sampling: not needed to read the samples.
            c.u32("the sample count")?;
            let tpc = c.f64("the time per cycle")?;
            let n = c.u32("the number of stored times")? as usize;
            // Checked against the block before anything is allocated.
            c.need(n.saturating_mul(8), "the stored times")?;
            let times = (0..n).map(|_| c.f64("a time")).collect::<Result<Vec<_>>>()?;
            out.push(TimeSampling { time_per_cycle: tpc, times });
        }
        Ok(out)
    }
}

/// A property reader: the header and its sample group's children (read once).
struct Samples<'r> {
    prop: Prop,
    kids: Vec<Child>,
    path: String,
    r: &'r Reader<'r>,
}

impl<'r> Samples<'r> {
    fn open(r: &'r Reader<'r>, prop: &Prop, depth: usize, path: String) -> Result<Samples<'r>> {
        let kids = r.o.tree_group(prop.group, depth)?;
        Ok(Samples { prop: prop.clone(), kids, path, r })
    }

    /// The values of sample `k` (after the 16-byte key) and their element count, checked
    /// against the dimensions and the element size. Also the stored index, to spot repeats.
    fn sample(&self, k: u32) -> Result<(&'r [u8], usize, usize)> {
        let p = &self.prop;
        if k >= p.samples {
            return Err(err!(Syntax, "{}: sample {k}, the property has {}", self.path, p.samples));
        }
        let stored = p.stored(k);
        let (di, dims_i) = match p.kind {
            PropKind::Array => (stored * 2, Some(stored * 2 + 1)),
            _ => (stored, None),
        };
        let what = format!("{} sample {k}", self.path);
        let (pos, data) = self.r.o.child_data(self.kids.get(di), &what)?;
        let values = if data.is_empty() {
            data
        } else if data.len() < 16 {
            return Err(err!(
                Truncated,
                "{what}: {} bytes: expected a 16-byte key before the values (or nothing)",
                data.len()
            )
            .at(Location::Byte(pos)));
        } else {
            &data[16..]
        };
        let elem = POD_BYTES[p.pod as usize] * p.extent.max(1) as usize;
        if p.pod >= 12 {
            return Ok((values, values.len(), stored));
        }
        if values.len() % elem != 0 {
            return Err(err!(
                Shape,
                "{what}: {} bytes of values is not a whole number of {} elements ({elem} bytes each)",
                values.len(),
                p.type_name()
            )
            .at(Location::Byte(pos)));
        }
        let n = values.len() / elem;
        if let Some(di) = dims_i {
            let (dpos, dims) = self.r.o.child_data(self.kids.get(di), &format!("{what} dimensions"))?;
            if !dims.is_empty() {
                if dims.len() % 8 != 0 {
                    return Err(err!(Shape, "{what}: dimensions of {} bytes: expected whole u64s", dims.len())
                        .at(Location::Byte(dpos)));
                }
                let total = dims
                    .chunks_exact(8)
                    .try_fold(1u64, |acc, d| acc.checked_mul(u64::from_le_bytes(d.try_into().unwrap_or([0; 8]))));
                if total != Some(n as u64) {
                    return Err(err!(
                        Shape,
                        "{what}: the dimensions hold {} elements, the values {n}",
                        total.map(|t| t.to_string()).unwrap_or_else(|| "more than 2^64".into())
                    )
                    .at(Location::Byte(dpos)));
                }
            }
        }
        Ok((values, n, stored))
    }

    fn expect(&self, pod: u8, extent: u8, kind: PropKind) -> Result<()> {
        if self.prop.pod != pod || self.prop.extent != extent || self.prop.kind != kind {
            return Err(err!(
                DType,
                "{}: {:?} property of {}: expected an {:?} property of {} x{extent}",
                self.path,
                self.prop.kind,
                self.prop.type_name(),
                kind,
                POD_NAMES[pod as usize]
            ));
        }
        Ok(())
    }
}

fn f32s(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
}

fn i32s(b: &[u8]) -> Vec<i32> {
    b.chunks_exact(4).map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
}

/// The rate of a time sampling for `n` samples; `Ok(None)` when it states none.
fn rate_of(ts: &TimeSampling, index: u32, n: usize, path: &str) -> Result<(Option<f64>, Vec<f64>)> {
    let acyclic = ts.time_per_cycle >= f64::MAX / 64.0;
    let spc = ts.times.len();
    if spc == 0 {
        return Err(err!(Syntax, "{path}: time sampling {index} stores no times: expected at least one"));
    }
    if acyclic && spc < n {
        return Err(err!(Syntax, "{path}: acyclic time sampling {index} lists {spc} times for {n} samples"));
    }
    let positive = ts.time_per_cycle.is_finite() && ts.time_per_cycle > 0.0;
    if !acyclic && !positive {
        return Err(err!(
            Syntax,
            "{path}: time sampling {index}: time per cycle {}: expected a positive number",
            ts.time_per_cycle
        ));
    }
    let times: Vec<f64> = (0..n)
        .map(|k| if acyclic { ts.times[k] } else { ts.times[k % spc] + (k / spc) as f64 * ts.time_per_cycle })
        .collect();
    if let Some(t) = times.iter().find(|t| !t.is_finite()) {
        return Err(err!(NonFinite, "{path}: time sampling {index} has the time {t}"));
    }
    if index == 0 {
        // The identity sampling: the writer never set a rate.
        return Ok((None, times));
    }
    // The frame time: the time per cycle over the samples per cycle (uniform: the time per
    // cycle itself), or for acyclic times their mean step; then every time is checked.
    let dt = if !acyclic {
        ts.time_per_cycle / spc as f64
    } else if n >= 2 {
        (times[n - 1] - times[0]) / (n - 1) as f64
    } else {
        return Ok((None, times));
    };
    if dt.is_nan() || dt <= 0.0 {
        return Err(err!(Unsupported, "{path}: the sample times do not increase ({} then {})", times[0], times[n - 1]));
    }
    for (k, t) in times.iter().enumerate() {
        let want = times[0] + k as f64 * dt;
        if (t - want).abs() > 1e-6 * dt {
            return Err(err!(
                Unsupported,
                "{path}: irregular sample times (sample {k} at {t} s, evenly spaced would be {want} s): surfcap plays frame k at k / fps; resample the animation to a constant rate"
            ));
        }
    }
    Ok((Some(snap_rate(1.0 / dt)), times))
}

/// A rate within 1e-9 (relative) of a whole number or of n * 1000/1001 becomes that value.
pub fn snap_rate(r: f64) -> f64 {
    let whole = r.round();
    if whole > 0.0 && (r - whole).abs() <= 1e-9 * r {
        return whole;
    }
    let n = (r * 1001.0 / 1000.0).round();
    let ntsc = n * 1000.0 / 1001.0;
    if n > 0.0 && (r - ntsc).abs() <= 1e-9 * r {
        return ntsc;
    }
    r
}

/// Parses an `.abc` archive held in memory (errors carry a byte offset or an object path).
pub fn parse_abc(bytes: &[u8]) -> Result<AbcArchive> {
    let o = Ogawa::open(bytes)?;
    let root = o.tree_group(o.root, 0)?;
    let kinds = [false, false, true, false, false, false];
    let names = [
        "the Alembic file version",
        "the library version",
        "the top object",
        "the archive metadata",
        "the time samplings",
        "the indexed metadata",
    ];
    for (i, (&group, name)) in kinds.iter().zip(names).enumerate() {
        match root.get(i) {
            Some(c) if c.is_group() == group => {}
            Some(_) => {
                return Err(err!(
                    Syntax,
                    "archive root group child {i} ({name}) should be {}",
                    if group { "a group" } else { "data" }
                )
                .at(Location::Byte(o.root)));
            }
            None => {
                return Err(err!(
                    Syntax,
                    "archive root group has {} children: expected 6 (versions, top object, metadata, time samplings, indexed metadata)",
                    root.len()
                )
                .at(Location::Byte(o.root)));
            }
        }
    }
    let file_len = o.len();
    let mut r = Reader { o, indexed: vec![String::new()], samplings: Vec::new(), file_len };
    let archive_meta = r.string(r.o.child_data(root.get(3), names[3])?, names[3])?;
    let (tpos, tdata) = r.o.child_data(root.get(4), names[4])?;
    r.samplings = Reader::time_samplings(tpos, tdata)?;
    if r.samplings.is_empty() {
        // The reference library always writes the identity sampling first; an archive without
        // it still reads, every property then using that default.
        r.samplings.push(TimeSampling { time_per_cycle: 1.0, times: vec![0.0] });
    }
    let (ipos, idata) = r.o.child_data(root.get(5), names[5])?;
    let mut c = Cursor { b: idata, pos: 0, base: ipos, what: "indexed metadata" };
    while !c.done() {
        let n = c.u8("a metadata size")? as usize;
        r.indexed.push(String::from_utf8_lossy(c.bytes(n, "a metadata string")?).into_owned());
    }
    let Some(&Child::Group(top)) = root.get(2) else {
        return Err(err!(Syntax, "archive root group child 2 (the top object) should be a group"));
    };
    read_objects(&r, top, &archive_meta)
}

struct Walk {
    group: u64,
    path: String,
    metadata: String,
    depth: usize,
    /// Non-identity Xforms above, outermost first.
    xforms: Vec<String>,
}

/// The inverse of surfcap's `abc::metadata_value`: `%3B`, `%3D` and `%25` back to `;`, `=`
/// and `%` (anything else is kept as written).
pub fn metadata_unescape(s: &str) -> String {
    s.replace("%3B", ";").replace("%3D", "=").replace("%25", "%")
}

fn read_objects(r: &Reader, top: u64, archive_meta: &str) -> Result<AbcArchive> {
    let mut notes = Vec::new();
    let surfcap_up = meta_get(archive_meta, "surfcap_up_axis");
    let up_axis = match surfcap_up {
        Some(u) => Some(
            UpAxis::parse(u).map_err(|e| err!(Metadata, "archive metadata surfcap_up_axis={u:?}: {}", e.message))?,
        ),
        None => {
            notes.push("no surfcap_up_axis in the archive metadata: +y assumed (Alembic's convention)".to_string());
            Some(UpAxis::PosY)
        }
    };
    let units = match meta_get(archive_meta, "surfcap_units") {
        // surfcap's writer records the name and, when known, the scale (`surfcap_metres_per_unit`):
        // the name alone may not say it ("0.5 m"), nor the scale the name ("metres" or "m").
        Some(u) => Some(match meta_get(archive_meta, "surfcap_metres_per_unit") {
            Some(m) => match m.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Units { name: metadata_unescape(u), metres_per_unit: Some(v) },
                _ => {
                    return Err(err!(
                        Metadata,
                        "archive metadata surfcap_metres_per_unit={m:?}: expected a positive number of metres"
                    ));
                }
            },
            None => Units::parse(&metadata_unescape(u)),
        }),
        None => {
            notes.push("no surfcap_units in the archive metadata: units unknown (Alembic does not record them)".into());
            None
        }
    };
    let mut meshes = Vec::new();
    let mut noted_xforms = HashSet::new();
    let mut stack =
        vec![Walk { group: top, path: "/".into(), metadata: archive_meta.into(), depth: 0, xforms: vec![] }];
    // Depth first, children in file order (the stack takes them reversed).
    while let Some(w) = stack.pop() {
        let kids = r.o.tree_group(w.group, w.depth)?;
        let schema = meta_get(&w.metadata, "schema").unwrap_or("");
        let mut xforms = w.xforms.clone();
        let props = |r: &Reader| -> Result<Vec<Prop>> {
            match kids.first() {
                Some(Child::Group(g)) if kids.len() >= 2 => r.properties(*g, w.depth + 1, &w.path),
                _ => Ok(Vec::new()),
            }
        };
        let mut is_mesh = false;
        if w.path != "/" {
            match schema {
                "AbcGeom_PolyMesh_v1" | "AbcGeom_SubD_v1" => is_mesh = true,
                "AbcGeom_Xform_v3" => {
                    let top_props = props(r)?;
                    if let Some(x) = top_props.iter().find(|p| p.name == ".xform" && p.kind == PropKind::Compound) {
                        let sub = r.properties(x.group, w.depth + 2, &format!("{}/.xform", w.path))?;
                        if sub.iter().any(|p| p.name == "isNotConstantIdentity") {
                            xforms.push(w.path.clone());
                        }
                    }
                }
                "" => {}
                other => notes.push(format!("{} ({other}) skipped: only PolyMesh and SubD objects are read", w.path)),
            }
        }
        if is_mesh {
            if schema == "AbcGeom_SubD_v1" {
                notes.push(format!("{}: a SubD surface, read as its control mesh (not subdivided)", w.path));
            }
            let parent = w.path.rsplit_once('/').map(|(p, _)| if p.is_empty() { "/" } else { p }).unwrap_or("/");
            for x in &xforms {
                if surfcap_up.is_some() && x == parent {
                    continue; // surfcap's writer puts the up-axis rotation on the sequence Xform.
                }
                if noted_xforms.insert(x.clone()) {
                    notes.push(format!(
                        "the transform of {x} is ignored: points are read in the mesh's own coordinates"
                    ));
                }
            }
            let top_props = props(r)?;
            let geom = top_props
                .iter()
                .find(|p| p.name == ".geom" && p.kind == PropKind::Compound)
                .ok_or_else(|| err!(Syntax, "{}: a {schema} object without its .geom compound property", w.path))?;
            if let Some(m) = read_mesh(r, &w.path, geom, w.depth + 2, &mut notes)? {
                meshes.push(m);
            }
        }
        for (name, metadata, g) in r.object_children(&kids, &w.path)?.into_iter().rev() {
            let path = if w.path == "/" { format!("/{name}") } else { format!("{}/{name}", w.path) };
            stack.push(Walk { group: g, path, metadata, depth: w.depth + 1, xforms: xforms.clone() });
        }
    }
    if meshes.is_empty() {
        return Err(err!(Empty, "no PolyMesh object with samples in this archive: expected at least one mesh"));
    }
    // Names: the path without its leading `/` and a last component `mesh`; colliding names
    // keep their full paths.
    let names: Vec<String> = meshes.iter().map(|m| name_of(&m.path)).collect();
    let mut uses = std::collections::HashMap::<&str, usize>::new();
    for n in &names {
        *uses.entry(n).or_default() += 1;
    }
    let full: Vec<bool> = names.iter().map(|n| uses[n.as_str()] > 1).collect();
    for ((m, n), f) in meshes.iter_mut().zip(names.iter()).zip(full) {
        m.name = if f { m.path.trim_start_matches('/').to_string() } else { n.clone() };
    }
    // One frame rate, one topology.
    let mut fps: Option<(f64, &str)> = None;
    for m in &meshes {
        if let Some(f) = m.fps {
            match fps {
                None => fps = Some((f, &m.path)),
                Some((g, p)) if g != f => {
                    return Err(err!(
                        Metadata,
                        "meshes {p} and {} play at different rates ({g} and {f} fps): one subject has one frame rate",
                        m.path
                    ));
                }
                _ => {}
            }
        }
    }
    let mut fps = fps.map(|f| f.0);
    // surfcap's writer records the rate in its shortest exact form (`surfcap_fps`): 1 / (1 / fps)
    // is not always fps in floating point. It is used when the sampling agrees with it.
    if let (Some(f), Some(text)) = (fps, meta_get(archive_meta, "surfcap_fps")) {
        match text.parse::<f64>() {
            Ok(exact) if exact > 0.0 && (exact - f).abs() <= 1e-9 * exact => fps = Some(exact),
            _ => notes.push(format!(
                "archive metadata surfcap_fps={text:?} does not match the sampling's {f} fps: the sampling's rate is used"
            )),
        }
    }
    if fps.is_none() {
        notes.push("no time sampling on the meshes (the default of one second per sample): pass --fps".into());
    }
    Ok(AbcArchive { meshes, fps, up_axis, units, notes })
}

impl AbcArchive {
    /// Why the meshes cannot be one subject's sequences: two meshes of constant topology differ
    /// (a mesh whose own topology changes is reported by [`AbcMesh::topology_change`]). Such an
    /// archive imports as a frame set.
    pub fn topology_mismatch(&self) -> Option<String> {
        let mut constant = self.meshes.iter().filter_map(|m| match &m.frames {
            AbcFrames::Constant { topology, .. } => Some((m, topology)),
            AbcFrames::Varying { .. } => None,
        });
        let (first, t0) = constant.next()?;
        constant.find_map(|(m, t)| {
            t0.first_difference(t).map(|d| {
                format!(
                    "meshes {} and {} differ in topology ({d}): one subject needs one topology (import them separately, or as a frame set: -o x.frames)",
                    first.path, m.path
                )
            })
        })
    }
}

fn name_of(path: &str) -> String {
    let mut parts: Vec<&str> = path.split('/').filter(|s| !s.is_empty()).collect();
    if parts.len() > 1 && parts.last() == Some(&"mesh") {
        parts.pop();
    }
    parts.join("/")
}

/// Builds one sample's topology: polygons reversed to counter-clockwise and fan-triangulated
/// (see the module documentation), UVs by their scope.
fn build_topology(
    counts: &[i32],
    indices: &[i32],
    n_points: usize,
    uv: Option<&UvSample>,
    at: &str,
    notes: &mut Vec<String>,
) -> Result<Topology> {
    let mut total: usize = 0;
    for (f, &c) in counts.iter().enumerate() {
        if c < 3 {
            let why = if c < 0 { "a negative count" } else { "fewer than 3 corners" };
            return Err(err!(
                DegenerateFace,
                "{at}: .faceCounts: face {f} has {c} corners ({why}): expected 3 or more"
            ));
        }
        total = total.saturating_add(c as usize);
    }
    if total != indices.len() {
        return Err(err!(
            Shape,
            "{at}: .faceCounts add up to {total} corners, .faceIndices has {}: expected them equal",
            indices.len()
        ));
    }
    if let Some((k, &v)) = indices.iter().enumerate().find(|(_, v)| **v < 0 || **v as usize >= n_points) {
        return Err(err!(
            IndexOutOfRange,
            "{at}: .faceIndices[{k}] = {v}: expected 0 to {} (P has {n_points} points)",
            n_points as i64 - 1
        ));
    }
    // Reverse each polygon (Alembic is clockwise), fan from the reversed polygon's first corner.
    let mut tris = Vec::with_capacity(indices.len());
    let mut corners_fv = Vec::with_capacity(indices.len());
    let mut base = 0usize;
    for &c in counts {
        let c = c as usize;
        let rev = |j: usize| base + c - 1 - j;
        for k in 1..c - 1 {
            let fv = [rev(0), rev(k), rev(k + 1)];
            tris.push(fv.map(|i| indices[i] as u32));
            corners_fv.push(fv);
        }
        base += c;
    }
    let uv = uv.and_then(|u| {
        let lookup = |i: usize| -> Option<u32> {
            let j = match &u.indices {
                Some(ix) => *ix.get(i)? as usize,
                None => i,
            };
            (j < u.coords.len()).then_some(j as u32)
        };
        let corners: Option<Vec<[u32; 3]>> = if u.face_varying {
            corners_fv.iter().map(|fv| Some([lookup(fv[0])?, lookup(fv[1])?, lookup(fv[2])?])).collect()
        } else {
            tris.iter()
                .map(|t| Some([lookup(t[0] as usize)?, lookup(t[1] as usize)?, lookup(t[2] as usize)?]))
                .collect()
        };
        if corners.is_none() {
            notes.push(format!("{at}: uv does not fit its scope: UVs dropped"));
        }
        corners.map(|corners| UvAtlas { coords: u.coords.clone(), corners })
    });
    Topology::new(n_points, tris, uv).map_err(|e: Error| {
        let loc = match e.location {
            Some(Location::Face(i)) => format!(" (triangle {i})"),
            _ => String::new(),
        };
        err!(DegenerateFace, "{at}: {}{loc}", e.message)
    })
}

struct UvSample {
    coords: Vec<[f32; 2]>,
    indices: Option<Vec<u32>>,
    face_varying: bool,
}

/// The `uv` geometry parameter: `(values, indices)` readers and whether it is face-varying;
/// `None` (with a note) when it cannot be used.
fn uv_param<'r>(
    r: &'r Reader<'r>,
    props: &[Prop],
    geom_path: &str,
    depth: usize,
    notes: &mut Vec<String>,
) -> Result<Option<(Samples<'r>, Option<Samples<'r>>, bool)>> {
    let Some(uv) = props.iter().find(|p| p.name == "uv") else { return Ok(None) };
    let path = format!("{geom_path}/uv");
    let scope = meta_get(&uv.metadata, "geoScope").unwrap_or("fvr");
    let face_varying = match scope {
        "fvr" => true,
        "vtx" | "var" => false,
        s => {
            notes.push(format!("{path}: scope {s:?} (not per corner or per vertex): UVs dropped"));
            return Ok(None);
        }
    };
    let (vals, idx) = match uv.kind {
        PropKind::Array => (Samples::open(r, uv, depth, path.clone())?, None),
        PropKind::Compound => {
            let sub = r.properties(uv.group, depth, &path)?;
            let Some(v) = sub.iter().find(|p| p.name == ".vals") else {
                notes.push(format!("{path}: indexed UVs without .vals: UVs dropped"));
                return Ok(None);
            };
            let vals = Samples::open(r, v, depth + 1, format!("{path}/.vals"))?;
            let idx = match sub.iter().find(|p| p.name == ".indices") {
                Some(i) => Some(Samples::open(r, i, depth + 1, format!("{path}/.indices"))?),
                None => None,
            };
            (vals, idx)
        }
        PropKind::Scalar => {
            notes.push(format!("{path}: a scalar property: UVs dropped"));
            return Ok(None);
        }
    };
    if vals.expect(FLOAT32, 2, PropKind::Array).is_err()
        || idx.as_ref().is_some_and(|i| i.expect(UINT32, 1, PropKind::Array).is_err())
    {
        notes.push(format!("{path}: {}: expected float32 pairs (uint32 indices): UVs dropped", vals.prop.type_name()));
        return Ok(None);
    }
    if vals.prop.samples == 0 {
        return Ok(None);
    }
    Ok(Some((vals, idx, face_varying)))
}

fn uv_sample(vals: &Samples, idx: Option<&Samples>, k: u32) -> Result<UvSample> {
    let kv = k.min(vals.prop.samples - 1);
    let (b, _, _) = vals.sample(kv)?;
    let coords = f32s(b).chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    let indices = match idx {
        Some(i) if i.prop.samples > 0 => {
            let (b, _, _) = i.sample(k.min(i.prop.samples - 1))?;
            Some(b.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
        }
        _ => None,
    };
    Ok(UvSample { coords, indices, face_varying: true })
}

/// Reads one PolyMesh's `.geom` compound; `None` (with a note) when it has no samples.
fn read_mesh(r: &Reader, path: &str, geom: &Prop, depth: usize, notes: &mut Vec<String>) -> Result<Option<AbcMesh>> {
    let geom_path = format!("{path}/.geom");
    let props = r.properties(geom.group, depth, &geom_path)?;
    let find = |name: &str| props.iter().find(|p| p.name == name);
    let open = |name: &str| -> Result<Samples> {
        let p = find(name).ok_or_else(|| {
            err!(Syntax, "{path}: the mesh has no {name} property: expected P, .faceIndices and .faceCounts")
        })?;
        Samples::open(r, p, depth + 1, format!("{path}/.geom/{name}"))
    };
    let p = open("P")?;
    p.expect(FLOAT32, 3, PropKind::Array)?;
    let n = p.prop.samples as usize;
    if n == 0 {
        notes.push(format!("{path}: no samples: skipped"));
        return Ok(None);
    }
    if n as u64 > r.file_len {
        return Err(err!(
            Shape,
            "{path}: P declares {n} samples in a file of {} bytes: refused (a sample count above the file's length)",
            r.file_len
        ));
    }
    let fi = open(".faceIndices")?;
    fi.expect(INT32, 1, PropKind::Array)?;
    let fc = open(".faceCounts")?;
    fc.expect(INT32, 1, PropKind::Array)?;
    for s in [&fi, &fc] {
        if s.prop.samples as usize != n && s.prop.samples != 1 {
            return Err(err!(
                Shape,
                "{}: {} samples, P has {n}: expected one per sample (or a single one)",
                s.path,
                s.prop.samples
            ));
        }
    }
    let ts_index = p.prop.time_sampling;
    let ts = &r.samplings[ts_index as usize];
    let (fps, times) = rate_of(ts, ts_index, n, path)?;
    if find("N").is_some() {
        notes.push(format!("{path}: normals ignored (surfcap computes its own)"));
    }
    let uv = uv_param(r, &props, &geom_path, depth + 1, notes)?;
    let name = name_of(path);
    let cap = 16u64.saturating_mul(r.file_len).saturating_add(256 << 20);
    // Frames: a new topology only when the faces or the point count change.
    struct Current<'b> {
        topology: Topology,
        faces: usize,
        fib: &'b [u8],
        fcb: &'b [u8],
    }
    let same_bytes = |a: &[u8], b: &[u8]| std::ptr::eq(a, b) || a == b;
    let mut positions: Vec<f32> = Vec::new();
    let mut frames: Vec<AbcFrame> = Vec::new();
    let mut current: Option<Current> = None;
    let mut varying = false;
    let mut total: u64 = 0;
    for k in 0..n as u32 {
        let at = format!("{path} sample {k} (frame {name}:{k})");
        let (pb, np, _) = p.sample(k)?;
        total = total.saturating_add(pb.len() as u64);
        if total > cap {
            return Err(err!(
                Shape,
                "{at}: the positions read reach {total} bytes from a file of {} bytes: refused (samples repeated too often)",
                r.file_len
            ));
        }
        let pts = f32s(pb);
        if let Some((i, v)) = pts.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(err!(NonFinite, "{at}: P: point {} has the coordinate {v}", i / 3));
        }
        let (fib, _, _) = fi.sample(k.min(fi.prop.samples - 1))?;
        let (fcb, _, _) = fc.sample(k.min(fc.prop.samples - 1))?;
        let same = current
            .as_ref()
            .is_some_and(|c| c.topology.n_vertices() == np && same_bytes(c.fib, fib) && same_bytes(c.fcb, fcb));
        let cur = match current.take() {
            Some(c) if same => c,
            prev => {
                let counts = i32s(fcb);
                let indices = i32s(fib);
                let uvs = match &uv {
                    Some((vals, idx, fv)) => {
                        let mut s = uv_sample(vals, idx.as_ref(), k)?;
                        s.face_varying = *fv;
                        Some(s)
                    }
                    None => None,
                };
                let topology = build_topology(&counts, &indices, np, uvs.as_ref(), &at, notes)?;
                if let Some(prev) = prev.filter(|_| !varying) {
                    // Every earlier frame had the previous (first) topology.
                    varying = true;
                    let nv = prev.topology.n_vertices() * 3;
                    frames = positions
                        .chunks_exact(nv)
                        .map(|c| AbcFrame { topology: prev.topology.clone(), positions: c.to_vec(), faces: prev.faces })
                        .collect();
                    positions = Vec::new();
                }
                Current { topology, faces: counts.len(), fib, fcb }
            }
        };
        if varying {
            // Each varying frame holds its own copy of its topology: counted against the cap too.
            let t = &cur.topology;
            total = total.saturating_add(12 * t.n_triangles() as u64 * if t.uv().is_some() { 2 } else { 1 });
            if total > cap {
                return Err(err!(
                    Shape,
                    "{path} sample {k}: the frames read reach {total} bytes from a file of {} bytes: refused (samples repeated too often)",
                    r.file_len
                ));
            }
            frames.push(AbcFrame { topology: cur.topology.clone(), positions: pts, faces: cur.faces });
        } else if positions.is_empty() {
            positions = pts;
        } else {
            positions.extend_from_slice(&pts);
        }
        current = Some(cur);
    }
    if let Some((vals, _, _)) = &uv
        && !varying
        && vals.prop.samples > 1
        && vals.prop.first_changed != 0
    {
        notes.push(format!("{path}: animated UVs: the first sample's are kept"));
    }
    // Labels.
    let mut labels = None;
    if let Some(arb) = find(".arbGeomParams").filter(|p| p.kind == PropKind::Compound) {
        let arb_path = format!("{geom_path}/.arbGeomParams");
        let sub = r.properties(arb.group, depth + 1, &arb_path)?;
        if let Some(lp) = sub.iter().find(|p| p.name == "surfcap_synthetic") {
            let s = Samples::open(r, lp, depth + 2, format!("{arb_path}/surfcap_synthetic"))?;
            if s.prop.pod != UINT8 || s.prop.extent != 1 || s.prop.kind == PropKind::Compound {
                return Err(err!(
                    DType,
                    "{}: {}: expected uint8 labels (0 original, 1 synthetic)",
                    s.path,
                    s.prop.type_name()
                ));
            }
            if s.prop.samples as usize != n {
                return Err(err!(
                    Metadata,
                    "{}: {} samples, P has {n}: expected one label per frame",
                    s.path,
                    s.prop.samples
                ));
            }
            let mut ls = Vec::with_capacity(n);
            for k in 0..n as u32 {
                let (b, _, _) = s.sample(k)?;
                ls.push(match b {
                    [0] => FrameLabel::Original,
                    [1] => FrameLabel::Synthetic,
                    _ => {
                        return Err(err!(
                            Metadata,
                            "{} sample {k} (frame {name}:{k}): {:?}: expected one value, 0 (original) or 1 (synthetic)",
                            s.path,
                            b
                        ));
                    }
                });
            }
            labels = Some(ls);
        }
    }
    let frames = match current {
        Some(c) if !varying => AbcFrames::Constant { topology: c.topology, positions },
        _ => AbcFrames::Varying { frames },
    };
    let velocities = match (find(".velocities"), &frames) {
        (None, _) => None,
        (Some(_), AbcFrames::Varying { .. }) => {
            notes.push(format!("{path}: velocities ignored (the topology changes between samples)"));
            None
        }
        (Some(_), AbcFrames::Constant { topology, .. }) => {
            Some(read_velocities(&open(".velocities")?, n, topology.n_vertices(), &name, r.file_len)?)
        }
    };
    Ok(Some(AbcMesh { path: path.to_string(), name, frames, times, fps, labels, velocities }))
}

/// The `.velocities` samples of a mesh of `n` frames and `vertices` points: one f32 x 3 per
/// point per frame (a single stored sample answers for every frame), finite.
fn read_velocities(s: &Samples, n: usize, vertices: usize, name: &str, file_len: u64) -> Result<Vec<f32>> {
    if s.prop.pod != FLOAT32 || s.prop.extent != 3 || s.prop.kind != PropKind::Array {
        return Err(err!(
            DType,
            "{}: {:?} property of {}: expected an array of float32 x3 (units per second)",
            s.path,
            s.prop.kind,
            s.prop.type_name()
        ));
    }
    if s.prop.samples as usize != n && s.prop.samples != 1 {
        return Err(err!(Shape, "{}: {} samples, P has {n}: expected one per sample", s.path, s.prop.samples));
    }
    if (n as u64).saturating_mul(vertices as u64 * 12) > 16u64.saturating_mul(file_len).saturating_add(256 << 20) {
        return Err(err!(
            Shape,
            "{}: {n} samples of {vertices} points from a file of {file_len} bytes: refused",
            s.path
        ));
    }
    let mut out = Vec::with_capacity(n * vertices * 3);
    for k in 0..n as u32 {
        let (b, count, _) = s.sample(k.min(s.prop.samples - 1))?;
        if count != vertices {
            return Err(err!(
                Shape,
                "{} sample {k} (frame {name}:{k}): {count} velocities: expected one per point ({vertices})",
                s.path
            ));
        }
        let v = f32s(b);
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(err!(
                NonFinite,
                "{} sample {k} (frame {name}:{k}): point {} has the velocity {x}",
                s.path,
                i / 3
            ));
        }
        out.extend_from_slice(&v);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ogawa_read::tests::Builder;
    use surfcap_mesh::error::ErrorKind;

    const DATA: u64 = 1 << 63;

    fn le_f32(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn le_i32(v: &[i32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    /// A property header with 1-byte sizes: kind 0 compound, 1 scalar, 2 array.
    fn header(kind: u32, pod: u32, extent: u32, samples: u8, name: &str) -> Vec<u8> {
        let mut info = kind;
        let mut h = Vec::new();
        if kind != 0 {
            info |= pod << 4 | 1 << 8 | extent << 12;
            h.push(samples);
            h.push(1); // time sampling 1
        }
        let mut out = info.to_le_bytes().to_vec();
        out.extend(h);
        out.push(name.len() as u8);
        out.extend(name.as_bytes());
        out
    }

    /// An array property's group: each sample a 16-byte key and its values, no dimensions.
    fn array_group(b: &mut Builder, samples: &[Vec<u8>]) -> u64 {
        let mut kids = Vec::new();
        for s in samples {
            let mut d = vec![7u8; 16];
            d.extend(s);
            kids.push(b.data(&d));
            kids.push(DATA);
        }
        b.group(&kids)
    }

    /// An archive with one PolyMesh `/walk/mesh` under an Xform `/walk`, one sample per entry
    /// of `points` (faces constant), at 30 fps; `extra` property headers are appended to .geom
    /// with empty groups.
    fn archive(counts: &[i32], indices: &[i32], points: &[Vec<f32>], extra: &[Vec<u8>]) -> Vec<u8> {
        let mut b = Builder::new();
        let n = points.len() as u8;
        let pg = array_group(&mut b, &points.iter().map(|p| le_f32(p)).collect::<Vec<_>>());
        let fig = array_group(&mut b, &[le_i32(indices)]);
        let fcg = array_group(&mut b, &[le_i32(counts)]);
        let mut geom_headers = header(2, 10, 3, n, "P");
        // The faces are stored once: the header's "same over all samples" flag (0x800).
        for name in [".faceIndices", ".faceCounts"] {
            let mut h = header(2, 6, 1, n, name);
            h[1] |= 0x08;
            geom_headers.extend(h);
        }
        let mut geom_kids = vec![pg, fig, fcg];
        for e in extra {
            geom_headers.extend(e);
            geom_kids.push(0);
        }
        geom_kids.push(b.data(&geom_headers));
        let geom = b.group(&geom_kids);
        let top_headers = header(0, 0, 0, 0, ".geom");
        let hd = b.data(&top_headers);
        let mesh_props = b.group(&[geom, hd]);
        let no_children = b.data(&[0u8; 32]);
        let mesh = b.group(&[mesh_props, no_children]);
        let obj_headers = |name: &str, md: u8| {
            let mut h = (name.len() as u32).to_le_bytes().to_vec();
            h.extend(name.as_bytes());
            h.push(md);
            h.extend([0u8; 32]);
            h
        };
        let mh = b.data(&obj_headers("mesh", 1));
        let walk = b.group(&[0, mesh, mh]);
        let wh = b.data(&obj_headers("walk", 2));
        let top = b.group(&[0, walk, wh]);
        let v = b.data(&9i32.to_le_bytes());
        let meta = b.data(b"surfcap_up_axis=+z");
        let mut ts = Vec::new();
        for (tpc, max) in [(1.0f64, 1u32), (1.0 / 30.0, u32::from(n))] {
            ts.extend(max.to_le_bytes());
            ts.extend(tpc.to_le_bytes());
            ts.extend(1u32.to_le_bytes());
            ts.extend(0f64.to_le_bytes());
        }
        let tsd = b.data(&ts);
        let mut md = Vec::new();
        for m in ["schema=AbcGeom_PolyMesh_v1", "schema=AbcGeom_Xform_v3"] {
            md.push(m.len() as u8);
            md.extend(m.as_bytes());
        }
        let mdd = b.data(&md);
        let root = b.group(&[v, v, top, meta, tsd, mdd]);
        b.finish(root)
    }

    const QUAD: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];

    fn error(bytes: &[u8]) -> Error {
        match parse_abc(bytes) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        }
    }

    /// A quad stored clockwise seen from +Z (Alembic's order) becomes two counter-clockwise
    /// triangles (normals to +Z), fanned from the reversed polygon's first corner.
    #[test]
    fn a_hand_built_archive_reads_with_clockwise_faces_reversed() {
        let p2: Vec<f32> = QUAD.iter().map(|x| x + 0.5).collect();
        let a = parse_abc(&archive(&[4], &[0, 3, 2, 1], &[QUAD.to_vec(), p2.clone(), QUAD.to_vec()], &[])).unwrap();
        assert_eq!(a.fps, Some(30.0));
        assert_eq!(a.up_axis, Some(UpAxis::PosZ));
        let m = &a.meshes[0];
        assert_eq!((m.path.as_str(), m.name.as_str()), ("/walk/mesh", "walk"));
        assert_eq!(m.times, [0.0, 1.0 / 30.0, 2.0 / 30.0]);
        let AbcFrames::Constant { topology, positions } = &m.frames else { panic!("constant") };
        assert_eq!(topology.triangles(), [[1, 2, 3], [1, 3, 0]]);
        for t in topology.triangles() {
            let p = |i: u32| [QUAD[3 * i as usize], QUAD[3 * i as usize + 1]];
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(z > 0.0, "triangle {t:?} faces -Z");
        }
        assert_eq!(positions[12..24], p2[..]);
        assert_eq!(positions.len(), 36);
    }

    #[test]
    fn bad_faces_are_refused_with_the_object_path_and_sample() {
        let e = error(&archive(&[4], &[0, 3, 2, 9], &[QUAD.to_vec()], &[]));
        assert_eq!(e.kind, ErrorKind::IndexOutOfRange);
        assert_eq!(
            e.to_string(),
            "/walk/mesh sample 0 (frame walk:0): .faceIndices[3] = 9: expected 0 to 3 (P has 4 points)"
        );
        let e = error(&archive(&[-4], &[0, 3, 2, 1], &[QUAD.to_vec()], &[]));
        assert!(e.to_string().contains(".faceCounts: face 0 has -4 corners (a negative count)"), "{e}");
        let e = error(&archive(&[3], &[0, 3, 2, 1], &[QUAD.to_vec()], &[]));
        assert!(e.to_string().contains(".faceCounts add up to 3 corners, .faceIndices has 4"), "{e}");
    }

    #[test]
    fn an_unknown_pod_type_names_the_byte_offset() {
        let mut bad = header(2, 10, 3, 1, "weird");
        bad[0] = 0xf2; // array of POD 15
        let bytes = archive(&[4], &[0, 3, 2, 1], &[QUAD.to_vec()], &[bad]);
        let e = error(&bytes);
        assert_eq!(e.kind, ErrorKind::DType);
        assert!(e.to_string().contains("property headers of /walk/mesh/.geom: unknown POD type 15"), "{e}");
        let Some(Location::Byte(at)) = e.location else { panic!("{e:?}") };
        assert_eq!(u32::from_le_bytes(bytes[at as usize..at as usize + 4].try_into().unwrap()) & 0xff, 0xf2);
    }

    #[test]
    fn truncation_anywhere_is_an_error_never_a_panic() {
        let bytes = archive(&[4], &[0, 3, 2, 1], &[QUAD.to_vec(), QUAD.to_vec()], &[]);
        for n in 0..bytes.len() {
            assert!(parse_abc(&bytes[..n]).is_err(), "a file cut at {n} bytes was read");
        }
        // Every single byte flipped: an error or a result, never a panic.
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0xff;
            let _ = parse_abc(&b);
        }
    }

    #[test]
    fn deep_nesting_is_refused() {
        let mut b = Builder::new();
        let hash = [0u8; 32];
        let hd0 = b.data(&hash);
        let mut child = b.group(&[0, hd0]);
        for _ in 0..300 {
            let mut h = 1u32.to_le_bytes().to_vec();
            h.extend(b"x");
            h.push(0);
            h.extend(hash);
            let hd = b.data(&h);
            child = b.group(&[0, child, hd]);
        }
        let v = b.data(&9i32.to_le_bytes());
        let root = b.group(&[v, v, child, DATA, DATA, DATA]);
        let e = error(&b.finish(root));
        assert!(e.to_string().contains("nested 257 levels deep: at most 256 are read"), "{e}");
    }

    #[test]
    fn rates_snap_and_irregular_times_are_refused() {
        assert_eq!(snap_rate(1.0 / (1.0 / 30.0)), 30.0);
        assert_eq!(snap_rate(1.0 / (1001.0 / 24000.0)), 24000.0 / 1001.0);
        assert_eq!(snap_rate(1.0 / (1001.0 / 60000.0)), 60000.0 / 1001.0);
        assert_eq!(snap_rate(12.5), 12.5);
        let acyclic = |times: Vec<f64>| TimeSampling { time_per_cycle: f64::MAX / 32.0, times };
        let (fps, _) = rate_of(&acyclic(vec![1.0, 1.04, 1.08]), 1, 3, "/m").unwrap();
        assert_eq!(fps, Some(25.0));
        let e = rate_of(&acyclic(vec![0.0, 0.04, 0.1]), 1, 3, "/m").unwrap_err();
        assert!(e.to_string().starts_with("/m: irregular sample times (sample 1 at 0.04 s"), "{e}");
        let cyclic = TimeSampling { time_per_cycle: 0.1, times: vec![0.0, 0.05] };
        assert_eq!(rate_of(&cyclic, 1, 4, "/m").unwrap(), (Some(20.0), vec![0.0, 0.05, 0.1, 0.15000000000000002]));
        let identity = TimeSampling { time_per_cycle: 1.0, times: vec![0.0] };
        assert_eq!(rate_of(&identity, 0, 2, "/m").unwrap().0, None);
    }
}

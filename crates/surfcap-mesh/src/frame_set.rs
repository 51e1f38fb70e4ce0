//! Frame sets: the input of Huang et al. 2009 ("Human motion synthesis from 3D video", CVPR;
//! `../shared/papers/huang2009-human-motion-synthesis-from-3d-video.txt`), whose surface motion
//! graph works on raw per-frame reconstructions, "an unstructured volumetric or mesh
//! approximation of the surface shape at each frame without temporal correspondence" (section
//! 1), "different mesh connectivity at each time-frame" (section 5): every frame has its own
//! vertices and triangles.
//!
//! A [`FrameSet`] is the counterpart of a [`Subject`] without the shared [`Topology`]: named
//! sequences of [`Frame`]s (each its own topology and f32 positions), frame labels, tags, fps, up
//! axis and units. Frames are named `sequence:frame` through the same [`FrameIndex`] as a
//! subject's, so every layer names them as the user does. A subject converts to a frame set
//! ([`FrameSet::from_subject`]) and back when every frame happens to share one topology
//! ([`FrameSet::into_subject`]).
//!
//! Validation happens on construction (never a frame set that breaks these): every face index
//! in range and no face repeating a vertex ([`Topology::new`]), one position triple per vertex,
//! every coordinate finite, at least one frame per sequence and one sequence per set, unique
//! sequence names, a positive frame rate. Unused vertices are allowed (raw reconstructions
//! have them, and they harm nothing downstream that looks at triangles).

use crate::error::{Location, Result, err};
use crate::frame_index::FrameIndex;
use crate::subject::{FrameLabel, Sequence, Subject, Units, UpAxis};
use crate::topology::Topology;

/// One frame of a frame set: its own triangles and its own vertex positions.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    topology: Topology,
    /// `[vertices][3]` f32.
    positions: Vec<f32>,
}

impl Frame {
    /// A frame; `positions` holds `3 * topology.n_vertices()` finite numbers.
    pub fn new(topology: Topology, positions: Vec<f32>) -> Result<Self> {
        let nv = topology.n_vertices();
        if positions.len() != 3 * nv {
            return Err(err!(
                Shape,
                "{} coordinates for {nv} vertices: expected {} (3 per vertex)",
                positions.len(),
                3 * nv
            ));
        }
        if let Some(k) = positions.iter().position(|x| !x.is_finite()) {
            return Err(err!(
                NonFinite,
                "vertex {} has a non-finite coordinate ({}): expected finite numbers",
                k / 3,
                positions[k]
            ));
        }
        Ok(Frame { topology, positions })
    }

    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// Positions `[vertices][3]`.
    pub fn positions(&self) -> &[f32] {
        &self.positions
    }

    pub fn n_vertices(&self) -> usize {
        self.topology.n_vertices()
    }

    pub fn n_triangles(&self) -> usize {
        self.topology.n_triangles()
    }

    /// The topology and positions, moved out.
    pub fn into_parts(self) -> (Topology, Vec<f32>) {
        (self.topology, self.positions)
    }
}

/// One named sequence of a frame set: frames with their own topologies, one label per frame,
/// tags, and optionally the known answer of a synthetic frame set (see [`Correspondence`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSetSequence {
    pub name: String,
    pub tags: Vec<String>,
    frames: Vec<Frame>,
    labels: Vec<FrameLabel>,
    correspondence: Option<Correspondence>,
}

/// Where each vertex of each frame lies on a source surface: the known answer of a frame set
/// made by re-meshing the frames of a shared-topology subject (`surfcap remesh-frames`). For
/// vertex `v` of frame `f`, `rows[v]` of that frame's block is `[t, b0, b1, b2]`: `t` a triangle
/// of the source subject's topology (an integer stored in f64, exact below 2^53) and the
/// barycentric coordinates, so the vertex is `b0 p[t0] + b1 p[t1] + b2 p[t2]` with `p` the source
/// frame's positions (up to the f32 rounding of the stored position).
#[derive(Debug, Clone, PartialEq)]
pub struct Correspondence {
    /// `[vertices of all frames, in frame order][4]`.
    pub rows: Vec<f64>,
}

impl FrameSetSequence {
    /// A sequence of original frames; at least one.
    pub fn new(name: impl Into<String>, frames: Vec<Frame>) -> Result<Self> {
        let name = name.into();
        if frames.is_empty() {
            return Err(err!(Empty, "sequence {name:?} has no frames: expected at least one"));
        }
        // Texture coordinates for every frame or for none, so that the `.frames` folder can
        // keep them in one array per sequence (a reader that meets a mix strips them, saying so).
        if let Some(f) = frames.iter().position(|fr| fr.topology.uv().is_some() != frames[0].topology.uv().is_some()) {
            let has = |k: usize| if frames[k].topology.uv().is_some() { "has" } else { "has no" };
            return Err(err!(
                Metadata,
                "sequence {name:?}: frame {name}:{f} {} texture coordinates and frame {name}:0 {}: expected all \
                 frames of a sequence with texture coordinates or none",
                has(f),
                has(0)
            ));
        }
        let n = frames.len();
        Ok(FrameSetSequence {
            name,
            tags: Vec::new(),
            frames,
            labels: vec![FrameLabel::Original; n],
            correspondence: None,
        })
    }

    /// A sequence from per-frame (topology, positions) pairs, as a reader of any format has them
    /// (an Alembic mesh whose topology varies, a folder of OBJ frames); a frame's error carries
    /// its location `sequence:frame`.
    pub fn from_frames(name: impl Into<String>, frames: Vec<(Topology, Vec<f32>)>) -> Result<Self> {
        let name = name.into();
        let frames = frames
            .into_iter()
            .enumerate()
            .map(|(f, (t, p))| Frame::new(t, p).map_err(|e| frame_error(e, &name, f)))
            .collect::<Result<Vec<_>>>()?;
        Self::new(name, frames)
    }

    pub fn with_tags(mut self, tags: Vec<String>) -> Self {
        self.tags = tags;
        self
    }

    pub fn with_labels(mut self, labels: Vec<FrameLabel>) -> Result<Self> {
        if labels.len() != self.frames.len() {
            return Err(err!(
                Shape,
                "sequence {:?}: {} frame labels, expected one per frame ({})",
                self.name,
                labels.len(),
                self.frames.len()
            ));
        }
        self.labels = labels;
        Ok(self)
    }

    /// Attaches the known correspondence to a source surface: four numbers per vertex of every
    /// frame, a whole non-negative triangle number and three finite barycentrics.
    pub fn with_correspondence(mut self, c: Correspondence) -> Result<Self> {
        let want = 4 * self.frames.iter().map(Frame::n_vertices).sum::<usize>();
        if c.rows.len() != want {
            return Err(err!(
                Shape,
                "sequence {:?}: correspondence holds {} numbers, expected {want} (4 per vertex of every frame)",
                self.name,
                c.rows.len()
            ));
        }
        let mut row = 0usize;
        for (f, fr) in self.frames.iter().enumerate() {
            for v in 0..fr.n_vertices() {
                let r = &c.rows[4 * row..4 * row + 4];
                if !(r[0] >= 0.0 && r[0].fract() == 0.0 && r[0] < 9.007_199_254_740_992e15)
                    || r[1..].iter().any(|b| !b.is_finite())
                {
                    return Err(err!(
                        Syntax,
                        "vertex {v}: correspondence [{}, {}, {}, {}]: expected a whole triangle number >= 0 and three finite barycentric coordinates",
                        r[0],
                        r[1],
                        r[2],
                        r[3]
                    )
                    .at(Location::Frame(f)));
                }
                row += 1;
            }
        }
        self.correspondence = Some(c);
        Ok(self)
    }

    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }

    pub fn labels(&self) -> &[FrameLabel] {
        &self.labels
    }

    pub fn correspondence(&self) -> Option<&Correspondence> {
        self.correspondence.as_ref()
    }

    /// Smallest and largest vertex count of a frame.
    pub fn vertex_count_range(&self) -> (usize, usize) {
        min_max(self.frames.iter().map(Frame::n_vertices))
    }

    /// Whether the frames have texture coordinates (all of them, or none: checked on
    /// construction).
    pub fn has_uv(&self) -> bool {
        self.frames[0].topology.uv().is_some()
    }

    /// Smallest and largest triangle count of a frame.
    pub fn triangle_count_range(&self) -> (usize, usize) {
        min_max(self.frames.iter().map(Frame::n_triangles))
    }
}

fn min_max(it: impl Iterator<Item = usize>) -> (usize, usize) {
    it.fold((usize::MAX, 0), |(lo, hi), n| (lo.min(n), hi.max(n)))
}

/// An error about frame `f` of sequence `name`, located as users write frames.
pub(crate) fn frame_error(mut e: crate::Error, name: &str, f: usize) -> crate::Error {
    e.message = format!("frame {name}:{f}: {}", e.message);
    e
}

/// A set of frames with their own topologies, in named sequences, with frame rate, up axis and
/// units: a [`Subject`] without the shared topology.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSet {
    pub name: String,
    sequences: Vec<FrameSetSequence>,
    pub fps: f64,
    pub up_axis: UpAxis,
    pub units: Units,
    index: FrameIndex,
}

impl FrameSet {
    /// Checks the frame rate, that there is a sequence, and that names are unique.
    pub fn new(
        name: impl Into<String>,
        sequences: Vec<FrameSetSequence>,
        fps: f64,
        up_axis: UpAxis,
        units: Units,
    ) -> Result<Self> {
        let name = name.into();
        crate::subject::check_frame_rate(fps)?;
        if sequences.is_empty() {
            return Err(err!(Empty, "frame set {name:?} has no sequences"));
        }
        crate::subject::check_sequence_names(sequences.iter().map(|s| s.name.as_str()))?;
        let index = FrameIndex::new(sequences.iter().map(FrameSetSequence::n_frames))
            .with_names(sequences.iter().map(|s| s.name.clone()).collect());
        Ok(FrameSet { name, sequences, fps, up_axis, units, index })
    }

    /// Every frame of a subject as a frame of its own (the topology copied into each), with
    /// the subject's names, labels, tags and metadata. Joints are not kept (a frame set has none).
    pub fn from_subject(s: &Subject) -> FrameSet {
        let sequences = s
            .sequences()
            .iter()
            .map(|q| FrameSetSequence {
                name: q.name.clone(),
                tags: q.tags.clone(),
                frames: (0..q.n_frames())
                    .map(|f| Frame { topology: s.topology().clone(), positions: q.frame(f).to_vec() })
                    .collect(),
                labels: q.labels.clone(),
                correspondence: None,
            })
            .collect();
        FrameSet {
            name: s.name.clone(),
            sequences,
            fps: s.fps,
            up_axis: s.up_axis,
            units: s.units.clone(),
            index: s.frame_index().clone(),
        }
    }

    /// The first frame (as `sequence:frame`) whose topology (vertex count, triangles, texture
    /// coordinates) differs from the first frame's, and how; `None` when every frame shares one.
    pub fn first_topology_difference(&self) -> Option<(String, String)> {
        let first = &self.sequences[0].frames[0].topology;
        for g in 1..self.frame_count() {
            let frame = self.frame(g).expect("in range");
            if let Some(diff) = first.first_difference(&frame.topology) {
                return Some((self.index.label(g), diff));
            }
            if first.uv() != frame.topology.uv() {
                return Some((self.index.label(g), "texture coordinates differ from the first frame's".into()));
            }
        }
        None
    }

    /// A subject, when every frame shares one topology (same vertex count and the same
    /// triangles in the same order); otherwise an error naming the first frame that differs.
    pub fn into_subject(self) -> Result<Subject> {
        if let Some((frame, diff)) = self.first_topology_difference() {
            let first = self.index.label(0);
            return Err(err!(
                TopologyMismatch,
                "frame set {:?} has no shared topology: frame {frame} differs from {first}: {}",
                self.name,
                diff.replace("as in the template", &format!("as in {first}"))
            ));
        }
        let FrameSet { name, sequences, fps, up_axis, units, .. } = self;
        let topology = sequences[0].frames[0].topology.clone();
        let nv = topology.n_vertices();
        let mut out = Vec::with_capacity(sequences.len());
        for s in sequences {
            let mut positions = Vec::with_capacity(s.frames.len() * 3 * nv);
            for f in &s.frames {
                positions.extend_from_slice(&f.positions);
            }
            out.push(Sequence::new(s.name, nv, positions)?.with_tags(s.tags).with_labels(s.labels)?);
        }
        Subject::new(name, topology, out, fps, up_axis, units)
    }

    pub fn sequences(&self) -> &[FrameSetSequence] {
        &self.sequences
    }

    pub fn sequence(&self, name: &str) -> Option<(usize, &FrameSetSequence)> {
        self.sequences.iter().enumerate().find(|(_, s)| s.name == name)
    }

    /// The global frame index <-> (sequence, frame) mapping, with the sequences' names.
    pub fn frame_index(&self) -> &FrameIndex {
        &self.index
    }

    /// Number of frames over all sequences.
    pub fn frame_count(&self) -> usize {
        self.index.len()
    }

    /// A frame by global index.
    pub fn frame(&self, global: usize) -> Option<&Frame> {
        let (s, f) = self.index.locate(global)?;
        Some(&self.sequences[s].frames[f])
    }

    /// Smallest and largest vertex count of a frame over all sequences.
    pub fn vertex_count_range(&self) -> (usize, usize) {
        min_max(self.sequences.iter().flat_map(|s| s.frames.iter().map(Frame::n_vertices)))
    }

    /// Smallest and largest triangle count of a frame over all sequences.
    pub fn triangle_count_range(&self) -> (usize, usize) {
        min_max(self.sequences.iter().flat_map(|s| s.frames.iter().map(Frame::n_triangles)))
    }

    /// Global index of a frame written `sequence:frame` (0-based frame), or a bare global
    /// index, as [`Subject::resolve_frame`].
    pub fn resolve_frame(&self, spec: &str) -> Result<usize> {
        self.index.resolve(spec, "frame set")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorKind;

    fn tet() -> Topology {
        Topology::new(4, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], None).unwrap()
    }

    fn tri() -> Topology {
        Topology::new(3, vec![[0, 1, 2]], None).unwrap()
    }

    #[test]
    fn frames_are_validated_with_their_place() {
        let e = Frame::new(tri(), vec![0.0; 8]).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Shape);
        let mut p = vec![0.0f32; 9];
        p[4] = f32::INFINITY;
        let e = FrameSetSequence::from_frames("walk", vec![(tri(), vec![0.0; 9]), (tri(), p)]).unwrap_err();
        assert_eq!(e.kind, ErrorKind::NonFinite);
        assert!(e.message.starts_with("frame walk:1: vertex 1 has a non-finite"), "{e}");
        assert_eq!(FrameSetSequence::new("x", vec![]).unwrap_err().kind, ErrorKind::Empty);
        // Face indices are checked by the topology itself.
        assert_eq!(Topology::new(3, vec![[0, 1, 3]], None).unwrap_err().kind, ErrorKind::IndexOutOfRange);
    }

    #[test]
    fn frames_are_named_and_counted_like_a_subjects() {
        let a = FrameSetSequence::from_frames("a", vec![(tri(), vec![0.0; 9]), (tet(), vec![1.0; 12])]).unwrap();
        let b = FrameSetSequence::from_frames("b", vec![(tet(), vec![2.0; 12])]).unwrap();
        let set = FrameSet::new("s", vec![a.clone(), b], 30.0, UpAxis::PosY, Units::metres()).unwrap();
        assert_eq!(set.frame_count(), 3);
        assert_eq!(set.frame_index().label(2), "b:0");
        assert_eq!(set.resolve_frame("a:1").unwrap(), 1);
        assert_eq!(set.frame(2).unwrap().positions()[0], 2.0);
        assert!(set.resolve_frame("a:2").is_err());
        assert_eq!(set.vertex_count_range(), (3, 4));
        assert_eq!(set.triangle_count_range(), (1, 4));
        let (frame, diff) = set.first_topology_difference().unwrap();
        assert_eq!(frame, "a:1");
        assert!(diff.starts_with("4 vertices"), "{diff}");
        let e = set.into_subject().unwrap_err();
        assert_eq!(e.kind, ErrorKind::TopologyMismatch);
        assert!(e.message.contains("frame a:1 differs from a:0: 4 vertices, expected 3 as in a:0"), "{e}");
        let e = FrameSet::new("s", vec![a.clone(), a], 30.0, UpAxis::PosY, Units::metres()).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Metadata);
    }

    #[test]
    fn converts_from_and_to_a_subject() {
        let s1 = Sequence::new("walk", 4, (0..24).map(|x| x as f32).collect())
            .unwrap()
            .with_tags(vec!["walk".into()])
            .with_labels(vec![FrameLabel::Original, FrameLabel::Synthetic])
            .unwrap();
        let s2 = Sequence::new("run", 4, vec![0.5; 12]).unwrap();
        let subject = Subject::new("tet", tet(), vec![s1, s2], 25.0, UpAxis::PosZ, Units::metres()).unwrap();
        let set = FrameSet::from_subject(&subject);
        assert_eq!(set.frame_count(), 3);
        assert_eq!(set.frame(1).unwrap().positions(), subject.frame(1).unwrap());
        assert_eq!(set.frame_index(), subject.frame_index());
        assert!(set.first_topology_difference().is_none());
        assert_eq!(set.clone().into_subject().unwrap(), subject);
    }

    #[test]
    fn texture_coordinates_are_all_or_none() {
        let uv = crate::UvAtlas { coords: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], corners: vec![[0, 1, 2]] };
        let with = Topology::new(3, vec![[0, 1, 2]], Some(uv)).unwrap();
        let e = FrameSetSequence::from_frames("a", vec![(with.clone(), vec![0.0; 9]), (tri(), vec![0.0; 9])]);
        let e = e.unwrap_err().to_string();
        assert!(e.contains("frame a:1 has no texture coordinates and frame a:0 has"), "{e}");
        let s = FrameSetSequence::from_frames("a", vec![(with.clone(), vec![0.0; 9]), (with, vec![0.0; 9])]).unwrap();
        assert!(s.has_uv());
    }

    #[test]
    fn correspondence_is_checked() {
        let s = FrameSetSequence::from_frames("a", vec![(tri(), vec![0.0; 9])]).unwrap();
        let good = Correspondence { rows: [0.0, 1.0, 0.0, 0.0].repeat(3) };
        assert!(s.clone().with_correspondence(good).is_ok());
        let e = s.clone().with_correspondence(Correspondence { rows: vec![0.0; 8] }).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Shape);
        let mut rows = [0.0, 1.0, 0.0, 0.0].repeat(3);
        rows[4] = 1.5;
        let e = s.with_correspondence(Correspondence { rows }).unwrap_err();
        assert!(e.to_string().starts_with("frame 0: vertex 1: correspondence [1.5"), "{e}");
    }
}

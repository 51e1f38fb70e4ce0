//! The subject: one topology, named sequences of vertex positions, and what is known about them.

use serde::{Deserialize, Serialize};

use crate::error::{Result, err};
use crate::frame_index::FrameIndex;
use crate::topology::Topology;

/// Which world axis points up (a signed coordinate axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum UpAxis {
    #[serde(rename = "+x")]
    PosX,
    #[serde(rename = "+y")]
    PosY,
    #[serde(rename = "+z")]
    PosZ,
    #[serde(rename = "-x")]
    NegX,
    #[serde(rename = "-y")]
    NegY,
    #[serde(rename = "-z")]
    NegZ,
}

impl std::str::FromStr for UpAxis {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self> {
        UpAxis::parse(s)
    }
}

impl UpAxis {
    /// Parses `y`, `+Y`, `-z`, and also descriptive strings that start with an axis, such as
    /// `+Y (Maya default; verify)` found in dataset metadata.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim().to_ascii_lowercase();
        let (neg, rest) = match t.strip_prefix('-') {
            Some(r) => (true, r),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        let mut chars = rest.chars();
        let axis = chars.next();
        let boundary = chars.next().is_none_or(|c| !c.is_ascii_alphanumeric());
        match (axis, boundary, neg) {
            (Some('x'), true, false) => Ok(UpAxis::PosX),
            (Some('y'), true, false) => Ok(UpAxis::PosY),
            (Some('z'), true, false) => Ok(UpAxis::PosZ),
            (Some('x'), true, true) => Ok(UpAxis::NegX),
            (Some('y'), true, true) => Ok(UpAxis::NegY),
            (Some('z'), true, true) => Ok(UpAxis::NegZ),
            _ => Err(err!(Metadata, "up axis {text:?}: expected one of +x, +y, +z, -x, -y, -z")),
        }
    }

    /// Coordinate index (0, 1, 2) and sign (+1.0 or -1.0).
    pub fn axis_and_sign(self) -> (usize, f64) {
        match self {
            UpAxis::PosX => (0, 1.0),
            UpAxis::PosY => (1, 1.0),
            UpAxis::PosZ => (2, 1.0),
            UpAxis::NegX => (0, -1.0),
            UpAxis::NegY => (1, -1.0),
            UpAxis::NegZ => (2, -1.0),
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            UpAxis::PosX => "+x",
            UpAxis::PosY => "+y",
            UpAxis::PosZ => "+z",
            UpAxis::NegX => "-x",
            UpAxis::NegY => "-y",
            UpAxis::NegZ => "-z",
        }
    }
}

/// Length unit of the positions: its name as given, and its size in metres when known.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Units {
    pub name: String,
    /// Metres per unit, or `None` for arbitrary units (rescaled scans, model units).
    pub metres_per_unit: Option<f64>,
}

impl Units {
    pub fn metres() -> Self {
        Units { name: "m".into(), metres_per_unit: Some(1.0) }
    }

    pub fn arbitrary() -> Self {
        Units { name: "arbitrary".into(), metres_per_unit: None }
    }

    /// How lengths in these units are written everywhere surfcap prints them: the unit's symbol
    /// (`m`, `cm`, `mm`, `in`) whatever word the source used (`metres (approx.)`, `meters`), the
    /// name of another known size as given, and `units` when the size is unknown.
    pub fn symbol(&self) -> &str {
        const SYMBOLS: [(f64, &str); 4] = [(1.0, "m"), (0.01, "cm"), (0.001, "mm"), (0.0254, "in")];
        match self.metres_per_unit {
            Some(m) => SYMBOLS.iter().find(|(size, _)| *size == m).map_or(self.name.as_str(), |(_, sym)| sym),
            None => "units",
        }
    }

    /// Reads the leading word of a description: `m`, `metres (approx.)`, `cm`, `mm`, `inches`;
    /// anything else (`arbitrary (rescaled)`, `model units`) is kept as arbitrary units.
    pub fn parse(text: &str) -> Self {
        let lower = text.trim().to_ascii_lowercase();
        let word: String = lower.chars().take_while(|c| c.is_ascii_alphabetic()).collect();
        let scale = match word.as_str() {
            "m" | "metre" | "metres" | "meter" | "meters" => Some(1.0),
            "cm" | "centimetre" | "centimetres" | "centimeter" | "centimeters" => Some(0.01),
            "mm" | "millimetre" | "millimetres" | "millimeter" | "millimeters" => Some(0.001),
            "in" | "inch" | "inches" => Some(0.0254),
            _ => None,
        };
        match scale {
            Some(s) => Units { name: word, metres_per_unit: Some(s) },
            None => Units { name: text.trim().to_string(), metres_per_unit: None },
        }
    }
}

/// Whether a frame was captured (original) or made by surfcap (synthetic: blends, interpolations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameLabel {
    Original,
    Synthetic,
}

impl FrameLabel {
    /// Labels of a synthetic segment between two captured frames: original at both ends,
    /// synthetic in between.
    pub fn original_ends(n: usize) -> Vec<FrameLabel> {
        (0..n).map(|t| if t == 0 || t + 1 == n { FrameLabel::Original } else { FrameLabel::Synthetic }).collect()
    }
}

/// Ground-truth skeleton of a sequence: per-frame world matrices of each joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrack {
    pub names: Vec<String>,
    /// Parent index of each joint, `None` for roots.
    pub parents: Vec<Option<usize>>,
    /// Row-major 4x4 world matrices (column-vector convention), `[frames][joints][4][4]`.
    pub matrices: Vec<f32>,
}

impl JointTrack {
    pub fn n_joints(&self) -> usize {
        self.names.len()
    }
}

/// Vertex positions of a sequence, contiguous `[frames][vertices][3]` f32, immutable once made:
/// owned, or held by another owner and shared without a copy (a numpy array passed in from
/// Python, kept alive by this buffer). Cloning shares the numbers.
#[derive(Clone)]
pub struct PositionBuffer(std::sync::Arc<dyn AsRef<[f32]> + Send + Sync>);

impl PositionBuffer {
    /// Numbers held by `owner` (which must not change them while the buffer lives).
    pub fn shared(owner: impl AsRef<[f32]> + Send + Sync + 'static) -> Self {
        PositionBuffer(std::sync::Arc::new(owner))
    }

    pub fn as_slice(&self) -> &[f32] {
        (*self.0).as_ref()
    }
}

impl From<Vec<f32>> for PositionBuffer {
    fn from(v: Vec<f32>) -> Self {
        PositionBuffer::shared(v)
    }
}

impl std::fmt::Debug for PositionBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PositionBuffer({} numbers)", self.as_slice().len())
    }
}

impl PartialEq for PositionBuffer {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

/// One named sequence of frames sharing the subject's topology.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    pub name: String,
    pub tags: Vec<String>,
    /// Vertex positions, contiguous `[frames][vertices][3]` f32.
    positions: PositionBuffer,
    n_frames: usize,
    /// One label per frame.
    pub labels: Vec<FrameLabel>,
    pub joints: Option<JointTrack>,
}

impl Sequence {
    /// A sequence of original frames. `positions.len()` must be a multiple of `3 * n_vertices`.
    pub fn new(name: impl Into<String>, n_vertices: usize, positions: Vec<f32>) -> Result<Self> {
        Self::from_buffer(name, n_vertices, positions.into())
    }

    /// The same, on numbers held elsewhere ([`PositionBuffer::shared`]): no copy is made.
    pub fn from_buffer(name: impl Into<String>, n_vertices: usize, buffer: PositionBuffer) -> Result<Self> {
        let name = name.into();
        let positions = buffer.as_slice();
        let per_frame = 3 * n_vertices;
        if per_frame == 0 || !positions.len().is_multiple_of(per_frame) {
            return Err(err!(
                Shape,
                "sequence {name:?}: {} coordinates is not a whole number of frames of {n_vertices} vertices",
                positions.len()
            ));
        }
        let n_frames = positions.len() / per_frame;
        if n_frames == 0 {
            return Err(err!(Empty, "sequence {name:?} has no frames"));
        }
        if let Some(k) = positions.iter().position(|x| !x.is_finite()) {
            return Err(err!(
                NonFinite,
                "sequence {name:?}: vertex {} has a non-finite coordinate ({}): expected finite numbers",
                (k % per_frame) / 3,
                positions[k]
            )
            .at_frame(k / per_frame));
        }
        Ok(Sequence {
            name,
            tags: Vec::new(),
            positions: buffer,
            n_frames,
            labels: vec![FrameLabel::Original; n_frames],
            joints: None,
        })
    }

    pub fn with_tags(mut self, tags: Vec<String>) -> Self {
        self.tags = tags;
        self
    }

    pub fn with_labels(mut self, labels: Vec<FrameLabel>) -> Result<Self> {
        if labels.len() != self.n_frames {
            return Err(err!(
                Shape,
                "sequence {:?}: {} frame labels, expected one per frame ({})",
                self.name,
                labels.len(),
                self.n_frames
            ));
        }
        self.labels = labels;
        Ok(self)
    }

    pub fn with_joints(mut self, joints: JointTrack) -> Result<Self> {
        let expected = self.n_frames * joints.n_joints() * 16;
        if joints.matrices.len() != expected || joints.parents.len() != joints.names.len() {
            return Err(err!(
                Shape,
                "sequence {:?}: joint matrices hold {} numbers for {} joints, expected {} ({} frames x {} joints x 4 x 4)",
                self.name,
                joints.matrices.len(),
                joints.n_joints(),
                expected,
                self.n_frames,
                joints.n_joints()
            ));
        }
        if let Some((j, _)) = joints.parents.iter().enumerate().find(|(_, p)| p.is_some_and(|p| p >= joints.n_joints()))
        {
            return Err(err!(Shape, "joint {j}'s parent is out of range ({} joints)", joints.n_joints()));
        }
        self.joints = Some(joints);
        Ok(self)
    }

    pub fn n_frames(&self) -> usize {
        self.n_frames
    }

    pub fn n_vertices(&self) -> usize {
        self.positions().len() / (3 * self.n_frames)
    }

    /// All positions, `[frames][vertices][3]`.
    pub fn positions(&self) -> &[f32] {
        self.positions.as_slice()
    }

    /// The buffer holding the positions, to share them without a copy.
    pub fn buffer(&self) -> &PositionBuffer {
        &self.positions
    }

    /// Positions of one frame, `[vertices][3]`.
    pub fn frame(&self, f: usize) -> &[f32] {
        let n = self.positions().len() / self.n_frames;
        &self.positions()[f * n..(f + 1) * n]
    }
}

/// The frame rates surfcap accepts, in frames per second: a frame time from 1e-4 s (10,000 fps)
/// to 10 s (0.1 fps). Every reader that learns a frame rate (BVH `Frame Time`, `meta.json`,
/// `surfcap.toml`, glb extras, USD and Alembic time codes, a subject cache) and every subject
/// checks it against this one range, so a typo like `Frame Time: 1e-300` cannot make a subject
/// at 1e300 fps.
pub const FRAME_RATES: std::ops::RangeInclusive<f64> = 0.1..=10_000.0;

/// The accepted frame rates and frame times, as an error message says them.
pub const FRAME_RATES_TEXT: &str = "0.1 to 10000 frames per second (a frame time of 1e-4 to 10 s)";

/// Checks a frame rate against [`FRAME_RATES`]: the error says the value and the range (the
/// caller adds the file and field).
pub fn check_frame_rate(fps: f64) -> Result<f64> {
    if FRAME_RATES.contains(&fps) {
        Ok(fps)
    } else {
        Err(err!(Metadata, "frame rate {} fps: expected {FRAME_RATES_TEXT}", short_number(fps)))
    }
}

/// Checks a frame time in seconds (the reciprocal of a frame rate) against [`FRAME_RATES`].
pub fn check_frame_time(seconds: f64) -> Result<f64> {
    if (1.0 / FRAME_RATES.end()..=1.0 / FRAME_RATES.start()).contains(&seconds) {
        Ok(seconds)
    } else {
        Err(err!(Metadata, "frame time {} s: expected {FRAME_RATES_TEXT}", short_number(seconds)))
    }
}

/// A number as a person writes it: plainly when moderate, in exponent form when tiny or huge
/// (`1e-300`, not three hundred zeros).
fn short_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&x.abs()) { format!("{x}") } else { format!("{x:e}") }
}

/// Checks sequence names: none empty, no two alike. The error names the 0-based index of the
/// sequence at fault (the caller adds the file).
pub fn check_sequence_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<()> {
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, n) in names.into_iter().enumerate() {
        if n.is_empty() {
            return Err(err!(Metadata, "sequence {i} has an empty name: expected a non-empty name"));
        }
        if let Some(j) = seen.insert(n, i) {
            return Err(err!(Metadata, "sequences {j} and {i} are both named {n:?}: expected unique sequence names"));
        }
    }
    Ok(())
}

/// A subject: one topology, several named sequences, frame rate, up axis and units.
#[derive(Debug, Clone, PartialEq)]
pub struct Subject {
    pub name: String,
    topology: Topology,
    sequences: Vec<Sequence>,
    pub fps: f64,
    pub up_axis: UpAxis,
    pub units: Units,
    index: FrameIndex,
}

impl Subject {
    /// Checks the frame rate ([`FRAME_RATES`]), that every sequence has the topology's vertex
    /// count, and that names are non-empty and unique.
    pub fn new(
        name: impl Into<String>,
        topology: Topology,
        sequences: Vec<Sequence>,
        fps: f64,
        up_axis: UpAxis,
        units: Units,
    ) -> Result<Self> {
        let name = name.into();
        check_frame_rate(fps)?;
        if sequences.is_empty() {
            return Err(err!(Empty, "subject {name:?} has no sequences"));
        }
        check_sequence_names(sequences.iter().map(|s| s.name.as_str()))?;
        for s in &sequences {
            if s.n_vertices() != topology.n_vertices() {
                return Err(err!(
                    TopologyMismatch,
                    "sequence {:?} has {} vertices, expected {} as in the subject's topology",
                    s.name,
                    s.n_vertices(),
                    topology.n_vertices()
                ));
            }
        }
        let index = FrameIndex::new(sequences.iter().map(|s| s.n_frames()))
            .with_names(sequences.iter().map(|s| s.name.clone()).collect());
        Ok(Subject { name, topology, sequences, fps, up_axis, units, index })
    }

    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    pub fn sequences(&self) -> &[Sequence] {
        &self.sequences
    }

    pub fn sequence(&self, name: &str) -> Option<(usize, &Sequence)> {
        self.sequences.iter().enumerate().find(|(_, s)| s.name == name)
    }

    /// The global frame index <-> (sequence, frame) mapping.
    pub fn frame_index(&self) -> &FrameIndex {
        &self.index
    }

    pub fn n_frames(&self) -> usize {
        self.index.len()
    }

    /// Positions of a frame by global index.
    pub fn frame(&self, global: usize) -> Option<&[f32]> {
        let (s, f) = self.index.locate(global)?;
        Some(self.sequences[s].frame(f))
    }

    /// A new subject with this one's topology, frame rate, up axis and units, holding `sequence`
    /// (a result made from this subject's frames: an interpolation, a transition, a synthesis).
    pub fn derived(&self, name: impl Into<String>, sequence: Sequence) -> Result<Subject> {
        Subject::new(name, self.topology.clone(), vec![sequence], self.fps, self.up_axis, self.units.clone())
    }

    /// Global index of a frame written `sequence:frame` (0-based frame), or a bare global index.
    pub fn resolve_frame(&self, spec: &str) -> Result<usize> {
        self.index.resolve(spec, "subject")
    }

    /// Keeps only the named sequences, in the given order.
    pub fn select(self, names: &[String]) -> Result<Self> {
        if names.is_empty() {
            return Ok(self);
        }
        let Subject { name, topology, mut sequences, fps, up_axis, units, .. } = self;
        let mut chosen = Vec::with_capacity(names.len());
        for n in names {
            let Some(i) = sequences.iter().position(|s| &s.name == n) else {
                let known: Vec<&str> = sequences.iter().map(|s| s.name.as_str()).collect();
                return Err(err!(Metadata, "no sequence named {n:?}: the subject has {}", known.join(", ")));
            };
            chosen.push(sequences.swap_remove(i));
        }
        Subject::new(name, topology, chosen, fps, up_axis, units)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorKind;

    #[test]
    fn parses_up_axes() {
        assert_eq!(UpAxis::parse("y").unwrap(), UpAxis::PosY);
        assert_eq!(UpAxis::parse("+Y (Maya default; verify)").unwrap(), UpAxis::PosY);
        assert_eq!(UpAxis::parse("-z").unwrap(), UpAxis::NegZ);
        assert!(UpAxis::parse("yz").is_err());
        assert!(UpAxis::parse("up").is_err());
    }

    #[test]
    fn parses_units() {
        assert_eq!(Units::parse("metres (approx.)").metres_per_unit, Some(1.0));
        // One spelling, the symbol, whatever word the source used.
        for (text, symbol) in
            [("metres (approx.)", "m"), ("meters", "m"), ("m", "m"), ("centimetres", "cm"), ("inches", "in")]
        {
            assert_eq!(Units::parse(text).symbol(), symbol, "{text}");
        }
        assert_eq!(Units::parse("model units (NOT meters)").symbol(), "units");
        assert_eq!(Units::parse("cm").metres_per_unit, Some(0.01));
        assert_eq!(Units::parse("arbitrary (rescaled)").metres_per_unit, None);
        assert_eq!(Units::parse("model units (NOT meters)").metres_per_unit, None);
    }

    #[test]
    fn sequence_rejects_nan_with_frame() {
        let mut p = vec![0.0f32; 18];
        p[13] = f32::NAN;
        let e = Sequence::new("s", 3, p).unwrap_err();
        assert_eq!(e.kind, ErrorKind::NonFinite);
        assert_eq!(e.location, Some(crate::Location::Frame(1)));
    }

    #[test]
    fn resolves_frame_specs() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let a = Sequence::new("a:b", 3, vec![0.0; 18]).unwrap();
        let c = Sequence::new("c", 3, vec![0.0; 27]).unwrap();
        let s = Subject::new("s", topo, vec![a, c], 30.0, UpAxis::PosY, Units::metres()).unwrap();
        assert_eq!(s.resolve_frame("c:2").unwrap(), 4);
        assert_eq!(s.resolve_frame("a:b:1").unwrap(), 1);
        assert_eq!(s.resolve_frame("3").unwrap(), 3);
        assert!(s.resolve_frame("c:3").is_err());
        assert!(s.resolve_frame("d:0").unwrap_err().to_string().contains("a:b, c"));
        assert!(s.resolve_frame("5").is_err());
        let d = s.derived(
            "d",
            Sequence::new("x", 3, vec![0.0; 9]).unwrap().with_labels(FrameLabel::original_ends(1)).unwrap(),
        );
        assert_eq!(d.unwrap().fps, 30.0);
        use FrameLabel::{Original as O, Synthetic as S};
        assert_eq!(FrameLabel::original_ends(4), vec![O, S, S, O]);
    }

    #[test]
    fn subject_checks_vertex_counts_and_names() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let a = Sequence::new("a", 3, vec![0.0; 9]).unwrap();
        let b = Sequence::new("b", 4, vec![0.0; 12]).unwrap();
        let e = Subject::new("s", topo.clone(), vec![a.clone(), b], 30.0, UpAxis::PosY, Units::metres());
        assert_eq!(e.unwrap_err().kind, ErrorKind::TopologyMismatch);
        let e = Subject::new("s", topo.clone(), vec![a.clone(), a.clone()], 30.0, UpAxis::PosY, Units::metres());
        assert_eq!(e.unwrap_err().kind, ErrorKind::Metadata);
        let s = Subject::new("s", topo, vec![a], 30.0, UpAxis::PosY, Units::metres()).unwrap();
        assert_eq!(s.n_frames(), 1);
    }

    #[test]
    fn subject_refuses_empty_names_and_frame_rates_out_of_range() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let a = Sequence::new("a", 3, vec![0.0; 9]).unwrap();
        let blank = Sequence::new("", 3, vec![0.0; 9]).unwrap();
        let e = Subject::new("s", topo.clone(), vec![a.clone(), blank], 30.0, UpAxis::PosY, Units::metres());
        assert!(e.unwrap_err().to_string().contains("sequence 1 has an empty name"));
        for fps in [1e300, 1e-300, 0.05, 20_000.0, f64::NAN, -30.0] {
            let e = Subject::new("s", topo.clone(), vec![a.clone()], fps, UpAxis::PosY, Units::metres()).unwrap_err();
            assert!(e.to_string().contains("0.1 to 10000 frames per second"), "{fps}: {e}");
        }
        for fps in [0.1, 24.0, 10_000.0] {
            assert!(Subject::new("s", topo.clone(), vec![a.clone()], fps, UpAxis::PosY, Units::metres()).is_ok());
        }
        assert!(check_frame_time(1e-4).is_ok() && check_frame_time(10.0).is_ok());
        assert!(check_frame_time(1e-300).is_err() && check_frame_time(1e300).is_err());
    }
}

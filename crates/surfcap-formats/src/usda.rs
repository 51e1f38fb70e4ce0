//! USD export as `.usda` text: one `Xform` per sequence under the
//! subject's root `Xform`, each holding one `Mesh` of constant topology whose `points` (and
//! `extent`) are time-sampled, one sample per frame at the subject's rate, whose
//! `velocities` are time-sampled with the points (units per second: the finite differences of
//! `vertex_velocity.rs`, for renderers' motion blur), and whose frame labels are the constant primvar `primvars:surfcap:synthetic` (0 original, 1 synthetic),
//! time-sampled too. The stage's `timeCodesPerSecond` and `framesPerSecond` are the subject's
//! fps; `metersPerUnit` comes from its units when known (their name, which USD has no field
//! for, is `customLayerData.surfcap_units`); `upAxis` is `Y` or `Z` (USD knows only
//! those two): a subject whose up axis is another is written with `upAxis = "Y"` and a root
//! transform turning its up axis onto +Y (the mesh keeps the subject's coordinates, as the glb
//! does). UVs, when the template has them, are the face-varying `primvars:st` with indices.
//!
//! Every sequence starts at time code 0. Prim names are the sequence names made valid USD
//! identifiers (letters, digits and `_`, not starting with a digit), made unique among the
//! sequences with a suffix.
//! Floats are written in their shortest form that reads back to the same f32.

use std::io::Write;

use crate::vertex_velocity::frame_velocity;
use surfcap_mesh::subject::{FrameLabel, Subject, UpAxis};

/// A valid, unique USD prim name for `name` among `taken`.
pub(crate) fn prim_name(name: &str, taken: &mut Vec<String>) -> String {
    let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    crate::unique_name(s, taken)
}

/// The rotation (column-vector convention, rows) that turns `up` onto +Y, or `None` when USD
/// can state the axis itself (+Y, +Z).
pub(crate) fn up_rotation(up: UpAxis) -> Option<[[i8; 3]; 3]> {
    match up {
        UpAxis::PosY | UpAxis::PosZ => None,
        UpAxis::NegZ => Some([[1, 0, 0], [0, 0, -1], [0, 1, 0]]),
        UpAxis::PosX => Some([[0, -1, 0], [1, 0, 0], [0, 0, 1]]),
        UpAxis::NegX => Some([[0, 1, 0], [-1, 0, 0], [0, 0, 1]]),
        UpAxis::NegY => Some([[1, 0, 0], [0, -1, 0], [0, 0, -1]]),
    }
}

fn point(w: &mut dyn Write, p: &[f32]) -> std::io::Result<()> {
    write!(w, "({}, {}, {})", p[0], p[1], p[2])
}

/// Writes `subject` as a `.usda` stage.
pub fn write_usda(w: &mut dyn Write, subject: &Subject) -> std::io::Result<()> {
    let topo = subject.topology();
    let root = prim_name(&subject.name, &mut Vec::new());
    // Sequence prims are siblings under the root: unique among themselves.
    let mut taken = Vec::new();
    let last = subject.sequences().iter().map(|s| s.n_frames()).max().unwrap_or(1).saturating_sub(1);
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(w, "    defaultPrim = \"{root}\"")?;
    // The units' name: metersPerUnit carries only their scale ("metres" and "m" are both 1, and
    // arbitrary units have none), so the name rides in the layer's custom data.
    let units: String = subject
        .units
        .name
        .chars()
        .flat_map(|c| match c {
            '"' | '\\' => vec!['\\', c],
            '\n' => vec!['\\', 'n'],
            c => vec![c],
        })
        .collect();
    writeln!(w, "    customLayerData = {{")?;
    writeln!(w, "        string surfcap_units = \"{units}\"")?;
    writeln!(w, "    }}")?;
    writeln!(w, "    doc = \"written by surfcap {}\"", env!("CARGO_PKG_VERSION"))?;
    writeln!(w, "    endTimeCode = {last}")?;
    writeln!(w, "    framesPerSecond = {}", subject.fps)?;
    if let Some(m) = subject.units.metres_per_unit {
        writeln!(w, "    metersPerUnit = {m}")?;
    }
    writeln!(w, "    startTimeCode = 0")?;
    writeln!(w, "    timeCodesPerSecond = {}", subject.fps)?;
    writeln!(w, "    upAxis = \"{}\"", if subject.up_axis == UpAxis::PosZ { "Z" } else { "Y" })?;
    writeln!(w, ")")?;
    writeln!(w)?;
    writeln!(w, "def Xform \"{root}\"")?;
    writeln!(w, "{{")?;
    if let Some(r) = up_rotation(subject.up_axis) {
        // USD multiplies row vectors: the matrix is the transpose of the column-vector rotation.
        write!(w, "    matrix4d xformOp:transform = (")?;
        let [r0, r1, r2] = r;
        for ((a, b), c) in r0.iter().zip(&r1).zip(&r2) {
            write!(w, "({a}, {b}, {c}, 0), ")?;
        }
        writeln!(w, "(0, 0, 0, 1))")?;
        writeln!(w, "    uniform token[] xformOpOrder = [\"xformOp:transform\"]")?;
    }
    let counts = vec!["3"; topo.n_triangles()].join(", ");
    let indices: Vec<String> = topo.triangles().iter().flatten().map(|v| v.to_string()).collect();
    let indices = indices.join(", ");
    for s in subject.sequences() {
        let name = prim_name(&s.name, &mut taken);
        writeln!(w)?;
        writeln!(w, "    def Xform \"{name}\"")?;
        writeln!(w, "    {{")?;
        writeln!(w, "        def Mesh \"mesh\"")?;
        writeln!(w, "        {{")?;
        writeln!(w, "            int[] faceVertexCounts = [{counts}]")?;
        writeln!(w, "            int[] faceVertexIndices = [{indices}]")?;
        writeln!(w, "            uniform token orientation = \"rightHanded\"")?;
        writeln!(w, "            uniform token subdivisionScheme = \"none\"")?;
        writeln!(w, "            point3f[] points.timeSamples = {{")?;
        for f in 0..s.n_frames() {
            write!(w, "                {f}: [")?;
            for (k, p) in s.frame(f).chunks_exact(3).enumerate() {
                if k > 0 {
                    write!(w, ", ")?;
                }
                point(w, p)?;
            }
            writeln!(w, "],")?;
        }
        writeln!(w, "            }}")?;
        // Velocities (units per second, USD's unit for them): `vertex_velocity`'s differences.
        let frames: Vec<&[f32]> = (0..s.n_frames()).map(|f| s.frame(f)).collect();
        writeln!(w, "            vector3f[] velocities.timeSamples = {{")?;
        for f in 0..s.n_frames() {
            write!(w, "                {f}: [")?;
            for (k, p) in frame_velocity(&frames, f, subject.fps).chunks_exact(3).enumerate() {
                if k > 0 {
                    write!(w, ", ")?;
                }
                point(w, p)?;
            }
            writeln!(w, "],")?;
        }
        writeln!(w, "            }}")?;
        writeln!(w, "            float3[] extent.timeSamples = {{")?;
        for f in 0..s.n_frames() {
            let (lo, hi) = surfcap_mesh::bounding_box(s.frame(f));
            write!(w, "                {f}: [")?;
            point(w, &lo)?;
            write!(w, ", ")?;
            point(w, &hi)?;
            writeln!(w, "],")?;
        }
        writeln!(w, "            }}")?;
        writeln!(w, "            int primvars:surfcap:synthetic (")?;
        writeln!(w, "                interpolation = \"constant\"")?;
        writeln!(w, "            )")?;
        writeln!(w, "            int primvars:surfcap:synthetic.timeSamples = {{")?;
        for (f, l) in s.labels.iter().enumerate() {
            writeln!(w, "                {f}: {},", u8::from(*l == FrameLabel::Synthetic))?;
        }
        writeln!(w, "            }}")?;
        if let Some(uv) = topo.uv() {
            let st: Vec<String> = uv.coords.iter().map(|c| format!("({}, {})", c[0], c[1])).collect();
            let st_ix: Vec<String> = uv.corners.iter().flatten().map(|v| v.to_string()).collect();
            writeln!(w, "            texCoord2f[] primvars:st = [{}] (", st.join(", "))?;
            writeln!(w, "                interpolation = \"faceVarying\"")?;
            writeln!(w, "            )")?;
            writeln!(w, "            int[] primvars:st:indices = [{}]", st_ix.join(", "))?;
        }
        writeln!(w, "        }}")?;
        writeln!(w, "    }}")?;
    }
    writeln!(w, "}}")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::subject::{Sequence, Units};
    use surfcap_mesh::topology::Topology;

    #[test]
    fn a_tiny_subject_as_usda() {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seq = Sequence::new(
            "walk 1",
            3,
            vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.5, 0.25, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.1],
        )
        .unwrap()
        .with_labels(vec![FrameLabel::Original, FrameLabel::Synthetic])
        .unwrap();
        let s = Subject::new("1st", topo, vec![seq], 24.0, UpAxis::PosX, Units::metres()).unwrap();
        let mut out = Vec::new();
        write_usda(&mut out, &s).unwrap();
        let t = String::from_utf8(out).unwrap();
        assert!(t.starts_with("#usda 1.0\n"));
        assert!(t.contains("defaultPrim = \"_1st\""), "{t}");
        assert!(
            t.contains("timeCodesPerSecond = 24") && t.contains("metersPerUnit = 1") && t.contains("upAxis = \"Y\"")
        );
        assert!(t.contains("def Xform \"walk_1\""));
        assert!(
            t.contains("matrix4d xformOp:transform = ((0, 1, 0, 0), (-1, 0, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1))"),
            "{t}"
        );
        assert!(t.contains("1: [(0, 0, 0), (2, 0, 0), (0, 1, 0.1)]"), "{t}");
        // Two frames 1/24 s apart: both velocities are the forward difference times 24.
        assert!(t.contains("vector3f[] velocities.timeSamples = {\n                0: [(0, 0, 0), (24, 0, 0), (0, -12, -3.6)],\n                1: [(0, 0, 0), (24, 0, 0), (0, -12, -3.6)],"), "{t}");
        assert!(t.contains("0: 0,\n                1: 1,"), "{t}");
        assert_eq!(prim_name("a", &mut vec!["a".into()]), "a_1");
    }
}

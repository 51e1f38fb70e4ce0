//! `surfcap import x.usda` - surfcap's own `--format usda` reads back exactly
//! (positions to the bit, topology with UVs, fps, up axis, metres per unit, labels) for a KayKit
//! clip and a 10-frame Vlasic crane subject; a stage written by Pixar's USD itself (quads, time
//! samples from frame 1) imports with its quads fan-triangulated and every frame, from its text
//! and from its binary crate (`.usdc`) encoding alike.

use std::path::Path;

use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_testkit::{p, stderr, surfcap};

/// Runs a Python script with usd-core (`tools/venv`), as `surfcap_testkit::read_usd` does.
fn python_usd(script: &str, args: &[&Path]) {
    let python = surfcap_testkit::workspace_root().join("tools/venv/bin/python");
    assert!(python.is_file(), "{} is missing: run scripts/test (it installs usd-core)", python.display());
    let o = std::process::Command::new(&python).arg("-c").arg(script).args(args).output().expect("python runs");
    assert!(o.status.success(), "the USD script failed:\n{}", String::from_utf8_lossy(&o.stderr));
}

/// Exports `subject` (a cache) as usda, imports it back and checks it is the same subject.
fn round_trip(subject: &Path, dir: &Path) -> Subject {
    let usda = dir.join("x.usda");
    let o = surfcap!(&["--quiet", "export", p(subject), "--format", "usda", "-o", p(&usda)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = dir.join("back.subject");
    let o = surfcap!(&["import", p(&usda), "-o", p(&back)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(!text.contains("no up axis") && !text.contains("no units"), "metadata came from the file:\n{text}");
    let a = surfcap_mesh::cache::read_cache(subject, &NoProgress).unwrap();
    let b = surfcap_mesh::cache::read_cache(&back, &NoProgress).unwrap();
    assert_eq!(a.topology(), b.topology(), "topology (with UVs)");
    assert_eq!((a.fps, a.up_axis), (b.fps, b.up_axis));
    assert_eq!(a.units.metres_per_unit, b.units.metres_per_unit);
    assert_eq!(a.sequences().len(), b.sequences().len());
    for (x, y) in a.sequences().iter().zip(b.sequences()) {
        assert_eq!(x.name, y.name);
        assert!(x.positions() == y.positions(), "positions of {} differ", x.name);
        assert_eq!(x.labels, y.labels, "labels of {}", x.name);
    }
    b
}

#[test]
fn surfcaps_usda_imports_back_exactly_kaykit_and_vlasic_crane() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    // A KayKit clip, with a synthetic interpolation so the labels are not all original.
    let walk = data.join("kaykit_adventurers/knight_Walking_A");
    let blend = d.path().join("blend.usda");
    let o = surfcap!(&[
        "--quiet",
        "interpolate",
        p(&walk),
        "--from",
        "knight_Walking_A:0",
        "--to",
        "knight_Walking_A:16",
        "--steps",
        "5",
        "--format",
        "usda",
        "-o",
        p(&blend)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // As Pixar's USD reads them: the interpolation's ends original, the rest synthetic.
    let u = surfcap_testkit::read_usd(&blend);
    let labels: Vec<u64> = u["meshes"][0]["labels"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    assert_eq!(labels, [0, 1, 1, 1, 0]);
    let knight = d.path().join("knight.subject");
    let o = surfcap!(&["--quiet", "import", p(&walk), "-o", p(&knight)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let b = round_trip(&knight, d.path());
    assert_eq!(b.sequences()[0].n_frames(), 33);
    // The interpolation written as usda: its labels come back (ends original, the rest synthetic).
    let back = d.path().join("blend-back.subject");
    let o = surfcap!(&["--quiet", "import", p(&blend), "-o", p(&back)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = surfcap_mesh::cache::read_cache(&back, &NoProgress).unwrap();
    let synthetic: Vec<bool> =
        s.sequences()[0].labels.iter().map(|l| *l == surfcap_mesh::FrameLabel::Synthetic).collect();
    assert_eq!(synthetic, [false, true, true, true, false]);

    // Vlasic crane cut to 10 frames, written as a small subject.
    let crane = surfcap_formats::import::import(&[data.join("vlasic2008/crane")], &Default::default(), &NoProgress)
        .unwrap()
        .subject;
    let v = crane.topology().n_vertices();
    let seq = Sequence::new("crane", v, crane.sequences()[0].positions()[..10 * v * 3].to_vec()).unwrap();
    let small =
        Subject::new("crane10", crane.topology().clone(), vec![seq], crane.fps, crane.up_axis, crane.units.clone())
            .unwrap();
    let path = d.path().join("crane10.subject");
    surfcap_mesh::cache::write_cache(&path, &small, false, &NoProgress).unwrap();
    let c = tempfile::tempdir().unwrap();
    let b = round_trip(&path, c.path());
    assert_eq!((b.n_frames(), b.topology().n_triangles(), b.fps), (10, 20000, 30.0));
}

const PIXAR: &str = r#"
import sys
from pxr import Usd, UsdGeom, Vt, Gf
stage = Usd.Stage.CreateInMemory()
stage.SetTimeCodesPerSecond(24)
stage.SetStartTimeCode(1)
stage.SetEndTimeCode(4)
UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
UsdGeom.SetStageMetersPerUnit(stage, 0.01)
root = UsdGeom.Xform.Define(stage, "/grid")
stage.SetDefaultPrim(root.GetPrim())
root.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
mesh = UsdGeom.Mesh.Define(stage, "/grid/sheet")
# A 3 x 2 grid of quads (12 points) plus one triangle.
mesh.CreateFaceVertexCountsAttr([4, 4, 4, 4, 4, 4, 3])
ix = []
for r in range(2):
    for c in range(3):
        a = r * 4 + c
        ix += [a, a + 1, a + 5, a + 4]
ix += [3, 12, 7]
mesh.CreateFaceVertexIndicesAttr(ix)
pts = mesh.CreatePointsAttr()
for t in range(1, 5):
    p = [Gf.Vec3f(c * 0.1, r * 0.1, 0.01 * t * c + 1.0 / 3.0) for r in range(3) for c in range(4)]
    p.append(Gf.Vec3f(0.5, 0.05, 0.0))
    pts.Set(Vt.Vec3fArray(p), Usd.TimeCode(t))
UsdGeom.Scope.Define(stage, "/grid/looks")
stage.GetRootLayer().Export(sys.argv[1])
stage.GetRootLayer().Export(sys.argv[2])
"#;

#[test]
fn a_stage_written_by_pixars_usd_imports_with_quads_fanned() {
    let Some(_) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let (usda, usdc) = (d.path().join("grid.usda"), d.path().join("grid.usdc"));
    python_usd(PIXAR, &[&usda, &usdc]);
    let out = d.path().join("grid.subject");
    let o = surfcap!(&["import", p(&usda), "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(said.contains("xformOp:translate of </grid> (line"), "the ignored transform is noted:\n{said}");
    let s = surfcap_mesh::cache::read_cache(&out, &NoProgress).unwrap();
    assert_eq!((s.fps, s.up_axis, s.units.metres_per_unit), (24.0, surfcap_mesh::UpAxis::PosZ, Some(0.01)));
    assert_eq!(s.sequences().len(), 1);
    let q = &s.sequences()[0];
    assert_eq!((q.name.as_str(), q.n_frames(), q.n_vertices()), ("sheet", 4, 13));
    let t = s.topology().triangles();
    assert_eq!(t.len(), 6 * 2 + 1);
    assert_eq!(&t[..2], &[[0, 1, 5], [0, 5, 4]], "the first quad (0, 1, 5, 4) fanned from its first corner");
    assert_eq!(t[12], [3, 12, 7]);
    // Frame k (time code k + 1): z of point (r, c) is 0.01 (k + 1) c + 1/3, as f32.
    for k in 0..4 {
        let z = q.frame(k)[3 * 3 + 2];
        assert_eq!(z, (0.01 * (k + 1) as f64 * 3.0 + 1.0 / 3.0) as f32, "frame {k}");
    }
    // The same stage as usd-core writes it in binary (its face indices integer-compressed):
    // the same subject.
    let from_usdc = d.path().join("c.subject");
    let o = surfcap!(&["import", p(&usdc), "-o", p(&from_usdc)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &stderr(&o);
    assert!(said.contains("xformOp:translate of </grid> is ignored"), "the ignored transform is noted:\n{said}");
    let c = surfcap_mesh::cache::read_cache(&from_usdc, &NoProgress).unwrap();
    assert_eq!((c.fps, c.up_axis, &c.units), (s.fps, s.up_axis, &s.units));
    assert_eq!(c.sequences()[0].name, "sheet");
    assert!(c.sequences()[0].positions() == q.positions());
    assert!(c.topology().first_difference(s.topology()).is_none());
}

/// Per-frame reconstructions as Pixar's USD writes them: a mesh whose faces and point count
/// are time-sampled and change between frames.
const PIXAR_VARYING: &str = r#"
import sys
from pxr import Usd, UsdGeom, Vt, Gf
stage = Usd.Stage.CreateInMemory()
stage.SetTimeCodesPerSecond(25)
mesh = UsdGeom.Mesh.Define(stage, "/capture")
counts, indices, points = mesh.CreateFaceVertexCountsAttr(), mesh.CreateFaceVertexIndicesAttr(), mesh.CreatePointsAttr()
for t in range(3):
    # Frame t: a fan of t + 1 triangles around point 0.
    n = t + 3
    p = [Gf.Vec3f(0, 0, 0.1 * t)] + [Gf.Vec3f(float(k), 1.0, 0.1 * t) for k in range(n - 1)]
    points.Set(Vt.Vec3fArray(p), Usd.TimeCode(t))
    counts.Set([3] * (n - 2), Usd.TimeCode(t))
    indices.Set(sum([[0, k + 1, k + 2] for k in range(n - 2)], []), Usd.TimeCode(t))
stage.GetRootLayer().Export(sys.argv[1])
"#;

#[test]
fn a_stage_whose_faces_change_imports_as_a_frame_set() {
    let Some(_) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let usda = d.path().join("capture.usda");
    python_usd(PIXAR_VARYING, &[&usda]);
    let o = surfcap!(&["import", p(&usda), "-o", p(&d.path().join("c.subject"))]);
    assert!(!o.status.success() && stderr(&o).contains("frame set"), "{}", stderr(&o));
    let out = d.path().join("c.frames");
    let o = surfcap!(&["--quiet", "import", p(&usda), "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let set = surfcap_mesh::frame_set_cache::read_frame_set(&out, &NoProgress).unwrap();
    let q = &set.sequences()[0];
    let sizes: Vec<(usize, usize)> = q.frames().iter().map(|f| (f.n_vertices(), f.n_triangles())).collect();
    assert_eq!(sizes, [(3, 1), (4, 2), (5, 3)]);
    assert_eq!(set.fps, 25.0);
    assert_eq!(q.frames()[2].positions()[2], 0.2f32);
}

//! The folder of a generated benchmark sequence ([`crate::texture_generator`]), written
//! atomically (`surfcap_mesh::atomic::write_dir`, marker kind [`OUTPUT_KIND`]) and read back by
//! [`GeneratedFrames::open`], which checks every file's presence and shape before use:
//!
//! - `frames.json`: [`FramesHeader`] (seed, options, source mesh and texture, sizes, the drift
//!   model's waves, light directions and colour gains per frame, the holes, file names);
//! - `frame_000.png` ...: the degraded frames (8-bit RGB; at least three digits, more when
//!   there are 1000 frames or more);
//! - `clean_000.png` ...: the ground truth before noise and holes;
//! - `holes.npy`: u8 `[K, H, W]`, 1 in the hole, one layer per frame with a hole, in the order
//!   of `hole_frames` (only those frames: a full `[F, H, W]` would be 100 MB of zeros at 1024);
//! - `template.obj`: a copy of the mesh (the UV atlas the textures belong to);
//! - `displacement.npy` (only when asked, 800 MB for 100 frames at 1024): f32 `[F, 2, H, W]`,
//!   `d_k` as `[u, v]` in texels. Without it, [`GeneratedFrames::displacement`] recomputes the
//!   same field from the waves in `frames.json` (stored to the bit).
//!
//! The ground-truth flow between frames is [`GeneratedFrames::true_flow`] (the convention of
//! [`crate::texture_drift`]: `warp_direct(frame_to, w) ~ frame_from`).

use std::path::{Path, PathBuf};

use npyz::WriterBuilder;
use rayon::prelude::*;
use surfcap_mesh::Progress;
use surfcap_mesh::atomic::{write_dir, write_file};
use surfcap_mesh::npy::{read_npy, write_npy};

use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::texture_drift::DriftModel;
use crate::texture_generator::{GeneratorOptions, Hole, TextureGenerator, read_uv_mesh};
use crate::texture_image::TextureImage;

/// The marker kind of the folder.
pub const OUTPUT_KIND: &str = "appearance-frames";
const HEADER_FILE: &str = "frames.json";
const FORMAT: &str = "surfcap-appearance-frames";
const VERSION: u32 = 1;
const MESH_FILE: &str = "template.obj";
const HOLES_FILE: &str = "holes.npy";
const DISPLACEMENT_FILE: &str = "displacement.npy";

/// `frames.json`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FramesHeader {
    pub format: String,
    pub version: u32,
    pub frames: usize,
    pub seed: u64,
    pub width: usize,
    pub height: usize,
    pub options: GeneratorOptions,
    /// The mesh and texture generated from, as given.
    pub source_mesh: PathBuf,
    pub source_texture: PathBuf,
    pub source_texture_size: [usize; 2],
    /// The copy of the mesh in the folder.
    pub mesh: String,
    pub drift: DriftModel,
    /// Largest `|d_k|` any frame can reach, texels.
    pub drift_bound: f64,
    /// Unit light direction per frame (+y up, +z the subject's front).
    pub lights: Vec<[f64; 3]>,
    /// Per-channel colour gain per frame.
    pub gains: Vec<[f64; 3]>,
    /// Frames with a hole, increasing (the layers of `holes.npy`).
    pub hole_frames: Vec<usize>,
    pub holes: Vec<Hole>,
    pub frame_files: Vec<String>,
    pub clean_files: Vec<String>,
    pub holes_file: String,
    pub displacement_file: Option<String>,
    /// How to read the flows, for people opening the folder without surfcap.
    pub convention: String,
}

fn names(prefix: &str, frames: usize) -> Vec<String> {
    let digits = (frames.saturating_sub(1)).to_string().len().max(3);
    (0..frames).map(|k| format!("{prefix}_{k:0digits$}.png")).collect()
}

/// Writes `generator`'s sequence as the folder `out` (see the module documentation), with
/// `displacement.npy` when `displacement` is true; `progress` counts frames.
#[allow(clippy::too_many_arguments)]
pub(crate) fn write(
    generator: &TextureGenerator,
    mesh: &Path,
    texture: &Path,
    texture_size: [usize; 2],
    mesh_bytes: &[u8],
    out: &Path,
    force: bool,
    displacement: bool,
    progress: &dyn Progress,
) -> Result<FramesHeader> {
    let o = generator.options();
    let (w, h) = (generator.width(), generator.height());
    let hole_frames: Vec<usize> = generator.holes().iter().map(|x| x.frame).collect();
    let header = FramesHeader {
        format: FORMAT.into(),
        version: VERSION,
        frames: o.frames,
        seed: o.seed,
        width: w,
        height: h,
        options: o.clone(),
        source_mesh: mesh.to_path_buf(),
        source_texture: texture.to_path_buf(),
        source_texture_size: texture_size,
        mesh: MESH_FILE.into(),
        drift: generator.drift().clone(),
        drift_bound: generator.drift().bound(),
        lights: generator.lights().to_vec(),
        gains: generator.gains().to_vec(),
        hole_frames: hole_frames.clone(),
        holes: generator.holes().to_vec(),
        frame_files: names("frame", o.frames),
        clean_files: names("clean", o.frames),
        holes_file: HOLES_FILE.into(),
        displacement_file: displacement.then(|| DISPLACEMENT_FILE.into()),
        convention: "texels, x right, y down, row 0 = v 1. frame_k(x) = shading_k(x) * T(x + d_k(x)) before blur, \
                     noise and holes; the true flow w from frame a to frame b satisfies frame_a(x) = frame_b(x + w(x)) \
                     (warp_direct(frame_b, w) ~ frame_a), i.e. x + w(x) + d_b(x + w(x)) = x + d_a(x)"
            .into(),
    };
    let json =
        serde_json::to_vec_pretty(&header).map_err(|e| Error::Invalid(format!("cannot encode {HEADER_FILE}: {e}")))?;
    // The folder writer's closure speaks the data layer's errors: a frame's own error is kept
    // aside and returned as it was.
    let failed: std::sync::Mutex<Option<Error>> = std::sync::Mutex::new(None);
    progress.start("generating texture frames", o.frames as u64);
    let written = write_dir(out, OUTPUT_KIND, force, |dir| {
        write_file(&dir.join(MESH_FILE), |wr| wr.write_all(mesh_bytes))?;
        let frames = (0..o.frames).into_par_iter().try_for_each(|k| -> std::result::Result<(), ()> {
            let result = generator.frame(k).and_then(|f| {
                f.frame.write_png(&dir.join(&header.frame_files[k]))?;
                f.clean.write_png(&dir.join(&header.clean_files[k]))
            });
            progress.advance(1);
            result.map_err(|e| {
                failed.lock().expect("no panic while holding the lock").get_or_insert(e);
            })
        });
        if frames.is_err() {
            return Err(surfcap_mesh::Error::new(surfcap_mesh::ErrorKind::Io, "a frame could not be written"));
        }
        let mut holes = Vec::with_capacity(hole_frames.len() * w * h);
        for &k in &hole_frames {
            let m = generator.hole_mask(k).expect("a listed hole frame has a mask");
            holes.extend(m.iter().map(|&b| b as u8));
        }
        write_file(&dir.join(HOLES_FILE), |wr| write_npy(wr, &[hole_frames.len(), h, w], &holes))?;
        if displacement {
            write_file(&dir.join(DISPLACEMENT_FILE), |wr| {
                let shape = [o.frames as u64, 2, h as u64, w as u64];
                let mut npy = npyz::WriteOptions::new().default_dtype().shape(&shape).writer(wr).begin_nd()?;
                for k in 0..o.frames {
                    let d = generator.drift().displacement(k);
                    npy.extend(d.u.iter().copied())?;
                    npy.extend(d.v.iter().copied())?;
                }
                npy.finish()
            })?;
        }
        write_file(&dir.join(HEADER_FILE), |wr| wr.write_all(&json))
    });
    if let Some(e) = failed.into_inner().expect("no panic while holding the lock") {
        return Err(e);
    }
    written?;
    progress.finish();
    Ok(header)
}

/// A generated sequence on disk, checked on opening.
#[derive(Debug, Clone)]
pub struct GeneratedFrames {
    dir: PathBuf,
    header: FramesHeader,
    /// `[K, H, W]` hole layers, in `hole_frames` order.
    holes: Vec<u8>,
}

impl GeneratedFrames {
    /// Opens the folder: reads `frames.json` and `holes.npy` and checks that every file it
    /// names is there, the header agrees with itself and the holes' shape is `[K, H, W]`.
    pub fn open(dir: &Path) -> Result<GeneratedFrames> {
        let hp = dir.join(HEADER_FILE);
        let text = surfcap_mesh::read_regular_file(&hp)?;
        let header: FramesHeader = serde_json::from_slice(&text).map_err(|e| {
            Error::Invalid(format!(
                "{}: not a generated texture sequence's description (line {}): {e}",
                hp.display(),
                e.line()
            ))
        })?;
        let bad = |m: String| Error::Invalid(format!("{}: {m}", hp.display()));
        if header.format != FORMAT || header.version != VERSION {
            return Err(bad(format!(
                "format {:?} version {}: expected {FORMAT:?} version {VERSION} (generate the sequence again with this surfcap)",
                header.format, header.version
            )));
        }
        let f = header.frames;
        if header.frame_files.len() != f
            || header.clean_files.len() != f
            || header.lights.len() != f
            || header.gains.len() != f
        {
            return Err(bad(format!("{f} frames, but the file, light and gain lists do not all have {f} entries")));
        }
        if header.drift.width != header.width || header.drift.height != header.height {
            return Err(bad(format!(
                "the drift model is {}x{}: expected {}x{} like the textures",
                header.drift.width, header.drift.height, header.width, header.height
            )));
        }
        if header.hole_frames.iter().any(|&k| k >= f) || header.hole_frames.windows(2).any(|p| p[0] >= p[1]) {
            return Err(bad(format!("hole_frames must be increasing frame numbers below {f}")));
        }
        for name in header.frame_files.iter().chain(&header.clean_files).chain([&header.mesh]) {
            if !dir.join(name).is_file() {
                return Err(Error::Invalid(format!("{}: missing (named by {HEADER_FILE})", dir.join(name).display())));
            }
        }
        let holes_path = dir.join(&header.holes_file);
        let holes = read_npy::<u8>(&holes_path)?;
        let want = [header.hole_frames.len(), header.height, header.width];
        if holes.shape != want {
            return Err(Error::Invalid(format!(
                "{}: shape {:?}: expected [{}, {}, {}] (one layer per frame with a hole)",
                holes_path.display(),
                holes.shape,
                want[0],
                want[1],
                want[2]
            )));
        }
        if let Some(d) = &header.displacement_file {
            let p = dir.join(d);
            if !p.is_file() {
                return Err(Error::Invalid(format!("{}: missing (named by {HEADER_FILE})", p.display())));
            }
        }
        Ok(GeneratedFrames { dir: dir.to_path_buf(), header, holes: holes.data })
    }

    pub fn header(&self) -> &FramesHeader {
        &self.header
    }
    pub fn dir(&self) -> &Path {
        &self.dir
    }
    pub fn frames(&self) -> usize {
        self.header.frames
    }
    pub fn width(&self) -> usize {
        self.header.width
    }
    pub fn height(&self) -> usize {
        self.header.height
    }

    fn read_texture(&self, name: &str, k: usize) -> Result<TextureImage> {
        let path = self.dir.join(name);
        let t = TextureImage::read(&path)?;
        if t.width() != self.width() || t.height() != self.height() {
            return Err(Error::Mismatch(format!(
                "{} (frame {k}) is {}x{}: expected {}x{} like {HEADER_FILE} says",
                path.display(),
                t.width(),
                t.height(),
                self.width(),
                self.height()
            )));
        }
        Ok(t)
    }

    fn check_frame(&self, k: usize) -> Result<()> {
        if k < self.frames() {
            return Ok(());
        }
        Err(Error::Invalid(format!("frame {k}: {} holds {} frames", self.dir.display(), self.frames())))
    }

    /// The degraded frame `k`.
    pub fn frame(&self, k: usize) -> Result<TextureImage> {
        self.check_frame(k)?;
        self.read_texture(&self.header.frame_files[k], k)
    }

    /// The clean frame `k` (ground truth before noise and holes).
    pub fn clean(&self, k: usize) -> Result<TextureImage> {
        self.check_frame(k)?;
        self.read_texture(&self.header.clean_files[k], k)
    }

    /// The hole mask of frame `k` (row-major), `None` when the frame has no hole.
    pub fn hole(&self, k: usize) -> Option<Vec<bool>> {
        let j = self.header.hole_frames.iter().position(|&f| f == k)?;
        let n = self.width() * self.height();
        Some(self.holes[j * n..(j + 1) * n].iter().map(|&b| b != 0).collect())
    }

    /// The template mesh (topology with its UV atlas, positions).
    pub fn mesh(&self) -> Result<(surfcap_mesh::Topology, Vec<f32>)> {
        read_uv_mesh(&self.dir.join(&self.header.mesh))
    }

    pub fn drift(&self) -> &DriftModel {
        &self.header.drift
    }

    /// The displacement `d_k` (frame_k = T(x + d_k(x)) before shading), recomputed from the
    /// stored waves.
    pub fn displacement(&self, k: usize) -> Result<FlowField> {
        self.check_frame(k)?;
        Ok(self.header.drift.displacement(k))
    }

    /// The ground-truth flow `w` with `frame_from(x) ~ frame_to(x + w(x))`, i.e.
    /// `warp_direct(frame_to, w) ~ frame_from` (up to illumination, blur and noise).
    pub fn true_flow(&self, from: usize, to: usize) -> Result<FlowField> {
        self.check_frame(from)?;
        self.check_frame(to)?;
        Ok(self.header.drift.true_flow(from, to))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture_generator::write_generated_frames;

    #[test]
    fn the_head_sequence_is_written_and_read_back() {
        let Some(data) = surfcap_testkit::shared_data() else { return };
        let head = data.join("leeperrysmith_head");
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("gen");
        let opts =
            GeneratorOptions { frames: 7, seed: 4, size: Some(128), hole_fraction: 0.3, ..GeneratorOptions::default() };
        let header = write_generated_frames(
            &head.join("template.obj"),
            &head.join("Map-COL.jpg"),
            &opts,
            &out,
            false,
            false,
            &surfcap_mesh::NoProgress,
        )
        .unwrap();
        assert_eq!(header.hole_frames.len(), 2);
        let g = GeneratedFrames::open(&out).unwrap();
        assert_eq!((g.frames(), g.width(), g.height()), (7, 128, 128));
        assert_eq!(g.header(), &header);
        assert!(out.join("frame_006.png").is_file() && out.join("clean_000.png").is_file());
        // What was written is what the generator makes (to 8-bit rounding).
        let (topo, pos) = g.mesh().unwrap();
        let src = TextureImage::read(&head.join("Map-COL.jpg")).unwrap();
        let generator = TextureGenerator::new(&topo, &pos, &src, &opts).unwrap();
        let k = header.hole_frames[1];
        let made = generator.frame(k).unwrap();
        let read = g.frame(k).unwrap();
        let worst = made.frame.data().iter().zip(read.data()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(worst <= 0.5 + 1e-3, "{worst}");
        assert_eq!(g.hole(k), made.hole);
        let plain = (0..7).find(|f| !header.hole_frames.contains(f)).unwrap();
        assert!(g.hole(plain).is_none());
        assert_eq!(g.displacement(3).unwrap(), generator.drift().displacement(3));
        // Rewriting the same kind of folder is allowed; a damaged folder is refused by name.
        std::fs::remove_file(out.join("clean_002.png")).unwrap();
        let e = GeneratedFrames::open(&out).unwrap_err().to_string();
        assert!(e.contains("clean_002.png") && e.contains("missing"), "{e}");
        std::fs::write(out.join("clean_002.png"), b"x").unwrap();
        std::fs::write(out.join("holes.npy"), b"x").unwrap();
        let e = GeneratedFrames::open(&out).unwrap_err().to_string();
        assert!(e.contains("holes.npy"), "{e}");
    }

    #[test]
    fn file_names_widen_past_a_thousand_frames() {
        assert_eq!(names("frame", 100)[99], "frame_099.png");
        assert_eq!(names("clean", 1500)[7], "clean_0007.png");
    }
}

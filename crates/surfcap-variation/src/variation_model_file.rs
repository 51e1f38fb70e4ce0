//! The variation model on disk: a folder (kind [`KIND`], written atomically by
//! `surfcap_mesh::atomic::write_dir`) that numpy opens:
//!
//! - `model.json`: format, version, subject (name, up axis, fps, units), the body parts, the
//!   reference sequence, every learnt sequence (name, origin, own frame count, time map, first
//!   placement as a row-major rotation and a translation), the displacement scales, and per
//!   part its GPDM's kernels (log-parameters), sequence lengths and fit report;
//! - `faces.npy` (u32 [T, 3]) and `reference_pose.npy` (f32 [V, 3]): what stitching needs;
//! - per part k: `part_<k>_latent.npy` (f64 [N, d], the learnt latent positions, sequences
//!   concatenated in `model.json`'s order) and `part_<k>_frames.npy` (f64 [N, D], the
//!   training vectors: the part's vertex coordinates in the body frame, the root part's rows
//!   ending with the 6 scaled displacement numbers).
//!
//! Loading checks every shape against `model.json` and names the file at fault; the GPDMs'
//! factorisations and the stitching's Poisson factorisation are recomputed (seconds).

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use surfcap_learn::Mat;
use surfcap_learn::gpdm::{Gpdm, GpdmSpec};
use surfcap_learn::kernels::Kernel;
use surfcap_mesh::npy::{NpyElement, expect_shape, read_npy, write_npy};
use surfcap_mesh::{Topology, Units, UpAxis};
use surfcap_transfer::BodyParts;
use surfcap_transfer::pose_representation::Placement;

use crate::error::{Error, Result};
use crate::motion_preparation::SequenceOrigin;
use crate::variation_model::{LearntSequence, ModelParts, PartFit, VariationModel};

/// The folder kind of a saved model (its marker).
pub const KIND: &str = "variation-model";
/// `model.json`'s format name and version.
pub const FORMAT: &str = "surfcap-variation-model";
pub const VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    subject: String,
    up_axis: UpAxis,
    fps: f64,
    units: Units,
    vertices: usize,
    triangles: usize,
    reference: String,
    frames: usize,
    parts: BodyParts,
    sequences: Vec<SequenceRecord>,
    displacement_scales: [f64; 6],
    part_models: Vec<PartRecord>,
}

#[derive(Serialize, Deserialize)]
struct SequenceRecord {
    name: String,
    origin: SequenceOrigin,
    own_frames: usize,
    times: Vec<f64>,
    /// Row-major 3x3.
    first_rotation: [f64; 9],
    first_translation: [f64; 3],
    /// Per reference frame, the placement: row-major rotation then translation.
    path: Vec<[f64; 12]>,
}

#[derive(Serialize, Deserialize)]
struct PartRecord {
    latent_dim: usize,
    dimensions: usize,
    sequence_lengths: Vec<usize>,
    kernel_y: Kernel,
    kernel_x: Kernel,
    fit: PartFit,
}

impl VariationModel {
    /// Writes the model folder at `path` (replacing only surfcap's own model folder, or any
    /// folder with `force`).
    pub fn save(&self, path: &Path, force: bool) -> Result<()> {
        surfcap_mesh::atomic::write_dir(path, KIND, force, |dir| self.write_files(dir).map_err(to_mesh_error))?;
        Ok(())
    }

    fn write_files(&self, dir: &Path) -> Result<()> {
        let head = Header {
            format: FORMAT.into(),
            version: VERSION,
            subject: self.subject.clone(),
            up_axis: self.up_axis,
            fps: self.fps,
            units: self.units.clone(),
            vertices: self.topology.n_vertices(),
            triangles: self.topology.triangles().len(),
            reference: self.reference.clone(),
            frames: self.frames,
            parts: self.parts.clone(),
            sequences: self
                .sequences
                .iter()
                .map(|s| {
                    let r = s.first_placement.rotation;
                    let t = s.first_placement.translation;
                    SequenceRecord {
                        name: s.name.clone(),
                        origin: s.origin.clone(),
                        own_frames: s.own_frames,
                        times: s.times.clone(),
                        first_rotation: std::array::from_fn(|k| r[(k / 3, k % 3)]),
                        first_translation: [t.x, t.y, t.z],
                        path: s
                            .path
                            .iter()
                            .map(|p| {
                                std::array::from_fn(|k| {
                                    if k < 9 { p.rotation[(k / 3, k % 3)] } else { p.translation[k - 9] }
                                })
                            })
                            .collect(),
                    }
                })
                .collect(),
            displacement_scales: self.displacement_scales,
            part_models: self
                .part_models
                .iter()
                .zip(&self.fits)
                .map(|(g, fit)| {
                    let spec = g.spec();
                    PartRecord {
                        latent_dim: g.latent_dim(),
                        dimensions: g.output_dim(),
                        sequence_lengths: spec.sequence_lengths.clone(),
                        kernel_y: spec.kernel_y.clone(),
                        kernel_x: spec.kernel_x.clone(),
                        fit: fit.clone(),
                    }
                })
                .collect(),
        };
        surfcap_mesh::atomic::write_file(&dir.join("model.json"), |w| {
            serde_json::to_writer_pretty(w, &head).map_err(std::io::Error::other)
        })?;
        let faces: Vec<u32> = self.topology.triangles().iter().flatten().copied().collect();
        let nt = self.topology.triangles().len();
        surfcap_mesh::atomic::write_file(&dir.join("faces.npy"), |w| write_npy(w, &[nt, 3], &faces))?;
        let nv = self.topology.n_vertices();
        surfcap_mesh::atomic::write_file(&dir.join("reference_pose.npy"), |w| {
            write_npy(w, &[nv, 3], &self.reference_pose)
        })?;
        for (k, g) in self.part_models.iter().enumerate() {
            let spec = g.spec();
            let flat = |m: &Mat<f64>| -> Vec<f64> {
                (0..m.nrows()).flat_map(|i| (0..m.ncols()).map(move |j| (i, j))).map(|(i, j)| m[(i, j)]).collect()
            };
            let (lat, y) = (&spec.latent, &spec.y);
            surfcap_mesh::atomic::write_file(&dir.join(format!("part_{k}_latent.npy")), |w| {
                write_npy(w, &[lat.nrows(), lat.ncols()], &flat(lat))
            })?;
            surfcap_mesh::atomic::write_file(&dir.join(format!("part_{k}_frames.npy")), |w| {
                write_npy(w, &[y.nrows(), y.ncols()], &flat(y))
            })?;
        }
        Ok(())
    }

    /// Reads a model folder written by [`VariationModel::save`].
    pub fn load(dir: &Path) -> Result<VariationModel> {
        let path = dir.join("model.json");
        let bytes = surfcap_mesh::read_regular_file(&path)?;
        let bad = |why: String| Error::Model(format!("{}: {why}", path.display()));
        let head: Header = serde_json::from_slice(&bytes)
            .map_err(|e| bad(format!("{e}: expected a model written by surfcap vary train")))?;
        if head.format != FORMAT || head.version != VERSION {
            return Err(bad(format!(
                "format {:?} version {}: expected {FORMAT:?} version {VERSION} (train again with this surfcap)",
                head.format, head.version
            )));
        }
        // Names and rate checked here, so that the error names this file (the parts' own check
        // and the model's do not know it).
        head.parts.validate().map_err(|e| bad(format!("{e}")))?;
        surfcap_mesh::subject::check_sequence_names(head.sequences.iter().map(|s| s.name.as_str()))
            .map_err(|e| bad(e.message.to_string()))?;
        surfcap_mesh::subject::check_frame_rate(head.fps).map_err(|e| bad(format!("fps: {}", e.message)))?;
        if head.part_models.len() != head.parts.len() {
            return Err(bad(format!(
                "{} part models for {} body parts: expected one per part",
                head.part_models.len(),
                head.parts.len()
            )));
        }
        let (nv, nt) = (head.vertices, head.triangles);
        // Every size the header declares is checked against the arrays' files before anything
        // is allocated from it: the reference pose fixes the vertex count before the topology
        // (which allocates per vertex) is made, and an edited frame count cannot overflow.
        let reference_pose =
            load_array::<f32>(&dir.join("reference_pose.npy"), &[Some(nv), Some(3)], "the reference pose")?;
        let faces = load_array::<u32>(&dir.join("faces.npy"), &[Some(nt), Some(3)], "the triangles")?;
        let triangles: Vec<[u32; 3]> = faces.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let topology = Topology::new(nv, triangles, None).map_err(|e| e.in_file(&dir.join("faces.npy")))?;
        let n: usize = head.frames.checked_mul(head.sequences.len()).ok_or_else(|| {
            bad(format!(
                "{} frames x {} sequences: expected a frame count that fits",
                head.frames,
                head.sequences.len()
            ))
        })?;
        let mut part_models = Vec::with_capacity(head.parts.len());
        let mut fits = Vec::with_capacity(head.parts.len());
        for (k, rec) in head.part_models.into_iter().enumerate() {
            if rec.sequence_lengths.iter().sum::<usize>() != n {
                return Err(bad(format!(
                    "part {k}: sequence lengths {:?}: expected {} sequences of {} frames",
                    rec.sequence_lengths,
                    head.sequences.len(),
                    head.frames
                )));
            }
            let lat_path = dir.join(format!("part_{k}_latent.npy"));
            let latent = load_array::<f64>(&lat_path, &[Some(n), Some(rec.latent_dim)], "the latent positions")?;
            let y_path = dir.join(format!("part_{k}_frames.npy"));
            let y = load_array::<f64>(&y_path, &[Some(n), Some(rec.dimensions)], "the training frames")?;
            let (d, dd) = (rec.latent_dim, rec.dimensions);
            let spec = GpdmSpec {
                latent: Mat::from_fn(n, d, |i, j| latent[i * d + j]),
                sequence_lengths: rec.sequence_lengths,
                y: Mat::from_fn(n, dd, |i, j| y[i * dd + j]),
                kernel_y: rec.kernel_y,
                kernel_x: rec.kernel_x,
            };
            part_models.push(Gpdm::from_spec(spec).map_err(|e| bad(format!("part {k}: {e}")))?);
            fits.push(rec.fit);
        }
        let sequences = head
            .sequences
            .into_iter()
            .map(|s| {
                let r = s.first_rotation;
                LearntSequence {
                    name: s.name,
                    origin: s.origin,
                    own_frames: s.own_frames,
                    times: s.times,
                    first_placement: Placement {
                        rotation: Matrix3::from_row_slice(&r),
                        translation: Vector3::from(s.first_translation),
                    },
                    path: s
                        .path
                        .iter()
                        .map(|q| Placement {
                            rotation: Matrix3::from_row_slice(&q[..9]),
                            translation: Vector3::new(q[9], q[10], q[11]),
                        })
                        .collect(),
                }
            })
            .collect();
        VariationModel::from_parts(ModelParts {
            subject: head.subject,
            topology,
            up_axis: head.up_axis,
            fps: head.fps,
            units: head.units,
            parts: head.parts,
            reference_pose,
            reference: head.reference,
            sequences,
            part_models,
            displacement_scales: head.displacement_scales,
            fits,
        })
        .map_err(|e| match e {
            Error::Model(m) => Error::Model(format!("{}: {m}", dir.display())),
            other => Error::Model(format!("{}: {other}", dir.display())),
        })
    }
}

/// Reads an array of the expected shape whose values are all finite; errors name the file.
fn load_array<T: NpyElement + Copy + Into<f64>>(path: &Path, shape: &[Option<usize>], what: &str) -> Result<Vec<T>> {
    let a = read_npy::<T>(path)?;
    expect_shape(&a, shape, what).map_err(|e| e.in_file(path))?;
    if let Some(i) = a.data.iter().position(|x| !(*x).into().is_finite()) {
        return Err(Error::Model(format!("{}: value {i} of {what} is not finite", path.display())));
    }
    Ok(a.data)
}

fn to_mesh_error(e: Error) -> surfcap_mesh::Error {
    match e {
        Error::Mesh(m) => m,
        other => surfcap_mesh::Error::new(surfcap_mesh::ErrorKind::Metadata, other.to_string()),
    }
}

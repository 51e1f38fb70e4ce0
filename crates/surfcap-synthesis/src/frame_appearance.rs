//! Shape and appearance animated together (thesis Fig. 7.1): an appearance model
//! (`surfcap appearance build <maps> --mesh SUBJECT`) names its frames by the subject's
//! `sequence:frame` labels; every output frame of an animation gets a texture from it (captured
//! frames their reconstruction, transition frames the two frames interpolated in the eigen
//! spaces with the weight Blend gives the geometry: `surfcap_appearance::blended_frame_textures`),
//! and the animation is written as a glb of a frame set with a texture per frame. Other formats
//! cannot switch a texture per frame and are refused when the model is opened.

use std::path::{Path, PathBuf};

use serde::Serialize;
use surfcap_appearance::AppearanceModel;
use surfcap_appearance::blended_frame_textures::{TextureMix, blended_frame_textures};
use surfcap_formats::export::{ExportFormat, export_textured_glb};
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::{FrameTextures, Progress, Subject};
use surfcap_motion::transition_frames::FrameMix;

use crate::error::{Context, Error, Result, refuse};

/// An appearance model checked against the subject it textures.
pub struct SubjectAppearance {
    pub path: PathBuf,
    pub model: AppearanceModel,
    /// The model's frame of each global frame of the subject.
    frame_of: Vec<usize>,
    /// The subject's frame labels, for the report.
    labels: Vec<String>,
}

/// What texturing an animation produced: the textures to write and the report's entry.
pub struct Textured {
    pub textures: FrameTextures,
    pub report: AppearanceReport,
}

/// The report's `appearance`: the model, the counts, the time spent instantiating and, per
/// output frame, where its texture comes from.
#[derive(Debug, Clone, Serialize)]
pub struct AppearanceReport {
    pub model: PathBuf,
    pub eigen_textures: usize,
    pub eigen_warps: usize,
    /// Width and height of the maps, texels.
    pub size: [usize; 2],
    /// Distinct textures written.
    pub textures: usize,
    pub reconstructed: usize,
    pub interpolated: usize,
    pub instantiate_seconds: f64,
    pub per_frame: Vec<FrameTexture>,
}

/// Where one output frame's texture comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum FrameTexture {
    /// One captured frame's texture (`sequence:frame`), reconstructed.
    Frame { frame: String },
    /// Two frames' textures interpolated, `weight` the second's.
    Blend { from: String, to: String, weight: f64 },
}

impl SubjectAppearance {
    /// Opens the model at `path` for `subject`, whose animation goes to `output` in `format`:
    /// refused when the output is not a glb file, when the subject has no UV atlas, or when the
    /// model's frames are not the subject's.
    pub fn open(path: &Path, subject: &Subject, format: ExportFormat, output: &Path) -> Result<Self> {
        surfcap_mesh::output_path::check_not_input(output, &[path])?;
        let frames_folder = output.extension().is_some_and(|e| e == "frames");
        if format != ExportFormat::Glb || frames_folder {
            refuse!(
                "--appearance {}: a texture per frame is written as a glb (a mesh per frame, each with its texture); \
                 {} cannot carry one: write -o NAME.glb",
                path.display(),
                if frames_folder {
                    "a .frames folder".to_string()
                } else {
                    format!("--format {}", format.output_kind().trim_start_matches("export-"))
                }
            );
        }
        if subject.topology().uv().is_none() {
            refuse!(
                "--appearance {}: the subject {:?} has no texture coordinates: expected the UV atlas the model's maps \
                 follow (a subject made from a UV-mapped mesh, e.g. `surfcap make head` or `--uv-atlas`)",
                path.display(),
                subject.name
            );
        }
        let model = AppearanceModel::load(path)
            .with_context(|| format!("{}: cannot open the appearance model", path.display()))?;
        Self::new(path, model, subject)
    }

    /// A model already in memory (`path` is what reports call it), checked against `subject`.
    pub fn new(path: &Path, model: AppearanceModel, subject: &Subject) -> Result<Self> {
        let labels: Vec<String> = (0..subject.n_frames()).map(|g| subject.frame_index().label(g)).collect();
        let frame_of = model_frames(&model, &labels).with_context(|| {
            format!("--appearance {}: its frames are not those of {:?}", path.display(), subject.name)
        })?;
        Ok(SubjectAppearance { path: path.to_path_buf(), model, frame_of, labels })
    }

    /// The textures of an animation whose frames mix the subject's frames as `mix` says (global
    /// frame numbers), with the report's `appearance` entry.
    pub fn textures(&self, mix: &[FrameMix], progress: &dyn Progress) -> Result<Textured> {
        let model_frame = |g: u32| -> Result<usize> {
            self.frame_of.get(g as usize).copied().ok_or_else(|| {
                Error::Request(format!(
                    "frame {g} of the animation's source is past the subject's {} frames",
                    self.labels.len()
                ))
            })
        };
        let mixes = mix
            .iter()
            .map(|m| Ok(TextureMix { from: model_frame(m.from)?, to: model_frame(m.to)?, weight: m.weight as f64 }))
            .collect::<Result<Vec<_>>>()?;
        let made = blended_frame_textures(&self.model, &mixes, progress)
            .with_context(|| format!("{}: cannot make the textures", self.path.display()))?;
        let per_frame = mix
            .iter()
            .zip(&mixes)
            .map(|(m, t)| {
                if t.single_frame().is_some() {
                    let g = if m.from == m.to || m.weight == 0.0 { m.from } else { m.to };
                    FrameTexture::Frame { frame: self.labels[g as usize].clone() }
                } else {
                    // The f32 weight in its shortest decimal form (0.25, not 0.2500000037...).
                    let weight: f64 = m.weight.to_string().parse().expect("a float's text reads back");
                    FrameTexture::Blend {
                        from: self.labels[m.from as usize].clone(),
                        to: self.labels[m.to as usize].clone(),
                        weight,
                    }
                }
            })
            .collect();
        let report = AppearanceReport {
            model: self.path.clone(),
            eigen_textures: self.model.n_textures(),
            eigen_warps: self.model.n_warps(),
            size: [self.model.mask().width(), self.model.mask().height()],
            textures: made.images.len(),
            reconstructed: made.reconstructed,
            interpolated: made.interpolated,
            instantiate_seconds: made.seconds,
            per_frame,
        };
        let textures = FrameTextures::new(made.images, vec![made.frame_texture])?;
        Ok(Textured { textures, report })
    }
}

/// The model's frame of each of `labels`; an error saying what differs when the model's
/// frames are not exactly those labels.
fn model_frames(model: &AppearanceModel, labels: &[String]) -> Result<Vec<usize>> {
    let names = model.names();
    let hint =
        "build the model with `surfcap appearance build MAPS --mesh SUBJECT` from one map per frame of the subject";
    if names.len() != labels.len() {
        refuse!(
            "the model has {} frames ({}, ...), the subject {} ({}, ...): {hint}",
            names.len(),
            names.iter().take(3).cloned().collect::<Vec<_>>().join(", "),
            labels.len(),
            labels.iter().take(3).cloned().collect::<Vec<_>>().join(", ")
        );
    }
    let by_name: std::collections::HashMap<&str, usize> =
        names.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
    labels
        .iter()
        .enumerate()
        .map(|(g, label)| {
            by_name.get(label.as_str()).copied().ok_or_else(|| {
                Error::Request(format!(
                    "the subject's frame {label} is not in the model (the model's frame {g} is named {:?}): {hint}",
                    names[g]
                ))
            })
        })
        .collect()
}

/// Writes `animation` (one sequence) with its textures as a glb of a frame set; returns the
/// paths written (the glb, then its sidecar JSON).
pub fn write_textured(
    animation: &Subject,
    textured: &Textured,
    output: &Path,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    let set = FrameSet::from_subject(animation);
    Ok(export_textured_glb(&set, &textured.textures, output, progress)?)
}

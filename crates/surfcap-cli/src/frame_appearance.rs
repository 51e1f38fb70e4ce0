//! `--appearance MODEL` of `synth path | keyposes | reach` and `interpolate`: shape and
//! appearance animated together (thesis Fig. 7.1, issue 20 item 8). The model
//! (`surfcap appearance build <maps> --mesh SUBJECT`) names its frames by the subject's
//! `sequence:frame` labels; every output frame gets a texture from it (captured frames their
//! reconstruction, transition frames the two frames interpolated in the eigen spaces with the
//! weight Blend gives the geometry: `surfcap_appearance::blended_frame_textures`), and the
//! animation is written as a glb of a frame set with a texture per frame. Other formats cannot
//! switch a texture per frame and are refused.

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde_json::json;
use surfcap_appearance::AppearanceModel;
use surfcap_appearance::blended_frame_textures::{TextureMix, blended_frame_textures};
use surfcap_formats::export::{ExportFormat, export_textured_glb};
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::{FrameTextures, Subject};
use surfcap_motion::transition_frames::FrameMix;

/// The appearance model an animation's textures come from.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct AppearanceOpts {
    /// An appearance model of the subject's frames (`surfcap appearance build MAPS --mesh
    /// SUBJECT -o MODEL`, its frames named by the subject's `sequence:frame`): every output frame
    /// gets a texture (captured frames their reconstruction, transition frames interpolated in
    /// the eigen spaces with the geometry's blend weight), written as a glb with a texture per
    /// frame (the only format that can carry one).
    #[arg(long)]
    pub appearance: Option<PathBuf>,
}

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
    pub report: serde_json::Value,
}

impl AppearanceOpts {
    /// Opens the model when one is given: refused when the output is not a glb file, when the
    /// subject has no UV atlas, or when the model's frames are not the subject's.
    pub fn open(
        &self,
        subject: &Subject,
        format: ExportFormat,
        output: &Path,
    ) -> anyhow::Result<Option<SubjectAppearance>> {
        let Some(path) = &self.appearance else { return Ok(None) };
        surfcap_mesh::output_path::check_not_input(output, &[path])?;
        let frames_folder = output.extension().is_some_and(|e| e == "frames");
        anyhow::ensure!(
            format == ExportFormat::Glb && !frames_folder,
            "--appearance {}: a texture per frame is written as a glb (a mesh per frame, each with its texture); \
             {} cannot carry one: write -o NAME.glb",
            path.display(),
            if frames_folder {
                "a .frames folder".to_string()
            } else {
                format!("--format {}", format.output_kind().trim_start_matches("export-"))
            }
        );
        anyhow::ensure!(
            subject.topology().uv().is_some(),
            "--appearance {}: the subject {:?} has no texture coordinates: expected the UV atlas the model's maps \
             follow (a subject made from a UV-mapped mesh, e.g. `surfcap synth --head` or `--uv-atlas`)",
            path.display(),
            subject.name
        );
        let model = AppearanceModel::load(path)
            .with_context(|| format!("{}: cannot open the appearance model", path.display()))?;
        let labels: Vec<String> = (0..subject.n_frames()).map(|g| subject.frame_index().label(g)).collect();
        let frame_of = model_frames(&model, &labels).with_context(|| {
            format!("--appearance {}: its frames are not those of {:?}", path.display(), subject.name)
        })?;
        Ok(Some(SubjectAppearance { path: path.clone(), model, frame_of, labels }))
    }
}

/// The model's frame of each of `labels`; an error saying what differs when the model's
/// frames are not exactly those labels.
fn model_frames(model: &AppearanceModel, labels: &[String]) -> anyhow::Result<Vec<usize>> {
    let names = model.names();
    let hint =
        "build the model with `surfcap appearance build MAPS --mesh SUBJECT` from one map per frame of the subject";
    anyhow::ensure!(
        names.len() == labels.len(),
        "the model has {} frames ({}, ...), the subject {} ({}, ...): {hint}",
        names.len(),
        names.iter().take(3).cloned().collect::<Vec<_>>().join(", "),
        labels.len(),
        labels.iter().take(3).cloned().collect::<Vec<_>>().join(", ")
    );
    let by_name: std::collections::HashMap<&str, usize> =
        names.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
    labels
        .iter()
        .enumerate()
        .map(|(g, label)| {
            by_name.get(label.as_str()).copied().ok_or_else(|| {
                anyhow::anyhow!(
                    "the subject's frame {label} is not in the model (the model's frame {g} is named {:?}): {hint}",
                    names[g]
                )
            })
        })
        .collect()
}

impl SubjectAppearance {
    /// The textures of an animation whose frames mix the subject's frames as `mix` says (global
    /// frame numbers), with the report's `appearance` entry: the model, the counts, the time
    /// spent instantiating and, per output frame, the frame its texture is or the two frames
    /// and the weight of the second.
    pub fn textures(&self, ctx: &crate::Ctx, mix: &[FrameMix]) -> anyhow::Result<Textured> {
        let model_frame = |g: u32| -> anyhow::Result<usize> {
            self.frame_of.get(g as usize).copied().ok_or_else(|| {
                anyhow::anyhow!(
                    "frame {g} of the animation's source is past the subject's {} frames",
                    self.labels.len()
                )
            })
        };
        let mixes = mix
            .iter()
            .map(|m| Ok(TextureMix { from: model_frame(m.from)?, to: model_frame(m.to)?, weight: m.weight as f64 }))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let bar = crate::progress::Bar::new(ctx);
        let made = blended_frame_textures(&self.model, &mixes, &bar)
            .with_context(|| format!("{}: cannot make the textures", self.path.display()))?;
        let per_frame: Vec<serde_json::Value> = mix
            .iter()
            .zip(&mixes)
            .map(|(m, t)| {
                if t.single_frame().is_some() {
                    let g = if m.from == m.to || m.weight == 0.0 { m.from } else { m.to };
                    json!({ "frame": self.labels[g as usize] })
                } else {
                    // The f32 weight in its shortest decimal form (0.25, not 0.2500000037...).
                    let weight: f64 = m.weight.to_string().parse().expect("a float's text reads back");
                    json!({ "from": self.labels[m.from as usize], "to": self.labels[m.to as usize], "weight": weight })
                }
            })
            .collect();
        let report = json!({
            "model": self.path,
            "eigen_textures": self.model.n_textures(),
            "eigen_warps": self.model.n_warps(),
            "size": [self.model.mask().width(), self.model.mask().height()],
            "textures": made.images.len(),
            "reconstructed": made.reconstructed,
            "interpolated": made.interpolated,
            "instantiate_seconds": made.seconds,
            "per_frame": per_frame,
        });
        let textures = FrameTextures::new(made.images, vec![made.frame_texture])?;
        Ok(Textured { textures, report })
    }
}

/// Writes `animation` (one sequence) with its textures as a glb of a frame set; returns the
/// paths written (the glb, then its sidecar JSON).
pub fn write_textured(
    ctx: &crate::Ctx,
    animation: &Subject,
    textured: &Textured,
    output: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    let set = FrameSet::from_subject(animation);
    let bar = crate::progress::Bar::new(ctx);
    Ok(export_textured_glb(&set, &textured.textures, output, &bar)?)
}

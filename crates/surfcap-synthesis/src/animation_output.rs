//! Writing a synthesised animation and its report: one topology (a subject's frames) or a frame
//! set (every frame its own mesh: the surface motion graph's output on per-frame
//! reconstructions), in the format the output asks for.

use std::path::{Path, PathBuf};

use serde::Serialize;
use surfcap_formats::export::{ExportFormat, ExportOptions, export, export_frame_set, plan_export};
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::output_set::{OutputSet, Stamped};
use surfcap_mesh::{Progress, Subject, UpAxis};

use crate::error::Result;

/// A synthesised animation to write.
pub enum Animation<'a> {
    Subject(&'a Subject),
    FrameSet(&'a FrameSet),
}

/// The format an animation is written in: `format`, else the output's extension, else glb.
pub fn output_format(format: Option<ExportFormat>, output: &Path) -> ExportFormat {
    format.unwrap_or_else(|| {
        output.extension().and_then(|e| e.to_str()).and_then(ExportFormat::parse).unwrap_or(ExportFormat::Glb)
    })
}

/// Writes a synthesised animation to `output` and returns the paths written. An output ending
/// in `.frames` (with no `format`) is a frame-set folder, lossless and surfcap's own; anything
/// else goes through the exporters in `format` (else the extension, else glb: a frame set's
/// glb holds a mesh per frame, see `surfcap_formats::glb_frame_set`).
pub fn write_animation(
    animation: Animation,
    format: Option<ExportFormat>,
    output: &Path,
    options: ExportOptions,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    if format.is_none() && output.extension().is_some_and(|e| e == "frames") {
        let from_subject;
        let set = match animation {
            Animation::FrameSet(set) => set,
            Animation::Subject(s) => {
                from_subject = FrameSet::from_subject(s);
                &from_subject
            }
        };
        surfcap_mesh::frame_set_cache::write_frame_set(output, set, options.force, progress)?;
        return Ok(vec![output.to_path_buf()]);
    }
    let format = output_format(format, output);
    if format == ExportFormat::RigGlb {
        // A skinned rig of the animation (Smooth Skinning Decomposition with Rigid Bones, the
        // rig command's defaults): engines play it as a character.
        let Animation::Subject(s) = animation else {
            return Err(crate::Error::Request(
                "--format rig-glb: a frame set (every frame its own topology) cannot be skinned; write glb, abc or obj"
                    .into(),
            ));
        };
        let rigged = crate::rig_run::rig_subject(s, &surfcap_skinning::SsdrOptions::default(), progress)?;
        surfcap_mesh::atomic::write_file(output, |w| w.write_all(&rigged.glb))?;
        return Ok(vec![output.to_path_buf()]);
    }
    Ok(match animation {
        Animation::Subject(s) => export(s, format, output, options, progress)?,
        Animation::FrameSet(set) => export_frame_set(set, format, output, options, progress)?,
    })
}

/// `x.glb` -> `x.report.json`, `dir/out` -> `dir/out.report.json`.
pub fn report_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "walk".into());
    output.with_file_name(format!("{stem}.report.json"))
}

/// The kind of side file a report is (`surfcap_mesh::output_set::Stamped`): a report replaces
/// only an earlier report surfcap wrote.
pub const REPORT_KIND: &str = "report";

/// Plans an animation's outputs in `set` before any work: the `.frames` folder (when `format` is
/// none and the output ends in `.frames`), else the exporter's file and sidecar or folder
/// (`surfcap_formats::export::plan_export`).
pub fn plan_animation(set: &mut OutputSet, format: Option<ExportFormat>, output: &Path, force: bool) -> Result<()> {
    if format.is_none() && output.extension().is_some_and(|e| e == "frames") {
        set.dir(output, surfcap_mesh::frame_set_cache::OUTPUT_KIND, force)?;
    } else {
        plan_export(set, output_format(format, output), output, force)?;
    }
    Ok(())
}

/// [`plan_animation`] and the report beside it ([`report_path`]).
pub fn plan_animation_and_report(
    set: &mut OutputSet,
    format: Option<ExportFormat>,
    output: &Path,
    force: bool,
) -> Result<()> {
    plan_animation(set, format, output, force)?;
    set.side_file(&report_path(output), REPORT_KIND)?;
    Ok(())
}

/// Writes a report as pretty JSON (a final newline) to `path`, atomically, stamped as surfcap's
/// report (`"written_by"`, `"output_kind"` first, then the report's own fields).
pub fn write_report<T: Serialize + ?Sized>(path: &Path, report: &T) -> Result<()> {
    surfcap_mesh::atomic::write_file(path, |w| {
        serde_json::to_writer_pretty(&mut *w, &Stamped::new(REPORT_KIND, report)).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(())
}

/// The centre of every output frame (which `surfcap view` draws over the animation).
#[derive(Debug, Clone, Serialize)]
pub struct CentreTrack {
    pub centre: Vec<[f64; 3]>,
}

/// What a report says about the travel of the written animation: the net displacement and
/// path length of its centre on the ground, and the centre of every frame.
#[derive(Debug, Clone, Serialize)]
pub struct Travel {
    pub net_displacement: f64,
    pub path_length: f64,
    pub per_frame: CentreTrack,
}

impl Travel {
    pub fn of(centres: &[[f64; 3]], up: UpAxis) -> Self {
        let (net, path) = surfcap_motion::clip_travel::horizontal_travel(centres, up);
        Travel { net_displacement: net, path_length: path, per_frame: CentreTrack { centre: centres.to_vec() } }
    }
}

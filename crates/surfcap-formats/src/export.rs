//! Writing a subject in the formats other tools read, with a sidecar JSON that keeps what those
//! formats cannot: frame rate, up axis, units, tags and the per-frame original/synthetic labels.

use std::path::{Path, PathBuf};

use serde_json::json;

use crate::{glb, obj, pc2, ply, shared_layout};
use surfcap_mesh::atomic::{write_dir, write_file};
use surfcap_mesh::error::Result;
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::output_set::{OutputSet, Stamped};
use surfcap_mesh::progress::Progress;
use surfcap_mesh::subject::Subject;

/// Output formats of `surfcap export`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// One `.glb` file: morph-target animation, one animation per sequence.
    Glb,
    /// A folder with one folder of `frame_NNNNN.obj` files per sequence.
    Obj,
    /// A folder with one folder of `frame_NNNNN.ply` files per sequence.
    Ply,
    /// A folder with `template.obj` and one `<sequence>.pc2` point cache per sequence.
    Pc2,
    /// A folder in the shared-data layout: `<sequence>/template.obj + positions.npy (+ joints.npy)`
    /// and `meta.json`; `surfcap import` reads it back as is.
    Npy,
    /// One `.usda` file (USD text): a time-sampled mesh per sequence (`usda`).
    Usda,
    /// One `.usdc` file (USD's binary crate format): the same stage as `usda` (`usdc`).
    Usdc,
    /// One `.abc` file (Alembic, Ogawa): an `Xform` + `PolyMesh` per sequence (`abc`).
    Abc,
    /// One `.scstream` file: the compact stream (quantised, predicted, deflated; `stream`).
    Stream,
    /// One `.glb` file: a skinned rig (bones, weights, a bone animation per sequence) made by
    /// the skinning decomposition (`rig-glb`); written by the synthesis layer and `surfcap rig`,
    /// not by these exporters, which only have frames.
    RigGlb,
}

impl ExportFormat {
    /// The kind of output a folder of this format is, in its marker (`surfcap_mesh::output_path`).
    pub fn output_kind(self) -> &'static str {
        match self {
            ExportFormat::Glb => "export-glb",
            ExportFormat::Obj => "export-obj",
            ExportFormat::Ply => "export-ply",
            ExportFormat::Pc2 => "export-pc2",
            ExportFormat::Npy => "export-npy",
            ExportFormat::Usda => "export-usda",
            ExportFormat::Usdc => "export-usdc",
            ExportFormat::Abc => "export-abc",
            ExportFormat::Stream => "export-stream",
            ExportFormat::RigGlb => "export-rig-glb",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "glb" | "gltf" => ExportFormat::Glb,
            "obj" => ExportFormat::Obj,
            "ply" => ExportFormat::Ply,
            "pc2" => ExportFormat::Pc2,
            "npy" => ExportFormat::Npy,
            "usda" | "usd" => ExportFormat::Usda,
            "usdc" => ExportFormat::Usdc,
            "abc" | "alembic" => ExportFormat::Abc,
            "stream" | "scstream" => ExportFormat::Stream,
            "rig-glb" => ExportFormat::RigGlb,
            _ => return None,
        })
    }
}

impl std::str::FromStr for ExportFormat {
    type Err = surfcap_mesh::Error;
    fn from_str(s: &str) -> surfcap_mesh::Result<Self> {
        ExportFormat::parse(s).ok_or_else(|| {
            surfcap_mesh::Error::new(
                surfcap_mesh::ErrorKind::Unsupported,
                format!("{s:?}: expected glb, obj, ply, pc2, npy, usda, usdc, abc, stream or rig-glb"),
            )
        })
    }
}

#[derive(Debug, Clone, Copy, Default)]
pub struct ExportOptions {
    /// Write ascii rather than binary PLY.
    pub ply_ascii: bool,
    /// Replace a non-empty output folder that holds no surfcap marker of the same format.
    pub force: bool,
}

/// A file-system-safe version of a sequence name.
pub fn safe_name(name: &str) -> String {
    let s: String = name.chars().map(|c| if c.is_alphanumeric() || "-_.".contains(c) { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with('.') { format!("_{s}") } else { s }
}

/// The sidecar description: subject metadata and every frame's label.
pub fn sidecar(subject: &Subject) -> serde_json::Value {
    let ix = subject.frame_index();
    json!({
        "subject": subject.name,
        "fps": subject.fps,
        "up_axis": subject.up_axis.as_str(),
        "units": subject.units,
        "vertices": subject.topology().n_vertices(),
        "triangles": subject.topology().n_triangles(),
        "sequences": subject.sequences().iter().enumerate().map(|(k, s)| json!({
            "name": s.name,
            "file_name": safe_name(&s.name),
            "frames": s.n_frames(),
            "first_global_frame": ix.range(k).start,
            "tags": s.tags,
            "frame_labels": s.labels,
        })).collect::<Vec<_>>(),
    })
}

/// The kind of side file a sidecar is (`surfcap_mesh::output_set::Stamped`): a sidecar replaces
/// only an earlier sidecar surfcap wrote.
pub const SIDECAR_KIND: &str = "export-sidecar";

/// Writes a sidecar beside a file output: `v` stamped as surfcap's (`"written_by"`,
/// `"output_kind"`), its own fields as they are.
fn write_sidecar(path: &Path, v: &serde_json::Value) -> Result<()> {
    write_file(path, |w| {
        serde_json::to_writer_pretty(&mut *w, &Stamped::new(SIDECAR_KIND, v)).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// Plans the outputs of an export to `out` in `format` in `set` (before any work): the file and
/// its sidecar for glb, usda and abc, else the folder (replacing a folder surfcap did not write
/// only with `force`).
pub fn plan_export(set: &mut OutputSet, format: ExportFormat, out: &Path, force: bool) -> Result<()> {
    match format {
        ExportFormat::Glb | ExportFormat::Usda | ExportFormat::Usdc | ExportFormat::Abc | ExportFormat::Stream => {
            set.file(out)?;
            set.side_file(&glb_sidecar_path(out), SIDECAR_KIND)?;
        }
        ExportFormat::Obj | ExportFormat::Ply | ExportFormat::Pc2 | ExportFormat::Npy => {
            set.dir(out, format.output_kind(), force)?;
        }
        ExportFormat::RigGlb => {
            set.file(out)?;
        }
    }
    Ok(())
}

fn write_json(path: &Path, v: &serde_json::Value) -> Result<()> {
    write_file(path, |w| {
        serde_json::to_writer_pretty(&mut *w, v).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// Where the sidecar of a `.glb` goes: `out.glb` -> `out.json`.
pub fn glb_sidecar_path(out: &Path) -> PathBuf {
    out.with_extension("json")
}

/// The sidecar of a frame set: what the formats cannot keep, as for a subject.
pub fn frame_set_sidecar(set: &FrameSet) -> serde_json::Value {
    json!({
        "frame_set": set.name,
        "fps": set.fps,
        "up_axis": set.up_axis.as_str(),
        "units": set.units,
        "vertices": set.vertex_count_range(),
        "triangles": set.triangle_count_range(),
        "sequences": set.sequences().iter().map(|s| json!({
            "name": s.name,
            "file_name": safe_name(&s.name),
            "frames": s.n_frames(),
            "tags": s.tags,
            "frame_labels": s.labels(),
        })).collect::<Vec<_>>(),
    })
}

/// Writes a frame set (every frame its own topology) to `out`: `.glb` (a mesh per frame, shown
/// one at a time: `glb_frame_set`), `.abc` (a `PolyMesh` of
/// heterogeneous topology per sequence) or `obj` (a folder per sequence of `frame_NNNNN.obj`,
/// as per-frame reconstructions are exchanged); the other formats hold one topology and refuse
/// it. Returns the paths written.
pub fn export_frame_set(
    set: &FrameSet,
    format: ExportFormat,
    out: &Path,
    opts: ExportOptions,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    let meta = frame_set_sidecar(set);
    match format {
        ExportFormat::Glb | ExportFormat::Abc => {
            progress.start(if format == ExportFormat::Glb { "writing glb" } else { "writing abc" }, 1);
            if format == ExportFormat::Glb {
                write_file(out, |w| crate::glb_frame_set::write_glb_frame_set(w, set))?;
            } else {
                write_file(out, |w| crate::abc::write_abc_frame_set(w, set))?;
            }
            let side = glb_sidecar_path(out);
            write_sidecar(&side, &meta)?;
            progress.finish();
            Ok(vec![out.to_path_buf(), side])
        }
        ExportFormat::Obj => {
            progress.start("writing obj frames", set.frame_count() as u64);
            write_dir(out, format.output_kind(), opts.force, |dir| {
                for s in set.sequences() {
                    let sd = dir.join(safe_name(&s.name));
                    for (f, frame) in s.frames().iter().enumerate() {
                        let p = sd.join(format!("frame_{f:05}.obj"));
                        write_file(&p, |w| obj::write_obj(w, frame.topology(), frame.positions()))?;
                        progress.advance(1);
                    }
                }
                write_json(&dir.join("frames.json"), &meta)
            })?;
            progress.finish();
            Ok(vec![out.to_path_buf()])
        }
        other => Err(surfcap_mesh::Error::new(
            surfcap_mesh::ErrorKind::Unsupported,
            format!(
                "a frame set (every frame its own topology) cannot be written as {other:?}, which holds one topology: expected glb, abc or obj"
            ),
        )),
    }
}

/// Writes an animation with a texture per frame to `out` as one `.glb` (a mesh per frame, each
/// with the material of its texture: `glb_frame_set`) and its sidecar, which lists the
/// number of distinct textures and each sequence's texture per frame; returns the paths
/// written. A subject's animation goes through [`FrameSet::from_subject`] first (see
/// `glb_frame_set::write_glb_subject_textured` for why and what it costs).
pub fn export_textured_glb(
    set: &FrameSet,
    textures: &surfcap_mesh::FrameTextures,
    out: &Path,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    let mut meta = frame_set_sidecar(set);
    meta["textures"] = textures.images().len().into();
    meta["frame_textures"] = serde_json::json!(textures.frames());
    progress.start("writing glb", 1);
    write_file(out, |w| crate::glb_frame_set::write_glb_frame_set_textured(w, set, textures))?;
    let side = glb_sidecar_path(out);
    write_sidecar(&side, &meta)?;
    progress.finish();
    Ok(vec![out.to_path_buf(), side])
}

/// Writes the subject to `out` as a compact stream (`stream.rs`) coded with `opts`, and its
/// sidecar; returns the paths written.
pub fn export_stream(
    subject: &Subject,
    out: &Path,
    opts: &crate::stream::StreamOptions,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    progress.start("writing stream", 1);
    write_file(out, |w| crate::stream::write_stream(w, subject, opts).map(|_| ()))?;
    let side = glb_sidecar_path(out);
    write_sidecar(&side, &sidecar(subject))?;
    progress.finish();
    Ok(vec![out.to_path_buf(), side])
}

/// Writes the subject to `out` and returns the paths written (outputs, then the sidecar).
pub fn export(
    subject: &Subject,
    format: ExportFormat,
    out: &Path,
    opts: ExportOptions,
    progress: &dyn Progress,
) -> Result<Vec<PathBuf>> {
    let topo = subject.topology();
    let meta = sidecar(subject);
    match format {
        ExportFormat::RigGlb => Err(surfcap_mesh::Error::new(
            surfcap_mesh::ErrorKind::Unsupported,
            "rig-glb: a skinned rig is made by the skinning decomposition, not written from frames: run `surfcap rig SUBJECT -o OUT.glb` (or `synth ... --format rig-glb`)".to_string(),
        )),
        ExportFormat::Glb => {
            progress.start("writing glb", 1);
            write_file(out, |w| glb::write_glb(w, subject))?;
            let side = glb_sidecar_path(out);
            write_sidecar(&side, &meta)?;
            progress.finish();
            Ok(vec![out.to_path_buf(), side])
        }
        ExportFormat::Usda | ExportFormat::Usdc | ExportFormat::Abc => {
            type Writer = fn(&mut dyn std::io::Write, &Subject) -> std::io::Result<()>;
            let (what, write): (&str, Writer) = match format {
                ExportFormat::Usda => ("writing usda", crate::usda::write_usda),
                ExportFormat::Usdc => ("writing usdc", crate::usd_crate_write::write_usdc),
                _ => ("writing abc", crate::abc::write_abc),
            };
            progress.start(what, 1);
            write_file(out, |w| write(w, subject))?;
            let side = glb_sidecar_path(out);
            write_sidecar(&side, &meta)?;
            progress.finish();
            Ok(vec![out.to_path_buf(), side])
        }
        ExportFormat::Stream => export_stream(subject, out, &crate::stream::StreamOptions::default(), progress),
        ExportFormat::Obj | ExportFormat::Ply => {
            let ext = if format == ExportFormat::Obj { "obj" } else { "ply" };
            progress.start(&format!("writing {ext} frames"), subject.n_frames() as u64);
            write_dir(out, format.output_kind(), opts.force, |dir| {
                for s in subject.sequences() {
                    let sd = dir.join(safe_name(&s.name));
                    for f in 0..s.n_frames() {
                        let p = sd.join(format!("frame_{f:05}.{ext}"));
                        if format == ExportFormat::Obj {
                            write_file(&p, |w| obj::write_obj(w, topo, s.frame(f)))?;
                        } else {
                            write_file(&p, |w| ply::write_ply(w, topo, s.frame(f), opts.ply_ascii))?;
                        }
                        progress.advance(1);
                    }
                }
                write_json(&dir.join("frames.json"), &meta)
            })?;
            progress.finish();
            Ok(vec![out.to_path_buf()])
        }
        ExportFormat::Pc2 => {
            write_dir(out, format.output_kind(), opts.force, |dir| {
                write_file(&dir.join("template.obj"), |w| obj::write_obj(w, topo, subject.sequences()[0].frame(0)))?;
                for s in subject.sequences() {
                    let p = dir.join(format!("{}.pc2", safe_name(&s.name)));
                    write_file(&p, |w| pc2::write_pc2(w, topo.n_vertices(), s.positions()))?;
                }
                write_json(&dir.join("frames.json"), &meta)
            })?;
            Ok(vec![out.to_path_buf()])
        }
        ExportFormat::Npy => {
            progress.start("writing npy sequences", subject.sequences().len() as u64);
            write_dir(out, format.output_kind(), opts.force, |dir| {
                let mut seqs = serde_json::Map::new();
                for (s, m) in subject.sequences().iter().zip(meta["sequences"].as_array().unwrap()) {
                    let sd = dir.join(safe_name(&s.name));
                    shared_layout::write_layout_sequence(&sd, topo, s.positions(), s.joints.as_ref())?;
                    seqs.insert(
                        safe_name(&s.name),
                        json!({
                            "name": s.name,
                            "frames": s.n_frames(),
                            "vertices": topo.n_vertices(),
                            "triangles": topo.n_triangles(),
                            "tags": m["tags"],
                            "frame_labels": m["frame_labels"],
                        }),
                    );
                    progress.advance(1);
                }
                let mut root = json!({
                    "dataset": subject.name,
                    "written_by": format!("surfcap {}", env!("CARGO_PKG_VERSION")),
                    "fps": subject.fps,
                    "up_axis": subject.up_axis.as_str(),
                    "units": subject.units.name,
                    "sequences": seqs,
                });
                if let Some(j) = subject.sequences().iter().find_map(|s| s.joints.as_ref()) {
                    root["joint_names"] = json!(j.names);
                    root["joint_parents"] =
                        json!(j.parents.iter().map(|p| p.map_or(-1, |p| p as i64)).collect::<Vec<_>>());
                }
                write_json(&dir.join("meta.json"), &root)
            })?;
            progress.finish();
            Ok(vec![out.to_path_buf()])
        }
    }
}

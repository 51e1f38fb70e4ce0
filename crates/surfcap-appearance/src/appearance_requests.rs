//! What the appearance commands (`surfcap appearance build | reconstruct | interpolate |
//! complete`) and their Python bindings take, turned into the model's inputs with the same
//! checks and messages: the texture files of a folder (a generated folder's frames without its
//! holed ones), the mesh whose UV atlas gives the active texels and whose frames may name the
//! maps, a frame named as the model lists it, frame weights, and the observed texels of a map
//! to complete; plus the thesis's texture flow through the derived cache (4.4.1).

use std::path::{Path, PathBuf};

use surfcap_mesh::{Progress, Subject, Topology};

use crate::appearance_model::AppearanceModel;
use crate::error::{Error, Result};
use crate::flow_cache::{FlowCache, TextureFlow};
use crate::generated_frames::GeneratedFrames;
use crate::texel_mask::TexelMask;
use crate::texture_folder::list_textures;
use crate::texture_image::TextureImage;
use crate::texture_preprocessing::PreprocessOptions;
use crate::tv_l1_flow::FlowOptions;

/// The texture files of `dir`: a generated folder's `frame_*` maps (without the frames it says
/// have occlusion holes, unless `keep_holed`: thesis 4.6.2 builds the model without the
/// incomplete frames, then completes them; a note says so), else every map.
pub fn texture_files(dir: &Path, keep_holed: bool, progress: &dyn Progress) -> Result<Vec<PathBuf>> {
    if dir.join("frames.json").is_file() {
        let generated = GeneratedFrames::open(dir)?;
        let header = generated.header();
        let holed = &header.hole_frames;
        if !keep_holed && !holed.is_empty() {
            progress.note(&format!(
                "{} of the {} frames have occlusion holes and are left out of the model (--keep-holed keeps them)",
                holed.len(),
                header.frames
            ));
        }
        return Ok(header
            .frame_files
            .iter()
            .enumerate()
            .filter(|(k, _)| keep_holed || !holed.contains(k))
            .map(|(_, f)| dir.join(f))
            .collect());
    }
    list_textures(dir, "")
}

/// The mesh of a texture folder: `mesh`, else the folder's `template.obj`.
pub fn mesh_of(textures: &Path, mesh: Option<&Path>) -> Result<PathBuf> {
    if let Some(m) = mesh {
        return Ok(m.to_path_buf());
    }
    let own = textures.join("template.obj");
    if !own.is_file() {
        return Err(Error::Invalid(format!(
            "{}: no template.obj in the folder: give the UV-mapped mesh the maps belong to with --mesh",
            textures.display()
        )));
    }
    Ok(own)
}

/// Whether `path` names an OBJ file (a mesh, not a subject: no frame rate to ask for).
pub fn is_obj(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// The active texels of the atlas of `mesh` (named `mesh_name` in messages) at the maps' size,
/// and the frame names its subject gives (`sequence:frame`) when it is a subject of `frames`
/// frames, more than one. `subject` is the opened subject, `None` for an OBJ.
pub fn atlas_mask(
    mesh_name: &Path,
    topology: &Topology,
    subject: Option<&Subject>,
    width: usize,
    height: usize,
    dilation: usize,
    frames: usize,
) -> Result<(TexelMask, Option<Vec<String>>)> {
    let names = subject.and_then(|s| {
        (s.n_frames() == frames && frames > 1).then(|| (0..frames).map(|g| s.frame_index().label(g)).collect())
    });
    let atlas = topology.uv().ok_or_else(|| {
        Error::Invalid(format!(
            "{}: the mesh has no texture coordinates: expected a UV atlas (OBJ `vt` and `f v/vt`)",
            mesh_name.display()
        ))
    })?;
    let mask = TexelMask::from_atlas(atlas, width, height, dilation)
        .map_err(|e| Error::Invalid(format!("{}: the UV atlas: {e}", mesh_name.display())))?;
    Ok((mask, names))
}

/// The model's frame named `name` (as `model.json` lists them).
pub fn frame_of(model: &AppearanceModel, name: &str) -> Result<usize> {
    if let Some(k) = model.names().iter().position(|n| n == name) {
        return Ok(k);
    }
    let shown: Vec<&str> = model.names().iter().take(4).map(String::as_str).collect();
    Err(Error::Invalid(format!(
        "frame {name:?}: the model has no frame of that name (its {} frames are named like {})",
        model.n_frames(),
        shown.join(", ")
    )))
}

/// `NAME=WEIGHT` or `NAME` items (`--frames`) as (name, weight) pairs: every item weighted or
/// none.
pub fn parse_frame_weights(items: &[String]) -> Result<Vec<(String, Option<f64>)>> {
    let weighted = items.iter().filter(|s| s.contains('=')).count();
    if weighted != 0 && weighted != items.len() {
        return Err(Error::Invalid(format!(
            "--frames {}: give every frame a weight (NAME=WEIGHT) or none",
            items.join(",")
        )));
    }
    items
        .iter()
        .map(|item| match item.rsplit_once('=') {
            Some((n, w)) => {
                let w: f64 = w
                    .trim()
                    .parse()
                    .map_err(|_| Error::Invalid(format!("--frames {item}: the weight {w:?} is not a number")))?;
                Ok((n.trim().to_string(), Some(w)))
            }
            None => Ok((item.trim().to_string(), None)),
        })
        .collect()
}

/// (frame name, weight) pairs as (model frame, weight): every frame weighted or none, equal
/// weights when none is given.
pub fn frame_weights(model: &AppearanceModel, items: &[(String, Option<f64>)]) -> Result<Vec<(usize, f64)>> {
    let weighted = items.iter().filter(|(_, w)| w.is_some()).count();
    if weighted != 0 && weighted != items.len() {
        let shown: Vec<String> =
            items.iter().map(|(n, w)| w.map_or_else(|| n.clone(), |w| format!("{n}={w}"))).collect();
        return Err(Error::Invalid(format!(
            "--frames {}: give every frame a weight (NAME=WEIGHT) or none",
            shown.join(",")
        )));
    }
    items.iter().map(|(name, w)| Ok((frame_of(model, name)?, w.unwrap_or(1.0 / items.len() as f64)))).collect()
}

/// The thesis's flow between texture maps (4.4.1) through the derived cache in `cache_dir`
/// (`None`: memory only; `refresh`: recompute), solved down to `finest_scale` (0 full
/// resolution), with the pre-processing unless `no_preprocess`.
pub fn texture_flow<'a>(
    cache_dir: Option<&Path>,
    refresh: bool,
    finest_scale: usize,
    no_preprocess: bool,
    progress: &'a dyn Progress,
) -> TextureFlow<'a> {
    let pre = if no_preprocess { PreprocessOptions::none() } else { PreprocessOptions::default() };
    let options = FlowOptions { finest_scale, ..FlowOptions::default() };
    TextureFlow::new(FlowCache::new(cache_dir, refresh, progress), pre, options)
}

/// A map to complete and its observed texels, checked against the model: the map must have the
/// model's size, the observed-texel image (observed where it is not black) the map's; without
/// one, every texel of the map that is not pure black is observed (how occluded texels are left
/// by texturing tools and by `surfcap appearance generate`). `texture_name` and
/// `observed_name` name the two in messages. Returns the observed texels and how many active
/// texels are missing.
pub fn observed_texels(
    model: &AppearanceModel,
    texture: &TextureImage,
    texture_name: &str,
    observed: Option<(&TextureImage, &str)>,
) -> Result<(Vec<bool>, usize)> {
    let mask = model.mask();
    if texture.width() != mask.width() || texture.height() != mask.height() {
        return Err(Error::Mismatch(format!(
            "{texture_name}: the map is {}x{}: expected {}x{} like the model's",
            texture.width(),
            texture.height(),
            mask.width(),
            mask.height()
        )));
    }
    let observed: Vec<bool> = match observed {
        Some((o, name)) => {
            if o.width() != texture.width() || o.height() != texture.height() {
                return Err(Error::Mismatch(format!(
                    "{name}: the observed-texel image is {}x{}: expected {}x{} like the map",
                    o.width(),
                    o.height(),
                    texture.width(),
                    texture.height()
                )));
            }
            o.grey().iter().map(|&v| v > 0.5).collect()
        }
        None => (0..texture.texels()).map(|i| (0..texture.channels()).any(|c| texture.plane(c)[i] > 0.0)).collect(),
    };
    let missing = (0..texture.texels()).filter(|&i| mask.is_active(i) && !observed[i]).count();
    Ok((observed, missing))
}

/// `completed` with the observed texels of `texture` pasted back (`--keep-observed`).
pub fn keep_observed(completed: &mut TextureImage, texture: &TextureImage, observed: &[bool]) {
    for c in 0..completed.channels() {
        let src = texture.plane(c);
        for (i, o) in completed.plane_mut(c).iter_mut().enumerate() {
            if observed[i] {
                *o = src[i];
            }
        }
    }
}

/// `poisson` or `direct`, as `--warping` and `--search-warping` take it.
pub fn parse_warping(s: &str) -> Option<crate::Warping> {
    match s {
        "poisson" => Some(crate::Warping::Poisson),
        "direct" => Some(crate::Warping::Direct),
        _ => None,
    }
}

/// What `surfcap appearance build` reports of a built model (its `--json` result): the frames,
/// size and active texels, the reference and the medoid shift's path, the eigen maps kept and
/// the variance they explain, the stages' and the whole build's seconds. `output` is the model
/// folder, when it is written.
pub fn build_summary(
    model: &AppearanceModel,
    report: &crate::appearance_model::BuildReport,
    output: Option<&Path>,
    seconds: f64,
) -> serde_json::Value {
    let names = model.names();
    let mask = model.mask();
    let mut v = serde_json::json!({
        "model": output,
        "frames": report.frames,
        "size": [mask.width(), mask.height()],
        "active_texels": report.active_texels,
        "reference": names[report.reference],
        "medoid_references": report.medoid_references.iter().map(|&k| &names[k]).collect::<Vec<_>>(),
        "medoid_errors": report.medoid_errors,
        "eigen_textures": model.n_textures(),
        "eigen_warps": model.n_warps(),
        "texture_explained_variance": report.texture_explained_variance.iter().sum::<f64>(),
        "warp_explained_variance": report.warp_explained_variance.iter().sum::<f64>(),
        "stages": report.seconds,
        "seconds": seconds,
    });
    if output.is_none()
        && let Some(o) = v.as_object_mut()
    {
        o.remove("model");
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_weights_are_all_given_or_none() {
        let items = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let parsed = parse_frame_weights(&items(&["walk:3=0.25", "run:7=0.75"])).unwrap();
        assert_eq!(parsed, vec![("walk:3".to_string(), Some(0.25)), ("run:7".to_string(), Some(0.75))]);
        assert_eq!(parse_frame_weights(&items(&["a", "b"])).unwrap(), vec![("a".into(), None), ("b".into(), None)]);
        let m = parse_frame_weights(&items(&["a=0.5", "b"])).unwrap_err().to_string();
        assert_eq!(m, "--frames a=0.5,b: give every frame a weight (NAME=WEIGHT) or none");
        let m = parse_frame_weights(&items(&["a=half"])).unwrap_err().to_string();
        assert_eq!(m, "--frames a=half: the weight \"half\" is not a number");
    }

    #[test]
    fn a_folder_without_a_mesh_names_the_missing_template() {
        let dir = std::env::temp_dir().join(format!("surfcap-no-template-{}", std::process::id()));
        let m = mesh_of(&dir, None).unwrap_err().to_string();
        assert!(
            m.ends_with("no template.obj in the folder: give the UV-mapped mesh the maps belong to with --mesh"),
            "{m}"
        );
        assert_eq!(mesh_of(&dir, Some(Path::new("head.obj"))).unwrap(), PathBuf::from("head.obj"));
        assert_eq!(parse_warping("poisson"), Some(crate::Warping::Poisson));
        assert_eq!(parse_warping("bend"), None);
    }
}

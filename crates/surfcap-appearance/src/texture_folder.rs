//! A folder of per-frame texture maps (PNG or JPEG, one per frame, in natural order of their
//! names: `frame_2.png` before `frame_10.png`), read in parallel, every map checked to have
//! the first one's size. The frame names are the file stems, unless the caller names frames
//! itself (a subject's `sequence:frame`).

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use surfcap_mesh::Progress;

use crate::error::{Error, Result};
use crate::texture_image::TextureImage;

/// Whether `path` names a texture map by its extension (png, jpg, jpeg; any case).
pub fn is_texture_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
}

/// The texture files of `dir` whose file names start with `prefix` (empty: all), in natural
/// order.
pub fn list_textures(dir: &Path, prefix: &str) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Error::Invalid(format!("{}: cannot list the folder: {e}", dir.display())))?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::Invalid(format!("{}: cannot list the folder: {e}", dir.display())))?;
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_file() && is_texture_file(&path) && name.starts_with(prefix) && !name.starts_with('.') {
            files.push(path);
        }
    }
    files.sort_by(|a, b| surfcap_mesh::natural_order::natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    if files.is_empty() {
        let what = if prefix.is_empty() { String::new() } else { format!(" named {prefix}*") };
        return Err(Error::Invalid(format!(
            "{}: no texture map{what} (expected .png, .jpg or .jpeg files)",
            dir.display()
        )));
    }
    Ok(files)
}

/// Reads `files` as the frames of one subject: all the size of the first.
pub fn read_textures(files: &[PathBuf], progress: &dyn Progress) -> Result<Vec<TextureImage>> {
    progress.start("reading texture maps", files.len() as u64);
    let textures: Vec<TextureImage> = files
        .par_iter()
        .map(|f| {
            let t = TextureImage::read(f);
            progress.advance(1);
            t
        })
        .collect::<Result<_>>()?;
    progress.finish();
    let first = &textures[0];
    for (t, f) in textures.iter().zip(files).skip(1) {
        if !t.same_shape(first) {
            return Err(Error::Mismatch(format!(
                "{}: the texture map is {}x{}: expected {}x{} like {}",
                f.display(),
                t.width(),
                t.height(),
                first.width(),
                first.height(),
                files[0].display()
            )));
        }
    }
    Ok(textures)
}

/// The frame name of a texture file: its stem.
pub fn frame_name(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textures_are_listed_in_natural_order_and_sizes_checked() {
        let dir = tempfile::tempdir().unwrap();
        for (name, w) in [("f_10.png", 2), ("f_2.png", 2), ("f_1.png", 3)] {
            TextureImage::zeros(w, 2, 3).write_png(&dir.path().join(name)).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), "x").unwrap();
        let files = list_textures(dir.path(), "f_").unwrap();
        let names: Vec<String> = files.iter().map(|f| frame_name(f)).collect();
        assert_eq!(names, ["f_1", "f_2", "f_10"]);
        let e = read_textures(&files, &surfcap_mesh::NoProgress).unwrap_err().to_string();
        assert!(e.contains("f_2.png: the texture map is 2x2: expected 3x2"), "{e}");
        assert!(list_textures(dir.path(), "g_").unwrap_err().to_string().contains("no texture map named g_*"));
    }
}

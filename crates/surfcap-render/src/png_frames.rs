//! A folder of numbered PNG files, one per rendered frame: `00000.png`, `00001.png`... in the
//! order they play (five digits, more when a render has more frames), the form video tools
//! read as an image sequence (`ffmpeg -i %05d.png`). Each file is written whole through
//! `surfcap_mesh::atomic`, so a folder the program planned as its output receives them in its
//! temporary until the commit.

use std::path::{Path, PathBuf};

use crate::{FrameSink, RenderError, Rgba};

/// Writes each frame as the next numbered PNG file in a folder.
pub struct PngFrames {
    dir: PathBuf,
    digits: usize,
    written: Vec<PathBuf>,
}

impl PngFrames {
    /// Files in `dir` (which exists), numbered with enough digits for `count` frames.
    pub fn new(dir: &Path, count: usize) -> Self {
        let digits = count.saturating_sub(1).to_string().len().max(5);
        PngFrames { dir: dir.to_path_buf(), digits, written: Vec::new() }
    }

    /// The name of frame `k`.
    pub fn name(&self, k: usize) -> String {
        format!("{k:0width$}.png", width = self.digits)
    }

    /// The files written so far.
    pub fn written(&self) -> &[PathBuf] {
        &self.written
    }
}

impl FrameSink for PngFrames {
    fn push(&mut self, frame: &Rgba) -> Result<(), RenderError> {
        let path = self.dir.join(self.name(self.written.len()));
        surfcap_mesh::atomic::write_file(&path, |w| {
            image::codecs::png::PngEncoder::new(w)
                .write_image(&frame.data, frame.width, frame.height, image::ColorType::Rgba8)
                .map_err(std::io::Error::other)
        })?;
        self.written.push(path);
        Ok(())
    }
}

use image::ImageEncoder as _;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_numbered_in_order_and_read_back() {
        let d = tempfile::tempdir().unwrap();
        let mut p = PngFrames::new(d.path(), 3);
        for c in [10u8, 200] {
            p.push(&Rgba { width: 4, height: 2, data: vec![c; 32] }).unwrap();
        }
        assert_eq!(p.name(7), "00007.png");
        assert_eq!(PngFrames::new(d.path(), 200_000).name(3), "000003.png");
        let back = image::open(d.path().join("00001.png")).unwrap().into_rgba8();
        assert_eq!((back.width(), back.height(), back.as_raw()[0]), (4, 2, 200));
        assert_eq!(p.written().len(), 2);
    }
}

//! A texture per frame of an animation (thesis Fig. 7.1: shape and appearance played together):
//! the distinct textures as encoded PNG files, and which one each frame of each sequence shows.
//!
//! The textures arrive already encoded (the appearance layer decodes and encodes images), so this
//! crate never depends on an image library: it checks the PNG signature and reads the image size
//! from the `IHDR` chunk, which every PNG starts with, to name a bad file in its errors.
//! Texture coordinates follow OBJ's convention (`v` = 1 at the top row of the image); writers of
//! formats with the other convention (glTF) flip them.

use crate::error::{Result, err};
use crate::frame_index::FrameIndex;

/// The 8 bytes every PNG file starts with.
pub const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// Width and height of a PNG file from its `IHDR` chunk; an error naming `what` when the bytes
/// are not a PNG.
pub fn png_size(bytes: &[u8], what: &str) -> Result<(u32, u32)> {
    if bytes.len() < 24 || bytes[..8] != PNG_SIGNATURE || &bytes[12..16] != b"IHDR" {
        return Err(err!(
            Syntax,
            "{what}: {} bytes that are not a PNG file (expected the PNG signature and an IHDR chunk)",
            bytes.len()
        ));
    }
    let be = |k: usize| u32::from_be_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let (w, h) = (be(16), be(20));
    if w == 0 || h == 0 {
        return Err(err!(Shape, "{what}: a PNG of {w} x {h} pixels: expected at least one pixel"));
    }
    Ok((w, h))
}

/// Textures of an animation's frames: `images` holds each distinct texture once, as an encoded
/// PNG file; `frames[s][f]` is the index into `images` of the texture of frame `f` of sequence
/// `s`. Frames that share an index share the texture (and, in a glb, its material).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameTextures {
    images: Vec<Vec<u8>>,
    frames: Vec<Vec<usize>>,
}

impl FrameTextures {
    /// Checks that every image is a PNG and every frame's index names one of them.
    pub fn new(images: Vec<Vec<u8>>, frames: Vec<Vec<usize>>) -> Result<Self> {
        for (k, im) in images.iter().enumerate() {
            png_size(im, &format!("texture {k}"))?;
        }
        for (s, q) in frames.iter().enumerate() {
            if let Some((f, &t)) = q.iter().enumerate().find(|&(_, &t)| t >= images.len()) {
                return Err(err!(
                    IndexOutOfRange,
                    "sequence {s}, frame {f}: texture {t}, expected below the {} textures given",
                    images.len()
                ));
            }
        }
        Ok(FrameTextures { images, frames })
    }

    /// One PNG per frame (`per_frame[s][f]`); frames whose files are byte for byte the same share
    /// one texture.
    pub fn one_per_frame(per_frame: Vec<Vec<Vec<u8>>>) -> Result<Self> {
        let mut images: Vec<Vec<u8>> = Vec::new();
        let mut by_hash: std::collections::HashMap<blake3::Hash, usize> = std::collections::HashMap::new();
        let frames = per_frame
            .into_iter()
            .map(|q| {
                q.into_iter()
                    .map(|png| {
                        *by_hash.entry(blake3::hash(&png)).or_insert_with(|| {
                            images.push(png);
                            images.len() - 1
                        })
                    })
                    .collect()
            })
            .collect();
        FrameTextures::new(images, frames)
    }

    /// The distinct textures (encoded PNG files).
    pub fn images(&self) -> &[Vec<u8>] {
        &self.images
    }

    /// Per sequence, per frame: the index of the frame's texture in [`FrameTextures::images`].
    pub fn frames(&self) -> &[Vec<usize>] {
        &self.frames
    }

    /// The PNG file of frame `frame` of sequence `seq`.
    pub fn frame_png(&self, seq: usize, frame: usize) -> &[u8] {
        &self.images[self.frames[seq][frame]]
    }

    /// Checks that there is one index per frame of each sequence of `index` (the animation the
    /// textures go with), naming the first mismatch.
    pub fn check_frames(&self, index: &FrameIndex) -> Result<()> {
        if self.frames.len() != index.n_sequences() {
            return Err(err!(
                Shape,
                "textures for {} sequences, the animation has {}",
                self.frames.len(),
                index.n_sequences()
            ));
        }
        for (s, q) in self.frames.iter().enumerate() {
            let n = index.range(s).len();
            if q.len() != n {
                return Err(err!(
                    Shape,
                    "sequence {}: {} texture indices, expected one per frame ({n})",
                    index.sequence_name(s),
                    q.len()
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_testkit::png_1x1;

    #[test]
    fn identical_files_share_a_texture_and_bad_ones_are_named() {
        let (red, blue) = (png_1x1([255, 0, 0]), png_1x1([0, 0, 255]));
        assert_eq!(png_size(&red, "x").unwrap(), (1, 1));
        let t = FrameTextures::one_per_frame(vec![vec![red.clone(), blue.clone(), red.clone()], vec![blue]]).unwrap();
        assert_eq!(t.images().len(), 2);
        assert_eq!(t.frames(), &[vec![0, 1, 0], vec![1]]);
        assert_eq!(t.frame_png(0, 2), &red[..]);
        let e = FrameTextures::new(vec![b"GIF89a".to_vec()], vec![vec![0]]).unwrap_err();
        assert!(e.message.contains("texture 0: 6 bytes that are not a PNG"), "{e}");
        let e = FrameTextures::new(vec![red], vec![vec![0, 1]]).unwrap_err();
        assert!(e.message.contains("frame 1: texture 1, expected below the 1 textures"), "{e}");
    }
}

//! A texture map: `channels` planes of `width x height` texels, f32 on the 8-bit scale (0-255),
//! so the thesis's pre-processing parameters (bilateral sigma colour 15, 4.4.1) apply as
//! printed. Row 0 is the top of the image file, i.e. texture coordinate v = 1 (OBJ convention).
//! Planar storage (`data[c * width * height + y * width + x]`) keeps each channel a contiguous
//! image for filtering, flow and the Poisson solve.

use std::path::Path;

use image::{ImageBuffer, Rgb};

use crate::error::{Error, Result};

/// The image file formats a texture map is written in, chosen by the output's extension so
/// that the bytes are what the name says (`-o base.jpg` writes a JPEG, not PNG bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFileFormat {
    /// `.png`: 8-bit RGB, lossless.
    Png,
    /// `.jpg` or `.jpeg`: 8-bit RGB baseline JPEG, quality 95.
    Jpeg,
}

impl ImageFileFormat {
    /// The extensions accepted, as an error message lists them.
    pub const EXTENSIONS: &'static str = ".png, .jpg or .jpeg";

    /// The format `path`'s extension names (any case); another extension or none is refused
    /// naming the file and the extensions accepted.
    pub fn of_path(path: &Path) -> Result<Self> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFileFormat::Png),
            Some("jpg" | "jpeg") => Ok(ImageFileFormat::Jpeg),
            other => Err(Error::WriteImage {
                path: path.to_path_buf(),
                message: format!(
                    "{}: expected {} (the format follows the extension)",
                    other.map_or_else(|| "no extension".to_string(), |e| format!("extension .{e}")),
                    Self::EXTENSIONS
                ),
            }),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct TextureImage {
    width: usize,
    height: usize,
    channels: usize,
    data: Vec<f32>,
}

impl TextureImage {
    /// A black image.
    pub fn zeros(width: usize, height: usize, channels: usize) -> TextureImage {
        TextureImage { width, height, channels, data: vec![0.0; width * height * channels] }
    }

    /// An image from planar data (`channels` planes of `width * height`).
    pub fn from_planes(width: usize, height: usize, channels: usize, data: Vec<f32>) -> Result<TextureImage> {
        if width == 0 || height == 0 || channels == 0 {
            return Err(Error::Invalid(format!(
                "a texture map needs a positive size, got {width}x{height}x{channels}"
            )));
        }
        if data.len() != width * height * channels {
            return Err(Error::Mismatch(format!(
                "{} values for a {width}x{height} texture of {channels} channels: expected {}",
                data.len(),
                width * height * channels
            )));
        }
        Ok(TextureImage { width, height, channels, data })
    }

    pub fn width(&self) -> usize {
        self.width
    }
    pub fn height(&self) -> usize {
        self.height
    }
    pub fn channels(&self) -> usize {
        self.channels
    }
    /// Texels per channel (`width * height`).
    pub fn texels(&self) -> usize {
        self.width * self.height
    }
    /// All planes, channel after channel.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }
    /// One channel as a `width * height` row-major plane.
    pub fn plane(&self, c: usize) -> &[f32] {
        let n = self.texels();
        &self.data[c * n..(c + 1) * n]
    }
    pub fn plane_mut(&mut self, c: usize) -> &mut [f32] {
        let n = self.texels();
        &mut self.data[c * n..(c + 1) * n]
    }
    /// The value of channel `c` at texel (x, y).
    pub fn get(&self, c: usize, x: usize, y: usize) -> f32 {
        self.data[c * self.texels() + y * self.width + x]
    }
    /// Whether two images have the same width, height and channel count.
    pub fn same_shape(&self, other: &TextureImage) -> bool {
        self.width == other.width && self.height == other.height && self.channels == other.channels
    }
    /// Checks that `other` has this image's shape; `what` names it in the error.
    pub fn check_same_shape(&self, other: &TextureImage, what: &str) -> Result<()> {
        if self.same_shape(other) {
            return Ok(());
        }
        Err(Error::Mismatch(format!(
            "{what} is {}x{}x{}: expected {}x{}x{} like the first texture",
            other.width, other.height, other.channels, self.width, self.height, self.channels
        )))
    }

    /// The mean of the channels (luminance proxy used for the optical flow).
    pub fn grey(&self) -> Vec<f32> {
        let n = self.texels();
        let mut out = vec![0.0f32; n];
        for c in 0..self.channels {
            for (o, v) in out.iter_mut().zip(self.plane(c)) {
                *o += v;
            }
        }
        let k = 1.0 / self.channels as f32;
        out.iter_mut().for_each(|o| *o *= k);
        out
    }

    /// The width and height of a PNG or JPEG file, from its header (nothing decoded): to size a
    /// request before any work.
    pub fn dimensions(path: &Path) -> Result<[usize; 2]> {
        let bytes = surfcap_mesh::read_regular_file(path)?;
        let bad = |e: &dyn std::fmt::Display| Error::ReadImage {
            path: path.to_path_buf(),
            message: format!("expected a PNG or JPEG image: {e}"),
        };
        let reader = image::io::Reader::new(std::io::Cursor::new(&bytes)).with_guessed_format().map_err(|e| bad(&e))?;
        let (w, h) = reader.into_dimensions().map_err(|e| bad(&e))?;
        Ok([w as usize, h as usize])
    }

    /// Reads a PNG or JPEG file as RGB (grey and alpha files converted; alpha dropped).
    pub fn read(path: &Path) -> Result<TextureImage> {
        let bytes = surfcap_mesh::read_regular_file(path)?;
        let decoded = image::load_from_memory(&bytes).map_err(|e| Error::ReadImage {
            path: path.to_path_buf(),
            message: format!("expected a PNG or JPEG image: {e}"),
        })?;
        let rgb = decoded.to_rgb8();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        if w == 0 || h == 0 {
            return Err(Error::ReadImage { path: path.to_path_buf(), message: "the image is empty".into() });
        }
        let n = w * h;
        let mut data = vec![0.0f32; 3 * n];
        for (i, p) in rgb.pixels().enumerate() {
            for c in 0..3 {
                data[c * n + i] = p[c] as f32;
            }
        }
        Ok(TextureImage { width: w, height: h, channels: 3, data })
    }

    /// 8-bit RGB (values rounded and clamped to 0-255; one channel is repeated as grey).
    pub fn to_rgb8(&self) -> Vec<u8> {
        let n = self.texels();
        let mut out = vec![0u8; 3 * n];
        for i in 0..n {
            for c in 0..3 {
                let src = if self.channels >= 3 { c } else { 0 };
                out[3 * i + c] = self.data[src * n + i].round().clamp(0.0, 255.0) as u8;
            }
        }
        out
    }

    /// The image encoded as an 8-bit RGB PNG file, in memory (what a glb embeds); the same
    /// image gives the same bytes.
    pub fn to_png_bytes(&self) -> std::result::Result<Vec<u8>, String> {
        let buffer: ImageBuffer<Rgb<u8>, Vec<u8>> =
            ImageBuffer::from_raw(self.width as u32, self.height as u32, self.to_rgb8())
                .expect("buffer sized from the image");
        let mut encoded = Vec::new();
        image::DynamicImage::ImageRgb8(buffer)
            .write_to(&mut std::io::Cursor::new(&mut encoded), image::ImageOutputFormat::Png)
            .map_err(|e| e.to_string())?;
        Ok(encoded)
    }

    /// Writes the image in the format its extension names ([`ImageFileFormat::of_path`]: PNG,
    /// or JPEG for `.jpg`/`.jpeg`), atomically; another extension is refused before anything is
    /// written.
    pub fn write(&self, path: &Path) -> Result<()> {
        let encoded = match ImageFileFormat::of_path(path)? {
            ImageFileFormat::Png => self.to_png_bytes(),
            ImageFileFormat::Jpeg => self.to_jpeg_bytes(),
        }
        .map_err(|message| Error::WriteImage { path: path.to_path_buf(), message })?;
        surfcap_mesh::atomic::write_file(path, |w| w.write_all(&encoded))?;
        Ok(())
    }

    /// The image encoded as an 8-bit RGB JPEG (quality 95), in memory.
    pub fn to_jpeg_bytes(&self) -> std::result::Result<Vec<u8>, String> {
        let mut encoded = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut encoded, 95)
            .encode(&self.to_rgb8(), self.width as u32, self.height as u32, image::ColorType::Rgb8)
            .map_err(|e| e.to_string())?;
        Ok(encoded)
    }

    /// Writes the image as an 8-bit RGB PNG, atomically (a temporary sibling renamed into place).
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let encoded = self.to_png_bytes().map_err(|message| Error::WriteImage { path: path.to_path_buf(), message })?;
        surfcap_mesh::atomic::write_file(path, |w| w.write_all(&encoded))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_8_bit_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.png");
        let data: Vec<f32> = (0..3 * 6).map(|i| (i * 13 % 256) as f32).collect();
        let img = TextureImage::from_planes(3, 2, 3, data).unwrap();
        img.write_png(&path).unwrap();
        let back = TextureImage::read(&path).unwrap();
        assert_eq!(back, img);
    }

    /// The bytes follow the extension: `.jpg` writes a JPEG (read back close to the image),
    /// `.png` a PNG, and any other extension is refused naming the file and those accepted.
    #[test]
    fn the_written_format_follows_the_extension() {
        let dir = tempfile::tempdir().unwrap();
        let data: Vec<f32> = (0..3 * 64).map(|i| (100 + i % 7) as f32).collect();
        let img = TextureImage::from_planes(8, 8, 3, data).unwrap();
        for (name, magic) in
            [("a.jpg", &[0xFF, 0xD8, 0xFF][..]), ("b.JPEG", &[0xFF, 0xD8, 0xFF]), ("c.png", b"\x89PNG")]
        {
            let path = dir.path().join(name);
            img.write(&path).unwrap();
            assert!(std::fs::read(&path).unwrap().starts_with(magic), "{name}");
            let back = TextureImage::read(&path).unwrap();
            assert!(back.data.iter().zip(&img.data).all(|(a, b)| (a - b).abs() <= 8.0), "{name}");
        }
        for name in ["d.gif", "e"] {
            let path = dir.path().join(name);
            let e = img.write(&path).unwrap_err().to_string();
            assert!(e.starts_with(&path.display().to_string()) && e.contains("expected .png, .jpg or .jpeg"), "{e}");
            assert!(!path.exists());
        }
    }

    #[test]
    fn a_file_that_is_not_an_image_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame_003.png");
        std::fs::write(&path, b"not a png").unwrap();
        let e = TextureImage::read(&path).unwrap_err().to_string();
        assert!(e.contains("frame_003.png") && e.contains("expected a PNG or JPEG"), "{e}");
    }

    #[test]
    fn shapes_must_agree() {
        let a = TextureImage::zeros(4, 4, 3);
        let b = TextureImage::zeros(4, 5, 3);
        let e = a.check_same_shape(&b, "frame 2").unwrap_err().to_string();
        assert!(e.contains("frame 2 is 4x5x3: expected 4x4x3"), "{e}");
    }
}

//! Animated GIF (GIF89a) encoding: each frame gets its own palette of at most 256 colours,
//! chosen by NeuQuant (Dekker 1994, "Kohonen neural networks for optimal colour quantization",
//! as the `color_quant` crate implements it, through `gif::Frame::from_rgb_speed`), and loops
//! forever (the NETSCAPE2.0 extension).
//!
//! Frame delays are in hundredths of a second, so a rate that does not divide 100 cannot be
//! kept exactly frame by frame: frame `k` lasts `round(100 (k+1) / fps) - round(100 k / fps)`
//! hundredths, which keeps the total duration right (30 fps gives 3, 4, 3, 3, 4, 3...). Rates
//! above 50 fps are refused: browsers draw delays under 2 hundredths as 10.

use crate::{FrameSink, RenderError, Rgba};

/// The highest frame rate a GIF plays at in browsers.
pub const MAX_GIF_FPS: f64 = 50.0;

/// NeuQuant's sampling factor (1 best and slowest, 30 fastest): 10 is the library's own
/// suggestion for a good trade-off.
const SPEED: i32 = 10;

/// Encodes frames into an animated GIF held in memory.
pub struct GifEncoder {
    encoder: gif::Encoder<Vec<u8>>,
    fps: f64,
    width: u32,
    height: u32,
    frames: u64,
}

/// The delay of frame `k` at `fps`, in hundredths of a second (module docs).
pub fn delay(k: u64, fps: f64) -> u16 {
    let at = |k: u64| (100.0 * k as f64 / fps).round() as i64;
    (at(k + 1) - at(k)).clamp(1, u16::MAX as i64) as u16
}

impl GifEncoder {
    /// A GIF of `width x height` pixels (at most 65,535 a side) playing at `fps`.
    pub fn new(width: u32, height: u32, fps: f64) -> Result<Self, RenderError> {
        if !(fps > 0.0 && fps <= MAX_GIF_FPS) {
            return Err(RenderError::Rate(
                fps,
                format!(
                    "a GIF plays at most {MAX_GIF_FPS} frames per second (delays are in hundredths, and browsers draw those under 2 as 10); choose --fps {MAX_GIF_FPS} or less, or MP4"
                ),
            ));
        }
        let (w, h) = match (u16::try_from(width), u16::try_from(height)) {
            (Ok(w), Ok(h)) if w > 0 && h > 0 => (w, h),
            _ => return Err(RenderError::Size(width, height, "a GIF has 1 to 65535 pixels a side".into())),
        };
        let mut encoder = gif::Encoder::new(Vec::new(), w, h, &[]).map_err(|e| RenderError::Gif(e.to_string()))?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(|e| RenderError::Gif(e.to_string()))?;
        Ok(GifEncoder { encoder, fps, width, height, frames: 0 })
    }

    /// The GIF file's bytes.
    pub fn finish(self) -> Result<Vec<u8>, RenderError> {
        self.encoder.into_inner().map_err(|e| RenderError::Gif(e.to_string()))
    }
}

impl FrameSink for GifEncoder {
    fn push(&mut self, frame: &Rgba) -> Result<(), RenderError> {
        if (frame.width, frame.height) != (self.width, self.height) {
            return Err(RenderError::Gif(format!(
                "frame {} is {}x{}, the GIF {}x{}",
                self.frames, frame.width, frame.height, self.width, self.height
            )));
        }
        let rgb: Vec<u8> = frame.data.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        let mut f = gif::Frame::from_rgb_speed(self.width as u16, self.height as u16, &rgb, SPEED);
        f.delay = delay(self.frames, self.fps);
        self.encoder.write_frame(&f).map_err(|e| RenderError::Gif(e.to_string()))?;
        self.frames += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_keep_the_total_duration() {
        let d: Vec<u16> = (0..6).map(|k| delay(k, 30.0)).collect();
        assert_eq!(d, vec![3, 4, 3, 3, 4, 3]);
        assert_eq!((0..30).map(|k| delay(k, 30.0) as u32).sum::<u32>(), 100);
        assert_eq!(delay(7, 25.0), 4);
    }

    #[test]
    fn frames_read_back_with_their_size_count_and_colours() {
        let (w, h) = (8u32, 6u32);
        let mut g = GifEncoder::new(w, h, 25.0).unwrap();
        for c in [[255u8, 0, 0], [0, 0, 255]] {
            let data = (0..w * h).flat_map(|_| [c[0], c[1], c[2], 255]).collect();
            g.push(&Rgba { width: w, height: h, data }).unwrap();
        }
        let bytes = g.finish().unwrap();
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::RGBA);
        let mut d = opts.read_info(&bytes[..]).unwrap();
        assert_eq!((d.width(), d.height()), (8, 6));
        let mut seen = Vec::new();
        while let Some(f) = d.read_next_frame().unwrap() {
            assert_eq!(f.delay, 4);
            seen.push(f.buffer[..3].to_vec());
        }
        assert_eq!(seen.len(), 2);
        // NeuQuant keeps a flat colour within a step or two.
        assert!(seen[0][0] > 250 && seen[0][2] < 5 && seen[1][2] > 250 && seen[1][0] < 5, "{seen:?}");
    }

    #[test]
    fn a_rate_a_gif_cannot_play_is_refused() {
        let e = GifEncoder::new(8, 8, 60.0).err().unwrap();
        assert!(e.to_string().contains("at most 50 frames per second"), "{e}");
        assert!(GifEncoder::new(70_000, 8, 25.0).is_err());
    }
}

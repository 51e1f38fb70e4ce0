//! surfcap's pictures to share: the viewer's page (`surfcap-view`) rendered headless, frame by
//! frame, into an animated GIF, an MP4 video or a folder of numbered PNG files.
//!
//! - [`chromium`]: starts headless Chromium through the Chrome DevTools Protocol
//!   (`headless_chrome`), opens the viewer's page with its bare scene (`?ui=0`) at an exact size
//!   in CSS pixels (device scale 1), waits for `window.surfcapViewer.ready`, and for each frame
//!   calls the page's `setFrame(i)` (pause, show frame `i`, render) and takes a screenshot.
//! - [`frame_sampling`]: which of the animation's frames a render at a chosen frame rate shows,
//!   so that it plays at the animation's own speed.
//! - [`gif_encoding`]: an animated GIF, a palette of 256 colours per frame (NeuQuant), looping.
//! - [`mp4_encoding`]: H.264 (OpenH264, built from its source) in an MP4 container (`mp4`).
//! - [`png_frames`]: numbered PNG files in a folder.
//! - [`render`]: the loop joining them, reporting a step per frame through
//!   `surfcap_mesh::Progress`.
//!
//! The library does not start the viewer's server, find Chromium or decide where outputs go:
//! the program does (`surfcap render`), and hands over the page's URL and Chromium's path.

pub mod chromium;
pub mod frame_sampling;
pub mod gif_encoding;
pub mod mp4_encoding;
pub mod png_frames;

use std::path::PathBuf;

pub use chromium::{Page, PageOptions};
pub use frame_sampling::sample_frames;

/// One picture: `width x height` pixels, RGBA, row by row from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgba {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

/// Where rendered frames go, one after the other, at a fixed rate.
pub trait FrameSink {
    /// Adds the next frame (every frame has the render's size).
    fn push(&mut self, frame: &Rgba) -> Result<(), RenderError>;
}

/// Why a render failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("Chromium not found at {0}")]
    ChromiumMissing(PathBuf),
    #[error("could not start Chromium ({0}): {1}")]
    ChromiumStart(PathBuf, String),
    #[error("the viewer's page at {0}: {1}")]
    Page(String, String),
    #[error("frame {frame} of the viewer's page: {why}")]
    Frame { frame: usize, why: String },
    #[error("--frames {first}-{last}: the animation has frames 0 to {last_frame}")]
    Frames { first: usize, last: usize, last_frame: usize },
    #[error("size {0}x{1}: {2}")]
    Size(u32, u32, String),
    #[error("frame rate {0}: {1}")]
    Rate(f64, String),
    #[error("GIF encoding: {0}")]
    Gif(String),
    #[error("MP4 encoding: {0}")]
    Mp4(String),
    #[error(transparent)]
    Write(#[from] surfcap_mesh::Error),
}

/// What to render of the page: the animation's frames `frames` (inclusive; all by default) at
/// `fps` frames per second (the animation's own rate by default).
#[derive(Debug, Clone, Default)]
pub struct RenderRequest {
    pub frames: Option<(usize, usize)>,
    pub fps: Option<f64>,
}

/// What a render did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Rendered {
    /// The animation's frames shown, one per output frame, in order.
    pub frames: Vec<usize>,
    /// The animation's frame count and rate, as the page plays it.
    pub animation_frames: usize,
    pub animation_fps: f64,
    /// The output's frame rate.
    pub fps: f64,
    pub width: u32,
    pub height: u32,
}

/// The inclusive range of frames `frames` asks (all by default) of an animation of `n_frames`
/// frames; an error naming both when it lies outside.
pub fn frame_range(frames: Option<(usize, usize)>, n_frames: usize) -> Result<(usize, usize), RenderError> {
    let last_frame = n_frames.saturating_sub(1);
    let (first, last) = frames.unwrap_or((0, last_frame));
    if first > last || last > last_frame {
        return Err(RenderError::Frames { first, last, last_frame });
    }
    Ok((first, last))
}

/// The frames of `request` and the output's rate, for a page playing `n_frames` at `fps`.
pub fn plan(request: &RenderRequest, n_frames: usize, fps: f64) -> Result<(Vec<usize>, f64), RenderError> {
    let (first, last) = frame_range(request.frames, n_frames)?;
    let out = request.fps.unwrap_or(fps);
    if !(out.is_finite() && out > 0.0 && out <= 1000.0) {
        return Err(RenderError::Rate(out, "expected more than 0 and at most 1000 frames per second".into()));
    }
    Ok((sample_frames(first, last, fps, out), out))
}

/// Renders `request` from the open `page` into `sink`: one screenshot per output frame, a
/// progress step each.
pub fn render(
    page: &Page,
    request: &RenderRequest,
    sink: &mut dyn FrameSink,
    progress: &dyn surfcap_mesh::Progress,
) -> Result<Rendered, RenderError> {
    let (frames, fps) = plan(request, page.n_frames, page.fps)?;
    progress.start("rendering frames", frames.len() as u64);
    for &f in &frames {
        let picture = page.frame(f)?;
        sink.push(&picture)?;
        progress.advance(1);
    }
    progress.finish();
    Ok(Rendered {
        frames,
        animation_frames: page.n_frames,
        animation_fps: page.fps,
        fps,
        width: page.width,
        height: page.height,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_outside_the_animation_is_refused_by_its_frames() {
        let e = plan(&RenderRequest { frames: Some((10, 200)), fps: None }, 175, 30.0).unwrap_err();
        assert_eq!(e.to_string(), "--frames 10-200: the animation has frames 0 to 174");
        let e = plan(&RenderRequest { frames: Some((20, 10)), fps: None }, 175, 30.0).unwrap_err();
        assert!(matches!(e, RenderError::Frames { first: 20, last: 10, .. }));
        let e = plan(&RenderRequest { frames: None, fps: Some(0.0) }, 175, 30.0).unwrap_err();
        assert!(e.to_string().starts_with("frame rate 0:"), "{e}");
        let (f, fps) = plan(&RenderRequest { frames: Some((5, 9)), fps: None }, 175, 30.0).unwrap();
        assert_eq!((f, fps), (vec![5, 6, 7, 8, 9], 30.0));
    }
}

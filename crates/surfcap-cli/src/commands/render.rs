//! `surfcap render <what view plays> -o out.mp4|out.gif|frames/`: pictures to share. Starts the
//! viewer's server (`surfcap view`'s items, on an ephemeral 127.0.0.1 port, in this process),
//! opens its page's bare scene in headless Chromium at the chosen size and view, and takes one
//! screenshot per output frame (`surfcap-render`): an H.264 MP4, an animated GIF or a folder of
//! numbered PNG files. The output is planned before any work and replaces only what surfcap may
//! replace (`surfcap_mesh::output_set`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant};

use surfcap_mesh::UpAxis;
use surfcap_render::gif_encoding::GifEncoder;
use surfcap_render::mp4_encoding::Mp4Encoder;
use surfcap_render::png_frames::PngFrames;
use surfcap_render::{FrameSink, Page, PageOptions, RenderError, RenderRequest};
use surfcap_view::server::{ServeOptions, serve};

use crate::options::{SourceOpts, positive};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to render, as `surfcap view` shows it (several side by side, labels, colour maps).
    #[command(flatten)]
    pub shown: crate::commands::view::Shown,
    /// The output: an .mp4 video (H.264), an animated .gif, or a folder of numbered PNG files
    /// (any other name without an extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Picture size in pixels, WIDTHxHEIGHT (even numbers for MP4).
    #[arg(long, default_value = "960x540")]
    pub size: Size,
    /// Camera: top, front, side, three-quarter, or follow (moves with the first sequence)
    /// [default: the viewer's own, across the longer side of the ground].
    #[arg(long)]
    pub view: Option<ViewPreset>,
    /// Frames per second of the output [default: the animation's]. The animation plays at its
    /// own speed: a lower rate skips frames, a higher one shows frames twice. A GIF plays at most
    /// 50.
    #[arg(long, value_parser = positive)]
    pub fps: Option<f64>,
    /// Only the animation's frames A to B (inclusive, counted from 0 as the viewer's counter
    /// shows them), written A-B.
    #[arg(long)]
    pub frames: Option<FrameRange>,
    /// Frame rate of sources that do not give it (as `surfcap view --fps`).
    #[arg(long, value_parser = positive)]
    pub source_fps: Option<f64>,
    /// Up axis of sources that do not give it: +x, +y, +z, -x, -y or -z.
    #[arg(long)]
    pub up_axis: Option<UpAxis>,
    /// Length unit of sources that do not give it: m, cm, mm, in, or any other word.
    #[arg(long)]
    pub units: Option<String>,
    /// The Chromium (or Chrome) program [default: /usr/bin/chromium, else chromium,
    /// chromium-browser, google-chrome or chrome on the PATH].
    #[arg(long)]
    pub chromium: Option<PathBuf>,
    /// Longest wait, in seconds, for the page to load and for any one frame.
    #[arg(long, default_value_t = 120.0, value_parser = positive)]
    pub timeout: f64,
}

/// A picture size, `WIDTHxHEIGHT` pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected WIDTHxHEIGHT in pixels, 16 to 8192 each (e.g. 960x540), got {s:?}");
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let (width, height) =
            (w.trim().parse::<u32>().map_err(|_| bad())?, h.trim().parse::<u32>().map_err(|_| bad())?);
        if !(16..=surfcap_render::chromium::MAX_SIDE).contains(&width)
            || !(16..=surfcap_render::chromium::MAX_SIDE).contains(&height)
        {
            return Err(bad());
        }
        Ok(Size { width, height })
    }
}

/// The animation's frames `first` to `last`, inclusive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    pub first: usize,
    pub last: usize,
}

impl FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected A-B, the first and last frame (from 0, A at most B), e.g. 0-99, got {s:?}");
        let (a, b) = s.split_once('-').ok_or_else(bad)?;
        let (first, last) =
            (a.trim().parse::<usize>().map_err(|_| bad())?, b.trim().parse::<usize>().map_err(|_| bad())?);
        if first > last {
            return Err(bad());
        }
        Ok(FrameRange { first, last })
    }
}

/// The viewer's camera presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ViewPreset {
    Top,
    Front,
    Side,
    ThreeQuarter,
    Follow,
}

impl ViewPreset {
    /// The name the page's `?view=` takes.
    pub fn name(self) -> &'static str {
        match self {
            ViewPreset::Top => "top",
            ViewPreset::Front => "front",
            ViewPreset::Side => "side",
            ViewPreset::ThreeQuarter => "three-quarter",
            ViewPreset::Follow => "follow",
        }
    }
}

/// What the output is, from its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Mp4,
    Gif,
    Frames,
}

impl Kind {
    fn of(output: &Path) -> anyhow::Result<Kind> {
        match output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()) {
            Some(e) if e == "mp4" => Ok(Kind::Mp4),
            Some(e) if e == "gif" => Ok(Kind::Gif),
            None => Ok(Kind::Frames),
            Some(_) if output.is_dir() => Ok(Kind::Frames),
            Some(e) => anyhow::bail!(
                "render -o {}: expected an .mp4 or .gif file, or a folder for PNG frames (a name without an extension), not .{e}",
                output.display()
            ),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Kind::Mp4 => "mp4",
            Kind::Gif => "gif",
            Kind::Frames => "png frames",
        }
    }
}

/// The folder kind a frames output is marked with (so a later render may replace it).
const FRAMES_KIND: &str = "render-frames";

/// Where Chromium is: `given`, else `/usr/bin/chromium`, else the first of the usual names on
/// the PATH.
fn chromium_path(given: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(p) = given {
        return Ok(p.to_path_buf());
    }
    let default = Path::new("/usr/bin/chromium");
    if default.is_file() {
        return Ok(default.to_path_buf());
    }
    let names = ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome"];
    if let Some(path) = std::env::var_os("PATH") {
        for dir in std::env::split_paths(&path) {
            if let Some(p) = names.iter().map(|n| dir.join(n)).find(|p| p.is_file()) {
                return Ok(p);
            }
        }
    }
    anyhow::bail!(
        "Chromium not found (looked for /usr/bin/chromium and {} on the PATH): install it (Debian: apt-get install chromium) or give its path with --chromium",
        names.join(", ")
    )
}

/// A missing Chromium said with what to do about it; other errors as they are.
fn explain(e: RenderError) -> anyhow::Error {
    match e {
        RenderError::ChromiumMissing(p) => anyhow::anyhow!(
            "Chromium not found at {}: install it (Debian: apt-get install chromium) or give its path with --chromium",
            p.display()
        ),
        e => e.into(),
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let kind = Kind::of(&a.output)?;
    let chromium = chromium_path(a.chromium.as_deref())?;
    if kind == Kind::Mp4 && (!a.size.width.is_multiple_of(2) || !a.size.height.is_multiple_of(2)) {
        anyhow::bail!(
            "--size {}x{}: an MP4 (H.264, 4:2:0) needs an even width and height",
            a.size.width,
            a.size.height
        );
    }
    if kind == Kind::Gif && a.fps.is_some_and(|f| f > surfcap_render::gif_encoding::MAX_GIF_FPS) {
        anyhow::bail!(
            "--fps {}: a GIF plays at most {} frames per second (delays are in hundredths of a second, and browsers draw those under 2 as 10); choose a lower rate or MP4",
            a.fps.unwrap_or_default(),
            surfcap_render::gif_encoding::MAX_GIF_FPS
        );
    }
    // The output planned before any work: never an input, never what surfcap may not replace.
    let inputs: Vec<&Path> = a.shown.paths.iter().map(PathBuf::as_path).collect();
    let (outs, frames_dir) = match kind {
        Kind::Frames => {
            let (set, dir) = ctx.claim_dir(&a.output, FRAMES_KIND, &inputs)?;
            (set, Some(dir))
        }
        _ => {
            let mut set = surfcap_mesh::output_set::OutputSet::new(&inputs);
            set.file(&a.output)?;
            (set, None)
        }
    };
    let source = SourceOpts { fps: a.source_fps, up_axis: a.up_axis, units: a.units.clone() };
    let (items, report) = crate::commands::view::load(ctx, &a.shown, &source)?;
    let names: Vec<String> = items.iter().map(|i| i.name.clone()).collect();
    // A frame range outside the animation is refused by name before Chromium starts: the page
    // plays as many frames as its longest item has.
    let request = RenderRequest { frames: a.frames.map(|r| (r.first, r.last)), fps: a.fps };
    surfcap_render::frame_range(request.frames, items.iter().map(|i| i.n_frames).max().unwrap_or(0))?;
    let started = Instant::now();
    // The viewer's server on a free loopback port, on its own thread for the rest of the run.
    let (tx, rx) = std::sync::mpsc::channel();
    let server = std::thread::spawn(move || {
        serve(items, ServeOptions { port: 0, report }, move |addr| {
            let _ = tx.send(addr);
        })
    });
    let addr = match rx.recv() {
        Ok(addr) => addr,
        Err(_) => {
            return match server.join() {
                Ok(Err(e)) => Err(e.into()),
                _ => Err(anyhow::anyhow!("the viewer's server stopped before it listened")),
            };
        }
    };
    let page = Page::open(
        &format!("http://{addr}/"),
        &PageOptions {
            chromium,
            width: a.size.width,
            height: a.size.height,
            view: a.view.map(|v| v.name().to_string()),
            timeout: Duration::from_secs_f64(a.timeout),
        },
    )
    .map_err(explain)?;
    let loaded = started.elapsed();
    let (frames, fps) = surfcap_render::plan(&request, page.n_frames, page.fps)?;
    let bar = crate::progress::Bar::new(ctx);
    let t0 = Instant::now();
    let (written, rendered) = match kind {
        Kind::Gif => {
            let mut sink = GifEncoder::new(a.size.width, a.size.height, fps)?;
            let r = surfcap_render::render(&page, &request, &mut sink, &bar)?;
            write_file(&a.output, &sink.finish()?)?;
            (vec![a.output.clone()], r)
        }
        Kind::Mp4 => {
            let mut sink = Mp4Encoder::new(a.size.width, a.size.height, fps)?;
            let r = surfcap_render::render(&page, &request, &mut sink, &bar)?;
            write_file(&a.output, &sink.finish()?)?;
            (vec![a.output.clone()], r)
        }
        Kind::Frames => {
            let dir = frames_dir.expect("planned above");
            let mut sink = PngFrames::new(&dir, frames.len());
            let r = surfcap_render::render(&page, &request, &mut sink as &mut dyn FrameSink, &bar)?;
            (vec![a.output.clone()], r)
        }
    };
    let seconds = t0.elapsed().as_secs_f64();
    drop(page);
    ctx.commit(outs)?;
    let bytes = output_bytes(&a.output);
    let speed = rendered.frames.len() as f64 / seconds.max(1e-9);
    let first = rendered.frames.first().copied().unwrap_or(0);
    let last = rendered.frames.last().copied().unwrap_or(0);
    let summary = serde_json::json!({
        "written": written,
        "format": kind.name(),
        "sequences": names,
        "frames": rendered.frames.len(),
        "animation_frames": [first, last],
        "animation_fps": rendered.animation_fps,
        "fps": rendered.fps,
        "width": rendered.width,
        "height": rendered.height,
        "view": a.view.map(|v| v.name()),
        "bytes": bytes,
        "load_seconds": loaded.as_secs_f64(),
        "render_seconds": seconds,
        "frames_per_second": speed,
    });
    ctx.result(&summary, || {
        println!(
            "rendered {} of {} ({} to {} at {} fps) as {} {}x{} at {} fps in {:.1} s: {:.1} frames/s (Chromium start and loading {:.1} s)",
            crate::output::count_of(rendered.frames.len(), "frame"),
            names.join(", "),
            first,
            last,
            rendered.animation_fps,
            kind.name(),
            rendered.width,
            rendered.height,
            rendered.fps,
            seconds,
            speed,
            loaded.as_secs_f64()
        );
        ctx.wrote(&written);
        println!("{} bytes ({:.2} MB)", bytes, bytes as f64 / 1e6);
    });
    let _ = std::io::stdout().flush();
    Ok(())
}

/// Writes a finished file output (to its planned temporary, until the commit).
fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    surfcap_mesh::atomic::write_file(path, |w| w.write_all(bytes))?;
    Ok(())
}

/// The size of a file output, or the sum of a folder's files.
fn output_bytes(path: &Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries.filter_map(|e| e.ok()?.metadata().ok()).filter(|m| m.is_file()).map(|m| m.len()).sum(),
        Err(_) => std::fs::metadata(path).map(|m| m.len()).unwrap_or(0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_frame_ranges_parse_or_say_what_they_expect() {
        assert_eq!("640x480".parse::<Size>(), Ok(Size { width: 640, height: 480 }));
        assert!("640".parse::<Size>().unwrap_err().contains("WIDTHxHEIGHT"));
        assert!("8x8".parse::<Size>().is_err());
        assert_eq!("3-9".parse::<FrameRange>(), Ok(FrameRange { first: 3, last: 9 }));
        assert!("9-3".parse::<FrameRange>().unwrap_err().contains("A at most B"));
        assert!("x".parse::<FrameRange>().is_err());
    }

    #[test]
    fn the_output_kind_comes_from_its_name() {
        assert_eq!(Kind::of(Path::new("a.MP4")).unwrap(), Kind::Mp4);
        assert_eq!(Kind::of(Path::new("a.gif")).unwrap(), Kind::Gif);
        assert_eq!(Kind::of(Path::new("frames")).unwrap(), Kind::Frames);
        let e = Kind::of(Path::new("a.png")).unwrap_err().to_string();
        assert!(e.contains("not .png"), "{e}");
    }
}

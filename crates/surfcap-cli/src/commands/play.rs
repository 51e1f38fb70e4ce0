//! `surfcap play <subject>`: steer a captured character live in the browser. The subject's
//! essential graph and walk model are read from the cache or built (as `synth` does), a live
//! session of the interactive controller is started on them
//! (`surfcap_synthesis::controller::live_session`: the controller, the captured stream, the
//! blending thread), and the play page (`surfcap_view::play`) is served on it: keyboard (WASD or
//! arrows, shift to run, space to stop) or a gamepad steer the character (the design, and why
//! decisions are made server-side: `surfcap_view::play`'s documentation).

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use surfcap_pipeline::{GraphKind, GraphParams};
use surfcap_synthesis::Prepared;
use surfcap_synthesis::controller::live_session::{LiveAsk, LiveSession};
use surfcap_view::play::{Player, StepAsk, serve_play};

use crate::options::{AlphaOpt, CacheOpts, PortOpt, SourceOpts, TableOpts};
use crate::output::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The subject to steer (anything `view` plays as one subject: a subject cache, a glb, a
    /// capture folder). It needs clips the walk can go on from (loops or transitions back).
    pub subject: PathBuf,
    #[command(flatten)]
    pub port: PortOpt,
    /// Open the page in the default browser.
    #[arg(long)]
    pub open: bool,
    /// Bits per coordinate of the streamed meshes (8 to 16; fewer: smaller and coarser).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(8..=16))]
    pub bits: u32,
    #[command(flatten)]
    pub source: SourceOpts,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let subject = crate::options::open(ctx, &a.subject, &a.source)?;
    let pipe = a.cache.pipeline(ctx, subject)?;
    let params = GraphParams { table: a.table.params_for(&pipe)?, kind: GraphKind::Essential, alpha: a.alpha.value() };
    let prep = Prepared::new(pipe, params, None)?;
    let session = LiveSession::start(prep, a.bits)?;
    if !ctx.quiet && !ctx.json {
        let (precompute, coding, cached) = session.set_up_seconds();
        eprintln!(
            "surfcap play: {} moves precomputed in {precompute:.2} s; {} frames streamed in {:.1} MB ({:.2} s to {}, {} bits)",
            session.moves(),
            session.prepared().subject().n_frames(),
            session.captured_stream().len() as f64 / 1e6,
            coding,
            if cached { "read from the cache" } else { "code" },
            a.bits
        );
    }
    let json = ctx.json;
    let open = a.open;
    serve_play(Arc::new(PagePlayer(session)), a.port.port, |addr| {
        let url = format!("http://{addr}/");
        if json {
            print_json(&serde_json::json!({ "url": url }));
        } else {
            println!("{url}");
            eprintln!(
                "surfcap play: steer with WASD or the arrows (shift: run, space: stop) at {url} (Ctrl-C to stop)"
            );
        }
        let _ = std::io::stdout().flush();
        if open {
            open_in_browser(&url);
        }
    })?;
    Ok(())
}

/// Opens `url` with the desktop's opener (`xdg-open`, `open` on macOS, `start` on Windows); a
/// failure only prints a note, the URL is printed anyway.
fn open_in_browser(url: &str) {
    let mut cmd = if cfg!(target_os = "macos") {
        std::process::Command::new("open")
    } else if cfg!(windows) {
        let mut c = std::process::Command::new("cmd");
        c.args(["/C", "start", ""]);
        c
    } else {
        std::process::Command::new("xdg-open")
    };
    if let Err(e) = cmd.arg(url).spawn() {
        eprintln!("surfcap play: could not open a browser ({e}); open {url} yourself");
    }
}

/// The play page's [`Player`]: the library's live session, as it is.
struct PagePlayer(LiveSession);

impl Player for PagePlayer {
    fn info(&self) -> serde_json::Value {
        self.0.info()
    }

    fn captured_stream(&self) -> Arc<Vec<u8>> {
        self.0.captured_stream()
    }

    fn step(&self, ask: &StepAsk) -> Result<serde_json::Value, String> {
        self.0.step(&LiveAsk { direction: ask.direction, run: ask.run, dt: ask.dt })
    }

    fn blend(&self, id: u64) -> Result<Arc<Vec<u8>>, String> {
        self.0.blend(id)
    }

    fn blend_from(&self, id: u64, from: usize) -> Result<(Vec<u8>, usize), String> {
        self.0.blend_from(id, from)
    }

    fn restart(&self) -> Result<(), String> {
        self.0.restart()
    }
}

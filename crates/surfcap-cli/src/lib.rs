//! `surfcap`: the command-line front of the surfcap toolkit, as a library so that the binary
//! (`src/main.rs`) and tests share one definition of the command line ([`Cli`], [`main`]), and
//! other front-end programs (`surfcap-bench`) share its pieces: the output context ([`Ctx`]),
//! progress bars, option groups ([`options`]), the global options ([`GlobalOpts`]) and the way a
//! program runs and reports failures ([`run_front`] for any [`Front`]).
//!
//! A command is a file under `commands/` (a folder for a family: `synth/`, `eval/`,
//! `appearance/`): its arguments and one `run` that calls one library function
//! (surfcap-synthesis, surfcap-eval, surfcap-pipeline, ...) and prints or writes the result.
//! Argument groups several commands share (subject and source, cache, table, graph, output,
//! constraint, appearance and variation options) are defined once in [`options`] and flattened.
//! Option values are checked when parsed (`--w nan`, `--branching 0`: the message names the
//! option, the value and the range). What the front end itself holds: results as text or JSON
//! (`--json`), progress bars (indicatif, on stderr, hidden when not a terminal) and notes hidden
//! by `--quiet`, the HTML report page, the memory this machine has available (read here and
//! handed to surfcap-synthesis's request sizing), and signal handling: SIGINT/SIGTERM delivered
//! by `signal-hook` to an ordinary thread remove the live temporaries (a raw handler may not
//! remove folders) and exit 130/143. `tests/doc_examples.rs` parses every `surfcap ...` example
//! of the README and the user guide with [`Cli`].
//!
//! Exit codes: 0 success, 1 user error (bad input, bad arguments; the message says what and
//! where), 2 internal error (a bug: please report it), 3 a soft constraint missed with
//! `--strict` (`synth path | keyposes | reach`, `smg query`: the animation and its report are
//! written).
//!
//! With `--json` (found in the raw arguments, so it holds for argument errors too) every
//! failure prints exactly one JSON object on stderr, `{"error", "causes", "exit_code"}`, and
//! nothing else there; results stay on stdout.

mod body_parts;
pub mod commands;
mod files;
mod html_report;
mod limits;
mod mannequin_spec;
pub mod options;
pub mod output;
pub mod progress;
mod signals;
mod subject_summary;
mod synthesis_args;
mod view_items;
// ---- director ----
mod view_director;
// ---- end director ----
// ---- played files ----
mod view_played;
// ---- end played files ----

pub use output::Ctx;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Make new animations from 4D surface capture.
#[derive(Parser, Debug)]
#[command(name = "surfcap", version, about, long_about = None, negative_values = true)]
pub struct Cli {
    #[command(flatten)]
    globals: GlobalOpts,
    #[command(subcommand)]
    command: Command,
}

/// Values that start with a hyphen: `--opt -1` gives `-1` to the option, as `--opt=-1` does, so a
/// negative number out of range gets the option's own range message rather than clap's
/// "unexpected argument '-1'" (whose tip, `-- -1`, does not apply). A front end's top-level
/// `#[command(negative_values = true)]` sets it for every option of every command (clap's
/// `allow_negative_numbers` is per argument; this walks the tree once it is built). Only
/// tokens that read as numbers are taken: `--opt --json` still sees the flag.
pub trait NegativeValues {
    fn negative_values(self, yes: bool) -> Self;
}

impl NegativeValues for clap::Command {
    fn negative_values(self, yes: bool) -> Self {
        self.mut_args(|a| if a.get_action().takes_values() { a.allow_negative_numbers(yes) } else { a })
            .mut_subcommands(|c| c.negative_values(yes))
    }
}

/// The options of every command of a front end (`surfcap`, `surfcap-bench`): how results are
/// reported and whether folder outputs may replace what surfcap did not write. In every
/// `--help` they come after the command's own options (`display_order` past any command's
/// count; each flattened group numbers its options from 0, so they would otherwise be
/// interleaved with the command's).
#[derive(clap::Args, Debug, Clone, Copy)]
#[command(next_display_order = 10_000)]
pub struct GlobalOpts {
    /// No progress bars and no notes; only results and errors.
    #[arg(long, global = true)]
    quiet: bool,
    /// Print results (and errors) as JSON for scripts.
    #[arg(long, global = true)]
    json: bool,
    /// Let a folder output replace a non-empty folder that surfcap did not write (by default
    /// only an empty folder or surfcap's own earlier output of the same kind is replaced).
    #[arg(long, global = true)]
    force: bool,
    /// Most memory a command may need, estimated before any work (requests above it are
    /// refused with their size), in bytes or with a K, M, G or T suffix (powers of 1024)
    /// [default: half the memory available when the command starts, from /proc/meminfo's
    /// MemAvailable].
    #[arg(long, global = true)]
    max_memory: Option<limits::Bytes>,
    /// Most a command may write to disk, estimated before any work, in bytes or with a K, M, G
    /// or T suffix [default: the free space of the output's file system].
    #[arg(long, global = true)]
    max_disk: Option<limits::Bytes>,
}

/// A command-line program run by [`run_front`]: its parsed command line.
pub trait Front: Parser {
    /// The program's name, in its error messages (`<NAME>: error: ...`).
    const NAME: &'static str;
    /// Its global options.
    fn globals(&self) -> &GlobalOpts;
    /// Runs the parsed command.
    fn run(self, ctx: &Ctx) -> anyhow::Result<()>;
}

impl Front for Cli {
    const NAME: &'static str = "surfcap";

    fn globals(&self) -> &GlobalOpts {
        &self.globals
    }

    fn run(self, ctx: &Ctx) -> anyhow::Result<()> {
        match self.command {
            Command::Import(a) => commands::import::run(ctx, a),
            Command::Info(a) => commands::info::run(ctx, a),
            Command::Export(a) => commands::export::run(ctx, a),
            Command::Distance(a) => commands::distance::run(ctx, a),
            Command::Interpolate(a) => commands::interpolate::run(ctx, a),
            Command::Eval(a) => commands::eval::run(ctx, a),
            Command::Transitions(a) => commands::transitions::run(ctx, a),
            Command::Transition(a) => commands::transition::run(ctx, a),
            Command::Synth(a) => commands::synth::run(ctx, *a),
            Command::Make(c) => commands::make::run(ctx, c),
            Command::Graph(a) => commands::graph::run(ctx, a),
            Command::Demo(a) => commands::demo::run(ctx, a),
            Command::View(a) => commands::view::run(ctx, a),
            // ---- live play ----
            Command::Play(a) => commands::play::run(ctx, a),
            // ---- end live play ----
            Command::Report(a) => commands::report::run(ctx, a),
            Command::Transfer(c) => commands::transfer::run(ctx, c),
            Command::Parts(a) => commands::parts::run(ctx, a),
            Command::RemeshFrames(a) => commands::remesh_frames::run(ctx, a),
            Command::Smg(c) => commands::smg::run(ctx, c),
            Command::Appearance(c) => commands::appearance::run(ctx, c),
            Command::Vary(c) => commands::vary::run(ctx, c),
            Command::Tiles(c) => commands::tiles::run(ctx, c),
            Command::Reproduce(a) => commands::reproduce::run(ctx, a),
            Command::Render(a) => commands::render::run(ctx, a),
            Command::Rig(a) => commands::rig::run(ctx, a),
        }
    }
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Read sequences from files into a subject cache that later commands read fast (or a
    /// `.frames` folder when every frame has its own vertices and triangles).
    Import(commands::import::Args),
    /// Describe a subject (sequences, frames, vertices, triangles, components, bounding box) or
    /// a frame set (sequences, frames, vertex and triangle count ranges).
    Info(commands::info::Args),
    /// Write a subject as glb, OBJ frames, PLY frames, PC2 point caches, npy arrays, USD (usda, usdc) or Alembic (abc).
    Export(commands::export::Args),
    /// All-pairs pose distance matrix (thesis eq. 2.2, 2.13, 2.14) as .npy, cached.
    Distance(commands::distance::Args),
    /// Interpolate two poses, non-linearly (thesis eq. 2.45-2.49) or linearly.
    Interpolate(commands::interpolate::Args),
    /// All-pairs optimal transitions (DTW + variable segment lengths, thesis 2.5) as .npy, cached.
    Transitions(commands::transitions::Args),
    /// One optimal transition between two frames, blended (thesis 2.5.4, Algorithm 2), as .glb.
    Transition(commands::transition::Args),
    /// The essential graph or the motion-graph baseline over all frames (thesis 3.3), cached.
    Graph(commands::graph::Args),
    /// Synthesise an animation from a subject's graph: follow a path, move key poses, or reach a
    /// frame covering a distance in a time (thesis 3.5).
    Synth(Box<commands::synth::Cmd>),
    /// Make a built-in subject: the mannequin moved by BVH motion capture or procedural
    /// locomotion, or a head scan bent into nod, turn and tilt.
    #[command(subcommand)]
    Make(commands::make::Cmd),
    /// Evaluations that produce the numbers of the thesis's tables.
    Eval(commands::eval::Args),
    /// Run the main job on built-in data: the procedural mannequin (or --bvh files), imported,
    /// exported, its pose distances, an interpolation, its essential graph and a path-following
    /// animation.
    Demo(commands::demo::Args),
    /// Play sequences in the browser: a local server (127.0.0.1) with a three.js page; original
    /// frames green, synthetic red, paths and centre trajectories overlaid, side by side.
    View(commands::view::Args),
    // ---- live play ----
    /// Steer a captured character live in the browser: keyboard (WASD or arrows, shift to
    /// run, space to stop) or a gamepad; the interactive controller decides on the subject's
    /// essential graph and the meshes are streamed quantised and delta-coded.
    Play(commands::play::Args),
    // ---- end live play ----
    /// Body parts for motion transfer (thesis 5.4.2): propose them (joints, components or the
    /// rigidity of the motion), check a user's file, or show them in the browser.
    Parts(commands::parts::Args),
    /// One static HTML page of what exists for a subject: summary, cached distance matrix,
    /// included evaluations (tables, plots) and animations (with their path errors).
    Report(commands::report::Args),
    /// Motion transfer between two subjects by GP regression on body parts (thesis ch. 5):
    /// train a model from pairs of corresponding frames, apply it to new motions.
    #[command(subcommand)]
    Transfer(commands::transfer::Cmd),
    /// A frame set with known answers: every frame of a subject re-meshed on its own (its own
    /// vertices and triangles, as per-frame reconstructions for Huang et al.'s surface motion
    /// graph), with each new vertex's source triangle and barycentrics.
    RemeshFrames(commands::remesh_frames::Args),
    /// Huang et al. 2009's surface motion graph, the second synthesis engine: works on subjects
    /// and on frame sets (every frame its own topology); paths between key frames that cover a
    /// distance in a time, by integer linear programming.
    #[command(subcommand)]
    Smg(commands::smg::Cmd),
    /// Eigen appearance maps (thesis ch. 4): generate texture sequences with ground truth or
    /// paint a base texture; build the eigen textures and warps of per-frame maps; reconstruct,
    /// interpolate or complete maps with them.
    #[command(subcommand)]
    Appearance(commands::appearance::AppearanceCmd),
    /// Motion variation (thesis ch. 6): learn a GPDM per body part from a few sequences of one
    /// motion type, then sample endless slightly different versions of them and of their blends.
    #[command(subcommand)]
    Vary(commands::vary::Cmd),
    /// The all-pairs work (distances, transition table, sparse essential graph) as tile jobs in
    /// a work folder, for clusters: plan, run jobs (one, a stage, or all), status, merge.
    #[command(subcommand)]
    Tiles(commands::tiles::Cmd),
    /// Every table and figure of the thesis and the two papers beside the published values:
    /// runs the evals of the chosen items (resumable), then writes one HTML page with
    /// results.json and results.csv; `--list` shows the catalogue.
    Reproduce(commands::reproduce::Args),
    /// Pictures to share: what `view` plays, rendered headless in Chromium at a chosen size,
    /// view and frame rate, to an MP4 video, an animated GIF or a folder of PNG frames.
    Render(commands::render::Args),
    /// A subject as a skinned character (Smooth Skinning Decomposition with Rigid Bones, Le and
    /// Deng 2012): bones, sparse weights and one bone animation per sequence as a glTF skin,
    /// with the reconstruction error per frame, the size and the time.
    Rig(commands::rig::Args),
}

/// `surfcap info x | head` must end quietly when `head` closes the pipe, as other command-line
/// programs do, rather than panic in `println!`: restore the default SIGPIPE action, which Rust
/// programs ignore by default.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to SIG_DFL at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Whether `--json` was given, read from the raw arguments so that errors clap raises before
/// anything is parsed (an unknown subcommand, a bad value) are reported as JSON too.
fn json_requested() -> bool {
    std::env::args_os().skip(1).take_while(|a| a != "--").any(|a| a == "--json")
}

/// The messages of an error and its causes, each cause once: a cause whose text its parent
/// already includes (an error that formats its source and also returns it) is left out.
fn messages(e: &anyhow::Error) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for m in e.chain().map(|c| c.to_string()) {
        if out.last().is_none_or(|prev| !prev.contains(&m)) {
            out.push(m);
        }
    }
    out
}

/// Prints a failure: under `--json` one JSON object on stderr (`error`, `causes`, `exit_code`,
/// and `help` for argument errors; stdout stays for results), else `<program>: error: ...` and
/// one `caused by` line per cause.
fn report_failure(program: &str, json: bool, error: &str, causes: &[String], code: u8) {
    if json {
        eprintln!("{}", serde_json::json!({ "error": error, "causes": causes, "exit_code": code }));
    } else {
        eprintln!("{program}: error: {error}");
        for c in causes {
            eprintln!("  caused by: {c}");
        }
    }
}

/// Runs the `surfcap` program on the process's arguments and returns its exit code.
pub fn main() -> ExitCode {
    run_front::<Cli>()
}

/// Runs a front-end program `F` on the process's arguments and returns its exit code (see the
/// crate's documentation): parses the command line, reports argument errors, failures and
/// panics (as JSON under `--json`), and removes live temporaries on SIGINT/SIGTERM.
pub fn run_front<F: Front>() -> ExitCode {
    restore_default_sigpipe();
    let json = json_requested();
    let default_hook = std::panic::take_hook();
    let reported = std::sync::atomic::AtomicBool::new(false);
    std::panic::set_hook(Box::new(move |info| {
        // One report, even when several threads panic.
        if reported.swap(true, std::sync::atomic::Ordering::SeqCst) {
            return;
        }
        let bug = "internal error (this is a bug; please report it with the command you ran)";
        if json {
            let what = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let at = info.location().map(|l| format!("{}:{}", l.file(), l.line())).unwrap_or_default();
            report_failure(F::NAME, true, bug, &[format!("panicked at {at}: {what}")], 2);
        } else {
            default_hook(info);
            eprintln!("{}: {bug}", F::NAME);
        }
    }));
    let cli = match F::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let done = matches!(e.kind(), clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion);
            if done {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            if json {
                // clap's text: the error's paragraph, then tips and usage.
                let text = e.render().to_string();
                let (first, help) = text.trim().split_once("\n\n").unwrap_or((text.trim(), ""));
                let first = first.split_whitespace().collect::<Vec<_>>().join(" ");
                let error = first.strip_prefix("error: ").unwrap_or(&first);
                eprintln!("{}", serde_json::json!({ "error": error, "causes": [], "help": help, "exit_code": 1 }));
            } else {
                let _ = e.print();
            }
            return ExitCode::from(1);
        }
    };
    let g = *cli.globals();
    let ctx = Ctx {
        quiet: g.quiet,
        json: g.json,
        force: g.force,
        max_memory: g.max_memory.map(|b| b.0),
        max_disk: g.max_disk.map(|b| b.0),
        results: true,
    };
    signals::remove_temporaries_on_signals();
    // Unwind-safe enough: after a panic nothing of the run is used again (the program exits).
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // The tests' way to reach the internal-error path (no input is known to panic): an
        // environment variable no user sets by accident.
        if std::env::var_os("SURFCAP_TEST_INTERNAL_ERROR").is_some() {
            panic!("SURFCAP_TEST_INTERNAL_ERROR is set");
        }
        cli.run(&ctx)
    }));
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            let code = if e.is::<surfcap_synthesis::ConstraintsMissed>() { 3 } else { 1 };
            let m = messages(&e);
            report_failure(F::NAME, json, &m[0], &m[1..], code);
            ExitCode::from(code)
        }
        Err(_) => ExitCode::from(2),
    }
}

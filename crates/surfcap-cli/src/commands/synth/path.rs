//! `surfcap synth path <subject> --curve c.csv -o out.glb`: follow a 3D or ground-plane curve
//! with the centre of mass (thesis 3.5.1; `surfcap_synthesis::path_run`).

use std::path::PathBuf;

use surfcap_synthesis::{CurveSource, PathRequest, synthesize_path};

use crate::options::{GraphOpts, OutOpts, open};
use crate::output::{count_of, length};
use crate::synthesis_args::{AppearanceOpts, VaryOpts, check_constraints, playback, playback_inputs};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// CSV of curve points: x,y,z in the subject's axes and units, or two columns for a path on
    /// the ground plane (the two horizontal axes, e.g. x,z for +y up). '#' starts a comment.
    #[arg(long)]
    pub curve: PathBuf,
    /// Follow only the projection on the ground plane (implied by a two-column curve).
    #[arg(long)]
    pub planar: bool,
    /// Motion types on parts of the curve: TAG:FROM-TO (arc lengths), e.g. run:5-9; only
    /// sequences with that tag are used there. Comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub tags: Vec<String>,
    /// The first frame (sequence:frame or global); default: the best of all frames from which
    /// the walk can go on (a frame whose every way on ends at a sequence's last frame is refused).
    #[arg(long)]
    pub start: Option<String>,
    /// Follow the centre of these vertices instead of the centre of mass (comma-separated ids).
    #[arg(long, value_delimiter = ',')]
    pub track: Vec<usize>,
    /// Arc length covered by each branch-and-bound window (subject units; default 3, or 2 when
    /// some clip is a loop shorter than two seconds).
    #[arg(long, value_parser = crate::options::positive)]
    pub window: Option<f64>,
    /// Transitions allowed within one window (default 2, or 3 when some clip is a loop shorter
    /// than two seconds: its turns all come from transitions).
    #[arg(long)]
    pub max_transitions: Option<usize>,
    /// Transitions tried at each frame (its cheapest ones, round robin over destination
    /// sequences); the search's speed knob.
    #[arg(long, default_value_t = 8, value_parser = crate::options::count)]
    pub branching: usize,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
    #[command(flatten)]
    pub appearance: AppearanceOpts,
    #[command(flatten)]
    pub vary: VaryOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut inputs = vec![a.subject.as_path(), a.curve.as_path()];
    inputs.extend(playback_inputs(&a.appearance, &a.vary));
    let outs = a.out.plan(ctx, &inputs)?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let units = s.units.clone();
    let request = PathRequest {
        curve: CurveSource::File(a.curve.clone()),
        planar: a.planar,
        tags: a.tags.clone(),
        start: a.start.clone(),
        track: a.track.clone(),
        window: a.window,
        max_transitions: a.max_transitions,
        branching: a.branching,
    };
    let pipe = a.graph.cache.pipeline(ctx, s)?;
    let params = a.graph.params_for(&pipe)?;
    let bar = crate::progress::Bar::new(ctx);
    let playback = playback(&a.appearance, &a.vary);
    let o = synthesize_path(
        pipe,
        params,
        &request,
        playback,
        &a.out.output(ctx),
        &a.out.limits.limits(ctx, &a.out.output),
        &bar,
    )?;
    drop(bar);
    ctx.commit(outs)?;
    let curve_length = o.report.curve_length;
    let missed = o.constraints.iter().any(|c| c.missed);
    ctx.result(&o.report, || {
        // A path off by more than the tolerance was not followed: say so, and where.
        let verb = if missed { "missed" } else { "followed" };
        println!(
            "{verb} a {} curve: {}, {}; centre error mean {}, max {} ({:.1}% of the curve); search {:.2} s",
            length(curve_length, &units, 2),
            count_of(o.frames, "frame"),
            count_of(o.played.transitions, "transition"),
            length(o.mean_error, &units, 3),
            length(o.max_error, &units, 3),
            100.0 * o.max_error / curve_length,
            o.search_seconds
        );
        for m in &o.report.missed_stretches {
            println!(
                "  off the curve from {} to {} along it, where it turns up to {:.0} degrees per {}",
                length(m.from, &units, 2),
                length(m.to, &units, 2),
                m.turn_degrees_per_unit,
                surfcap_synthesis::words::unit_name(&units)
            );
        }
    });
    ctx.wrote(o.played.written.iter().chain(&o.played.report_path));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

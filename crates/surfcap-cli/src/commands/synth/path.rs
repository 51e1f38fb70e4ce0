//! `surfcap synth path <subject> --curve c.csv -o out.glb`: follow a 3D or ground-plane curve
//! with the centre of mass (thesis 3.5.1).

use std::path::PathBuf;

use anyhow::Context;
use surfcap_motion::path_following::PathSearch;
use surfcap_pipeline::constraint_files::{parse_restriction, read_curve};

use crate::limits::{Request, fastest_speed};
use crate::options::{GraphOpts, OutOpts, open};
use crate::output::length;
use crate::synthesis::{Prepared, check_constraints, run_path};

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
    /// Arc length covered by each branch-and-bound window (subject units).
    #[arg(long, default_value_t = 3.0, value_parser = crate::options::positive)]
    pub window: f64,
    /// Transitions allowed within one window.
    #[arg(long, default_value_t = 2)]
    pub max_transitions: usize,
    /// Transitions tried at each frame (its cheapest ones, round robin over destination
    /// sequences); the search's speed knob.
    #[arg(long, default_value_t = 8, value_parser = crate::options::count)]
    pub branching: usize,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
    #[command(flatten)]
    pub appearance: crate::frame_appearance::AppearanceOpts,
    #[command(flatten)]
    pub vary: crate::synthesis::VaryOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.out.output, &[&a.subject, &a.curve])?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let params = a.graph.params(s.fps)?;
    let appearance = a.appearance.open(&s, a.out.format(), &a.out.output)?;
    a.vary.check(&a.out.output)?;
    let curve = read_curve(&a.curve, s.up_axis, a.planar)?;
    if let Some(speed) = fastest_speed(&s, curve.axes()) {
        let what = format!(
            "--curve {} ({} long, the subject's fastest motion covers {} a second)",
            a.curve.display(),
            length(curve.length(), &s.units, 1),
            length(speed, &s.units, 2)
        );
        let frames = curve.length() / speed * s.fps;
        a.out.limits.check(&Request { what, frames, subject: &s, search_bytes: 0, format: a.out.format() })?;
    }
    let restrictions = a
        .tags
        .iter()
        .map(|t| parse_restriction(&s, t).with_context(|| format!("--tags {t:?}")))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let travel = surfcap_motion::clip_travel::subject_travel(&s);
    crate::travel::require_travel(&s, &travel, "a path constraint", None)?;
    for (t, r) in a.tags.iter().zip(&restrictions) {
        crate::travel::require_travel(&s, &travel, &format!("--tags {t}"), Some(&r.allowed))?;
    }
    let start = a.start.as_deref().map(|x| s.resolve_frame(x)).transpose()?.map(|g| g as u32);
    let search = PathSearch {
        window: a.window,
        max_transitions: a.max_transitions,
        branching: a.branching,
        ..PathSearch::for_fps(s.fps)
    };
    let tracked = (!a.track.is_empty()).then_some(a.track.as_slice());
    let prep = Prepared::new(a.graph.cache.pipeline(ctx, s), params, tracked)?
        .with_appearance(appearance)
        .with_variation(a.vary.clone());
    let o = run_path(ctx, &prep, &curve, &restrictions, start, &search, &a.out)?;
    let units = &prep.subject().units;
    ctx.result(&o.played.report, || {
        println!(
            "followed a {} curve: {}, {}; centre error mean {}, max {} ({:.1}% of the curve); search {:.2} s",
            length(curve.length(), units, 2),
            crate::output::count_of(o.frames, "frame"),
            crate::output::count_of(o.played.transitions, "transition"),
            length(o.mean_error, units, 3),
            length(o.max_error, units, 3),
            100.0 * o.max_error / curve.length(),
            o.search_seconds
        );
    });
    ctx.wrote(o.played.written.iter().chain([&o.played.report_path]));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

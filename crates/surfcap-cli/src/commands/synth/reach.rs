//! `surfcap synth reach <subject> --from a --to b --distance D --time T -o out.glb`: go from
//! one frame to another covering a distance in a time (Huang et al. 2009's constraint, searched
//! in the essential graph; `surfcap_synthesis::reach_run`).

use std::path::PathBuf;

use surfcap_pipeline::constraint_files::TimeSpec;
use surfcap_synthesis::{ReachRequest, synthesize_reach};

use crate::options::{GraphOpts, OutOpts, Positive, open};
use crate::output::length;
use crate::synthesis_args::{AppearanceOpts, VaryOpts, check_constraints, playback, playback_inputs};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// Start frame (sequence:frame or global).
    #[arg(long)]
    pub from: String,
    /// End frame.
    #[arg(long)]
    pub to: String,
    /// Ground-plane distance the centre of mass must travel (subject units).
    #[arg(long, value_parser = crate::options::non_negative)]
    pub distance: f64,
    /// Duration: seconds (a bare number, e.g. 3, or 3s) or frames shown (90f). T seconds show
    /// round(T x fps) frames, start included, as `smg query` counts them.
    #[arg(long, value_parser = crate::options::positive_time)]
    pub time: TimeSpec,
    /// Distance error worth one unit of realism cost (Huang et al.: 0.3 m).
    #[arg(long, default_value = "0.3")]
    pub distance_scale: Positive,
    /// Timing error, in frames, worth one unit of realism cost (Huang et al.: 10 frames).
    #[arg(long, default_value = "10")]
    pub time_scale: Positive,
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
    let mut inputs = vec![a.subject.as_path()];
    inputs.extend(playback_inputs(&a.appearance, &a.vary));
    let outs = a.out.plan(ctx, &inputs)?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let units = s.units.clone();
    let request = ReachRequest {
        from: a.from.clone(),
        to: a.to.clone(),
        distance: a.distance,
        time: a.time,
        distance_scale: a.distance_scale.0,
        time_scale: a.time_scale.0,
    };
    let pipe = a.graph.cache.pipeline(ctx, s)?;
    let params = a.graph.params_for(&pipe)?;
    let bar = crate::progress::Bar::new(ctx);
    let playback = playback(&a.appearance, &a.vary);
    let o = synthesize_reach(
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
    let r = &o.report;
    ctx.result(r, || {
        println!(
            "{} -> {}: {} travelled (asked {}) in {} frames, {:.2} s (asked {}: {} frames); realism cost {:.3}; \
             search {:.3} s",
            o.from_label,
            o.to_label,
            length(r.distance, &units, 2),
            length(a.distance, &units, 2),
            r.obtained_frames,
            r.seconds,
            request.time_text(),
            r.target_frames,
            r.realism_cost,
            r.search_seconds
        );
        if let Some(why) = &r.unreachable_why {
            println!("no walk of the graph can meet this target: {why}");
        } else if !r.met {
            println!("missed: the target lies within what the graph's walks can travel, but the search found no walk meeting it");
        }
        if !r.excluded_loops.is_empty() {
            println!(
                "{} degenerate loop(s) never played to pad time (fewer than {} frames, or poses varying less than {} typical frame step(s)); the report lists them",
                r.excluded_loops.len(),
                r.loop_rule.min_frames,
                r.loop_rule.variation_floor
            );
        }
    });
    ctx.wrote(o.played.written.iter().chain(&o.played.report_path));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

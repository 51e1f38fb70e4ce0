//! `surfcap synth keyposes <subject> --keys k.csv -o out.glb`: move key poses to new times
//! (thesis 3.5.2; `surfcap_synthesis::keyposes_run`); prints the table of Fig. 3.18.

use std::path::PathBuf;

use surfcap_synthesis::synthesize_keyposes;

use crate::options::{GraphOpts, OutOpts, open};
use crate::synthesis_args::{AppearanceOpts, VaryOpts, check_constraints, playback, playback_inputs};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// CSV of key poses: frame,time: the frame (sequence:frame or global) and when it must
    /// appear, in increasing time: an output frame number (a bare number, e.g. 90, or 90f) or
    /// seconds (3s, rounded to the nearest frame at the subject's rate). '#' starts a comment.
    #[arg(long)]
    pub keys: PathBuf,
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
    let mut inputs = vec![a.subject.as_path(), a.keys.as_path()];
    inputs.extend(playback_inputs(&a.appearance, &a.vary));
    let outs = a.out.plan(ctx, &inputs)?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let pipe = a.graph.cache.pipeline(ctx, s)?;
    let params = a.graph.params_for(&pipe)?;
    let bar = crate::progress::Bar::new(ctx);
    let playback = playback(&a.appearance, &a.vary);
    let o = synthesize_keyposes(
        pipe,
        params,
        &a.keys,
        playback,
        &a.out.output(ctx),
        &a.out.limits.limits(ctx, &a.out.output),
        &bar,
    )?;
    drop(bar);
    ctx.commit(outs)?;
    ctx.result(&o.report, || {
        // Thesis Fig. 3.18: input, requested and obtained times.
        let row = |label: &str, v: Vec<String>| {
            println!("{label:<10}{}", v.iter().map(|x| format!("{x:>7}")).collect::<String>())
        };
        let keys = &o.report.keys;
        row("Input", keys.iter().map(|k| k.input_time.to_string()).collect());
        row("Requested", keys.iter().map(|k| k.requested_time.to_string()).collect());
        row("Obtained", o.obtained.iter().map(|x| x.to_string()).collect());
        // Pose distance (eq. 2.13) between each key's pose and the frame shown at its time.
        row("Distance", keys.iter().map(|k| format!("{:.1}", k.pose_distance)).collect());
        println!("mean absolute timing error {:.2} frames; search {:.3} s", o.mean_abs_error, o.search_seconds);
        for k in keys {
            if let Some(why) = &k.unreachable_why {
                println!(
                    "key {} at frame {}: no walk of the graph can meet this time: {why}",
                    k.frame, k.requested_time
                );
            }
        }
    });
    ctx.wrote(o.played.written.iter().chain(&o.played.report_path));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

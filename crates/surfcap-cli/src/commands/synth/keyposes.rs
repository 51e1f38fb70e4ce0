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
    // The keys' poses are named `sequence:frame` in the table, however the file gave them.
    let index = s.frame_index().clone();
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
        // Thesis Fig. 3.18: each key's pose, the output frame asked and the one obtained, and
        // the pose distance (eq. 2.13) between the key's pose and the frame shown at its time.
        let keys = &o.report.keys;
        let poses: Vec<String> = keys
            .iter()
            .map(|k| index.resolve(&k.frame, "subject").map(|g| index.label(g)).unwrap_or(k.frame.clone()))
            .collect();
        let rows = [
            ("key pose", poses),
            ("asked at frame", keys.iter().map(|k| k.requested_time.to_string()).collect()),
            ("obtained at frame", o.obtained.iter().map(|x| x.to_string()).collect()),
            ("pose distance", keys.iter().map(|k| format!("{:.1}", k.pose_distance)).collect()),
        ];
        let width = rows.iter().flat_map(|(_, v)| v.iter().map(String::len)).max().unwrap_or(0) + 2;
        for (label, v) in &rows {
            println!("{label:<18}{}", v.iter().map(|x| format!("{x:>width$}")).collect::<String>());
        }
        println!("mean absolute timing error {:.2} frames; search {:.3} s", o.mean_abs_error, o.search_seconds);
        for k in keys {
            if let Some(why) = &k.unreachable_why {
                println!(
                    "key {} at output frame {}: no walk of the graph can meet this time: {why}",
                    k.frame, k.requested_time
                );
            }
        }
    });
    ctx.wrote(o.played.written.iter().chain(&o.played.report_path));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

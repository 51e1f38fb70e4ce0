//! `surfcap synth keyposes <subject> --keys k.csv -o out.glb`: move key poses to new times
//! (thesis 3.5.2); prints the table of Fig. 3.18.

use std::path::PathBuf;

use surfcap_motion::timed_walk::search_table_bytes;
use surfcap_pipeline::constraint_files::read_key_poses;

use crate::limits::Request;
use crate::options::{GraphOpts, OutOpts, open};
use crate::synthesis::{Prepared, check_constraints, run_keyposes};

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
    pub appearance: crate::frame_appearance::AppearanceOpts,
    #[command(flatten)]
    pub vary: crate::synthesis::VaryOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.out.output, &[&a.subject, &a.keys])?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let params = a.graph.params(s.fps)?;
    let appearance = a.appearance.open(&s, a.out.format(), &a.out.output)?;
    a.vary.check(&a.out.output)?;
    let keys = read_key_poses(&a.keys, &s)?;
    let (first, last) = (keys[0].requested, keys[keys.len() - 1].requested);
    let longest = keys.windows(2).map(|p| (p[1].requested - p[0].requested) as usize).max().unwrap_or(0);
    let what = format!("{}: keys from output frame {first} to {last}", a.keys.display());
    let frames = (last - first + 1) as f64;
    let search_bytes = search_table_bytes(s.n_frames(), longest);
    a.out.limits.check(&Request { what, frames, subject: &s, search_bytes, format: a.out.format() })?;
    let prep = Prepared::new(a.graph.cache.pipeline(ctx, s), params, None)?
        .with_appearance(appearance)
        .with_variation(a.vary.clone());
    let o = run_keyposes(ctx, &prep, &keys, &a.out)?;
    ctx.result(&o.played.report, || {
        // Thesis Fig. 3.18: input, requested and obtained times.
        let row = |label: &str, v: Vec<String>| {
            println!("{label:<10}{}", v.iter().map(|x| format!("{x:>7}")).collect::<String>())
        };
        row("Input", keys.iter().map(|k| k.input.to_string()).collect());
        row("Requested", keys.iter().map(|k| k.requested.to_string()).collect());
        row("Obtained", o.obtained.iter().map(|x| x.to_string()).collect());
        // Pose distance (eq. 2.13) between each key's pose and the frame shown at its time.
        let shown = o.played.report["keys"].as_array().map(Vec::as_slice).unwrap_or_default();
        row(
            "Distance",
            shown.iter().map(|k| format!("{:.1}", k["pose_distance"].as_f64().unwrap_or(f64::NAN))).collect(),
        );
        println!("mean absolute timing error {:.2} frames; search {:.3} s", o.mean_abs_error, o.search_seconds);
    });
    ctx.wrote(o.played.written.iter().chain([&o.played.report_path]));
    check_constraints(ctx, &a.out.constraints, &o.constraints)
}

//! `surfcap eval root-motion`: root motion recovered from ground contacts against the real
//! travel of BVH clips (issue 16; `surfcap_eval::root_motion_eval` computes it; this command
//! writes `root-motion.json` and prints the table per clip).

use std::path::Path;

use surfcap_eval::root_motion_eval::{RootMotionOptions, root_motion_eval};

pub fn run(ctx: &crate::Ctx, opts: &RootMotionOptions, output: &Path) -> anyhow::Result<()> {
    let r = root_motion_eval(opts)?;
    std::fs::create_dir_all(output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let (report, path) = super::save_report(output, "root-motion.json", &r, "written", &[])?;
    ctx.result(&report, || {
        println!(
            "root motion from ground contacts vs the real root travel (mannequin of {} vertices, legs as long as each \
             BVH's; travel stripped, then recovered); lengths in metres",
            r.vertices
        );
        println!(
            "{:<8} {:<18} {:>6} {:>7} {:>7} {:>7} {:>6} {:>6} {:>7} {:>7} {:>8}",
            "clip", "tags", "frames", "walked", "net", "found", "mean", "max", "final", "final%", "heading"
        );
        for c in &r.clips {
            println!(
                "{:<8} {:<18} {:>6} {:>7.2} {:>7.2} {:>7.2} {:>6.3} {:>6.3} {:>7.3} {:>6.1}% {:>8}",
                c.clip,
                c.tags.join(","),
                c.frames,
                c.distance_walked,
                c.true_displacement,
                c.recovered_displacement,
                c.mean_error,
                c.max_error,
                c.final_error,
                c.final_error_percent,
                c.heading_error_degrees.map_or_else(|| "-".into(), |h| format!("{h:.1} deg"))
            );
        }
        println!("wrote {} ({:.1} s)", path.display(), r.seconds);
    });
    Ok(())
}

//! `surfcap eval root-motion`: root motion recovered from ground contacts against the real
//! travel of BVH clips (`surfcap_eval::root_motion_eval` computes it; this command
//! writes `root-motion.json` and prints the table per clip).

use std::path::{Path, PathBuf};

use surfcap_eval::root_motion_eval::{RootMotionOptions, root_motion_eval};
use surfcap_geometry::root_motion_from_contacts::ContactParams;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// BVH files with real root travel (CMU joint names), e.g. ../shared/data/cmu_bvh/16_*.bvh.
    #[arg(long, num_args = 1.., required = true)]
    pub bvh: Vec<PathBuf>,
    /// Target vertex count of the mannequin (1000 to 20000).
    #[arg(long, default_value_t = 2000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Contact height, as a fraction of the subject's height above the ground.
    #[arg(long, default_value_t = ContactParams::default().height, value_parser = crate::options::positive)]
    pub contact_height: f64,
    /// Contact stillness, as a fraction of the subject's height per second: how closely the
    /// planted vertices move together.
    #[arg(long, default_value_t = ContactParams::default().speed, value_parser = crate::options::positive)]
    pub contact_speed: f64,
    /// Largest vertical speed of a contact vertex, as a fraction of the subject's height per
    /// second.
    #[arg(long, default_value_t = ContactParams::default().vertical_speed, value_parser = crate::options::positive)]
    pub contact_vertical_speed: f64,
    /// Folder for the report (root-motion.json).
    #[arg(short, long, default_value = "root-motion-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let bvh: Vec<&Path> = a.bvh.iter().map(PathBuf::as_path).collect();
    let outs = super::folder::claim(ctx, &a.output, &bvh, "eval-root-motion")?;
    let contacts =
        ContactParams { height: a.contact_height, speed: a.contact_speed, vertical_speed: a.contact_vertical_speed };
    let output = a.output.as_path();
    let r = root_motion_eval(&RootMotionOptions { bvh: a.bvh, vertices: a.vertices, contacts })?;
    std::fs::create_dir_all(output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let (report, path) = super::folder::save_report(output, "root-motion.json", &r, "written", &[])?;
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
    ctx.commit(outs)
}

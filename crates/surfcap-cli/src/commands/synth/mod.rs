//! `surfcap synth --bvh <files...> | --procedural walk,jog,... -o <subject>`: the built-in
//! mannequin moved by motion capture or by procedural locomotion, written as a subject cache
//! with per-sequence tags and ground-truth joints.

use std::time::Instant;

use serde_json::json;

use crate::mannequin_spec::{MannequinArgs, build};

mod keyposes;
mod path;
mod reach;

/// `surfcap synth`: build a mannequin subject (flat arguments), or one of the subcommands.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Cmd {
    #[command(subcommand)]
    pub what: Option<What>,
    #[command(flatten)]
    pub build: MannequinArgs,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Follow a 3D or ground-plane curve with the centre of mass (thesis 3.5.1).
    Path(path::Args),
    /// Move key poses to new times (thesis 3.5.2, Fig. 3.18).
    Keyposes(keyposes::Args),
    /// Go from one frame to another covering a distance in a time (Huang et al. 2009).
    Reach(reach::Args),
}

pub fn run(ctx: &crate::Ctx, c: Cmd) -> anyhow::Result<()> {
    match c.what {
        Some(What::Path(a)) => path::run(ctx, a),
        Some(What::Keyposes(a)) => keyposes::run(ctx, a),
        Some(What::Reach(a)) => reach::run(ctx, a),
        None => build_and_write(ctx, c.build),
    }
}

fn build_and_write(ctx: &crate::Ctx, a: MannequinArgs) -> anyhow::Result<()> {
    let Some(output) = a.output.clone() else {
        anyhow::bail!("-o/--output: the subject cache folder to write is required");
    };
    let inputs: Vec<&std::path::Path> = a.bvh.iter().map(|p| p.as_path()).collect();
    surfcap_mesh::output_path::check_not_input(&output, &inputs)?;
    let t0 = Instant::now();
    let s = build(ctx, &a)?;
    let bar = crate::progress::Bar::new(ctx);
    surfcap_mesh::cache::write_cache(&output, &s, ctx.force, &bar)?;
    let secs = t0.elapsed().as_secs_f64();
    let sequences: Vec<serde_json::Value> =
        s.sequences().iter().map(|q| json!({ "name": q.name, "frames": q.n_frames(), "tags": q.tags })).collect();
    let result = json!({
        "subject": s.name,
        "output": output,
        "fps": s.fps,
        "vertices": s.topology().n_vertices(),
        "triangles": s.topology().n_triangles(),
        "sequences": sequences,
        "seconds": secs,
    });
    ctx.result(&result, || {
        println!(
            "synthesised {:?}: {} vertices, {} triangles, {} fps -> {} ({secs:.2} s)",
            s.name,
            s.topology().n_vertices(),
            s.topology().n_triangles(),
            s.fps,
            output.display()
        );
        for q in s.sequences() {
            println!(
                "  {:<12} {:>12}  tags {}",
                q.name,
                crate::output::count_of(q.n_frames(), "frame"),
                q.tags.join(", ")
            );
        }
    });
    Ok(())
}

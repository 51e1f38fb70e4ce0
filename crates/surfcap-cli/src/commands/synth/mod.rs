//! `surfcap synth --bvh <files...> | --procedural walk,jog,... -o <subject>`: the built-in
//! mannequin moved by motion capture or by procedural locomotion, written as a subject cache
//! with per-sequence tags and ground-truth joints (`--uv-atlas`: with a UV atlas).
//! `surfcap synth --head ../shared/data/leeperrysmith_head -o head.subject`: the head scan
//! bent into three sequences (nod, turn, tilt; `surfcap_builtin::head_motion`), keeping its UV
//! atlas, the textured subject of thesis Fig. 7.1.

use std::path::Path;
use std::time::Instant;

use serde_json::json;
use surfcap_builtin::head_motion::{head_motion_size, head_motion_subject};
use surfcap_mesh::Subject;

use crate::mannequin_spec::{MannequinArgs, build};

mod keyposes;
mod path;
mod reach;

/// `surfcap synth`: build a mannequin subject (flat arguments), or one of the subcommands.
#[derive(clap::Args, Debug)]
// With no arguments at all, the help (its subcommands path, keyposes and reach, and the
// options that build a subject) rather than the build's "-o is required".
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true, arg_required_else_help = true)]
pub struct Cmd {
    #[command(subcommand)]
    pub what: Option<What>,
    #[command(flatten)]
    pub build: MannequinArgs,
    #[command(flatten)]
    pub head: HeadArgs,
}

/// The moving head: a UV-mapped scan bent into nod, turn and tilt sequences.
#[derive(clap::Args, Debug)]
pub struct HeadArgs {
    /// A UV-mapped head scan (a folder holding `template.obj`, e.g.
    /// ../shared/data/leeperrysmith_head, or an OBJ file) moved into three sequences, nod, turn
    /// and tilt (a non-rigid bend of the neck), at 30 fps, keeping its UV atlas.
    #[arg(long, conflicts_with_all = ["bvh", "procedural", "uv_atlas"])]
    pub head: Option<std::path::PathBuf>,
    /// Frames of each head sequence (one period of the motion, starting and ending at rest); the
    /// subject's size is checked against --max-memory and --max-disk before any frame is made.
    #[arg(long, default_value_t = 34, requires = "head", value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub frames_per_sequence: usize,
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
        None => build_and_write(ctx, c.build, c.head),
    }
}

/// The head scan of `head` (a folder's `template.obj`, or an OBJ) bent into its sequences.
fn head_subject(
    ctx: &crate::Ctx,
    head: &Path,
    frames_per_sequence: usize,
    name: Option<&str>,
    output: &Path,
) -> anyhow::Result<Subject> {
    let obj = if head.is_dir() { head.join("template.obj") } else { head.to_path_buf() };
    let mesh = surfcap_formats::obj::read_obj(&obj)?;
    let topology = mesh.topology().map_err(|e| e.in_file(&obj))?;
    anyhow::ensure!(
        topology.uv().is_some(),
        "{}: the scan has no texture coordinates: expected a UV-mapped mesh (`vt` on every face corner)",
        obj.display()
    );
    ctx.check_size(&head_motion_size(topology.n_vertices(), frames_per_sequence), Some(output))?;
    let mut s = head_motion_subject(&topology, &mesh.positions, frames_per_sequence, "arbitrary")
        .map_err(|e| e.in_file(&obj))?;
    if let Some(n) = name {
        s.name = n.to_string();
    }
    Ok(s)
}

fn build_and_write(ctx: &crate::Ctx, a: MannequinArgs, head: HeadArgs) -> anyhow::Result<()> {
    let Some(output) = a.output.clone() else {
        anyhow::bail!("-o/--output: the subject cache folder to write is required");
    };
    let mut inputs: Vec<&Path> = a.bvh.iter().map(|p| p.as_path()).collect();
    inputs.extend(head.head.as_deref());
    surfcap_mesh::output_path::check_not_input(&output, &inputs)?;
    let t0 = Instant::now();
    let s = match &head.head {
        Some(h) => head_subject(ctx, h, head.frames_per_sequence, a.name.as_deref(), &output)?,
        None => build(ctx, &a)?,
    };
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

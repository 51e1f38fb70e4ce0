//! `surfcap synth path | keyposes | reach`: an animation synthesised from a subject's graph
//! (thesis 3.5). The older flat form that built a subject, `surfcap synth --bvh <files...> |
//! --procedural walk,jog,... | --head <scan> -o <subject>`, is still accepted, hidden from help,
//! with a note naming `surfcap make mannequin | head` (see `commands/make.rs`), which builds
//! them now.

use crate::mannequin_spec::{Built, MannequinArgs, build_and_write as build_and_write_subject};

mod keyposes;
mod path;
mod reach;

/// `surfcap synth`: one of the subcommands (or, hidden, the older flat build of a subject).
#[derive(clap::Args, Debug)]
// With no arguments at all, the help (its subcommands path, keyposes and reach, and where
// subjects are built) rather than the build's "-o is required". The flat build options are
// hidden from help (the `mut_args` runs before the global options join).
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    arg_required_else_help = true,
    mut_args(|a| a.hide(true)),
    after_help = "Built-in subjects (the mannequin moved by BVH files or procedural motions, the head scan) are made by `surfcap make mannequin | head`."
)]
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

/// The older flat form, `surfcap synth --bvh | --procedural | --head ... -o X`: still accepted
/// (hidden from help), with a note naming the command that now builds subjects.
fn build_and_write(ctx: &crate::Ctx, a: MannequinArgs, head: HeadArgs) -> anyhow::Result<()> {
    let Some(output) = a.output.clone() else {
        anyhow::bail!(
            "-o/--output: the subject cache folder to write is required (built-in subjects are now made by `surfcap make mannequin | head ... -o X.subject`)"
        );
    };
    match &head.head {
        Some(h) => {
            ctx.note(&format!(
                "`surfcap synth --head` is now `surfcap make head {} -o {}`",
                h.display(),
                output.display()
            ));
            build_and_write_subject(
                ctx,
                Built::Head { scan: h, frames_per_sequence: head.frames_per_sequence, name: a.name.as_deref() },
                &output,
            )
        }
        None => {
            ctx.note("`surfcap synth --bvh | --procedural` is now `surfcap make mannequin --bvh | --procedural ...`");
            build_and_write_subject(ctx, Built::Mannequin(&a), &output)
        }
    }
}

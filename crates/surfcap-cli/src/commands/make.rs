//! `surfcap make mannequin (--bvh FILES | --procedural walk,jog,...) -o X.subject` and `surfcap
//! make head <scan> -o head.subject`: the built-in subjects, written as subject caches. The
//! mannequin (`surfcap_builtin::mannequin`) is moved by BVH motion capture retargeted onto it or
//! by procedural locomotion, with per-sequence tags and ground-truth joints; the head is a
//! UV-mapped scan bent into nod, turn and tilt sequences (`surfcap_builtin::head_motion`), the
//! textured subject of thesis Fig. 7.1.

use std::path::PathBuf;

use crate::mannequin_spec::{Built, MannequinArgs, build_and_write};

#[derive(clap::Subcommand, Debug)]
pub enum Cmd {
    /// The mannequin moved by BVH motion capture (one sequence per file) and/or procedural
    /// locomotion (walk, jog, turn_left, turn_right, jump, idle), as a subject.
    Mannequin(MannequinCmd),
    /// A UV-mapped head scan bent into three sequences, nod, turn and tilt (a non-rigid bend of
    /// the neck), at 30 fps, keeping its UV atlas, as a subject.
    Head(HeadCmd),
}

/// `surfcap make mannequin`: the mannequin's options, the output required.
#[derive(clap::Args, Debug)]
#[command(mut_arg("output", |a| a.required(true)))]
pub struct MannequinCmd {
    #[command(flatten)]
    pub build: MannequinArgs,
}

/// `surfcap make head`.
#[derive(clap::Args, Debug)]
pub struct HeadCmd {
    /// The head scan: a folder holding `template.obj` (e.g. $SURFCAP_DATA/leeperrysmith_head) or
    /// an OBJ file, with texture coordinates.
    pub scan: PathBuf,
    /// Frames of each sequence (one period of the motion, starting and ending at rest); the
    /// subject's size is checked against --max-memory and --max-disk before any frame is made.
    #[arg(long, default_value_t = 34, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub frames_per_sequence: usize,
    /// Subject name (default: head).
    #[arg(long)]
    pub name: Option<String>,
    /// The subject cache folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Mannequin(m) => {
            let output = m.build.output.clone().expect("clap requires -o for make mannequin");
            build_and_write(ctx, Built::Mannequin(&m.build), &output)
        }
        Cmd::Head(h) => build_and_write(
            ctx,
            Built::Head { scan: &h.scan, frames_per_sequence: h.frames_per_sequence, name: h.name.as_deref() },
            &h.output,
        ),
    }
}

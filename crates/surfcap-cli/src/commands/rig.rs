//! `surfcap rig <subject> --bones N --max-influences 4 -o rig.glb`: the subject as a skinned
//! character (Smooth Skinning Decomposition with Rigid Bones, Le and Deng 2012) written as a glTF
//! skin, with a report of its reconstruction error per frame, size and time.

use std::path::PathBuf;

use serde_json::json;
use surfcap_skinning::SsdrOptions;

use crate::options::{SubjectArgs, whole_in};

fn bones(s: &str) -> Result<usize, String> {
    whole_in(s, 1, surfcap_skinning::ssdr::MAX_BONES)
}

fn influences(s: &str) -> Result<usize, String> {
    whole_in(s, 1, surfcap_skinning::ssdr::MAX_INFLUENCES)
}

fn iterations(s: &str) -> Result<usize, String> {
    whole_in(s, 0, 1000)
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of bones: more bones give a smaller error and a larger file (each bone adds a
    /// joint animation: 28 bytes per frame).
    #[arg(long, default_value_t = 32, value_parser = bones)]
    pub bones: usize,
    /// Most bones that move one vertex (4 is what every engine plays; up to 8).
    #[arg(long, default_value_t = 4, value_parser = influences)]
    pub max_influences: usize,
    /// Alternations of the bone and weight updates: more give a smaller error and take longer.
    #[arg(long, default_value_t = 20, value_parser = iterations)]
    pub iterations: usize,
    /// Seed of the initial bones: the same seed gives the same rig.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Only these sequences (repeatable; default: all, one rig for all of them).
    #[arg(long = "sequence")]
    pub sequences: Vec<String>,
    /// Output .glb (a skinned mesh, one animation per sequence); its report goes beside it as
    /// <output stem>.report.json.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let report_path = surfcap_synthesis::report_path(&a.output);
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&[&a.subject.path]);
    outs.file(&a.output)?;
    outs.side_file(&report_path, surfcap_synthesis::REPORT_KIND)?;
    let s = a.subject.open(ctx)?.select(&a.sequences)?;
    let opts = SsdrOptions {
        bones: a.bones,
        max_influences: a.max_influences,
        iterations: a.iterations,
        seed: a.seed,
        ..SsdrOptions::default()
    };
    let bar = crate::progress::Bar::new(ctx);
    let rigged = surfcap_synthesis::rig_run::rig_subject(&s, &opts, &bar)?;
    surfcap_mesh::atomic::write_file(&a.output, |w| w.write_all(&rigged.glb))?;
    surfcap_synthesis::write_report(&report_path, &rigged.report)?;
    ctx.commit(outs)?;
    let r = &rigged.report;
    let written = vec![a.output.clone(), report_path];
    ctx.result(&json!({ "rig": r, "written": written }), || {
        let u = &s.units;
        println!(
            "{}: {} bones (at most {} per vertex) over {} frames of {} vertices",
            r.subject, r.bones, r.max_influences, r.frames, r.vertices
        );
        println!(
            "error against the source: RMS {} ({:.3}% of height), max {} ({:.3}% of height); worst frame RMS {}",
            crate::output::length(r.rms, u, 4),
            r.rms_percent_of_height,
            crate::output::length(r.max, u, 4),
            r.max_percent_of_height,
            r.per_frame
                .iter()
                .max_by(|x, y| x.rms.total_cmp(&y.rms))
                .map(|f| format!("{} at {}", crate::output::length(f.rms, u, 4), f.frame))
                .unwrap_or_default(),
        );
        println!(
            "size {} bytes ({:.1}x smaller than the morph-target glb's {} bytes); decomposition {:.2} s, total {:.2} s",
            r.bytes,
            r.morph_glb_bytes as f64 / r.bytes.max(1) as f64,
            r.morph_glb_bytes,
            r.decomposition_seconds,
            r.seconds
        );
        ctx.wrote(&written);
    });
    Ok(())
}

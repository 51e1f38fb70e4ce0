//! `surfcap demo`: the main job on built-in data. For now: build the built-in subject, write it
//! as source files, import them into a subject cache, describe it, export it in every format,
//! compute its pose distance matrix and a non-linear interpolation between two of its poses.

use std::path::PathBuf;

use serde_json::json;
use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_mesh::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::io::npy::write_npy;
use surfcap_mesh::{FrameLabel, Sequence};
use surfcap_synth::{WormParams, worm_subject};

use super::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder for everything the demo writes.
    #[arg(short, long, default_value = "surfcap-demo")]
    pub output: PathBuf,
    /// Seed of the built-in motion.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let bar = crate::progress::Bar::new(ctx);
    let say = |s: &str| {
        if !ctx.json && !ctx.quiet {
            println!("{s}");
        }
    };
    let built = worm_subject(&WormParams { seed: a.seed, ..Default::default() })?;
    say(&format!(
        "1. built the built-in subject {:?}: {} sequences, {} frames, {} vertices",
        built.name,
        built.sequences().len(),
        built.n_frames(),
        built.topology().n_vertices()
    ));
    let source = a.output.join("source");
    export(&built, ExportFormat::Npy, &source, ExportOptions::default(), &bar)?;
    say(&format!("2. wrote it as source files (template.obj + positions.npy) in {}", source.display()));
    let opts = surfcap_mesh::import::ImportOptions { name: Some(built.name.clone()), ..Default::default() };
    let imported = surfcap_mesh::import::import(std::slice::from_ref(&source), &opts, &bar)?;
    let subject = imported.subject;
    anyhow::ensure!(
        built.sequences().iter().all(|b| subject.sequence(&b.name).is_some_and(|(_, a)| a == b)),
        "the imported sequences differ from the built ones"
    );
    let cache = a.output.join("worm.subject");
    surfcap_mesh::cache::write_cache(&cache, &subject, &bar)?;
    say(&format!("3. imported them into the subject cache {}", cache.display()));
    let mut written = Vec::new();
    for (fmt, name) in [
        (ExportFormat::Glb, "worm.glb"),
        (ExportFormat::Obj, "obj"),
        (ExportFormat::Ply, "ply"),
        (ExportFormat::Pc2, "pc2"),
        (ExportFormat::Npy, "npy"),
    ] {
        written.extend(export(&subject, fmt, &a.output.join("export").join(name), ExportOptions::default(), &bar)?);
    }
    say(&format!("4. exported it as glb, OBJ, PLY, PC2 and npy in {}", a.output.join("export").display()));

    // Pose geometry (thesis 2.3-2.4): all-pairs distances and a non-linear interpolation.
    let d = distance_matrix(&subject, &DistanceParams::default(), &bar);
    let dist_path = a.output.join("distances.npy");
    surfcap_mesh::atomic::write_file(&dist_path, |w| write_npy(w, &[d.n, d.n], &d.values))?;
    say(&format!("5. computed the {0} x {0} deformation-gradient pose distances -> {1}", d.n, dist_path.display()));
    let (from, to) = (subject.resolve_frame("slither:0")?, subject.resolve_frame("curl:40")?);
    let interp = NonlinearInterpolator::new(
        subject.topology(),
        subject.frame(from).expect("resolved"),
        subject.frame(to).expect("resolved"),
        subject.up_axis,
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    let steps = 12usize;
    let nv = subject.topology().n_vertices();
    let mut pos = Vec::with_capacity(steps * 3 * nv);
    for k in 0..steps {
        let lambda = k as f64 / (steps - 1) as f64;
        pos.extend_from_slice(&interp.at(lambda, StretchInterpolation::Linear));
    }
    let seq = Sequence::new("slither_0_to_curl_40", nv, pos)?.with_labels(FrameLabel::original_ends(steps))?;
    let blend = subject.derived("worm-interpolation", seq)?;
    let interp_path = a.output.join("export/interpolation.glb");
    written.extend(export(&blend, ExportFormat::Glb, &interp_path, ExportOptions::default(), &bar)?);
    say(&format!("6. interpolated slither:0 -> curl:40 non-linearly in {steps} poses -> {}", interp_path.display()));
    if ctx.json {
        print_json(&json!({ "subject": super::info::describe(&subject), "cache": cache, "written": written }));
    } else if !ctx.quiet {
        println!("\nsurfcap info {}:", cache.display());
        super::info::run(ctx, super::info::Args { subject: cache.clone(), source: Default::default() })?;
        println!(
            "\nplay {} and {} in Blender (File > Import > glTF) or any three.js viewer",
            a.output.join("export/worm.glb").display(),
            interp_path.display()
        );
    }
    Ok(())
}

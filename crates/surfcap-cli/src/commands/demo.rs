//! `surfcap demo`: the main job on built-in data. Build the built-in subject (the mannequin
//! walking, jogging, turning, jumping and idling, or driven by `--bvh` files), write it as
//! source files, import them into a subject cache, describe it, export it in every format,
//! compute its pose distance matrix and a non-linear interpolation between two of its poses;
//! then its transitions, essential graph, and an animation that follows an S-shaped path.

use std::path::PathBuf;

use serde_json::json;
use surfcap_formats::export::{ExportFormat, export};
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_mesh::npy::write_npy;
use surfcap_mesh::{FrameLabel, Sequence};
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::path_following::PathSearch;

use surfcap_pipeline::constraint_files::read_curve;
use surfcap_pipeline::{GraphKind, GraphParams};

use crate::html_report::write_report;
use crate::mannequin_spec::{MannequinArgs, build};
use crate::options::{CacheOpts, TableOpts};
use crate::output::print_json;
use crate::subject_summary::{describe, print_summary};
use surfcap_synthesis::{Output, PathQuery, Prepared};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder for everything the demo writes.
    #[arg(short, long, default_value = "surfcap-demo")]
    pub output: PathBuf,
    /// Seed of the built-in motion.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// BVH files to drive the mannequin instead of the procedural motions.
    #[arg(long, num_args = 1..)]
    pub bvh: Vec<PathBuf>,
    /// Target vertex count of the mannequin.
    #[arg(long, default_value_t = 2500, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let inputs: Vec<&std::path::Path> = a.bvh.iter().map(|p| p.as_path()).collect();
    surfcap_mesh::output_path::check_not_input(&a.output, &inputs)?;
    // Filled in place (the demo reads back what it writes); a folder surfcap did not write is
    // refused, even with --force, so a failed demo never leaves its marker among the user's files.
    surfcap_mesh::output_path::claim_dir(&a.output, "demo", ctx.force)?;
    let bar = crate::progress::Bar::new(ctx);
    let say = |s: &str| ctx.say(s);
    let procedural: Vec<String> = if a.bvh.is_empty() {
        ["walk", "jog", "turn_left", "turn_right", "jump", "idle"].map(String::from).to_vec()
    } else {
        Vec::new()
    };
    let spec = MannequinArgs {
        bvh: a.bvh.clone(),
        procedural,
        shape: "average".into(),
        vertices: a.vertices,
        seed: a.seed,
        fps: None,
        duration: None,
        bvh_units: None,
        uv_atlas: false,
        name: Some("mannequin".into()),
        output: None,
    };
    let built = build(ctx, &spec)?;
    say(&format!(
        "1. built the mannequin ({} vertices) {}: {} ({}), {} frames at {} fps",
        built.topology().n_vertices(),
        if a.bvh.is_empty() { "with procedural motions" } else { "driven by the BVH files" },
        crate::output::count_of(built.sequences().len(), "sequence"),
        built.sequences().iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", "),
        built.n_frames(),
        built.fps
    ));
    let source = a.output.join("source");
    export(&built, ExportFormat::Npy, &source, ctx.export_options(), &bar)?;
    say(&format!("2. wrote it as source files (template.obj + positions.npy) in {}", source.display()));
    let opts = surfcap_formats::import::ImportOptions { name: Some(built.name.clone()), ..Default::default() };
    let imported = surfcap_formats::import::import(std::slice::from_ref(&source), &opts, &bar)?;
    let subject = imported.subject;
    anyhow::ensure!(
        built.sequences().iter().all(|b| subject.sequence(&b.name).is_some_and(|(_, a)| a == b)),
        "the imported sequences differ from the built ones"
    );
    let cache = a.output.join("mannequin.subject");
    surfcap_mesh::cache::write_cache(&cache, &subject, ctx.force, &bar)?;
    say(&format!("3. imported them into the subject cache {}", cache.display()));
    let mut written = Vec::new();
    for (fmt, name) in [
        (ExportFormat::Glb, "mannequin.glb"),
        (ExportFormat::Obj, "obj"),
        (ExportFormat::Ply, "ply"),
        (ExportFormat::Pc2, "pc2"),
        (ExportFormat::Npy, "npy"),
    ] {
        written.extend(export(&subject, fmt, &a.output.join("export").join(name), ctx.export_options(), &bar)?);
    }
    say(&format!("4. exported it as glb, OBJ, PLY, PC2 and npy in {}", a.output.join("export").display()));

    // Pose geometry (thesis 2.3-2.4): all-pairs distances and a non-linear interpolation. The
    // distances go to the demo's own cache, where the later steps read them.
    let pipe = CacheOpts { cache_dir: Some(a.output.join("cache")), no_cache: false }.pipeline(ctx, subject.clone())?;
    let d = pipe.distances(&DistanceParams::default())?.value;
    let n = d.n;
    let dist_path = a.output.join("distances.npy");
    surfcap_mesh::atomic::write_file(&dist_path, |w| write_npy(w, &[n, n], &d.values))?;
    say(&format!("5. computed the {n} x {n} deformation-gradient pose distances -> {}", dist_path.display()));
    // From the first frame of the first sequence to the middle of the last one (with the
    // procedural motions: standing in the walk -> the jump's crouch).
    let (mut first, mut last) = (&subject.sequences()[0], &subject.sequences()[subject.sequences().len() - 1]);
    if a.bvh.is_empty() {
        first = subject.sequence("walk").map_or(first, |(_, s)| s);
        last = subject.sequence("jump").map_or(last, |(_, s)| s);
    }
    let (from_spec, to_spec) = (format!("{}:0", first.name), format!("{}:{}", last.name, last.n_frames() / 4));
    let (from, to) = (subject.resolve_frame(&from_spec)?, subject.resolve_frame(&to_spec)?);
    let interp = NonlinearInterpolator::new(
        subject.topology(),
        subject.frame(from).expect("resolved"),
        subject.frame(to).expect("resolved"),
        subject.up_axis,
    )?;
    let steps = 12usize;
    let nv = subject.topology().n_vertices();
    let mut pos = Vec::with_capacity(steps * 3 * nv);
    for k in 0..steps {
        let lambda = k as f64 / (steps - 1) as f64;
        pos.extend_from_slice(&interp.at(lambda, StretchInterpolation::Linear));
    }
    let seq = Sequence::new(format!("{from_spec}_to_{to_spec}").replace(':', "_"), nv, pos)?
        .with_labels(FrameLabel::original_ends(steps))?;
    let blend = subject.derived("mannequin-interpolation", seq)?;
    let interp_path = a.output.join("export/interpolation.glb");
    written.extend(export(&blend, ExportFormat::Glb, &interp_path, ctx.export_options(), &bar)?);
    say(&format!(
        "6. interpolated {from_spec} -> {to_spec} non-linearly in {steps} poses -> {}",
        interp_path.display()
    ));

    // Transitions, essential graph and a path-following animation (thesis 2.5, 3.3, 3.5.1).
    let params = GraphParams {
        table: TableOpts::default().params_for(&pipe)?,
        kind: GraphKind::Essential,
        alpha: Alpha::new(0.05)?,
    };
    let prep = Prepared::new(pipe, params, None)?;
    say(&format!(
        "7. found the optimal transition between every pair of frames (DTW, thesis 2.5) and built the essential graph: {} edges, {} of them transitions ({:.1} s)",
        prep.graph.edges().len(),
        prep.model.n_transitions(),
        prep.seconds
    ));
    // An S-shaped path on the ground, 9 units long, starting at the subject's first frame.
    let (iu, iv, _) = surfcap_geometry::motion_plane_alignment::plane_axes(subject.up_axis);
    let c0 = surfcap_motion::blend::centre(subject.frame(0).expect("a frame"));
    let curve_path = a.output.join("s_path.csv");
    let mut csv = String::from("# the demo's path on the ground plane\nu,v\n");
    for k in 0..=72 {
        let x = k as f64 * 0.1;
        csv += &format!("{:.4},{:.4}\n", c0[iu] + x, c0[iv] + (2.0 * std::f64::consts::PI * x / 7.2).sin());
    }
    surfcap_mesh::atomic::write_file(&curve_path, |w| w.write_all(csv.as_bytes()))?;
    let curve = read_curve(&curve_path, subject.up_axis, true)?;
    let out_path = a.output.join("export/path.glb");
    let report_path = surfcap_synthesis::report_path(&out_path);
    let out = Output { force: ctx.force, ..Output::new(&out_path) };
    // Twice the default branching: this graph is small and the S tight (radius ~1.3 m), and the
    // wider search halves the error (0.32 -> 0.17 m) for ~1 s more.
    let search = PathSearch { branching: 16, ..PathSearch::for_fps(subject.fps) };
    let path = prep.follow_path(&PathQuery { curve: &curve, restrictions: &[], start: None, search }, &out, &bar)?;
    say(&format!(
        "8. followed the S-shaped path {} ({:.1} long): {} frames, {} transitions, centre-of-mass error mean {:.3}, max {:.3} -> {} and {}",
        curve_path.display(),
        curve.length(),
        path.frames,
        path.played.transitions,
        path.mean_error,
        path.max_error,
        out_path.display(),
        report_path.display()
    ));
    written.extend(path.played.written.iter().cloned());
    written.push(report_path);
    // The report of what the demo made, and the command that plays it.
    let report_dir = a.output.join("report");
    let include = vec![interp_path.clone(), out_path.clone()];
    let rep = write_report(&prep.pipe, &cache, &report_dir, &include, ctx.force)?;
    say(&format!(
        "9. wrote the report {} ({} plots, {} animations); play them in the browser with: surfcap view {}",
        rep.index.display(),
        rep.plots,
        rep.animations,
        report_dir.display()
    ));
    written.push(rep.index.clone());
    if ctx.json {
        print_json(&json!({ "subject": describe(&subject), "cache": cache, "written": written,
            "path": { "mean_error": path.mean_error, "max_error": path.max_error, "frames": path.frames } }));
    } else if !ctx.quiet {
        println!("\nsurfcap info {}:", cache.display());
        print_summary(&subject, &describe(&subject));
        println!(
            "\nsee the report: {}\nplay the animations in the browser: surfcap view {}\n(or open {}, {} and {} in Blender: File > Import > glTF)",
            rep.index.display(),
            report_dir.display(),
            a.output.join("export/mannequin.glb").display(),
            interp_path.display(),
            out_path.display()
        );
    }
    Ok(())
}

//! `surfcap synth reach <subject> --from a --to b --distance D --time T -o out.glb`: go from
//! one frame to another covering a distance in a time (Huang et al. 2009's constraint, searched
//! in the essential graph).

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_motion::timed_walk::{TimedGraph, search_table_bytes};
use surfcap_pipeline::constraint_files::{TimeSpec, TimeUnit};

use crate::limits::Request;
use crate::options::{GraphOpts, OutOpts, Positive, open};
use crate::output::length;
use crate::synthesis::{
    Constraint, Prepared, add_constraints, add_travel, check_constraints, length_unit, pose_distance_to_output,
    write_walk,
};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// Start frame (sequence:frame or global).
    #[arg(long)]
    pub from: String,
    /// End frame.
    #[arg(long)]
    pub to: String,
    /// Ground-plane distance the centre of mass must travel (subject units).
    #[arg(long, value_parser = crate::options::non_negative)]
    pub distance: f64,
    /// Duration: seconds (a bare number, e.g. 3, or 3s) or output frames (90f; seconds are
    /// rounded to the nearest frame at the subject's rate).
    #[arg(long, value_parser = crate::options::positive_time)]
    pub time: TimeSpec,
    /// Distance error worth one unit of realism cost (Huang et al.: 0.3 m).
    #[arg(long, default_value = "0.3")]
    pub distance_scale: Positive,
    /// Timing error, in frames, worth one unit of realism cost (Huang et al.: 10 frames).
    #[arg(long, default_value = "10")]
    pub time_scale: Positive,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
    #[command(flatten)]
    pub appearance: crate::frame_appearance::AppearanceOpts,
    #[command(flatten)]
    pub vary: crate::synthesis::VaryOpts,
}

impl Args {
    /// `--time` as given, with its unit.
    fn time_text(&self) -> String {
        match self.time.unit {
            Some(TimeUnit::Frames) => format!("{}f", self.time.value),
            Some(TimeUnit::Seconds) | None => format!("{}s", self.time.value),
        }
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.out.output, &[&a.subject])?;
    let s = open(ctx, &a.subject, &a.graph.source)?;
    let params = a.graph.params(s.fps)?;
    let appearance = a.appearance.open(&s, a.out.format(), &a.out.output)?;
    a.vary.check(&a.out.output)?;
    let (from, to) = (s.resolve_frame(&a.from)? as u32, s.resolve_frame(&a.to)? as u32);
    let frames = match a.time.frames(s.fps, TimeUnit::Seconds) {
        Some(f) if f >= 1 => f as usize,
        _ => anyhow::bail!(
            "--time {}: expected a duration of at least one whole frame (at {} fps), e.g. 90f or 3s",
            a.time_text(),
            s.fps
        ),
    };
    let search_bytes = search_table_bytes(s.n_frames(), frames);
    let what = format!("--time {} at {} fps", a.time_text(), s.fps);
    let (from_label, to_label) = (s.frame_index().label(from as usize), s.frame_index().label(to as usize));
    a.out.limits.check(&Request { what, frames: frames as f64, subject: &s, search_bytes, format: a.out.format() })?;
    if a.distance > 0.0 {
        let travel = surfcap_motion::clip_travel::subject_travel(&s);
        crate::travel::require_travel(&s, &travel, &format!("--distance {}", a.distance), None)?;
    }
    let prep = Prepared::new(a.graph.cache.pipeline(ctx, s), params, None)?
        .with_appearance(appearance)
        .with_variation(a.vary.clone());
    let t0 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let scales = (a.distance_scale.0, a.time_scale.0);
    let (w, cost) = tg.walk_with_distance_and_time(from, to, a.distance, frames, scales, tg.longest_edge())?;
    let search_seconds = t0.elapsed().as_secs_f64();
    // The time asks for a duration: `frames` steps of 1/fps, so the animation that lasts it
    // shows one frame more (both ends). Counts below are frames written, as `frames` is.
    let (asked_frames, obtained_frames) = (frames + 1, w.frames + 1);
    let distance_error = (w.distance - a.distance).abs();
    let time_error = w.frames.abs_diff(frames);
    let fps = prep.subject().fps;
    let report = json!({
        "constraint": "reach", "from": a.from, "to": a.to,
        "target_distance": a.distance, "distance": w.distance, "distance_error": distance_error,
        "target_seconds": frames as f64 / fps, "seconds": w.frames as f64 / fps,
        "target_frames": asked_frames, "obtained_frames": obtained_frames,
        "time_error_frames": time_error,
        "realism_cost": w.cost, "total_cost": cost, "search_seconds": search_seconds,
    });
    let mut played = write_walk(ctx, &prep, &w.walk, &PlaneMotion::identity(prep.up()), "reach", &a.out, report)?;
    // The viewer draws the centre track over the animation, as it does for `synth path`.
    add_travel(&mut played.report, &played.centres, prep.up());
    // The poses shown first and last against the frames asked for there.
    let last = played.output.n_frames() - 1;
    played.report["pose_distance_from"] = json!(pose_distance_to_output(&prep, &played.output, from, 0)?);
    played.report["pose_distance_to"] = json!(pose_distance_to_output(&prep, &played.output, to, last)?);
    let tol = &a.out.constraints;
    let constraints = [
        Constraint::new(
            "distance",
            length_unit(prep.subject()),
            a.distance,
            w.distance,
            distance_error,
            tol.distance(a.distance),
        )
        .relative_to(a.distance),
        Constraint::new("time", "frames", asked_frames as f64, obtained_frames as f64, time_error as f64, tol.frames())
            .relative_to(frames as f64),
    ];
    add_constraints(&mut played.report, &constraints);
    played.save_report()?;
    let units = &prep.subject().units;
    ctx.result(&played.report, || {
        println!(
            "{from_label} -> {to_label}: {} travelled (asked {}) in {obtained_frames} frames, {:.2} s (asked {}: \
             {asked_frames} frames); realism cost {:.3}; search {search_seconds:.3} s",
            length(w.distance, units, 2),
            length(a.distance, units, 2),
            w.frames as f64 / fps,
            a.time_text(),
            w.cost
        );
    });
    ctx.wrote(played.written.iter().chain([&played.report_path]));
    check_constraints(ctx, &a.out.constraints, &constraints)
}

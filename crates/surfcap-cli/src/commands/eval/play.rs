//! `surfcap eval play`: the interactive controller on scripted inputs against offline path
//! following on the same trajectories (`surfcap_eval::play_eval` computes it; this command
//! builds the subjects, writes play.json and prints the table).

use std::path::PathBuf;

use surfcap_eval::play_eval::{
    PlayEval, PlayEvalOptions, Script, cmu_play_subject, knight_play_subject, play_eval, vlasic_play_subject,
};
use surfcap_pipeline::{GraphKind, GraphParams};

use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{AlphaOpt, CacheOpts, TableOpts};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("CMU clips, the KayKit knight and the Vlasic capture"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Subjects: `cmu` (the mannequin moved by CMU walks, turns, jog, stop and a stand),
    /// `knight` (the KayKit knight's idle, walk and run with root motion from contacts),
    /// `vlasic` (the crane capture).
    #[arg(long, value_delimiter = ',', default_value = "cmu,knight,vlasic", value_parser = ["cmu", "knight", "vlasic"])]
    pub subjects: Vec<String>,
    /// Scripts: straight-run, turn-left, stop-and-idle, zig-zag, circle, speed-ramp.
    #[arg(long, value_delimiter = ',', default_value = "straight-run,turn-left,stop-and-idle,zig-zag,circle,speed-ramp",
          value_parser = ["straight-run", "turn-left", "stop-and-idle", "zig-zag", "circle", "speed-ramp"])]
    pub scripts: Vec<String>,
    /// Vertices of the mannequin (1000 to 20000).
    #[arg(long, default_value_t = 1000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Do not follow the trajectories offline.
    #[arg(long)]
    pub no_offline: bool,
    /// Parametric blending: `compare` plays every script with the captured clips only and
    /// with blending (a partner clip mixed in at a continuous weight); `on` or `off` play it
    /// once.
    #[arg(long, default_value = "compare", value_parser = ["compare", "on", "off"])]
    pub parametric: String,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    /// Folder for the report (play.json).
    #[arg(short, long, default_value = "play-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.data], "eval-play")?;
    let scripts: Vec<Script> = a.scripts.iter().filter_map(|s| Script::parse(s)).collect();
    let mut opts = PlayEvalOptions { scripts, offline: !a.no_offline, ..Default::default() };
    opts.controller.parametric = a.parametric != "off";
    opts.compare_parametric = a.parametric == "compare";
    let (mut results, mut failed) = (Vec::new(), Vec::new());
    for name in &a.subjects {
        let subject = match name.as_str() {
            "cmu" => cmu_play_subject(&a.data, a.vertices)?,
            "knight" => knight_play_subject(&a.data)?,
            _ => vlasic_play_subject(&a.data)?,
        };
        ctx.note(&format!(
            "{name}: {} ({} frames of {} vertices at {} fps)",
            subject.name,
            subject.n_frames(),
            subject.topology().n_vertices(),
            subject.fps
        ));
        let pipe = a.cache.pipeline(ctx, subject)?;
        // Segments fit the subject's shortest looping clip, as `surfcap play` and `synth path`
        // build them: the knight's one-cycle clips are shorter than the default 1/3-2 s windows.
        let params =
            GraphParams { table: a.table.params_for(&pipe)?, kind: GraphKind::Essential, alpha: a.alpha.value() };
        let prep = surfcap_synthesis::Prepared::new(pipe, params, None)?;
        // A subject the controller cannot play at all (no frame from which a walk goes on) is
        // reported as such; the others are still evaluated.
        match play_eval(&prep, &opts) {
            Ok(r) => results.push(r),
            Err(surfcap_eval::Error::Synthesis(e)) => {
                failed.push(serde_json::json!({ "subject": name, "why": e.to_string() }));
            }
            Err(e) => return Err(e.into()),
        }
    }
    let output = a.output.as_path();
    std::fs::create_dir_all(output).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let mut plots = Vec::new();
    for r in &results {
        plots.extend(write_plots(output, r)?);
    }
    let (report, path) = super::folder::save_report(
        output,
        "play.json",
        &serde_json::json!({ "subjects": &results, "not_evaluated": &failed }),
        "written",
        &plots,
    )?;
    ctx.result(&report, || {
        print_table(&results, &path);
        for f in &failed {
            println!("{}: not evaluated: {}", f["subject"].as_str().unwrap_or("?"), f["why"].as_str().unwrap_or("?"));
        }
    });
    ctx.commit(outs)
}

/// Per script, the heading and the speed over time against the command, one line per mode
/// (captured clips only, parametric blending): `<subject>-<script>-heading` and `-speed`.
fn write_plots(output: &std::path::Path, r: &PlayEval) -> anyhow::Result<Vec<PathBuf>> {
    let palette = [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0)];
    let mut written = Vec::new();
    for script in Script::ALL.into_iter().filter(|x| r.scripts.iter().any(|s| s.script == *x)) {
        let runs: Vec<_> = r.scripts.iter().filter(|s| s.script == script).collect();
        let Some(first) = runs.first() else { continue };
        let t = &first.over_time.time;
        let series = |name: String, points: Vec<(f64, f64)>, color, dashed| Series {
            name,
            points,
            color,
            dashed,
            markers: false,
        };
        let mode = |parametric: bool| if parametric { "blending" } else { "captured clips" };
        // Gaps (standing) split a line: only the moving stretches are drawn, as separate series.
        let stretches = |v: &[Option<f64>], time: &[f64]| -> Vec<Vec<(f64, f64)>> {
            let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for (k, x) in v.iter().enumerate() {
                match x {
                    Some(y) => out.last_mut().expect("one stretch").push((time[k], *y)),
                    None if out.last().is_some_and(|l| !l.is_empty()) => out.push(Vec::new()),
                    None => {}
                }
            }
            out.retain(|l| !l.is_empty());
            out
        };
        let mut heading = Vec::new();
        for (k, pts) in stretches(&first.over_time.commanded_heading, t).into_iter().enumerate() {
            heading.push(series(if k == 0 { "command".into() } else { String::new() }, pts, (0, 0, 0), true));
        }
        let mut speed = vec![series(
            "command".into(),
            t.iter().copied().zip(first.over_time.commanded_speed.iter().copied()).collect(),
            (0, 0, 0),
            true,
        )];
        for (i, run) in runs.iter().enumerate() {
            let color = palette[i % palette.len()];
            let time = &run.over_time.time;
            for (k, pts) in stretches(&run.over_time.heading, time).into_iter().enumerate() {
                heading.push(series(
                    if k == 0 { mode(run.parametric).into() } else { String::new() },
                    pts,
                    color,
                    false,
                ));
            }
            speed.push(series(
                mode(run.parametric).into(),
                time.iter().copied().zip(run.over_time.speed.iter().copied()).collect(),
                color,
                false,
            ));
            if run.parametric && run.blended_frames > 0 {
                // The blend weight, scaled to the speed axis's command.
                let top = first.commanded_speed.max(f64::MIN_POSITIVE);
                speed.push(series(
                    format!("blend weight (x {top:.2})"),
                    time.iter().zip(&run.over_time.blend_weight).map(|(t, w)| (*t, w * top)).collect(),
                    (150, 150, 150),
                    false,
                ));
            }
        }
        let stem = format!("{}-{}", r.subject, script.name());
        let u = &r.unit;
        written.extend(write_line_chart(
            &output.join(format!("{stem}-heading")),
            &LineChart {
                title: format!("{}, {}: heading against the command", r.subject, script.name()),
                x_label: "time (s)".into(),
                y_label: "heading (degrees, unwrapped)".into(),
                series: heading,
            },
        )?);
        written.extend(write_line_chart(
            &output.join(format!("{stem}-speed")),
            &LineChart {
                title: format!("{}, {}: speed against the command", r.subject, script.name()),
                x_label: "time (s)".into(),
                y_label: format!("ground speed ({u}/s)"),
                series: speed,
            },
        )?);
    }
    Ok(written)
}

fn opt(x: Option<f64>, decimals: usize) -> String {
    x.map_or_else(|| "-".into(), |v| format!("{v:.decimals$}"))
}

/// Latencies as `0.37` or `0.37/0.40/-` (one per change; `-` never reached), `-` when none.
fn latencies(v: &[Option<f64>]) -> String {
    if v.is_empty() { "-".into() } else { v.iter().map(|x| opt(*x, 2)).collect::<Vec<_>>().join("/") }
}

fn print_table(results: &[PlayEval], path: &std::path::Path) {
    for r in results {
        let u = &r.unit;
        println!(
            "{}: {} frames x {} vertices at {} fps, height {:.2} {u}; walk {} {u}/s, run {} {u}/s; {} moves, precomputed in {:.2} s \
             (errors and sliding in {u} and {u}/s)",
            r.subject,
            r.frames,
            r.vertices,
            r.fps,
            r.height,
            opt(r.walk_speed, 2),
            opt(r.run_speed, 2),
            r.moves,
            r.precompute_seconds
        );
        println!(
            "  the data's quickest turns (captured clips): 45 degrees in {} s, 90 degrees in {} s",
            opt(r.quickest_turn_45, 2),
            opt(r.quickest_turn_90, 2)
        );
        match &r.no_blend_pairs {
            Some(why) => println!("  parametric blending: no clip pair qualifies: {why}"),
            None => println!(
                "  parametric blending pairs (clip+partner: frames): {}",
                r.blend_pairs.iter().map(|(a, b, n)| format!("{a}+{b}: {n}")).collect::<Vec<_>>().join(", ")
            ),
        }
        println!(
            "  {:<14} {:<5} {:>6} {:>8} {:>9} {:>11} {:>13} {:>8} {:>12} {:>9} | {:>9} {:>12} {:>8}",
            "script",
            "mode",
            "blend%",
            "head err",
            "speed err",
            "head lat s",
            "speed lat s",
            "sliding",
            "trans (cost)",
            "path err",
            "offline",
            "trans (cost)",
            "sliding"
        );
        for s in &r.scripts {
            let (off_err, off_trans, off_slide) = match &s.offline {
                Some(o) => (
                    format!("{:.3}", o.mean_path_error),
                    format!("{} ({:.2})", o.transitions, o.transition_cost),
                    opt(o.foot_sliding, 3),
                ),
                None => ("-".into(), "-".into(), "-".into()),
            };
            println!(
                "  {:<14} {:<5} {:>6.0} {:>6} d {:>9.3} {:>11} {:>13} {:>8} {:>12} {:>9.3} | {:>9} {:>12} {:>8}",
                s.script.name(),
                if s.parametric { "blend" } else { "clips" },
                100.0 * s.blended_frames as f64 / s.frames.max(1) as f64,
                opt(s.heading_error_mean, 1),
                s.speed_error_mean,
                latencies(&s.heading_latency),
                latencies(&s.speed_latency),
                opt(s.foot_sliding, 3),
                format!("{} ({:.2})", s.transitions, s.transition_cost),
                s.mean_path_error,
                off_err,
                off_trans,
                off_slide
            );
            for n in &s.cannot_follow {
                println!("      cannot follow: {n}");
            }
            if let Some(why) = &s.offline_refused {
                println!("      offline walk not made: {why}");
            }
        }
    }
    println!(
        "mode: captured clips only, or with parametric blending (blend%: output frames blended); \
         head err: mean heading error, degrees; speed err: mean; lat: seconds to half of each commanded change (- never); \
         sliding: foot sliding; path err: mean distance to the commanded trajectory at the same arc length; offline: \
         path following on the same trajectory"
    );
    println!("wrote {}", path.display());
}

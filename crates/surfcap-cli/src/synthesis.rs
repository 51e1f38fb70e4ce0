//! Constrained synthesis as the commands run it (thesis 3.5): a subject prepared with its graph
//! and walk model from the pipeline, a search (path, key poses, distance and time), the walk
//! played by the library and written with its JSON report. Shared by `synth path | keyposes |
//! reach`, `demo` and `bench synth`. `--vary SEED --variation-model DIR` plays learned variants
//! (thesis chapter 6) when the walk repeats frames (issue 19 item 6, [`VaryOpts`]).

use anyhow::Context;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use serde_json::json;
use surfcap_formats::export::{ExportFormat, export, export_frame_set};
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::{Subject, UpAxis};
use surfcap_motion::graph::Graph;
use surfcap_motion::path_following::{Curve, PathSearch, Restriction, follow_path, path_errors};
use surfcap_motion::timed_walk::TimedGraph;
use surfcap_motion::walk_sequence::WalkModel;
use surfcap_pipeline::constraint_files::KeyPose;
use surfcap_pipeline::frame_variants::FrameVariants;
use surfcap_pipeline::walk_playback::{play_walk, play_walk_with, walk_passes};
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::options::{ConstraintOpts, OutOpts};
use crate::output::{count_of, mean, write_json};

/// A soft constraint and how closely the walk met it (the report's `constraints`).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Constraint {
    pub name: String,
    /// `frames`, or the subject's length unit (`m`, `cm`, ... or `arbitrary`).
    pub unit: String,
    pub asked: f64,
    pub achieved: f64,
    /// How far from the request: |achieved - asked|, or for a path its largest centre error.
    pub error: f64,
    /// `error` as a fraction of the asked length or duration (a path's: its curve length);
    /// `None` for a key's time, which is a position in the output, not a length.
    pub relative_error: Option<f64>,
    pub tolerance: f64,
    pub missed: bool,
}

impl Constraint {
    pub fn new(
        name: impl Into<String>,
        unit: impl Into<String>,
        asked: f64,
        achieved: f64,
        error: f64,
        tolerance: f64,
    ) -> Self {
        Constraint {
            name: name.into(),
            unit: unit.into(),
            asked,
            achieved,
            error,
            relative_error: None,
            tolerance,
            missed: error > tolerance,
        }
    }

    /// One line for people: `distance: 3.02 m (asked 3, error 0.02)`, `missed` added when it was
    /// (what the viewer shows beside a synthesis output).
    pub fn summary(&self) -> String {
        let missed = if self.missed { ", missed" } else { "" };
        format!(
            "{}: {} {} (asked {}, error {}{missed})",
            self.name,
            fmt_number(self.achieved),
            self.unit,
            fmt_number(self.asked),
            fmt_number(self.error)
        )
    }

    /// Sets `relative_error` to the error over `size` (the asked length or duration), when it
    /// is positive.
    pub fn relative_to(mut self, size: f64) -> Self {
        self.relative_error = (size > 0.0).then(|| self.error / size);
        self
    }
}

/// The error of `--strict` when constraints were missed: `main` exits with code 3 for it.
#[derive(Debug)]
pub struct ConstraintsMissed(pub usize);

impl std::fmt::Display for ConstraintsMissed {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let n = self.0;
        write!(f, "{} missed (--strict; the animation and its report were written)", count_of(n, "constraint"))
    }
}

impl std::error::Error for ConstraintsMissed {}

/// Adds the constraints to `report` (as `constraints`).
pub fn add_constraints(report: &mut serde_json::Value, constraints: &[Constraint]) {
    let o = report.as_object_mut().expect("reports are JSON objects");
    o.insert("constraints".into(), json!(constraints));
}

/// Warns about every missed constraint on stderr (also under --quiet: it is part of the
/// result; under --json the report's `constraints` says it), then fails with
/// [`ConstraintsMissed`] under `--strict`.
pub fn check_constraints(ctx: &crate::Ctx, opts: &ConstraintOpts, constraints: &[Constraint]) -> anyhow::Result<()> {
    let missed: Vec<&Constraint> = constraints.iter().filter(|c| c.missed).collect();
    if !ctx.json {
        for c in &missed {
            let relative = c.relative_error.map(|r| format!(", {} of the asked", fmt_percent(r))).unwrap_or_default();
            eprintln!(
                "warning: constraint {} missed: asked {}, achieved {} (error {} {}{relative}, tolerance {}; --tolerance/--frame-tolerance set it)",
                c.name,
                fmt_number(c.asked),
                fmt_number(c.achieved),
                fmt_number(c.error),
                c.unit,
                fmt_number(c.tolerance)
            );
        }
    }
    if opts.strict && !missed.is_empty() {
        return Err(ConstraintsMissed(missed.len()).into());
    }
    Ok(())
}

/// A number with at most 3 decimals, no trailing zeros and never "-0".
fn fmt_number(x: f64) -> String {
    let s = format!("{:.3}", x + 0.0);
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

/// A fraction as a percentage with at most 3 significant decimals (`12.5%`, `1e+09%` stays
/// readable as a number).
fn fmt_percent(r: f64) -> String {
    format!("{}%", fmt_number(100.0 * r))
}

/// The subject's length unit as reports name it.
pub fn length_unit(s: &Subject) -> String {
    crate::output::unit_name(&s.units).to_string()
}

/// Pose distance (thesis eq. 2.13, the graph's metric) between a frame of the subject and a
/// frame of the written output: 0 when the output shows that very pose. The two frames are
/// compared as a two-frame subject, so the motion-plane alignment is the matrix's.
pub fn pose_distance_to_output(
    prep: &Prepared,
    output: &Subject,
    source: u32,
    out_frame: usize,
) -> anyhow::Result<f64> {
    let s = prep.subject();
    let mut positions = s.frame(source as usize).expect("a resolved frame").to_vec();
    let shown = output
        .frame(out_frame)
        .ok_or_else(|| anyhow::anyhow!("output frame {out_frame} is past the output's {} frames", output.n_frames()))?;
    positions.extend_from_slice(shown);
    let pair = s.derived("pair", surfcap_mesh::Sequence::new("pair", s.topology().n_vertices(), positions)?)?;
    let d = surfcap_geometry::distance_matrix::distance_matrix(
        &pair,
        &surfcap_geometry::distance_matrix::DistanceParams::default(),
        &surfcap_mesh::NoProgress,
    );
    Ok(d.get(0, 1))
}

/// A subject with its graph and walk model.
pub struct Prepared {
    pub pipe: Pipeline,
    pub params: GraphParams,
    pub graph: Arc<Graph>,
    pub model: Arc<WalkModel>,
    /// The vertices whose centre is followed (`None`: all).
    pub tracked: Option<Vec<usize>>,
    /// Time to read or build the graph and the walk model.
    pub seconds: f64,
    /// Where every output frame's texture comes from (`--appearance`), if anywhere.
    pub appearance: Option<crate::frame_appearance::SubjectAppearance>,
    /// Learned variants shown when the walk repeats frames (`--vary`), if asked.
    pub vary: VaryOpts,
}

impl Prepared {
    /// Reads (or builds) the graph and walk model of `params` from the pipeline.
    pub fn new(pipe: Pipeline, params: GraphParams, tracked: Option<&[usize]>) -> anyhow::Result<Self> {
        let t0 = Instant::now();
        if let Some(ids) = tracked {
            let nv = pipe.subject().topology().n_vertices();
            if let Some(v) = ids.iter().find(|&&v| v >= nv) {
                anyhow::bail!("--track {v}: the subject has vertices 0 to {}", nv - 1);
            }
        }
        let graph = pipe.graph(&params)?.value;
        let model = pipe.walk_model(&params, tracked)?.value;
        let tracked = tracked.map(<[usize]>::to_vec);
        Ok(Prepared {
            pipe,
            params,
            graph,
            model,
            tracked,
            seconds: t0.elapsed().as_secs_f64(),
            appearance: None,
            vary: VaryOpts::default(),
        })
    }

    /// The same, texturing every output frame from `appearance` (`--appearance`, opened and
    /// checked against the subject by [`crate::frame_appearance::AppearanceOpts::open`]).
    pub fn with_appearance(mut self, appearance: Option<crate::frame_appearance::SubjectAppearance>) -> Self {
        self.appearance = appearance;
        self
    }

    /// The same, playing learned variants where the walk repeats frames (`--vary`, checked by
    /// [`VaryOpts::check`]).
    pub fn with_variation(mut self, vary: VaryOpts) -> Self {
        self.vary = vary;
        self
    }

    pub fn subject(&self) -> &Subject {
        self.pipe.subject()
    }

    pub fn up(&self) -> UpAxis {
        self.subject().up_axis
    }
}

/// What writing a played walk produced.
pub struct Played {
    pub written: Vec<PathBuf>,
    /// Where [`Played::save_report`] writes `report`.
    pub report_path: PathBuf,
    pub report: serde_json::Value,
    /// Tracked centre of every output frame, from the written positions.
    pub centres: Vec<[f64; 3]>,
    /// The animation as written (one sequence), for measures at its frames.
    pub output: Subject,
    pub transitions: usize,
}

impl Played {
    /// Writes the report to its `report_path`.
    pub fn save_report(&self) -> anyhow::Result<()> {
        write_json(&self.report_path, &self.report)
    }
}

/// Plays `walk` (Algorithm 3), writes the animation, and completes `report` with frame counts,
/// the walk and timings (the caller adds what it measures, then saves the report).
pub fn write_walk(
    ctx: &crate::Ctx,
    prep: &Prepared,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
    out: &OutOpts,
    mut report: serde_json::Value,
) -> anyhow::Result<Played> {
    let s = prep.subject();
    let tracked = prep.tracked.as_deref();
    let variants = match (prep.vary.vary, &prep.vary.variation_model) {
        (Some(seed), Some(model)) => Some(variants_for_walk(ctx, prep, seed, model, walk)?),
        _ => None,
    };
    let played = match &variants {
        Some(v) => play_walk_with(&prep.pipe, &prep.params, tracked, walk, start, name, v)?,
        None => play_walk(&prep.pipe, &prep.params, tracked, walk, start, name)?,
    };
    let repeats = played.repeat_summary(s);
    let frames = played.frames();
    let result = s.derived(format!("{}-{name}", s.name), played.sequence)?;
    let (written, appearance) = match &prep.appearance {
        // Thesis Fig. 7.1: each frame's texture blended with the geometry's weights.
        Some(a) => {
            let textured = a.textures(ctx, &played.mix)?;
            (crate::frame_appearance::write_textured(ctx, &result, &textured, &out.output)?, Some(textured.report))
        }
        None => (write_animation(ctx, Animation::Subject(&result), out.format, &out.output)?, None),
    };
    let obj = report.as_object_mut().expect("reports are JSON objects");
    if let Some(a) = appearance {
        obj.insert("appearance".into(), a);
    }
    obj.insert("subject".into(), json!(s.name));
    obj.insert("graph".into(), json!({ "kind": prep.params.kind, "alpha": prep.params.alpha,
        "edges": prep.graph.edges().len(), "transitions": prep.model.n_transitions(), "prepare_seconds": prep.seconds }));
    obj.insert("fps".into(), json!(s.fps));
    obj.insert("frames".into(), json!(frames));
    obj.insert("original_frames".into(), json!(played.original_frames));
    obj.insert("synthetic_frames".into(), json!(played.synthetic_frames));
    obj.insert("transitions".into(), json!(played.transitions));
    obj.insert("blend_seconds".into(), json!(played.blend_seconds));
    obj.insert("repeated_frames".into(), json!(repeats.repeats));
    if let (Some(seed), Some(model)) = (prep.vary.vary, &prep.vary.variation_model) {
        // Issue 19 item 6: what the walk repeated and how much of it variants showed.
        obj.insert(
            "variation".into(),
            json!({ "seed": seed, "model": model, "frames": repeats.frames, "repeats": repeats.repeats,
                "played_as_variants": repeats.played_as_variants, "sequences": repeats.sequences }),
        );
        ctx.note(&format!(
            "{} of {} were repeats; {} played as variants",
            repeats.repeats,
            count_of(frames, "frame"),
            repeats.played_as_variants
        ));
    }
    obj.insert("walk".into(), json!(walk));
    obj.insert("segments".into(), json!(played.segments));
    obj.insert("outputs".into(), json!(written));
    Ok(Played {
        written,
        report_path: report_path(&out.output),
        report,
        centres: played.centres,
        output: result,
        transitions: played.transitions,
    })
}

/// `--vary SEED --variation-model DIR` of `synth path | keyposes | reach` (issue 19 item 6).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct VaryOpts {
    /// Show learned variants of the captured motion (thesis chapter 6) each time the walk plays
    /// frames it has already shown, instead of the same poses again (transitions still blended,
    /// the walk placed as without); SEED seeds the variants' sampling (same seed, same
    /// animation). Needs --variation-model.
    #[arg(long, value_name = "SEED", requires = "variation_model")]
    pub vary: Option<u64>,
    /// The variation model the variants are sampled from (the folder `surfcap vary train
    /// SUBJECT -o DIR` writes, trained on this subject's sequences).
    #[arg(long, value_name = "DIR", requires = "vary")]
    pub variation_model: Option<PathBuf>,
}

impl VaryOpts {
    /// Refuses, before any search, a model folder that is not there or that is the output.
    pub fn check(&self, output: &Path) -> anyhow::Result<()> {
        let Some(model) = &self.variation_model else { return Ok(()) };
        surfcap_mesh::output_path::check_not_input(output, &[model])?;
        anyhow::ensure!(
            model.is_dir(),
            "--variation-model {}: expected the folder of a variation model (`surfcap vary train SUBJECT -o DIR`)",
            model.display()
        );
        Ok(())
    }
}

/// Most variants sampled per sequence for one walk: further repeats cycle through them
/// ([`FrameVariants`] shows variant (p - 1) mod K on pass p), which keeps sampling time
/// bounded (about 5 s a variant on 2 cores for a 117-frame walk of 1,500 vertices).
pub const MAX_VARIANTS_PER_SEQUENCE: usize = 5;

/// The learned variants `--vary SEED --variation-model DIR` shows on a walk's repeated runs:
/// for each sequence of the subject the walk plays more than once, as many variants as its
/// largest pass ([`walk_passes`]), at most [`MAX_VARIANTS_PER_SEQUENCE`], sampled from the
/// model (thesis 6.6) with the seed and put on the sequence's own path
/// (`variant_on_source_path`: only the body's poses vary, so the walk's placement, which the
/// search solved, holds). A sequence the model has not learnt keeps its captured frames, with
/// a note.
pub fn variants_for_walk(
    ctx: &crate::Ctx,
    prep: &Prepared,
    seed: u64,
    model_dir: &Path,
    walk: &[u32],
) -> anyhow::Result<FrameVariants> {
    let s = prep.subject();
    let needed = walk_passes(s, &prep.model, walk)?;
    let mut fv = FrameVariants::new(s);
    if needed.iter().all(|&n| n == 0) {
        return Ok(fv);
    }
    let model = surfcap_variation::VariationModel::load(model_dir)
        .with_context(|| format!("--variation-model {}", model_dir.display()))?;
    if model.topology.n_vertices() != s.topology().n_vertices()
        || model.topology.triangles() != s.topology().triangles()
    {
        anyhow::bail!(
            "--variation-model {}: trained on a mesh of {} vertices and {} triangles, but {:?} has {} and {}: expected a model trained on this subject (surfcap vary train)",
            model_dir.display(),
            model.topology.n_vertices(),
            model.topology.triangles().len(),
            s.name,
            s.topology().n_vertices(),
            s.topology().triangles().len()
        );
    }
    let opts = surfcap_variation::variation_sampling::SamplingOptions::default();
    for (q, seq) in s.sequences().iter().enumerate() {
        if needed[q] == 0 {
            continue;
        }
        let Ok(j) = model.sequence_index(&seq.name) else {
            ctx.note(&format!(
                "{:?} is not in the variation model {}: its {} repeated passes play the captured frames",
                seq.name,
                model_dir.display(),
                needed[q]
            ));
            continue;
        };
        if model.sequences[j].own_frames != seq.n_frames() {
            anyhow::bail!(
                "--variation-model {}: its {:?} has {} frames, the subject's {}: expected a model trained on this subject",
                model_dir.display(),
                seq.name,
                model.sequences[j].own_frames,
                seq.n_frames()
            );
        }
        let count = needed[q].min(MAX_VARIANTS_PER_SEQUENCE);
        ctx.say(&format!("sampling {} of {} (seed {seed})", count_of(count, "variant"), seq.name));
        let (variants, _) =
            surfcap_variation::variation_sampling::sample_variants(&model, &seq.name, count, seed, &opts)
                .with_context(|| format!("sampling variants of {}", seq.name))?;
        let source: Vec<&[f32]> = (0..seq.n_frames()).map(|f| seq.frame(f)).collect();
        let placed = variants
            .iter()
            .map(|v| {
                Ok(surfcap_variation::variation_sampling::variant_on_source_path(&model, j, v, &source)?
                    .into_iter()
                    .flatten()
                    .collect::<Vec<f32>>())
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        fv.add(&seq.name, placed)?;
    }
    Ok(fv)
}

/// A synthesised animation to write: one topology (a subject's frames) or a frame set (every
/// frame its own mesh: the surface motion graph's output on per-frame reconstructions).
pub enum Animation<'a> {
    Subject(&'a Subject),
    FrameSet(&'a FrameSet),
}

/// Writes a synthesised animation to `output` and returns the paths written. An output ending
/// in `.frames` (with no `--format`) is a frame-set folder, lossless and surfcap's own; anything
/// else goes through the exporters in `format` (`--format`, else the extension, else glb: a
/// frame set's glb holds a mesh per frame, see `surfcap_formats::glb_frame_set`).
pub fn write_animation(
    ctx: &crate::Ctx,
    animation: Animation,
    format: Option<ExportFormat>,
    output: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    let bar = crate::progress::Bar::new(ctx);
    if format.is_none() && output.extension().is_some_and(|e| e == "frames") {
        let from_subject;
        let set = match animation {
            Animation::FrameSet(set) => set,
            Animation::Subject(s) => {
                from_subject = FrameSet::from_subject(s);
                &from_subject
            }
        };
        surfcap_mesh::frame_set_cache::write_frame_set(output, set, ctx.force, &bar)?;
        return Ok(vec![output.to_path_buf()]);
    }
    let format = crate::options::output_format(format, output);
    Ok(match animation {
        Animation::Subject(s) => export(s, format, output, ctx.export_options(), &bar)?,
        Animation::FrameSet(set) => export_frame_set(set, format, output, ctx.export_options(), &bar)?,
    })
}

/// Adds what a synthesis report says about the travel of the written animation: the centre of
/// every output frame (`per_frame.centre`, which `surfcap view` draws over the animation), and
/// the net displacement and path length of that centre on the ground.
pub fn add_travel(report: &mut serde_json::Value, centres: &[[f64; 3]], up: UpAxis) {
    let (net, path) = surfcap_motion::clip_travel::horizontal_travel(centres, up);
    report["net_displacement"] = json!(net);
    report["path_length"] = json!(path);
    report["per_frame"] = json!({ "centre": centres });
}

/// `x.glb` -> `x.report.json`, `dir/out` -> `dir/out.report.json`.
pub fn report_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "walk".into());
    output.with_file_name(format!("{stem}.report.json"))
}

fn mean_max(x: &[f64]) -> (f64, f64) {
    (mean(x.iter().copied()), x.iter().copied().fold(0.0, f64::max))
}

/// Summary of a path-following run.
pub struct PathOutcome {
    pub played: Played,
    pub mean_error: f64,
    pub max_error: f64,
    pub frames: usize,
    pub search_seconds: f64,
    pub constraints: Vec<Constraint>,
}

/// Follows `curve` (thesis 3.5.1) on a prepared subject and writes the animation and report;
/// the errors are measured on the written frames.
pub fn run_path(
    ctx: &crate::Ctx,
    prep: &Prepared,
    curve: &Curve,
    restrictions: &[Restriction],
    start: Option<u32>,
    search: &PathSearch,
    out: &OutOpts,
) -> anyhow::Result<PathOutcome> {
    let tolerance = &out.constraints;
    let r = follow_path(&prep.model, &prep.graph, curve, restrictions, start, search).map_err(|e| {
        // The search's own messages give lengths as bare numbers (the motion library does not
        // know units): say which unit they are in.
        use surfcap_motion::Error::{PathStalls, PathStuck};
        let says_lengths = matches!(e, PathStuck { .. } | PathStalls { .. });
        let e = anyhow::Error::new(e);
        if says_lengths {
            e.context(format!(
                "the curve could not be followed (lengths in {})",
                crate::output::unit_name(&prep.subject().units)
            ))
        } else {
            e
        }
    })?;
    let (pred_mean, pred_max) = mean_max(&r.errors);
    let report = json!({
        "constraint": "path",
        "curve_length": curve.length(),
        "planar": curve.axes().len() == 2,
        "search": { "window": search.window, "max_transitions": search.max_transitions, "windows": r.windows,
            "expanded": r.expanded, "seconds": r.seconds },
        "predicted": { "mean_error": pred_mean, "max_error": pred_max },
    });
    let mut played = write_walk(ctx, prep, &r.walk, &r.start, "path", out, report)?;
    let (errors, travelled) = path_errors(curve, &played.centres);
    let (mean, max) = mean_max(&errors);
    let o = played.report.as_object_mut().expect("object");
    o.insert("mean_error".into(), json!(mean));
    o.insert("max_error".into(), json!(max));
    // Path length adds up the centre's sway; the net displacement says whether it went anywhere.
    let (net, _) = surfcap_motion::clip_travel::horizontal_travel(&played.centres, prep.up());
    o.insert("travelled".into(), json!(travelled));
    o.insert("path_length".into(), json!(travelled));
    o.insert("net_displacement".into(), json!(net));
    o.insert("per_frame".into(), json!({ "error": errors, "centre": played.centres }));
    o.insert("curve".into(), json!((0..=200).map(|k| curve.at(curve.length() * k as f64 / 200.0)).collect::<Vec<_>>()));
    if let Some(f) = start {
        // The pose shown first against the asked start frame (--start).
        let d = pose_distance_to_output(prep, &played.output, f, 0)?;
        played.report["pose_distance_start"] = json!(d);
    }
    let unit = length_unit(prep.subject());
    let constraints = vec![
        Constraint::new("path", unit, curve.length(), travelled, max, tolerance.distance(curve.length()))
            .relative_to(curve.length()),
    ];
    add_constraints(&mut played.report, &constraints);
    played.save_report()?;
    Ok(PathOutcome {
        frames: errors.len(),
        played,
        mean_error: mean,
        max_error: max,
        search_seconds: r.seconds,
        constraints,
    })
}

/// Summary of a key-pose timing run.
pub struct KeyposesOutcome {
    pub played: Played,
    /// The output frame at which each key pose appears.
    pub obtained: Vec<i64>,
    pub mean_abs_error: f64,
    pub search_seconds: f64,
    pub constraints: Vec<Constraint>,
}

/// Key-pose timing (thesis 3.5.2): the walk through `keys` meeting their requested times as
/// closely as the graph allows, written with its report.
pub fn run_keyposes(
    ctx: &crate::Ctx,
    prep: &Prepared,
    keys: &[KeyPose],
    out: &OutOpts,
) -> anyhow::Result<KeyposesOutcome> {
    let tolerance = &out.constraints;
    let t0 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let longest = tg.longest_edge();
    let mut walk = vec![keys[0].frame];
    let mut obtained = vec![keys[0].requested];
    for (k, pair) in keys.windows(2).enumerate() {
        let now = *obtained.last().expect("one key at least");
        let w = tg.walk_with_duration(pair[0].frame, pair[1].frame, pair[1].requested - now, longest).map_err(|e| {
            let label = |k: &KeyPose| prep.subject().frame_index().label(k.frame as usize);
            anyhow::anyhow!("keys {} and {} ({} -> {}): {e}", k + 1, k + 2, label(&pair[0]), label(&pair[1]))
        })?;
        walk.extend_from_slice(&w.walk[1..]);
        obtained.push(now + w.frames as i64);
    }
    let search_seconds = t0.elapsed().as_secs_f64();
    let errors: Vec<i64> = keys.iter().zip(&obtained).map(|(k, o)| (o - k.requested).abs()).collect();
    let mean_abs_error = errors.iter().sum::<i64>() as f64 / errors.len() as f64;
    let report = json!({
        "constraint": "keyposes",
        "keys": keys.iter().zip(&obtained).map(|(k, o)| json!({
            "frame": k.spec, "input_time": k.input, "requested_time": k.requested, "obtained_time": o,
            "error": (o - k.requested).abs() })).collect::<Vec<_>>(),
        "mean_abs_error_frames": mean_abs_error,
        "search_seconds": search_seconds,
    });
    let mut played = write_walk(ctx, prep, &walk, &PlaneMotion::identity(prep.up()), "keyposes", out, report)?;
    // The pose shown at each key's obtained time against the pose asked for there.
    for (k, (key, &o)) in keys.iter().zip(&obtained).enumerate() {
        let d = pose_distance_to_output(prep, &played.output, key.frame, (o - obtained[0]) as usize)?;
        played.report["keys"][k]["pose_distance"] = json!(d);
    }
    // The viewer draws this track over the animation, as it does for `synth path` and `reach`.
    played.report["per_frame"] = json!({ "centre": played.centres });
    let constraints: Vec<Constraint> = keys
        .iter()
        .zip(&obtained)
        .map(|(k, &o)| {
            let error = (o - k.requested).abs() as f64;
            Constraint::new(
                format!("key {}", k.spec),
                "frames",
                k.requested as f64,
                o as f64,
                error,
                tolerance.frames(),
            )
        })
        .collect();
    add_constraints(&mut played.report, &constraints);
    played.save_report()?;
    Ok(KeyposesOutcome { played, obtained, mean_abs_error, search_seconds, constraints })
}

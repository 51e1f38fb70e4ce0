//! `surfcap synth path | keyposes | reach`: animations synthesised from a subject's graph under
//! user constraints (thesis 3.5), played by Algorithm 3 and written with a JSON report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
use surfcap_mesh::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::io::npy::NpyArray;
use surfcap_mesh::{FrameLabel, Sequence, Subject};
use surfcap_motion::graph::Graph;
use surfcap_motion::path_following::{Curve, PathSearch, Restriction, follow_path, path_errors};
use surfcap_motion::timed_walk::TimedGraph;
use surfcap_motion::walk_sequence::{WalkModel, tracked_centre, walk_sequence};

use super::distance::{CacheOpts, cached_distance_matrix};
use super::graph::{Kind, SubjectGraphs, check_alpha};
use super::transitions::TableOpts;
use super::{SourceOpts, print_json};

/// Which graph to search, and how it is built.
#[derive(clap::Args, Debug, Clone)]
pub struct GraphOpts {
    /// essential (union of all shortest-path trees) or motion (Kovar's baseline).
    #[arg(long, default_value = "essential")]
    pub kind: String,
    /// Tolerance alpha of the edge weights (thesis eq. 3.2-3.3); smaller gives a denser graph.
    #[arg(long, default_value_t = 0.05)]
    pub alpha: f64,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// Where the animation goes.
#[derive(clap::Args, Debug, Clone)]
pub struct OutOpts {
    /// Output: a .glb file, or a folder for --format obj, pc2 or npy. The JSON report is written
    /// beside it as <output>.report.json.
    #[arg(short, long)]
    pub output: PathBuf,
    /// glb, obj, pc2 or npy (default: from the output's extension, else glb).
    #[arg(long)]
    pub format: Option<String>,
}

#[derive(clap::Args, Debug)]
pub struct PathArgs {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// CSV of curve points: x,y,z in the subject's axes and units, or two columns for a path on
    /// the ground plane (the two horizontal axes, e.g. x,z for +y up). '#' starts a comment.
    #[arg(long)]
    pub curve: PathBuf,
    /// Follow only the projection on the ground plane (implied by a two-column curve).
    #[arg(long)]
    pub planar: bool,
    /// Motion types on parts of the curve: TAG:FROM-TO (arc lengths), e.g. run:5-9; only
    /// sequences with that tag are used there. Comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub tags: Vec<String>,
    /// The first frame (sequence:frame or global); default: the best of all frames.
    #[arg(long)]
    pub start: Option<String>,
    /// Follow the centre of these vertices instead of the centre of mass (comma-separated ids).
    #[arg(long, value_delimiter = ',')]
    pub track: Vec<usize>,
    /// Arc length covered by each branch-and-bound window (subject units).
    #[arg(long, default_value_t = 3.0)]
    pub window: f64,
    /// Transitions allowed within one window.
    #[arg(long, default_value_t = 2)]
    pub max_transitions: usize,
    /// Transitions tried at each frame (its cheapest ones, round robin over destination
    /// sequences); the search's speed knob.
    #[arg(long, default_value_t = 8)]
    pub branching: usize,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
}

#[derive(clap::Args, Debug)]
pub struct KeyposesArgs {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// CSV of key poses: frame,time: the frame (sequence:frame or global) and the output frame
    /// number at which it must appear, in increasing time. '#' starts a comment.
    #[arg(long)]
    pub keys: PathBuf,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
}

#[derive(clap::Args, Debug)]
pub struct ReachArgs {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// Start frame (sequence:frame or global).
    #[arg(long)]
    pub from: String,
    /// End frame.
    #[arg(long)]
    pub to: String,
    /// Ground-plane distance the centre of mass must travel (subject units).
    #[arg(long)]
    pub distance: f64,
    /// Duration in seconds.
    #[arg(long)]
    pub time: f64,
    /// Distance error worth one unit of realism cost (Huang et al.: 0.3 m).
    #[arg(long, default_value_t = 0.3)]
    pub distance_scale: f64,
    /// Timing error, in frames, worth one unit of realism cost (Huang et al.: 10 frames).
    #[arg(long, default_value_t = 10.0)]
    pub time_scale: f64,
    #[command(flatten)]
    pub graph: GraphOpts,
    #[command(flatten)]
    pub out: OutOpts,
}

/// A subject with its graph and walk model.
pub struct Prepared {
    pub s: Subject,
    pub graph: Graph,
    pub model: WalkModel,
    pub kind: Kind,
    pub alpha: f64,
    /// The vertices whose centre is followed (`None`: all).
    pub tracked: Option<Vec<usize>>,
    /// Where the distance matrix is cached (playing a walk recomputes its transitions' warps).
    pub cache: CacheOpts,
    pub seconds: f64,
}

/// Opens the subject and builds (or reads from the cache) what the searches need.
pub fn prepare(ctx: &crate::Ctx, subject: &Path, o: &GraphOpts, tracked: Option<&[usize]>) -> anyhow::Result<Prepared> {
    let kind = Kind::parse(&o.kind)?;
    check_alpha(o.alpha)?;
    let s = super::open(ctx, subject, &o.source)?;
    prepare_subject(ctx, s, o, kind, tracked)
}

pub fn prepare_subject(
    ctx: &crate::Ctx,
    s: Subject,
    o: &GraphOpts,
    kind: Kind,
    tracked: Option<&[usize]>,
) -> anyhow::Result<Prepared> {
    let t0 = Instant::now();
    if let Some(ids) = tracked {
        let nv = s.topology().n_vertices();
        if let Some(v) = ids.iter().find(|&&v| v >= nv) {
            anyhow::bail!("--track {v}: the subject has vertices 0..{}", nv - 1);
        }
    }
    let p = o.table.params(s.fps)?;
    let sg = SubjectGraphs::new(ctx, &s, p, &o.cache);
    let (graph, _) = sg.graph(kind, o.alpha)?;
    let model = cached_walk_model(ctx, &sg, &graph, &o.cache, tracked)?;
    drop(sg);
    let tracked = tracked.map(<[usize]>::to_vec);
    let cache = o.cache.clone();
    Ok(Prepared { s, graph, model, kind, alpha: o.alpha, tracked, cache, seconds: t0.elapsed().as_secs_f64() })
}

/// The walk model of `graph` (every transition's rigid track: the centres of its Blend frames
/// and its end placement), from the derived-matrix cache when possible: a `walkmodel-*.npy` of
/// f32 rows of three numbers ([`WalkModel::tracks_to_rows`] documents the layout), keyed by the
/// subject's geometry, the graph's edges, the DTW slope and the tracked vertices. On a dense
/// graph it costs as much as the graph itself (one DTW per transition). A freshly computed model
/// is read back from its f32 rows too, so a cached and an uncached run search the same numbers
/// and find the same walk (f32 keeps frame numbers exact below 2^24).
fn cached_walk_model(
    ctx: &crate::Ctx,
    sg: &SubjectGraphs,
    graph: &Graph,
    cache: &CacheOpts,
    tracked: Option<&[usize]>,
) -> anyhow::Result<WalkModel> {
    let s = sg.subject();
    anyhow::ensure!(s.n_frames() < 1 << 24, "{} frames: the walk model cache holds fewer than 2^24", s.n_frames());
    let mut h = blake3::Hasher::new();
    for e in graph.edges() {
        h.update(&e.from.to_le_bytes());
        h.update(&e.to.to_le_bytes());
    }
    let tracked_hash =
        blake3::hash(&tracked.unwrap_or(&[]).iter().flat_map(|v| (*v as u64).to_le_bytes()).collect::<Vec<u8>>());
    let slope = sg.params().slope;
    let key = format!(
        "graph={} slope={slope:?} tracked={}:{} v1",
        h.finalize().to_hex(),
        tracked.is_some(),
        tracked_hash.to_hex()
    );
    let store = cache.cache();
    let path = store.path("walkmodel", &surfcap_mesh::derived_cache::subject_hash(s), &key);
    if cache.no_cache {
        let _ = std::fs::remove_file(&path);
    }
    let compute = || -> anyhow::Result<NpyArray<f32>> {
        let table = sg.table()?;
        let (d, _, _) = cached_distance_matrix(ctx, s, &DistanceParams::default(), cache)?;
        let rows: Vec<f32> = WalkModel::new(s, graph, table, &d.data, slope, tracked)
            .tracks_to_rows()
            .iter()
            .map(|&x| x as f32)
            .collect();
        Ok(NpyArray { shape: vec![rows.len() / 3, 3], data: rows })
    };
    let parse = |a: &NpyArray<f32>| -> Result<WalkModel, String> {
        if a.shape.len() != 2 || a.shape[1] != 3 {
            return Err(format!("shape {:?}, expected [R, 3]", a.shape));
        }
        WalkModel::from_rows(s, &a.data.iter().map(|&x| x as f64).collect::<Vec<_>>(), tracked, slope)
            .map_err(|e| e.to_string())
    };
    let (a, cached) = store.get_or_compute(&path, compute)?;
    match parse(&a) {
        Ok(model) => Ok(model),
        // A readable entry that does not fit this subject (damaged, or an older layout) is
        // recomputed and replaced, as unreadable ones are.
        Err(_) if cached => {
            let _ = std::fs::remove_file(&path);
            let (a, _) = store.get_or_compute(&path, compute)?;
            parse(&a).map_err(|e| anyhow::anyhow!("the walk model just computed: {e}"))
        }
        Err(e) => anyhow::bail!("the walk model just computed: {e}"),
    }
}

fn format_of(out: &OutOpts) -> anyhow::Result<ExportFormat> {
    match &out.format {
        Some(f) => ExportFormat::parse(f).with_context(|| format!("--format {f:?}: expected glb, obj, pc2 or npy")),
        None => Ok(match out.output.extension().and_then(|e| e.to_str()) {
            Some(e) if ExportFormat::parse(e).is_some() => ExportFormat::parse(e).expect("checked"),
            _ => ExportFormat::Glb,
        }),
    }
}

/// The walk as runs of original frames and transitions, by sequence name.
fn walk_segments(s: &Subject, model: &WalkModel, walk: &[u32]) -> Vec<serde_json::Value> {
    let name = |g: u32| {
        let (q, f) = s.frame_index().locate(g as usize).expect("walk nodes are frames");
        (s.sequences()[q].name.clone(), f)
    };
    let mut out = Vec::new();
    let mut run_start = 0;
    for k in 1..=walk.len() {
        let ends_run = k == walk.len()
            || matches!(model.step(walk[k - 1], walk[k]), Some(surfcap_motion::walk_sequence::Step::Transition(_)));
        if ends_run {
            let (q, a) = name(walk[run_start]);
            let (_, b) = name(walk[k - 1]);
            out.push(json!({ "sequence": q, "first": a, "last": b }));
            if k < walk.len() {
                let (qa, fa) = name(walk[k - 1]);
                let (qb, fb) = name(walk[k]);
                out.push(json!({ "transition": format!("{qa}:{fa} -> {qb}:{fb}") }));
            }
            run_start = k;
        }
    }
    out
}

/// What playing a walk produced.
pub struct Played {
    pub written: Vec<PathBuf>,
    /// Where [`save_report`] writes `report`.
    pub report_path: PathBuf,
    pub report: serde_json::Value,
    /// Tracked centre of every output frame, from the written positions.
    pub centres: Vec<[f64; 3]>,
}

/// Plays `walk` (Algorithm 3), writes the animation, and completes `report` with frame counts,
/// the walk and timings (the caller adds what it measures, then calls [`save_report`]).
pub fn write_walk(
    ctx: &crate::Ctx,
    prep: &Prepared,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
    out: &OutOpts,
    mut report: serde_json::Value,
) -> anyhow::Result<Played> {
    let tracked = prep.tracked.as_deref();
    let format = format_of(out)?;
    let s = &prep.s;
    let t0 = Instant::now();
    let (d, _, _) = cached_distance_matrix(ctx, s, &DistanceParams::default(), &prep.cache)?;
    let ws = walk_sequence(s, &prep.model, &d.data, walk, start)?;
    let blend_seconds = t0.elapsed().as_secs_f64();
    let nv = s.topology().n_vertices();
    let centres: Vec<[f64; 3]> = ws.positions.chunks_exact(3 * nv).map(|f| tracked_centre(f, tracked)).collect();
    let original = ws.labels.iter().filter(|l| **l == FrameLabel::Original).count();
    let frames = ws.n_frames();
    let seq = Sequence::new(name, nv, ws.positions)?.with_labels(ws.labels)?.with_tags(vec!["synthesised".into()]);
    let result = s.derived(format!("{}-{name}", s.name), seq)?;
    let bar = crate::progress::Bar::new(ctx);
    let written = export(&result, format, &out.output, ExportOptions::default(), &bar)?;
    let obj = report.as_object_mut().expect("reports are JSON objects");
    obj.insert("subject".into(), json!(s.name));
    obj.insert("graph".into(), json!({ "kind": format!("{:?}", prep.kind).to_lowercase(), "alpha": prep.alpha,
        "edges": prep.graph.edges().len(), "transitions": prep.model.n_transitions(), "prepare_seconds": prep.seconds }));
    obj.insert("fps".into(), json!(s.fps));
    obj.insert("frames".into(), json!(frames));
    obj.insert("original_frames".into(), json!(original));
    obj.insert("synthetic_frames".into(), json!(frames - original));
    obj.insert("transitions".into(), json!(ws.n_transitions));
    obj.insert("blend_seconds".into(), json!(blend_seconds));
    obj.insert("walk".into(), json!(walk));
    obj.insert("segments".into(), json!(walk_segments(s, &prep.model, walk)));
    obj.insert("outputs".into(), json!(written));
    Ok(Played { written, report_path: report_path(&out.output), report, centres })
}

/// Writes a played walk's report to its `report_path`.
pub fn save_report(played: &Played) -> anyhow::Result<()> {
    surfcap_mesh::atomic::write_file(&played.report_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &played.report).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(())
}

/// `x.glb` -> `x.report.json`, `dir/out` -> `dir/out.report.json`.
pub fn report_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "walk".into());
    output.with_file_name(format!("{stem}.report.json"))
}

/// Rows of numbers from a CSV file: blank lines and '#' comments skipped, a first line that is
/// not numeric taken as a header. Each row is returned with its line number.
fn csv_rows(path: &Path) -> anyhow::Result<Vec<(usize, Vec<String>)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut rows = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let cells: Vec<String> = line.split([',', ';', '\t']).map(|c| c.trim().to_string()).collect();
        rows.push((k + 1, cells));
    }
    Ok(rows)
}

/// Reads a curve: 2 or 3 numeric columns.
pub fn read_curve(path: &Path, up: surfcap_mesh::UpAxis, planar: bool) -> anyhow::Result<Curve> {
    let mut rows = csv_rows(path)?;
    if rows.first().is_some_and(|(_, c)| c.iter().any(|x| x.parse::<f64>().is_err())) {
        rows.remove(0); // header
    }
    let cols = rows.first().map(|r| r.1.len()).with_context(|| format!("{}: no curve points", path.display()))?;
    anyhow::ensure!(
        cols == 2 || cols == 3,
        "{}:{}: {cols} columns; expected x,y,z or two ground-plane coordinates",
        path.display(),
        rows[0].0
    );
    let (iu, iv, iw) = plane_axes(up);
    let mut points = Vec::with_capacity(rows.len());
    for (line, cells) in &rows {
        anyhow::ensure!(
            cells.len() == cols,
            "{}:{line}: {} columns, expected {cols} like the first row",
            path.display(),
            cells.len()
        );
        let mut v = [0.0; 3];
        for (k, c) in cells.iter().enumerate() {
            v[k] = c
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .with_context(|| format!("{}:{line}: {c:?} is not a finite number", path.display()))?;
        }
        points.push(if cols == 2 {
            let mut p = [0.0; 3];
            p[iu] = v[0];
            p[iv] = v[1];
            p[iw] = 0.0;
            p
        } else {
            v
        });
    }
    let axes = if planar || cols == 2 { vec![iu, iv] } else { vec![0, 1, 2] };
    Curve::new(points, axes).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

fn parse_restrictions(s: &Subject, tags: &[String]) -> anyhow::Result<Vec<Restriction>> {
    tags.iter()
        .map(|t| {
            let bad = || format!("--tags {t:?}: expected TAG:FROM-TO with arc lengths FROM < TO, e.g. run:5-9");
            let (tag, range) = t.rsplit_once(':').with_context(bad)?;
            let (a, b) = range.split_once('-').with_context(bad)?;
            let (from, to): (f64, f64) =
                (a.trim().parse().ok().with_context(bad)?, b.trim().parse().ok().with_context(bad)?);
            anyhow::ensure!(from < to && from.is_finite() && to.is_finite(), bad());
            let allowed: Vec<bool> = s.sequences().iter().map(|q| q.tags.iter().any(|x| x == tag)).collect();
            if !allowed.iter().any(|&x| x) {
                let mut known: Vec<&str> =
                    s.sequences().iter().flat_map(|q| q.tags.iter().map(|x| x.as_str())).collect();
                known.sort();
                known.dedup();
                anyhow::bail!(
                    "--tags {t:?}: no sequence is tagged {tag:?}; the subject's tags are {}",
                    known.join(", ")
                );
            }
            Ok(Restriction { from, to, allowed })
        })
        .collect()
}

fn mean_max(x: &[f64]) -> (f64, f64) {
    (x.iter().sum::<f64>() / x.len().max(1) as f64, x.iter().copied().fold(0.0, f64::max))
}

/// Summary of a path-following run, shared with the demo.
pub struct PathOutcome {
    pub played: Played,
    pub mean_error: f64,
    pub max_error: f64,
    pub frames: usize,
    pub transitions: usize,
    pub search_seconds: f64,
}

/// Follows `curve` on a prepared subject and writes the animation and report.
pub fn run_path(
    ctx: &crate::Ctx,
    prep: &Prepared,
    curve: &Curve,
    restrictions: &[Restriction],
    start: Option<u32>,
    search: &PathSearch,
    out: &OutOpts,
) -> anyhow::Result<PathOutcome> {
    let r = follow_path(&prep.model, &prep.graph, curve, restrictions, start, search).map_err(anyhow::Error::msg)?;
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
    // The errors measured on the written frames.
    let o = played.report.as_object_mut().expect("object");
    o.insert("mean_error".into(), json!(mean));
    o.insert("max_error".into(), json!(max));
    o.insert("travelled".into(), json!(travelled));
    o.insert("per_frame".into(), json!({ "error": errors, "centre": played.centres }));
    o.insert("curve".into(), json!((0..=200).map(|k| curve.at(curve.length() * k as f64 / 200.0)).collect::<Vec<_>>()));
    let transitions = o["transitions"].as_u64().unwrap_or(0) as usize;
    save_report(&played)?;
    Ok(PathOutcome {
        frames: errors.len(),
        played,
        mean_error: mean,
        max_error: max,
        transitions,
        search_seconds: r.seconds,
    })
}

fn print_written(ctx: &crate::Ctx, played: &Played) {
    if !ctx.json && !ctx.quiet {
        for w in played.written.iter().chain([&played.report_path]) {
            println!("wrote {}", w.display());
        }
    }
}

pub fn path(ctx: &crate::Ctx, a: PathArgs) -> anyhow::Result<()> {
    let tracked = (!a.track.is_empty()).then_some(a.track.as_slice());
    let prep = prepare(ctx, &a.subject, &a.graph, tracked)?;
    let curve = read_curve(&a.curve, prep.s.up_axis, a.planar)?;
    let restrictions = parse_restrictions(&prep.s, &a.tags)?;
    let start = a.start.as_deref().map(|x| prep.s.resolve_frame(x)).transpose()?.map(|g| g as u32);
    let search = PathSearch {
        window: a.window,
        max_transitions: a.max_transitions,
        branching: a.branching,
        ..PathSearch::for_fps(prep.s.fps)
    };
    let o = run_path(ctx, &prep, &curve, &restrictions, start, &search, &a.out)?;
    if ctx.json {
        print_json(&o.played.report);
    } else if !ctx.quiet {
        println!(
            "followed a {:.2}-long curve: {} frames, {} transitions; centre error mean {:.3}, max {:.3}; search {:.2} s",
            curve.length(),
            o.frames,
            o.transitions,
            o.mean_error,
            o.max_error,
            o.search_seconds
        );
    }
    print_written(ctx, &o.played);
    Ok(())
}

/// One key pose: the frame, its original time and the requested one.
struct Key {
    spec: String,
    frame: u32,
    input: usize,
    requested: i64,
}

fn read_keys(path: &Path, s: &Subject) -> anyhow::Result<Vec<Key>> {
    let mut rows = csv_rows(path)?;
    if rows.first().is_some_and(|(_, c)| c.len() == 2 && c[1].parse::<i64>().is_err()) {
        rows.remove(0);
    }
    let mut keys: Vec<Key> = Vec::new();
    for (line, cells) in rows {
        anyhow::ensure!(
            cells.len() == 2,
            "{}:{line}: expected frame,time (2 columns), found {}",
            path.display(),
            cells.len()
        );
        let frame = s.resolve_frame(&cells[0]).with_context(|| format!("{}:{line}", path.display()))?;
        let requested: i64 = cells[1].parse().ok().filter(|t| *t >= 0).with_context(|| {
            format!("{}:{line}: time {:?}: expected a whole number of frames >= 0", path.display(), cells[1])
        })?;
        if let Some(prev) = keys.last() {
            anyhow::ensure!(
                requested > prev.requested,
                "{}:{line}: time {requested} is not after the previous key's {}",
                path.display(),
                prev.requested
            );
        }
        let input = s.frame_index().locate(frame).expect("resolved").1;
        keys.push(Key { spec: cells[0].clone(), frame: frame as u32, input, requested });
    }
    anyhow::ensure!(keys.len() >= 2, "{}: {} key pose(s); expected at least two", path.display(), keys.len());
    Ok(keys)
}

/// Key-pose timing (thesis 3.5.2): prints the table of Fig. 3.18 and writes the animation.
pub fn run_keyposes(ctx: &crate::Ctx, prep: &Prepared, keys_path: &Path, out: &OutOpts) -> anyhow::Result<Played> {
    let keys = read_keys(keys_path, &prep.s)?;
    let t0 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let longest = tg.longest_edge();
    let mut walk = vec![keys[0].frame];
    let mut obtained = vec![keys[0].requested];
    for (k, pair) in keys.windows(2).enumerate() {
        let now = *obtained.last().expect("one key at least");
        let w = tg
            .walk_with_duration(pair[0].frame, pair[1].frame, pair[1].requested - now, longest)
            .map_err(|e| anyhow::anyhow!("keys {} and {} ({} -> {}): {e}", k + 1, k + 2, pair[0].spec, pair[1].spec))?;
        walk.extend_from_slice(&w.walk[1..]);
        obtained.push(now + w.frames as i64);
    }
    let search_seconds = t0.elapsed().as_secs_f64();
    let requested: Vec<i64> = keys.iter().map(|k| k.requested).collect();
    let errors: Vec<i64> = requested.iter().zip(&obtained).map(|(r, o)| (o - r).abs()).collect();
    let mean_abs_error = errors.iter().sum::<i64>() as f64 / errors.len() as f64;
    let report = json!({
        "constraint": "keyposes",
        "keys": keys.iter().zip(&obtained).map(|(k, o)| json!({
            "frame": k.spec, "input_time": k.input, "requested_time": k.requested, "obtained_time": o,
            "error": (o - k.requested).abs() })).collect::<Vec<_>>(),
        "mean_abs_error_frames": mean_abs_error,
        "search_seconds": search_seconds,
    });
    let played = write_walk(ctx, prep, &walk, &PlaneMotion::identity(prep.s.up_axis), "keyposes", out, report)?;
    save_report(&played)?;
    if !ctx.json && !ctx.quiet {
        // Thesis Fig. 3.18: input, requested and obtained times.
        let row = |label: &str, v: Vec<String>| {
            println!("{label:<10}{}", v.iter().map(|x| format!("{x:>7}")).collect::<String>())
        };
        row("Input", keys.iter().map(|k| k.input.to_string()).collect());
        row("Requested", requested.iter().map(|x| x.to_string()).collect());
        row("Obtained", obtained.iter().map(|x| x.to_string()).collect());
        println!("mean absolute timing error {mean_abs_error:.2} frames; search {search_seconds:.3} s");
    }
    Ok(played)
}

pub fn keyposes(ctx: &crate::Ctx, a: KeyposesArgs) -> anyhow::Result<()> {
    let prep = prepare(ctx, &a.subject, &a.graph, None)?;
    let played = run_keyposes(ctx, &prep, &a.keys, &a.out)?;
    if ctx.json {
        print_json(&played.report);
    }
    print_written(ctx, &played);
    Ok(())
}

pub fn reach(ctx: &crate::Ctx, a: ReachArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.distance.is_finite() && a.distance >= 0.0, "--distance {}: expected a distance >= 0", a.distance);
    anyhow::ensure!(a.time.is_finite() && a.time > 0.0, "--time {}: expected a positive number of seconds", a.time);
    anyhow::ensure!(a.distance_scale > 0.0 && a.time_scale > 0.0, "--distance-scale and --time-scale must be positive");
    let prep = prepare(ctx, &a.subject, &a.graph, None)?;
    let (from, to) = (prep.s.resolve_frame(&a.from)? as u32, prep.s.resolve_frame(&a.to)? as u32);
    let frames = (a.time * prep.s.fps).round().max(1.0) as usize;
    let t0 = Instant::now();
    let tg = TimedGraph::new(&prep.graph, &prep.model);
    let (w, cost) = tg
        .walk_with_distance_and_time(from, to, a.distance, frames, (a.distance_scale, a.time_scale), tg.longest_edge())
        .map_err(anyhow::Error::msg)?;
    let search_seconds = t0.elapsed().as_secs_f64();
    let report = json!({
        "constraint": "reach", "from": a.from, "to": a.to,
        "target_distance": a.distance, "distance": w.distance, "distance_error": (w.distance - a.distance).abs(),
        "target_frames": frames, "obtained_frames": w.frames, "time_error_frames": (w.frames as i64 - frames as i64).abs(),
        "realism_cost": w.cost, "total_cost": cost, "search_seconds": search_seconds,
    });
    let played = write_walk(ctx, &prep, &w.walk, &PlaneMotion::identity(prep.s.up_axis), "reach", &a.out, report)?;
    save_report(&played)?;
    if ctx.json {
        print_json(&played.report);
    } else if !ctx.quiet {
        println!(
            "{} -> {}: {:.2} travelled (asked {:.2}) in {} frames (asked {frames}); realism cost {:.3}; search {search_seconds:.3} s",
            a.from, a.to, w.distance, a.distance, w.frames, w.cost
        );
    }
    print_written(ctx, &played);
    Ok(())
}

//! `surfcap smg query <input> --connect A:B ... --from seq:frame --to seq:frame --distance D
//! --time SECONDS -o out`: Huang et al. 2009's surface motion graph, surfcap's second synthesis
//! engine (issue 17): the input may be a subject or a frame set (every frame its own topology).
//! The library does the work (`surfcap_smg`: the similarity, cached; the graph from the user's
//! higher level and the two key frames; the ILP path); this command opens the input, writes the
//! animation and its report as the other synthesis commands do (`synthesis::write_animation`:
//! glb by default, a subject's in any `--format`, a frame set's as glb (a mesh per frame), abc,
//! obj or a `.frames` folder; the report with the centre track, the target distance and the
//! transition frames that `surfcap view` draws), and reports a missed distance or time as
//! missed (`--strict`: exit 3).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_formats::import::{ImportedData, open_any};
use surfcap_mesh::frame_set::{FrameSet, FrameSetSequence};
use surfcap_mesh::{Sequence, Subject, Topology, Units};
use surfcap_smg::motion_frames::MotionFrames;
use surfcap_smg::path_optimisation::{
    PathQuery, PathSolution, PlayedFrame, Tolerance, optimise_path, path_segments, play_path,
};
use surfcap_smg::shape_similarity::HistogramParams;
use surfcap_smg::surface_motion_graph::{GraphInput, SurfaceMotionGraph, build_graph};

use crate::options::{CacheOpts, ConstraintOpts, SourceOpts};
use crate::synthesis::{Animation, Constraint, add_travel, check_constraints, report_path, write_animation};

#[derive(clap::Subcommand, Debug)]
pub enum Cmd {
    /// One synthesis: the path between two key frames that covers a distance in a time at the
    /// least transition cost (eq. 6-20), written with its report.
    Query(QueryArgs),
    /// The precomputation alone: the shape similarity of every frame pair (eq. 2, cached as
    /// `smg-similarity-*.npy`, which later queries on the same frames reuse) and the two-level
    /// graph (3.3), written as JSON for inspection.
    Build(BuildArgs),
}

/// What the graph is built from: the input, the user's higher level, the transitions.
#[derive(clap::Args, Debug)]
pub struct GraphArgs {
    /// A subject or a frame set (`.frames`), or any source `surfcap import` reads.
    pub input: PathBuf,
    /// The higher-level graph: sequence pairs FROM:TO that may follow each other (TO may be
    /// FROM: a loop in a cyclic motion), comma-separated or repeated.
    #[arg(long = "connect", value_delimiter = ',', required = true)]
    pub connect: Vec<String>,
    /// Transition windows searched, in frames: MIN-MAX (eq. 5's adaptive window).
    #[arg(long, default_value = "3-30")]
    pub windows: String,
    /// Transitions per connection: 1 is the paper's (eq. 5's single best); more adds the next
    /// best windows whose switches lie at least --separation frames apart (an extension: more
    /// entry points, so loops are reachable from more key frames).
    #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 1, 20))]
    pub transitions: usize,
    /// Least distance between the switches of one connection's transitions, frames.
    #[arg(long, default_value_t = 15, value_parser = crate::options::count)]
    pub separation: usize,
    /// Voxels along the frames' largest extent (the shape histograms' lattice).
    #[arg(long, default_value_t = 64, value_parser = |s: &str| crate::options::whole_in(s, 8, 512))]
    pub resolution: usize,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    #[command(flatten)]
    pub graph: GraphArgs,
    /// Key frames (`sequence:frame`, comma-separated or repeated) that become nodes of the
    /// lower level (a query adds its own).
    #[arg(long = "keys", value_delimiter = ',')]
    pub keys: Vec<String>,
    /// The graph as JSON (nodes, edges, transitions), for inspection.
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct QueryArgs {
    #[command(flatten)]
    pub graph: GraphArgs,
    /// Start and end key frames, `sequence:frame`.
    #[arg(long)]
    pub from: String,
    #[arg(long)]
    pub to: String,
    /// Ground distance to cover, in the subject's units.
    #[arg(long, value_parser = crate::options::non_negative)]
    pub distance: f64,
    /// Duration, in seconds.
    #[arg(long, value_parser = crate::options::positive)]
    pub time: f64,
    /// Weight of a distance error per subject unit (the paper: 1/0.3 per metre).
    #[arg(long, default_value_t = 1.0 / 0.3, value_parser = crate::options::positive)]
    pub distance_weight: f64,
    /// Weight of a time error per frame (the paper: 1/10).
    #[arg(long, default_value_t = 0.1, value_parser = crate::options::positive)]
    pub time_weight: f64,
    /// Take eq. 6's optimum as the paper does. By default the least-cost path that meets the
    /// targets within 1% of the distance and 1 frame is taken where one exists (beyond the
    /// paper: eq. 6 may trade a missed target for a cheaper transition), and the report says
    /// why when none does.
    #[arg(long)]
    pub paper_cost: bool,
    /// Output: a .glb (the default format), .abc or .usda file, a folder (see --format), or a
    /// `.frames` folder (surfcap's own frame set, lossless). The report goes beside it as
    /// <output>.report.json, which `surfcap view <output>` shows over the animation.
    #[arg(short, long)]
    pub output: PathBuf,
    /// glb, obj, ply, pc2, npy, usda or abc (default: from the extension, else glb); a frame
    /// set's output (every frame its own mesh) is glb, abc or obj.
    #[arg(long)]
    pub format: Option<surfcap_formats::export::ExportFormat>,
    #[command(flatten)]
    pub constraints: ConstraintOpts,
}

/// Writes the played path: a subject's frames as one sequence of the subject, a frame set's as a
/// frame set (every frame its own mesh), in the format the output asks for
/// (`synthesis::write_animation`: glb by default, `.frames` a frame-set folder).
fn write_output(
    ctx: &crate::Ctx,
    a: &QueryArgs,
    frames: &MotionFrames,
    subject: Option<&Subject>,
    played: Vec<PlayedFrame>,
    name: String,
    units: &Units,
) -> anyhow::Result<Vec<PathBuf>> {
    match subject {
        Some(s) => {
            let positions: Vec<f32> = played.iter().flat_map(|(p, _)| p.iter().copied()).collect();
            let sequence = Sequence::new("smg", s.topology().n_vertices(), positions)?;
            let result = s.derived(name, sequence)?;
            write_animation(ctx, Animation::Subject(&result), a.format, &a.output)
        }
        None => {
            let per_frame = played
                .into_iter()
                .map(|(p, t)| Ok((Topology::new(p.len() / 3, t.to_vec(), None)?, p)))
                .collect::<anyhow::Result<Vec<_>>>()?;
            let sequence = FrameSetSequence::from_frames("smg", per_frame)?;
            let set = FrameSet::new(name, vec![sequence], frames.fps, frames.up, units.clone())?;
            write_animation(ctx, Animation::FrameSet(&set), a.format, &a.output)
        }
    }
}

/// The area-weighted centroid of every output frame: its source frame's, moved by the ground
/// offset the path adds there (as `play_path` moves the vertices).
fn played_centres(frames: &MotionFrames, path: &PathSolution) -> Vec<[f64; 3]> {
    let centroids = frames.centroids();
    let (axis, _) = frames.up.axis_and_sign();
    let (x, y) = ((axis + 1) % 3, (axis + 2) % 3);
    path.frames
        .iter()
        .zip(&path.offsets)
        .map(|(&f, o)| {
            let mut c = centroids[f];
            c[x] += o[0];
            c[y] += o[1];
            c
        })
        .collect()
}

fn windows(text: &str) -> anyhow::Result<std::ops::RangeInclusive<usize>> {
    let parse = |s: &str| s.trim().parse::<usize>().ok().filter(|&n| n >= 1);
    let (a, b) = text.split_once('-').unwrap_or((text, text));
    match (parse(a), parse(b)) {
        (Some(a), Some(b)) if a <= b => Ok(a..=b),
        _ => anyhow::bail!("--windows {text:?}: expected MIN-MAX frames, 1 <= MIN <= MAX"),
    }
}

pub fn run(ctx: &crate::Ctx, cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Query(a) => query(ctx, a),
        Cmd::Build(a) => build(ctx, a),
    }
}

/// An opened input with its similarity and graph.
struct Opened {
    data: ImportedData,
    frames: MotionFrames,
    ground: Vec<[f64; 2]>,
    similarity_seconds: f64,
    similarity_cached: bool,
    graph: SurfaceMotionGraph,
    /// The key frames asked for (global frames), in order.
    keys: Vec<usize>,
}

/// Opens `a.input`, computes (or reads back) its similarity and builds the graph with the
/// key frames `keys` (`(option, sequence:frame)`, named in errors).
fn open_graph(ctx: &crate::Ctx, a: &GraphArgs, keys: &[(&str, &str)]) -> anyhow::Result<Opened> {
    let lengths = windows(&a.windows)?;
    let bar = crate::progress::Bar::new(ctx);
    let data = open_any(&a.input, &a.source.to_import(None)?, &bar)?;
    let frames = match &data {
        ImportedData::Subject(i) => MotionFrames::from_subject(&i.subject),
        ImportedData::FrameSet(f) => MotionFrames::from_frame_set(&f.frame_set),
    };
    let t0 = Instant::now();
    let store = surfcap_mesh::derived_cache::DerivedCache::new(a.cache.dir());
    let params = HistogramParams { resolution: a.resolution, ..Default::default() };
    let (similarity, similarity_cached) = frames.shape_similarity(params, Some((&store, a.cache.no_cache)), &bar)?;
    let similarity_seconds = t0.elapsed().as_secs_f64();
    let seq = |name: &str| {
        frames.names.iter().position(|n| n == name).ok_or_else(|| {
            anyhow::anyhow!("--connect: no sequence {name:?}: expected one of {}", frames.names.join(", "))
        })
    };
    let mut connections = Vec::new();
    for c in &a.connect {
        let (x, y) = c.split_once(':').with_context(|| format!("--connect {c:?}: expected FROM:TO"))?;
        connections.push((seq(x)?, seq(y)?));
    }
    let keys = keys
        .iter()
        .map(|(option, spec)| frames.resolve(spec).with_context(|| format!("{option} {spec:?}")))
        .collect::<anyhow::Result<Vec<usize>>>()?;
    let ground = frames.ground_centroids();
    let graph = build_graph(&GraphInput {
        sequences: &frames.sequences,
        similarity: &similarity,
        ground: &ground,
        connections: &connections,
        key_frames: &keys,
        lengths,
        per_connection: a.transitions,
        separation: a.separation,
    })?;
    for (x, y) in &graph.missing {
        ctx.note(&format!(
            "no transition {} -> {}: a sequence is shorter than the smallest window",
            frames.names[*x], frames.names[*y]
        ));
    }
    Ok(Opened { data, frames, ground, similarity_seconds, similarity_cached, graph, keys })
}

/// The graph's transitions for reports: last frame played, first frame switched to
/// (`sequence:frame`), window and cost.
fn transitions_json(f: &MotionFrames, g: &SurfaceMotionGraph) -> Vec<serde_json::Value> {
    g.transitions
        .iter()
        .map(|(x, y, t)| {
            json!({
                "from": f.name_of(f.sequences[*x].start + t.last_x),
                "to": f.name_of(f.sequences[*y].start + t.first_y),
                "window": t.length, "cost": t.cost})
        })
        .collect()
}

fn build(ctx: &crate::Ctx, a: BuildArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.graph.input])?;
    let keys: Vec<(&str, &str)> = a.keys.iter().map(|k| ("--keys", k.as_str())).collect();
    let o = open_graph(ctx, &a.graph, &keys)?;
    let (f, g) = (&o.frames, &o.graph);
    let name = |node: usize| f.name_of(g.nodes[node]);
    let report = json!({
        "input": a.graph.input,
        "frames": f.n_frames(),
        "sequences": f.names,
        "connections": a.graph.connect,
        "key_frames": o.keys.iter().map(|&k| f.name_of(k)).collect::<Vec<_>>(),
        "similarity_seconds": o.similarity_seconds,
        "similarity_cached": o.similarity_cached,
        "nodes": g.nodes.iter().map(|&n| f.name_of(n)).collect::<Vec<_>>(),
        "edges": g.edges.iter().map(|e| json!({
            "from": name(e.from), "to": name(e.to), "kind": e.kind, "frames": e.frames,
            "distance": e.distance, "cost": e.cost})).collect::<Vec<_>>(),
        "transitions": transitions_json(f, g),
        "missing_transitions": g.missing.iter().map(|&(x, y)| format!("{}:{}", f.names[x], f.names[y])).collect::<Vec<_>>(),
    });
    crate::output::write_json(&a.output, &report)?;
    ctx.result(&report, || {
        println!(
            "{} frames in {} sequence(s); similarity {:.1} s{}; {} nodes, {} edges, {} transition(s)",
            f.n_frames(),
            f.names.len(),
            o.similarity_seconds,
            if o.similarity_cached { " (cached)" } else { "" },
            g.nodes.len(),
            g.edges.len(),
            g.transitions.len()
        );
        for t in report["transitions"].as_array().into_iter().flatten() {
            println!(
                "  transition {} -> {} (window {}, cost {:.4})",
                t["from"].as_str().unwrap_or(""),
                t["to"].as_str().unwrap_or(""),
                t["window"],
                t["cost"].as_f64().unwrap_or(0.0)
            );
        }
        println!("wrote {}", a.output.display());
    });
    Ok(())
}

fn query(ctx: &crate::Ctx, a: QueryArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.graph.input])?;
    let o = open_graph(ctx, &a.graph, &[("--from", &a.from), ("--to", &a.to)])?;
    let (frames, graph, ground) = (&o.frames, &o.graph, &o.ground);
    let (from, to) = (o.keys[0], o.keys[1]);
    let (similarity_seconds, cached) = (o.similarity_seconds, o.similarity_cached);
    let (subject, set_name, units) = match &o.data {
        ImportedData::Subject(i) => (Some(&i.subject), i.subject.name.clone(), i.subject.units.clone()),
        ImportedData::FrameSet(f) => (None, f.frame_set.name.clone(), f.frame_set.units.clone()),
    };
    let q = PathQuery {
        w_d: a.distance_weight,
        w_t: a.time_weight,
        tolerance: (!a.paper_cost).then(Tolerance::default),
        ..PathQuery::new(from, to, a.distance, a.time * frames.fps)
    };
    let t1 = Instant::now();
    let path = optimise_path(graph, ground, &q)?;
    let query_seconds = t1.elapsed().as_secs_f64();
    let played = play_path(frames, &path);
    let written = write_output(ctx, &a, frames, subject, played, format!("{set_name}-smg"), &units)?;
    let unit = crate::output::unit_name(&units).to_string();
    let constraints = vec![
        Constraint::new(
            "distance",
            unit.clone(),
            a.distance,
            path.distance,
            path.distance_error,
            a.constraints.distance(a.distance),
        )
        .relative_to(a.distance),
        Constraint::new("time", "frames", q.frames, path.frames.len() as f64, path.time_error, a.constraints.frames())
            .relative_to(q.frames),
    ];
    let mut report = json!({
        "input": a.graph.input,
        "engine": "surface motion graph (Huang et al. 2009)",
        "fps": frames.fps,
        "from": a.from,
        "to": a.to,
        "connections": a.graph.connect,
        "frames": path.frames.len(),
        "distance": path.distance,
        "unit": unit,
        "transition_cost": path.transition_cost,
        "cost": path.cost,
        "path": path_segments(frames, &path),
        "loops": path.loops.iter().map(|(c, n)| json!({"edges": c.len(), "repetitions": n})).collect::<Vec<_>>(),
        "graph": {"nodes": graph.nodes.len(), "edges": graph.edges.len(),
            "transitions": transitions_json(frames, graph),
            "walks": path.walks, "loops": path.loops_in_graph},
        "similarity_seconds": similarity_seconds,
        "similarity_cached": cached,
        "query_seconds": query_seconds,
        "ilp_solves": path.ilp_solves,
        "constraints": constraints,
        "outputs": written,
        "target_distance": a.distance,
        "target_seconds": a.time,
        "seconds": path.frames.len() as f64 / frames.fps,
        // Output frames where the path jumps to another sequence or back (the transitions play
        // captured frames only, nothing is blended, so every frame is labelled original):
        // `surfcap view` marks them on its timeline.
        "transition_frames": path.switches,
        // With the tolerance: whether the path meets it, and why no path can when it does not.
        "tolerance": q.tolerance,
        "within_tolerance": path.within_tolerance,
        "unreachable": path.unreachable.as_ref().map(|u| json!({"kind": u.kind(), "why": u.to_string(), "detail": u})),
        "unconverged_subproblems": path.unconverged_subproblems,
    });
    add_travel(&mut report, &played_centres(frames, &path), frames.up);
    let rp = report_path(&a.output);
    crate::output::write_json(&rp, &report)?;
    ctx.result(&report, || {
        println!(
            "{} frames ({:.1} s), {:.2} {unit} covered (asked {} in {} s); {} transition(s), cost {:.3}; {} walk(s), {} loop(s) in the graph, {} ILP solve(s) in {:.3} s",
            path.frames.len(),
            path.frames.len() as f64 / frames.fps,
            path.distance,
            a.distance,
            a.time,
            path.switches.len(),
            path.transition_cost,
            path.walks,
            path.loops_in_graph,
            path.ilp_solves,
            query_seconds
        );
        println!("path: {}", path_segments(frames, &path).join(", "));
        if let Some(u) = &path.unreachable {
            println!("no path of the graph meets {} {unit} in {} s within 1% and 1 frame: {u}", a.distance, a.time);
        }
        println!("wrote {}, {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "), rp.display());
    });
    check_constraints(ctx, &a.constraints, &constraints)
}

//! `surfcap eval smg`: Huang et al. 2009's Table 1 for the surface motion graph on the
//! CMU-driven mannequin, or on any subject or frame set (`--input` with `--connect` and `--pair`) (`surfcap_eval::smg_eval` computes it; this command writes `smg.json`
//! and prints one row per key-frame pair beside the paper's own figures).

use std::path::{Path, PathBuf};

use surfcap_formats::import::{ImportedData, open_any};

use surfcap_eval::smg_comparison::{ESSENTIAL_GRAPH, SmgComparison, default_graph_params, smg_comparison};
use surfcap_eval::smg_eval::{
    LOCOMOTION_CONNECTIONS, LOCOMOTION_KEY_PAIRS, STAND_WALK_JOG_HIT_CONNECTIONS, STAND_WALK_JOG_HIT_KEY_PAIRS,
    SmgEval, SmgEvalOptions, grid, locomotion_subject, smg_eval, stand_walk_jog_hit_subject,
};
use surfcap_smg::motion_frames::MotionFrames;

use crate::options::{CacheOpts, SourceOpts};

/// `A<sep>B` split at its last `sep`.
fn split_pair(text: &str, sep: char, option: &str, expected: &str) -> anyhow::Result<(String, String)> {
    text.rsplit_once(sep)
        .map(|(a, b)| (a.trim().to_string(), b.trim().to_string()))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty())
        .ok_or_else(|| anyhow::anyhow!("{option} {text:?}: expected {expected}"))
}

/// The clips driving the mannequin.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipSet {
    /// Huang et al.'s setting: stand, walk, jog and hit loops (CMU 113_21 idle; subject 2's
    /// walk 02_01, jog 02_03 and punch 02_05), their four key pairs.
    StandWalkJogHit,
    /// CMU subject 16's stand-to-walk, walk, jog, jump and jog-to-stop (no in-place loop).
    Locomotion,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// The clips driving the mannequin (without --input).
    #[arg(long, value_enum, default_value_t = ClipSet::StandWalkJogHit)]
    pub set: ClipSet,
    /// Vertices of the mannequin (1000 to 20000).
    #[arg(long, default_value_t = 2000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Re-mesh every frame on its own first (seeded), so no two frames share vertices or
    /// triangles: the input Huang et al.'s engine is made for.
    #[arg(long, value_name = "SEED")]
    pub remeshed: Option<u64>,
    /// Transitions per connection: 1 is the paper's; more adds the next best windows whose
    /// switches lie at least 15 frames apart (an extension).
    #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 1, 20))]
    pub transitions: usize,
    #[command(flatten)]
    pub self_transitions: crate::commands::smg::SelfTransitionArgs,
    /// Evaluate this subject or frame set instead of the CMU mannequin (with --connect and
    /// --pair).
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// The higher-level graph of --input: FROM:TO sequence pairs.
    #[arg(long = "connect", value_delimiter = ',')]
    pub connect: Vec<String>,
    /// Key-frame pairs: FROM,TO as sequence:frame (repeatable); needed with --input, and on
    /// the mannequin they replace its four.
    #[arg(long = "pair")]
    pub pairs: Vec<String>,
    /// Target distances, subject units (Huang et al.: 1 to 20 m).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20", value_parser = crate::options::non_negative)]
    pub distances: Vec<f64>,
    /// Target times, seconds (Huang et al.: 1 to 40 s); every distance with every time is a
    /// query.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27,28,29,30,31,32,33,34,35,36,37,38,39,40", value_parser = crate::options::positive)]
    pub seconds: Vec<f64>,
    /// Skip the essential graph's run beside the surface motion graph (on by default when
    /// the frames share one topology).
    #[arg(long)]
    pub no_compare: bool,
    #[command(flatten)]
    pub source: SourceOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    /// Folder for the report (smg.json).
    #[arg(short, long, default_value = "smg-eval")]
    pub output: PathBuf,
}

/// A user's subject or frame set to evaluate instead of the mannequin.
struct Input {
    path: PathBuf,
    connect: Vec<String>,
    pairs: Vec<String>,
    source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = vec![&a.data];
    inputs.extend(a.input.as_deref());
    let outs = super::folder::claim(ctx, &a.output, &inputs, "eval-smg")?;
    let Args {
        data,
        set,
        vertices,
        remeshed,
        transitions,
        self_transitions,
        input,
        connect,
        pairs,
        distances,
        seconds,
        no_compare,
        source,
        cache,
        output,
    } = a;
    let compare = !no_compare;
    let (input, mannequin_pairs) = match input {
        Some(path) => (Some(Input { path, connect, pairs, source }), Vec::new()),
        None => (None, pairs),
    };
    let (data, cache, output) = (data.as_path(), &cache, output.as_path());
    let bar = crate::progress::Bar::new(ctx);
    // The subject: the CMU mannequin, or the user's; a frame set is used as it is.
    let data = match &input {
        None => ImportedData::Subject(surfcap_formats::import::Imported {
            subject: match set {
                ClipSet::StandWalkJogHit => stand_walk_jog_hit_subject(data, vertices)?,
                ClipSet::Locomotion => locomotion_subject(data, vertices)?,
            },
            notes: Vec::new(),
            sources: Vec::new(),
        }),
        Some(i) => open_any(&i.path, &i.source.to_import(None)?, &bar)?,
    };
    // Either the shared topology, or every frame re-meshed on its own (`surfcap remesh-frames`): the
    // same motion without any correspondence between frames.
    // The subject stays for the essential graph when its topology is shared.
    let (frames, form, subject) = match (data, remeshed) {
        (ImportedData::FrameSet(f), _) => (MotionFrames::from_frame_set(&f.frame_set), "frame set".to_string(), None),
        (ImportedData::Subject(s), None) => {
            (MotionFrames::from_subject(&s.subject), "shared topology".to_string(), Some(s.subject))
        }
        (ImportedData::Subject(s), Some(seed)) => {
            let opts = surfcap_builtin::frame_remeshing::RemeshFramesOptions { seed, ..Default::default() };
            let set = surfcap_builtin::frame_remeshing::remesh_subject_frames(&s.subject, &opts, &bar)?;
            (MotionFrames::from_frame_set(&set), format!("every frame re-meshed (seed {seed})"), None)
        }
    };
    // Sequence pairs of the higher-level graph, and key-frame pairs.
    type Pairs = Vec<(String, String)>;
    let parse_pairs = |p: &[String]| -> anyhow::Result<Pairs> {
        p.iter().map(|t| split_pair(t, ',', "--pair", "FROM,TO (each sequence:frame)")).collect()
    };
    let (connections, pairs): (Pairs, Pairs) = match &input {
        None => {
            type Named<'a> = &'a [(&'a str, &'a str)];
            let (c, p): (Named, Named) = match set {
                ClipSet::StandWalkJogHit => (&STAND_WALK_JOG_HIT_CONNECTIONS, &STAND_WALK_JOG_HIT_KEY_PAIRS),
                ClipSet::Locomotion => (&LOCOMOTION_CONNECTIONS, &LOCOMOTION_KEY_PAIRS),
            };
            let owned = |v: &[(&str, &str)]| v.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
            (owned(c), if mannequin_pairs.is_empty() { owned(p) } else { parse_pairs(&mannequin_pairs)? })
        }
        Some(i) => {
            if i.connect.is_empty() || i.pairs.is_empty() {
                anyhow::bail!("--input needs --connect FROM:TO and --pair FROM,TO (each sequence:frame)");
            }
            let c =
                i.connect.iter().map(|t| split_pair(t, ':', "--connect", "FROM:TO")).collect::<anyhow::Result<_>>()?;
            (c, parse_pairs(&i.pairs)?)
        }
    };
    let connections: Vec<(&str, &str)> = connections.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let pairs: Vec<(&str, &str)> = pairs.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let store = surfcap_mesh::derived_cache::DerivedCache::new(cache.dir()?);
    let opts = SmgEvalOptions {
        per_connection: transitions,
        targets: grid(&distances, &seconds),
        loops: self_transitions.loop_rule(),
        loops_per_sequence: self_transitions.loops_per_sequence,
        ..SmgEvalOptions::default()
    };
    let r = smg_eval(&frames, &form, &connections, &pairs, &opts, Some((&store, cache.no_cache)), &bar)?;
    let not_compared = match (&subject, compare) {
        (None, _) => Some(format!(
            "no essential graph beside it: the essential graph needs a shared topology, and this is {}",
            if remeshed.is_some() { "every frame re-meshed on its own" } else { "a frame set" }
        )),
        (Some(_), false) => Some("no essential graph beside it (--no-compare)".to_string()),
        (Some(_), true) => None,
    };
    // The essential graph on the same key frames and targets: only with a shared topology.
    let comparison = match (subject, compare) {
        (Some(s), true) => {
            let params = default_graph_params(s.fps);
            let pipe = cache.pipeline(ctx, s)?;
            Some(smg_comparison(&pipe, &frames, &r, &opts, &params, &bar)?)
        }
        _ => None,
    };
    let plots = heat_maps(output, &r, comparison.as_ref(), (&distances, &seconds))?;
    let path = output.join("smg.json");
    let mut report = serde_json::to_value(&r)?;
    report["written"] = serde_json::to_value(&plots)?;
    report["targets"] = serde_json::json!({ "distances": distances, "seconds": seconds });
    match &comparison {
        Some(c) => report["comparison"] = serde_json::to_value(c)?,
        None => report["comparison_skipped"] = serde_json::json!(not_compared),
    }
    crate::output::write_json(&path, &report)?;
    ctx.result(&report, || {
        println!(
            "surface motion graph ({}, {} transition(s) per connection): {} frames of {}-{} vertices, {} nodes, {} edges; similarity {:.1} s{}",
            r.form,
            r.per_connection,
            r.frames,
            r.vertices_min,
            r.vertices_max,
            r.graph_nodes,
            r.graph_edges,
            r.similarity_seconds,
            if r.similarity_cached { " (cached)" } else { "" }
        );
        match r.loop_rule {
            Some(rule) => println!(
                "self-transitions ({} per sequence) chosen among the loops of at least {} frames varying at least {} typical frame step(s), \
                 spanning each sequence's cross transitions and key frames; shorter or stiller loops never pad time",
                self_transitions.loops_per_sequence, rule.min_frames, rule.variation_floor
            ),
            None => println!("self-transitions by eq. 5 alone, every loop played (--eq5-self-transitions)"),
        }
        for t in &r.transitions {
            println!("  transition {} -> {} (window {}, cost {:.4}, smoothness {:.1} cm)", t.from, t.to, t.window, t.cost, 100.0 * t.smoothness);
        }
        println!(
            "{:<22} {:>7} {:>7} {:>7} {:>7} {:>7} {:>6} {:>6} {:>6} {:>14}",
            "key frames", "smooth", "(cm)", "dist", "err", "(m)", "time", "err", "(fr)", "cpu ms"
        );
        println!("{:<22} {:>7} {:>7} {:>7} {:>7} {:>7} {:>6} {:>6} {:>6} {:>14}", "", "min", "max", "min", "rms", "max", "min", "rms", "max", "mean +- std");
        for p in &r.pairs {
            println!(
                "{:<22} {:>7.1} {:>7.1} {:>7.3} {:>7.2} {:>7.2} {:>6.0} {:>6.1} {:>6.0} {:>7.2} +- {:<5.2}",
                format!("{} -> {}", p.from, p.to),
                100.0 * p.smoothness_min,
                100.0 * p.smoothness_max,
                p.distance_error.min,
                p.distance_error.rms,
                p.distance_error.max,
                p.time_error_frames.min,
                p.time_error_frames.rms,
                p.time_error_frames.max,
                1e3 * p.cpu_seconds.mean,
                1e3 * p.cpu_seconds.std
            );
        }
        for p in &r.pairs {
            let g = &p.goal;
            let why: Vec<String> = g.unreachable.iter().map(|(k, n)| format!("{n} {k}")).collect();
            println!(
                "goal ({}% and {} frame): {} -> {}: {} of {} targets met (worst {:.2}% and {} frame(s)); unreachable: {}; cpu {:.2} +- {:.2} ms",
                100.0 * g.tolerance.distance_relative,
                g.tolerance.frames,
                p.from,
                p.to,
                g.met,
                p.queries,
                100.0 * g.met_distance_relative_max,
                g.met_time_error_max,
                if why.is_empty() { "none".to_string() } else { why.join(", ") },
                1e3 * g.cpu_seconds.mean,
                1e3 * g.cpu_seconds.std
            );
        }
        println!("over the reachable targets (met within the tolerance), eq. 6's optimum (the paper's measures):");
        for p in &r.pairs {
            match &p.not_connected {
                Some(why) => println!("  {} -> {}: {} targets unreachable: {why}", p.from, p.to, p.goal.met + p.goal.unreachable.values().sum::<usize>()),
                None => println!(
                    "  {} -> {}: {} met; distance error rms {:.2} max {:.2} m; time error rms {:.1} max {:.0} frames; cpu {:.2} ms per query",
                    p.from,
                    p.to,
                    p.goal.met,
                    p.reachable_distance_error.rms,
                    p.reachable_distance_error.max,
                    p.reachable_time_error_frames.rms,
                    p.reachable_time_error_frames.max,
                    1e3 * p.cpu_seconds.mean
                ),
            }
        }
        println!(
            "Huang et al. 2009 (Table 1): distance error rms 0.17-0.47 m, max < 1 m; time error max 22-25 frames; 5.7-15.0 s per query (Matlab)"
        );
        match &comparison {
            Some(c) => print_comparison(c),
            None => println!("{}", not_compared.as_deref().unwrap_or_default()),
        }
        println!("wrote {}", path.display());
        for p in plots.iter().filter(|p| p.extension().is_some_and(|e| e == "png")) {
            println!("wrote {}", p.display());
        }
    });
    ctx.commit(outs)
}

/// The comparison table: one row per key pair and engine.
fn print_comparison(c: &SmgComparison) {
    let eg = &c.essential_graph;
    println!(
        "beside it, the essential graph (alpha {}, segments {}-{} frames): {} nodes, {} edges, {} transitions; \
         precomputed in {:.1} s{} (the surface motion graph's: {:.1} s)",
        eg.alpha,
        eg.l_min,
        eg.l_max,
        eg.nodes,
        eg.edges,
        eg.transitions,
        eg.precompute_seconds,
        if eg.graph_cached { " (graph cached)" } else { "" },
        c.smg_precompute_seconds
    );
    println!(
        "{:<22} {:<4} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>7} {:>7} {:>6} {:>6} {:>16}",
        "key frames",
        "eng",
        "dist",
        "err",
        "(m)",
        "time",
        "err",
        "(fr)",
        "trans",
        "cost",
        "(def)",
        "smooth",
        "(cm)",
        "cpu ms"
    );
    println!(
        "{:<22} {:<4} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>7} {:>7} {:>6} {:>6} {:>16}",
        "", "", "min", "rms", "max", "min", "rms", "max", "/q", "mean", "max", "mean", "max", "mean +- std"
    );
    for r in &c.rows {
        println!(
            "{:<22} {:<4} {:>6.2} {:>6.2} {:>6.2} {:>6.0} {:>6.1} {:>6.0} {:>5.1} {:>7.2} {:>7.2} {:>6.1} {:>6.1} {:>7.2} +- {:<6.2}",
            format!("{} -> {}", r.from, r.to),
            if r.engine == ESSENTIAL_GRAPH { "EG" } else { "SMG" },
            r.distance_error.min,
            r.distance_error.rms,
            r.distance_error.max,
            r.time_error_frames.min,
            r.time_error_frames.rms,
            r.time_error_frames.max,
            r.transitions_per_query,
            r.transition_cost.mean,
            r.transition_cost.max,
            100.0 * r.smoothness.mean,
            100.0 * r.smoothness.max,
            1e3 * r.cpu_seconds.mean,
            1e3 * r.cpu_seconds.std
        );
    }
    for r in &c.rows {
        let why: Vec<String> = r.unreachable.iter().map(|(k, n)| format!("{n} {k}")).collect();
        println!(
            "{} {} -> {}: {} of {} targets met within the tolerance (worst {:.2}% and {} frame(s)); unreachable: {}; missed while reachable: {}",
            if r.engine == ESSENTIAL_GRAPH { "EG" } else { "SMG" },
            r.from,
            r.to,
            r.met,
            r.queries + r.failed,
            100.0 * r.met_distance_relative_max,
            r.met_time_error_max,
            if why.is_empty() { "none".to_string() } else { why.join(", ") },
            r.missed_reachable
        );
    }
    if eg.excluded_loops > 0 {
        println!(
            "the essential graph never pads time with its {} degenerate loop(s) (fewer than {} frames, or poses varying less than {} typical frame step(s))",
            eg.excluded_loops, eg.loop_rule.min_frames, eg.loop_rule.variation_floor
        );
    }
    for r in c.rows.iter().filter(|r| r.failed > 0) {
        println!(
            "{} {} -> {}: {} of {} queries found no path (first: {})",
            r.engine,
            r.from,
            r.to,
            r.failed,
            r.failed + r.queries,
            r.first_failure.as_deref().unwrap_or_default()
        );
    }
    println!(
        "(cost: deformation distance, thesis eq. 2.13; smoothness: Hausdorff; both per transition taken, over the frames it matches)"
    );
}

/// A file-name part for a `sequence:frame`.
fn file_part(frame: &str) -> String {
    frame.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '-' }).collect()
}

/// The axis label of a list of target values: its unit when the values are 1, 2, 3, ... from
/// a whole number (the map's cells then sit at their values), else the list itself.
fn axis_label(what: &str, unit: &str, values: &[f64]) -> (String, usize) {
    let whole = values.first().is_some_and(|v| v.fract() == 0.0 && *v >= 0.0);
    if whole && values.windows(2).all(|w| w[1] - w[0] == 1.0) {
        (format!("target {what} ({unit})"), values[0] as usize)
    } else {
        let list: Vec<String> = values.iter().map(|v| format!("{v}")).collect();
        (format!("target {what}: cell k of [{}] {unit}", list.join(", ")), 0)
    }
}

/// For each key pair, distance- and time-error heat maps over the target grid (rows: distance,
/// columns: time) for the surface motion graph and, beside it, the essential graph, each
/// measure on one colour range for both engines. Written as `<measure>_<engine>_<from>_to_<to>`
/// .png and .svg.
fn heat_maps(
    output: &Path,
    r: &SmgEval,
    comparison: Option<&SmgComparison>,
    (distances, seconds): (&[f64], &[f64]),
) -> anyhow::Result<Vec<PathBuf>> {
    let (y_label, r0) = axis_label("distance", "m", distances);
    let (x_label, c0) = axis_label("time", "s", seconds);
    let mut written = Vec::new();
    for (k, p) in r.pairs.iter().enumerate() {
        // Key frames no path joins: no answer to any target (blank cells, as a failed query's).
        let smg: Vec<(f64, f64)> = if p.outcomes.is_empty() {
            vec![(f64::NAN, f64::NAN); distances.len() * seconds.len()]
        } else {
            p.outcomes.iter().map(|q| (q.distance_error, q.time_error)).collect()
        };
        let mut engines = vec![("smg", "surface motion graph", smg)];
        if let Some(c) = comparison {
            let eg = c.rows.iter().filter(|row| row.engine == ESSENTIAL_GRAPH).nth(k).expect("one row per pair");
            engines.push(("essential", "essential graph", eg.errors.clone()));
        }
        for (measure, unit, pick) in [("distance-error", "m", 0usize), ("time-error", "frames", 1usize)] {
            let value = |e: &(f64, f64)| if pick == 0 { e.0 } else { e.1 };
            let hi = engines.iter().flat_map(|(_, _, e)| e.iter().map(value)).fold(0.0, f64::max);
            for (tag, name, errors) in &engines {
                let heat = surfcap_plot::HeatMap {
                    title: format!(
                        "{name}, {} -> {}: {} ({unit}; dark 0, yellow {hi:.2})",
                        p.from,
                        p.to,
                        measure.replace('-', " ")
                    ),
                    x_label: x_label.clone(),
                    y_label: y_label.clone(),
                    values: errors.iter().map(value).collect(),
                    rows: distances.len(),
                    cols: seconds.len(),
                    origin: (r0, c0),
                    range: Some((0.0, hi.max(1e-12))),
                    path: Vec::new(),
                    value_label: format!("{} ({unit})", measure.replace('-', " ")),
                };
                let stem = format!("{measure}_{tag}_{}_to_{}", file_part(&p.from), file_part(&p.to));
                written.extend(surfcap_plot::write_heat_map(&output.join(stem), &heat)?);
            }
        }
    }
    Ok(written)
}

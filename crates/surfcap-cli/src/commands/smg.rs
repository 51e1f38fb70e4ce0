//! `surfcap smg query <input> --connect A:B ... --from seq:frame --to seq:frame --distance D
//! --time SECONDS -o out`: Huang et al. 2009's surface motion graph, surfcap's second synthesis
//! engine: the input may be a subject or a frame set (every frame its own topology). The
//! library does the work (`surfcap_synthesis::smg_query` over `surfcap_smg`: the similarity,
//! cached; the graph from the user's higher level and the two key frames; the ILP path; the
//! animation written as the other synthesis commands write theirs, glb by default, a frame set's
//! as glb (a mesh per frame), abc, obj or a `.frames` folder, and its report with the centre
//! track, the target distance and the transition frames that `surfcap view` draws); this command
//! prints the result and reports a missed distance or time as missed (`--strict`: exit 3).

use std::path::PathBuf;

use surfcap_synthesis::Output;
use surfcap_synthesis::smg_query::{SimilarityCache, SmgGraph, SmgGraphRequest, SmgQuery};

use crate::options::{CacheOpts, ConstraintOpts, SourceOpts};
use crate::synthesis_args::check_constraints;

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

/// Which loops a query may play to pad time, and how self-transitions are chosen (shared by
/// `smg build`, `smg query` and `eval smg`, so the commands build the graph the eval measures).
#[derive(clap::Args, Debug)]
pub struct SelfTransitionArgs {
    /// The paper's graph as printed: every self-transition by eq. 5 alone (a clip's stillest
    /// 3 frames may be its loop). By default a self-transition is chosen among the loops a
    /// query may play (--min-loop, --loop-variation-floor), spanning the sequence's cross
    /// transitions and key frames. `smg query` still never pads time with an excluded loop;
    /// `eval smg` with this flag plays every loop, as the paper does.
    #[arg(long)]
    pub eq5_self_transitions: bool,
    /// Excluded loops: a loop playing fewer frames than this per repetition is never repeated
    /// to pad time, nor chosen as a self-transition (a few frames repeated dozens of times is a
    /// stutter, not a motion; 1: no minimum).
    #[arg(long, default_value_t = 10, value_parser = crate::options::count)]
    pub min_loop: usize,
    /// Excluded loops: a loop whose frames differ among themselves (largest shape
    /// dissimilarity) by less than this many typical frame-to-frame dissimilarities of their
    /// sequences is a held pose, never repeated to pad time, nor chosen as a self-transition
    /// (0: no floor).
    #[arg(long, default_value_t = 1.0, value_parser = crate::options::non_negative)]
    pub loop_variation_floor: f64,
    /// Self-transitions per sequence (without --eq5-self-transitions): the loop spanning the
    /// sequence's cross transitions and key frames, then the cheapest admissible loops inside
    /// it, which queries may repeat to meet their times.
    #[arg(long, default_value_t = 2, value_parser = |s: &str| crate::options::whole_in(s, 1, 10))]
    pub loops_per_sequence: usize,
}

impl SelfTransitionArgs {
    /// The loops that may pad time (and, by default, be chosen as self-transitions).
    pub fn rule(&self) -> surfcap_smg::loop_exclusion::LoopRule {
        surfcap_smg::loop_exclusion::LoopRule { min_frames: self.min_loop, variation_floor: self.loop_variation_floor }
    }

    /// The rule self-transitions are chosen by (`None`: the paper's eq. 5 graph).
    pub fn loop_rule(&self) -> Option<surfcap_smg::loop_exclusion::LoopRule> {
        (!self.eq5_self_transitions).then_some(self.rule())
    }
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
    /// entry points, so loops are reachable from more key frames). A self-connection (FROM:FROM)
    /// counts here only with --eq5-self-transitions; by default its loops are set by
    /// --loops-per-sequence.
    #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 1, 20))]
    pub transitions: usize,
    /// Least distance between the switches of one connection's transitions, frames.
    #[arg(long, default_value_t = 15, value_parser = crate::options::count)]
    pub separation: usize,
    /// Voxels along the frames' largest extent (the shape histograms' lattice).
    #[arg(long, default_value_t = 64, value_parser = |s: &str| crate::options::whole_in(s, 8, 512))]
    pub resolution: usize,
    #[command(flatten)]
    pub self_transitions: SelfTransitionArgs,
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
    /// lower level, taken in pairs FROM,TO as a query's --from and --to (an odd last one is
    /// both): the self-transitions span them, so `--keys A,B` builds the graph of `smg query
    /// --from A --to B`.
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
    /// Duration: seconds (a bare number, e.g. 3, or 3s) or frames shown (90f). T seconds show
    /// round(T x fps) frames, start included, as `synth reach` counts them.
    #[arg(long, value_parser = crate::options::positive_time)]
    pub time: surfcap_pipeline::constraint_files::TimeSpec,
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

pub fn run(ctx: &crate::Ctx, cmd: Cmd) -> anyhow::Result<()> {
    match cmd {
        Cmd::Query(a) => query(ctx, a),
        Cmd::Build(a) => build(ctx, a),
    }
}

impl GraphArgs {
    fn request(&self) -> SmgGraphRequest {
        SmgGraphRequest {
            input: self.input.clone(),
            connect: self.connect.clone(),
            windows: self.windows.clone(),
            transitions: self.transitions,
            separation: self.separation,
            resolution: self.resolution,
            loops: self.self_transitions.loop_rule(),
            loops_per_sequence: self.self_transitions.loops_per_sequence,
        }
    }

    /// Opens the input with its similarity and graph, the key frames `keys` among the nodes.
    fn open(&self, keys: &[(&str, &str)], bar: &crate::progress::Bar) -> anyhow::Result<SmgGraph> {
        crate::options::record_input(&self.input);
        let cache = SimilarityCache { dir: self.cache.dir()?, refresh: self.cache.no_cache };
        Ok(SmgGraph::open(&self.request(), &self.source.to_import(None)?, &cache, keys, bar)?)
    }
}

fn build(ctx: &crate::Ctx, a: BuildArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.graph.input])?;
    let keys: Vec<(&str, &str)> = a.keys.iter().map(|k| ("--keys", k.as_str())).collect();
    let bar = crate::progress::Bar::new(ctx);
    let o = a.graph.open(&keys, &bar)?;
    drop(bar);
    let report = o.report(&a.graph.request());
    crate::output::write_json(&a.output, &report)?;
    ctx.result(&report, || {
        println!(
            "{} frames in {} sequence(s); similarity {:.1} s{}; {} nodes, {} edges, {} transition(s)",
            report.frames,
            report.sequences.len(),
            report.similarity_seconds,
            if report.similarity_cached { " (cached)" } else { "" },
            report.nodes.len(),
            report.edges.len(),
            report.transitions.len()
        );
        match (&report.self_transitions.loop_rule, report.self_transitions.per_sequence) {
            (Some(rule), Some(k)) => println!(
                "self-transitions ({k} per sequence) chosen among the loops of at least {} frames varying at least {} \
                 typical frame step(s), spanning each sequence's cross transitions and key frames",
                rule.min_frames, rule.variation_floor
            ),
            _ => println!("self-transitions by eq. 5 alone (--eq5-self-transitions)"),
        }
        for t in &report.transitions {
            println!("  transition {} -> {} (window {}, cost {:.4})", t.from, t.to, t.window, t.cost);
        }
        println!("wrote {}", a.output.display());
    });
    Ok(())
}

fn query(ctx: &crate::Ctx, a: QueryArgs) -> anyhow::Result<()> {
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&[&a.graph.input]);
    surfcap_synthesis::plan_animation_and_report(&mut outs, a.format, &a.output, ctx.force)?;
    let bar = crate::progress::Bar::new(ctx);
    let o = a.graph.open(&[("--from", &a.from), ("--to", &a.to)], &bar)?;
    let q = SmgQuery {
        from: a.from.clone(),
        to: a.to.clone(),
        distance: a.distance,
        time: a.time,
        distance_weight: a.distance_weight,
        time_weight: a.time_weight,
        paper_cost: a.paper_cost,
        loops: a.graph.self_transitions.rule(),
    };
    let out = Output {
        path: Some(a.output.clone()),
        format: a.format,
        force: ctx.force,
        tolerances: a.constraints.tolerances(),
    };
    let done = o.query(&a.graph.request(), &q, &out, &bar)?;
    drop(bar);
    ctx.commit(outs)?;
    let (r, path) = (&done.report, &done.path);
    ctx.result(r, || {
        println!(
            "{} frames ({:.1} s), {:.2} {} covered (asked {} in {} s: {} frames); {} transition(s), cost {:.3}; {} walk(s), {} loop(s) in the graph, {} ILP solve(s) in {:.3} s",
            r.frames,
            r.seconds,
            r.distance,
            r.unit,
            a.distance,
            r.target_seconds,
            r.target_frames,
            path.switches.len(),
            r.transition_cost,
            r.graph.walks,
            r.graph.loops,
            r.ilp_solves,
            r.query_seconds
        );
        println!("path: {}", r.path.join(", "));
        for x in &r.excluded_loops {
            println!("excluded loop {} (not used to pad time): {}", x.frames.join(", "), x.why);
        }
        if let Some(u) = &path.unreachable {
            let excluded = match r.excluded_loops.len() {
                0 => String::new(),
                n => format!(" ({n} excluded loop(s) not counted)"),
            };
            println!(
                "no path of the graph meets {} {} in {} s within 1% and 1 frame: {}{excluded}",
                a.distance,
                r.unit,
                r.target_seconds,
                u.in_unit(&r.unit)
            );
        }
        let written: Vec<String> = done.written.iter().map(|p| p.display().to_string()).collect();
        println!("wrote {}, {}", written.join(", "), surfcap_synthesis::report_path(&a.output).display());
    });
    check_constraints(ctx, &a.constraints, &done.constraints)
}

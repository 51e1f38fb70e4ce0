//! The options several commands share, each group defined once and flattened
//! (`#[command(flatten)]`) into the commands that take it: the subject a command reads
//! ([`SubjectArgs`]) and what its sources do not say ([`SourceOpts`]), where derived products are
//! cached ([`CacheOpts`]), the pose distance ([`DistanceOpts`]), how the flow between texture
//! maps runs ([`FlowArgs`]), the transition table ([`TableOpts`]), the edge weights'
//! tolerance ([`AlphaOpt`]), the graph ([`GraphOpts`]), where an animation goes ([`OutOpts`]),
//! when its constraints count as missed ([`ConstraintOpts`]), a plain seed ([`SeedOpt`]) and
//! the viewer's port ([`PortOpt`]).
//!
//! Option values are parsed by `FromStr` (clap calls it): library types implement it
//! (`UpAxis`, `ExportFormat`, `PoseMetric`, `StretchInterpolation`, `GraphKind`, and `Alpha`, the
//! edge weights' tolerance, checked there once for every caller), and the few values that are
//! only the command line's ([`SlopeArg`], [`Positive`]) are newtypes here.
//! Every numeric option is checked when it is parsed, by its type ([`Positive`], `Alpha`) or
//! one of the value parsers [`positive`], [`non_negative`], [`fraction`], [`count`],
//! [`at_least`], [`whole_in`], and for values that scale a size or a coordinate
//! [`number_from`], [`positive_at_most`] and [`frame_rate`] (documented bounds, so that `1e308`
//! is refused by name instead of overflowing later): clap's
//! message names the option and the value, ours the allowed range, and nothing runs (or is
//! cached) with NaN, a negative weight or a count of 0.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use surfcap_appearance::flow_cache::TextureFlow;
use surfcap_formats::export::ExportFormat;
use surfcap_formats::import::ImportOptions;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_geometry::pose_distance::PoseMetric;
use surfcap_mesh::{Subject, Units, UpAxis};
use surfcap_motion::dtw::Slope;
use surfcap_motion::edge_weights::Alpha;
use surfcap_motion::segment_bounds;
use surfcap_motion::transition_table::TableParams;
use surfcap_pipeline::{CacheStore, GraphKind, GraphParams, Pipeline};

/// Options that say what the sources do not (shared by every command that opens a subject).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SourceOpts {
    /// Frame rate, when the sources do not give it (or to override them).
    #[arg(long, value_parser = positive)]
    pub fps: Option<f64>,
    /// Up axis: +x, +y, +z, -x, -y or -z.
    #[arg(long)]
    pub up_axis: Option<UpAxis>,
    /// Length unit: m, cm, mm, in, or any other word for arbitrary units.
    #[arg(long)]
    pub units: Option<String>,
}

impl SourceOpts {
    pub fn to_import(&self, name: Option<String>) -> anyhow::Result<ImportOptions> {
        Ok(ImportOptions { name, fps: self.fps, up_axis: self.up_axis, units: self.units.as_deref().map(Units::parse) })
    }
}

/// The subject a command reads: its path (a positional argument) and what its sources do not
/// say.
#[derive(clap::Args, Debug, Clone)]
pub struct SubjectArgs {
    /// A subject cache, or any source `surfcap import` reads.
    #[arg(id = "subject", value_name = "SUBJECT")]
    pub path: PathBuf,
    #[command(flatten)]
    pub source: SourceOpts,
}

impl SubjectArgs {
    /// Opens the subject (see [`open`]).
    pub fn open(&self, ctx: &crate::Ctx) -> anyhow::Result<Subject> {
        open(ctx, &self.path, &self.source)
    }
}

/// The seed of a command's random choices (for commands whose seed has no more to say).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct SeedOpt {
    /// Seed of every random choice: the same seed gives the same result.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// The pose distance: which metric, and the weight of its stretch term.
#[derive(clap::Args, Debug, Clone)]
pub struct DistanceOpts {
    /// deformation (thesis eq. 2.13), deformation-log (eq. 2.14), euclidean (eq. 2.2) or
    /// deformation-literal (eq. 2.13 with eq. 2.6 read literally, A^-1 B).
    #[arg(long, default_value = "deformation")]
    pub metric: PoseMetric,
    /// Weight of the stretch term (eq. 2.13).
    #[arg(long, default_value_t = 0.01, value_parser = non_negative)]
    pub w: f64,
}

impl DistanceOpts {
    /// The distance matrix's parameters (every vertex weighted alike).
    pub fn params(&self) -> DistanceParams {
        DistanceParams { metric: self.metric, w: self.w, vertex_weights: None }
    }
}

/// The tolerance of the edge weights of a graph.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct AlphaOpt {
    /// Tolerance alpha of the edge weights (thesis eq. 3.2-3.3); larger gives a denser graph
    /// (more transitions are worth their cost).
    #[arg(long, default_value = "0.05")]
    pub alpha: Alpha,
}

impl AlphaOpt {
    pub fn value(&self) -> Alpha {
        self.alpha
    }
}

/// The port of the local viewer server.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PortOpt {
    /// Port on 127.0.0.1 (default: any free one; the URL is printed).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
}

/// `--data`'s help for a command that reads `what` from the shared real-data folder (laid out
/// as `../shared/data`: `<dataset>/<sequence>/...`). The option's default is
/// [`default_data_dir`] (`default_value_os_t`), so the command runs the same from any working
/// folder and `--help` shows the folder it resolves to.
pub fn data_help(what: &str) -> String {
    format!(
        "The shared data folder ({what}); default: $SURFCAP_DATA when set, else the shared/data \
         folder beside the checkout surfcap was built from"
    )
}

/// The data folder when no `--data` is given: `$SURFCAP_DATA` when set (and not empty), else
/// [`checkout_data_dir`].
pub fn default_data_dir() -> PathBuf {
    match std::env::var_os("SURFCAP_DATA") {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => checkout_data_dir(),
    }
}

/// `../shared/data` next to the workspace (the checkout) this program was built from.
pub fn checkout_data_dir() -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let workspace = crate_dir.parent().and_then(Path::parent).unwrap_or(crate_dir);
    workspace.parent().unwrap_or(workspace).join("shared").join("data")
}

/// Where derived matrices are cached.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct CacheOpts {
    /// Cache folder for derived matrices (default: $XDG_CACHE_HOME/surfcap or ~/.cache/surfcap).
    #[arg(long)]
    pub cache_dir: Option<PathBuf>,
    /// Recompute even if a cached result exists.
    #[arg(long)]
    pub no_cache: bool,
}

impl CacheOpts {
    /// The cache folder: `--cache-dir`, else `$XDG_CACHE_HOME/surfcap`, else `~/.cache/surfcap`.
    /// Refused when it is or lies inside one of the inputs this run has opened
    /// ([`record_input`]): its entries would be written into the input. A cache folder that
    /// merely holds an input (`--cache-dir .` beside `walk.subject`) is fine: entries are
    /// written only under the cache's own hashed names, never into a folder of the input's.
    /// (Whether other users can write it is checked by the cache itself, when it is first used.)
    pub fn dir(&self) -> anyhow::Result<PathBuf> {
        let dir = self.cache_dir.clone().unwrap_or_else(surfcap_pipeline::default_cache_dir);
        let out = surfcap_mesh::output_path::resolve(&dir)?;
        for input in INPUTS.lock().unwrap_or_else(|e| e.into_inner()).iter() {
            let Ok(inp) = std::fs::canonicalize(input) else { continue };
            let how = if out == inp {
                "is"
            } else if out.starts_with(&inp) {
                "lies inside"
            } else {
                continue;
            };
            anyhow::bail!(
                "{}: the cache folder {how} the input {}: the cache would write its entries into the input; choose a --cache-dir outside the inputs",
                dir.display(),
                input.display()
            );
        }
        Ok(dir)
    }

    pub fn store(&self) -> anyhow::Result<CacheStore> {
        Ok(CacheStore::in_folder(self.dir()?, self.no_cache))
    }

    /// The derived-product pipeline of `subject`, with progress bars.
    pub fn pipeline(&self, ctx: &crate::Ctx, subject: Subject) -> anyhow::Result<Pipeline> {
        Ok(Pipeline::new(subject, self.store()?, Box::new(crate::progress::Bar::new(ctx))))
    }
}

/// The inputs this run has opened, which the cache folder must stay out of ([`CacheOpts::dir`]).
static INPUTS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Records an input of this run (every subject [`open`] opens is recorded).
pub fn record_input(path: &Path) {
    INPUTS.lock().unwrap_or_else(|e| e.into_inner()).push(path.to_path_buf());
}

/// How the optical flow between texture maps runs (thesis 4.4.1): `appearance build |
/// complete` and `eval appearance`.
#[derive(clap::Args, Debug, Clone)]
pub struct FlowArgs {
    /// Finest scale of the TV-L1 flow: 0 solves at full resolution, 1 stops at half
    /// resolution and upsamples (a quarter of the pixels to solve at the finest scale; the flow
    /// between texture maps is smooth).
    #[arg(long, default_value_t = 1, value_parser = |s: &str| whole_in(s, 0, 4))]
    pub flow_scale: usize,
    /// Skip the pre-processing (histogram equalisation and bilateral filter) before the flow.
    #[arg(long)]
    pub no_preprocess: bool,
}

impl FlowArgs {
    /// The thesis's flow through the derived cache (`--cache-dir`, `--no-cache` recomputes).
    pub fn estimator<'a>(
        &self,
        cache: &CacheOpts,
        progress: &'a dyn surfcap_mesh::Progress,
    ) -> anyhow::Result<TextureFlow<'a>> {
        let dir = cache.dir()?;
        Ok(surfcap_appearance::appearance_requests::texture_flow(
            Some(&dir),
            cache.no_cache,
            self.flow_scale,
            self.no_preprocess,
            progress,
        ))
    }
}

/// A slope constraint p of a warping path (thesis eq. 2.53): a whole number >= 1, or `inf`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlopeArg(pub Slope);

impl FromStr for SlopeArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "inf" | "infinity" => Ok(SlopeArg(None)),
            _ => match s.parse::<usize>() {
                Ok(p) if p >= 1 => Ok(SlopeArg(Some(p))),
                _ => Err(format!("{s:?}: expected a whole number >= 1 or inf")),
            },
        }
    }
}

/// A finite number > 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Positive(pub f64);

impl FromStr for Positive {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        positive(s).map(Positive)
    }
}

/// A number in `ok`, else the message `expected {range}`.
fn number_in(s: &str, ok: impl Fn(f64) -> bool, range: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && ok(x) => Ok(x),
        _ => Err(format!("expected {range}")),
    }
}

/// Value parser: an image file to write, whose extension names its format (`.png`, `.jpg`,
/// `.jpeg`), so that a `.jpg` never holds PNG bytes.
pub fn image_output(s: &str) -> Result<std::path::PathBuf, String> {
    let p = std::path::PathBuf::from(s);
    match surfcap_appearance::texture_image::ImageFileFormat::of_path(&p) {
        Ok(_) => Ok(p),
        Err(_) => Err(format!(
            "expected an image file ending in {} (the format follows the extension)",
            surfcap_appearance::texture_image::ImageFileFormat::EXTENSIONS
        )),
    }
}

/// Value parser: a finite number > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    number_in(s, |x| x > 0.0, "a finite number > 0")
}

/// Value parser: a duration > 0, in seconds (bare or `3s`) or frames (`90f`).
pub fn positive_time(s: &str) -> Result<surfcap_pipeline::constraint_files::TimeSpec, String> {
    match s.parse::<surfcap_pipeline::constraint_files::TimeSpec>() {
        Ok(t) if t.value > 0.0 => Ok(t),
        _ => Err(format!("expected a duration > 0 in seconds (3 or 3s) or frames (90f), got {s:?}")),
    }
}

/// Value parser: a finite number from `min` to `max` (both included): for the options whose
/// value scales a size or a coordinate, so an overflow (`1e308`) is refused by name at parse time.
pub fn number_from(s: &str, min: f64, max: f64) -> Result<f64, String> {
    number_in(s, |x| (min..=max).contains(&x), &format!("a number from {min} to {max}"))
}

/// Value parser: a finite number > 0 and at most `max`.
pub fn positive_at_most(s: &str, max: f64) -> Result<f64, String> {
    number_in(s, |x| x > 0.0 && x <= max, &format!("a number > 0 and at most {max}"))
}

/// Value parser: a frame rate from 0.1 to 10000 fps (frame times from 1e-4 to 10 s: no capture
/// or animation is outside them).
pub fn frame_rate(s: &str) -> Result<f64, String> {
    number_in(s, |x| (0.1..=10_000.0).contains(&x), "a frame rate from 0.1 to 10000 fps")
}

/// Value parser: a finite number >= 0.
pub fn non_negative(s: &str) -> Result<f64, String> {
    number_in(s, |x| x >= 0.0, "a finite number >= 0")
}

/// Value parser: a number in [0, 1].
pub fn fraction(s: &str) -> Result<f64, String> {
    number_in(s, |x| (0.0..=1.0).contains(&x), "a number in [0, 1]")
}

/// Value parser: a whole number >= `min`.
pub fn at_least(s: &str, min: usize) -> Result<usize, String> {
    whole_in(s, min, usize::MAX)
}

/// Value parser: a whole number from `min` to `max`.
pub fn whole_in(s: &str, min: usize, max: usize) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (min..=max).contains(&n) => Ok(n),
        _ if max == usize::MAX => Err(format!("expected a whole number >= {min}")),
        _ => Err(format!("expected a whole number from {min} to {max}")),
    }
}

/// Value parser: a whole number >= 1.
pub fn count(s: &str) -> Result<usize, String> {
    at_least(s, 1)
}

/// Options of a transition table.
#[derive(clap::Args, Debug, Clone)]
pub struct TableOpts {
    /// Slope constraint p of the warping path (thesis eq. 2.53; "inf" for none).
    #[arg(long, default_value = "3")]
    pub slope: SlopeArg,
    /// Shortest segment, frames (default: a third of a second at the subject's fps, at most a
    /// third of the longest).
    #[arg(long, value_parser = count)]
    pub l_min: Option<usize>,
    /// Longest segment, frames (default: two seconds, at most half the shortest looping clip).
    #[arg(long, value_parser = count)]
    pub l_max: Option<usize>,
}

impl Default for TableOpts {
    fn default() -> Self {
        TableOpts { slope: SlopeArg(Some(3)), l_min: None, l_max: None }
    }
}

impl TableOpts {
    pub fn params(&self, fps: f64) -> anyhow::Result<TableParams> {
        self.with_bounds(segment_bounds(fps))
    }

    /// The parameters for a pipeline's subject: by default segments fit its shortest looping
    /// clip ([`surfcap_pipeline::Pipeline::segment_bounds`]: a one-cycle game clip of 25 frames
    /// gets windows of 4 to 12 frames, not 10 to 60).
    pub fn params_for(&self, pipe: &surfcap_pipeline::Pipeline) -> anyhow::Result<TableParams> {
        self.with_bounds(pipe.segment_bounds())
    }

    fn with_bounds(&self, bounds: (usize, usize)) -> anyhow::Result<TableParams> {
        Ok(surfcap_pipeline::table_params(self.slope.0, self.l_min, self.l_max, bounds)?)
    }
}

/// Which graph to search, and how it is built.
#[derive(clap::Args, Debug, Clone)]
pub struct GraphOpts {
    /// essential (union of all shortest-path trees, O(N^3)), sparse-essential (the same on every
    /// frame's --k cheapest transitions plus the original edges: for long captures)
    /// or motion (Kovar's baseline).
    #[arg(long, default_value = "essential")]
    pub kind: GraphKind,
    /// Transitions kept per frame by --kind sparse-essential (default 64, chosen by `surfcap
    /// eval sparse-graph`).
    #[arg(long, value_parser = count)]
    pub k: Option<usize>,
    #[command(flatten)]
    pub alpha: AlphaOpt,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

impl GraphOpts {
    pub fn params(&self, fps: f64) -> anyhow::Result<GraphParams> {
        self.with_table(self.table.params(fps)?)
    }

    /// [`GraphOpts::params`] with segment bounds that fit these clips ([`TableOpts::params_for`]).
    pub fn params_for(&self, pipe: &surfcap_pipeline::Pipeline) -> anyhow::Result<GraphParams> {
        self.with_table(self.table.params_for(pipe)?)
    }

    fn with_table(&self, table: TableParams) -> anyhow::Result<GraphParams> {
        Ok(GraphParams { table, kind: self.kind.with_k(self.k)?, alpha: self.alpha.value() })
    }
}

/// Where an animation goes.
#[derive(clap::Args, Debug, Clone)]
pub struct OutOpts {
    /// Output: a .glb, .usda, .usdc or .abc file, or a folder for --format obj, ply, pc2 or npy. The JSON report is written
    /// beside it as <output>.report.json.
    #[arg(short, long)]
    pub output: PathBuf,
    /// glb, obj, ply, pc2, npy, usda, usdc or abc (default: from the output's extension, else glb); or
    /// rig-glb: a skinned character (bones and weights, as `surfcap rig` makes it) in a .glb.
    #[arg(long)]
    pub format: Option<ExportFormat>,
    #[command(flatten)]
    pub limits: crate::limits::LimitOpts,
    /// What the report calls a missed constraint.
    #[command(flatten)]
    pub constraints: ConstraintOpts,
}

/// How closely the soft constraints of a synthesis (path, key-pose times, reach distance and
/// time) must be met before they are reported as missed.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ConstraintOpts {
    /// A distance constraint (reach's distance, the path's largest centre-of-mass error) missed
    /// by more than this, in the subject's units, is reported as missed (default: 10% of the
    /// asked distance or of the curve's length).
    #[arg(long, value_parser = non_negative)]
    pub tolerance: Option<f64>,
    /// A timing constraint (a key pose's time, reach's duration) missed by more than this many
    /// frames is reported as missed (default: 10, Huang et al.'s timing scale).
    #[arg(long, value_parser = |s: &str| at_least(s, 0))]
    pub frame_tolerance: Option<usize>,
    /// Exit with code 3 when a constraint is missed (the animation and its report are written
    /// first).
    #[arg(long)]
    pub strict: bool,
}

impl ConstraintOpts {
    /// `--tolerance` and `--frame-tolerance` (`surfcap_synthesis::Tolerances` has the defaults).
    pub fn tolerances(&self) -> surfcap_synthesis::Tolerances {
        surfcap_synthesis::Tolerances { distance: self.tolerance, frames: self.frame_tolerance }
    }
}

impl OutOpts {
    /// Plans the animation (its sidecar when a file) and its report before any work, checked
    /// against `inputs` and the place rules (`surfcap_mesh::output_set`); commit it with
    /// [`crate::Ctx::commit`] once written.
    pub fn plan(&self, ctx: &crate::Ctx, inputs: &[&Path]) -> anyhow::Result<surfcap_mesh::output_set::OutputSet> {
        let mut set = surfcap_mesh::output_set::OutputSet::new(inputs);
        surfcap_synthesis::plan_animation_and_report(&mut set, self.format, &self.output, ctx.force)?;
        Ok(set)
    }

    pub fn format(&self) -> ExportFormat {
        output_format(self.format, &self.output)
    }
}

/// The format an animation is written in: `--format`, else the output's extension, else glb.
pub fn output_format(format: Option<ExportFormat>, output: &Path) -> ExportFormat {
    format.unwrap_or_else(|| {
        output.extension().and_then(|e| e.to_str()).and_then(ExportFormat::parse).unwrap_or(ExportFormat::Glb)
    })
}

/// Opens a subject (cache or any importable source) with a progress bar and shows the notes.
pub fn open(ctx: &crate::Ctx, path: &Path, opts: &SourceOpts) -> anyhow::Result<Subject> {
    record_input(path);
    let bar = crate::progress::Bar::new(ctx);
    let imported = surfcap_formats::import::open_subject(path, &opts.to_import(None)?, &bar)?;
    for n in &imported.notes {
        ctx.note(n);
    }
    Ok(imported.subject)
}

/// `--path source|sampled` of `vary sample` and `eval vary`: where a variant goes in the world
/// (surfcap_variation's `VariantPath`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PathArg(pub surfcap_variation::variation_sampling::VariantPath);

impl FromStr for PathArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        surfcap_variation::variation_sampling::VariantPath::parse(s)
            .map(PathArg)
            .ok_or_else(|| format!("{s:?}: expected source, contacts or sampled"))
    }
}

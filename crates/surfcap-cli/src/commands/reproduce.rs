//! `surfcap reproduce [--all | --figure 2.15 | --table huang-1 | --check root-motion ...] -o
//! repro/`: every table and figure of the thesis and the two papers beside the published values
//! (`surfcap_eval::published_values`, embedded in the program), and surfcap's own checks.
//!
//! The chosen items are grouped by the `surfcap eval` that reproduces them; each eval runs once,
//! in this process (the eval commands' own `run`, with their progress bars; what it prints, its
//! tables, is captured for the page), into its own folder `runs/<eval>/` (the eval's
//! all-or-nothing folder output), and a run record `runs/<eval>.run.json` (time, machine,
//! settings, printed text) is committed after it as the completion marker. An eval with paper
//! readings that have a switch (`READINGS`: eq. 2.6 in `eval pose-metric`, the DTW's first step
//! and normalisation in `eval transitions`, the essential graph's ties in `eval graphs`) runs
//! once more per other reading, into `runs/<eval>-<reading>/`, shown beside it. A run whose record is there
//! with the same settings is not redone (unless `--redo`); derived matrices go through the cache
//! as for the evals themselves. Then the page (`surfcap_eval::reproduce_report`): index.html,
//! results.json and results.csv, committed together, and with `--results-dir` the same tables
//! as markdown pages (`surfcap_eval::reproduce_markdown`). The output folder is surfcap's own
//! (its marker, kind `reproduce`); a folder surfcap did not write is refused, and so is a
//! markdown page it did not write.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use surfcap_eval::published_values::{PublishedCatalogue, PublishedItem};
use surfcap_eval::reproduce_markdown;
use surfcap_eval::reproduce_report::{
    EvalRun, Figure, Machine, Page, item_rows, results_csv, results_html, results_json,
};
use surfcap_mesh::output_set::{OutputSet, Stamped, is_own_side_file};

use crate::options::CacheOpts;
use crate::output::write_json;

/// The kind of the output folder's marker.
const KIND: &str = "reproduce";
/// The kind of a run record.
const RUN_KIND: &str = "reproduce-run";
/// Images of one run embedded in the page at most (the rest stay in its folder).
const MAX_FIGURES: usize = 24;
/// Largest image embedded, bytes.
const MAX_FIGURE_BYTES: u64 = 8 << 20;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Every item of the catalogue.
    #[arg(long, conflicts_with_all = ["figures", "tables", "checks"])]
    pub all: bool,
    /// Figures by number ("2.15"), source and number ("cvpr2017-3", "cvpr-3") or id; repeatable
    /// or comma-separated.
    #[arg(long = "figure", value_delimiter = ',')]
    pub figures: Vec<String>,
    /// Tables by number, source and number ("huang-1") or id; repeatable or comma-separated.
    #[arg(long = "table", value_delimiter = ',')]
    pub tables: Vec<String>,
    /// surfcap's own checks (no paper figure) by name: root-motion, interchange; repeatable or
    /// comma-separated.
    #[arg(long = "check", value_delimiter = ',')]
    pub checks: Vec<String>,
    /// Print the catalogue (items, their eval and how many published values) and stop.
    #[arg(long)]
    pub list: bool,
    /// Small settings for every eval (a check of the whole chain in minutes); the page says so.
    #[arg(long)]
    pub quick: bool,
    /// Run the chosen evals again even when their finished run is there (as does `--force`).
    #[arg(long)]
    pub redo: bool,
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the Vlasic crane, KayKit characters, CMU clips, ..."),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Folder for the page (index.html, results.json, results.csv) and the evals' outputs.
    #[arg(short, long, default_value = "repro")]
    pub output: PathBuf,
    /// Also write the page's tables as markdown into this folder (e.g. docs/results):
    /// reproduce.md (the index) and reproduce-<eval>.md per eval, each with this command. Only
    /// pages written by `surfcap reproduce` are replaced.
    #[arg(long, value_name = "DIR")]
    pub results_dir: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpts,
}

/// How one eval is run: its arguments after `surfcap eval <name>` (without `-o` and the cache
/// folder), whether it reads the cache, the report it writes, whether it needs the knight
/// subject (imported once into `subjects/`), its folder's name under `runs/`, and the paper
/// reading it uses when the page shows another beside it.
#[derive(Clone)]
struct Recipe {
    eval: &'static str,
    args: Vec<String>,
    cache: bool,
    report: &'static str,
    knight: bool,
    folder: String,
    reading: Option<&'static str>,
}

/// An eval's paper readings that change numbers and have a cheap switch (PAPER-NOTES): the
/// eval, the name of surfcap's readings (its default run), and per other reading the run
/// folder's suffix, the reading's name and the arguments that choose it.
type Readings = (&'static str, &'static str, &'static [(&'static str, &'static str, [&'static str; 2])]);

/// The readings shown beside surfcap's:
/// - eq. 2.6, the deformation gradient: surfcap's J = B A^-1, or A^-1 B as printed;
/// - eq. 2.53, the DTW's first step: surfcap lets up to p - 1 straight steps open the warping
///   path, the literal eq. 2.53 takes a diagonal step first;
/// - eq. 2.55, the DTW's normalised cost: surfcap's DP minimises the sum and divides by the
///   path length, the exact one finds the least ratio;
/// - eq. 3.2 and the essential graph's ties: surfcap adds a same-sequence edge only when
///   strictly cheaper than the original frames; read literally every forward pair has one, and
///   one tying with the original frames is kept.
const READINGS: [Readings; 3] = [
    (
        "pose-metric",
        "surfcap's reading of eq. 2.6, J = B A^-1",
        &[("literal", "eq. 2.6 read literally, A^-1 B", ["--deformation-gradient", "literal"])],
    ),
    (
        "transitions",
        "surfcap's readings of eq. 2.53 and 2.55",
        &[
            ("literal", "eq. 2.53 read literally", ["--dtw-first-step", "literal"]),
            ("exact-ratio", "eq. 2.55's least ratio found exactly", ["--dtw-ratio", "exact"]),
        ],
    ),
    (
        "graphs",
        "surfcap's reading of eq. 3.2 and its tie rule",
        &[("literal-ties", "eq. 3.2 read literally, ties to the direct edge", ["--tie-rule", "literal"])],
    ),
];

/// The recipe of `eval` and those of its other readings ([`READINGS`]).
fn recipes(eval: &str, data: &Path, knight: &Path, quick: bool) -> Option<(Recipe, Vec<Recipe>)> {
    let mut main = recipe(eval, data, knight, quick)?;
    let mut others = Vec::new();
    for (e, ours, alternatives) in READINGS {
        if e == eval {
            main.reading = Some(ours);
            for (suffix, other, args) in alternatives {
                let mut alt = main.clone();
                alt.args.extend(args.iter().map(|a| a.to_string()));
                alt.folder = format!("{eval}-{suffix}");
                alt.reading = Some(other);
                others.push(alt);
            }
        }
    }
    Some((main, others))
}

/// The BVH clips of `eval root-motion`: every .bvh in the data's cmu_bvh, sorted (the folder
/// itself when it holds none, so that the eval names it in its error).
fn cmu_clips(data: &Path) -> Vec<String> {
    let dir = data.join("cmu_bvh");
    let mut v: Vec<String> = std::fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("bvh")))
                .map(|p| p.display().to_string())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    if v.is_empty() {
        v.push(dir.display().to_string());
    }
    v
}

/// The KayKit knight's clips of the pose-metric subject (ground-truth joints).
const KNIGHT_CLIPS: [&str; 4] = ["knight_Idle", "knight_Running_A", "knight_Jump_Full_Short", "knight_Cheer"];

fn recipe(eval: &str, data: &Path, knight: &Path, quick: bool) -> Option<Recipe> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let d = data.display().to_string();
    let crane = data.join("vlasic2008/crane").display().to_string();
    let (eval, mut args, extra, cache, report, needs_knight): (&str, Vec<String>, Vec<String>, bool, &str, bool) =
        match eval {
            "interpolation" => (
                "interpolation",
                s(&[&crane, "--pair", "crane:0,crane:120"]),
                vec![],
                false,
                "interpolation.json",
                false,
            ),
            "transitions" => ("transitions", s(&[&crane]), s(&["--plot-pairs", "20"]), true, "transitions.json", false),
            "graphs" => {
                ("graphs", s(&[&crane]), s(&["--alpha", "0.05,0.1", "--plot-pairs", "20"]), true, "graphs.json", false)
            }
            "gpdm" => (
                "gpdm",
                s(&[&crane]),
                s(&["--max-frames", "60", "--vertices", "100", "--iterations", "20", "--samples", "1"]),
                false,
                "gpdm.json",
                false,
            ),
            "pose-metric" => (
                "pose-metric",
                s(&[&knight.display().to_string()]),
                s(&["--max-frames", "60", "--permutations", "500", "--classes", "5"]),
                true,
                "pose-metric.json",
                true,
            ),
            "transfer" => (
                "transfer",
                s(&["--data", &d]),
                // Case 0 is the forward knight -> barbarian case with or without `--quick`
                // (the published pointers read /cases/0); two sizes for their point 1.
                s(&["--cases", "barbarian", "--direction", "forward", "--sizes", "5,10", "--components", "3"]),
                false,
                "transfer.json",
                false,
            ),
            "smg" => (
                "smg",
                s(&["--data", &d]),
                s(&["--vertices", "1000", "--distances", "5,10", "--seconds", "5,10", "--no-compare"]),
                true,
                "smg.json",
                false,
            ),
            "sparse-graph" => (
                "sparse-graph",
                s(&["--data", &d]),
                s(&["--fps", "25", "--k", "2,8"]),
                true,
                "sparse-graph.json",
                false,
            ),
            "appearance" => (
                "appearance",
                s(&["--data", &d]),
                s(&[
                    "--frames",
                    "12",
                    "--size",
                    "64",
                    "--components",
                    "3,6",
                    "--held-out",
                    "0,0.2",
                    "--image-frames",
                    "3",
                    "--views",
                    "2",
                    "--image-size",
                    "64",
                ]),
                true,
                "appearance.json",
                false,
            ),
            "vary" => (
                "vary",
                s(&["--data", &d]),
                s(&[
                    "--only",
                    "cmu",
                    "--cmu-clips",
                    "16_15,16_36",
                    "--variants",
                    "2",
                    "--iterations",
                    "20",
                    "--vertices",
                    "1000",
                ]),
                false,
                "vary.json",
                false,
            ),
            "root-motion" => {
                let mut bvh = s(&["--bvh"]);
                bvh.extend(cmu_clips(data));
                ("root-motion", bvh, s(&["--vertices", "1000"]), false, "root-motion.json", false)
            }
            "interchange" => (
                "interchange",
                s(&["--data", &d]),
                s(&["--datasets", "walking_cat_depraz,threejs_morph_animals"]),
                false,
                "interchange.json",
                false,
            ),
            _ => return None,
        };
    if quick {
        args.extend(extra);
    }
    Some(Recipe { eval, args, cache, report, knight: needs_knight, folder: eval.to_string(), reading: None })
}

/// `surfcap eval <name> ...` parsed in-process.
#[derive(Parser, Debug)]
#[command(name = "surfcap eval", no_binary_name = true)]
struct EvalLine {
    #[command(subcommand)]
    what: super::eval::What,
}

/// A run record: what ran, how long it took and where.
#[derive(serde::Serialize, serde::Deserialize)]
struct RunRecord {
    eval: String,
    args: Vec<String>,
    quick: bool,
    seconds: f64,
    machine: Machine,
    /// What the eval reported as missed after writing its report (e.g. `eval vary`'s criteria).
    error: Option<String>,
    /// What the eval printed (its tables); absent in records of earlier versions.
    #[serde(default)]
    printed: Option<String>,
}

/// This machine: cores, CPU model (/proc/cpuinfo) and memory (/proc/meminfo).
fn machine() -> Machine {
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let memory_bytes = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal:"))?.to_string();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .map_or(0, |kb| kb * 1024);
    Machine { cores, cpu, memory_bytes }
}

fn progress(ctx: &crate::Ctx, text: &str) {
    if !ctx.quiet && !ctx.json {
        eprintln!("{text}");
    }
}

fn elapsed(s: f64) -> String {
    format!("{}:{:02}", (s / 60.0) as u64, (s as u64) % 60)
}

fn print_list(cat: &PublishedCatalogue) {
    println!("{:<24} {:<7} {:<7} {:<14} {:>6}  title", "id", "kind", "number", "eval", "values");
    for it in &cat.items {
        println!(
            "{:<24} {:<7} {:<7} {:<14} {:>6}  {}",
            it.id,
            it.kind.as_str(),
            it.number,
            if it.eval.is_empty() { "-" } else { &it.eval },
            cat.values_of(&it.id).count(),
            it.title
        );
    }
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let cat = PublishedCatalogue::load_builtin()?;
    if a.list {
        if ctx.json {
            crate::output::print_json(&cat);
        } else {
            print_list(&cat);
        }
        return Ok(());
    }
    if !a.all && a.figures.is_empty() && a.tables.is_empty() && a.checks.is_empty() {
        anyhow::bail!(
            "choose the items: --all, --figure NUMBER, --table NUMBER or --check NAME (`surfcap reproduce --list` shows them)"
        );
    }
    let items = cat.select(a.all, &a.figures, &a.tables, &a.checks)?;
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.data])?;
    if let Some(dir) = &a.results_dir {
        surfcap_mesh::output_path::check_not_input(dir, &[&a.data])?;
        check_results_dir(dir)?;
    }
    let out = surfcap_mesh::output_path::claim_dir(&a.output, KIND, false)?;
    let runs_dir = out.join("runs");
    let knight = out.join("subjects/knight.subject");
    let redo = a.redo || ctx.force;
    let here = machine();
    // The evals to run, in the order of their first item.
    let mut evals: Vec<(&str, Vec<&PublishedItem>)> = Vec::new();
    for it in items.iter().copied() {
        if it.eval.is_empty() {
            continue;
        }
        match evals.iter_mut().find(|(e, _)| *e == it.eval) {
            Some((_, v)) => v.push(it),
            None => evals.push((&it.eval, vec![it])),
        }
    }
    let n = evals.len();
    let start = Instant::now();
    let mut runs: BTreeMap<String, EvalRun> = BTreeMap::new();
    let mut failed: Vec<String> = Vec::new();
    let step = Step {
        ctx,
        runs_dir: &runs_dir,
        knight: &knight,
        data: &a.data,
        cache: &a.cache,
        quick: a.quick,
        redo,
        here: &here,
        start,
    };
    for (k, (eval, its)) in evals.iter().enumerate() {
        let names: Vec<&str> = its.iter().map(|i| i.id.as_str()).collect();
        let Some((main, others)) = recipes(eval, &a.data, &knight, a.quick) else {
            progress(
                ctx,
                &format!("[{}/{n}] eval {eval} ({}): not known to surfcap reproduce", k + 1, names.join(", ")),
            );
            continue;
        };
        let label = |r: &Recipe| match r.reading {
            Some(x) if r.folder != r.eval => format!("[{}/{n}] eval {eval} ({}; {x})", k + 1, names.join(", ")),
            _ => format!("[{}/{n}] eval {eval} ({})", k + 1, names.join(", ")),
        };
        let mut run = step.run(&main, &label(&main), &mut failed)?;
        for alt in &others {
            let other = step.run(alt, &label(alt), &mut failed)?;
            run.alternates.push(other);
        }
        runs.insert(eval.to_string(), run);
    }
    let page = Page { quick: a.quick, machine: here, items: item_rows(&cat, &items, &runs), runs };
    let mut set = OutputSet::new(&[&a.data]);
    let html = set.file(&out.join("index.html"))?;
    let json = set.file(&out.join("results.json"))?;
    let csv = set.file(&out.join("results.csv"))?;
    let pages = match &a.results_dir {
        Some(dir) => {
            check_results_dir(dir)?;
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            let mut v = Vec::new();
            for (name, md) in reproduce_markdown::results_markdown(&page, &command_line()) {
                v.push((set.file(&dir.join(&name))?, md));
            }
            v
        }
        None => Vec::new(),
    };
    surfcap_mesh::atomic::write_file(&html, |w| w.write_all(results_html(&page).as_bytes()))?;
    let results = results_json(&page);
    write_json(&json, &results)?;
    surfcap_mesh::atomic::write_file(&csv, |w| w.write_all(results_csv(&page).as_bytes()))?;
    for (path, md) in &pages {
        surfcap_mesh::atomic::write_file(path, |w| w.write_all(md.as_bytes()))?;
    }
    ctx.commit(set)?;
    let index = out.join("index.html");
    let written: Vec<&PathBuf> = pages.iter().map(|(p, _)| p).collect();
    ctx.result(
        &serde_json::json!({ "page": index, "counts": results["counts"], "failed": failed, "results_pages": written }),
        || {
            let c = &results["counts"];
            println!(
                "{} items: {} reproduced, {} better, {} differs, {} not measured{}",
                page.items.len(),
                c["reproduced"],
                c["better"],
                c["differs"],
                c["not measured"],
                if a.quick { " (quick mode)" } else { "" }
            );
            println!("wrote {}, results.json, results.csv", index.display());
            for p in &written {
                println!("wrote {}", p.display());
            }
        },
    );
    if !failed.is_empty() {
        anyhow::bail!(
            "{} of {n} evals failed (the page shows their items as not measured): {}",
            failed.len(),
            failed.join("; ")
        );
    }
    Ok(())
}

/// Refuses a results folder holding a page `surfcap reproduce` would replace but did not write
/// (a hand-written reproduce.md or reproduce-<eval>.md), naming it.
fn check_results_dir(dir: &Path) -> anyhow::Result<()> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Ok(()) };
    for e in rd.filter_map(|e| e.ok()) {
        let name = e.file_name().to_string_lossy().to_string();
        let ours = name == reproduce_markdown::INDEX || (name.starts_with("reproduce-") && name.ends_with(".md"));
        if ours {
            let text = std::fs::read_to_string(e.path()).unwrap_or_default();
            if !reproduce_markdown::is_own_page(&text) {
                anyhow::bail!(
                    "{}: not written by surfcap reproduce (its first line is not the marker \"{}\"); \
                     move it away or choose another --results-dir",
                    e.path().display(),
                    reproduce_markdown::MARKER
                );
            }
        }
    }
    Ok(())
}

/// This command as typed (program name `surfcap`), for the markdown pages.
fn command_line() -> String {
    let mut parts = vec!["surfcap".to_string()];
    for a in std::env::args().skip(1) {
        if a.is_empty() || a.contains(|c: char| c.is_whitespace() || "'\"$`\\*?;&|<>()".contains(c)) {
            parts.push(format!("'{}'", a.replace('\'', "'\\''")));
        } else {
            parts.push(a);
        }
    }
    parts.join(" ")
}

/// What every run of one `surfcap reproduce` shares.
struct Step<'a> {
    ctx: &'a crate::Ctx,
    runs_dir: &'a Path,
    knight: &'a Path,
    data: &'a Path,
    cache: &'a CacheOpts,
    quick: bool,
    redo: bool,
    here: &'a Machine,
    start: Instant,
}

impl Step<'_> {
    /// Runs one recipe into `runs/<folder>/` (or keeps its finished run) and reads its outputs;
    /// a failure is added to `failed` and shown on the page.
    fn run(&self, r: &Recipe, label: &str, failed: &mut Vec<String>) -> anyhow::Result<EvalRun> {
        let ctx = self.ctx;
        let folder = self.runs_dir.join(&r.folder);
        let record_path = self.runs_dir.join(format!("{}.run.json", r.folder));
        let mut run = EvalRun {
            eval: r.eval.into(),
            args: r.args.clone(),
            folder: format!("runs/{}", r.folder),
            reading: r.reading.map(str::to_string),
            ..Default::default()
        };
        let done = (!self.redo).then(|| finished(&record_path, &folder, r, self.quick)).flatten();
        if let Some(rec) = done {
            progress(ctx, &format!("{label}: finished earlier in {:.1} s, kept (--redo runs it again)", rec.seconds));
            run.seconds = Some(rec.seconds);
            run.machine = Some(rec.machine);
            run.error = rec.error;
            run.printed = rec.printed;
        } else {
            progress(ctx, &format!("{label}: running, {} elapsed", elapsed(self.start.elapsed().as_secs_f64())));
            let t0 = Instant::now();
            let (result, printed) = captured_stdout(|| {
                if r.knight && !self.knight.join("subject.json").is_file() {
                    import_knight(ctx, self.data, self.knight)?;
                }
                run_eval(ctx, r, &folder, self.cache)
            });
            let seconds = t0.elapsed().as_secs_f64();
            let report_written = surfcap_mesh::output_path::has_marker(&folder) && folder.join(r.report).is_file();
            let error = result.err().map(|e| crate::messages(&e).join(": "));
            if report_written && (error.is_none() || fresh(&folder, r.report, t0)) {
                let rec = RunRecord {
                    eval: r.eval.into(),
                    args: r.args.clone(),
                    quick: self.quick,
                    seconds,
                    machine: self.here.clone(),
                    error: error.clone(),
                    printed: printed.clone(),
                };
                let mut set = OutputSet::new(&[]);
                let p = set.side_file(&record_path, RUN_KIND)?;
                write_json(&p, &Stamped::new(RUN_KIND, &rec))?;
                ctx.commit(set)?;
                run.seconds = Some(seconds);
                run.machine = Some(self.here.clone());
                run.error = error.clone();
                run.printed = printed;
                progress(
                    ctx,
                    &format!(
                        "{label}: done in {seconds:.1} s{}",
                        error.as_ref().map(|e| format!(" (it reported: {e})")).unwrap_or_default()
                    ),
                );
            } else {
                let e = error.unwrap_or_else(|| format!("{} was not written", r.report));
                progress(ctx, &format!("{label}: failed after {seconds:.1} s: {e}"));
                failed.push(format!("eval {} ({}): {e}", r.eval, run.folder));
                run.error = Some(e);
            }
        }
        if run.error.is_none() || folder.join(r.report).is_file() {
            load_outputs(&mut run, &folder, r.report)?;
        }
        Ok(run)
    }
}

/// Runs `f` with this process's standard output going to a temporary file, and returns what
/// was printed (None when the redirection could not be set up: then `f` prints as usual).
/// The evals print their tables with `println!`; the page shows them.
fn captured_stdout<T>(f: impl FnOnce() -> T) -> (T, Option<String>) {
    use std::io::{Read, Seek, Write};
    use std::os::fd::AsRawFd;
    let Ok(mut file) = tempfile::tempfile() else { return (f(), None) };
    let _ = std::io::stdout().flush();
    // SAFETY: plain descriptor calls on descriptors this function owns (the duplicate of 1 and
    // the temporary file, which outlives the redirection); 1 is restored before returning.
    let saved = unsafe { libc::dup(1) };
    if saved < 0 || unsafe { libc::dup2(file.as_raw_fd(), 1) } < 0 {
        if saved >= 0 {
            unsafe { libc::close(saved) };
        }
        return (f(), None);
    }
    let out = f();
    let _ = std::io::stdout().flush();
    unsafe {
        libc::dup2(saved, 1);
        libc::close(saved);
    }
    let mut text = String::new();
    let read = file.seek(std::io::SeekFrom::Start(0)).is_ok() && file.read_to_string(&mut text).is_ok();
    (out, read.then_some(text))
}

/// Whether the report in `folder` was written by this run (not left by an earlier one).
fn fresh(folder: &Path, report: &str, since: Instant) -> bool {
    let age = since.elapsed();
    std::fs::metadata(folder.join(report))
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|a| a <= age)
}

/// The run record at `path`, when it is surfcap's, its eval's folder is complete and it ran
/// with the same settings.
fn finished(path: &Path, folder: &Path, r: &Recipe, quick: bool) -> Option<RunRecord> {
    if !is_own_side_file(path, RUN_KIND) || !surfcap_mesh::output_path::has_marker(folder) {
        return None;
    }
    let rec: RunRecord = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
    (rec.eval == r.eval && rec.args == r.args && rec.quick == quick && folder.join(r.report).is_file()).then_some(rec)
}

/// Runs `surfcap eval <r.eval> <r.args> -o folder [--cache-dir ...]` in this process: progress
/// bars and notes as usual, its printed tables on standard output (captured for the page).
fn run_eval(ctx: &crate::Ctx, r: &Recipe, folder: &Path, cache: &CacheOpts) -> anyhow::Result<()> {
    let mut line: Vec<String> = vec![r.eval.into()];
    line.extend(r.args.iter().cloned());
    line.extend(["-o".into(), folder.display().to_string()]);
    if r.cache {
        if let Some(c) = &cache.cache_dir {
            line.extend(["--cache-dir".into(), c.display().to_string()]);
        }
        if cache.no_cache {
            line.push("--no-cache".into());
        }
    }
    let parsed = EvalLine::try_parse_from(&line).with_context(|| format!("surfcap eval {}", line.join(" ")))?;
    let inner = crate::Ctx { results: true, json: false, quiet: ctx.quiet || ctx.json, force: false, ..*ctx };
    super::eval::run(&inner, super::eval::Args { what: parsed.what })
}

/// Imports the knight's clips (`KNIGHT_CLIPS`) as the pose-metric subject.
fn import_knight(ctx: &crate::Ctx, data: &Path, knight: &Path) -> anyhow::Result<()> {
    #[derive(Parser)]
    #[command(no_binary_name = true)]
    struct ImportLine {
        #[command(flatten)]
        a: super::import::Args,
    }
    let k = data.join("kaykit_adventurers");
    let mut line: Vec<String> = KNIGHT_CLIPS.iter().map(|c| k.join(c).display().to_string()).collect();
    line.extend(["-o".into(), knight.display().to_string(), "--name".into(), "knight".into()]);
    let parsed = ImportLine::try_parse_from(&line).context("importing the knight")?;
    let inner = crate::Ctx { results: false, json: false, quiet: ctx.quiet || ctx.json, force: false, ..*ctx };
    super::import::run(&inner, parsed.a)
}

/// Reads a finished run's report and images into `run`.
fn load_outputs(run: &mut EvalRun, folder: &Path, report: &str) -> anyhow::Result<()> {
    let path = folder.join(report);
    let text = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
    run.report = Some(serde_json::from_slice(&text).with_context(|| format!("{}: not JSON", path.display()))?);
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in std::iter::once(folder.to_path_buf()).chain(subfolders(folder)) {
        if let Ok(rd) = std::fs::read_dir(&dir) {
            files.extend(rd.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_file()));
        }
    }
    files.sort();
    let images: Vec<PathBuf> = files
        .into_iter()
        .filter(|p| {
            let n = p.to_string_lossy().to_ascii_lowercase();
            n.ends_with(".svg") || n.ends_with(".png") || n.ends_with(".jpg")
        })
        .collect();
    let mut figures = Vec::new();
    for p in images {
        let name = p.strip_prefix(folder).unwrap_or(&p).display().to_string();
        if std::fs::metadata(&p).map(|m| m.len()).unwrap_or(u64::MAX) > MAX_FIGURE_BYTES {
            continue;
        }
        figures.push(Figure { name, bytes: std::fs::read(&p).with_context(|| format!("reading {}", p.display()))? });
    }
    let shown = surfcap_eval::reproduce_report::shown_figures(&figures).len();
    if shown > MAX_FIGURES {
        let keep: Vec<String> = surfcap_eval::reproduce_report::shown_figures(&figures)
            .iter()
            .take(MAX_FIGURES)
            .map(|f| f.name.clone())
            .collect();
        figures.retain(|f| keep.contains(&f.name));
    }
    run.figures = figures;
    Ok(())
}

fn subfolders(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_dir()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

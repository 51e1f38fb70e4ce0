//! The HTML report (`surfcap report`, `demo`): one static HTML page (opens from disk, no server) gathering what exists
//! for a subject: its summary, the cached pose-distance matrix as a heat map, the cached
//! transition table's statistics, and the evaluation outputs and animations given with
//! `--include` (eval folders with their JSON tables and plots, synthesised .glb files with their
//! reports and per-frame error curves). `surfcap view <dir>` plays its animations.
//!
//! Laid out to be read, not scrolled: every heat map carries its colour bar (surfcap-plot), the
//! animations' per-frame path errors share one chart (one line per animation) instead of one
//! near-identical chart each, included plots sit in a grid grouped by the folder they came
//! from, and tables scroll sideways inside their own box (long words wrap) rather than
//! widening the page.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde_json::Value;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_mesh::FrameLabel;

use surfcap_pipeline::Pipeline;
use surfcap_pipeline::product_key::DistanceKey;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn num(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_f64() {
            Some(x) if x.fract() != 0.0 => format!("{x:.4}"),
            _ => n.to_string(),
        },
        Value::String(s) => esc(s),
        Value::Bool(b) => b.to_string(),
        Value::Null => "-".into(),
        _ => esc(&v.to_string()),
    }
}

/// Flattens nested objects into `a.b` keys (arrays are left out).
fn flatten(prefix: &str, v: &Value, out: &mut Vec<(String, Value)>) {
    if let Value::Object(m) = v {
        for (k, x) in m {
            let key = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
            match x {
                Value::Object(_) => flatten(&key, x, out),
                Value::Array(_) => {}
                _ => out.push((key, x.clone())),
            }
        }
    }
}

/// A JSON evaluation as HTML: its scalars, then its `rows` (if any) as a table.
fn json_section(title: &str, v: &Value) -> String {
    let mut h = if title.is_empty() { String::new() } else { format!("<h3>{}</h3>\n", esc(title)) };
    let mut scalars = Vec::new();
    flatten("", v, &mut scalars);
    if !scalars.is_empty() {
        h += "<table>";
        for (k, x) in &scalars {
            let _ = write!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(k), num(x));
        }
        h += "</table>\n";
    }
    if let Some(rows) = v["rows"].as_array().filter(|r| !r.is_empty()) {
        let flat: Vec<Vec<(String, Value)>> = rows
            .iter()
            .map(|r| {
                let mut o = Vec::new();
                flatten("", r, &mut o);
                o
            })
            .collect();
        h += "<table><tr>";
        for (k, _) in &flat[0] {
            let _ = write!(h, "<th>{}</th>", esc(k));
        }
        h += "</tr>";
        for r in &flat {
            h += "<tr>";
            for (_, x) in r {
                let _ = write!(h, "<td>{}</td>", num(x));
            }
            h += "</tr>";
        }
        h += "</table>\n";
    }
    h
}

/// Files under `p` (or `p` itself) with the report's extensions, sorted.
fn files_of(p: &Path) -> anyhow::Result<Vec<PathBuf>> {
    anyhow::ensure!(p.exists(), "--include {}: no such file or folder", p.display());
    let shown = ["json", "svg", "png", "glb"];
    if p.is_file() {
        // A file named on its own is shown or refused, never silently left out.
        let ext = p.extension().and_then(|x| x.to_str()).map(str::to_ascii_lowercase);
        anyhow::ensure!(
            ext.as_deref().is_some_and(|x| shown.contains(&x)),
            "--include {}: the report shows .json tables, .svg or .png plots and .glb animations (or the folders that hold them)",
            p.display()
        );
        return Ok(vec![p.to_path_buf()]);
    }
    crate::files::files_under(p, &shown)
}

/// A unique name inside `dir` for `file` (`name`, `name-2`, ...).
fn unique(dir: &Path, file: &Path) -> PathBuf {
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "file".into());
    let ext = file.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut k = 1;
    loop {
        let name = if k == 1 { format!("{stem}.{ext}") } else { format!("{stem}-{k}.{ext}") };
        if !dir.join(&name).exists() {
            return dir.join(name);
        }
        k += 1;
    }
}

/// Copies `file` into `dir` (in the report folder's temporary while the report is built);
/// returns the copy's final path.
fn copy_into(dir: &Path, file: &Path) -> anyhow::Result<PathBuf> {
    let place = surfcap_mesh::output_set::write_place(dir);
    std::fs::create_dir_all(&place).with_context(|| format!("creating {}", dir.display()))?;
    let to = unique(&place, file);
    std::fs::copy(file, &to).with_context(|| format!("copying {} to {}", file.display(), to.display()))?;
    Ok(to.file_name().map_or(to.clone(), |n| dir.join(n)))
}

fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).to_string_lossy().replace('\\', "/")
}

/// Written into every report's page: how a later run knows the folder is a report it may replace.
const REPORT_MARK: &str = "<meta name=\"generator\" content=\"surfcap report\">";

/// What a report holds, for the caller's message.
pub struct Written {
    pub index: PathBuf,
    pub plots: usize,
    pub animations: usize,
    pub tables: usize,
}

/// Whether `out` holds a report surfcap wrote before its folders had a marker (its page names
/// surfcap as generator).
pub fn is_earlier_report(out: &Path) -> bool {
    std::fs::read_to_string(out.join("index.html")).is_ok_and(|h| h.contains(REPORT_MARK))
}

/// Writes the report of `s` into `out`, replacing an earlier report there; any other non-empty
/// folder is refused unless `force` (then the new report is written among its files).
pub fn write_report(
    pipe: &Pipeline,
    source: &Path,
    out: &Path,
    include: &[PathBuf],
    force: bool,
) -> anyhow::Result<Written> {
    let s = pipe.subject();
    let mut files = Vec::new();
    for p in include {
        files.extend(files_of(p)?);
    }
    // An earlier report in `out` (marked, or older than the marker: its page names surfcap as
    // generator) is replaced whole, never mixed with the new one; any other non-empty folder is
    // refused unless `force`.
    let unmarked_report = is_earlier_report(out);
    let old_report = unmarked_report || surfcap_mesh::output_path::is_output_of(out, "report");
    surfcap_mesh::output_path::claim_dir(out, "report", force || unmarked_report)?;
    // Built in place (not planned in an output set, as inside the demo's folder): an earlier
    // report's files go first.
    if old_report && !surfcap_mesh::output_set::is_planned(out) {
        for sub in ["plots", "anim", "data"] {
            let _ = std::fs::remove_dir_all(out.join(sub));
        }
    }
    let (plots_dir, anim_dir, data_dir) = (out.join("plots"), out.join("anim"), out.join("data"));
    let mut body = String::new();
    let (mut n_plots, mut n_anim, mut n_tables) = (0, 0, 0);

    // Summary.
    let _ = writeln!(
        body,
        "<h2>Subject</h2><table><tr><th>source</th><td>{}</td></tr><tr><th>frames</th><td>{}</td></tr><tr><th>vertices</th><td>{}</td></tr><tr><th>triangles</th><td>{}</td></tr><tr><th>fps</th><td>{}</td></tr><tr><th>up axis</th><td>{}</td></tr></table>",
        esc(&source.display().to_string()),
        s.n_frames(),
        s.topology().n_vertices(),
        s.topology().triangles().len(),
        s.fps,
        s.up_axis.as_str()
    );
    body += "<table><tr><th>sequence</th><th>frames</th><th>seconds</th><th>synthetic frames</th><th>tags</th></tr>";
    for q in s.sequences() {
        let synthetic = q.labels.iter().filter(|l| **l == FrameLabel::Synthetic).count();
        let _ = write!(
            body,
            "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{synthetic}</td><td>{}</td></tr>",
            esc(&q.name),
            q.n_frames(),
            q.n_frames() as f64 / s.fps,
            esc(&q.tags.join(", "))
        );
    }
    body += "</table>\n";

    // The cached distance matrix, if any.
    body += "<h2>Pose distances (thesis eq. 2.13)</h2>\n";
    let dpath = pipe.cache_file(&DistanceKey::new(&DistanceParams::default())).unwrap_or_default();
    match surfcap_mesh::npy::read_npy::<f64>(&dpath) {
        Ok(d)
            if d.shape == [s.n_frames(), s.n_frames()]
                && surfcap_motion::transition_table::check_distances(&d.data, s.frame_index()).is_ok() =>
        {
            let n = s.n_frames();
            let heat = surfcap_plot::HeatMap {
                title: format!("{}: deformation distance between every pair of frames", s.name),
                x_label: "frame".into(),
                y_label: "frame".into(),
                values: d.data,
                rows: n,
                cols: n,
                origin: (0, 0),
                range: None,
                path: Vec::new(),
                value_label: "deformation distance".into(),
            };
            let written = surfcap_plot::write_heat_map(&plots_dir.join("distances"), &heat)?;
            n_plots += 1;
            let _ = writeln!(
                body,
                "<p>From the cache ({}).</p><img src=\"{}\" alt=\"distance matrix\">",
                esc(&dpath.display().to_string()),
                rel(out, &written[0])
            );
        }
        _ => {
            body += "<p>Not computed yet: <code>surfcap distance SUBJECT -o d.npy</code> computes and caches it.</p>\n";
        }
    }

    // Included evaluations and animations.
    let (mut tables, mut anims) = (String::new(), String::new());
    // Included plots by the folder they came from (an eval's output), in the order met.
    let mut images: Vec<(String, String)> = Vec::new();
    // Each animation's per-frame distance from its requested path: one chart for all.
    let mut error_series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for f in &files {
        let name = f.display().to_string();
        match f.extension().and_then(|x| x.to_str()) {
            Some("glb") => {
                let to = copy_into(&anim_dir, f)?;
                let mut row = format!(
                    "<div class=\"card\"><h3>{}</h3><p><a href=\"{}\">{}</a>",
                    esc(&name),
                    rel(out, &to),
                    rel(out, &to)
                );
                // The synthesis report and the labels sidecar travel with the animation.
                let report = surfcap_synthesis::report_path(f);
                let to_stem = to.file_stem().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default();
                for (side, suffix) in [(report.clone(), ".report.json"), (f.with_extension("json"), ".json")] {
                    if side.is_file() {
                        let dest = to.with_file_name(format!("{to_stem}{suffix}"));
                        std::fs::copy(&side, surfcap_mesh::output_set::write_place(&dest))
                            .with_context(|| format!("copying {}", side.display()))?;
                    }
                }
                row += "</p>";
                let parsed = std::fs::read(&report).ok().and_then(|b| serde_json::from_slice::<Value>(&b).ok());
                if let Some(v) = parsed {
                    // The report's numbers folded away (they are many); its per-frame error
                    // joins the shared chart below.
                    let _ =
                        write!(row, "<details><summary>synthesis report</summary>{}</details>", json_section("", &v));
                    if let Some(errors) = v["per_frame"]["error"].as_array() {
                        let pts: Vec<(f64, f64)> =
                            errors.iter().enumerate().filter_map(|(k, e)| Some((k as f64, e.as_f64()?))).collect();
                        let name = to.file_name().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default();
                        error_series.push((name, pts));
                    }
                }
                row += "</div>";
                anims += &row;
                n_anim += 1;
            }
            Some("json")
                if files.contains(&f.with_extension("glb"))
                    || (f.to_string_lossy().ends_with(".report.json")
                        && files.contains(&f.with_extension("").with_extension("glb"))) =>
            {
                // A glb's labels sidecar or synthesis report, when the glb is included too:
                // shown with its animation.
            }
            Some("json") => {
                let v: Value = serde_json::from_slice(&std::fs::read(f).with_context(|| format!("reading {name}"))?)
                    .with_context(|| format!("{name}: not JSON"))?;
                let to = copy_into(&data_dir, f)?;
                tables += &json_section(&name, &v);
                let _ = writeln!(tables, "<p><a href=\"{}\">{}</a></p>", rel(out, &to), rel(out, &to));
                n_tables += 1;
            }
            // A plot: its SVG when that is included too, else its PNG (`--include t-dtw.png`
            // beside a t-dtw.svg shows the PNG asked for).
            Some(ext @ ("svg" | "png")) if ext == "svg" || !files.contains(&f.with_extension("svg")) => {
                let to = copy_into(&plots_dir, f)?;
                let folder = f.parent().map(|d| d.display().to_string()).unwrap_or_default();
                let file = f.file_name().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default();
                let figure = format!(
                    "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{2}</figcaption></figure>\n",
                    rel(out, &to),
                    esc(&name),
                    esc(&file)
                );
                match images.iter_mut().find(|(d, _)| *d == folder) {
                    Some((_, figures)) => *figures += &figure,
                    None => images.push((folder, figure)),
                }
                n_plots += 1;
            }
            _ => {}
        }
    }
    body += "<h2>Evaluations</h2>\n";
    if tables.is_empty() && images.is_empty() {
        body += "<p>None included: <code>surfcap report SUBJECT -o DIR --include EVAL_DIR</code> adds the outputs of <code>surfcap eval ...</code>.</p>\n";
    }
    body += &tables;
    for (folder, figures) in &images {
        let _ = write!(body, "<h3>Plots of {}</h3>\n<div class=\"plots\">\n{figures}</div>\n", esc(folder));
    }
    body += "<h2>Animations</h2>\n";
    if anims.is_empty() {
        body += "<p>None included (<code>--include x.glb</code>).</p>\n";
    } else {
        let _ = writeln!(
            body,
            "<p>Play them in the browser, original frames green and synthetic red, paths overlaid: <code>surfcap view {}</code> (this page is then at <code>/report/index.html</code>; <a href=\"../../\">the viewer</a> when served).</p>",
            esc(&out.display().to_string())
        );
        if !error_series.is_empty() {
            const COLOURS: [(u8, u8, u8); 6] =
                [(220, 60, 30), (30, 110, 200), (40, 150, 60), (160, 60, 170), (200, 150, 20), (60, 60, 60)];
            let chart = surfcap_plot::LineChart {
                title: "distance from the requested path, per frame".into(),
                x_label: "output frame".into(),
                y_label: format!("centre error ({})", surfcap_synthesis::words::unit_name(&s.units)),
                series: error_series
                    .iter()
                    .enumerate()
                    .map(|(k, (name, points))| surfcap_plot::Series {
                        name: name.clone(),
                        points: points.clone(),
                        color: COLOURS[k % COLOURS.len()],
                        dashed: k >= COLOURS.len(),
                        markers: false,
                    })
                    .collect(),
            };
            let w = surfcap_plot::write_line_chart(&plots_dir.join("path-errors"), &chart)?;
            n_plots += 1;
            let _ =
                writeln!(body, "<figure><img class=\"wide\" src=\"{}\" alt=\"path errors\"></figure>", rel(out, &w[0]));
        }
        let _ = writeln!(body, "<div class=\"plots\">\n{anims}</div>");
    }
    let html = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">{REPORT_MARK}<title>surfcap report: {name}</title>\n<style>\nbody {{ font: 14px system-ui, sans-serif; max-width: 60em; margin: 2em auto; color: #222; }}\ntable {{ border-collapse: collapse; margin: 0.5em 0; display: block; max-width: 100%; overflow-x: auto; }}\nth, td {{ border: 1px solid #ccc; padding: 2px 8px; text-align: left; font-variant-numeric: tabular-nums; overflow-wrap: anywhere; }}\nimg {{ max-width: 100%; }}\nimg.wide {{ max-width: 48em; }}\nfigure {{ margin: 0.5em 0; }}\nfigcaption {{ overflow-wrap: anywhere; }}\n.plots {{ display: grid; grid-template-columns: repeat(auto-fill, minmax(18em, 1fr)); gap: 0.5em 1em; }}\n.card {{ min-width: 0; }}\n</style></head><body>\n<h1>surfcap report: {name}</h1>\n{body}</body></html>\n",
        name = esc(&s.name)
    );
    let index = out.join("index.html");
    surfcap_mesh::atomic::write_file(&index, |w| w.write_all(html.as_bytes()))?;
    Ok(Written { index, plots: n_plots, animations: n_anim, tables: n_tables })
}

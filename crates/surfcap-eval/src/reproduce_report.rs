//! The page of `surfcap reproduce`: each selected item of the published-values catalogue with its
//! values beside ours (read by JSON pointer from the report of the eval that reproduces it) and a
//! status per value, the figures that eval drew, its own printed tables, the machine and the
//! time each eval took; as one self-contained HTML page (figures embedded as data URIs), a JSON
//! document and a CSV table. Where a paper reading that changes numbers has a switch (the DTW's
//! first step of thesis eq. 2.53), the eval also runs under the other reading and each value
//! shows both: surfcap's reading as "ours", the other in its own column ([`OtherReading`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use crate::published_values::{Kind, PublishedCatalogue, PublishedItem, PublishedValue, Status, status};

/// The machine an eval ran on.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Machine {
    pub cores: usize,
    pub cpu: String,
    pub memory_bytes: u64,
}

impl Machine {
    /// "2 cores, Intel Xeon ..., 7.8 GiB".
    pub fn describe(&self) -> String {
        format!("{} cores, {}, {:.1} GiB", self.cores, self.cpu, self.memory_bytes as f64 / (1u64 << 30) as f64)
    }
}

/// A figure an eval wrote: its file name and bytes.
#[derive(Debug, Clone)]
pub struct Figure {
    pub name: String,
    pub bytes: Vec<u8>,
}

/// One eval's run as the page shows it.
#[derive(Debug, Clone, Default)]
pub struct EvalRun {
    /// The eval's name (`surfcap eval <name>`).
    pub eval: String,
    /// Its arguments after the name.
    pub args: Vec<String>,
    /// Its output folder, relative to the page.
    pub folder: String,
    /// Wall-clock seconds it took (when it ran).
    pub seconds: Option<f64>,
    pub machine: Option<Machine>,
    /// Its report (None when it has not run or failed before writing one).
    pub report: Option<serde_json::Value>,
    /// Why it has no report, or what it reported as missed after writing one.
    pub error: Option<String>,
    pub figures: Vec<Figure>,
    /// What the eval printed (its tables), as it printed it; None when not captured.
    pub printed: Option<String>,
    /// The paper reading this run uses, when the page shows another beside it
    /// ("surfcap's reading of eq. 2.53").
    pub reading: Option<String>,
    /// The same eval under other readings (each with its `reading` set), shown beside this one.
    pub alternates: Vec<EvalRun>,
}

/// One value under another reading of the paper (another run of the same eval).
#[derive(Debug, Clone, Serialize)]
pub struct OtherReading {
    /// The reading, as its run names it.
    pub reading: String,
    pub ours: Option<f64>,
    pub status: Status,
}

/// One value beside ours.
#[derive(Debug, Clone, Serialize)]
pub struct ValueRow {
    #[serde(flatten)]
    pub value: PublishedValue,
    pub ours: Option<f64>,
    pub status: Status,
    /// Why it differs or is not measured ("" when reproduced or better).
    pub reason: String,
    /// The value under the other readings of its eval's alternate runs (empty when none).
    pub other_readings: Vec<OtherReading>,
}

/// One item with its values.
#[derive(Debug, Clone, Serialize)]
pub struct ItemRow {
    #[serde(flatten)]
    pub item: PublishedItem,
    pub values: Vec<ValueRow>,
}

/// Everything the page shows.
#[derive(Debug, Clone)]
pub struct Page {
    /// Small settings (`--quick`): the numbers are not the evaluation's.
    pub quick: bool,
    pub machine: Machine,
    pub items: Vec<ItemRow>,
    /// The runs the items use, by eval name.
    pub runs: BTreeMap<String, EvalRun>,
}

/// The rows of `items`: each value's measured number from its item's run (by pointer) and its
/// status; the reason is the value's note, else the item's, else what is missing.
pub fn item_rows(cat: &PublishedCatalogue, items: &[&PublishedItem], runs: &BTreeMap<String, EvalRun>) -> Vec<ItemRow> {
    items
        .iter()
        .map(|it| {
            let run = runs.get(&it.eval);
            let values = cat
                .values_of(&it.id)
                .map(|v| {
                    let ours = run.and_then(|r| r.report.as_ref()).and_then(|r| v.measure(r));
                    let st = status(v, ours);
                    let note = if v.note.is_empty() { it.note.clone() } else { v.note.clone() };
                    let reason = match st {
                        Status::Reproduced | Status::Better => String::new(),
                        Status::Differs if note.is_empty() => {
                            format!("outside the tolerance of {}%", fmt_num(v.tolerance * 100.0))
                        }
                        Status::Differs => note,
                        Status::NotMeasured => not_measured_reason(it, v, run),
                    };
                    let other_readings = run
                        .map(|r| r.alternates.as_slice())
                        .unwrap_or_default()
                        .iter()
                        .map(|alt| {
                            let ours = alt.report.as_ref().and_then(|r| v.measure(r));
                            OtherReading {
                                reading: alt.reading.clone().unwrap_or_default(),
                                ours,
                                status: status(v, ours),
                            }
                        })
                        .collect();
                    ValueRow { value: v.clone(), ours, status: st, reason, other_readings }
                })
                .collect();
            ItemRow { item: (*it).clone(), values }
        })
        .collect()
}

fn not_measured_reason(it: &PublishedItem, v: &PublishedValue, run: Option<&EvalRun>) -> String {
    if it.eval.is_empty() {
        return "no surfcap eval reproduces this item yet".into();
    }
    let Some(run) = run else { return format!("eval {} is not known to surfcap reproduce", it.eval) };
    let Some(report) = &run.report else {
        return match &run.error {
            Some(e) => format!("eval {} failed: {e}", it.eval),
            None => format!("eval {} has not run", it.eval),
        };
    };
    if v.measured.is_empty() {
        return "surfcap's report has no matching number".into();
    }
    for p in [&v.measured, &v.measured_over].into_iter().filter(|p| !p.is_empty()) {
        match report.pointer(p) {
            None => return format!("{p} is not in the report of eval {}", it.eval),
            Some(x) if x.as_f64().is_none() && !x.is_boolean() => {
                return format!("{p} in the report of eval {} is not a number", it.eval);
            }
            Some(_) => {}
        }
    }
    format!("{} is 0 in the report of eval {}", v.measured_over, it.eval)
}

/// The count of each status over all values of `items`.
pub fn status_counts(items: &[ItemRow]) -> BTreeMap<&'static str, usize> {
    let mut m = BTreeMap::new();
    for s in [Status::Reproduced, Status::Better, Status::Differs, Status::NotMeasured] {
        m.insert(s.label(), 0);
    }
    for v in items.iter().flat_map(|i| &i.values) {
        *m.entry(v.status.label()).or_default() += 1;
    }
    m
}

/// results.json: the settings, the machine, the counts, every item with its values and each
/// run's time, machine, folder, error and figures (names).
pub fn results_json(page: &Page) -> serde_json::Value {
    let runs: BTreeMap<&String, serde_json::Value> = page
        .runs
        .iter()
        .map(|(k, r)| {
            (
                k,
                serde_json::json!({
                    "eval": r.eval,
                    "args": r.args,
                    "folder": r.folder,
                    "seconds": r.seconds,
                    "machine": r.machine,
                    "error": r.error,
                    "figures": r.figures.iter().map(|f| &f.name).collect::<Vec<_>>(),
                    "printed": r.printed,
                    "reading": r.reading,
                    "alternates": r.alternates.iter().map(|a| serde_json::json!({
                        "reading": a.reading,
                        "args": a.args,
                        "folder": a.folder,
                        "seconds": a.seconds,
                        "error": a.error,
                    })).collect::<Vec<_>>(),
                }),
            )
        })
        .collect();
    serde_json::json!({
        "quick": page.quick,
        "machine": page.machine,
        "counts": status_counts(&page.items),
        "total_seconds": total_seconds(page),
        "items": page.items,
        "runs": runs,
    })
}

/// The time of every run, alternates included.
pub fn total_seconds(page: &Page) -> f64 {
    page.runs.values().flat_map(|r| std::iter::once(r).chain(&r.alternates)).filter_map(|r| r.seconds).sum()
}

/// results.csv: one row per value (item, source, kind, number, label, published, ours, unit,
/// status, reason, read off plot, where, eval, seconds, then the other reading, its number and
/// its status, `;`-separated when there are several), RFC 4180 quoting.
pub fn results_csv(page: &Page) -> String {
    let mut s = String::from(
        "item,source,kind,number,label,published,ours,unit,status,reason,read_off_plot,where,eval,seconds,\
         other_reading,other_ours,other_status\n",
    );
    for it in &page.items {
        let secs = page.runs.get(&it.item.eval).and_then(|r| r.seconds).map(|x| format!("{x:.1}")).unwrap_or_default();
        for v in &it.values {
            let fields = [
                it.item.id.clone(),
                it.item.source.to_string(),
                it.item.kind.to_string(),
                it.item.number.clone(),
                v.value.label.clone(),
                fmt_num(v.value.published),
                v.ours.map(fmt_num).unwrap_or_default(),
                v.value.unit.clone(),
                v.status.label().into(),
                v.reason.clone(),
                v.value.read_off_plot.to_string(),
                v.value.place.clone(),
                it.item.eval.clone(),
                secs.clone(),
                v.other_readings.iter().map(|o| o.reading.as_str()).collect::<Vec<_>>().join(";"),
                v.other_readings.iter().map(|o| o.ours.map(fmt_num).unwrap_or_default()).collect::<Vec<_>>().join(";"),
                v.other_readings.iter().map(|o| o.status.label()).collect::<Vec<_>>().join(";"),
            ];
            let row: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
            s.push_str(&row.join(","));
            s.push('\n');
        }
    }
    s
}

fn csv_field(f: &str) -> String {
    if f.contains([',', '"', '\n', '\r']) { format!("\"{}\"", f.replace('"', "\"\"")) } else { f.to_string() }
}

/// A number with up to four significant decimals, no trailing zeros.
pub fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = (4 - x.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Standard base64 (RFC 4648, padded).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n =
            (u32::from(c[0]) << 16) | (u32::from(*c.get(1).unwrap_or(&0)) << 8) | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn mime(name: &str) -> Option<&'static str> {
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".svg") {
        Some("image/svg+xml")
    } else if lower.ends_with(".png") {
        Some("image/png")
    } else if lower.ends_with(".jpg") || lower.ends_with(".jpeg") {
        Some("image/jpeg")
    } else {
        None
    }
}

/// The figures of a run the page embeds: every image, except a PNG whose SVG is also there
/// (the plots are written in both).
pub fn shown_figures(figures: &[Figure]) -> Vec<&Figure> {
    figures
        .iter()
        .filter(|f| mime(&f.name).is_some())
        .filter(|f| {
            let Some(stem) = f.name.strip_suffix(".png") else { return true };
            !figures.iter().any(|g| g.name == format!("{stem}.svg"))
        })
        .collect()
}

/// "12.3 s" under a minute, else "m:ss min".
pub fn duration(s: f64) -> String {
    if s < 60.0 { format!("{s:.1} s") } else { format!("{}:{:02} min", (s / 60.0) as u64, (s as u64) % 60) }
}

fn status_class(s: Status) -> &'static str {
    match s {
        Status::Reproduced => "reproduced",
        Status::Better => "better",
        Status::Differs => "differs",
        Status::NotMeasured => "not_measured",
    }
}

/// A run's command line, output folder, time, machine and error.
fn run_meta(h: &mut String, r: &EvalRun) {
    let _ = write!(
        h,
        "<p class=\"meta\"><code>surfcap eval {} {}</code>{}<br>output: <a href=\"{}/\">{}</a>",
        esc(&r.eval),
        esc(&r.args.join(" ")),
        r.reading.as_ref().map(|x| format!(" ({})", esc(x))).unwrap_or_default(),
        esc(&r.folder),
        esc(&r.folder)
    );
    if let Some(s) = r.seconds {
        let _ = write!(h, "; took {}", duration(s));
    }
    if let Some(m) = &r.machine {
        let _ = write!(h, " on {}", esc(&m.describe()));
    }
    h.push_str("</p>\n");
    if let Some(e) = &r.error {
        let _ = writeln!(h, "<p class=\"differs\">{}</p>", esc(e));
    }
}

/// What a run printed, under a heading naming the command (collapsed: the tables can be long).
fn printed_tables(h: &mut String, r: &EvalRun) {
    let Some(text) = r.printed.as_deref().filter(|t| !t.trim().is_empty()) else { return };
    let _ = writeln!(
        h,
        "<details class=\"printed\"><summary>What <code>surfcap eval {}</code> printed{}</summary><pre>{}</pre></details>",
        esc(&r.eval),
        r.reading.as_ref().map(|x| format!(" ({})", esc(x))).unwrap_or_default(),
        esc(text)
    );
}

/// The page: a summary (counts, machine, total time, the quick-mode warning), then one section
/// per eval run: its items' tables (published beside ours, status and reason, where in the
/// paper, read off a plot or not; a column per other reading), the run's machine, time and
/// folder, its figures embedded and what it printed.
/// An onload script records in `body[data-images-loaded|broken]` how many images loaded, for
/// headless checks.
pub fn results_html(page: &Page) -> String {
    let mut h = String::new();
    let counts = status_counts(&page.items);
    let total = total_seconds(page);
    h.push_str(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>surfcap: the papers' tables and figures reproduced</title>\n<style>\
         body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em;color:#222}\
         table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}\
         th{background:#f0f0f0}td.n{text-align:right;font-family:monospace}\
         .reproduced{background:#d8f5d8}.better{background:#d8e8ff}.differs{background:#ffe4c8}\
         .not_measured{background:#eee;color:#666}.quick{background:#fff3b0;padding:.5em;border:1px solid #d9b800}\
         figure{display:inline-block;margin:.3em;vertical-align:top}figure img{max-width:560px;border:1px solid #ddd}\
         figcaption{font-size:80%;color:#555}.meta{color:#555;font-size:90%}\
         pre{background:#f8f8f8;border:1px solid #ddd;padding:.5em;overflow-x:auto;font-size:85%}\
         </style></head>\n<body>\n<h1>The papers' tables and figures, reproduced by surfcap</h1>\n",
    );
    if page.quick {
        h.push_str(
            "<p class=\"quick\" id=\"quick-mode\"><b>Quick mode</b> (<code>--quick</code>): every eval ran on \
             small settings, so these numbers check the pipeline, not the papers' claims.</p>\n",
        );
    }
    let _ = writeln!(
        h,
        "<p>{} items, {} values: {} reproduced, {} better, {} differs, {} not measured. \
         Machine: {}. Time of the evals: {}.</p>",
        page.items.len(),
        page.items.iter().map(|i| i.values.len()).sum::<usize>(),
        counts["reproduced"],
        counts["better"],
        counts["differs"],
        counts["not measured"],
        esc(&page.machine.describe()),
        duration(total)
    );
    h.push_str(
        "<p class=\"meta\">Status: <span class=\"reproduced\">reproduced</span> within the value's relative \
         tolerance; <span class=\"better\">better</span> outside it on the better side; \
         <span class=\"differs\">differs</span> with the reason; <span class=\"not_measured\">not measured</span>. \
         Published values marked &#8776; are read off a plot. Files: <a href=\"results.json\">results.json</a>, \
         <a href=\"results.csv\">results.csv</a>.</p>\n",
    );
    // Runs in the order their first item appears; items without a run last.
    let mut order: Vec<&str> = Vec::new();
    for it in &page.items {
        if !order.contains(&it.item.eval.as_str()) {
            order.push(&it.item.eval);
        }
    }
    for eval in order {
        let items: Vec<&ItemRow> = page.items.iter().filter(|i| i.item.eval == eval).collect();
        let names: Vec<String> = items.iter().map(|i| i.item.display_name()).collect();
        let _ = writeln!(
            h,
            "<section class=\"run\" id=\"run-{}\">",
            esc(if eval.is_empty() { crate::reproduce_markdown::NOT_RUN } else { eval })
        );
        let _ = writeln!(h, "<h2>{}</h2>", esc(&names.join(", ")));
        let run = page.runs.get(eval);
        match run {
            Some(r) => {
                run_meta(&mut h, r);
                for alt in &r.alternates {
                    run_meta(&mut h, alt);
                }
            }
            None if eval.is_empty() => h.push_str("<p class=\"meta\">No surfcap eval reproduces these yet.</p>\n"),
            None => {
                let _ = writeln!(h, "<p class=\"meta\">eval {} is not known to surfcap reproduce.</p>", esc(eval));
            }
        }
        let alternates: &[EvalRun] = run.map(|r| r.alternates.as_slice()).unwrap_or_default();
        for it in items {
            let _ =
                write!(h, "<h3 id=\"{}\">{}: {}", esc(&it.item.id), esc(&it.item.display_name()), esc(&it.item.title));
            if let Some(p) = it.item.page {
                let _ = write!(h, " <span class=\"meta\">(p. {p})</span>");
            }
            h.push_str("</h3>\n");
            if it.item.kind == Kind::Check {
                let _ = writeln!(
                    h,
                    "<p class=\"meta check\">surfcap's own check, no paper figure: {} Its tables are below.</p>",
                    esc(&it.item.note)
                );
                continue;
            }
            if it.values.is_empty() {
                h.push_str(
                    "<p class=\"meta\">The paper gives this as a picture only: compare the figures below.</p>\n",
                );
                continue;
            }
            h.push_str("<table><tr><th>value</th><th>published</th><th>ours");
            if let Some(reading) = run.and_then(|r| r.reading.as_ref()) {
                let _ = write!(h, " ({})", esc(reading));
            }
            h.push_str("</th><th>unit</th><th>status</th>");
            for alt in alternates {
                let _ = write!(
                    h,
                    "<th>ours ({})</th><th>status</th>",
                    esc(alt.reading.as_deref().unwrap_or("another reading"))
                );
            }
            h.push_str("<th>reason</th><th>where</th></tr>\n");
            for v in &it.values {
                let _ = write!(
                    h,
                    "<tr class=\"{}\"><td>{}</td><td class=\"n\">{}{}</td><td class=\"n\">{}</td><td>{}</td><td>{}</td>",
                    status_class(v.status),
                    esc(&v.value.label),
                    if v.value.read_off_plot { "&#8776; " } else { "" },
                    fmt_num(v.value.published),
                    v.ours.map(fmt_num).unwrap_or_else(|| "&mdash;".into()),
                    esc(&v.value.unit),
                    v.status.label(),
                );
                for o in &v.other_readings {
                    let _ = write!(
                        h,
                        "<td class=\"n {c}\">{}</td><td class=\"{c}\">{}</td>",
                        o.ours.map(fmt_num).unwrap_or_else(|| "&mdash;".into()),
                        o.status.label(),
                        c = status_class(o.status)
                    );
                }
                let _ = writeln!(h, "<td>{}</td><td>{}</td></tr>", esc(&v.reason), esc(&v.value.place));
            }
            h.push_str("</table>\n");
        }
        if let Some(r) = run {
            let figs = shown_figures(&r.figures);
            if !figs.is_empty() {
                h.push_str("<div class=\"figures\">\n");
                for f in figs {
                    let Some(m) = mime(&f.name) else { continue };
                    let _ = writeln!(
                        h,
                        "<figure><img alt=\"{n}\" src=\"data:{m};base64,{}\"><figcaption>{n}</figcaption></figure>",
                        base64(&f.bytes),
                        n = esc(&f.name)
                    );
                }
                h.push_str("</div>\n");
            }
            for one in std::iter::once(r).chain(&r.alternates) {
                printed_tables(&mut h, one);
            }
        }
        h.push_str("</section>\n");
    }
    h.push_str(
        "<script>window.addEventListener('load',function(){var ok=0,bad=0;\
         document.querySelectorAll('img').forEach(function(i){if(i.complete&&i.naturalWidth>0)ok++;else bad++;});\
         document.body.setAttribute('data-images-loaded',ok);document.body.setAttribute('data-images-broken',bad);});\
         </script>\n</body></html>\n",
    );
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAT: &str = r#"
[[item]]
id = "thesis-fig-2.15"
source = "thesis"
kind = "figure"
number = "2.15"
title = "costs"
eval = "transitions"
[[item]]
id = "thesis-fig-9.9"
source = "thesis"
kind = "figure"
number = "9.9"
title = "none yet"
eval = ""
[[value]]
item = "thesis-fig-2.15"
label = "mean, \"slope\" 2"
published = 0.2
unit = ""
read_off_plot = false
where = "Fig. 2.15"
measured = "/rows/0/mean"
better = "lower"
tolerance = 0.1
note = "other data"
[[value]]
item = "thesis-fig-2.15"
label = "missing"
published = 1.0
unit = ""
read_off_plot = false
where = "Fig. 2.15"
measured = "/rows/5/mean"
better = "closer"
tolerance = 0.1
note = ""
[[value]]
item = "thesis-fig-9.9"
label = "x"
published = 1.0
unit = ""
read_off_plot = true
where = "Fig. 9.9"
measured = ""
better = "closer"
tolerance = 0.1
note = ""
"#;

    fn page(report: Option<serde_json::Value>) -> Page {
        let cat = PublishedCatalogue::parse("t.toml", CAT).unwrap();
        let items = cat.select(true, &[], &[], &[]).unwrap();
        let svg = b"<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"4\" height=\"4\"></svg>".to_vec();
        let run = EvalRun {
            eval: "transitions".into(),
            args: vec!["crane".into()],
            folder: "runs/transitions".into(),
            seconds: Some(3.0),
            report,
            figures: vec![
                Figure { name: "costs.svg".into(), bytes: svg.clone() },
                Figure { name: "costs.png".into(), bytes: vec![1, 2] },
                Figure { name: "transitions.json".into(), bytes: vec![] },
            ],
            ..Default::default()
        };
        let runs = BTreeMap::from([("transitions".to_string(), run)]);
        let machine = Machine { cores: 2, cpu: "cpu".into(), memory_bytes: 1 << 30 };
        Page { quick: true, machine, items: item_rows(&cat, &items, &runs), runs }
    }

    #[test]
    fn statuses_and_reasons_per_value() {
        let p = page(Some(serde_json::json!({"rows": [{"mean": 0.5}]})));
        let v = &p.items[0].values;
        assert_eq!((v[0].ours, v[0].status, v[0].reason.as_str()), (Some(0.5), Status::Differs, "other data"));
        assert_eq!(v[1].status, Status::NotMeasured);
        assert!(v[1].reason.contains("/rows/5/mean is not in the report"), "{}", v[1].reason);
        assert!(p.items[1].values[0].reason.contains("no surfcap eval"), "{}", p.items[1].values[0].reason);
        let failed = page(None);
        assert!(failed.items[0].values[0].reason.contains("has not run"));
    }

    #[test]
    fn csv_quotes_and_json_counts() {
        let p = page(Some(serde_json::json!({"rows": [{"mean": 0.19}]})));
        let csv = results_csv(&p);
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.contains("\"mean, \"\"slope\"\" 2\",0.2,0.19,,reproduced"), "{csv}");
        let j = results_json(&p);
        assert_eq!(j["counts"]["reproduced"], 1);
        assert_eq!(j["counts"]["not measured"], 2);
        assert_eq!(j["total_seconds"], 3.0);
        assert_eq!(j["items"][0]["values"][0]["status"], "reproduced");
    }

    #[test]
    fn html_embeds_svg_once_and_marks_quick_mode() {
        let html = results_html(&page(None));
        assert_eq!(html.matches("<img ").count(), 1, "the PNG twin of an SVG and non-images are left out");
        assert!(html.contains("data:image/svg+xml;base64,"));
        assert!(html.contains("id=\"quick-mode\""));
        assert!(html.contains("&#8776; 1"));
    }

    #[test]
    fn another_reading_gets_its_own_columns_and_printed_tables_show() {
        let mut p = page(Some(serde_json::json!({"rows": [{"mean": 0.19}]})));
        let cat = PublishedCatalogue::parse("t.toml", CAT).unwrap();
        let items = cat.select(true, &[], &[], &[]).unwrap();
        let run = p.runs.get_mut("transitions").unwrap();
        run.reading = Some("surfcap's reading".into());
        run.printed = Some("slope  mean\n2      <0.19>\n".into());
        run.alternates.push(EvalRun {
            eval: "transitions".into(),
            args: vec!["crane".into(), "--dtw-first-step".into(), "literal".into()],
            folder: "runs/transitions-literal".into(),
            seconds: Some(4.0),
            report: Some(serde_json::json!({"rows": [{"mean": 0.5}]})),
            reading: Some("literal".into()),
            ..Default::default()
        });
        p.items = item_rows(&cat, &items, &p.runs);
        let v = &p.items[0].values[0];
        assert_eq!((v.status, v.other_readings.len()), (Status::Reproduced, 1));
        assert_eq!((v.other_readings[0].ours, v.other_readings[0].status), (Some(0.5), Status::Differs));
        let csv = results_csv(&p);
        assert!(csv.lines().next().unwrap().ends_with(",other_reading,other_ours,other_status"));
        assert!(csv.contains(",reproduced,,false,Fig. 2.15,transitions,3.0,literal,0.5,differs\n"), "{csv}");
        let html = results_html(&p);
        assert!(
            html.contains("<th>ours (surfcap&#39;s reading)</th>")
                || html.contains("<th>ours (surfcap's reading)</th>")
        );
        assert!(html.contains("<th>ours (literal)</th><th>status</th>"), "{html}");
        assert!(html.contains("<pre>slope  mean\n2      &lt;0.19&gt;\n</pre>"), "printed tables escaped");
        assert!(html.contains("--dtw-first-step literal</code> (literal)"));
        let j = results_json(&p);
        assert_eq!(j["total_seconds"], 7.0);
        assert_eq!(j["items"][0]["values"][0]["other_readings"][0]["status"], "differs");
        assert_eq!(j["runs"]["transitions"]["alternates"][0]["reading"], "literal");
    }

    #[test]
    fn base64_matches_rfc_4648() {
        for (i, o) in [("", ""), ("f", "Zg=="), ("fo", "Zm8="), ("foo", "Zm9v"), ("foobar", "Zm9vYmFy")] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}

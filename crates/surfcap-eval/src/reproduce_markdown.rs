//! The measured tables of `surfcap reproduce` as markdown pages for `docs/results/`
//! (`surfcap reproduce ... --results-dir docs/results`): one page per eval run with the
//! command that made it, the run's settings, machine and time, each item's published values
//! beside ours (a column per other paper reading), and what the eval printed; and an index page
//! with the status counts per item. The numbers are those of the HTML page and of results.json
//! (the same [`Page`], the same formatting, [`fmt_num`]).
//!
//! Every page starts with [`MARKER`], so that a later run replaces only the pages it wrote
//! ([`is_own_page`]).

use std::fmt::Write as _;

use crate::published_values::Kind;
use crate::reproduce_report::{EvalRun, ItemRow, Page, duration, fmt_num, status_counts};

/// The first line of every page this module writes.
pub const MARKER: &str = "<!-- written by surfcap reproduce; a later run replaces this page: do not edit by hand -->";

/// The index page's file name.
pub const INDEX: &str = "reproduce.md";

/// Whether `text` (a file's content) is a page this module wrote.
pub fn is_own_page(text: &str) -> bool {
    text.lines().next() == Some(MARKER)
}

/// What the pages call the items no surfcap eval reproduces (their page is
/// `reproduce-not-run.md`).
pub const NOT_RUN: &str = "not-run";

/// The file name of the page of `eval`'s run: "reproduce-transitions.md".
pub fn page_name(eval: &str) -> String {
    format!("reproduce-{eval}.md")
}

/// A table cell: `|` escaped, line breaks as spaces.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn ours(x: Option<f64>) -> String {
    x.map(fmt_num).unwrap_or_else(|| "-".into())
}

fn run_line(r: &EvalRun) -> String {
    let mut s = format!("`surfcap eval {} {}`", r.eval, r.args.join(" "));
    if let Some(reading) = &r.reading {
        let _ = write!(s, " ({reading})");
    }
    match r.seconds {
        Some(secs) => {
            let _ = write!(s, ": took {}", duration(secs));
        }
        None => s.push_str(": has not run"),
    }
    if let Some(m) = &r.machine {
        let _ = write!(s, " on {}", m.describe());
    }
    if let Some(e) = &r.error {
        let _ = write!(s, "; {e}");
    }
    s
}

fn header(md: &mut String, title: &str, page: &Page, command: &str) {
    let _ = writeln!(md, "{MARKER}\n\n# {title}\n");
    let _ = writeln!(md, "Made by:\n\n```sh\n{command}\n```\n");
    if page.quick {
        md.push_str(
            "**Quick mode** (`--quick`): every eval ran on small settings, so these numbers check the \
             pipeline, not the papers' claims.\n\n",
        );
    }
}

/// One item's table: value, published, ours, unit, status, a pair of columns per other reading,
/// reason, where.
fn item_table(md: &mut String, it: &ItemRow, run: Option<&EvalRun>) {
    let _ = write!(md, "## {}: {}", it.item.display_name(), it.item.title);
    if let Some(p) = it.item.page {
        let _ = write!(md, " (p. {p})");
    }
    md.push_str("\n\n");
    if it.item.kind == Kind::Check {
        let _ = writeln!(md, "surfcap's own check, no paper figure: {} Its tables are below.\n", it.item.note);
        return;
    }
    if it.values.is_empty() {
        md.push_str("The paper gives this as a picture only: compare the figures of the page.\n\n");
        return;
    }
    let reading = run.and_then(|r| r.reading.as_ref()).map(|x| format!(" ({x})")).unwrap_or_default();
    let _ = write!(md, "| value | published | ours{} | unit | status |", cell(&reading));
    let alternates: &[EvalRun] = run.map(|r| r.alternates.as_slice()).unwrap_or_default();
    for alt in alternates {
        let _ = write!(md, " ours ({}) | status |", cell(alt.reading.as_deref().unwrap_or("another reading")));
    }
    md.push_str(" reason | where |\n|---|---|---|---|---|");
    for _ in alternates {
        md.push_str("---|---|");
    }
    md.push_str("---|---|\n");
    for v in &it.values {
        let _ = write!(
            md,
            "| {} | {}{} | {} | {} | {} |",
            cell(&v.value.label),
            if v.value.read_off_plot { "≈ " } else { "" },
            fmt_num(v.value.published),
            ours(v.ours),
            cell(&v.value.unit),
            v.status.label()
        );
        for o in &v.other_readings {
            let _ = write!(md, " {} | {} |", ours(o.ours), o.status.label());
        }
        let _ = writeln!(md, " {} | {} |", cell(&v.reason), cell(&v.value.place));
    }
    md.push('\n');
}

/// The pages: (file name, markdown), the index first, then one per eval run in the order of
/// the items. `command` is the `surfcap reproduce` command line that made them.
pub fn results_markdown(page: &Page, command: &str) -> Vec<(String, String)> {
    let mut order: Vec<&str> = Vec::new();
    for it in &page.items {
        if !order.contains(&it.item.eval.as_str()) {
            order.push(&it.item.eval);
        }
    }
    let mut index = String::new();
    header(&mut index, "The papers' tables and figures, reproduced by surfcap", page, command);
    let counts = status_counts(&page.items);
    let _ = writeln!(
        index,
        "{} items, {} values: {} reproduced, {} better, {} differs, {} not measured. Machine: {}. \
         Time of the evals: {}.\n",
        page.items.len(),
        page.items.iter().map(|i| i.values.len()).sum::<usize>(),
        counts["reproduced"],
        counts["better"],
        counts["differs"],
        counts["not measured"],
        page.machine.describe(),
        duration(crate::reproduce_report::total_seconds(page))
    );
    index.push_str("| item | eval | values | reproduced | better | differs | not measured | page |\n");
    index.push_str("|---|---|---|---|---|---|---|---|\n");
    let mut pages = Vec::new();
    for eval in order {
        let items: Vec<&ItemRow> = page.items.iter().filter(|i| i.item.eval == eval).collect();
        let name = page_name(if eval.is_empty() { NOT_RUN } else { eval });
        for it in &items {
            let c = status_counts(std::slice::from_ref(*it));
            let _ = writeln!(
                index,
                "| {} | {} | {} | {} | {} | {} | {} | [{name}]({name}) |",
                cell(&it.item.display_name()),
                if eval.is_empty() { "-" } else { eval },
                it.values.len(),
                c["reproduced"],
                c["better"],
                c["differs"],
                c["not measured"]
            );
        }
        let names: Vec<String> = items.iter().map(|i| i.item.display_name()).collect();
        let mut md = String::new();
        header(&mut md, &names.join(", "), page, command);
        let run = page.runs.get(eval);
        match run {
            Some(r) => {
                for one in std::iter::once(r).chain(&r.alternates) {
                    let _ = writeln!(md, "- {}", run_line(one));
                }
                md.push('\n');
            }
            None if eval.is_empty() => md.push_str("No surfcap eval reproduces these yet.\n\n"),
            None => {
                let _ = writeln!(md, "eval {eval} is not known to surfcap reproduce.\n");
            }
        }
        for it in &items {
            item_table(&mut md, it, run);
        }
        for one in run.into_iter().flat_map(|r| std::iter::once(r).chain(&r.alternates)) {
            if let Some(text) = one.printed.as_deref().filter(|t| !t.trim().is_empty()) {
                let reading = one.reading.as_ref().map(|x| format!(" ({x})")).unwrap_or_default();
                let fence = if text.contains("```") { "~~~~" } else { "```" };
                let _ = writeln!(
                    md,
                    "## What `surfcap eval {}` printed{reading}\n\n{fence}text\n{}\n{fence}\n",
                    one.eval,
                    text.trim_end()
                );
            }
        }
        pages.push((name, md));
    }
    let mut all = vec![(INDEX.to_string(), index)];
    all.extend(pages);
    all
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::published_values::PublishedCatalogue;
    use crate::reproduce_report::{Machine, item_rows, results_json};
    use surfcap_testkit::markdown_cells as cells;

    const CAT: &str = r#"
[[item]]
id = "thesis-fig-2.15"
source = "thesis"
kind = "figure"
number = "2.15"
title = "costs | durations"
page = 43
eval = "transitions"
[[value]]
item = "thesis-fig-2.15"
label = "mean | slope 2"
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
label = "ratio"
published = 1.0
unit = "x"
read_off_plot = true
where = "Sec. 2.5"
measured = "/rows/1/mean"
better = "closer"
tolerance = 0.1
note = ""
"#;

    fn page() -> Page {
        let cat = PublishedCatalogue::parse("t.toml", CAT).unwrap();
        let items = cat.select(true, &[], &[], &[]).unwrap();
        let literal = EvalRun {
            eval: "transitions".into(),
            args: vec!["crane".into(), "--dtw-first-step".into(), "literal".into()],
            folder: "runs/transitions-literal".into(),
            seconds: Some(2.0),
            report: Some(serde_json::json!({"rows": [{"mean": 0.21}, {"mean": 0.5}]})),
            reading: Some("eq. 2.53 literally".into()),
            printed: Some("slope | mean\n2 | 0.21\n".into()),
            ..Default::default()
        };
        let run = EvalRun {
            eval: "transitions".into(),
            args: vec!["crane".into()],
            folder: "runs/transitions".into(),
            seconds: Some(3.0),
            report: Some(serde_json::json!({"rows": [{"mean": 0.123456}, {"mean": 1.04}]})),
            reading: Some("surfcap's reading".into()),
            printed: Some("slope mean\n2 0.12\n".into()),
            alternates: vec![literal],
            ..Default::default()
        };
        let runs = BTreeMap::from([("transitions".to_string(), run)]);
        let machine = Machine { cores: 2, cpu: "cpu".into(), memory_bytes: 1 << 30 };
        Page { quick: false, machine, items: item_rows(&cat, &items, &runs), runs }
    }

    #[test]
    fn the_markdown_tables_hold_the_json_values() {
        let p = page();
        let json = results_json(&p);
        let pages = results_markdown(&p, "surfcap reproduce --figure 2.15 --results-dir docs/results");
        assert_eq!(pages.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), [INDEX, "reproduce-transitions.md"]);
        for (_, md) in &pages {
            assert!(is_own_page(md));
            assert!(md.contains("```sh\nsurfcap reproduce --figure 2.15 --results-dir docs/results\n```"));
        }
        let md = &pages[1].1;
        let rows: Vec<Vec<String>> =
            md.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| value")).map(cells).collect();
        let values = json["items"][0]["values"].as_array().unwrap();
        assert_eq!(rows.len(), values.len());
        for (row, v) in rows.iter().zip(values) {
            assert_eq!(row.len(), 9, "{row:?}");
            assert_eq!(row[0], v["label"].as_str().unwrap());
            assert_eq!(row[1].trim_start_matches("≈ "), fmt_num(v["published"].as_f64().unwrap()));
            assert_eq!(row[1].starts_with('≈'), v["read_off_plot"].as_bool().unwrap());
            assert_eq!(row[2], fmt_num(v["ours"].as_f64().unwrap()));
            assert_eq!(row[4].replace(' ', "_"), v["status"].as_str().unwrap());
            let other = &v["other_readings"][0];
            assert_eq!(row[5], fmt_num(other["ours"].as_f64().unwrap()));
            assert_eq!(row[6].replace(' ', "_"), other["status"].as_str().unwrap());
            assert_eq!(row[7], v["reason"].as_str().unwrap());
        }
        assert_eq!((rows[0][4].as_str(), rows[0][6].as_str()), ("better", "reproduced"));
        assert!(
            md.contains("| value | published | ours (surfcap's reading) | unit | status | ours (eq. 2.53 literally) |")
        );
        // Both runs' printed tables, the literal bar kept inside the fence.
        assert!(md.contains("printed (surfcap's reading)\n\n```text\nslope mean\n2 0.12\n```"), "{md}");
        assert!(md.contains("printed (eq. 2.53 literally)\n\n```text\nslope | mean\n"));
        // The index counts the statuses as the JSON does.
        let index = &pages[0].1;
        let row = cells(index.lines().find(|l| l.starts_with("| Thesis Fig. 2.15")).unwrap());
        let c = &json["counts"];
        assert_eq!(
            row[3..7],
            [&c["reproduced"], &c["better"], &c["differs"], &c["not measured"]].map(|x| x.to_string())
        );
        assert!(index.contains("[reproduce-transitions.md](reproduce-transitions.md)"));
    }

    #[test]
    fn only_its_own_pages_are_recognised() {
        assert!(is_own_page(&format!("{MARKER}\n# x\n")));
        assert!(!is_own_page("# Motion transfer\n"));
        assert!(!is_own_page(""));
    }
}

//! The published values of the thesis's figures and tables, Huang et al. 2009's Table 1 and the
//! CVPR 2017 paper's figures, typed in from the papers (`crates/surfcap-eval/published/*.toml`,
//! built into the library), and where each one's counterpart sits in the result JSON of the
//! `surfcap eval` command that reproduces it. Beside them, surfcap's own checks
//! (`published/surfcap.toml`, source `surfcap`, kind `check`): evals with no paper figure
//! (root motion from contacts, the interchange round trips) that the page lists with their
//! printed tables and no published value.
//!
//! A file holds `[[item]]` tables (one per figure or table: id, source, kind, number, title,
//! page, eval) and `[[value]]` tables (one per published number: the item it belongs to, label,
//! published value, unit, whether it was read off a plot, where in the paper, the JSON pointer
//! `measured` into the eval's result, `better` = lower | higher | closer, a relative tolerance and
//! a note). Two optional fields turn a measurement into the published quantity:
//! `measured_over` (a second pointer the measured value is divided by, for ratios) and
//! `measured_scale` (a factor, for units). [`PublishedCatalogue::check`] enforces the rules a
//! typo would break: unique item ids, every value's item present, a known source, kind and
//! `better`, a finite published value, a tolerance > 0, pointers that are empty or start with `/`.
//!
//! `surfcap reproduce` picks items with [`PublishedCatalogue::select`] (`--figure 2.15`,
//! `--table huang-1`) and gives each value a [`Status`] with [`status`]: reproduced (within the
//! relative tolerance), better (outside it, on the side the value's `better` names), differs or
//! not measured.

use std::collections::HashSet;

use serde::{Deserialize, Serialize};

/// The three papers' files and surfcap's own checks, built in.
const BUILTIN: [(&str, &str); 4] = [
    ("thesis.toml", include_str!("../published/thesis.toml")),
    ("huang2009.toml", include_str!("../published/huang2009.toml")),
    ("cvpr2017.toml", include_str!("../published/cvpr2017.toml")),
    ("surfcap.toml", include_str!("../published/surfcap.toml")),
];

/// Why a published-values file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PublishedValuesError {
    /// The file is not TOML of the schema (an unknown or missing field, a wrong type).
    #[error("{file}{}: {message}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
    Parse { file: String, line: Option<usize>, message: String },
    /// The file parses but breaks a rule of the schema; `entry` names the item or value.
    #[error("{file}: {entry}: {expected}")]
    Rule { file: String, entry: String, expected: String },
    /// A `--figure` / `--table` / `--check` value that names no item.
    #[error("--{option} {value}: no such {option} in the catalogue (see `surfcap reproduce --list`)")]
    NoSuchItem { option: &'static str, value: String },
}

/// Which paper a value comes from (or `surfcap` for its own checks, which have no paper).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    Thesis,
    Huang2009,
    Cvpr2017,
    Surfcap,
}

/// A figure, a table, or one of surfcap's own checks (no paper figure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    Figure,
    Table,
    Check,
}

impl Source {
    /// As written in the files: "thesis", "huang2009", "cvpr2017", "surfcap".
    pub fn as_str(self) -> &'static str {
        match self {
            Source::Thesis => "thesis",
            Source::Huang2009 => "huang2009",
            Source::Cvpr2017 => "cvpr2017",
            Source::Surfcap => "surfcap",
        }
    }

    /// As a reader names it: "Thesis", "Huang et al. 2009", "CVPR 2017", "surfcap".
    pub fn title(self) -> &'static str {
        match self {
            Source::Thesis => "Thesis",
            Source::Huang2009 => "Huang et al. 2009",
            Source::Cvpr2017 => "CVPR 2017",
            Source::Surfcap => "surfcap",
        }
    }
}

impl Kind {
    /// As written in the files: "figure", "table", "check".
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Figure => "figure",
            Kind::Table => "table",
            Kind::Check => "check",
        }
    }
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How a measured value compares for the status "better": lower, higher, or only as close as
/// possible (no direction is better).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Better {
    Lower,
    Higher,
    Closer,
}

/// One figure or table of a paper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PublishedItem {
    /// Stable id, e.g. "thesis-fig-2.15" or "huang-1".
    pub id: String,
    pub source: Source,
    pub kind: Kind,
    /// The number as printed ("2.15", "1").
    pub number: String,
    pub title: String,
    /// Page as printed; `None` when the text extraction does not give it.
    #[serde(default)]
    pub page: Option<u32>,
    /// The `surfcap eval <name>` that reproduces it; empty when none does yet.
    pub eval: String,
    /// What holds for the whole item (plots without values, the data used, ...).
    #[serde(default)]
    pub note: String,
}

/// One published number and where its measured counterpart is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PublishedValue {
    /// The [`PublishedItem::id`] it belongs to.
    pub item: String,
    pub label: String,
    pub published: f64,
    pub unit: String,
    /// Read off a plot (true) or typed from the text or a table (false).
    pub read_off_plot: bool,
    /// Where in the paper, with the quoted words.
    #[serde(rename = "where")]
    pub place: String,
    /// JSON pointer into the eval's result; empty when nothing matches.
    pub measured: String,
    /// JSON pointer of a divisor (the published value is a ratio); empty for none.
    #[serde(default)]
    pub measured_over: String,
    /// Factor applied to the measured value (e.g. 100 for metres against centimetres).
    #[serde(default = "one")]
    pub measured_scale: f64,
    pub better: Better,
    /// Relative tolerance for "reproduced".
    pub tolerance: f64,
    pub note: String,
}

fn one() -> f64 {
    1.0
}

impl PublishedValue {
    /// The measured counterpart in `result` (an eval's result JSON): the value at `measured` (a
    /// number, or a boolean as 1 / 0),
    /// divided by the one at `measured_over` when given, times `measured_scale`. `None` when the
    /// value has no pointer, a pointer does not resolve to a number, or the divisor is 0.
    pub fn measure(&self, result: &serde_json::Value) -> Option<f64> {
        if self.measured.is_empty() {
            return None;
        }
        let mut x = measured_value(result, &self.measured)?;
        if !self.measured_over.is_empty() {
            let d = measured_value(result, &self.measured_over)?;
            if d == 0.0 {
                return None;
            }
            x /= d;
        }
        Some(x * self.measured_scale)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    item: Vec<PublishedItem>,
    #[serde(default)]
    value: Vec<PublishedValue>,
}

/// Every item and value of the three papers.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PublishedCatalogue {
    pub items: Vec<PublishedItem>,
    pub values: Vec<PublishedValue>,
}

impl PublishedCatalogue {
    /// The three built-in files (thesis, Huang et al. 2009, CVPR 2017), parsed and checked.
    pub fn load_builtin() -> Result<Self, PublishedValuesError> {
        let mut all = PublishedCatalogue::default();
        for (file, text) in BUILTIN {
            let one = Self::parse(file, text)?;
            all.items.extend(one.items);
            all.values.extend(one.values);
        }
        all.check("the built-in published values")?;
        Ok(all)
    }

    /// Parses one file's text (`file` names it in errors) and checks it.
    pub fn parse(file: &str, text: &str) -> Result<Self, PublishedValuesError> {
        let parsed: File = toml::from_str(text).map_err(|e| PublishedValuesError::Parse {
            file: file.to_string(),
            line: e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
            message: e.message().to_string(),
        })?;
        let cat = PublishedCatalogue { items: parsed.item, values: parsed.value };
        cat.check(file)?;
        Ok(cat)
    }

    /// The schema's rules (see the module doc); `file` names the catalogue in errors.
    pub fn check(&self, file: &str) -> Result<(), PublishedValuesError> {
        let rule = |entry: String, expected: &str| PublishedValuesError::Rule {
            file: file.to_string(),
            entry,
            expected: expected.to_string(),
        };
        let mut ids = HashSet::new();
        for it in &self.items {
            if it.id.is_empty() || !ids.insert(it.id.as_str()) {
                return Err(rule(format!("item \"{}\"", it.id), "a non-empty id used by no other item"));
            }
            if (it.kind == Kind::Check) != (it.source == Source::Surfcap) {
                return Err(rule(format!("item \"{}\"", it.id), "kind \"check\" exactly for source \"surfcap\""));
            }
            if it.kind == Kind::Check && it.eval.is_empty() {
                return Err(rule(format!("item \"{}\"", it.id), "a check names the eval that makes it"));
            }
        }
        for (k, v) in self.values.iter().enumerate() {
            let entry = || format!("value {} (\"{}\" of item \"{}\")", k + 1, v.label, v.item);
            if !ids.contains(v.item.as_str()) {
                return Err(rule(entry(), "an item id listed by an [[item]] table"));
            }
            if !v.published.is_finite() {
                return Err(rule(entry(), "a finite published value"));
            }
            if !(v.tolerance.is_finite() && v.tolerance > 0.0) {
                return Err(rule(entry(), "a tolerance > 0"));
            }
            if !(v.measured_scale.is_finite() && v.measured_scale != 0.0) {
                return Err(rule(entry(), "a finite, non-zero measured_scale"));
            }
            for p in [&v.measured, &v.measured_over] {
                if !(p.is_empty() || p.starts_with('/')) {
                    return Err(rule(entry(), "JSON pointers that are empty or start with '/'"));
                }
            }
            if v.measured.is_empty() && !v.measured_over.is_empty() {
                return Err(rule(entry(), "measured_over only together with measured"));
            }
            if v.label.is_empty() || v.place.is_empty() {
                return Err(rule(entry(), "a label and where in the paper"));
            }
        }
        Ok(())
    }

    /// The item with this id.
    pub fn item(&self, id: &str) -> Option<&PublishedItem> {
        self.items.iter().find(|i| i.id == id)
    }

    /// The values of one item, in file order.
    pub fn values_of<'a>(&'a self, id: &'a str) -> impl Iterator<Item = &'a PublishedValue> + 'a {
        self.values.iter().filter(move |v| v.item == id)
    }

    /// The items a selection names, in catalogue order, each once: every item with `all`, else
    /// those `figures`, `tables` and `checks` name ([`PublishedItem::is_named_by`]). A name
    /// matching no item is refused.
    pub fn select(
        &self,
        all: bool,
        figures: &[String],
        tables: &[String],
        checks: &[String],
    ) -> Result<Vec<&PublishedItem>, PublishedValuesError> {
        if all {
            return Ok(self.items.iter().collect());
        }
        let mut chosen = vec![false; self.items.len()];
        for (option, kind, names) in
            [("figure", Kind::Figure, figures), ("table", Kind::Table, tables), ("check", Kind::Check, checks)]
        {
            for name in names {
                let mut found = false;
                for (k, it) in self.items.iter().enumerate() {
                    if it.kind == kind && it.is_named_by(name) {
                        chosen[k] = true;
                        found = true;
                    }
                }
                if !found {
                    return Err(PublishedValuesError::NoSuchItem { option, value: name.clone() });
                }
            }
        }
        Ok(self.items.iter().zip(chosen).filter(|(_, c)| *c).map(|(it, _)| it).collect())
    }
}

impl PublishedItem {
    /// Whether `name` names this item: its id, its number ("2.15"), or source and number
    /// ("huang2009-1", or "huang-1" with the source's year left out).
    pub fn is_named_by(&self, name: &str) -> bool {
        let source = self.source.as_str();
        let short = source.trim_end_matches(|c: char| c.is_ascii_digit());
        name == self.id
            || name == self.number
            || name == format!("{source}-{}", self.number)
            || name == format!("{short}-{}", self.number)
    }

    /// "Thesis Fig. 2.15", "Huang et al. 2009 Table 1".
    pub fn display_name(&self) -> String {
        let kind = match self.kind {
            Kind::Table => "Table",
            Kind::Figure => "Fig.",
            Kind::Check => return format!("surfcap's own check: {}", self.number),
        };
        format!("{} {kind} {}", self.source.title(), self.number)
    }
}

/// How a measured value stands beside the published one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Reproduced,
    Better,
    Differs,
    NotMeasured,
}

impl Status {
    pub fn label(self) -> &'static str {
        match self {
            Status::Reproduced => "reproduced",
            Status::Better => "better",
            Status::Differs => "differs",
            Status::NotMeasured => "not measured",
        }
    }
}

/// The status of `ours` beside `v.published`: reproduced when `|ours - published| <= tolerance
/// * |published|` (an absolute tolerance when the published value is 0), else better when it is
/// on the side `v.better` names, else differs; not measured without a finite value.
pub fn status(v: &PublishedValue, ours: Option<f64>) -> Status {
    let Some(x) = ours.filter(|x| x.is_finite()) else { return Status::NotMeasured };
    let scale = if v.published == 0.0 { 1.0 } else { v.published.abs() };
    if (x - v.published).abs() <= v.tolerance * scale {
        return Status::Reproduced;
    }
    match v.better {
        Better::Lower if x < v.published => Status::Better,
        Better::Higher if x > v.published => Status::Better,
        _ => Status::Differs,
    }
}

/// The number at JSON pointer `pointer` of `report`: a number, or a boolean as 1 / 0; `None` for
/// an empty pointer, one that does not resolve, or anything else.
pub fn measured_value(report: &serde_json::Value, pointer: &str) -> Option<f64> {
    if pointer.is_empty() {
        return None;
    }
    match report.pointer(pointer)? {
        serde_json::Value::Number(n) => n.as_f64(),
        serde_json::Value::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_files_parse_and_keep_the_schema() {
        let cat = PublishedCatalogue::load_builtin().unwrap();
        for (source, want_items) in
            [(Source::Thesis, 17), (Source::Huang2009, 1), (Source::Cvpr2017, 4), (Source::Surfcap, 2)]
        {
            assert_eq!(cat.items.iter().filter(|i| i.source == source).count(), want_items, "{source:?}");
        }
        // Every figure and table the reproduction covers is there.
        for id in [
            "thesis-fig-2.5",
            "thesis-fig-2.6",
            "thesis-fig-2.7",
            "thesis-fig-2.8",
            "thesis-fig-2.15",
            "thesis-fig-3.2",
            "thesis-fig-3.8",
            "thesis-fig-3.18",
            "thesis-fig-4.9",
            "thesis-fig-4.10",
            "thesis-fig-4.11",
            "thesis-fig-4.12",
            "thesis-fig-5.8",
            "thesis-fig-5.9",
            "thesis-fig-5.10",
            "thesis-fig-6.4",
            "thesis-fig-6.7",
            "huang-1",
            "cvpr2017-fig-7",
            "cvpr2017-fig-8",
            "cvpr2017-fig-9",
        ] {
            assert!(cat.item(id).is_some(), "{id} missing");
        }
        // Values typed from the printed tables, spot-checked against the papers.
        let value = |item: &str, label: &str| {
            cat.values_of(item).find(|v| v.label == label).unwrap_or_else(|| panic!("{item}: {label}")).published
        };
        assert_eq!(value("thesis-fig-2.15", "DTW + VLS, slope 3: mean normalised cost"), 0.1860);
        assert_eq!(value("thesis-fig-3.8", "alpha = 0.2: essential graph, mean shortest-path cost"), 4.5102);
        assert_eq!(value("thesis-fig-2.7", "Actor 2: Pearson, ours"), 0.9189);
        assert_eq!(value("huang-1", "Character1 Walk#16 -> Jog#13: time error rms"), 4.81);
        assert_eq!(cat.values_of("huang-1").count(), 12 * 10 + 1);
        // Item evals name real `surfcap eval` subcommands.
        let evals = [
            "",
            "pose-metric",
            "interpolation",
            "transitions",
            "graphs",
            "appearance",
            "transfer",
            "vary",
            "smg",
            "root-motion",
            "interchange",
        ];
        for it in &cat.items {
            assert!(evals.contains(&it.eval.as_str()), "{}: eval {:?}", it.id, it.eval);
        }
    }

    #[test]
    fn a_typo_in_a_file_is_an_error_naming_file_and_place() {
        let item = "[[item]]\nid = \"a\"\nsource = \"thesis\"\nkind = \"figure\"\nnumber = \"1\"\ntitle = \"t\"\neval = \"\"\n";
        let value = |item: &str, better: &str, tol: &str| {
            format!(
                "[[value]]\nitem = \"{item}\"\nlabel = \"l\"\npublished = 1.0\nunit = \"\"\nread_off_plot = false\n\
                 where = \"Fig. 1\"\nmeasured = \"/x\"\nbetter = \"{better}\"\ntolerance = {tol}\nnote = \"\"\n"
            )
        };
        assert!(PublishedCatalogue::parse("ok.toml", &format!("{item}{}", value("a", "lower", "0.1"))).is_ok());
        let err = |text: String| PublishedCatalogue::parse("bad.toml", &text).unwrap_err().to_string();
        let e = err(format!("{item}{item}"));
        assert!(e.contains("bad.toml") && e.contains("item \"a\""), "{e}");
        let e = err(format!("{item}{}", value("b", "lower", "0.1")));
        assert!(e.contains("item id listed"), "{e}");
        let e = err(format!("{item}{}", value("a", "smaller", "0.1")));
        assert!(e.contains("bad.toml, line 16"), "{e}");
        let e = err(format!("{item}{}", value("a", "lower", "0.0")));
        assert!(e.contains("tolerance > 0"), "{e}");
        let e = err(format!("{item}{}", value("a", "lower", "0.1")).replace("note = ", "nte = "));
        assert!(e.contains("nte"), "{e}");
    }

    #[test]
    fn a_measurement_is_read_divided_and_scaled() {
        let cat = PublishedCatalogue::load_builtin().unwrap();
        let result =
            serde_json::json!({"rows": [{"essential_graph": {"density": 0.02}, "motion_graph": {"density": 0.04}}]});
        let v = cat.values_of("thesis-fig-3.2").next().unwrap();
        assert_eq!(v.measure(&result), Some(0.5));
        let smoothness =
            cat.values_of("huang-1").find(|v| v.label.ends_with("Stand#1 -> Hit#45: smoothness min")).unwrap();
        let smg = serde_json::json!({"pairs": [{"smoothness_min": 0.0424}]});
        assert!((smoothness.measure(&smg).unwrap() - 4.24).abs() < 1e-12);
        assert_eq!(v.measure(&serde_json::json!({"rows": []})), None);
    }

    /// The pointers of the evals cheap enough for a unit test resolve to numbers in the result
    /// JSON those evals write with their default lists (slopes 2-5, the six alphas).
    #[test]
    fn the_pointers_resolve_in_the_results_of_transitions_graphs_and_interpolation() {
        use crate::test_subjects::{pipeline, worm};
        use surfcap_motion::dtw::FirstStep;
        use surfcap_motion::transition_table::TableParams;
        let cat = PublishedCatalogue::load_builtin().unwrap();
        let transitions = crate::transition_costs_eval(
            &pipeline(worm(9.0)),
            &crate::TransitionCostsOptions {
                slopes: vec![2, 3, 4, 5],
                fixed: None,
                plot_pairs: 5,
                first_step: FirstStep::Straight,
                normalisation: surfcap_motion::dtw::Normalisation::SumThenDivide,
            },
        )
        .unwrap();
        let alphas =
            [0.01, 0.02, 0.03, 0.05, 0.1, 0.2].map(|a| surfcap_motion::edge_weights::Alpha::new(a).unwrap()).to_vec();
        let graphs = crate::graph_comparison_eval(
            &pipeline(worm(30.0)),
            &crate::GraphComparisonOptions {
                alphas,
                plot_pairs: 5,
                table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
                ties: crate::graph_comparison_eval::TieReading::Surfcap,
            },
        )
        .unwrap();
        let interpolation = crate::interpolation_eval(
            &worm(30.0),
            &crate::InterpolationOptions {
                pairs: vec!["0,12".into()],
                lambda: 0.5,
                stretch: surfcap_geometry::pose_interpolation::StretchInterpolation::Linear,
                sweeps: false,
            },
        )
        .unwrap();
        let results = [
            ("transitions", serde_json::to_value(&transitions).unwrap()),
            ("graphs", serde_json::to_value(&graphs).unwrap()),
            ("interpolation", serde_json::to_value(&interpolation).unwrap()),
        ];
        let mut checked = 0;
        for (eval, json) in &results {
            for it in cat.items.iter().filter(|i| i.eval == *eval) {
                for v in cat.values_of(&it.id).filter(|v| !v.measured.is_empty()) {
                    assert!(v.measure(json).is_some(), "{}: {} ({} {})", it.id, v.label, v.measured, v.measured_over);
                    checked += 1;
                }
            }
        }
        assert!(checked >= 40, "{checked} pointers checked");
    }

    const ONE: &str = r#"
[[item]]
id = "thesis-fig-2.15"
source = "thesis"
kind = "figure"
number = "2.15"
title = "t"
page = 47
eval = "transitions"

[[value]]
item = "thesis-fig-2.15"
label = "a"
published = 0.5
unit = ""
read_off_plot = false
where = "Fig. 2.15"
measured = "/rows/0/x"
better = "lower"
tolerance = 0.1
note = ""
"#;

    #[test]
    fn status_follows_tolerance_and_direction() {
        let c = PublishedCatalogue::parse("a.toml", ONE).unwrap();
        let v = &c.values[0];
        assert_eq!(status(v, Some(0.54)), Status::Reproduced);
        assert_eq!(status(v, Some(0.46)), Status::Reproduced);
        assert_eq!(status(v, Some(0.3)), Status::Better);
        assert_eq!(status(v, Some(0.7)), Status::Differs);
        assert_eq!(status(v, None), Status::NotMeasured);
        assert_eq!(status(v, Some(f64::NAN)), Status::NotMeasured);
        let mut closer = v.clone();
        closer.better = Better::Closer;
        assert_eq!(status(&closer, Some(0.3)), Status::Differs);
        let mut zero = v.clone();
        zero.published = 0.0;
        assert_eq!(status(&zero, Some(0.05)), Status::Reproduced);
    }

    #[test]
    fn selection_by_number_id_and_short_source() {
        let huang = ONE.replace("thesis-fig-2.15", "huang2009-table-1").replace("\"thesis\"", "\"huang2009\"");
        let huang = huang.replace("\"figure\"", "\"table\"").replace("\"2.15\"", "\"1\"");
        let mut c = PublishedCatalogue::parse("a.toml", ONE).unwrap();
        let h = PublishedCatalogue::parse("b.toml", &huang).unwrap();
        c.items.extend(h.items);
        c.values.extend(h.values);
        let ids = |s: Vec<&PublishedItem>| s.iter().map(|i| i.id.clone()).collect::<Vec<_>>();
        assert_eq!(ids(c.select(false, &["2.15".into()], &[], &[]).unwrap()), ["thesis-fig-2.15"]);
        assert_eq!(ids(c.select(false, &[], &["huang-1".into()], &[]).unwrap()), ["huang2009-table-1"]);
        assert_eq!(ids(c.select(false, &[], &["huang2009-table-1".into()], &[]).unwrap()), ["huang2009-table-1"]);
        assert_eq!(c.select(true, &[], &[], &[]).unwrap().len(), 2);
        let e = c.select(false, &["1".into()], &[], &[]).unwrap_err().to_string();
        assert!(e.contains("--figure 1") && e.contains("--list"), "{e}");
        // The built-in files answer the names the brief uses.
        let cat = PublishedCatalogue::load_builtin().unwrap();
        assert_eq!(ids(cat.select(false, &[], &["huang-1".into()], &[]).unwrap()), ["huang-1"]);
        assert_eq!(ids(cat.select(false, &["2.15".into()], &[], &[]).unwrap()), ["thesis-fig-2.15"]);
        assert_eq!(cat.item("huang-1").unwrap().display_name(), "Huang et al. 2009 Table 1");
        // surfcap's own checks: by --check name, with --all, never by --figure.
        assert_eq!(ids(cat.select(false, &[], &[], &["root-motion".into()]).unwrap()), ["surfcap-check-root-motion"]);
        assert!(cat.select(false, &["interchange".into()], &[], &[]).is_err());
        let all = ids(cat.select(true, &[], &[], &[]).unwrap());
        assert!(all.contains(&"surfcap-check-interchange".to_string()), "{all:?}");
        assert_eq!(cat.item("surfcap-check-interchange").unwrap().display_name(), "surfcap's own check: interchange");
    }

    #[test]
    fn a_check_is_surfcaps_and_names_its_eval() {
        let check = "[[item]]\nid = \"c\"\nsource = \"surfcap\"\nkind = \"check\"\nnumber = \"c\"\ntitle = \"t\"\neval = \"e\"\n";
        assert!(PublishedCatalogue::parse("s.toml", check).is_ok());
        let e = PublishedCatalogue::parse("s.toml", &check.replace("\"surfcap\"", "\"thesis\"")).unwrap_err();
        assert!(e.to_string().contains("s.toml: item \"c\": kind \"check\" exactly for source"), "{e}");
        let e = PublishedCatalogue::parse("s.toml", &check.replace("\"check\"", "\"figure\"")).unwrap_err();
        assert!(e.to_string().contains("exactly for source"), "{e}");
        let e = PublishedCatalogue::parse("s.toml", &check.replace("eval = \"e\"", "eval = \"\"")).unwrap_err();
        assert!(e.to_string().contains("names the eval"), "{e}");
    }

    #[test]
    fn pointers_read_numbers_and_booleans() {
        let r = serde_json::json!({"rows": [{"x": 0.25, "ok": true, "s": "a"}]});
        assert_eq!(measured_value(&r, "/rows/0/x"), Some(0.25));
        assert_eq!(measured_value(&r, "/rows/0/ok"), Some(1.0));
        assert_eq!(measured_value(&r, "/rows/0/s"), None);
        assert_eq!(measured_value(&r, "/rows/1/x"), None);
        assert_eq!(measured_value(&r, ""), None);
    }

    /// The transfer pointers name curves by index into `eval transfer`'s report: two curves
    /// (random, key-seeded) per method of `Method::ALL` in order, then the GP-NN whole-body
    /// curve. Each pointer's curve must be the method its label names, so that a method added
    /// to the eval (e.g. the nearest-pose baseline) cannot silently shift a comparison.
    #[test]
    fn transfer_pointers_name_the_curves_their_labels_compare() {
        use crate::transfer_eval::Method;
        let cat = PublishedCatalogue::load_builtin().unwrap();
        let curve_name = |k: usize| -> String {
            if k < 2 * Method::ALL.len() {
                Method::ALL[k / 2].name().to_string()
            } else {
                assert_eq!(k, 2 * Method::ALL.len(), "curve {k} is past the whole-body curve");
                "whole body".to_string()
            }
        };
        let mut checked = 0;
        for v in &cat.values {
            let transfer = cat.item(&v.item).is_some_and(|i| i.eval == "transfer");
            for pointer in [&v.measured, &v.measured_over] {
                let Some(rest) = pointer.strip_prefix("/cases/0/curves/") else { continue };
                assert!(transfer, "{}: {pointer}", v.label);
                let k: usize = rest.split('/').next().unwrap().parse().unwrap();
                let name = curve_name(k);
                assert!(v.label.contains(&name), "{} ({pointer}): curve {k} is {name}", v.label);
                checked += 1;
            }
        }
        assert!(checked >= 40, "only {checked} transfer pointers checked");
    }
}

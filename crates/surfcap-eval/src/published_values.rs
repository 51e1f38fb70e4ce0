//! The published values of the thesis and the two papers (`published/*.toml`, embedded in the
//! program), the items they belong to, which items a `--figure` / `--table` selection names, and
//! how a measured value compares with a published one: reproduced (within the relative
//! tolerance), better (outside it, on the side the value's `better` names), differs (with the
//! value's or the item's note as the reason) or not measured.
//!
//! The schema: one file per source, `[[item]]` tables (id, source, kind, number, title, page,
//! eval, note) and `[[value]]` tables (item, label, published, unit, read_off_plot, where,
//! measured, better, tolerance, note); `measured` is a JSON pointer into the report the item's
//! `surfcap eval` writes.

use serde::{Deserialize, Serialize};

/// The embedded published-values files, by name.
pub const EMBEDDED: [(&str, &str); 3] = [
    ("thesis.toml", include_str!("../published/thesis.toml")),
    ("huang2009.toml", include_str!("../published/huang2009.toml")),
    ("cvpr2017.toml", include_str!("../published/cvpr2017.toml")),
];

/// What is wrong with a published-values file or a selection of its items.
#[derive(Debug, thiserror::Error)]
pub enum PublishedError {
    /// A file that is not valid TOML of the schema: the file, and toml's message (line, column,
    /// field and what was expected).
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A file that parses but breaks a rule of the schema.
    #[error("{file}: {what}")]
    Invalid { file: String, what: String },
    /// A `--figure` / `--table` value that names no item.
    #[error("--{option} {value}: no such {option} in the catalogue (see `surfcap reproduce --list`)")]
    NoSuchItem { option: &'static str, value: String },
}

/// A page reference as printed: a number, or text ("iv", "5-6").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Page {
    Number(i64),
    Text(String),
}

/// One figure or table of a paper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PublishedItem {
    /// Stable id ("thesis-fig-2.15").
    pub id: String,
    /// thesis | huang2009 | cvpr2017.
    pub source: String,
    /// figure | table.
    pub kind: String,
    /// As printed ("2.15", "1").
    pub number: String,
    pub title: String,
    #[serde(default)]
    pub page: Option<Page>,
    /// The `surfcap eval <name>` that reproduces it ("" if none yet).
    #[serde(default)]
    pub eval: String,
    #[serde(default)]
    pub note: String,
}

/// How ours compares with the published value when it is outside the tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Better {
    Lower,
    Higher,
    /// Only agreement counts: outside the tolerance it differs.
    #[default]
    Closer,
}

/// One published number.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PublishedValue {
    /// The id of its item.
    pub item: String,
    pub label: String,
    pub published: f64,
    #[serde(default)]
    pub unit: String,
    /// Read off a plot (true) or typed from text or a table (false).
    #[serde(default)]
    pub read_off_plot: bool,
    /// Where in the paper.
    #[serde(default, rename = "where")]
    pub place: String,
    /// JSON pointer into the eval's report ("" if none matches).
    #[serde(default)]
    pub measured: String,
    #[serde(default)]
    pub better: Better,
    /// Relative tolerance of "reproduced".
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    #[serde(default)]
    pub note: String,
}

fn default_tolerance() -> f64 {
    0.1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    item: Vec<PublishedItem>,
    #[serde(default)]
    value: Vec<PublishedValue>,
}

/// Every item and value of the published-values files, items in file order.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Catalogue {
    pub items: Vec<PublishedItem>,
    pub values: Vec<PublishedValue>,
}

/// The catalogue of the embedded files ([`EMBEDDED`]).
pub fn embedded_catalogue() -> Result<Catalogue, PublishedError> {
    parse_catalogue(&EMBEDDED)
}

/// Parses `(file name, text)` pairs into one catalogue. Refused: invalid TOML, a duplicate item
/// id, a value whose item is missing, a kind other than figure or table, a published value or
/// tolerance that is not a finite number (tolerance >= 0), a pointer not starting with "/".
pub fn parse_catalogue(files: &[(&str, &str)]) -> Result<Catalogue, PublishedError> {
    let mut cat = Catalogue::default();
    let mut owner: Vec<&str> = Vec::new();
    for (name, text) in files {
        let f: File = toml::from_str(text)
            .map_err(|e| PublishedError::Parse { file: name.to_string(), message: e.to_string() })?;
        let invalid = |what: String| PublishedError::Invalid { file: name.to_string(), what };
        for it in f.item {
            if let Some(k) = cat.items.iter().position(|x| x.id == it.id) {
                return Err(invalid(format!("item {:?} is also defined in {}", it.id, owner[k])));
            }
            if it.kind != "figure" && it.kind != "table" {
                return Err(invalid(format!("item {:?}: kind {:?}: expected figure or table", it.id, it.kind)));
            }
            owner.push(name);
            cat.items.push(it);
        }
        for v in f.value {
            if !cat.items.iter().any(|x| x.id == v.item) {
                return Err(invalid(format!("value {:?}: item {:?} is not defined", v.label, v.item)));
            }
            if !v.published.is_finite() {
                return Err(invalid(format!("value {:?}: published: expected a finite number", v.label)));
            }
            if !(v.tolerance.is_finite() && v.tolerance >= 0.0) {
                return Err(invalid(format!("value {:?}: tolerance: expected a number >= 0", v.label)));
            }
            if !v.measured.is_empty() && !v.measured.starts_with('/') {
                return Err(invalid(format!(
                    "value {:?}: measured {:?}: expected a JSON pointer starting with \"/\" (or \"\")",
                    v.label, v.measured
                )));
            }
            cat.values.push(v);
        }
    }
    Ok(cat)
}

impl Catalogue {
    /// The values of item `id`, in file order.
    pub fn values_of<'a>(&'a self, id: &'a str) -> impl Iterator<Item = &'a PublishedValue> + 'a {
        self.values.iter().filter(move |v| v.item == id)
    }

    /// The items a selection names, in catalogue order, each once: every item with `all`, else
    /// those `figures` and `tables` name ([`PublishedItem::is_named_by`]). A name matching no
    /// item is refused.
    pub fn select(
        &self,
        all: bool,
        figures: &[String],
        tables: &[String],
    ) -> Result<Vec<&PublishedItem>, PublishedError> {
        if all {
            return Ok(self.items.iter().collect());
        }
        let mut chosen = vec![false; self.items.len()];
        for (option, kind, names) in [("figure", "figure", figures), ("table", "table", tables)] {
            for name in names {
                let mut found = false;
                for (k, it) in self.items.iter().enumerate() {
                    if it.kind == kind && it.is_named_by(name) {
                        chosen[k] = true;
                        found = true;
                    }
                }
                if !found {
                    return Err(PublishedError::NoSuchItem { option, value: name.clone() });
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
        let short = self.source.trim_end_matches(|c: char| c.is_ascii_digit());
        name == self.id
            || name == self.number
            || name == format!("{}-{}", self.source, self.number)
            || name == format!("{short}-{}", self.number)
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
/// on the side `v.better` names, else differs; not measured without a value.
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

/// The number at JSON pointer `pointer` of `report`: a number, or a boolean as 1 / 0.
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
measured = "/rows/0/x"
better = "lower"
tolerance = 0.1
"#;

    #[test]
    fn the_embedded_files_parse() {
        let c = embedded_catalogue().unwrap();
        assert!(!c.items.is_empty());
    }

    #[test]
    fn status_follows_tolerance_and_direction() {
        let c = parse_catalogue(&[("a.toml", ONE)]).unwrap();
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
        let c = parse_catalogue(&[("a.toml", ONE), ("b.toml", &huang)]).unwrap();
        let ids = |s: Vec<&PublishedItem>| s.iter().map(|i| i.id.clone()).collect::<Vec<_>>();
        assert_eq!(ids(c.select(false, &["2.15".into()], &[]).unwrap()), ["thesis-fig-2.15"]);
        assert_eq!(ids(c.select(false, &[], &["huang-1".into()]).unwrap()), ["huang2009-table-1"]);
        assert_eq!(ids(c.select(false, &[], &["huang2009-table-1".into()]).unwrap()), ["huang2009-table-1"]);
        assert_eq!(c.select(true, &[], &[]).unwrap().len(), 2);
        let e = c.select(false, &["1".into()], &[]).unwrap_err().to_string();
        assert!(e.contains("--figure 1") && e.contains("--list"), "{e}");
    }

    #[test]
    fn bad_files_name_the_file_and_the_field() {
        let e = parse_catalogue(&[("t.toml", "[[item]]\nid = 3\n")]).unwrap_err().to_string();
        assert!(e.starts_with("t.toml:") && e.contains("line"), "{e}");
        let e = parse_catalogue(&[("t.toml", &ONE.replace("item = \"thesis", "item = \"nope"))]).unwrap_err();
        assert!(e.to_string().contains("\"nope-fig-2.15\" is not defined"), "{e}");
        let e = parse_catalogue(&[("a.toml", ONE), ("b.toml", ONE)]).unwrap_err().to_string();
        assert!(e.contains("b.toml") && e.contains("also defined in a.toml"), "{e}");
        let e = parse_catalogue(&[("t.toml", &ONE.replace("/rows/0/x", "rows"))]).unwrap_err().to_string();
        assert!(e.contains("JSON pointer"), "{e}");
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
}

//! How numbers, counts and lengths read in the messages and summaries this crate makes.

use surfcap_mesh::{Subject, Units};

/// `n` and `word`, with an "s" unless `n` is 1 ("1 sequence", "2 sequences").
pub fn count_of(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// A number with at most 3 decimals, no trailing zeros and never "-0".
pub fn fmt_number(x: f64) -> String {
    let s = format!("{:.3}", x + 0.0);
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

/// A fraction as a percentage (`12.5%`).
pub fn fmt_percent(r: f64) -> String {
    format!("{}%", fmt_number(100.0 * r))
}

/// The name lengths are given in: the unit's symbol, or "units" when it has no known size
/// ([`surfcap_mesh::Units::symbol`]).
pub fn unit_name(units: &Units) -> &str {
    units.symbol()
}

/// The subject's length unit as reports name it.
pub fn length_unit(s: &Subject) -> String {
    unit_name(&s.units).to_string()
}

/// A length in the subject's units, as "3.00 m" (or "3.00 units"), `decimals` after the point.
pub fn length(x: f64, units: &Units, decimals: usize) -> String {
    format!("{:.decimals$} {}", x + 0.0, unit_name(units))
}

/// The mean of `values`, 0 for none (a float sum of nothing is -0.0).
pub fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = values.into_iter().fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

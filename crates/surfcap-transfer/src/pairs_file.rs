//! The user's key-pose pairs between two subjects (thesis 5.3: "sparse frame correspondences
//! between sequences ... given to bootstrap the motion transfer"; 5.5.1: about 5 per sequence).
//!
//! A CSV file, one pair per line: `source sequence:frame, target sequence:frame` (0-based
//! frames, as everywhere in surfcap). Blank lines and lines starting with `#` are ignored; a
//! first line `source,target` is a header. A range pairs frames one to one:
//! `walk:0-29, walk:10-39` pairs 30 frames (both ranges must have the same length), which is
//! how ground-truth pairs of identical clips are written.

use surfcap_mesh::Subject;

use crate::error::{Error, Result};

/// A pair of global frames, with the line it came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyPair {
    pub source: usize,
    pub target: usize,
    pub line: usize,
}

/// Resolves `seq:frame` or `seq:a-b` into global frames of `s`.
fn frames(s: &Subject, spec: &str) -> std::result::Result<Vec<usize>, String> {
    let spec = spec.trim();
    let (name, f) = spec.rsplit_once(':').ok_or_else(|| format!("{spec:?}: expected sequence:frame"))?;
    if let Some((a, b)) = f.split_once('-') {
        let (k, seq) = s.sequence(name).ok_or_else(|| {
            let known: Vec<&str> = s.sequences().iter().map(|q| q.name.as_str()).collect();
            format!("{spec:?}: no sequence {name:?}; the subject has {}", known.join(", "))
        })?;
        let parse = |t: &str| t.trim().parse::<usize>().map_err(|_| format!("{spec:?}: {t:?} is not a frame number"));
        let (a, b) = (parse(a)?, parse(b)?);
        if a > b || b >= seq.n_frames() {
            return Err(format!(
                "{spec:?}: expected a range a-b with a <= b within frames 0 to {} of {name:?}",
                seq.n_frames().saturating_sub(1)
            ));
        }
        return Ok((a..=b).map(|f| s.frame_index().global(k, f).expect("checked")).collect());
    }
    s.resolve_frame(spec).map(|g| vec![g]).map_err(|e| e.to_string())
}

/// Parses the pairs file `text` (named `file` in errors) between `source` and `target`.
pub fn parse_pairs(text: &str, file: &str, source: &Subject, target: &Subject) -> Result<Vec<KeyPair>> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let at = |why: String| Error::Invalid(format!("{file} line {line}: {why}"));
        let cols: Vec<&str> = l.split(',').map(str::trim).collect();
        if out.is_empty() && cols.len() == 2 && cols[0].eq_ignore_ascii_case("source") {
            continue;
        }
        if cols.len() != 2 {
            return Err(at(format!(
                "{} comma-separated fields: expected two, source sequence:frame and target sequence:frame",
                cols.len()
            )));
        }
        let s = frames(source, cols[0]).map_err(|e| at(format!("source {e}")))?;
        let t = frames(target, cols[1]).map_err(|e| at(format!("target {e}")))?;
        if s.len() != t.len() {
            return Err(at(format!(
                "the source names {} frames and the target {}: a range pairs frames one to one",
                s.len(),
                t.len()
            )));
        }
        out.extend(s.into_iter().zip(t).map(|(source, target)| KeyPair { source, target, line }));
    }
    if out.len() < 2 {
        return Err(Error::Invalid(format!("{file}: {} pairs: expected at least 2", out.len())));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{Sequence, Topology, Units, UpAxis};

    fn subject(names: &[(&str, usize)]) -> Subject {
        let topo = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let seqs =
            names.iter().map(|(n, f)| Sequence::new(*n, 3, (0..9 * f).map(|i| i as f32).collect()).unwrap()).collect();
        Subject::new("s", topo, seqs, 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    #[test]
    fn pairs_ranges_headers_and_comments() {
        let a = subject(&[("walk", 10), ("run", 5)]);
        let b = subject(&[("walk", 12)]);
        let p = parse_pairs("source,target\n# keys\nwalk:0, walk:1\n\nrun:1-3,walk:9-11\n", "p.csv", &a, &b).unwrap();
        let g: Vec<(usize, usize, usize)> = p.iter().map(|k| (k.source, k.target, k.line)).collect();
        assert_eq!(g, vec![(0, 1, 3), (11, 9, 5), (12, 10, 5), (13, 11, 5)]);
    }

    #[test]
    fn bad_lines_name_the_file_line_and_what_was_expected() {
        let a = subject(&[("walk", 10)]);
        let cases = [
            ("walk:0\n", "p.csv line 1: 1 comma-separated fields: expected two"),
            ("walk:0,jog:1\n", "p.csv line 1: target frame \"jog:1\": no sequence \"jog\"; the subject has walk"),
            ("walk:0,walk:10\n", "p.csv line 1: target frame \"walk:10\": sequence \"walk\" has frames 0 to 9"),
            ("walk:0-3,walk:0-2\n", "p.csv line 1: the source names 4 frames and the target 3"),
            ("walk:5-3,walk:0-2\n", "expected a range a-b with a <= b within frames 0 to 9"),
            ("walk:1,walk:1\n", "p.csv: 1 pairs: expected at least 2"),
        ];
        for (text, want) in cases {
            let e = parse_pairs(text, "p.csv", &a, &a).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }
}

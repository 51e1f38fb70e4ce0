//! The files users write to constrain a synthesis (thesis 3.5): curves to follow, key poses
//! with their new times, and motion-type restrictions along a curve. Errors name the file and
//! the line.

use std::path::Path;

use surfcap_geometry::motion_plane_alignment::plane_axes;
use surfcap_mesh::{Subject, UpAxis};
use surfcap_motion::path_following::{Curve, Restriction};

use crate::error::{Error, Result};

/// The text of a constraint file.
fn read_text(path: &Path) -> Result<String> {
    let bytes = surfcap_mesh::read_regular_file(path).map_err(|e| Error::file(path, None, e.message))?;
    String::from_utf8(bytes).map_err(|e| {
        let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()].iter().filter(|&&b| b == b'\n').count();
        Error::file(path, Some(line), "not UTF-8 text: expected a CSV file")
    })
}

/// Rows of a CSV text: blank lines and '#' comments skipped, cells split at ',', ';' or tab.
/// Each row comes with its 1-based line number.
fn csv_rows(text: &str) -> Vec<(usize, Vec<String>)> {
    let mut rows = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        rows.push((k + 1, line.split([',', ';', '\t']).map(|c| c.trim().to_string()).collect()));
    }
    rows
}

/// Reads a curve: rows of x,y,z in the subject's axes and units, or two columns for a path on
/// the ground plane (the two horizontal axes of `up`, e.g. x,z for +y up). A first row that is
/// not numeric is a header. `planar` follows only the ground-plane projection (implied by two
/// columns).
pub fn read_curve(path: &Path, up: UpAxis, planar: bool) -> Result<Curve> {
    parse_curve(&read_text(path)?, path, up, planar)
}

/// [`read_curve`] on text already read; `path` names it in errors.
pub fn parse_curve(text: &str, path: &Path, up: UpAxis, planar: bool) -> Result<Curve> {
    let mut rows = csv_rows(text);
    if rows.first().is_some_and(|(_, c)| c.iter().any(|x| x.parse::<f64>().is_err())) {
        rows.remove(0); // header
    }
    let Some((first_line, first)) = rows.first() else {
        return Err(Error::file(path, None, "no curve points"));
    };
    let cols = first.len();
    if cols != 2 && cols != 3 {
        return Err(Error::file(
            path,
            Some(*first_line),
            format!("{cols} columns; expected x,y,z or two ground-plane coordinates"),
        ));
    }
    let mut values = Vec::with_capacity(rows.len() * cols);
    for (line, cells) in &rows {
        if cells.len() != cols {
            return Err(Error::file(
                path,
                Some(*line),
                format!("{} columns, expected {cols} like the first row", cells.len()),
            ));
        }
        for c in cells {
            values.push(
                c.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| Error::file(path, Some(*line), format!("{c:?} is not a finite number")))?,
            );
        }
    }
    curve_from_points(&values, cols, path, up, planar)
}

/// A curve from points already read: `values` holds `columns` finite numbers a point, point
/// after point (3: x,y,z in the subject's axes; 2: the ground plane's two axes of `up`, e.g.
/// x,z for +y up); `planar` follows only the ground-plane projection (implied by two columns).
/// `source` names the points in errors (a file, or a front end's argument).
pub fn curve_from_points(values: &[f64], columns: usize, source: &Path, up: UpAxis, planar: bool) -> Result<Curve> {
    if columns != 2 && columns != 3 {
        return Err(Error::file(
            source,
            None,
            format!("{columns} columns; expected x,y,z or two ground-plane coordinates"),
        ));
    }
    if values.is_empty() {
        return Err(Error::file(source, None, "no curve points"));
    }
    if !values.len().is_multiple_of(columns) {
        return Err(Error::file(source, None, format!("{} numbers do not make points of {columns}", values.len())));
    }
    if let Some(k) = values.iter().position(|x| !x.is_finite()) {
        return Err(Error::file(source, None, format!("point {}: {} is not a finite number", k / columns, values[k])));
    }
    let (iu, iv, iw) = plane_axes(up);
    let points: Vec<[f64; 3]> = values
        .chunks_exact(columns)
        .map(|v| {
            if columns == 2 {
                let mut p = [0.0; 3];
                p[iu] = v[0];
                p[iv] = v[1];
                p[iw] = 0.0;
                p
            } else {
                [v[0], v[1], v[2]]
            }
        })
        .collect();
    let axes = if planar || columns == 2 { vec![iu, iv] } else { vec![0, 1, 2] };
    let curve = Curve::new(points, axes).map_err(|e| Error::file(source, None, e.to_string()))?;
    if !curve.length().is_finite() {
        // Finite coordinates can still be too far apart for their distance to be one.
        return Err(Error::file(source, None, "the curve's length overflows: expected coordinates below about 1e150"));
    }
    Ok(curve)
}

/// One key pose (thesis 3.5.2): a frame of the subject and the output frame number at which it
/// must appear.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyPose {
    /// The frame as the user wrote it (`sequence:frame` or a global index).
    pub spec: String,
    /// Its global frame index.
    pub frame: u32,
    /// Its frame number inside its own sequence.
    pub input: usize,
    /// The requested output frame number.
    pub requested: i64,
}

/// A duration or instant as users write it: `90f` (frames), `3s` or `1.5s` (seconds), or a bare
/// number whose unit the command says (key files: output frames; `reach --time`: seconds), so
/// that every command accepts both units and none changes the meaning of what worked before.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSpec {
    pub value: f64,
    /// `None` for a bare number.
    pub unit: Option<TimeUnit>,
}

/// The unit of a [`TimeSpec`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    Frames,
    Seconds,
}

impl std::str::FromStr for TimeSpec {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let t = text.trim();
        let (number, unit) = match t.char_indices().last() {
            Some((k, 'f')) => (&t[..k], Some(TimeUnit::Frames)),
            Some((k, 's')) => (&t[..k], Some(TimeUnit::Seconds)),
            _ => (t, None),
        };
        match number.trim().parse::<f64>() {
            Ok(value) if value.is_finite() && value >= 0.0 => Ok(TimeSpec { value, unit }),
            _ => Err(format!("{text:?}: expected a time >= 0 such as 90f (frames) or 3s (seconds)")),
        }
    }
}

impl TimeSpec {
    /// The time in frames at `fps` (`bare` is the unit of a bare number); seconds are rounded
    /// to the nearest frame. `None` when a frame count is not whole.
    pub fn frames(&self, fps: f64, bare: TimeUnit) -> Option<i64> {
        match self.unit.unwrap_or(bare) {
            TimeUnit::Frames => (self.value.fract() == 0.0).then_some(self.value as i64),
            TimeUnit::Seconds => Some((self.value * fps).round() as i64),
        }
    }
}

/// Reads key poses: `frame,time` rows (an optional header), times >= 0 and increasing in output
/// frames (a bare whole number, or `90f`) or seconds (`3s`, rounded to the nearest output frame
/// at the subject's rate); at least two keys.
pub fn read_key_poses(path: &Path, s: &Subject) -> Result<Vec<KeyPose>> {
    parse_key_poses(&read_text(path)?, path, s)
}

/// [`read_key_poses`] on text already read; `path` names it in errors.
pub fn parse_key_poses(text: &str, path: &Path, s: &Subject) -> Result<Vec<KeyPose>> {
    let mut rows = csv_rows(text);
    if rows.first().is_some_and(|(_, c)| c.len() == 2 && c[1].parse::<TimeSpec>().is_err()) {
        rows.remove(0);
    }
    key_poses_from_rows(rows, path, s)
}

/// Key poses from rows already split into cells, each with its number (a file's line, or a
/// front end's 1-based item number), checked as [`read_key_poses`] checks a file's: `frame,time`
/// cells, times increasing, at least two keys. `source` names the rows in errors.
pub fn key_poses_from_rows(rows: Vec<(usize, Vec<String>)>, source: &Path, s: &Subject) -> Result<Vec<KeyPose>> {
    let path = source;
    let mut keys: Vec<KeyPose> = Vec::new();
    for (line, cells) in rows {
        if cells.len() != 2 {
            return Err(Error::file(
                path,
                Some(line),
                format!("expected frame,time (2 columns), found {}", cells.len()),
            ));
        }
        let frame = s.resolve_frame(&cells[0]).map_err(|e| Error::file(path, Some(line), e.to_string()))?;
        let requested: i64 =
            cells[1].parse::<TimeSpec>().ok().and_then(|t| t.frames(s.fps, TimeUnit::Frames)).ok_or_else(|| {
                Error::file(
                    path,
                    Some(line),
                    format!(
                        "time {:?}: expected an output frame number >= 0 (a whole number such as 90 or 90f) or seconds (3s)",
                        cells[1]
                    ),
                )
            })?;
        if let Some(prev) = keys.last()
            && requested <= prev.requested
        {
            return Err(Error::file(
                path,
                Some(line),
                format!("time {requested} is not after the previous key's {}", prev.requested),
            ));
        }
        let input = s.frame_index().locate(frame).map_or(0, |l| l.1);
        keys.push(KeyPose { spec: cells[0].clone(), frame: frame as u32, input, requested });
    }
    if keys.len() < 2 {
        return Err(Error::file(path, None, format!("{} key pose(s); expected at least two", keys.len())));
    }
    Ok(keys)
}

/// Parses a motion-type restriction `TAG:FROM-TO` (arc lengths along the curve, FROM < TO):
/// there only sequences tagged TAG are used. The tag must be one of the subject's.
pub fn parse_restriction(s: &Subject, text: &str) -> Result<Restriction> {
    let bad = || Error::Request(format!("{text:?}: expected TAG:FROM-TO with arc lengths FROM < TO, e.g. run:5-9"));
    let (tag, range) = text.rsplit_once(':').ok_or_else(bad)?;
    let (a, b) = range.split_once('-').ok_or_else(bad)?;
    let (from, to): (f64, f64) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if !(from < to && from.is_finite() && to.is_finite()) {
        return Err(bad());
    }
    let allowed: Vec<bool> = s.sequences().iter().map(|q| q.tags.iter().any(|x| x == tag)).collect();
    if !allowed.iter().any(|&x| x) {
        if s.sequences().iter().all(|q| q.tags.is_empty()) {
            return Err(Error::Request(format!(
                "{text:?}: no sequence is tagged {tag:?}: the subject has no tags; tag its sequences in a surfcap.toml manifest (tags = [\"{tag}\"] in a [[sequence]] entry, see docs/formats.md, \"Manifest\") and import it again"
            )));
        }
        let mut known: Vec<&str> = s.sequences().iter().flat_map(|q| q.tags.iter().map(|x| x.as_str())).collect();
        known.sort();
        known.dedup();
        return Err(Error::Request(format!(
            "{text:?}: no sequence is tagged {tag:?}; the subject's tags are {}",
            known.join(", ")
        )));
    }
    Ok(Restriction { from, to, allowed })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};

    fn file(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(&p, text).unwrap();
        (d, p)
    }

    #[test]
    fn curves_with_headers_comments_and_two_or_three_columns() {
        let (_d, p) = file("# a path\nx,z\n0,0\n\n3,4 # end\n");
        let c = read_curve(&p, UpAxis::PosY, false).unwrap();
        assert!((c.length() - 5.0).abs() < 1e-12);
        assert_eq!(c.axes(), &[0, 2]);
        let (_d, p) = file("0,0,0\n0,2,3\n");
        let c = read_curve(&p, UpAxis::PosY, false).unwrap();
        assert!((c.length() - 13f64.sqrt()).abs() < 1e-12);
        assert_eq!(c.axes().len(), 3);
        // Planar: only the ground-plane (x, z) projection counts.
        assert!((read_curve(&p, UpAxis::PosY, true).unwrap().length() - 3.0).abs() < 1e-12);
    }

    #[test]
    fn curve_errors_name_the_file_and_line() {
        for (text, want) in [
            ("x,z\n0,0\n1,zero\n", "c.csv:3: \"zero\" is not a finite number"),
            ("0,0\n1,1,1\n", "c.csv:2: 3 columns, expected 2"),
            ("0\n1\n", "c.csv:1: 1 columns"),
            ("# nothing\n", "c.csv: no curve points"),
            ("0,0\n1e300,0\n", "c.csv: the curve's length overflows"),
        ] {
            let (_d, p) = file(text);
            let e = read_curve(&p, UpAxis::PosY, false).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let e = read_curve(Path::new("/nonexistent/c.csv"), UpAxis::PosY, false).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/c.csv: cannot read"), "{e}");
        // A FIFO is refused, not opened (opening it would block until a writer came).
        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("keys.csv");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let e = read_curve(&fifo, UpAxis::PosY, false).unwrap_err().to_string();
        assert_eq!(e, format!("{}: is a FIFO (named pipe): expected a regular file", fifo.display()));
        let (_d, p) = file("0,0\n");
        std::fs::write(&p, b"0,0\n1,\xff\n").unwrap();
        assert_eq!(
            read_curve(&p, UpAxis::PosY, false).unwrap_err().to_string(),
            format!("{}:2: not UTF-8 text: expected a CSV file", p.display())
        );
    }

    fn worm() -> Subject {
        worm_subject(&WormParams { rings: 6, segments: 6, frames: 12, ..Default::default() }).unwrap()
    }

    #[test]
    fn key_poses_and_their_errors() {
        let s = worm();
        let q = s.sequences()[0].name.clone();
        let (_d, p) = file(&format!("frame,time\n{q}:2,0\n{q}:5,10\n"));
        let keys = read_key_poses(&p, &s).unwrap();
        assert_eq!(keys.len(), 2);
        assert_eq!((keys[1].frame, keys[1].input, keys[1].requested), (5, 5, 10));
        for (text, want) in [
            (format!("{q}:2,5\n{q}:5,5\n"), "c.csv:2: time 5 is not after"),
            (format!("{q}:2,0\n{q}:5,-1\n"), "c.csv:2: time \"-1\""),
            (format!("{q}:2,0\n{q}:500,4\n"), "c.csv:2:"),
            (format!("{q}:2,0,1\n"), "c.csv:1: expected frame,time"),
            (format!("{q}:2,0\n"), "1 key pose(s)"),
            (format!("{q}:2,0\n{q}:5,2.5f\n"), "c.csv:2: time \"2.5f\": expected an output frame number >= 0"),
            (format!("{q}:2,0\n{q}:5,3x\n"), "or seconds (3s)"),
        ] {
            let (_d, p) = file(&text);
            let e = read_key_poses(&p, &s).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    /// Key times in output frames (bare or `f`) or seconds (`s`, rounded at the subject's rate).
    #[test]
    fn key_times_take_frame_and_second_suffixes() {
        let s = worm();
        let q = s.sequences()[0].name.clone();
        let (_d, p) = file(&format!("frame,time\n{q}:2,0s\n{q}:5,12f\n{q}:7,1.5s\n"));
        let keys = read_key_poses(&p, &s).unwrap();
        let want = (1.5 * s.fps).round() as i64;
        assert!(want > 12, "fps {}", s.fps);
        assert_eq!(keys.iter().map(|k| k.requested).collect::<Vec<_>>(), vec![0, 12, want]);
        assert_eq!("90".parse::<TimeSpec>().unwrap().frames(30.0, TimeUnit::Seconds), Some(2700));
        assert_eq!("90f".parse::<TimeSpec>().unwrap().frames(30.0, TimeUnit::Seconds), Some(90));
        assert!("-3s".parse::<TimeSpec>().is_err() && "s".parse::<TimeSpec>().is_err());
    }

    /// A subject without tags says so and how to add them, instead of an empty list.
    #[test]
    fn restrictions_on_an_untagged_subject_say_how_to_tag() {
        let s = worm();
        let untagged = Subject::new(
            s.name.clone(),
            s.topology().clone(),
            s.sequences()
                .iter()
                .cloned()
                .map(|mut q| {
                    q.tags.clear();
                    q
                })
                .collect(),
            s.fps,
            s.up_axis,
            s.units.clone(),
        )
        .unwrap();
        let e = parse_restriction(&untagged, "run:1-2").unwrap_err().to_string();
        assert!(e.contains("the subject has no tags; tag its sequences in a surfcap.toml manifest"), "{e}");
        assert!(!e.contains("tags are"), "{e}");
    }

    #[test]
    fn restrictions_name_known_tags() {
        let s = worm();
        let tag = s.sequences()[0].tags.first().cloned();
        if let Some(tag) = tag {
            let r = parse_restriction(&s, &format!("{tag}:1-2.5")).unwrap();
            assert_eq!((r.from, r.to), (1.0, 2.5));
            assert!(r.allowed[0]);
        }
        assert!(parse_restriction(&s, "run:9-5").unwrap_err().to_string().contains("FROM < TO"));
        assert!(parse_restriction(&s, "run").unwrap_err().to_string().contains("TAG:FROM-TO"));
        assert!(parse_restriction(&s, "moonwalk:1-2").unwrap_err().to_string().contains("no sequence is tagged"));
    }
}

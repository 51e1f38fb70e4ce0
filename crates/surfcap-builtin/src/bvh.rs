//! BVH motion capture: the hierarchy (one root, joints, end sites, any channel order), the motion
//! section (frame count, frame time, one line of numbers per frame), and forward kinematics.
//!
//! Semantics (Biovision / CMU convention): a joint's local transform is a translation by its
//! OFFSET (plus its position channels, when it has them) followed by its rotation channels
//! applied in the order they are listed, each in degrees about its own axis
//! (`Zrotation Xrotation Yrotation` means R = Rz Rx Ry). World transforms compose parent first.
//!
//! Errors name the line and what was expected: several roots, unknown channels, a CHANNELS count
//! that differs from the names listed, a second OFFSET or CHANNELS in one joint, no channels at
//! all, non-numbers, `Frames: 0`, a motion line with the wrong number of values, fewer or more
//! motion lines than `Frames:` announces. Any nesting depth parses (no recursion).

use std::path::Path;

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use surfcap_mesh::{Error, ErrorKind, Result};

/// One channel of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    fn parse(s: &str) -> Option<Channel> {
        Some(match s.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Xposition,
            "yposition" => Channel::Yposition,
            "zposition" => Channel::Zposition,
            "xrotation" => Channel::Xrotation,
            "yrotation" => Channel::Yrotation,
            "zrotation" => Channel::Zrotation,
            _ => return None,
        })
    }
}

/// A joint of the hierarchy.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub parent: Option<usize>,
    pub offset: [f64; 3],
    pub channels: Vec<Channel>,
    /// Index of this joint's first value in a motion line.
    pub first_channel: usize,
    /// End-site offsets below this joint (CMU files have at most one per joint).
    pub end_sites: Vec<[f64; 3]>,
}

/// A parsed BVH file.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// Joints in file order (parents before children).
    pub joints: Vec<Joint>,
    /// Seconds per frame.
    pub frame_time: f64,
    /// `[frames][channels]` values as written (positions in file units, angles in degrees).
    pub motion: Vec<f64>,
    pub n_channels: usize,
}

fn syntax(line: usize, msg: String) -> Error {
    Error::new(ErrorKind::Syntax, msg).at_line(line)
}

struct Tokens<'a> {
    items: Vec<(usize, &'a str)>,
    pos: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self, what: &str) -> Result<(usize, &'a str)> {
        let t = self.items.get(self.pos).copied();
        self.pos += 1;
        t.ok_or_else(|| {
            let line = self.items.last().map_or(1, |t| t.0);
            Error::new(ErrorKind::Truncated, format!("file ends before {what}")).at_line(line)
        })
    }

    fn expect(&mut self, word: &str) -> Result<usize> {
        let (line, t) = self.next(word)?;
        if !t.eq_ignore_ascii_case(word) {
            return Err(syntax(line, format!("{t:?}: expected {word:?}")));
        }
        Ok(line)
    }

    fn number(&mut self, what: &str) -> Result<f64> {
        let (line, t) = self.next(what)?;
        let x: f64 = t.parse().map_err(|_| syntax(line, format!("{t:?} is not a number: expected {what}")))?;
        if !x.is_finite() {
            return Err(Error::new(ErrorKind::NonFinite, format!("{t:?}: expected a finite {what}")).at_line(line));
        }
        Ok(x)
    }
}

/// A new joint named by the next token, its `{` read.
fn open_joint(tk: &mut Tokens, joints: &mut Vec<Joint>, parent: Option<usize>) -> Result<()> {
    let (_, name) = tk.next("a joint name")?;
    joints.push(Joint {
        name: name.to_string(),
        parent,
        offset: [0.0; 3],
        channels: Vec::new(),
        first_channel: 0,
        end_sites: Vec::new(),
    });
    tk.expect("{")?;
    Ok(())
}

/// The hierarchy from `ROOT`'s name to its closing `}`. A loop over an explicit stack of open
/// joints rather than recursion: a file nesting 100,000 joints must not overflow the stack.
/// Each joint's values in a motion line start where its CHANNELS appear in the file.
fn parse_hierarchy(tk: &mut Tokens) -> Result<(Vec<Joint>, usize)> {
    let mut joints = Vec::new();
    let mut n_channels = 0;
    open_joint(tk, &mut joints, None)?;
    let mut open = vec![0];
    let (mut has_offset, mut has_channels) = (vec![false], vec![false]);
    while let Some(&idx) = open.last() {
        let (line, t) = tk.next("'}'")?;
        let twice =
            |what: &str| syntax(line, format!("a second {what} for joint {:?}: expected one", joints[idx].name));
        match t.to_ascii_uppercase().as_str() {
            "OFFSET" => {
                if std::mem::replace(&mut has_offset[idx], true) {
                    return Err(twice("OFFSET"));
                }
                joints[idx].offset = [tk.number("an OFFSET x")?, tk.number("an OFFSET y")?, tk.number("an OFFSET z")?];
            }
            "CHANNELS" => {
                if std::mem::replace(&mut has_channels[idx], true) {
                    return Err(twice("CHANNELS"));
                }
                let (cl, c) = tk.next("a channel count")?;
                let count: usize = c.parse().map_err(|_| syntax(cl, format!("{c:?}: expected a channel count")))?;
                let mut channels = Vec::with_capacity(count.min(6));
                for k in 0..count {
                    let (l2, name) = tk.next("a channel name")?;
                    let ch = Channel::parse(name).ok_or_else(|| {
                        let structural =
                            ["JOINT", "END", "OFFSET", "CHANNELS", "}"].iter().any(|k| name.eq_ignore_ascii_case(k));
                        if name.parse::<f64>().is_ok() || structural {
                            syntax(l2, format!("CHANNELS {count} lists only {k} channels: expected {count} names"))
                        } else {
                            syntax(l2, format!("unknown channel {name:?}: expected X/Y/Z position or rotation"))
                        }
                    })?;
                    channels.push(ch);
                }
                joints[idx].first_channel = n_channels;
                n_channels += channels.len();
                joints[idx].channels = channels;
            }
            "JOINT" => {
                open_joint(tk, &mut joints, Some(idx))?;
                open.push(joints.len() - 1);
                has_offset.push(false);
                has_channels.push(false);
            }
            "END" => {
                tk.expect("Site")?;
                tk.expect("{")?;
                tk.expect("OFFSET")?;
                let o = [tk.number("an End Site x")?, tk.number("an End Site y")?, tk.number("an End Site z")?];
                tk.expect("}")?;
                joints[idx].end_sites.push(o);
            }
            "}" => {
                open.pop();
            }
            "ROOT" => return Err(syntax(line, "a second ROOT: surfcap reads BVH files with one skeleton".into())),
            _ => return Err(syntax(line, format!("{t:?}: expected OFFSET, CHANNELS, JOINT, End Site or '}}'"))),
        }
    }
    Ok((joints, n_channels))
}

/// Parses BVH text.
pub fn parse_bvh(text: &str) -> Result<Bvh> {
    // The motion section starts at the first line that is the word MOTION (a joint name may
    // contain it).
    let motion_at = text
        .split_inclusive('\n')
        .scan(0, |at, l| {
            let start = *at;
            *at += l.len();
            Some((start, l))
        })
        .find(|(_, l)| l.trim().eq_ignore_ascii_case("MOTION"))
        .map(|(start, _)| start);
    let head = &text[..motion_at.unwrap_or(text.len())];
    let items: Vec<(usize, &str)> =
        head.lines().enumerate().flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 1, t))).collect();
    if items.is_empty() {
        return Err(Error::new(ErrorKind::Empty, "empty file: expected a BVH HIERARCHY"));
    }
    let mut tk = Tokens { items, pos: 0 };
    tk.expect("HIERARCHY")?;
    let root_line = tk.expect("ROOT")?;
    let (joints, n_channels) = parse_hierarchy(&mut tk)?;
    if let Some(&(line, t)) = tk.items.get(tk.pos) {
        return Err(if t.eq_ignore_ascii_case("ROOT") {
            syntax(line, "a second ROOT: surfcap reads BVH files with one skeleton".into())
        } else {
            syntax(line, format!("{t:?} after the hierarchy: expected MOTION"))
        });
    }
    if n_channels == 0 {
        return Err(
            Error::new(ErrorKind::Shape, "no joint has CHANNELS: expected at least the root's").at_line(root_line)
        );
    }
    let Some(m) = motion_at else {
        let line = head.lines().count();
        return Err(Error::new(ErrorKind::Truncated, "no MOTION section").at_line(line));
    };
    let first_line = text[..m].lines().count() + 1;
    let mut lines =
        text[m..].lines().enumerate().map(|(i, l)| (first_line + i, l)).skip(1).filter(|(_, l)| !l.trim().is_empty());
    let mut field = |key: &str| -> Result<(usize, String)> {
        let (line, l) = lines
            .next()
            .ok_or_else(|| Error::new(ErrorKind::Truncated, format!("file ends before {key:?}")).at_line(first_line))?;
        let rest =
            l.trim().strip_prefix(key).ok_or_else(|| syntax(line, format!("{:?}: expected {key:?}", l.trim())))?;
        Ok((line, rest.trim().to_string()))
    };
    let (fl, frames) = field("Frames:")?;
    let frames: usize = frames.parse().map_err(|_| syntax(fl, format!("{frames:?}: expected a frame count")))?;
    if frames == 0 {
        return Err(Error::new(ErrorKind::Empty, "Frames: 0: expected at least one frame of motion").at_line(fl));
    }
    let (tl, ft) = field("Frame Time:")?;
    let frame_time: f64 = ft.parse().map_err(|_| syntax(tl, format!("{ft:?}: expected seconds per frame")))?;
    surfcap_mesh::subject::check_frame_time(frame_time).map_err(|e| syntax(tl, e.message))?;
    // Reserve no more than the text can hold (a value takes at least two bytes), so a huge
    // 'Frames:' in a small file costs nothing before its error.
    let mut motion = Vec::with_capacity(frames.saturating_mul(n_channels).min((text.len() - m) / 2 + 1));
    let mut last = tl;
    for f in 0..frames {
        let Some((line, l)) = lines.next() else {
            return Err(Error::new(
                ErrorKind::Truncated,
                format!("motion ends after {f} of the {frames} frames 'Frames:' announces (line {fl})"),
            )
            .at_line(last + 1));
        };
        last = line;
        let before = motion.len();
        for t in l.split_whitespace() {
            let x: f64 =
                t.parse().map_err(|_| syntax(line, format!("{t:?} is not a number: expected a channel value")))?;
            if !x.is_finite() {
                return Err(Error::new(ErrorKind::NonFinite, format!("{t:?}: expected a finite value")).at_line(line));
            }
            motion.push(x);
        }
        let got = motion.len() - before;
        if got != n_channels {
            return Err(Error::new(ErrorKind::Shape, format!("{got} values: expected {n_channels} (one per channel)"))
                .at_line(line));
        }
    }
    if let Some((line, _)) = lines.next() {
        return Err(Error::new(
            ErrorKind::Shape,
            format!("more motion lines than the {frames} frames 'Frames:' announces (line {fl})"),
        )
        .at_line(line));
    }
    Ok(Bvh { joints, frame_time, motion, n_channels })
}

/// Reads a BVH file; errors name it.
pub fn read_bvh(path: &Path) -> Result<Bvh> {
    let bytes = surfcap_mesh::read_regular_file(path)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| Error::new(ErrorKind::Syntax, "not UTF-8 text: expected a BVH file").in_file(path))?;
    parse_bvh(&text).map_err(|e| e.in_file(path))
}

impl Bvh {
    pub fn n_frames(&self) -> usize {
        self.motion.len().checked_div(self.n_channels).unwrap_or(0)
    }

    /// Frames per second. Files write the frame time rounded (0.0333333 for 30 fps): a rate
    /// within 0.01% of a whole number is that number.
    pub fn fps(&self) -> f64 {
        let fps = 1.0 / self.frame_time;
        if (fps - fps.round()).abs() < 1e-4 * fps { fps.round() } else { fps }
    }

    /// Local transform of joint `j` at frame `f`.
    pub fn local(&self, f: usize, j: usize) -> Isometry3<f64> {
        let joint = &self.joints[j];
        let values = &self.motion[f * self.n_channels + joint.first_channel..][..joint.channels.len()];
        let mut t = Vector3::from(joint.offset);
        let mut r = UnitQuaternion::identity();
        for (c, &v) in joint.channels.iter().zip(values) {
            let a = v.to_radians();
            match c {
                Channel::Xposition => t.x += v,
                Channel::Yposition => t.y += v,
                Channel::Zposition => t.z += v,
                Channel::Xrotation => {
                    r *= UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(&Vector3::x_axis(), a))
                }
                Channel::Yrotation => {
                    r *= UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(&Vector3::y_axis(), a))
                }
                Channel::Zrotation => {
                    r *= UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(&Vector3::z_axis(), a))
                }
            }
        }
        Isometry3::from_parts(Translation3::from(t), r)
    }

    /// Vertical extent (y) of the rest pose (offsets only, every rotation zero), end sites
    /// included: the standing height of the skeleton, in the file's units.
    pub fn rest_height(&self) -> f64 {
        let mut pos: Vec<Vector3<f64>> = Vec::with_capacity(self.joints.len());
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for joint in &self.joints {
            let p = joint.parent.map_or(Vector3::zeros(), |q| pos[q]) + Vector3::from(joint.offset);
            for e in std::iter::once(Vector3::zeros()).chain(joint.end_sites.iter().map(|&e| Vector3::from(e))) {
                lo = lo.min(p.y + e.y);
                hi = hi.max(p.y + e.y);
            }
            pos.push(p);
        }
        hi - lo
    }

    /// BVH files carry no unit. Guess it from the rest pose's height: of metres, centimetres,
    /// millimetres, inches and CMU's ASF length unit (1/0.45 inch = 0.056444 m, used by the
    /// cgspeed conversions), the one that makes the skeleton closest to 1.6 m tall
    /// (in ratio). Returns metres per unit and the unit's name.
    pub fn guess_metres_per_unit(&self) -> (f64, &'static str) {
        const UNITS: [(f64, &str); 5] = [
            (1.0, "metres"),
            (0.01, "centimetres"),
            (0.001, "millimetres"),
            (0.0254, "inches"),
            (0.0254 / 0.45, "CMU ASF length units (1/0.45 inch)"),
        ];
        let h = self.rest_height().max(1e-12);
        UNITS
            .into_iter()
            .min_by(|a, b| (a.0 * h / 1.6).ln().abs().total_cmp(&(b.0 * h / 1.6).ln().abs()))
            .expect("a list of units")
    }

    /// World transforms of every joint at frame `f` (forward kinematics).
    pub fn world(&self, f: usize) -> Vec<Isometry3<f64>> {
        let mut out: Vec<Isometry3<f64>> = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.joints.iter().enumerate() {
            let local = self.local(f, j);
            out.push(match joint.parent {
                Some(p) => out[p] * local,
                None => local,
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "HIERARCHY\r\nROOT hips\r\n{\r\n OFFSET 0 0 0\r\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\r\n \
        JOINT knee\r\n {\r\n  OFFSET 0 -10 0\r\n  CHANNELS 3 Xrotation Yrotation Zrotation\r\n  End Site\r\n  {\r\n   OFFSET 0 -5 0\r\n  }\r\n }\r\n}\r\n\
        MOTION\r\nFrames: 2\r\nFrame Time: 0.5\r\n1 2 3 0 0 0 0 0 0\r\n1 2 3 90 0 0 0 0 0\r\n";

    #[test]
    fn parses_channels_and_runs_forward_kinematics() {
        let b = parse_bvh(SMALL).unwrap();
        assert_eq!((b.joints.len(), b.n_channels, b.n_frames(), b.fps()), (2, 9, 2, 2.0));
        assert_eq!(b.joints[1].parent, Some(0));
        assert_eq!(b.joints[1].end_sites, vec![[0.0, -5.0, 0.0]]);
        let w0 = b.world(0);
        assert!((w0[1].translation.vector - Vector3::new(1.0, -8.0, 3.0)).norm() < 1e-12);
        // Frame 1 turns the root by 90 degrees about z: the knee swings to +x.
        let w1 = b.world(1);
        assert!(
            (w1[1].translation.vector - Vector3::new(11.0, 2.0, 3.0)).norm() < 1e-9,
            "{}",
            w1[1].translation.vector
        );
    }

    #[test]
    fn bad_files_name_the_line() {
        let cases: Vec<(String, ErrorKind, usize)> = vec![
            (SMALL.replace("Frames: 2", "Frames: 3"), ErrorKind::Truncated, 21),
            (SMALL.replace("1 2 3 90 0 0 0 0 0", "1 2 3 90 0 0 0 0"), ErrorKind::Shape, 20),
            (SMALL.replace("1 2 3 90 0 0 0 0 0", "1 2 x 90 0 0 0 0 0"), ErrorKind::Syntax, 20),
            (SMALL.replace("CHANNELS 3 Xrotation", "CHANNELS 4 Xrotation"), ErrorKind::Syntax, 10),
            (SMALL.replace("Zrotation Xrotation Yrotation", "Zrotation Wrotation Yrotation"), ErrorKind::Syntax, 5),
            (SMALL.replace("MOTION", "ROOT other\r\n{\r\n}\r\nMOTION"), ErrorKind::Syntax, 16),
            (SMALL.replace("OFFSET 0 -10 0", "OFFSET 0 abc 0"), ErrorKind::Syntax, 8),
            (SMALL.replace("Frame Time: 0.5", "Frame Time: 0"), ErrorKind::Syntax, 18),
        ];
        for (text, kind, line) in cases {
            let e = parse_bvh(&text).unwrap_err();
            assert_eq!((e.kind, e.location.clone()), (kind, Some(surfcap_mesh::Location::Line(line))), "{e}");
        }
        assert_eq!(parse_bvh("").unwrap_err().kind, ErrorKind::Empty);
        for ft in ["1e-300", "1e300", "0.00001", "11"] {
            let e = parse_bvh(&SMALL.replace("Frame Time: 0.5", &format!("Frame Time: {ft}"))).unwrap_err();
            assert_eq!(e.location, Some(surfcap_mesh::Location::Line(18)), "{e}");
            assert!(e.to_string().contains("a frame time of 1e-4 to 10 s"), "{e}");
        }
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("fast.bvh");
        std::fs::write(&f, SMALL.replace("Frame Time: 0.5", "Frame Time: 1e-300")).unwrap();
        let e = read_bvh(&f).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: line 18: frame time 1e-300 s", f.display())), "{e}");
        for ft in ["0.0001", "10", "0.0083333"] {
            assert!(parse_bvh(&SMALL.replace("Frame Time: 0.5", &format!("Frame Time: {ft}"))).is_ok(), "{ft}");
        }
        let e = parse_bvh(&SMALL.replace("Frames: 2", "Frames: 0")).unwrap_err();
        assert_eq!(e.to_string(), "line 17: Frames: 0: expected at least one frame of motion");
        let e = parse_bvh(&SMALL.replace("1 2 3 90 0 0 0 0 0\r\n", "1 2 3 90 0 0 0 0 0\r\n1 2 3 0 0 0 0 0 0\r\n"));
        assert_eq!(
            e.unwrap_err().to_string(),
            "line 21: more motion lines than the 2 frames 'Frames:' announces (line 17)"
        );
        let e = parse_bvh(&SMALL.replace("Frames: 2", "Frames: 99999999999999")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 21: motion ends after 2 of the 99999999999999 frames 'Frames:' announces (line 17)"
        );
        let e = parse_bvh(
            &SMALL
                .replace("  CHANNELS 3 Xrotation Yrotation Zrotation\r\n", "")
                .replace(" CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\r\n", ""),
        )
        .unwrap_err();
        assert_eq!(e.to_string(), "line 2: no joint has CHANNELS: expected at least the root's");
        let e =
            parse_bvh(&SMALL.replace("  OFFSET 0 -10 0\r\n", "  OFFSET 0 -10 0\r\n  OFFSET 0 -10 0\r\n")).unwrap_err();
        assert_eq!(e.to_string(), "line 9: a second OFFSET for joint \"knee\": expected one");
        let twice = SMALL.replace(
            "CHANNELS 3 Xrotation Yrotation Zrotation",
            "CHANNELS 3 Xrotation Yrotation Zrotation CHANNELS 1 Xrotation",
        );
        assert_eq!(
            parse_bvh(&twice).unwrap_err().to_string(),
            "line 9: a second CHANNELS for joint \"knee\": expected one"
        );
        assert_eq!(parse_bvh(&SMALL[..SMALL.find("JOINT").unwrap()]).unwrap_err().kind, ErrorKind::Truncated);
    }

    /// 100,000 nested joints parse without recursion (this overflowed the stack),
    /// and forward kinematics and the unit guess walk them in order.
    #[test]
    fn deep_nesting_parses_without_recursion() {
        let depth = 100_000;
        let mut t = String::from("HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n");
        for k in 1..depth {
            t.push_str(&format!("JOINT j{k}\n{{\nOFFSET 0 1 0\n"));
        }
        t.push_str(&"}\n".repeat(depth));
        t.push_str("MOTION\nFrames: 1\nFrame Time: 0.04\n1 2 3\n");
        let b = parse_bvh(&t).unwrap();
        assert_eq!((b.joints.len(), b.joints[depth - 1].parent, b.n_frames()), (depth, Some(depth - 2), 1));
        assert_eq!(b.world(0)[depth - 1].translation.vector, Vector3::new(1.0, 2.0 + (depth - 1) as f64, 3.0));
        assert_eq!(b.rest_height(), (depth - 1) as f64);
        // One brace short: an error at the end of the hierarchy, not a crash.
        let short = t.replacen("}\n", "", 1);
        assert_eq!(parse_bvh(&short).unwrap_err().kind, ErrorKind::Truncated);
    }

    /// Values come in the order CHANNELS appear in the file, even when a joint lists its channels
    /// after its children; a joint named with MOTION in it does not end the hierarchy.
    #[test]
    fn channels_after_children_and_motion_in_names() {
        let t = "HIERARCHY\nROOT MOTIONhips\n{\nOFFSET 0 0 0\nJOINT knee\n{\nOFFSET 0 -1 0\nCHANNELS 1 Xposition\n}\n\
                 CHANNELS 1 Yposition\n}\nMOTION\nFrames: 1\nFrame Time: 0.5\n7 9\n";
        let b = parse_bvh(t).unwrap();
        assert_eq!((b.joints[0].first_channel, b.joints[1].first_channel), (1, 0));
        assert_eq!(b.world(0)[1].translation.vector, Vector3::new(7.0, 8.0, 0.0));
    }
}

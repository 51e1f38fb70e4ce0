//! Global frame index <-> (sequence, frame) mapping, used by every algorithm that treats the
//! frames of all sequences as one set (distance matrices, transition tables, graphs).

use crate::error::{Result, err};

/// Prefix sums of the sequences' frame counts, and the sequences' names when known (a
/// subject's index has them), so that every layer can name a frame as the user does.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameIndex {
    /// `offsets[s]` is the global index of sequence `s`'s first frame; the last entry is the total.
    offsets: Vec<usize>,
    /// One name per sequence, or empty when the index was built from counts only.
    names: Vec<String>,
}

impl FrameIndex {
    pub fn new(frame_counts: impl IntoIterator<Item = usize>) -> Self {
        let mut offsets = vec![0];
        for n in frame_counts {
            offsets.push(offsets.last().unwrap() + n);
        }
        FrameIndex { offsets, names: Vec::new() }
    }

    /// This index with the sequences' names (one per sequence), used by [`FrameIndex::label`].
    pub fn with_names(mut self, names: Vec<String>) -> Self {
        assert_eq!(names.len(), self.n_sequences(), "one name per sequence");
        self.names = names;
        self
    }

    /// A global frame as users write it (`surfcap ... --start walk:12`): `sequence:frame` with
    /// the sequence's name, or its number when the index has no names; the global number when
    /// out of range.
    pub fn label(&self, global: usize) -> String {
        match self.locate(global) {
            Some((s, f)) => match self.names.get(s) {
                Some(name) => format!("{name}:{f}"),
                None => format!("sequence {s}:{f}"),
            },
            None => format!("frame {global} (out of range)"),
        }
    }

    /// Sequence `s` as users write it: its name, or `sequence s` when the index has no names.
    pub fn sequence_name(&self, s: usize) -> String {
        self.names.get(s).cloned().unwrap_or_else(|| format!("sequence {s}"))
    }

    /// Total number of frames.
    pub fn len(&self) -> usize {
        *self.offsets.last().unwrap()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn n_sequences(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Global index of `frame` in `sequence`, if both are in range.
    pub fn global(&self, sequence: usize, frame: usize) -> Option<usize> {
        let start = *self.offsets.get(sequence)?;
        let end = *self.offsets.get(sequence + 1)?;
        (start + frame < end).then_some(start + frame)
    }

    /// (sequence, frame) of a global index, if in range. O(log sequences).
    pub fn locate(&self, global: usize) -> Option<(usize, usize)> {
        if global >= self.len() {
            return None;
        }
        // Last offset <= global; empty sequences share offsets, so take the last one.
        let s = self.offsets.partition_point(|&o| o <= global) - 1;
        Some((s, global - self.offsets[s]))
    }

    /// The global frame a user wrote: `sequence:frame` (the sequence by its name) or a global
    /// frame number; an error says what is wrong and what `owner` ("subject", "frame set") has.
    /// Needs the index's names ([`FrameIndex::with_names`]) to find a sequence by name.
    pub fn resolve(&self, spec: &str, owner: &str) -> Result<usize> {
        let bad = |why: String| err!(Metadata, "frame {spec:?}: {why}");
        match spec.rsplit_once(':') {
            Some((name, f)) => {
                let k =
                    self.names.iter().position(|n| n == name).ok_or_else(|| {
                        bad(format!("no sequence {name:?}; the {owner} has {}", self.names.join(", ")))
                    })?;
                let f: usize = f.parse().map_err(|_| bad(format!("{f:?} is not a frame number")))?;
                let frames = self.range(k).len();
                if f >= frames {
                    return Err(bad(format!("sequence {name:?} has frames 0 to {}", frames - 1)));
                }
                Ok(self.global(k, f).expect("checked above"))
            }
            None => {
                let g: usize =
                    spec.parse().map_err(|_| bad("expected sequence:frame or a global frame number".into()))?;
                if g >= self.len() {
                    return Err(bad(format!("the {owner} has global frames 0 to {}", self.len() - 1)));
                }
                Ok(g)
            }
        }
    }

    /// Global range of a sequence's frames.
    pub fn range(&self, sequence: usize) -> std::ops::Range<usize> {
        self.offsets[sequence]..self.offsets[sequence + 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_every_frame() {
        let ix = FrameIndex::new([3, 0, 2, 5]);
        assert_eq!(ix.len(), 10);
        for g in 0..ix.len() {
            let (s, f) = ix.locate(g).unwrap();
            assert_eq!(ix.global(s, f), Some(g));
        }
        assert_eq!(ix.locate(3), Some((2, 0)));
        assert_eq!(ix.locate(10), None);
        assert_eq!(ix.global(1, 0), None);
        assert_eq!(ix.label(4), "sequence 2:1");
        let named = ix.clone().with_names(["a", "b", "c", "d"].map(String::from).to_vec());
        assert_eq!(
            (named.label(0), named.label(9), named.label(10)),
            ("a:0".into(), "d:4".into(), "frame 10 (out of range)".into())
        );
        assert_eq!(ix.global(0, 3), None);
        assert_eq!(ix.range(3), 5..10);
    }

    #[test]
    fn frames_written_by_users_resolve_or_say_what_is_wrong() {
        let ix = FrameIndex::new([3, 2]).with_names(vec!["walk".into(), "run".into()]);
        assert_eq!(ix.resolve("run:1", "subject").unwrap(), 4);
        assert_eq!(ix.resolve("2", "subject").unwrap(), 2);
        let e = |spec: &str| ix.resolve(spec, "frame set").unwrap_err().to_string();
        assert_eq!(e("jump:0"), r#"frame "jump:0": no sequence "jump"; the frame set has walk, run"#);
        assert_eq!(e("run:2"), r#"frame "run:2": sequence "run" has frames 0 to 1"#);
        assert_eq!(e("run:x"), r#"frame "run:x": "x" is not a frame number"#);
        assert_eq!(e("5"), r#"frame "5": the frame set has global frames 0 to 4"#);
        assert_eq!(e("walk"), r#"frame "walk": expected sequence:frame or a global frame number"#);
    }
}

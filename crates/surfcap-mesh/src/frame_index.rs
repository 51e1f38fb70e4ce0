//! Global frame index <-> (sequence, frame) mapping, used by every algorithm that treats the
//! frames of all sequences as one set (distance matrices, transition tables, graphs).

/// Prefix sums of the sequences' frame counts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameIndex {
    /// `offsets[s]` is the global index of sequence `s`'s first frame; the last entry is the total.
    offsets: Vec<usize>,
}

impl FrameIndex {
    pub fn new(frame_counts: impl IntoIterator<Item = usize>) -> Self {
        let mut offsets = vec![0];
        for n in frame_counts {
            offsets.push(offsets.last().unwrap() + n);
        }
        FrameIndex { offsets }
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
        assert_eq!(ix.global(0, 3), None);
        assert_eq!(ix.range(3), 5..10);
    }
}

//! Learned variants of a subject's sequences played in the captured frames' stead when a walk
//! repeats them (thesis 6.1's motivation: endless motion that does not repeat
//! itself). A variant of a sequence has exactly its frame count, frame f standing for captured
//! frame f in the same world coordinates (thesis 6.6: sampled from the GPDM and placed by the
//! source's global displacement); the walk places it as it places the captured frame
//! (`surfcap_motion::walk_sequence::walk_sequence_with`).
//!
//! Pass p >= 1 of a run (its p-th repetition in the walk,
//! `surfcap_motion::repeat_passes::run_passes`) shows variant (p - 1) mod K of the run's
//! sequence, K its number of variants: the first play is the capture, every repetition a
//! different variant until all K were shown, then they come round again. A sequence without
//! variants is always played as captured.

use surfcap_mesh::{FrameIndex, Subject};
use surfcap_motion::repeat_passes::{FrameSource, Substitute};

use crate::error::{Error, Result};

/// Variants of some of a subject's sequences, each `[frames][vertices][3]` like its sequence.
#[derive(Debug, Clone)]
pub struct FrameVariants {
    index: FrameIndex,
    names: Vec<String>,
    /// Numbers per frame: 3 per vertex.
    frame_len: usize,
    /// Per sequence of the subject, its variants' positions.
    per_sequence: Vec<Vec<Vec<f32>>>,
}

impl FrameVariants {
    /// No variants yet: every frame plays as captured.
    pub fn new(subject: &Subject) -> Self {
        FrameVariants {
            index: subject.frame_index().clone(),
            names: subject.sequences().iter().map(|q| q.name.clone()).collect(),
            frame_len: 3 * subject.topology().n_vertices(),
            per_sequence: vec![Vec::new(); subject.sequences().len()],
        }
    }

    /// Adds `variants` of the sequence named `sequence` (after any it has): each must have that
    /// sequence's frame count of the subject's vertex count, all finite. Errors name the
    /// sequence, the variant and, for a non-finite number, its frame.
    pub fn add(&mut self, sequence: &str, variants: Vec<Vec<f32>>) -> Result<()> {
        let q = self.names.iter().position(|n| n == sequence).ok_or_else(|| {
            Error::Request(format!(
                "variants of sequence {sequence:?}: the subject has no such sequence (it has {})",
                self.names.join(", ")
            ))
        })?;
        let frames = self.index.range(q).len();
        let have = self.per_sequence[q].len();
        for (k, v) in variants.iter().enumerate() {
            let expected = frames * self.frame_len;
            if v.len() != expected {
                return Err(Error::Request(format!(
                    "variant {} of sequence {sequence:?}: {} numbers, expected {expected} ({frames} frames of {} vertices, as the sequence)",
                    have + k,
                    v.len(),
                    self.frame_len / 3
                )));
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::Request(format!(
                    "variant {} of sequence {sequence:?}: a non-finite coordinate at frame {sequence}:{}",
                    have + k,
                    i / self.frame_len
                )));
            }
        }
        self.per_sequence[q].extend(variants);
        Ok(())
    }

    /// Number of variants of sequence `q` (its index in the subject).
    pub fn n_variants(&self, q: usize) -> usize {
        self.per_sequence.get(q).map_or(0, Vec::len)
    }

    /// No sequence has a variant.
    pub fn is_empty(&self) -> bool {
        self.per_sequence.iter().all(Vec::is_empty)
    }

    /// Variant `k` of global frame `global`, when its sequence has that variant.
    pub fn variant_frame(&self, k: usize, global: u32) -> Option<&[f32]> {
        let (q, f) = self.index.locate(global as usize)?;
        let v = self.per_sequence[q].get(k)?;
        Some(&v[f * self.frame_len..(f + 1) * self.frame_len])
    }
}

impl FrameSource for FrameVariants {
    /// Pass 0 as captured, pass p >= 1 variant (p - 1) mod K of the frame's sequence.
    fn substitute(&self, pass: usize, frame: u32) -> Option<Substitute<'_>> {
        if pass == 0 {
            return None;
        }
        let (q, _) = self.index.locate(frame as usize)?;
        let k = self.n_variants(q);
        if k == 0 {
            return None;
        }
        let variant = (pass - 1) % k;
        Some(Substitute { variant: variant as u32, positions: self.variant_frame(variant, frame)? })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph_kind::GraphKind;
    use crate::pipeline::{CacheStore, GraphParams, Pipeline};
    use crate::walk_playback::{play_walk, play_walk_with, walk_passes};
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_geometry::motion_plane_alignment::{PlaneMotion, plane_axes};
    use surfcap_mesh::NoProgress;
    use surfcap_motion::blend::centre;
    use surfcap_motion::transition_table::TableParams;
    use surfcap_motion::walk_sequence::Step;

    fn pipeline() -> (Pipeline, GraphParams) {
        let s = worm_subject(&WormParams { rings: 8, segments: 6, frames: 24, ..Default::default() }).unwrap();
        let pipe = Pipeline::new(s, CacheStore::memory_only(), Box::new(NoProgress));
        let p = GraphParams {
            table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
            kind: GraphKind::Essential,
            alpha: surfcap_motion::edge_weights::Alpha::new(0.05).unwrap(),
        };
        (pipe, p)
    }

    /// A walk over `b..=a` `times` times, looping by a transition a -> b back within one
    /// sequence (the tube crawls periodically, so its graph has one).
    fn looping_walk(pipe: &Pipeline, p: &GraphParams, times: usize) -> (Vec<u32>, std::ops::RangeInclusive<u32>) {
        let graph = pipe.graph(p).unwrap();
        let model = pipe.walk_model(p, None).unwrap();
        let (a, b) = graph
            .value
            .edges()
            .iter()
            .map(|e| (e.from, e.to))
            .filter(|&(a, b)| {
                b + 4 <= a
                    && matches!(model.value.step(a, b), Some(Step::Transition(_)))
                    && (b..a).all(|k| matches!(model.value.step(k, k + 1), Some(Step::Original)))
            })
            .max_by_key(|&(a, b)| a - b)
            .expect("a transition looping back within a sequence");
        ((0..times).flat_map(|_| b..=a).collect(), b..=a)
    }

    /// Variants of sequence `q` of the subject: its frames lifted by `lift[k]` along the up axis
    /// and stretched along it by a pass-dependent factor (a pose change, not only a motion).
    fn variants(s: &Subject, q: usize, lifts: &[f32]) -> Vec<Vec<f32>> {
        let up = plane_axes(s.up_axis).2;
        let seq = &s.sequences()[q];
        lifts
            .iter()
            .map(|&lift| {
                let mut v = Vec::new();
                for f in 0..seq.n_frames() {
                    let frame = seq.frame(f);
                    let c = centre(frame)[up] as f32;
                    v.extend(frame.chunks_exact(3).flat_map(|x| {
                        let mut y = [x[0], x[1], x[2]];
                        y[up] = c + (1.0 + lift) * (y[up] - c) + lift;
                        y
                    }));
                }
                v
            })
            .collect()
    }

    #[test]
    fn a_looping_walk_plays_a_new_variant_each_pass_and_blends_the_frames_it_shows() {
        let (pipe, p) = pipeline();
        let s = pipe.subject();
        let up_axis = plane_axes(s.up_axis).2;
        let (walk, run) = looping_walk(&pipe, &p, 4);
        let q = s.frame_index().locate(*run.start() as usize).unwrap().0;
        let start = PlaneMotion { theta: 0.4, t: [0.5, -1.0], up: s.up_axis };
        let captured = play_walk(&pipe, &p, None, &walk, &start, "w").unwrap();
        let lifts = [0.05f32, 0.1, 0.15];
        // Two variants for four plays: variants 0, 1, then 0 again.
        let mut fv = FrameVariants::new(s);
        fv.add(&s.sequences()[q].name, variants(s, q, &lifts[..2])).unwrap();
        let varied = play_walk_with(&pipe, &p, None, &walk, &start, "w", &fv).unwrap();
        assert_eq!(varied.frames(), captured.frames());
        assert_eq!(varied.mix, captured.mix);
        let frame = |w: &crate::walk_playback::PlayedWalk, k: usize| w.sequence.frame(k).to_vec();
        let run_len = run.clone().count();
        let mut seen = 0;
        for k in 0..varied.frames() {
            let (c, v) = (frame(&captured, k), frame(&varied, k));
            let lift = centre(&v)[up_axis] - centre(&c)[up_axis];
            let m = varied.mix[k];
            let play = varied.plays[k];
            if m.from == m.to && m.weight == 0.0 {
                // An original frame: the first pass is the capture to the bit, later ones the
                // variant of the pass, placed as the captured frame (the ground-plane
                // placement leaves the vertical lift as it is).
                let pass = seen / run_len;
                seen += 1;
                let want = if pass == 0 { None } else { Some(((pass - 1) % 2) as u32) };
                assert_eq!((play.from, play.to), (want, want), "frame {k}, pass {pass}");
                assert_eq!(play.is_repeat(), pass > 0);
                match want {
                    None => assert_eq!(c, v, "frame {k}"),
                    Some(w) => {
                        assert!((lift - lifts[w as usize] as f64).abs() < 1e-4, "frame {k}: lift {lift}");
                        let plane = (0..3).filter(|&a| a != up_axis);
                        for a in plane {
                            assert!((centre(&v)[a] - centre(&c)[a]).abs() < 1e-4, "frame {k}: moved in the plane");
                        }
                    }
                }
            } else {
                // A transition frame blends the frames shown on either side with its weight:
                // the centre's lift is the weighted mix of the two sides' lifts.
                let side = |v: Option<u32>| v.map_or(0.0, |w| lifts[w as usize] as f64);
                let want = (1.0 - m.weight as f64) * side(play.from) + m.weight as f64 * side(play.to);
                assert!((lift - want).abs() < 1e-3, "frame {k}: lift {lift}, expected {want} ({play:?})");
                assert_ne!(play.from, play.to, "frame {k}: a loop's transition leaves one pass for the next");
            }
        }
        // Consecutive passes differ, so the same frames never show the same pose twice in a row.
        let summary = varied.repeat_summary(s);
        assert_eq!(summary.frames, varied.frames());
        assert_eq!(summary.repeats, 3 * run_len);
        assert!(summary.played_as_variants > 3 * run_len, "the transitions into and out of variants count too");
        assert_eq!(summary.sequences.len(), 1);
        assert_eq!(summary.sequences[0].variants, vec![0, 1]);
        assert_eq!(summary.sequences[0].frames_as_variants, summary.played_as_variants);
        assert_eq!(walk_passes(s, &pipe.walk_model(&p, None).unwrap().value, &walk).unwrap()[q], 3);
        // The captured walk records its repeats too, and no variant.
        let plain = captured.repeat_summary(s);
        assert_eq!((plain.repeats, plain.played_as_variants), (3 * run_len, 0));
        assert!(plain.sequences.is_empty());
    }

    #[test]
    fn without_variants_the_walk_plays_as_captured_to_the_bit() {
        let (pipe, p) = pipeline();
        let s = pipe.subject();
        let (walk, _) = looping_walk(&pipe, &p, 3);
        let start = PlaneMotion::identity(s.up_axis);
        let captured = play_walk(&pipe, &p, None, &walk, &start, "w").unwrap();
        let none = play_walk_with(&pipe, &p, None, &walk, &start, "w", &FrameVariants::new(s)).unwrap();
        assert_eq!(none.sequence.positions(), captured.sequence.positions());
        assert_eq!(none.centres, captured.centres);
        assert!(none.plays.iter().all(|p| !p.is_variant()));
        // Variants of another sequence leave this walk as captured.
        let q = s.frame_index().locate(walk[0] as usize).unwrap().0;
        let other = (0..s.sequences().len()).find(|&o| o != q).expect("the tube has two sequences");
        let mut fv = FrameVariants::new(s);
        fv.add(&s.sequences()[other].name, variants(s, other, &[0.1])).unwrap();
        let elsewhere = play_walk_with(&pipe, &p, None, &walk, &start, "w", &fv).unwrap();
        assert_eq!(elsewhere.sequence.positions(), captured.sequence.positions());
    }

    #[test]
    fn variants_that_do_not_fit_their_sequence_are_refused_with_their_names() {
        let (pipe, _) = pipeline();
        let s = pipe.subject();
        let name = s.sequences()[0].name.clone();
        let mut fv = FrameVariants::new(s);
        assert!(fv.is_empty());
        let e = fv.add("nope", vec![]).unwrap_err().to_string();
        assert!(e.contains("\"nope\"") && e.contains(&name), "{e}");
        let mut good = variants(s, 0, &[0.1]);
        let e = fv.add(&name, vec![good[0][3..].to_vec()]).unwrap_err().to_string();
        assert!(e.contains("variant 0") && e.contains("expected"), "{e}");
        good[0][3 * s.topology().n_vertices() * 2 + 1] = f32::NAN;
        let e = fv.add(&name, good).unwrap_err().to_string();
        assert!(e.contains(&format!("{name}:2")), "{e}");
        assert!(fv.is_empty());
        // Pass 0 is always the capture; a sequence's variants come round again.
        fv.add(&name, variants(s, 0, &[0.1, 0.2, 0.3])).unwrap();
        assert_eq!(fv.n_variants(0), 3);
        assert!(fv.substitute(0, 0).is_none());
        let got: Vec<u32> = (1..=5).map(|p| fv.substitute(p, 1).unwrap().variant).collect();
        assert_eq!(got, [0, 1, 2, 0, 1]);
        assert_eq!(fv.substitute(2, 1).unwrap().positions, fv.variant_frame(1, 1).unwrap());
    }
}

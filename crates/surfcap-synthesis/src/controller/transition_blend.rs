//! Blend (thesis Algorithm 2) of one chosen transition, frame by frame in playing order, for a
//! live player: the frames are those offline synthesis plays for the transition
//! ([`surfcap_motion::walk_sequence::walk_sequence`] on the walk `[u, v]` with `u` unmoved, to
//! the bit), but each is handed over as soon as it is made, so that the first frames can be
//! sent while the later ones are still being solved, and what depends on the mesh alone (the
//! Poisson system's connected components and symbolic Cholesky factorisation,
//! [`PoissonPattern`]) is made once per subject instead of once per transition.
//!
//! Each frame still costs two numeric factorisations of the Poisson system (eq. 2.48, one per
//! pose, the two sides of eq. 2.49), the polar decomposition of every triangle's deformation
//! gradient (eq. 2.45) and two solves; [`BlendTimes`] says how the time splits.

use std::sync::Arc;
use std::time::Instant;

use surfcap_geometry::poisson_reconstruction::PoissonPattern;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_mesh::Subject;
use surfcap_motion::blend::{Lambda, blend_placements, centre};
use surfcap_motion::subject_placement::{Placement, captured_placements};
use surfcap_motion::walk_sequence::{Step as EdgeStep, WalkModel};

use crate::error::Result;

/// Seconds spent in each part of blending transitions.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BlendTimes {
    /// The DTW warp and Algorithm 2's rigid placements.
    pub placements: f64,
    /// Per frame: both poses' Poisson factorisations and the triangles' polar decompositions.
    pub factorise: f64,
    /// Per frame: the interpolated gradients and the two Poisson solves.
    pub solve: f64,
    pub frames: usize,
}

impl BlendTimes {
    pub fn add(&mut self, o: &BlendTimes) {
        self.placements += o.placements;
        self.factorise += o.factorise;
        self.solve += o.solve;
        self.frames += o.frames;
    }
}

/// Blends transitions of one subject.
pub struct TransitionBlender {
    pattern: Arc<PoissonPattern>,
}

impl TransitionBlender {
    /// The symbolic factorisation of the subject's mesh, once.
    pub fn new(subject: &Subject) -> Result<Self> {
        Ok(TransitionBlender { pattern: Arc::new(PoissonPattern::new(subject.topology())?) })
    }

    /// The frames transition `u -> v` of `model` adds after `u` (Blend's S(2..L-1), then frame
    /// `v` placed), in the coordinates where `u` is unmoved; `d` is the distance matrix the
    /// model was built from. `emit(k, total, frame)` receives them in order (frame k of
    /// `total`); it returns false to stop early. Returns the number of frames of the transition (0 when `u -> v` is not one of the
    /// model's transitions) and the time spent.
    pub fn blend(
        &self,
        subject: &Subject,
        model: &WalkModel,
        d: &[f64],
        (u, v): (u32, u32),
        mut emit: impl FnMut(usize, usize, Vec<f32>) -> bool,
    ) -> Result<(usize, BlendTimes)> {
        let mut times = BlendTimes::default();
        let t0 = Instant::now();
        let Some(EdgeStep::Transition(t)) = model.step(u, v) else { return Ok((0, times)) };
        let Some(offsets) = model.warp(d, u, v) else { return Ok((0, times)) };
        let (s0, d0) = (u as usize, (v + 1 - t.lj) as usize);
        let frames = |range: std::ops::Range<usize>| range.map(|g| subject.frame(g)).collect::<Option<Vec<&[f32]>>>();
        let (Some(src), Some(dst), Some(last)) =
            (frames(s0..s0 + t.li as usize), frames(d0..v as usize + 1), subject.frame(v as usize))
        else {
            return Ok((0, times));
        };
        let up = subject.up_axis;
        let placement = model.placement();
        let steps = match placement {
            Placement::Aligned => blend_placements(up, &src, &dst, &offsets, Lambda::Ramp),
            Placement::Captured => {
                let cs: Vec<[f64; 3]> = src.iter().map(|f| centre(f)).collect();
                let cd: Vec<[f64; 3]> = dst.iter().map(|f| centre(f)).collect();
                captured_placements(up, &cs, &cd, &offsets, Lambda::Ramp)
            }
        };
        times.placements = t0.elapsed().as_secs_f64();
        let inner = steps.len().saturating_sub(1);
        let total = inner.saturating_sub(1) + 1;
        let topology = subject.topology();
        for (k, st) in steps.iter().take(inner).skip(1).enumerate() {
            let t1 = Instant::now();
            let (mut a, mut b) = (src[st.n].to_vec(), dst[st.m].to_vec());
            st.src.apply(&mut a);
            st.dst.apply(&mut b);
            let interpolator = match placement {
                Placement::Aligned => NonlinearInterpolator::with_pattern(&self.pattern, topology, &a, &b, up)?,
                Placement::Captured => NonlinearInterpolator::as_placed(&self.pattern, topology, &a, &b)?,
            };
            let t2 = Instant::now();
            let frame = interpolator.at(st.lambda, StretchInterpolation::Linear);
            times.factorise += (t2 - t1).as_secs_f64();
            times.solve += t2.elapsed().as_secs_f64();
            times.frames += 1;
            if !emit(k, total, frame) {
                return Ok((total, times));
            }
        }
        let mut end = last.to_vec();
        t.end.apply(&mut end);
        emit(total - 1, total, end);
        Ok((total, times))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::display_blend::display_blend;
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    use surfcap_geometry::motion_plane_alignment::PlaneMotion;
    use surfcap_mesh::NoProgress;
    use surfcap_motion::clip_loops::clip_loops;
    use surfcap_motion::edge_weights::{Alpha, edge_weights};
    use surfcap_motion::essential_graph::essential_graph;
    use surfcap_motion::transition_table::{TableParams, transition_table};
    use surfcap_motion::walk_sequence::walk_sequence;

    /// The built-in crawling tube's walk model, and its transitions.
    fn setup() -> (Subject, WalkModel, Vec<f64>, Vec<(u32, u32)>) {
        let s = worm_subject(&WormParams { rings: 10, segments: 8, frames: 30, ..Default::default() }).unwrap();
        let d = distance_matrix(&s, &DistanceParams::default(), &NoProgress);
        let p = TableParams { l_min: 4, l_max: 8, slope: Some(3) };
        let table = transition_table(&d.values, s.frame_index(), &p, &NoProgress).unwrap();
        let w = edge_weights(&table, s.frame_index(), Alpha::new(0.05).unwrap()).unwrap();
        let g = essential_graph(&w, &NoProgress).graph;
        let model = WalkModel::new(&s, &clip_loops(&s), &g, &table, &d.values, p.slope, None);
        let transitions: Vec<(u32, u32)> = g
            .edges()
            .iter()
            .map(|e| (e.from, e.to))
            .filter(|&(u, v)| matches!(model.step(u, v), Some(EdgeStep::Transition(_))))
            .collect();
        (s, model, d.values, transitions)
    }

    /// Frame by frame, the blended frames are offline synthesis's to the bit; stopping early
    /// stops; the stand-ins have the same number of frames, the exact frames' centres of mass
    /// and stay near their poses.
    #[test]
    fn frames_in_order_equal_offline_synthesis_and_the_stand_ins_follow_them() {
        let (s, model, d, transitions) = setup();
        assert!(transitions.len() >= 2, "the tube's graph has transitions");
        let blender = TransitionBlender::new(&s).unwrap();
        let n = 3 * s.topology().n_vertices();
        let extent = s.frame(0).unwrap().chunks_exact(3).map(|p| p[0]).fold(f32::MIN, f32::max)
            - s.frame(0).unwrap().chunks_exact(3).map(|p| p[0]).fold(f32::MAX, f32::min);
        for &(u, v) in &transitions {
            let offline = walk_sequence(&s, &model, &d, &[u, v], &PlaneMotion::identity(s.up_axis)).unwrap();
            let mut got = Vec::new();
            let (total, times) = blender
                .blend(&s, &model, &d, (u, v), |k, n, f| {
                    assert_eq!(k, got.len());
                    assert!(k < n);
                    got.push(f);
                    true
                })
                .unwrap();
            assert_eq!(total, got.len());
            assert_eq!(times.frames, total - 1);
            assert_eq!(got.concat(), offline.positions[n..], "{u} -> {v}");
            let mixes = display_blend(&s, &model, &d, u, v).unwrap();
            assert_eq!(mixes.len(), total - 1);
            for (m, exact) in mixes.iter().zip(&got) {
                let stand_in = m.positions(&s).unwrap();
                let (ca, cb) = (centre(&stand_in), centre(exact));
                for k in 0..3 {
                    assert!((ca[k] - cb[k]).abs() < 1e-4 * f64::from(extent), "{u} -> {v}: centres {ca:?} {cb:?}");
                }
                let far = stand_in.iter().zip(exact).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
                assert!(far < 0.5 * extent, "{u} -> {v}: a stand-in vertex {far} from the exact one");
            }
            let mut seen = 0;
            blender
                .blend(&s, &model, &d, (u, v), |_, _, _| {
                    seen += 1;
                    false
                })
                .unwrap();
            assert_eq!(seen, 1);
        }
        assert!(blender.blend(&s, &model, &d, (0, 1), |_, _, _| true).unwrap().0 == 0, "not a transition");
    }
}

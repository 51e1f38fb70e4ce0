//! Per-vertex velocities of a mesh sequence: the time derivative of each vertex's position, in
//! the subject's units per second, as renderers read them to draw motion blur (Alembic's
//! `.velocities` on `PolyMesh` samples, USD's `velocities` on `Mesh`, both in units per second).
//!
//! The derivative is estimated by finite differences over the frame spacing `dt = 1 / fps`:
//! - interior frames, the central difference `v_f = (p_{f+1} - p_{f-1}) / (2 dt)` (second-order
//!   accurate, and symmetric, so a renderer's shutter centred on the frame blurs both ways);
//! - the first frame, the forward difference `v_0 = (p_1 - p_0) / dt`; the last, the backward
//!   difference `v_{n-1} = (p_{n-1} - p_{n-2}) / dt` (first-order: the sequence has no frame
//!   beyond its ends);
//! - a sequence of one frame stands still: zero.
//!
//! Each sequence is differentiated on its own: frames of different sequences are not
//! neighbours in time.

/// The velocities of one sequence's `positions` (`[frames * vertices * 3]`, frame-major) at
/// `fps` frames per second: same layout, units per second. Computed in f64, stored as f32.
///
/// # Panics
/// When `positions` is not a whole number of frames of `n_vertices` (a caller's bug: the data
/// model checks its layouts).
pub fn vertex_velocities(positions: &[f32], n_vertices: usize, fps: f64) -> Vec<f32> {
    let stride = n_vertices * 3;
    assert!(stride > 0 && positions.len().is_multiple_of(stride), "positions are whole frames");
    let frames: Vec<&[f32]> = positions.chunks_exact(stride).collect();
    let mut out = Vec::with_capacity(positions.len());
    for f in 0..frames.len() {
        out.extend(frame_velocity(&frames, f, fps));
    }
    out
}

/// The velocities of frame `f` of a sequence given as one slice per frame (`[vertices * 3]`
/// each, all the same length), at `fps`: the finite difference the module states.
pub fn frame_velocity(frames: &[&[f32]], f: usize, fps: f64) -> Vec<f32> {
    let n = frames.len();
    if n == 1 {
        return vec![0.0; frames[0].len()];
    }
    let (a, b, span) = if f == 0 {
        (0, 1, 1.0)
    } else if f == n - 1 {
        (n - 2, n - 1, 1.0)
    } else {
        (f - 1, f + 1, 2.0)
    };
    let scale = fps / span;
    frames[b].iter().zip(frames[a]).map(|(&q, &p)| ((f64::from(q) - f64::from(p)) * scale) as f32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_motion_has_its_exact_speed_everywhere_and_a_parabola_the_central_slope() {
        // One vertex moving x = 2 t (units per second) at 10 fps, and one with y = t^2.
        let fps = 10.0;
        let mut p = Vec::new();
        for f in 0..5 {
            let t = f as f32 / 10.0;
            p.extend([2.0 * t, 0.0, 0.0, 0.0, t * t, 0.0]);
        }
        let v = vertex_velocities(&p, 2, fps);
        assert_eq!(v.len(), p.len());
        for f in 0..5 {
            assert!((v[f * 6] - 2.0).abs() < 1e-5, "frame {f}: {}", v[f * 6]);
        }
        // Central differences of t^2 are exact: 2 t at interior frames.
        for f in 1..4 {
            let t = f as f32 / 10.0;
            assert!((v[f * 6 + 4] - 2.0 * t).abs() < 1e-5, "frame {f}: {}", v[f * 6 + 4]);
        }
        // Ends: one-sided, (0.01 - 0) / 0.1 = 0.1 and (0.16 - 0.09) / 0.1 = 0.7.
        assert!((v[4] - 0.1).abs() < 1e-5 && (v[4 * 6 + 4] - 0.7).abs() < 1e-5);
    }

    #[test]
    fn one_frame_stands_still() {
        assert_eq!(vertex_velocities(&[1.0, 2.0, 3.0], 1, 30.0), vec![0.0; 3]);
    }
}

//! A moving head from one static scan: a textured subject built from the head scan (thesis
//! Fig. 7.1, shape and appearance animated together). The scan
//! (`../shared/data/leeperrysmith_head`, one mesh) is bent about a pivot below it: each vertex
//! turns by the frame's angles times a weight rising smoothly with its height, so the neck bends
//! while the skull turns whole. The motion is therefore not rigid, the pose distance of
//! chapter 2 sees it, and the essential graph can find transitions between the sequences.
//!
//! Three sequences, each one period of a smooth oscillation that starts and ends at rest:
//! `nod` (pitch, +-15 degrees), `turn` (yaw, +-25 degrees), `tilt` (roll, +-12 degrees, with a
//! little pitch). The vertices keep the scan's order, topology and UV atlas.

use nalgebra::{Rotation3, Vector3};
use surfcap_mesh::sizing::{Estimate, bytes};
use surfcap_mesh::{Result, Sequence, Subject, Topology, Units, UpAxis};

/// One sequence: its name and the peak (pitch, yaw, roll) in degrees.
const MOTIONS: [(&str, [f64; 3]); 3] =
    [("nod", [15.0, 0.0, 0.0]), ("turn", [0.0, 25.0, 0.0]), ("tilt", [4.0, 0.0, 12.0])];

/// What [`head_motion_subject`] takes for a scan of `n_vertices` vertices, estimated before any
/// frame is made: three sequences of `frames_per_sequence` frames of three f32 per vertex, in
/// memory and in the subject cache.
pub fn head_motion_size(n_vertices: usize, frames_per_sequence: usize) -> Estimate {
    let b = bytes(&[MOTIONS.len() as f64, frames_per_sequence as f64, n_vertices as f64], 12);
    Estimate {
        what: format!(
            "--frames-per-sequence {frames_per_sequence} ({} sequences of {n_vertices} vertices)",
            MOTIONS.len()
        ),
        memory: b,
        disk: b,
        lower: "--frames-per-sequence".into(),
    }
}

/// The scan moved: `frames_per_sequence` frames of each of `nod`, `turn`, `tilt` at 30 fps, +y
/// up (as the scan), in the scan's units (arbitrary; `units_name` names them).
pub fn head_motion_subject(
    topology: &Topology,
    rest: &[f32],
    frames_per_sequence: usize,
    units_name: &str,
) -> Result<Subject> {
    let nv = topology.n_vertices();
    if rest.len() != 3 * nv {
        return Err(surfcap_mesh::Error::new(
            surfcap_mesh::ErrorKind::Shape,
            format!("{} coordinates for {nv} vertices: expected {}", rest.len(), 3 * nv),
        ));
    }
    if frames_per_sequence < 2 {
        return Err(surfcap_mesh::Error::new(
            surfcap_mesh::ErrorKind::Unsupported,
            "a head motion needs at least 2 frames per sequence",
        ));
    }
    let (lo, hi) = surfcap_mesh::bounding_box(rest);
    let height = (hi[1] - lo[1]) as f64;
    // The pivot: the base of the neck, at the bottom of the scan, a little behind its middle.
    let pivot = Vector3::new(
        ((lo[0] + hi[0]) * 0.5) as f64,
        lo[1] as f64 - 0.1 * height,
        ((lo[2] + hi[2]) * 0.5) as f64 - 0.1 * height,
    );
    // Weight: 0 at the pivot's height, 1 from 60% of the scan's height up, smoothstep between.
    let weight = |y: f64| {
        let t = ((y - pivot.y) / (0.7 * height)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let mut sequences = Vec::new();
    for (name, peak) in MOTIONS {
        let mut positions = Vec::with_capacity(frames_per_sequence * 3 * nv);
        for f in 0..frames_per_sequence {
            let phase = f as f64 / (frames_per_sequence - 1) as f64;
            let s = (std::f64::consts::TAU * phase).sin();
            let [pitch, yaw, roll] = peak.map(|p| (p * s).to_radians());
            for v in rest.chunks_exact(3) {
                let p = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                let w = weight(p.y);
                let r = Rotation3::from_euler_angles(w * pitch, w * yaw, w * roll);
                let q = pivot + r * (p - pivot);
                positions.extend([q.x as f32, q.y as f32, q.z as f32]);
            }
        }
        sequences.push(Sequence::new(name, nv, positions)?.with_tags(vec![name.to_string()]));
    }
    let units = Units { name: units_name.to_string(), metres_per_unit: None };
    Subject::new("head", topology.clone(), sequences, 30.0, UpAxis::PosY, units)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_motion_bends_the_neck_and_keeps_the_first_frame_at_rest() {
        // A column of vertices: three triangles up a thin strip.
        let rest: Vec<f32> = (0..8).flat_map(|k| [(k % 2) as f32 * 0.1, k as f32 / 2.0, 0.0]).collect();
        let tris = vec![[0, 1, 2], [1, 3, 2], [2, 3, 4], [3, 5, 4], [4, 5, 6], [5, 7, 6]];
        let topo = Topology::new(8, tris, None).unwrap();
        let s = head_motion_subject(&topo, &rest, 9, "units").unwrap();
        assert_eq!(s.n_frames(), 27);
        assert_eq!(s.frame(0).unwrap(), &rest[..]);
        // At the nod's peak the top moves more than the bottom: a bend, not a rigid turn.
        let peak = s.frame(2).unwrap();
        let moved = |k: usize| (0..3).map(|a| (peak[3 * k + a] - rest[3 * k + a]).powi(2)).sum::<f32>().sqrt();
        assert!(moved(7) > 3.0 * moved(0), "top {} bottom {}", moved(7), moved(0));
    }
}

//! Checks shared by the mannequin's tests: folds and edge stretch.

use nalgebra::{Isometry3, Vector3};
use surfcap_builtin::mannequin::Mannequin;

fn point(s: &[f32], i: u32) -> Vector3<f64> {
    let k = 3 * i as usize;
    Vector3::new(s[k] as f64, s[k + 1] as f64, s[k + 2] as f64)
}

fn normal(s: &[f32], t: &[u32; 3]) -> Vector3<f64> {
    (point(s, t[1]) - point(s, t[0])).cross(&(point(s, t[2]) - point(s, t[0])))
}

/// Poses every frame and asserts the mesh-quality checks: no degenerate triangle, no triangle
/// folded over (its posed normal against the rest normal turned by the skinning rotations at
/// its corners: turning the whole body is no fold), 99.9% of edges within 2.5x their rest
/// length. Returns the edge length ratios' 99.9th percentile, largest and smallest.
pub fn assert_clean_skinning(what: &str, m: &Mannequin, poses: &[Vec<Isometry3<f64>>]) -> [f64; 3] {
    let mut stretches = Vec::new();
    for (frame, w) in poses.iter().enumerate() {
        let posed = m.pose(w);
        let turn = m.vertex_rotations(w);
        assert_eq!(m.topology.count_degenerate_triangles(&posed, 1e-12), 0, "{what} frame {frame}");
        for t in m.topology.triangles() {
            let rest = normal(&m.positions, t);
            let expected: Vector3<f64> = t.iter().map(|&v| turn[v as usize] * rest).sum();
            assert!(expected.dot(&normal(&posed, t)) > 0.0, "{what} frame {frame}: triangle {t:?} folded over");
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                stretches.push(
                    (point(&posed, a) - point(&posed, b)).norm()
                        / (point(&m.positions, a) - point(&m.positions, b)).norm(),
                );
            }
        }
    }
    stretches.sort_by(f64::total_cmp);
    let p999 = stretches[(stretches.len() as f64 * 0.999) as usize];
    assert!(p999 <= 2.5, "{what}: 99.9th percentile edge stretch {p999}");
    [p999, *stretches.last().unwrap(), stretches[0]]
}

//! Measures of how much an interpolated pose distorts the shape, used to compare linear and
//! non-linear interpolation (thesis 2.4, Fig. 2.8): edge-length distortion and volume change,
//! each relative to what linear interpolation of the two inputs' own measures gives.

use surfcap_mesh::Topology;

use crate::deformation_gradient::vertex;

fn edges(topology: &Topology) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = topology
        .triangles()
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

fn edge_lengths(e: &[(u32, u32)], p: &[f32]) -> Vec<f64> {
    e.iter().map(|&(a, b)| (vertex(p, a) - vertex(p, b)).norm()).collect()
}

/// Mean over edges of | l(lambda) / ((1 - lambda) l_i + lambda l_j) - 1 |.
pub fn edge_length_distortion(topology: &Topology, pi: &[f32], pj: &[f32], p: &[f32], lambda: f64) -> f64 {
    let e = edges(topology);
    let (li, lj, l) = (edge_lengths(&e, pi), edge_lengths(&e, pj), edge_lengths(&e, p));
    let mut sum = 0.0;
    let mut n = 0usize;
    for k in 0..e.len() {
        let r = (1.0 - lambda) * li[k] + lambda * lj[k];
        if r > 0.0 {
            sum += (l[k] / r - 1.0).abs();
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// Signed enclosed volume (sum of signed tetrahedra to the centroid), exact for closed meshes
/// and a consistent measure of bulk for open ones.
pub fn signed_volume(topology: &Topology, p: &[f32]) -> f64 {
    let n = p.len() / 3;
    let c = (0..n as u32).map(|k| vertex(p, k)).sum::<nalgebra::Vector3<f64>>() / n.max(1) as f64;
    topology
        .triangles()
        .iter()
        .map(|t| {
            let (a, b, d) = (vertex(p, t[0]) - c, vertex(p, t[1]) - c, vertex(p, t[2]) - c);
            a.dot(&b.cross(&d)) / 6.0
        })
        .sum()
}

/// | V(lambda) / ((1 - lambda) V_i + lambda V_j) - 1 |.
pub fn volume_change(topology: &Topology, pi: &[f32], pj: &[f32], p: &[f32], lambda: f64) -> f64 {
    let r = (1.0 - lambda) * signed_volume(topology, pi) + lambda * signed_volume(topology, pj);
    (signed_volume(topology, p) / r - 1.0).abs()
}

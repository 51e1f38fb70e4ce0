//! Per-vertex edge-length strain of a pose against a rest pose: at each vertex, the mean over
//! the mesh edges that meet there of |l / l0 - 1|, where l is the edge's length in the pose and
//! l0 in the rest pose. It is the per-vertex form of the edge-length distortion the thesis uses
//! to compare interpolations (2.4, Fig. 2.8; [`crate::shape_distortion::edge_length_distortion`]
//! averages the same ratio over all edges): 0 where the surface is only moved rigidly, 0.1 where
//! its edges are 10% longer or shorter on average. Edges of zero rest length (collapsed
//! vertices in the source) are left out; a vertex with no edge of positive rest length gets 0.

use surfcap_mesh::Topology;

/// The mesh's undirected edges, once each.
pub fn unique_edges(topology: &Topology) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> = topology
        .triangles()
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

fn length(p: &[f32], [a, b]: [u32; 2]) -> f64 {
    let (a, b) = (3 * a as usize, 3 * b as usize);
    (0..3).map(|k| (p[a + k] as f64 - p[b + k] as f64).powi(2)).sum::<f64>().sqrt()
}

/// The strain of every vertex of `pose` against `rest` (both `[vertices][3]`, the topology's
/// vertices) over `edges` (from [`unique_edges`]).
pub fn vertex_edge_strain(edges: &[[u32; 2]], rest: &[f32], pose: &[f32]) -> Vec<f32> {
    let n = rest.len() / 3;
    let (mut sum, mut count) = (vec![0.0f64; n], vec![0u32; n]);
    for &e in edges {
        let l0 = length(rest, e);
        if l0 <= 0.0 {
            continue;
        }
        let s = (length(pose, e) / l0 - 1.0).abs();
        for v in e {
            sum[v as usize] += s;
            count[v as usize] += 1;
        }
    }
    sum.iter().zip(&count).map(|(&s, &c)| if c == 0 { 0.0 } else { (s / c as f64) as f32 }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strain_is_zero_under_rigid_motion_and_the_stretch_where_edges_stretch() {
        // Two triangles sharing the edge 0-2: a unit square.
        let t = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], None).unwrap();
        let rest = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
        let e = unique_edges(&t);
        assert_eq!(e.len(), 5);
        // Turned a quarter about z and moved: no strain.
        let moved: Vec<f32> = rest.chunks(3).flat_map(|p| [-p[1] + 5.0, p[0], p[2] + 2.0]).collect();
        assert!(vertex_edge_strain(&e, &rest, &moved).iter().all(|s| s.abs() < 1e-6));
        // Stretched by 2 along x: edges 0-1 and 2-3 double (strain 1), 1-2 and 0-3 keep their
        // length, the diagonal 0-2 grows from sqrt 2 to sqrt 5.
        let wide: Vec<f32> = rest.chunks(3).flat_map(|p| [2.0 * p[0], p[1], p[2]]).collect();
        let s = vertex_edge_strain(&e, &rest, &wide);
        let diagonal = (5.0f64.sqrt() / 2.0f64.sqrt() - 1.0) as f32;
        // Vertex 1: edges 0-1 (1) and 1-2 (0); vertex 0: 0-1 (1), 0-2 (diagonal), 0-3 (0).
        assert!((s[1] - 0.5).abs() < 1e-6, "{s:?}");
        assert!((s[0] - (1.0 + diagonal) / 3.0).abs() < 1e-6, "{s:?}");
    }
}

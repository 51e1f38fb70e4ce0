//! Isotropic re-meshing of a triangle surface, and the frame sets with known answers built from
//! it: every frame of a shared-topology subject re-meshed on its own, so each
//! frame has its own vertex count and connectivity, as the per-frame reconstructions of Huang et
//! al. 2009 ("Human motion synthesis from 3D video", section 5: "unstructured meshes with unknown
//! temporal correspondence and different mesh connectivity at each time-frame"), while where each
//! new vertex lies on the original frame stays known.
//!
//! The remesher is that of Botsch and Kobbelt 2004 ("A remeshing approach to multiresolution
//! modeling", SGP), with the operations the mannequin already used (`mannequin.rs` calls the
//! general ones kept here: [`collapse_short_edges`], [`flip_edges`], [`vertex_neighbours`],
//! [`mean_edge_length`]; its output is unchanged). For a target edge length `L`, `iterations`
//! rounds of: split every edge longer than 4/3 L at its midpoint; collapse every edge shorter
//! than 4/5 L (link condition, no triangle turned over); Delaunay edge flips between nearly
//! coplanar triangles (the mannequin's criterion, not Botsch-Kobbelt's valence one: it keeps the
//! shape where the valence rule would flip across creases); tangential smoothing (each vertex
//! halfway to its neighbours' centroid within its tangent plane), each vertex then projected back
//! to the closest point of the *source* triangles (a bounding-volume hierarchy over them), the
//! move refused if it would turn one of its triangles over. A last projection of every vertex
//! records its source triangle and barycentric coordinates: the new vertex is exactly that point
//! of the source surface (up to f32 rounding of the stored position), the known answer
//! (`surfcap_mesh::Correspondence`).
//!
//! Per-frame variation, seeded: the target edge length is the one that gives the requested vertex
//! count on the frame's area (`L = sqrt(2 A / (sqrt(3) N))`: a closed mesh has about 2N
//! equilateral triangles), times a factor uniform in [0.9, 1.1]; the triangles are processed in
//! a seeded random order (collapses and flips take the first candidate they meet among equals),
//! and the output's vertices are numbered in a seeded random order. Each frame's random stream
//! depends only on (seed, sequence number, frame number), so the result is the same whatever the
//! thread count.
//!
//! Boundaries (open surfaces) are kept: boundary vertices neither collapse nor move, and a split
//! boundary edge's midpoint lies on it. The input must be an oriented 2-manifold, possibly with
//! boundary (every directed edge in at most one triangle); anything else is refused by name,
//! since the local operations are only defined there. Zero-area source triangles are left out
//! of the projection (their points are on their neighbours' edges).

use std::collections::{HashMap, HashSet};

use nalgebra::Vector3;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use surfcap_mesh::{
    Correspondence, Error, ErrorKind, Frame, FrameLabel, FrameSet, FrameSetSequence, Progress, Result, Subject,
    Topology,
};

/// Collapses every edge shorter than `min_length` into its midpoint, when that keeps the mesh a
/// closed 2-manifold (the link condition: the two ends share exactly the two opposite
/// vertices, neither of which has only three neighbours) and turns no surrounding triangle over.
/// Marching tetrahedra leaves stars of up to fourteen vertices within a tenth of a grid step of
/// a grid point that lies almost on the surface; this merges them. Passes repeat (each end of a
/// collapse and its neighbours wait for the next pass) until nothing changes. Returns the
/// compacted positions and triangles. With `max_length`, a collapse that would make an edge
/// longer than it is skipped (Botsch and Kobbelt's guard). Vertices on a boundary are never collapsed (an open
/// surface keeps its outline).
pub fn collapse_short_edges(
    positions: &[f32],
    tris: &[[u32; 3]],
    min_length: f64,
    max_length: Option<f64>,
) -> (Vec<f32>, Vec<[u32; 3]>) {
    let mut pos: Vec<Vector3<f64>> =
        positions.chunks_exact(3).map(|v| Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)).collect();
    let mut tris: Vec<[u32; 3]> = tris.to_vec();
    loop {
        let mut around: Vec<Vec<usize>> = vec![Vec::new(); pos.len()];
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                around[v as usize].push(i);
            }
        }
        let neighbours = |v: u32, tris: &[[u32; 3]]| {
            let mut n: Vec<u32> = around[v as usize].iter().flat_map(|&i| tris[i]).filter(|&u| u != v).collect();
            n.sort_unstable();
            n.dedup();
            n
        };
        // Vertices on a boundary (an edge of one triangle) stay where they are, so an open
        // surface keeps its outline; a closed one has none.
        let directed: HashSet<(u32, u32)> =
            tris.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
        let mut on_boundary = vec![false; pos.len()];
        for &(a, b) in &directed {
            if !directed.contains(&(b, a)) {
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
            }
        }
        let mut short: Vec<(f64, u32, u32)> = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|&(a, b)| a < b)
            .map(|(a, b)| ((pos[a as usize] - pos[b as usize]).norm(), a, b))
            .filter(|&(l, _, _)| l < min_length)
            .collect();
        short.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut touched = vec![false; pos.len()];
        let mut dead = vec![false; tris.len()];
        let mut collapsed = 0;
        for (_, a, b) in short {
            if touched[a as usize] || touched[b as usize] || on_boundary[a as usize] || on_boundary[b as usize] {
                continue;
            }
            let (na, nb) = (neighbours(a, &tris), neighbours(b, &tris));
            let common: Vec<u32> = na.iter().copied().filter(|v| nb.binary_search(v).is_ok()).collect();
            if common.len() != 2 || common.iter().any(|&c| neighbours(c, &tris).len() <= 3) {
                continue;
            }
            let mid = (pos[a as usize] + pos[b as usize]) * 0.5;
            // Botsch and Kobbelt's guard: no edge longer than `max_length` may result.
            if max_length.is_some_and(|m| na.iter().chain(&nb).any(|&v| (pos[v as usize] - mid).norm() > m)) {
                continue;
            }
            // No triangle that stays may turn over.
            let turns_over = [a, b].iter().flat_map(|&v| around[v as usize].iter()).any(|&i| {
                let t = tris[i];
                if t.contains(&a) && t.contains(&b) {
                    return false;
                }
                let p = |u: u32| if u == a || u == b { mid } else { pos[u as usize] };
                let before =
                    (pos[t[1] as usize] - pos[t[0] as usize]).cross(&(pos[t[2] as usize] - pos[t[0] as usize]));
                let after = (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0])));
                after.dot(&before) <= 0.0
            });
            if turns_over {
                continue;
            }
            pos[a as usize] = mid;
            for &i in &around[b as usize] {
                if tris[i].contains(&a) {
                    dead[i] = true;
                } else {
                    for v in tris[i].iter_mut() {
                        if *v == b {
                            *v = a;
                        }
                    }
                }
            }
            for v in na.iter().chain(&nb).chain([&a, &b]) {
                touched[*v as usize] = true;
            }
            collapsed += 1;
        }
        if collapsed == 0 {
            break;
        }
        let mut k = 0;
        tris.retain(|_| {
            k += 1;
            !dead[k - 1]
        });
    }
    // Compact: drop the vertices no triangle uses any more.
    let mut new_index = vec![u32::MAX; pos.len()];
    let mut out = Vec::new();
    for t in tris.iter_mut() {
        for v in t.iter_mut() {
            if new_index[*v as usize] == u32::MAX {
                new_index[*v as usize] = (out.len() / 3) as u32;
                let p = pos[*v as usize];
                out.extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
            }
            *v = new_index[*v as usize];
        }
    }
    (out, tris)
}

/// Delaunay-style edge flips on a closed oriented mesh: an edge whose two opposite angles sum
/// to more than pi is replaced by the other diagonal of its two triangles, when the two
/// triangles are nearly coplanar (so the shape is kept), the new edge is not already an edge,
/// and neither end of the old edge drops below four neighbours. Removes the slivers marching
/// tetrahedra leaves, whose normals no skinning could keep steady.
pub fn flip_edges(positions: &[f32], tris: &mut [[u32; 3]]) {
    let at = |v: u32| {
        let k = 3 * v as usize;
        Vector3::new(positions[k] as f64, positions[k + 1] as f64, positions[k + 2] as f64)
    };
    let angle = |apex: u32, a: u32, b: u32| {
        let (u, v) = (at(a) - at(apex), at(b) - at(apex));
        u.angle(&v)
    };
    let normal = |t: &[u32; 3]| (at(t[1]) - at(t[0])).cross(&(at(t[2]) - at(t[0])));
    // Directed edge -> triangle holding it.
    let mut edge: HashMap<(u32, u32), usize> = HashMap::new();
    let mut valence: HashMap<u32, usize> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            edge.insert((t[k], t[(k + 1) % 3]), i);
            *valence.entry(t[k]).or_default() += 1;
        }
    }
    for i in 0..tris.len() {
        for k in 0..3 {
            let t1 = tris[i];
            let (a, b, c) = (t1[k], t1[(k + 1) % 3], t1[(k + 2) % 3]);
            let Some(&j) = edge.get(&(b, a)) else { continue };
            let t2 = tris[j];
            let d = t2.iter().copied().find(|&v| v != a && v != b).expect("a triangle has three vertices");
            if edge.contains_key(&(c, d)) || edge.contains_key(&(d, c)) || valence[&a] <= 4 || valence[&b] <= 4 {
                continue;
            }
            if angle(c, a, b) + angle(d, a, b) <= std::f64::consts::PI + 1e-9 {
                continue;
            }
            let (n1, n2) = (normal(&t1), normal(&t2));
            if n1.normalize().dot(&n2.normalize()) < 0.9 {
                continue;
            }
            let (t3, t4) = ([c, a, d], [d, b, c]);
            let n = n1 + n2;
            if normal(&t3).dot(&n) <= 0.0 || normal(&t4).dot(&n) <= 0.0 {
                continue;
            }
            for t in [t1, t2] {
                for q in 0..3 {
                    edge.remove(&(t[q], t[(q + 1) % 3]));
                }
            }
            tris[i] = t3;
            tris[j] = t4;
            for (t, ti) in [(t3, i), (t4, j)] {
                for q in 0..3 {
                    edge.insert((t[q], t[(q + 1) % 3]), ti);
                }
            }
            *valence.get_mut(&a).expect("vertex") -= 1;
            *valence.get_mut(&b).expect("vertex") -= 1;
            *valence.get_mut(&c).expect("vertex") += 1;
            *valence.get_mut(&d).expect("vertex") += 1;
        }
    }
}

/// Vertex neighbour lists of a closed mesh of `n` vertices (each undirected edge once per side).
pub fn vertex_neighbours(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            // On a closed oriented mesh each undirected edge appears once in each direction.
            if a < b {
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
            }
        }
    }
    neighbours
}

pub fn mean_edge_length(positions: &[f32], neighbours: &[Vec<u32>]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (a, nb) in neighbours.iter().enumerate() {
        for &b in nb {
            let d = (0..3).map(|c| (positions[3 * a + c] - positions[3 * b as usize + c]) as f64);
            sum += d.map(|x| x * x).sum::<f64>().sqrt();
            n += 1;
        }
    }
    sum / n as f64
}

/// One-ring neighbours of every vertex of any triangle mesh (boundaries included), sorted.
fn one_rings(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut rings: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            rings[a as usize].push(b);
            rings[b as usize].push(a);
        }
    }
    for r in &mut rings {
        r.sort_unstable();
        r.dedup();
    }
    rings
}

/// Refuses a mesh that is not an oriented 2-manifold (with or without boundary): a directed
/// edge in two triangles means an edge shared by three or more, or two neighbours of opposite
/// orientation.
fn check_oriented_manifold(triangles: &[[u32; 3]]) -> Result<()> {
    let mut seen: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * triangles.len());
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            if let Some(j) = seen.insert((t[k], t[(k + 1) % 3]), i) {
                return Err(Error::new(
                    ErrorKind::TopologyMismatch,
                    format!(
                        "triangles {j} and {i} both hold the edge from vertex {} to vertex {} (0-based): re-meshing \
                         needs an oriented 2-manifold (each edge in at most two triangles, consistently oriented)",
                        t[k],
                        t[(k + 1) % 3]
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn at(p: &[f32], i: u32) -> Vector3<f64> {
    let k = 3 * i as usize;
    Vector3::new(p[k] as f64, p[k + 1] as f64, p[k + 2] as f64)
}

/// Splits every edge longer than `max_length` at its midpoint, longest first, each triangle at
/// most once per pass; passes repeat until no edge is longer (at most 32: each halves the
/// lengths). The two triangles of a split edge become four; a boundary edge's one becomes two.
fn split_long_edges(positions: &mut Vec<f32>, tris: &mut Vec<[u32; 3]>, max_length: f64) {
    for _ in 0..32 {
        let mut holder: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * tris.len());
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                holder.insert((t[k], t[(k + 1) % 3]), i);
            }
        }
        // Each undirected edge once: from its lower end, or its only direction on a boundary.
        let mut long: Vec<(f64, u32, u32)> = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|&(a, b)| a < b || !holder.contains_key(&(b, a)))
            .map(|(a, b)| ((at(positions, a) - at(positions, b)).norm(), a, b))
            .filter(|&(l, _, _)| l > max_length)
            .collect();
        if long.is_empty() {
            return;
        }
        long.sort_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut busy = vec![false; tris.len()];
        for (_, a, b) in long {
            let t1 = holder[&(a, b)];
            let t2 = holder.get(&(b, a)).copied();
            if busy[t1] || t2.is_some_and(|t| busy[t]) {
                continue;
            }
            let m = (positions.len() / 3) as u32;
            let mid = (at(positions, a) + at(positions, b)) * 0.5;
            positions.extend_from_slice(&[mid.x as f32, mid.y as f32, mid.z as f32]);
            for (t, (u, v)) in [(Some(t1), (a, b)), (t2, (b, a))] {
                let Some(t) = t else { continue };
                let tri = tris[t];
                let k = (0..3).find(|&k| tri[k] == u && tri[(k + 1) % 3] == v).expect("the triangle holds the edge");
                let c = tri[(k + 2) % 3];
                tris[t] = [u, m, c];
                tris.push([m, v, c]);
                busy[t] = true;
            }
        }
    }
}

/// Closest points on a triangle soup: a bounding-volume hierarchy (median splits along the
/// longest axis of the centroids' box, four triangles per leaf) over its non-degenerate
/// triangles, queried depth-first nearer child first with the boxes' distances as bounds.
pub struct ClosestPoint {
    corners: Vec<[Vector3<f64>; 3]>,
    /// Index of each stored triangle in the mesh given.
    ids: Vec<u32>,
    nodes: Vec<Node>,
}

struct Node {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    /// A leaf's first triangle; an inner node's first child.
    start: usize,
    /// A leaf's triangle count (`start..start + count`); 0 for an inner node.
    count: usize,
    /// An inner node's second child.
    second: usize,
}

const LEAF: usize = 4;

impl ClosestPoint {
    /// The hierarchy over `triangles` of `positions` (`[n][3]`), leaving out zero-area ones.
    /// `None` when every triangle has zero area.
    pub fn new(positions: &[f32], triangles: &[[u32; 3]]) -> Option<ClosestPoint> {
        let mut corners = Vec::with_capacity(triangles.len());
        let mut ids = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let c = [at(positions, t[0]), at(positions, t[1]), at(positions, t[2])];
            if (c[1] - c[0]).cross(&(c[2] - c[0])).norm_squared() > 0.0 {
                corners.push(c);
                ids.push(i as u32);
            }
        }
        if corners.is_empty() {
            return None;
        }
        let mut order: Vec<usize> = (0..corners.len()).collect();
        let mut nodes = Vec::with_capacity(2 * corners.len() / LEAF + 1);
        let centroid = |i: usize| (corners[i][0] + corners[i][1] + corners[i][2]) / 3.0;
        build(&mut nodes, &mut order, 0, &corners, &centroid);
        let corners_sorted = order.iter().map(|&i| corners[i]).collect();
        let ids_sorted = order.iter().map(|&i| ids[i]).collect();
        Some(ClosestPoint { corners: corners_sorted, ids: ids_sorted, nodes })
    }

    /// The closest point of the surface to `p`: (triangle of the mesh given, barycentric
    /// coordinates, the point, its squared distance). Ties go to the first triangle found.
    pub fn closest(&self, p: &Vector3<f64>) -> (u32, [f64; 3], Vector3<f64>, f64) {
        let mut best = (0u32, [1.0, 0.0, 0.0], self.corners[0][0], f64::INFINITY);
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if box_distance2(p, &node.lo, &node.hi) >= best.3 {
                continue;
            }
            if node.count > 0 {
                for k in node.start..node.start + node.count {
                    let (b, q) = closest_on_triangle(p, &self.corners[k]);
                    let d = (q - p).norm_squared();
                    if d < best.3 {
                        best = (self.ids[k], b, q, d);
                    }
                }
                continue;
            }
            let (a, b) = (node.start, node.second);
            let (da, db) = (
                box_distance2(p, &self.nodes[a].lo, &self.nodes[a].hi),
                box_distance2(p, &self.nodes[b].lo, &self.nodes[b].hi),
            );
            // The nearer child is popped first.
            if da <= db {
                stack.push(b);
                stack.push(a);
            } else {
                stack.push(a);
                stack.push(b);
            }
        }
        best
    }
}

fn build(
    nodes: &mut Vec<Node>,
    order: &mut [usize],
    offset: usize,
    corners: &[[Vector3<f64>; 3]],
    centroid: &dyn Fn(usize) -> Vector3<f64>,
) -> usize {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for &i in order.iter() {
        for c in &corners[i] {
            lo = lo.inf(c);
            hi = hi.sup(c);
        }
    }
    let me = nodes.len();
    nodes.push(Node { lo, hi, start: offset, count: order.len(), second: 0 });
    if order.len() <= LEAF {
        return me;
    }
    let mut clo = Vector3::repeat(f64::INFINITY);
    let mut chi = Vector3::repeat(f64::NEG_INFINITY);
    for &i in order.iter() {
        let c = centroid(i);
        clo = clo.inf(&c);
        chi = chi.sup(&c);
    }
    let axis = (chi - clo).imax();
    let half = order.len() / 2;
    order.select_nth_unstable_by(half, |&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]).then(a.cmp(&b)));
    let (left, right) = order.split_at_mut(half);
    let a = build(nodes, left, offset, corners, centroid);
    let b = build(nodes, right, offset + half, corners, centroid);
    nodes[me].count = 0;
    nodes[me].start = a;
    nodes[me].second = b;
    me
}

fn box_distance2(p: &Vector3<f64>, lo: &Vector3<f64>, hi: &Vector3<f64>) -> f64 {
    (0..3).map(|k| (lo[k] - p[k]).max(0.0).max(p[k] - hi[k])).map(|d| d * d).sum()
}

/// Closest point of a triangle to `p` and its barycentric coordinates (Ericson, Real-Time
/// Collision Detection, 5.1.5).
fn closest_on_triangle(p: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> ([f64; 3], Vector3<f64>) {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ([1.0, 0.0, 0.0], a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return ([0.0, 1.0, 0.0], b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return ([1.0 - v, v, 0.0], a + ab * v);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return ([0.0, 0.0, 1.0], c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return ([1.0 - w, 0.0, w], a + ac * w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return ([0.0, 1.0 - w, w], b + (c - b) * w);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    ([1.0 - v - w, v, w], a + ab * v + ac * w)
}

/// Tangential smoothing with projection onto the source (one Gauss-Seidel round): each
/// vertex not on a boundary moves halfway to its neighbours' centroid within its tangent plane
/// (normal: the area-weighted normal of its triangles), then to the closest source point; the
/// move is kept only if none of its triangles turns over (normal against the old one).
fn relax_onto(positions: &mut [f32], tris: &[[u32; 3]], source: &ClosestPoint) {
    let n = positions.len() / 3;
    let rings = one_rings(n, tris);
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, t) in tris.iter().enumerate() {
        for &v in t {
            around[v as usize].push(i);
        }
    }
    let directed: HashSet<(u32, u32)> = tris.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
    let mut on_boundary = vec![false; n];
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !directed.contains(&(b, a)) {
                on_boundary[a as usize] = true;
                on_boundary[b as usize] = true;
            }
        }
    }
    let normal = |p: &[f32], t: &[u32; 3]| (at(p, t[1]) - at(p, t[0])).cross(&(at(p, t[2]) - at(p, t[0])));
    for i in 0..n {
        if on_boundary[i] || rings[i].is_empty() {
            continue;
        }
        let p = at(positions, i as u32);
        let c = rings[i].iter().map(|&v| at(positions, v)).sum::<Vector3<f64>>() / rings[i].len() as f64;
        let nv: Vector3<f64> = around[i].iter().map(|&t| normal(positions, &tris[t])).sum();
        let Some(nv) = nv.try_normalize(1e-300) else { continue };
        let d = c - p;
        let q = p + 0.5 * (d - nv * nv.dot(&d));
        let (_, _, q, _) = source.closest(&q);
        let before: Vec<Vector3<f64>> = around[i].iter().map(|&t| normal(positions, &tris[t])).collect();
        let old = [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
        positions[3 * i..3 * i + 3].copy_from_slice(&[q.x as f32, q.y as f32, q.z as f32]);
        let turned = around[i].iter().zip(&before).any(|(&t, b)| normal(positions, &tris[t]).dot(b) <= 0.0);
        if turned {
            positions[3 * i..3 * i + 3].copy_from_slice(&old);
        }
    }
}

/// A frame re-meshed, with where each of its vertices lies on the source surface.
#[derive(Debug, Clone)]
pub struct RemeshedFrame {
    pub topology: Topology,
    /// `[vertices][3]`.
    pub positions: Vec<f32>,
    /// `[vertices][4]`: source triangle, then its three barycentric coordinates.
    pub correspondence: Vec<f64>,
    /// The target edge length used (after the seeded jitter).
    pub target_edge_length: f64,
}

/// Total area of a mesh.
pub fn surface_area(positions: &[f32], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            0.5 * (at(positions, t[1]) - at(positions, t[0])).cross(&(at(positions, t[2]) - at(positions, t[0]))).norm()
        })
        .sum()
}

/// The edge length that gives about `vertices` vertices on a surface of `area` (equilateral
/// triangles, two per vertex).
pub fn edge_length_for(area: f64, vertices: usize) -> f64 {
    (2.0 * area / (3f64.sqrt() * vertices as f64)).sqrt()
}

/// Re-meshes one surface (`positions` `[n][3]`, `triangles`) isotropically to `target_edge`,
/// the processing and numbering orders drawn from `seed` (see the module's description).
pub fn remesh_surface(
    positions: &[f32],
    triangles: &[[u32; 3]],
    target_edge: f64,
    iterations: usize,
    seed: u64,
) -> Result<RemeshedFrame> {
    check_oriented_manifold(triangles)?;
    if !(target_edge.is_finite() && target_edge > 0.0) {
        return Err(Error::new(
            ErrorKind::Unsupported,
            format!("target edge length {target_edge}: expected a positive length"),
        ));
    }
    let source = ClosestPoint::new(positions, triangles)
        .ok_or_else(|| Error::new(ErrorKind::Empty, "every triangle has zero area: nothing to re-mesh onto"))?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut tris = triangles.to_vec();
    tris.shuffle(&mut rng);
    let mut pos = positions.to_vec();
    for _ in 0..iterations {
        split_long_edges(&mut pos, &mut tris, 4.0 / 3.0 * target_edge);
        (pos, tris) = collapse_short_edges(&pos, &tris, 0.8 * target_edge, Some(4.0 / 3.0 * target_edge));
        flip_edges(&pos, &mut tris);
        relax_onto(&mut pos, &tris, &source);
    }
    // Unused vertices are dropped (`collapse_short_edges` compacts; zero iterations keep the
    // source's own).
    let n = pos.len() / 3;
    let mut perm: Vec<u32> = (0..n as u32).collect();
    perm.shuffle(&mut rng);
    let mut new_of = vec![u32::MAX; n];
    let mut used = vec![false; n];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut out_p = Vec::with_capacity(pos.len());
    let mut corr = Vec::with_capacity(4 * n);
    for &old in &perm {
        if !used[old as usize] {
            continue;
        }
        new_of[old as usize] = (out_p.len() / 3) as u32;
        let (tri, b, _, _) = source.closest(&at(&pos, old));
        let t = triangles[tri as usize];
        let q = at(positions, t[0]) * b[0] + at(positions, t[1]) * b[1] + at(positions, t[2]) * b[2];
        out_p.extend_from_slice(&[q.x as f32, q.y as f32, q.z as f32]);
        corr.extend_from_slice(&[tri as f64, b[0], b[1], b[2]]);
    }
    let out_t: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|v| new_of[v as usize])).collect();
    let topology = Topology::new(out_p.len() / 3, out_t, None)?;
    Ok(RemeshedFrame { topology, positions: out_p, correspondence: corr, target_edge_length: target_edge })
}

/// One-sided distances from each point of `points` (`[n][3]`) to the surface of `positions` and
/// `triangles` (the closest point of any non-degenerate triangle); their maximum is the
/// one-sided Hausdorff distance.
pub fn distances_to_surface(points: &[f32], positions: &[f32], triangles: &[[u32; 3]]) -> Vec<f64> {
    let Some(surface) = ClosestPoint::new(positions, triangles) else { return vec![f64::INFINITY; points.len() / 3] };
    (0..points.len() / 3).into_par_iter().map(|i| surface.closest(&at(points, i as u32)).3.sqrt()).collect()
}

/// Options of [`remesh_subject_frames`].
#[derive(Debug, Clone)]
pub struct RemeshFramesOptions {
    pub seed: u64,
    /// Vertices wanted per frame (before the +-10% edge-length jitter, which moves the count by
    /// about +-20%); `None`: the subject's vertex count.
    pub target_vertices: Option<usize>,
    /// Sequences to re-mesh, in this order; empty: all.
    pub sequences: Vec<String>,
    /// Only the first frames of each sequence.
    pub frames: Option<usize>,
    /// Remeshing rounds (Botsch and Kobbelt use 5 to 10).
    pub iterations: usize,
}

impl Default for RemeshFramesOptions {
    fn default() -> Self {
        RemeshFramesOptions { seed: 0, target_vertices: None, sequences: Vec::new(), frames: None, iterations: 5 }
    }
}

/// Largest vertex count asked of a re-meshed frame.
pub const MAX_TARGET_VERTICES: usize = 2_000_000;

/// The stream seed of frame `f` of sequence `s` (SplitMix64 of the three), so that a frame's
/// result depends on nothing else.
fn frame_seed(seed: u64, s: usize, f: usize) -> u64 {
    let mut z = seed ^ (s as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (f as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// What [`remesh_subject_frames`] takes for `frames` frames of about `vertices` vertices
/// (+10% at most), estimated before any work: each kept frame's positions and triangles (two
/// per vertex: 36 bytes a vertex), in memory and in the frame set folder, and each thread's
/// re-meshing work (about 400 bytes a vertex: half-edges, queues, the projection's grid).
pub fn remeshed_frames_size(frames: usize, vertices: usize, threads: usize) -> surfcap_mesh::sizing::Estimate {
    use surfcap_mesh::sizing::bytes;
    let v = vertices as f64 * 1.1;
    let kept = bytes(&[frames as f64, v], 36);
    surfcap_mesh::sizing::Estimate {
        what: format!("re-meshing {frames} frames to --vertices {vertices}"),
        memory: kept.saturating_add(bytes(&[threads.max(1) as f64, v], 400)),
        disk: kept,
        lower: "--vertices or --frames".into(),
    }
}

/// Every frame of a shared-topology subject re-meshed on its own (frames in parallel), as a
/// frame set with the known correspondence to the subject's triangles (source triangle indices
/// refer to `subject.topology()`, barycentrics to the same frame's positions). Names, labels,
/// tags, fps, up axis and units are the subject's.
pub fn remesh_subject_frames(
    subject: &Subject,
    opts: &RemeshFramesOptions,
    progress: &dyn Progress,
) -> Result<FrameSet> {
    let target = opts.target_vertices.unwrap_or(subject.topology().n_vertices());
    if !(4..=MAX_TARGET_VERTICES).contains(&target) {
        return Err(Error::new(
            ErrorKind::Unsupported,
            format!("a target of {target} vertices per frame: expected 4 to {MAX_TARGET_VERTICES}"),
        ));
    }
    if opts.frames == Some(0) {
        return Err(Error::new(ErrorKind::Unsupported, "0 frames per sequence: expected at least 1"));
    }
    let chosen: Vec<(usize, &surfcap_mesh::Sequence)> = if opts.sequences.is_empty() {
        subject.sequences().iter().enumerate().collect()
    } else {
        opts.sequences
            .iter()
            .map(|n| {
                subject.sequence(n).ok_or_else(|| {
                    let known: Vec<&str> = subject.sequences().iter().map(|s| s.name.as_str()).collect();
                    Error::new(
                        ErrorKind::Metadata,
                        format!("no sequence named {n:?}: the subject has {}", known.join(", ")),
                    )
                })
            })
            .collect::<Result<_>>()?
    };
    let jobs: Vec<(usize, usize)> = chosen
        .iter()
        .enumerate()
        .flat_map(|(c, (_, s))| (0..s.n_frames().min(opts.frames.unwrap_or(usize::MAX))).map(move |f| (c, f)))
        .collect();
    let tris = subject.topology().triangles();
    progress.start("re-meshing frames", jobs.len() as u64);
    let results: Vec<Result<RemeshedFrame>> = jobs
        .par_iter()
        .map(|&(c, f)| {
            let (k, s) = chosen[c];
            let p = s.frame(f);
            let mut rng = ChaCha8Rng::seed_from_u64(frame_seed(opts.seed, k, f));
            let jitter: f64 = rng.random_range(0.9..1.1);
            let edge = edge_length_for(surface_area(p, tris), target) * jitter;
            let r = remesh_surface(p, tris, edge, opts.iterations, rng.random()).map_err(|mut e| {
                e.message = format!("frame {}:{f}: {}", s.name, e.message);
                e
            });
            progress.advance(1);
            r
        })
        .collect();
    progress.finish();
    let mut results = results.into_iter();
    let mut sequences = Vec::with_capacity(chosen.len());
    for (_, s) in &chosen {
        let n = s.n_frames().min(opts.frames.unwrap_or(usize::MAX));
        let mut frames = Vec::with_capacity(n);
        let mut rows = Vec::new();
        for _ in 0..n {
            let r = results.next().expect("one result per job")?;
            rows.extend_from_slice(&r.correspondence);
            frames.push(Frame::new(r.topology, r.positions)?);
        }
        let labels: Vec<FrameLabel> = s.labels[..n].to_vec();
        sequences.push(
            FrameSetSequence::new(s.name.clone(), frames)?
                .with_tags(s.tags.clone())
                .with_labels(labels)?
                .with_correspondence(Correspondence { rows })?,
        );
    }
    FrameSet::new(subject.name.clone(), sequences, subject.fps, subject.up_axis, subject.units.clone())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{WormParams, worm_subject};

    fn worm() -> Subject {
        worm_subject(&WormParams { rings: 24, segments: 12, frames: 4, ..Default::default() }).unwrap()
    }

    fn max(v: &[f64]) -> f64 {
        v.iter().copied().fold(0.0, f64::max)
    }

    #[test]
    fn a_closed_tube_is_remeshed_onto_itself_with_its_correspondence() {
        let s = worm();
        let (p, t) = (s.frame(5).unwrap(), s.topology().triangles());
        let edge = edge_length_for(surface_area(p, t), 400);
        let r = remesh_surface(p, t, edge, 5, 3).unwrap();
        let n = r.topology.n_vertices();
        assert!((300..=520).contains(&n), "{n} vertices for a target of 400");
        assert!(r.topology.is_closed_manifold());
        assert_eq!(r.topology.count_degenerate_triangles(&r.positions, 1e-12), 0);
        // Every vertex on the source surface, where its correspondence says.
        assert!(max(&distances_to_surface(&r.positions, p, t)) < 1e-6);
        for (v, c) in r.correspondence.chunks_exact(4).enumerate() {
            let tri = t[c[0] as usize];
            assert!(
                c[1..].iter().all(|b| (-1e-12..=1.0 + 1e-12).contains(b)) && (c[1] + c[2] + c[3] - 1.0).abs() < 1e-9
            );
            for k in 0..3 {
                let want: f64 = (0..3).map(|j| c[1 + j] * p[3 * tri[j] as usize + k] as f64).sum();
                assert!((want - r.positions[3 * v + k] as f64).abs() < 1e-6);
            }
        }
        // The source's vertices are near the new surface: within a fraction of an edge (the
        // largest at the tube's pointed caps, which the new mesh cuts across).
        let mean_edge = mean_edge_length(&r.positions, &vertex_neighbours(n, r.topology.triangles()));
        let back = distances_to_surface(p, &r.positions, r.topology.triangles());
        let mean_back = back.iter().sum::<f64>() / back.len() as f64;
        assert!(max(&back) < 0.5 * mean_edge, "{} vs mean edge {mean_edge}", max(&back));
        assert!(mean_back < 0.1 * mean_edge, "{mean_back} vs mean edge {mean_edge}");
        // Another seed, another mesh; the same seed, the same mesh.
        let again = remesh_surface(p, t, edge, 5, 3).unwrap();
        assert_eq!((&again.topology, &again.positions), (&r.topology, &r.positions));
        let other = remesh_surface(p, t, edge, 5, 4).unwrap();
        assert_ne!(other.topology, r.topology);
    }

    #[test]
    fn frames_differ_and_the_result_does_not_depend_on_the_thread_count() {
        let s = worm();
        let opts = RemeshFramesOptions {
            seed: 11,
            target_vertices: Some(300),
            sequences: vec!["curl".into()],
            frames: Some(3),
            ..Default::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| remesh_subject_frames(&s, &opts, &surfcap_mesh::NoProgress).unwrap())
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one, two);
        assert_eq!(one.frame_count(), 3);
        assert_eq!(one.frame_index().label(2), "curl:2");
        let counts: Vec<usize> = (0..3).map(|g| one.frame(g).unwrap().n_vertices()).collect();
        assert!(counts[0] != counts[1] || counts[1] != counts[2], "{counts:?}");
        assert!(one.first_topology_difference().is_some());
        let c = one.sequences()[0].correspondence().unwrap();
        assert_eq!(c.rows.len(), 4 * counts.iter().sum::<usize>());
        let other =
            remesh_subject_frames(&s, &RemeshFramesOptions { seed: 12, ..opts.clone() }, &surfcap_mesh::NoProgress);
        assert_ne!(other.unwrap(), one);
    }

    #[test]
    fn an_open_patch_keeps_its_outline() {
        // A 9 x 9 grid on the unit square with a bump: a surface with a boundary.
        let n = 9;
        let mut p = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f32 / 8.0, j as f32 / 8.0);
                p.extend_from_slice(&[x, y, 0.1 * (3.0 * x).sin() * (3.0 * y).sin()]);
            }
        }
        let id = |i: usize, j: usize| (i * n + j) as u32;
        let mut t = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let r = remesh_surface(&p, &t, 0.07, 5, 1).unwrap();
        assert!(r.topology.n_vertices() > 2 * p.len() / 3, "{} vertices", r.topology.n_vertices());
        assert!(max(&distances_to_surface(&r.positions, &p, &t)) < 1e-6);
        // The outline is the square's: boundary edges add up to its perimeter.
        let tris = r.topology.triangles();
        let directed: HashSet<(u32, u32)> =
            tris.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).collect();
        let perimeter: f64 = directed
            .iter()
            .filter(|(a, b)| !directed.contains(&(*b, *a)))
            .map(|&(a, b)| (at(&r.positions, a) - at(&r.positions, b)).norm())
            .sum();
        let source_perimeter: f64 = (0..n - 1)
            .flat_map(|k| {
                [(id(k, 0), id(k + 1, 0)), (id(8, k), id(8, k + 1)), (id(k, 8), id(k + 1, 8)), (id(0, k), id(0, k + 1))]
            })
            .map(|(a, b)| (at(&p, a) - at(&p, b)).norm())
            .sum();
        assert!((perimeter - source_perimeter).abs() < 1e-5, "{perimeter} vs {source_perimeter}");
    }

    #[test]
    fn bad_inputs_are_refused_by_name() {
        let p = [0.0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., -1., 0.];
        let fan = [[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let e = remesh_surface(&p, &fan, 0.5, 2, 0).unwrap_err();
        assert_eq!(e.kind, ErrorKind::TopologyMismatch);
        assert!(e.message.starts_with("triangles 0 and 2 both hold the edge from vertex 0 to vertex 1"), "{e}");
        let s = worm();
        let bad =
            |o: RemeshFramesOptions| remesh_subject_frames(&s, &o, &surfcap_mesh::NoProgress).unwrap_err().to_string();
        assert!(bad(RemeshFramesOptions { target_vertices: Some(3), ..Default::default() }).contains("expected 4 to"));
        assert!(
            bad(RemeshFramesOptions { sequences: vec!["fly".into()], ..Default::default() }).contains("slither, curl")
        );
        assert!(bad(RemeshFramesOptions { frames: Some(0), ..Default::default() }).contains("at least 1"));
    }
}

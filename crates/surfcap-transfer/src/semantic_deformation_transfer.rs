//! The baseline of thesis 5.7.1 (Fig. 5.8): Baran, Vlasic, Grinspun and Popovic, "Semantic
//! deformation transfer", SIGGRAPH 2009, which "uses source and target affine spaces spanned
//! with key-poses, and a mapping derived from these key-pose pair associations".
//!
//! # What is implemented
//!
//! 1. **Shape space** (Baran et al.'s "patch-based LRI coordinates", after the linear
//!    rotation-invariant coordinates of Lipman et al. 2005). Every pose of a subject is
//!    encoded against the subject's first key pose (the reference). Per triangle the
//!    deformation gradient J = B A^-1 (thesis eq. 2.6, spatial reading, as in
//!    `surfcap_geometry::deformation_gradient`) is polar-decomposed J = Q S
//!    (`polar_decomposition`, thesis eq. 2.8-2.12). The triangles are grouped into patches
//!    (region growing on the triangle adjacency from farthest-point seeds, about
//!    [`SdtOptions::triangles_per_patch`] triangles each); patch k's rotation G_k is the rotation
//!    nearest to the area-weighted sum of its triangles' Q. The coordinates are:
//!    - per triangle: the 6 entries of S (combined linearly) and log(G_p(f)^T Q_f), the rotation
//!      of the triangle relative to its patch;
//!    - per pair of neighbouring patches (i, j): log(G_i^T G_j);
//!    - per connected component other than the root one: the offset of its vertex centroid from
//!      its parent component's centroid, in the frame of an anchor patch of the parent
//!      (G_a^T (c_child - c_parent)), divided by the reference's bounding-box diagonal.
//!
//!    Every coordinate is invariant to a rigid motion of the pose (tested), and a linear
//!    combination of encodings decodes to a mesh.
//! 2. **Projection**: a source pose x is projected onto the affine span of the source
//!    key poses' encodings: weights w with sum w = 1 minimising ||W (sum_i w_i x_i - x)||^2
//!    (the pseudo-inverse of the key differences; degenerate key sets are handled by an
//!    eigenvalue cut-off, so duplicated keys share their weight instead of blowing up).
//! 3. **Transfer**: the same weights combine the target key encodings, y = sum_i w_i y_i.
//! 4. **Reconstruction**: patch rotations from the relative rotations by linear least squares
//!    G_j = G_i exp(r_ij) with the root patch fixed, each result projected onto the nearest
//!    rotation (Lipman et al.'s LRI recipe; our reading, the paper's solver details were not
//!    available to check); triangle rotations Q_f = G_p(f) exp(r_f); gradients Q_f S_f;
//!    vertices by the Poisson solve of thesis eq. 2.48
//!    (`PoissonSolver`, factorised once on the target's reference pose); each connected
//!    component translated to the centroid its offsets give.
//!
//! The result is placed where the target key poses are: the root patch's rotation is the
//! rotation nearest sum_i w_i G_root,i and the root component's centroid is sum_i w_i c_root,i,
//! so a source key pose transfers to its target key pose exactly, in place.
//!
//! # Simplifications and choices (the paper leaves them open or they are ours)
//!
//! - Patches: Baran et al. segment the mesh into patches without saying how in a way we can
//!   reproduce; we grow them from farthest-point seeds (hop distance), deterministic.
//! - Several connected components (KayKit meshes are separate body parts; the original method
//!   needs one connected surface, Zhou et al. 2010 extend it): the pieces (triangles connected
//!   by edges) are joined into a spanning tree by centroid distance in the reference pose, and
//!   each tree edge adds one "bridge" relative rotation between the nearest patches; component
//!   translations are encoded as the offsets above. Pieces smaller than a quarter of a patch
//!   join the patch nearest to them instead of getting their own.
//! - Projection metric: as far as we could check, the paper projects in the plain Euclidean
//!   norm of its coordinates. The patch-pair rotations are few (one per patch pair) against 9
//!   numbers per triangle, so in a plain norm the articulation between patches would hardly
//!   count; we weight each patch-pair and component-offset coordinate by
//!   sqrt(triangles / patches), so that a patch pair counts as much as a patch's worth of
//!   triangles. The off-diagonal entries of S are weighted by sqrt 2 (the Frobenius norm of
//!   S). Measured (tests/baran_real_data.rs): knight -> barbarian walk, non-key RMS 1.24% of
//!   the height with the plain norm, 0.90% weighted; cat -> lion leave-one-out 25.2% and
//!   22.5%. The weights only change the projection; the combination itself is unweighted.
//! - Zero-area triangles: a triangle of zero area in the reference pose has no deformation
//!   gradient; it is left out of the encoding (its coordinates stay 0) and of the patches, and
//!   it has zero area, hence no weight, in the Poisson system. A triangle that collapses in a
//!   later pose gets a deformation gradient whose normal column uses the mean normal of its
//!   neighbours: its action on the triangle's edges is exact (S gets a near-zero singular
//!   value), which is all the Poisson solve uses, so key poses still reproduce exactly.
//! - The patch-rotation system is dense (3 (P - 1) unknowns); [`SdtOptions::max_patches`]
//!   bounds it: patches grow on large meshes, and a mesh of more separate pieces than that
//!   (each needs a patch) is refused by name.
//! - The paper's optional split into independent body parts with their own key poses is not
//!   implemented: one transfer for the whole body.

use std::collections::{BTreeSet, HashMap, VecDeque};

use nalgebra::{DMatrix, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use surfcap_geometry::deformation_gradient::{triangle_frame, vertex};
use surfcap_geometry::poisson_reconstruction::PoissonSolver;
use surfcap_geometry::polar_decomposition::polar_decomposition;
use surfcap_geometry::rotation_log_exp::{exp_rotation, log_rotation};
use surfcap_mesh::{Components, Topology, connected_components};

use crate::error::{Error, Result, check_positions};

/// Coordinates per triangle: 6 of S, 3 of the rotation relative to the patch.
const PER_TRIANGLE: usize = 9;

/// Tuning of the shape space.
#[derive(Debug, Clone, PartialEq)]
pub struct SdtOptions {
    /// Target size of a patch, in triangles (default 150); larger when the mesh would need
    /// more than half of `max_patches`.
    pub triangles_per_patch: usize,
    /// Most patches a subject may have (the patch-rotation solve is dense; default 400).
    pub max_patches: usize,
}

impl Default for SdtOptions {
    fn default() -> Self {
        SdtOptions { triangles_per_patch: 150, max_patches: 400 }
    }
}

/// One pose in a subject's shape space.
#[derive(Debug, Clone)]
struct Encoding {
    coords: Vec<f64>,
    /// Absolute rotation of the root patch (relative to the reference pose).
    root_rotation: Matrix3<f64>,
    /// Vertex centroid of the root component.
    root_centroid: Vector3<f64>,
}

/// A subject's patch-based rotation-invariant shape space.
#[derive(Debug, Clone)]
struct ShapeSpace {
    triangles: Vec<[u32; 3]>,
    n_vertices: usize,
    /// Inverse of the reference frame (v1 - v3, v2 - v3, n) per triangle; `None`: zero area.
    ref_inv: Vec<Option<Matrix3<f64>>>,
    ref_area: Vec<f64>,
    /// Edge-adjacent triangles of each triangle.
    neighbours: Vec<Vec<u32>>,
    /// Patch of each triangle (`u32::MAX` for the ones left out).
    tri_patch: Vec<u32>,
    patches: Vec<Vec<u32>>,
    /// Neighbouring patches (i < j not required: the pair's order fixes the convention).
    patch_edges: Vec<(u32, u32)>,
    root_patch: usize,
    components: Components,
    root_component: usize,
    /// Non-root components in tree order: (component, parent component, anchor patch).
    component_tree: Vec<(usize, usize, usize)>,
    /// Length unit of the offsets (reference bounding-box diagonal).
    scale: f64,
    /// Projection weight of each coordinate.
    metric: Vec<f64>,
}

fn centroid_of(p: &[f32], t: &[u32; 3]) -> Vector3<f64> {
    (vertex(p, t[0]) + vertex(p, t[1]) + vertex(p, t[2])) / 3.0
}

/// Index of the nearest point to `q` among `candidates` (first one on ties).
fn nearest(candidates: impl Iterator<Item = (usize, Vector3<f64>)>, q: &Vector3<f64>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in candidates {
        let d = (c - q).norm_squared();
        if best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// Prim's spanning tree over points (O(n^2)), from `root`: (child, parent) in attachment order.
fn spanning_tree(points: &[Vector3<f64>], root: usize) -> Vec<(usize, usize)> {
    let n = points.len();
    let mut in_tree = vec![false; n];
    let mut best = vec![(f64::INFINITY, root); n];
    in_tree[root] = true;
    for k in 0..n {
        best[k] = ((points[k] - points[root]).norm_squared(), root);
    }
    let mut out = Vec::with_capacity(n.saturating_sub(1));
    for _ in 1..n {
        let mut pick: Option<usize> = None;
        for k in 0..n {
            if !in_tree[k] && pick.is_none_or(|p| best[k].0 < best[p].0) {
                pick = Some(k);
            }
        }
        let Some(c) = pick else { break };
        in_tree[c] = true;
        out.push((c, best[c].1));
        for k in 0..n {
            let d = (points[k] - points[c]).norm_squared();
            if !in_tree[k] && d < best[k].0 {
                best[k] = (d, c);
            }
        }
    }
    out
}

/// Multi-source breadth-first search from `sources` through `allowed` triangles: the hop
/// distance and the source index of every member reached (`dist` of `members` reset first).
fn bfs(
    sources: &[u32],
    neighbours: &[Vec<u32>],
    allowed: &[bool],
    dist: &mut [u32],
    owner: &mut [u32],
    members: &[u32],
) {
    for &m in members {
        dist[m as usize] = u32::MAX;
    }
    let mut queue = VecDeque::new();
    for (k, &s) in sources.iter().enumerate() {
        dist[s as usize] = 0;
        owner[s as usize] = k as u32;
        queue.push_back(s);
    }
    while let Some(t) = queue.pop_front() {
        for &u in &neighbours[t as usize] {
            if allowed[u as usize] && dist[u as usize] == u32::MAX {
                dist[u as usize] = dist[t as usize] + 1;
                owner[u as usize] = owner[t as usize];
                queue.push_back(u);
            }
        }
    }
}

impl ShapeSpace {
    fn new(who: &str, topology: &Topology, reference: &[f32], opts: &SdtOptions) -> Result<Self> {
        let triangles = topology.triangles().to_vec();
        let n_t = triangles.len();
        let ref_frames: Vec<Option<Matrix3<f64>>> = triangles.iter().map(|t| triangle_frame(reference, t)).collect();
        let ref_inv: Vec<Option<Matrix3<f64>>> = ref_frames.iter().map(|a| a.and_then(|a| a.try_inverse())).collect();
        let ref_area: Vec<f64> =
            ref_frames.iter().map(|a| a.map_or(0.0, |a| 0.5 * a.column(0).cross(&a.column(1)).norm())).collect();
        let valid: Vec<bool> = ref_inv.iter().map(Option::is_some).collect();
        let n_valid = valid.iter().filter(|&&v| v).count();
        if n_valid == 0 {
            return Err(Error::Invalid(format!(
                "{who} key pose 0 has no triangle of non-zero area: expected a surface to encode"
            )));
        }

        // Edge adjacency.
        let mut edge_owner: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (f, t) in triangles.iter().enumerate() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                edge_owner.entry((a.min(b), a.max(b))).or_default().push(f as u32);
            }
        }
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n_t];
        for (f, t) in triangles.iter().enumerate() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                for &g in &edge_owner[&(a.min(b), a.max(b))] {
                    if g as usize != f && !neighbours[f].contains(&g) {
                        neighbours[f].push(g);
                    }
                }
            }
        }
        for nb in &mut neighbours {
            nb.sort_unstable();
        }

        // Pieces: valid triangles connected through edges shared with valid triangles.
        let mut piece = vec![u32::MAX; n_t];
        let mut pieces: Vec<Vec<u32>> = Vec::new();
        for f in 0..n_t {
            if !valid[f] || piece[f] != u32::MAX {
                continue;
            }
            let id = pieces.len() as u32;
            let mut members = vec![f as u32];
            piece[f] = id;
            let mut k = 0;
            while k < members.len() {
                let t = members[k] as usize;
                for &u in &neighbours[t] {
                    if valid[u as usize] && piece[u as usize] == u32::MAX {
                        piece[u as usize] = id;
                        members.push(u);
                    }
                }
                k += 1;
            }
            members.sort_unstable();
            pieces.push(members);
        }

        // Patches grown inside each piece large enough to hold one.
        // Patches grow past the asked size when the mesh is large, so that the pieces' patches
        // take at most half of `max_patches` (the rest is room for one per separate piece).
        let per_patch = opts.triangles_per_patch.max(1).max((2 * n_valid).div_ceil(opts.max_patches.max(2)));
        let min_piece = (per_patch / 4).max(1);
        let big: Vec<bool> = {
            let any_big = pieces.iter().any(|p| p.len() >= min_piece);
            pieces.iter().map(|p| !any_big || p.len() >= min_piece).collect()
        };
        let mut tri_patch = vec![u32::MAX; n_t];
        let mut patches: Vec<Vec<u32>> = Vec::new();
        let mut dist = vec![u32::MAX; n_t];
        let mut owner = vec![0u32; n_t];
        for (pi, members) in pieces.iter().enumerate() {
            if !big[pi] {
                continue;
            }
            let k = members.len().div_ceil(per_patch).max(1);
            let mut seeds = vec![members[0]];
            while seeds.len() < k {
                bfs(&seeds, &neighbours, &valid, &mut dist, &mut owner, members);
                // Farthest member; ties to the lowest index.
                let far = members.iter().copied().max_by_key(|&m| (dist[m as usize], std::cmp::Reverse(m)));
                match far {
                    Some(m) if dist[m as usize] > 0 => seeds.push(m),
                    _ => break,
                }
            }
            bfs(&seeds, &neighbours, &valid, &mut dist, &mut owner, members);
            let base = patches.len();
            patches.extend((0..seeds.len()).map(|_| Vec::new()));
            for &m in members {
                let p = base + owner[m as usize] as usize;
                tri_patch[m as usize] = p as u32;
                patches[p].push(m);
            }
        }
        if patches.len() > opts.max_patches {
            return Err(Error::Invalid(format!(
                "{who} mesh needs {} patches ({} separate pieces): expected at most {} (raise the patch size)",
                patches.len(),
                pieces.len(),
                opts.max_patches
            )));
        }
        let tri_centroid: Vec<Vector3<f64>> = triangles.iter().map(|t| centroid_of(reference, t)).collect();
        let big_patched: Vec<u32> = (0..n_t as u32).filter(|&f| tri_patch[f as usize] != u32::MAX).collect();
        // Small pieces join the patch nearest to their centroid.
        for (pi, members) in pieces.iter().enumerate() {
            if big[pi] {
                continue;
            }
            let c = members.iter().map(|&m| tri_centroid[m as usize]).sum::<Vector3<f64>>() / members.len() as f64;
            let near = nearest(big_patched.iter().map(|&f| (f as usize, tri_centroid[f as usize])), &c)
                .expect("some piece is big");
            let p = tri_patch[near];
            for &m in members {
                tri_patch[m as usize] = p;
                patches[p as usize].push(m);
            }
        }
        for p in &mut patches {
            p.sort_unstable();
        }

        // Patch adjacency from triangle adjacency.
        let mut pairs = BTreeSet::new();
        for f in 0..n_t {
            let pf = tri_patch[f];
            if pf == u32::MAX {
                continue;
            }
            for &g in &neighbours[f] {
                let pg = tri_patch[g as usize];
                if pg != u32::MAX && pg != pf {
                    pairs.insert((pf.min(pg), pf.max(pg)));
                }
            }
        }

        // Vertex components and the root (most valid triangles, then lowest index).
        let components = connected_components(topology);
        let mut comp_valid = vec![0usize; components.count];
        for (f, t) in triangles.iter().enumerate() {
            if valid[f] {
                comp_valid[components.labels[t[0] as usize] as usize] += 1;
            }
        }
        let root_component =
            (0..components.count).max_by_key(|&c| (comp_valid[c], std::cmp::Reverse(c))).expect("a valid triangle");
        // The root patch lies in a big piece of the root component when there is one.
        let in_root = |f: usize| {
            tri_patch[f] != u32::MAX && components.labels[triangles[f][0] as usize] as usize == root_component
        };
        let root_tri = (0..n_t)
            .find(|&f| in_root(f) && big[piece[f] as usize])
            .or_else(|| (0..n_t).find(|&f| in_root(f)))
            .expect("the root component has a valid triangle");
        let root_patch = tri_patch[root_tri] as usize;

        // Bridges between big pieces: spanning tree by centroid distance.
        let big_ids: Vec<usize> = (0..pieces.len()).filter(|&p| big[p]).collect();
        let piece_centroids: Vec<Vector3<f64>> = big_ids
            .iter()
            .map(|&p| {
                pieces[p].iter().map(|&m| tri_centroid[m as usize]).sum::<Vector3<f64>>() / pieces[p].len() as f64
            })
            .collect();
        let root_piece = big_ids.iter().position(|&p| p == piece[root_tri] as usize).unwrap_or(0);
        for (child, parent) in spanning_tree(&piece_centroids, root_piece) {
            let (pc, pp) = (big_ids[child], big_ids[parent]);
            let a =
                nearest(pieces[pp].iter().map(|&m| (m as usize, tri_centroid[m as usize])), &piece_centroids[child])
                    .expect("pieces are not empty");
            let b = nearest(pieces[pc].iter().map(|&m| (m as usize, tri_centroid[m as usize])), &tri_centroid[a])
                .expect("pieces are not empty");
            let (pa, pb) = (tri_patch[a], tri_patch[b]);
            if pa != pb {
                pairs.insert((pa.min(pb), pa.max(pb)));
            }
        }
        let patch_edges: Vec<(u32, u32)> = pairs.into_iter().collect();

        // Component tree for the translations.
        let mut comp_sum = vec![Vector3::zeros(); components.count];
        let mut comp_n = vec![0usize; components.count];
        for (v, &c) in components.labels.iter().enumerate() {
            comp_sum[c as usize] += vertex(reference, v as u32);
            comp_n[c as usize] += 1;
        }
        let comp_centroid: Vec<Vector3<f64>> =
            comp_sum.iter().zip(&comp_n).map(|(s, &n)| s / n.max(1) as f64).collect();
        let mut comp_tris: Vec<Vec<u32>> = vec![Vec::new(); components.count];
        for f in 0..n_t {
            if tri_patch[f] != u32::MAX {
                comp_tris[components.labels[triangles[f][0] as usize] as usize].push(f as u32);
            }
        }
        let component_tree: Vec<(usize, usize, usize)> = spanning_tree(&comp_centroid, root_component)
            .into_iter()
            .map(|(child, parent)| {
                let anchor = nearest(
                    comp_tris[parent].iter().map(|&m| (m as usize, tri_centroid[m as usize])),
                    &comp_centroid[child],
                )
                .map_or(root_patch, |f| tri_patch[f] as usize);
                (child, parent, anchor)
            })
            .collect();

        let (lo, hi) = surfcap_mesh::bounding_box(reference);
        let diag = (0..3).map(|k| ((hi[k] - lo[k]) as f64).powi(2)).sum::<f64>().sqrt();
        let scale = if diag > 0.0 && diag.is_finite() { diag } else { 1.0 };

        let long_weight = (n_valid as f64 / patches.len() as f64).sqrt();
        let s2 = std::f64::consts::SQRT_2;
        let mut metric = Vec::with_capacity(PER_TRIANGLE * n_t + 3 * (patch_edges.len() + component_tree.len()));
        for _ in 0..n_t {
            metric.extend_from_slice(&[1.0, s2, s2, 1.0, s2, 1.0, 1.0, 1.0, 1.0]);
        }
        metric.extend(std::iter::repeat_n(long_weight, 3 * (patch_edges.len() + component_tree.len())));

        Ok(ShapeSpace {
            triangles,
            n_vertices: topology.n_vertices(),
            ref_inv,
            ref_area,
            neighbours,
            tri_patch,
            patches,
            patch_edges,
            root_patch,
            components,
            root_component,
            component_tree,
            scale,
            metric,
        })
    }

    fn dim(&self) -> usize {
        self.metric.len()
    }

    /// The per-triangle polar factors (Q, S) of `pose` against the reference.
    fn polar_factors(&self, pose: &[f32]) -> Vec<Option<(Matrix3<f64>, Matrix3<f64>)>> {
        let normals: Vec<Option<Vector3<f64>>> = self
            .triangles
            .par_iter()
            .map(|t| {
                let (v1, v2, v3) = (vertex(pose, t[0]), vertex(pose, t[1]), vertex(pose, t[2]));
                let (e1, e2) = (v1 - v3, v2 - v3);
                let c = e1.cross(&e2);
                let scale = e1.norm_squared().max(e2.norm_squared());
                (scale > 0.0 && c.norm() > 1e-12 * scale).then(|| c.normalize())
            })
            .collect();
        (0..self.triangles.len())
            .into_par_iter()
            .map(|f| {
                let a_inv = self.ref_inv[f]?;
                let t = &self.triangles[f];
                let (v1, v2, v3) = (vertex(pose, t[0]), vertex(pose, t[1]), vertex(pose, t[2]));
                let (e1, e2) = (v1 - v3, v2 - v3);
                let n = normals[f].unwrap_or_else(|| {
                    // Collapsed triangle: the neighbours' mean normal, made orthogonal to the
                    // (collinear) edges; the reference normal as a last resort.
                    let mut m: Vector3<f64> = self.neighbours[f].iter().filter_map(|&g| normals[g as usize]).sum();
                    let dir = if e1.norm_squared() >= e2.norm_squared() { e1 } else { e2 };
                    if dir.norm_squared() > 0.0 {
                        let d = dir.normalize();
                        m -= d * d.dot(&m);
                    }
                    if m.norm() > 1e-9 {
                        m.normalize()
                    } else {
                        let r = a_inv.try_inverse().unwrap_or_else(Matrix3::identity);
                        r.column(2).into_owned()
                    }
                });
                let j = Matrix3::from_columns(&[e1, e2, n]) * a_inv;
                Some(polar_decomposition(&j))
            })
            .collect()
    }

    fn encode(&self, pose: &[f32]) -> Encoding {
        let factors = self.polar_factors(pose);
        let g: Vec<Matrix3<f64>> = self
            .patches
            .iter()
            .map(|members| {
                let mut sum = Matrix3::zeros();
                for &m in members {
                    if let Some((q, _)) = &factors[m as usize] {
                        sum += q * self.ref_area[m as usize];
                    }
                }
                polar_decomposition(&sum).0
            })
            .collect();
        let mut coords = vec![0.0; self.dim()];
        coords[..PER_TRIANGLE * self.triangles.len()].par_chunks_mut(PER_TRIANGLE).enumerate().for_each(|(f, out)| {
            if let Some((q, s)) = &factors[f] {
                let gp = &g[self.tri_patch[f] as usize];
                let r = log_rotation(&(gp.transpose() * q));
                out.copy_from_slice(&[s[(0, 0)], s[(0, 1)], s[(0, 2)], s[(1, 1)], s[(1, 2)], s[(2, 2)], r.x, r.y, r.z]);
            }
        });
        let mut k = PER_TRIANGLE * self.triangles.len();
        for &(i, j) in &self.patch_edges {
            let r = log_rotation(&(g[i as usize].transpose() * g[j as usize]));
            coords[k..k + 3].copy_from_slice(r.as_slice());
            k += 3;
        }
        let centroids = self.component_centroids(pose);
        for &(child, parent, anchor) in &self.component_tree {
            let d = g[anchor].transpose() * (centroids[child] - centroids[parent]) / self.scale;
            coords[k..k + 3].copy_from_slice(d.as_slice());
            k += 3;
        }
        Encoding { coords, root_rotation: g[self.root_patch], root_centroid: centroids[self.root_component] }
    }

    fn component_centroids(&self, pose: &[f32]) -> Vec<Vector3<f64>> {
        let mut sum = vec![Vector3::zeros(); self.components.count];
        let mut n = vec![0usize; self.components.count];
        for (v, &c) in self.components.labels.iter().enumerate() {
            sum[c as usize] += vertex(pose, v as u32);
            n[c as usize] += 1;
        }
        sum.iter().zip(&n).map(|(s, &n)| s / n.max(1) as f64).collect()
    }

    /// Patch rotations from the relative ones (least squares, root fixed to `root`), each
    /// projected onto the nearest rotation.
    fn patch_rotations(&self, coords: &[f64], root: &Matrix3<f64>) -> Result<Vec<Matrix3<f64>>> {
        let n_p = self.patches.len();
        let r0 = self.root_patch;
        // Unknown index of each non-root patch.
        let idx: Vec<Option<usize>> = (0..n_p)
            .scan(0usize, |next, p| {
                Some(if p == r0 {
                    None
                } else {
                    *next += 1;
                    Some(*next - 1)
                })
            })
            .collect();
        let m = 3 * (n_p - 1);
        let mut h = DMatrix::<f64>::zeros(m, m);
        let mut b = DMatrix::<f64>::zeros(m, 3);
        let base = PER_TRIANGLE * self.triangles.len();
        let root_t = root.transpose();
        for (e, &(i, j)) in self.patch_edges.iter().enumerate() {
            let w = Vector3::new(coords[base + 3 * e], coords[base + 3 * e + 1], coords[base + 3 * e + 2]);
            let r = exp_rotation(&w);
            // G_j^T - R^T G_i^T = 0, unknowns stacked as G_k^T blocks.
            match (idx[i as usize], idx[j as usize]) {
                (Some(a), Some(c)) => {
                    for (x, y, blk) in
                        [(a, a, Matrix3::identity()), (c, c, Matrix3::identity()), (a, c, -r), (c, a, -r.transpose())]
                    {
                        let mut v = h.fixed_view_mut::<3, 3>(3 * x, 3 * y);
                        v += blk;
                    }
                }
                (None, Some(c)) => {
                    let mut v = h.fixed_view_mut::<3, 3>(3 * c, 3 * c);
                    v += Matrix3::identity();
                    let mut rhs = b.fixed_view_mut::<3, 3>(3 * c, 0);
                    rhs += r.transpose() * root_t;
                }
                (Some(a), None) => {
                    let mut v = h.fixed_view_mut::<3, 3>(3 * a, 3 * a);
                    v += Matrix3::identity();
                    let mut rhs = b.fixed_view_mut::<3, 3>(3 * a, 0);
                    rhs += r * root_t;
                }
                (None, None) => {}
            }
        }
        let mut g = vec![*root; n_p];
        if m > 0 {
            for k in 0..m {
                h[(k, k)] += 1e-12;
            }
            let chol = h.cholesky().ok_or_else(|| {
                Error::Invalid(
                    "patch rotations: the patch graph is not connected (expected one connected graph)".into(),
                )
            })?;
            let x = chol.solve(&b);
            for (p, id) in idx.iter().enumerate() {
                if let Some(a) = id {
                    let gt: Matrix3<f64> = x.fixed_view::<3, 3>(3 * a, 0).into_owned();
                    g[p] = polar_decomposition(&gt.transpose()).0;
                }
            }
        }
        Ok(g)
    }
}

/// Semantic deformation transfer (Baran et al. 2009) between two subjects with different
/// topologies, from pairs of corresponding key poses.
pub struct SemanticDeformationTransfer {
    source: ShapeSpace,
    target: ShapeSpace,
    /// Source key 0's encoding.
    source_origin: Vec<f64>,
    /// Metric-weighted differences x_i - x_0 (i >= 1) of the source keys.
    source_diffs: Vec<Vec<f64>>,
    /// Pseudo-inverse of their Gram matrix.
    gram_pinv: DMatrix<f64>,
    target_keys: Vec<Encoding>,
    solver: PoissonSolver,
    /// Gradient of the target reference positions per triangle (tangent projector).
    target_ref_gradients: Vec<Matrix3<f64>>,
}

impl SemanticDeformationTransfer {
    /// Encodes the key poses of both subjects (key 0 of each is its reference) and factorises
    /// the target's Poisson system. `source_keys[k]` and `target_keys[k]` correspond.
    pub fn new(
        source_topology: &Topology,
        source_keys: &[Vec<f32>],
        target_topology: &Topology,
        target_keys: &[Vec<f32>],
    ) -> Result<Self> {
        Self::with_options(source_topology, source_keys, target_topology, target_keys, &SdtOptions::default())
    }

    /// [`SemanticDeformationTransfer::new`] with explicit options.
    pub fn with_options(
        source_topology: &Topology,
        source_keys: &[Vec<f32>],
        target_topology: &Topology,
        target_keys: &[Vec<f32>],
        opts: &SdtOptions,
    ) -> Result<Self> {
        if source_keys.is_empty() {
            return Err(Error::Invalid("no key pose pairs: expected at least one".into()));
        }
        if source_keys.len() != target_keys.len() {
            return Err(Error::Invalid(format!(
                "{} source key poses and {} target key poses: expected one target key pose per source key pose",
                source_keys.len(),
                target_keys.len()
            )));
        }
        for (k, p) in source_keys.iter().enumerate() {
            check_positions(p, source_topology.n_vertices(), &format!("source key pose {k}"))?;
        }
        for (k, p) in target_keys.iter().enumerate() {
            check_positions(p, target_topology.n_vertices(), &format!("target key pose {k}"))?;
        }
        let source = ShapeSpace::new("source", source_topology, &source_keys[0], opts)?;
        let target = ShapeSpace::new("target", target_topology, &target_keys[0], opts)?;
        let source_enc: Vec<Vec<f64>> = source_keys.iter().map(|p| source.encode(p).coords).collect();
        let target_enc: Vec<Encoding> = target_keys.iter().map(|p| target.encode(p)).collect();
        let origin = source_enc[0].clone();
        let diffs: Vec<Vec<f64>> = source_enc[1..]
            .iter()
            .map(|x| x.iter().zip(&origin).zip(&source.metric).map(|((a, b), w)| w * (a - b)).collect())
            .collect();
        let n = diffs.len();
        let gram = DMatrix::<f64>::from_fn(n, n, |i, j| diffs[i].iter().zip(&diffs[j]).map(|(a, b)| a * b).sum());
        let gram_pinv = pseudo_inverse(&gram);
        let solver = PoissonSolver::new(target_topology, &target_keys[0])?;
        let target_ref_gradients = solver.operator().gradients(&target_keys[0]);
        Ok(SemanticDeformationTransfer {
            source,
            target,
            source_origin: origin,
            source_diffs: diffs,
            gram_pinv,
            target_keys: target_enc,
            solver,
            target_ref_gradients,
        })
    }

    /// Number of key pose pairs.
    pub fn n_keys(&self) -> usize {
        self.target_keys.len()
    }

    /// Number of patches of the source and of the target shape spaces.
    pub fn n_patches(&self) -> (usize, usize) {
        (self.source.patches.len(), self.target.patches.len())
    }

    /// The projection of `source_pose` onto the affine span of the source key poses: one weight
    /// per key pose, summing to 1.
    pub fn weights(&self, source_pose: &[f32]) -> Result<Vec<f64>> {
        check_positions(source_pose, self.source.n_vertices, "source pose")?;
        let x = self.source.encode(source_pose).coords;
        let d: Vec<f64> =
            x.iter().zip(&self.source_origin).zip(&self.source.metric).map(|((a, b), w)| w * (a - b)).collect();
        let n = self.source_diffs.len();
        let rhs =
            nalgebra::DVector::<f64>::from_fn(n, |i, _| self.source_diffs[i].iter().zip(&d).map(|(a, b)| a * b).sum());
        let a = &self.gram_pinv * rhs;
        let mut w = Vec::with_capacity(n + 1);
        w.push(1.0 - a.iter().sum::<f64>());
        w.extend(a.iter());
        Ok(w)
    }

    /// The target pose of the weighted combination of the target key poses (weights as
    /// [`SemanticDeformationTransfer::weights`] gives, one per key pose; they need not sum to 1).
    pub fn reconstruct(&self, weights: &[f64]) -> Result<Vec<f32>> {
        if weights.len() != self.n_keys() {
            return Err(Error::Invalid(format!(
                "{} weights: expected one per key pose ({})",
                weights.len(),
                self.n_keys()
            )));
        }
        if let Some(k) = weights.iter().position(|w| !w.is_finite()) {
            return Err(Error::Invalid(format!("weight {k} is not finite: expected finite weights")));
        }
        let t = &self.target;
        let mut y = vec![0.0; t.dim()];
        let mut rot = Matrix3::zeros();
        let mut centre = Vector3::zeros();
        for (w, key) in weights.iter().zip(&self.target_keys) {
            for (o, c) in y.iter_mut().zip(&key.coords) {
                *o += w * c;
            }
            rot += key.root_rotation * *w;
            centre += key.root_centroid * *w;
        }
        let root = polar_decomposition(&rot).0;
        let g = t.patch_rotations(&y, &root)?;
        let targets: Vec<Matrix3<f64>> = (0..t.triangles.len())
            .into_par_iter()
            .map(|f| {
                if t.tri_patch[f] == u32::MAX {
                    return Matrix3::zeros();
                }
                let c = &y[PER_TRIANGLE * f..PER_TRIANGLE * (f + 1)];
                let s = Matrix3::new(c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5]);
                let q = g[t.tri_patch[f] as usize] * exp_rotation(&Vector3::new(c[6], c[7], c[8]));
                self.target_ref_gradients[f] * (q * s).transpose()
            })
            .collect();
        // Component centroids down the tree.
        let mut centroids = vec![centre; t.components.count];
        let mut k = PER_TRIANGLE * t.triangles.len() + 3 * t.patch_edges.len();
        for &(child, parent, anchor) in &t.component_tree {
            let d = Vector3::new(y[k], y[k + 1], y[k + 2]) * t.scale;
            centroids[child] = centroids[parent] + g[anchor] * d;
            k += 3;
        }
        debug_assert_eq!(self.solver.components(), &t.components);
        let out = self.solver.solve(&targets, &centroids);
        if out.iter().any(|x| !x.is_finite()) {
            return Err(Error::Invalid("the reconstruction is not finite: expected finite key poses".into()));
        }
        Ok(out)
    }

    /// Transfers one source pose: its projection weights, then the target pose they combine.
    pub fn transfer(&self, source_pose: &[f32]) -> Result<Vec<f32>> {
        self.reconstruct(&self.weights(source_pose)?)
    }
}

/// Pseudo-inverse of a symmetric positive semi-definite matrix (eigenvalues below 1e-10 of the
/// largest are dropped).
fn pseudo_inverse(m: &DMatrix<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    if n == 0 {
        return DMatrix::zeros(0, 0);
    }
    let eig = SymmetricEigen::new(m.clone());
    let top = eig.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut out = DMatrix::zeros(n, n);
    for (k, &l) in eig.eigenvalues.iter().enumerate() {
        if top > 0.0 && l > 1e-10 * top {
            let v = eig.eigenvectors.column(k);
            out += (v * v.transpose()) / l;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed-ish tube along y (rings of `around` vertices, `along` rings), radius `r`, length
    /// `len`, its base shifted by `offset`.
    fn tube(around: usize, along: usize, r: f64, len: f64, offset: [f64; 3]) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
        let mut p = Vec::new();
        for i in 0..along {
            let y = len * i as f64 / (along - 1) as f64;
            for k in 0..around {
                let a = std::f64::consts::TAU * k as f64 / around as f64;
                p.push([offset[0] + r * a.cos(), offset[1] + y, offset[2] + r * a.sin()]);
            }
        }
        let mut t = Vec::new();
        for i in 0..along - 1 {
            for k in 0..around {
                let (a, b) = ((i * around + k) as u32, (i * around + (k + 1) % around) as u32);
                let (c, d) = (a + around as u32, b + around as u32);
                t.push([a, b, d]);
                t.push([a, d, c]);
            }
        }
        (t, p)
    }

    /// Bends everything above height `y0` (relative to `base`) by `angle` about the x axis,
    /// blended over a short joint.
    fn bend(p: &[[f64; 3]], base: f64, y0: f64, angle: f64) -> Vec<f32> {
        p.iter()
            .flat_map(|v| {
                let h = v[1] - base - y0;
                let s = (h / 0.3).clamp(0.0, 1.0);
                let s = s * s * (3.0 - 2.0 * s);
                let (c, sn) = ((angle * s).cos(), (angle * s).sin());
                let (y, z) = (h, v[2]);
                let (y2, z2) = (c * y - sn * z, sn * y + c * z);
                [v[0] as f32, (base + y0 + y2) as f32, z2 as f32]
            })
            .collect()
    }

    fn subject(parts: &[(usize, usize, f64, f64, [f64; 3])]) -> (Topology, Vec<[f64; 3]>) {
        let (mut tris, mut pos) = (Vec::new(), Vec::new());
        for &(around, along, r, len, off) in parts {
            let (t, p) = tube(around, along, r, len, off);
            let base = pos.len() as u32;
            tris.extend(t.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
            pos.extend(p);
        }
        (Topology::new(pos.len(), tris, None).unwrap(), pos)
    }

    fn rel_err(a: &[f32], b: &[f32]) -> f64 {
        let num: f64 = a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum();
        let den: f64 = b.iter().map(|y| (*y as f64).powi(2)).sum();
        (num / den).sqrt()
    }

    fn poses(p: &[[f64; 3]], angles: &[f64]) -> Vec<Vec<f32>> {
        angles.iter().map(|&a| bend(p, 0.0, 1.0, a)).collect()
    }

    const ANGLES: [f64; 4] = [0.0, 0.8, 1.6, -0.7];

    #[test]
    fn reproduces_key_poses_exactly_between_different_topologies() {
        let (ts, ps) = subject(&[(8, 12, 0.2, 2.0, [0.0; 3])]);
        let (tt, pt) = subject(&[(11, 17, 0.35, 2.4, [0.0; 3])]);
        let (sk, tk) = (poses(&ps, &ANGLES), poses(&pt, &ANGLES));
        let opts = SdtOptions { triangles_per_patch: 20, ..SdtOptions::default() };
        let sdt = SemanticDeformationTransfer::with_options(&ts, &sk, &tt, &tk, &opts).unwrap();
        assert!(sdt.n_patches().0 > 3 && sdt.n_patches().1 > 3, "{:?}", sdt.n_patches());
        for k in 0..ANGLES.len() {
            let w = sdt.weights(&sk[k]).unwrap();
            for (i, wi) in w.iter().enumerate() {
                assert!((wi - if i == k { 1.0 } else { 0.0 }).abs() < 1e-6, "key {k}: weights {w:?}");
            }
            let out = sdt.transfer(&sk[k]).unwrap();
            let e = rel_err(&out, &tk[k]);
            assert!(e < 1e-5, "key {k}: relative error {e}");
        }
    }

    #[test]
    fn encoding_is_rigid_motion_invariant_and_in_between_poses_transfer() {
        let (ts, ps) = subject(&[(8, 12, 0.2, 2.0, [0.0; 3])]);
        let (tt, pt) = subject(&[(11, 17, 0.35, 2.4, [0.0; 3])]);
        let (sk, tk) = (poses(&ps, &ANGLES[..3]), poses(&pt, &ANGLES[..3]));
        let sdt = SemanticDeformationTransfer::new(&ts, &sk, &tt, &tk).unwrap();
        // A rigidly moved source key has the same weights.
        let r = exp_rotation(&Vector3::new(0.4, -2.0, 1.1));
        let moved: Vec<f32> = sk[1]
            .chunks(3)
            .flat_map(|v| {
                let q = r * Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64) + Vector3::new(5.0, -1.0, 2.0);
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect();
        let (w0, w1) = (sdt.weights(&sk[1]).unwrap(), sdt.weights(&moved).unwrap());
        for (a, b) in w0.iter().zip(&w1) {
            assert!((a - b).abs() < 1e-5, "{w0:?} vs {w1:?}");
        }
        // A bend between two keys lands between the target's keys: close to the target bent
        // by the same angle, and clearly better than either neighbouring key.
        let src = bend(&ps, 0.0, 1.0, 1.2);
        let want = bend(&pt, 0.0, 1.0, 1.2);
        let w = sdt.weights(&src).unwrap();
        assert!(w[1] > 0.2 && w[2] > 0.2 && (w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{w:?}");
        let out = sdt.transfer(&src).unwrap();
        let e = rel_err(&out, &want);
        assert!(e < 0.03, "in-between error {e}");
        assert!(e < 0.5 * rel_err(&tk[1], &want) && e < 0.5 * rel_err(&tk[2], &want), "{e}");
    }

    #[test]
    fn several_components_and_zero_area_triangles_reproduce_keys_without_nan() {
        // Source: one tube; target: a body tube and a separate limb tube beside it.
        let (ts, ps) = subject(&[(8, 12, 0.2, 2.0, [0.0; 3])]);
        let (tt, pt) = subject(&[(10, 14, 0.3, 2.0, [0.0; 3]), (6, 8, 0.1, 1.0, [0.6, 0.8, 0.0])]);
        let mut sk = poses(&ps, &ANGLES);
        let tk = poses(&pt, &ANGLES);
        // Collapse one triangle of source key 2 (two vertices on top of each other).
        let t = ts.triangles()[30];
        for c in 0..3 {
            sk[2][3 * t[1] as usize + c] = sk[2][3 * t[0] as usize + c];
        }
        let opts = SdtOptions { triangles_per_patch: 25, ..SdtOptions::default() };
        let sdt = SemanticDeformationTransfer::with_options(&ts, &sk, &tt, &tk, &opts).unwrap();
        assert_eq!(sdt.target.components.count, 2);
        for k in 0..ANGLES.len() {
            let out = sdt.transfer(&sk[k]).unwrap();
            assert!(out.iter().all(|x| x.is_finite()));
            let e = rel_err(&out, &tk[k]);
            assert!(e < 1e-5, "key {k}: relative error {e}");
        }
        // A target whose reference has a zero-area triangle: still finite, keys still exact
        // (the triangle has no weight in the Poisson system).
        let mut tk2 = tk.clone();
        let t = tt.triangles()[7];
        for key in &mut tk2 {
            for c in 0..3 {
                key[3 * t[2] as usize + c] = key[3 * t[0] as usize + c];
            }
        }
        let sdt = SemanticDeformationTransfer::with_options(&ts, &sk, &tt, &tk2, &opts).unwrap();
        for k in 0..ANGLES.len() {
            let out = sdt.transfer(&sk[k]).unwrap();
            assert!(out.iter().all(|x| x.is_finite()));
            let e = rel_err(&out, &tk2[k]);
            assert!(e < 1e-4, "key {k} with a degenerate reference triangle: {e}");
        }
    }

    #[test]
    fn same_output_whatever_the_thread_count() {
        let (ts, ps) = subject(&[(9, 14, 0.2, 2.0, [0.0; 3]), (5, 6, 0.1, 0.8, [0.5, 0.5, 0.0])]);
        let (tt, pt) = subject(&[(12, 16, 0.3, 2.2, [0.0; 3])]);
        let (sk, tk) = (poses(&ps, &ANGLES), poses(&pt, &ANGLES));
        let run = || {
            let opts = SdtOptions { triangles_per_patch: 15, ..SdtOptions::default() };
            let sdt = SemanticDeformationTransfer::with_options(&ts, &sk, &tt, &tk, &opts).unwrap();
            sdt.transfer(&bend(&ps, 0.0, 1.0, 0.3)).unwrap()
        };
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(run);
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(run);
        assert!(one.iter().zip(&three).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn patches_grow_to_fit_the_bound_and_isolated_vertices_keep_their_place() {
        let (ts, ps) = subject(&[(8, 12, 0.2, 2.0, [0.0; 3])]);
        let (tt, mut pt) = subject(&[(11, 17, 0.35, 2.4, [0.0; 3])]);
        // One extra vertex in no triangle.
        pt.push([0.9, 1.5, 0.2]);
        let tt = Topology::new(pt.len(), tt.triangles().to_vec(), None).unwrap();
        let (sk, tk) = (poses(&ps, &ANGLES), poses(&pt, &ANGLES));
        let opts = SdtOptions { triangles_per_patch: 1, max_patches: 8 };
        let sdt = SemanticDeformationTransfer::with_options(&ts, &sk, &tt, &tk, &opts).unwrap();
        let (a, b) = sdt.n_patches();
        assert!((2..=4).contains(&a) && (2..=4).contains(&b), "{a} {b}");
        for k in 0..ANGLES.len() {
            let e = rel_err(&sdt.transfer(&sk[k]).unwrap(), &tk[k]);
            assert!(e < 1e-5, "key {k}: {e}");
        }
        // Too many separate pieces for the bound: refused by name.
        let many: Vec<(usize, usize, f64, f64, [f64; 3])> =
            (0..5).map(|k| (4, 3, 0.1, 0.5, [k as f64, 0.0, 0.0])).collect();
        let (tm, pm) = subject(&many);
        let keys = vec![pm.iter().flat_map(|v| v.map(|x| x as f32)).collect::<Vec<f32>>()];
        let opts = SdtOptions { triangles_per_patch: 1, max_patches: 4 };
        let e = SemanticDeformationTransfer::with_options(&tm, &keys, &tt, &tk[..1], &opts).err().unwrap().to_string();
        assert!(e.contains("source mesh needs 5 patches (5 separate pieces): expected at most 4"), "{e}");
    }

    #[test]
    fn duplicate_keys_share_weight_and_bad_input_is_refused_by_name() {
        let (ts, ps) = subject(&[(6, 6, 0.2, 2.0, [0.0; 3])]);
        let (tt, pt) = subject(&[(7, 8, 0.3, 2.0, [0.0; 3])]);
        let sk = poses(&ps, &[0.0, 1.0, 1.0]);
        let tk = poses(&pt, &[0.0, 1.0, 1.0]);
        let sdt = SemanticDeformationTransfer::new(&ts, &sk, &tt, &tk).unwrap();
        let w = sdt.weights(&sk[1]).unwrap();
        assert!((w[1] - 0.5).abs() < 1e-6 && (w[2] - 0.5).abs() < 1e-6, "{w:?}");
        assert!(rel_err(&sdt.transfer(&sk[1]).unwrap(), &tk[1]) < 1e-5);

        let msg = |r: Result<SemanticDeformationTransfer>| r.err().expect("an error").to_string();
        let m = msg(SemanticDeformationTransfer::new(&ts, &sk, &tt, &tk[..2]));
        assert!(m.contains("3 source key poses and 2 target key poses"), "{m}");
        let m = msg(SemanticDeformationTransfer::new(&ts, &[], &tt, &[]));
        assert!(m.contains("expected at least one"), "{m}");
        let mut bad = sk.clone();
        bad[1].pop();
        let m = msg(SemanticDeformationTransfer::new(&ts, &bad, &tt, &tk));
        assert!(m.contains("source key pose 1 has 107 coordinates: expected 3 x 36 = 108"), "{m}");
        let mut nan = tk.clone();
        nan[2][10] = f32::NAN;
        let m = msg(SemanticDeformationTransfer::new(&ts, &sk, &tt, &nan));
        assert!(m.contains("target key pose 2 has a non-finite coordinate at vertex 3"), "{m}");
        let e = sdt.transfer(&sk[0][..9]).unwrap_err().to_string();
        assert!(e.contains("source pose has 9 coordinates"), "{e}");
        let e = sdt.reconstruct(&[1.0]).unwrap_err().to_string();
        assert!(e.contains("1 weights: expected one per key pose (3)"), "{e}");
    }
}

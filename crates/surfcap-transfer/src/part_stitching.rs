//! Body part stitching (thesis 5.6.2, Fig. 5.6; CVPR 2017 sec. 6.2): predicted parts, each in
//! the target's aligned body frame, merged into one seamless template mesh.
//!
//! Top-down over the part tree, each child is rigidly aligned to its already placed parent on
//! their overlap vertices (Procrustes), then a closed curve is chosen inside the overlap band
//! that has the least deformation cost between its two instantiations (the parent's and the
//! aligned child's geometry), following Huang et al. 2007b (optimal boundaries for Poisson mesh
//! merging) with a Dijkstra approximation. Triangles on the parent's side of the curve take the
//! parent's geometry, the others the child's, and one Poisson reconstruction over the whole
//! template (thesis eq. 2.48) from the owning parts' per-triangle gradients, measured with the
//! template's rest operator, makes the mesh seamless.
//!
//! Choices where the thesis is vague:
//!
//! - **Merge.** The thesis uses the curve as the Dirichlet boundary of Yu et al. 2004's Poisson
//!   merging, which pins the curve to one part and re-solves the other. We solve once over the
//!   whole template instead, each triangle's target gradient taken from the part owning it
//!   (least squares, one translation per connected component): the curve is where the target
//!   field switches from parent to child, so the merge is seamless where the curve is cheap,
//!   as in Yu et al.; the residual mismatch spreads over both sides rather than only the
//!   child's; every child and every component is merged in the same solve; and the rest
//!   pose's factorisation serves every frame. Parts cut from one true frame give back that
//!   frame exactly (to f32 rounding), since their gradients are then consistent.
//! - **Aligned to the parent, when asked.** The thesis aligns each child "to the root part";
//!   with a deeper tree we align each child to its parent once the parent is placed, which is
//!   the same for the thesis's five parts (every child hangs from the torso). surfcap's parts
//!   are predicted in one body frame, so the alignment is off by default
//!   ([`Stitcher::aligning_children`] says why, with the measurements).
//! - **Cost of a curve.** A curve is a closed loop of template vertices; on each of its edges
//!   (u, v) the two sides of the Poisson merge disagree by the change of the edge vector between
//!   the instantiations, |(x_c(u) - x_c(v)) - (x_p(u) - x_p(v))|, which is what the gradient
//!   mismatch the Poisson solve must absorb is made of (a constant offset between the two
//!   copies costs nothing: the merge is translation-free). The loop's cost is the sum of that
//!   over its edges (the total variation of x_c - x_p along the curve, the mesh analogue of
//!   Jia et al. 2006's boundary energy) plus 1e-3 of its rest length, which makes the loop the
//!   shortest one when the two copies agree (ground truth) and breaks ties.
//! - **Closed curve by Dijkstra.** A closed curve around a cylinder is not a shortest path
//!   between two points. As Jia et al. 2006 do for image bands, we cut the band open along a
//!   fixed seam, the shortest path (rest lengths) from the parent-side boundary loop to the
//!   child-side one, duplicating the seam's vertices into a left and a right copy (each band
//!   triangle around a seam vertex keeps the copy of its side). For each seam vertex s the
//!   shortest path from s-left to s-right in the cut band is the cheapest closed curve through
//!   s that crosses the seam once; the cheapest over all seam vertices is the curve used. It
//!   is exact among curves crossing the seam once and an approximation otherwise (a curve may
//!   touch the seam again from one side, it may not wind back across it).
//! - **Which side is which.** Band triangles reachable from the parent-side boundary loop
//!   without crossing a curve edge are the parent's, the rest the child's (a curve that runs
//!   along the parent's boundary gives the whole band to the child, one along the child's
//!   boundary gives it to the parent).
//! - **When the band is not a cylinder** (overlap in several pieces, other than two boundary
//!   loops, a non-manifold vertex, a boundary loop touching both sides), there is no closed
//!   curve to search: the band is split half-way, each band triangle going to the side whose
//!   boundary is nearer in rest geodesic distance (Dijkstra on the band's edges), and the report
//!   says why ([`Cut::Midway`]). A band with no parent-side boundary goes wholly to the child,
//!   one with no child-side boundary wholly to the parent.
//! - **Alignment.** Procrustes without scale, parent ≈ R child + t on the overlap. An overlap
//!   of one or two vertices fixes no rotation: the child is only translated.
//! - **Parts without overlap** (KayKit's separate body-part meshes) are neither aligned nor
//!   stitched: they keep their predicted placement.
//! - **Ownership.** A triangle belongs to the first part in top-down order that holds its three
//!   vertices, then each child's band hands the triangles on its side of the curve to the child
//!   (processed top-down, so the deepest decision stands). A triangle no part holds whole (its
//!   vertices in different parts without overlap) takes its gradient from the vertex-wise
//!   assembly below.
//! - **Translations.** The merge fixes one translation per connected component of the template:
//!   each component's vertex mean is that of the vertex-wise assembly, where each vertex takes
//!   its position from the part owning most of its triangles (ties to the part higher in the
//!   tree).

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::procrustes;
use surfcap_geometry::poisson_reconstruction::PoissonSolver;
use surfcap_mesh::Topology;

use crate::body_parts::BodyParts;
use crate::error::{Error, Result, check_positions};

/// Weight of a curve's rest length in its cost, against its mismatch (both lengths).
const LENGTH_WEIGHT: f64 = 1e-3;
const NONE: u32 = u32::MAX;

/// How one part was put in place.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartStitch {
    pub name: String,
    pub parent: Option<String>,
    /// Vertices shared with the parent.
    pub overlap_vertices: usize,
    /// RMS distance between the parent's and the aligned child's overlap vertices (0 for the
    /// root and parts without overlap): how well the two predictions agree there.
    pub overlap_rms: f64,
    pub cut: Cut,
}

/// Where a child was cut from its parent.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Cut {
    /// The root: nothing to cut.
    Root,
    /// No vertex shared with the parent: kept where it was predicted.
    NoOverlap,
    /// The cheapest closed curve found in a cylinder-like band.
    Loop {
        /// The curve's template vertices in order (closed: the last joins the first).
        vertices: Vec<u32>,
        /// Sum over the curve's edges of the edge-vector change between the parent's and the
        /// child's copy (the subject's length unit).
        mismatch: f64,
        band_triangles: usize,
        /// Band triangles given to the child.
        child_triangles: usize,
    },
    /// The band is not a cylinder: split half-way between its parent and child boundaries.
    Midway { reason: String, band_triangles: usize, child_triangles: usize },
}

/// How every part was put in place, in the parts' order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StitchReport {
    pub parts: Vec<PartStitch>,
}

/// Relative edge-length change |l / l_ref - 1| of the template's edges, split by region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EdgeDistortion {
    /// Over edges with an end in an overlap (a vertex held by two or more parts).
    pub boundary_max: f64,
    pub boundary_mean: f64,
    /// Over edges whose two ends are each held by one part only.
    pub inside_max: f64,
    pub inside_mean: f64,
    pub boundary_edges: usize,
    pub inside_edges: usize,
}

/// Checks every part's vertices index the template (parts built without
/// [`BodyParts::validate`], e.g. children without overlap, must not index out of it).
fn check_vertex_range(parts: &BodyParts) -> Result<()> {
    for p in &parts.parts {
        if let Some(&v) = p.vertices.iter().find(|&&v| v as usize >= parts.n_vertices) {
            return Err(Error::Parts(format!(
                "part \"{}\" has vertex {v}: expected 0 to {}",
                p.name,
                parts.n_vertices.saturating_sub(1)
            )));
        }
    }
    Ok(())
}

fn check_part_positions(parts: &BodyParts, part_positions: &[Vec<f32>]) -> Result<()> {
    check_vertex_range(parts)?;
    if part_positions.len() != parts.len() {
        return Err(Error::Invalid(format!(
            "{} part meshes: expected {} (one per body part: {})",
            part_positions.len(),
            parts.len(),
            parts.names().join(", ")
        )));
    }
    for (p, pos) in parts.parts.iter().zip(part_positions) {
        check_positions(pos, p.vertices.len(), &format!("part \"{}\"", p.name))?;
    }
    Ok(())
}

#[inline]
fn at(p: &[f32], k: usize) -> Vector3<f64> {
    Vector3::new(p[3 * k] as f64, p[3 * k + 1] as f64, p[3 * k + 2] as f64)
}

/// Per part, template vertex -> index in the part (NONE when not in it).
fn local_maps(parts: &BodyParts) -> Vec<Vec<u32>> {
    parts
        .parts
        .iter()
        .map(|p| {
            let mut m = vec![NONE; parts.n_vertices];
            for (i, &v) in p.vertices.iter().enumerate() {
                m[v as usize] = i as u32;
            }
            m
        })
        .collect()
}

/// Each part's RMS mismatch with its parent over their overlap, as predicted (0 for the root
/// and for parts without overlap).
fn overlap_rms(parts: &BodyParts, local: &[Vec<u32>], part_positions: &[Vec<f32>]) -> Vec<f64> {
    (0..parts.len())
        .map(|k| {
            let Some(p) = parts.parent(k) else { return 0.0 };
            let overlap = parts.overlap(k);
            if overlap.is_empty() {
                return 0.0;
            }
            let s: f64 = overlap
                .iter()
                .map(|&v| {
                    let (i, j) = (local[k][v as usize] as usize, local[p][v as usize] as usize);
                    (at(&part_positions[k], i) - at(&part_positions[p], j)).norm_squared()
                })
                .sum();
            (s / overlap.len() as f64).sqrt()
        })
        .collect()
}

/// The parts moved top-down so each child fits its placed parent on their overlap (rigid
/// Procrustes; translation only for an overlap of fewer than 3 vertices; untouched without
/// overlap). Returns the placed parts and each part's overlap RMS after alignment.
fn place_parts(parts: &BodyParts, local: &[Vec<u32>], part_positions: &[Vec<f32>]) -> (Vec<Vec<f32>>, Vec<f64>) {
    let mut placed: Vec<Vec<f32>> = part_positions.to_vec();
    let mut rms = vec![0.0; parts.len()];
    for k in parts.top_down() {
        let Some(p) = parts.parent(k) else { continue };
        let overlap = parts.overlap(k);
        if overlap.is_empty() {
            continue;
        }
        let gather = |pos: &[f32], map: &[u32]| -> Vec<f32> {
            overlap
                .iter()
                .flat_map(|&v| {
                    let i = map[v as usize] as usize;
                    [pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]]
                })
                .collect()
        };
        let target = gather(&placed[p], &local[p]);
        let source = gather(&placed[k], &local[k]);
        let (r, t) = if overlap.len() >= 3 {
            let (r, t, _) = procrustes(&target, &source, None, false);
            (r, t)
        } else {
            let n = overlap.len() as f64;
            let mean = |x: &[f32]| (0..overlap.len()).map(|i| at(x, i)).sum::<Vector3<f64>>() / n;
            (Matrix3::identity(), mean(&target) - mean(&source))
        };
        for q in placed[k].chunks_exact_mut(3) {
            let v = r * Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64) + t;
            q.copy_from_slice(&[v.x as f32, v.y as f32, v.z as f32]);
        }
        let moved = gather(&placed[k], &local[k]);
        let s: f64 = (0..overlap.len()).map(|i| (at(&moved, i) - at(&target, i)).norm_squared()).sum();
        rms[k] = (s / overlap.len() as f64).sqrt();
    }
    (placed, rms)
}

/// Dijkstra queue entry: smallest cost first, ties to the smallest node.
#[derive(Clone, Copy, PartialEq)]
struct Entry {
    cost: f64,
    node: u32,
}
impl Eq for Entry {}
impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        o.cost.total_cmp(&self.cost).then(o.node.cmp(&self.node))
    }
}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// An undirected graph in compressed rows; every neighbour entry carries an edge index.
struct Graph {
    start: Vec<usize>,
    /// (neighbour, edge index).
    adj: Vec<(u32, u32)>,
}

impl Graph {
    fn new(n: usize, edges: &[(u32, u32, u32)]) -> Graph {
        let mut deg = vec![0usize; n + 1];
        for &(a, b, _) in edges {
            deg[a as usize + 1] += 1;
            deg[b as usize + 1] += 1;
        }
        for i in 0..n {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut adj = vec![(0, 0); deg[n]];
        for &(a, b, e) in edges {
            adj[fill[a as usize]] = (b, e);
            fill[a as usize] += 1;
            adj[fill[b as usize]] = (a, e);
            fill[b as usize] += 1;
        }
        Graph { start: deg, adj }
    }

    fn n(&self) -> usize {
        self.start.len() - 1
    }

    fn neighbours(&self, v: usize) -> &[(u32, u32)] {
        &self.adj[self.start[v]..self.start[v + 1]]
    }

    /// Shortest distances from `sources` with edge costs `cost[edge]`; stops once `stop`
    /// returns true for a settled node and returns it. Predecessors as (node, edge).
    fn dijkstra(
        &self,
        sources: &[u32],
        cost: &[f64],
        stop: impl Fn(u32) -> bool,
    ) -> (Vec<f64>, Vec<(u32, u32)>, Option<u32>) {
        let mut dist = vec![f64::INFINITY; self.n()];
        let mut pred = vec![(NONE, NONE); self.n()];
        let mut done = vec![false; self.n()];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            dist[s as usize] = 0.0;
            heap.push(Entry { cost: 0.0, node: s });
        }
        while let Some(Entry { cost: d, node }) = heap.pop() {
            let u = node as usize;
            if done[u] {
                continue;
            }
            done[u] = true;
            if stop(node) {
                return (dist, pred, Some(node));
            }
            for &(w, e) in self.neighbours(u) {
                let nd = d + cost[e as usize];
                if nd < dist[w as usize] {
                    dist[w as usize] = nd;
                    pred[w as usize] = (node, e);
                    heap.push(Entry { cost: nd, node: w });
                }
            }
        }
        (dist, pred, None)
    }
}

/// Union-find with path halving.
fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let g = parent[parent[x as usize] as usize];
        parent[x as usize] = g;
        x = g;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// The overlap band of a child and its parent, and how it is cut.
struct Band {
    child: usize,
    parent: usize,
    /// Band triangles (template indices): the triangles whose three vertices are in the overlap.
    triangles: Vec<u32>,
    /// Band edges as template vertex pairs (a < b), sorted.
    edges: Vec<[u32; 2]>,
    rest_len: Vec<f64>,
    /// Per band triangle, its three band edges.
    tri_edges: Vec<[u32; 3]>,
    /// Per band edge, its band triangles (one or two; NONE for the missing second).
    edge_tris: Vec<[u32; 2]>,
    kind: BandKind,
}

enum BandKind {
    Cylinder(CutBand),
    /// Per band triangle, whether it goes to the child.
    Midway {
        reason: String,
        child_side: Vec<bool>,
    },
}

/// A cylinder band cut open along a seam from its parent-side to its child-side boundary.
struct CutBand {
    /// Graph over the cut band's nodes (band vertices, plus a right copy of each seam vertex);
    /// edge indices are band edges.
    graph: Graph,
    /// Template vertex of each node.
    node_vertex: Vec<u32>,
    /// Per seam vertex, its (left, right) nodes.
    seam: Vec<(u32, u32)>,
    /// Band edges on the parent-side boundary loop.
    parent_boundary: Vec<bool>,
}

impl Band {
    /// Per band triangle, whether it goes to the child, for the curve made of `loop_edges`
    /// (a flag per band edge): flood from the parent-side boundary without crossing the curve.
    fn child_side(&self, cut: &CutBand, loop_edges: &[bool]) -> Vec<bool> {
        let mut parent_side = vec![false; self.triangles.len()];
        let mut stack: Vec<u32> = Vec::new();
        for (t, es) in self.tri_edges.iter().enumerate() {
            if es.iter().any(|&e| cut.parent_boundary[e as usize] && !loop_edges[e as usize]) {
                parent_side[t] = true;
                stack.push(t as u32);
            }
        }
        while let Some(t) = stack.pop() {
            for &e in &self.tri_edges[t as usize] {
                if loop_edges[e as usize] {
                    continue;
                }
                for &o in &self.edge_tris[e as usize] {
                    if o != NONE && !parent_side[o as usize] {
                        parent_side[o as usize] = true;
                        stack.push(o);
                    }
                }
            }
        }
        parent_side.iter().map(|p| !p).collect()
    }
}

/// Per-subject precomputation of stitching: the whole template's Poisson factorisation on its
/// rest pose, each part's vertex map, the base triangle ownership and every overlap band with
/// its cut structure. [`Stitcher::stitch`] then does one frame.
pub struct Stitcher {
    topology: Topology,
    parts: BodyParts,
    solver: PoissonSolver,
    order: Vec<usize>,
    /// Position of each part in `order` (higher in the tree = smaller).
    rank: Vec<usize>,
    local: Vec<Vec<u32>>,
    /// Per triangle, the first part in top-down order holding its three vertices.
    base_owner: Vec<u32>,
    /// Per vertex, its triangles (compressed rows).
    vt_start: Vec<usize>,
    vt: Vec<u32>,
    bands: Vec<Band>,
    /// Per part, the number of vertices it shares with its parent.
    overlap_sizes: Vec<usize>,
    /// Rigidly align each child onto its parent over their overlap before cutting (the
    /// thesis's step; off by default, see [`Stitcher::aligning_children`]).
    align: bool,
}

impl Stitcher {
    /// Everything that depends on the subject only: checks the parts fit `topology`,
    /// factorises the Poisson system on the rest pose `rest` (`[n][3]`), analyses each overlap.
    pub fn new(topology: &Topology, rest: &[f32], parts: &BodyParts) -> Result<Stitcher> {
        let n = topology.n_vertices();
        if parts.n_vertices != n {
            return Err(Error::Parts(format!(
                "made for a template of {} vertices, but the topology has {n}",
                parts.n_vertices
            )));
        }
        check_positions(rest, n, "the template's rest pose")?;
        check_vertex_range(parts)?;
        let solver = PoissonSolver::new(topology, rest)?;
        let order = parts.top_down();
        if order.len() != parts.len() {
            return Err(Error::Parts("some parts are not reachable from the root: expected one tree".into()));
        }
        let mut rank = vec![0; parts.len()];
        for (i, &k) in order.iter().enumerate() {
            rank[k] = i;
        }
        let local = local_maps(parts);
        let tris = topology.triangles();
        let base_owner: Vec<u32> = tris
            .iter()
            .map(|t| {
                order.iter().find(|&&k| t.iter().all(|&v| local[k][v as usize] != NONE)).map_or(NONE, |&k| k as u32)
            })
            .collect();
        let (vt_start, vt) = vertex_triangles(n, tris);
        // Template edge -> its triangles, for the sides of a band's boundary loops.
        let mut edge_map: HashMap<[u32; 2], Vec<u32>> = HashMap::new();
        for (m, t) in tris.iter().enumerate() {
            for j in 0..3 {
                let (a, b) = (t[j], t[(j + 1) % 3]);
                edge_map.entry([a.min(b), a.max(b)]).or_default().push(m as u32);
            }
        }
        let ctx = Context { tris, rest, local: &local, vt_start: &vt_start, vt: &vt, edge_map };
        let bands: Vec<Band> = order
            .iter()
            .filter_map(|&k| {
                let p = parts.parent(k)?;
                (!parts.overlap(k).is_empty()).then(|| ctx.build_band(k, p))
            })
            .collect();
        let overlap_sizes = (0..parts.len()).map(|k| parts.overlap(k).len()).collect();
        Ok(Stitcher {
            topology: topology.clone(),
            parts: parts.clone(),
            solver,
            order,
            rank,
            local,
            base_owner,
            vt_start,
            vt,
            bands,
            overlap_sizes,
            align: false,
        })
    }

    /// Whether each child is first rigidly aligned onto its placed parent over their overlap
    /// (thesis 5.6.2: "after rigidly aligning the child parts to the root part with respect to
    /// the overlap region"). Off by default: the thesis aligns because its parts are each
    /// rigidly aligned on their own before PCA; surfcap predicts every part in the target's
    /// body frame (see `pose_representation`), so the two copies of an overlap already agree
    /// up to their prediction errors, and a rigid fit between two noisy copies of a small band
    /// moves the whole limb by the difference of those errors. Measured on motions absent from
    /// training (GP-NN on every true pair), RMS error against the truth, with / without the
    /// alignment: KayKit barbarian Cheer (a 20-vertex overlap at one shoulder) arm 0.571 /
    /// 0.109 m and torso 0.095 / 0.047 m (averaging the overlaps instead: 0.144 and 0.068);
    /// mannequin dance arms 0.122 / 0.121 m and 0.141 / 0.142 m, legs 0.062 / 0.058 m and
    /// 0.047 / 0.042 m.
    pub fn aligning_children(mut self, align: bool) -> Stitcher {
        self.align = align;
        self
    }

    pub fn parts(&self) -> &BodyParts {
        &self.parts
    }

    /// One frame: `part_positions[k]` holds part k's vertices (`[n_k][3]`, in the order of
    /// `parts.parts[k].vertices`). Returns the merged template positions and how each part was
    /// placed.
    pub fn stitch(&self, part_positions: &[Vec<f32>]) -> Result<(Vec<f32>, StitchReport)> {
        check_part_positions(&self.parts, part_positions)?;
        let (placed, rms) = if self.align {
            place_parts(&self.parts, &self.local, part_positions)
        } else {
            (part_positions.to_vec(), overlap_rms(&self.parts, &self.local, part_positions))
        };
        let mut owner = self.base_owner.clone();
        let mut cuts: Vec<Cut> = (0..self.parts.len())
            .map(|k| if self.parts.parent(k).is_none() { Cut::Root } else { Cut::NoOverlap })
            .collect();
        for band in &self.bands {
            let (child_side, cut) = self.cut_band(band, &placed);
            for (&t, &c) in band.triangles.iter().zip(&child_side) {
                if c {
                    owner[t as usize] = band.child as u32;
                }
            }
            cuts[band.child] = cut;
        }
        let n = self.topology.n_vertices();
        // Vertex-wise assembly: each vertex from the part owning most of its triangles.
        let mut assembled = vec![0.0f32; 3 * n];
        let mut count = vec![0u32; self.parts.len()];
        for v in 0..n {
            count.iter_mut().for_each(|c| *c = 0);
            for &m in &self.vt[self.vt_start[v]..self.vt_start[v + 1]] {
                let o = owner[m as usize];
                if o != NONE {
                    count[o as usize] += 1;
                }
            }
            let best = (0..self.parts.len())
                .filter(|&k| count[k] > 0)
                .max_by(|&a, &b| count[a].cmp(&count[b]).then(self.rank[b].cmp(&self.rank[a])))
                .or_else(|| self.order.iter().copied().find(|&k| self.local[k][v] != NONE));
            let Some(k) = best else {
                return Err(Error::Parts(format!(
                    "template vertex {v} is in no part: every vertex must belong to a part"
                )));
            };
            let i = self.local[k][v] as usize;
            assembled[3 * v..3 * v + 3].copy_from_slice(&placed[k][3 * i..3 * i + 3]);
        }
        // Target gradients from each triangle's owner (eq. 2.27 with the rest operator's basis).
        let op = self.solver.operator();
        let targets: Vec<Matrix3<f64>> = self
            .topology
            .triangles()
            .iter()
            .enumerate()
            .map(|(m, t)| {
                let o = owner[m];
                let pos = |v: u32| -> Vector3<f64> {
                    if o == NONE {
                        at(&assembled, v as usize)
                    } else {
                        at(&placed[o as usize], self.local[o as usize][v as usize] as usize)
                    }
                };
                (0..3).map(|j| op.basis[m][j] * pos(t[j]).transpose()).sum()
            })
            .collect();
        let centroids = self.solver.component_centroids(&assembled);
        let out = self.solver.solve(&targets, &centroids);
        if out.iter().any(|x| !x.is_finite()) {
            return Err(Error::Invalid("stitching produced a non-finite position".into()));
        }
        let report = StitchReport {
            parts: self
                .parts
                .parts
                .iter()
                .enumerate()
                .map(|(k, p)| PartStitch {
                    name: p.name.clone(),
                    parent: p.parent.clone(),
                    overlap_vertices: self.overlap_sizes[k],
                    overlap_rms: rms[k],
                    cut: cuts[k].clone(),
                })
                .collect(),
        };
        Ok((out, report))
    }

    /// The child side of a band for this frame's placed parts, and the cut made.
    fn cut_band(&self, band: &Band, placed: &[Vec<f32>]) -> (Vec<bool>, Cut) {
        let cut = match &band.kind {
            BandKind::Midway { reason, child_side } => {
                let child_triangles = child_side.iter().filter(|&&c| c).count();
                let c = Cut::Midway { reason: reason.clone(), band_triangles: band.triangles.len(), child_triangles };
                return (child_side.clone(), c);
            }
            BandKind::Cylinder(cut) => cut,
        };
        let (lp, lc) = (&self.local[band.parent], &self.local[band.child]);
        let (xp, xc) = (&placed[band.parent], &placed[band.child]);
        let d = |v: u32| at(xc, lc[v as usize] as usize) - at(xp, lp[v as usize] as usize);
        let mismatch: Vec<f64> = band.edges.iter().map(|&[a, b]| (d(a) - d(b)).norm()).collect();
        let cost: Vec<f64> = mismatch.iter().zip(&band.rest_len).map(|(m, l)| m + LENGTH_WEIGHT * l).collect();
        // The cheapest closed curve through each seam vertex, crossing the seam there.
        let best = cut
            .seam
            .par_iter()
            .enumerate()
            .map(|(i, &(left, right))| {
                let (dist, _, _) = cut.graph.dijkstra(&[left], &cost, |x| x == right);
                (dist[right as usize], i)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let (left, right) = cut.seam[best.map_or(0, |b| b.1)];
        let (dist, pred, _) = cut.graph.dijkstra(&[left], &cost, |x| x == right);
        let mut loop_edges = vec![false; band.edges.len()];
        let mut vertices = Vec::new();
        let mut total = 0.0;
        if dist[right as usize].is_finite() {
            let mut x = right;
            while x != left {
                let (p, e) = pred[x as usize];
                loop_edges[e as usize] = true;
                total += mismatch[e as usize];
                x = p;
                vertices.push(cut.node_vertex[x as usize]);
            }
            vertices.reverse();
        }
        let child_side = band.child_side(cut, &loop_edges);
        let child_triangles = child_side.iter().filter(|&&c| c).count();
        (child_side, Cut::Loop { vertices, mismatch: total, band_triangles: band.triangles.len(), child_triangles })
    }
}

/// Stitches one frame's parts into the template (see [`Stitcher`]; build one once per subject
/// when stitching many frames).
pub fn stitch(
    topology: &Topology,
    template_rest: &[f32],
    parts: &BodyParts,
    part_positions: &[Vec<f32>],
) -> Result<(Vec<f32>, StitchReport)> {
    Stitcher::new(topology, template_rest, parts)?.stitch(part_positions)
}

/// The baseline without curve or Poisson merge: every template vertex is the mean of its
/// copies in the parts holding it, after the same top-down rigid alignment of each child onto
/// its parent when `align` (the parts as predicted otherwise).
pub fn average_overlaps(parts: &BodyParts, part_positions: &[Vec<f32>], align: bool) -> Result<Vec<f32>> {
    check_part_positions(parts, part_positions)?;
    let local = local_maps(parts);
    let placed = if align { place_parts(parts, &local, part_positions).0 } else { part_positions.to_vec() };
    let mut sum = vec![0.0f64; 3 * parts.n_vertices];
    let mut count = vec![0u32; parts.n_vertices];
    for (p, pos) in parts.parts.iter().zip(&placed) {
        for (i, &v) in p.vertices.iter().enumerate() {
            for d in 0..3 {
                sum[3 * v as usize + d] += pos[3 * i + d] as f64;
            }
            count[v as usize] += 1;
        }
    }
    if let Some(v) = count.iter().position(|&c| c == 0) {
        return Err(Error::Parts(format!("template vertex {v} is in no part: every vertex must belong to a part")));
    }
    Ok(sum.iter().enumerate().map(|(i, s)| (s / count[i / 3] as f64) as f32).collect())
}

/// Relative edge-length change |l / l_ref - 1| between `positions` and `reference` (both
/// template poses `[n][3]`), over edges touching an overlap (a vertex held by two or more
/// parts: where seams can show) and edges inside parts. Edges shorter than 1% of the median
/// reference edge (vertices quantised together) are left out: their ratio is rounding noise.
pub fn edge_distortion_by_region(
    topology: &Topology,
    parts: &BodyParts,
    positions: &[f32],
    reference: &[f32],
) -> Result<EdgeDistortion> {
    let n = topology.n_vertices();
    if parts.n_vertices != n {
        return Err(Error::Parts(format!(
            "made for a template of {} vertices, but the topology has {n}",
            parts.n_vertices
        )));
    }
    check_vertex_range(parts)?;
    check_positions(positions, n, "the stitched mesh")?;
    check_positions(reference, n, "the reference mesh")?;
    let multiplicity = parts.multiplicity();
    let mut edges: Vec<[u32; 2]> = topology
        .triangles()
        .iter()
        .flat_map(|t| (0..3).map(move |j| [t[j].min(t[(j + 1) % 3]), t[j].max(t[(j + 1) % 3])]))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut d = EdgeDistortion {
        boundary_max: 0.0,
        boundary_mean: 0.0,
        inside_max: 0.0,
        inside_mean: 0.0,
        boundary_edges: 0,
        inside_edges: 0,
    };
    // Edges far shorter than the mesh's typical edge (vertices quantised together in game
    // meshes, 1e-6 of an edge) would turn a rounding into a 3,000% change: below 1% of the
    // median reference edge they are left out of both regions.
    let mut lengths: Vec<f64> =
        edges.iter().map(|&[a, b]| (at(reference, a as usize) - at(reference, b as usize)).norm()).collect();
    lengths.sort_unstable_by(f64::total_cmp);
    let floor = 0.01 * lengths.get(lengths.len() / 2).copied().unwrap_or(0.0);
    for [a, b] in edges {
        let (a, b) = (a as usize, b as usize);
        let l_ref = (at(reference, a) - at(reference, b)).norm();
        if l_ref <= floor || l_ref <= 0.0 {
            continue;
        }
        let r = ((at(positions, a) - at(positions, b)).norm() / l_ref - 1.0).abs();
        if multiplicity[a] > 1 || multiplicity[b] > 1 {
            d.boundary_max = d.boundary_max.max(r);
            d.boundary_mean += r;
            d.boundary_edges += 1;
        } else {
            d.inside_max = d.inside_max.max(r);
            d.inside_mean += r;
            d.inside_edges += 1;
        }
    }
    d.boundary_mean /= d.boundary_edges.max(1) as f64;
    d.inside_mean /= d.inside_edges.max(1) as f64;
    Ok(d)
}

/// Per vertex, its triangles in compressed rows (start offsets, triangle indices).
fn vertex_triangles(n: usize, tris: &[[u32; 3]]) -> (Vec<usize>, Vec<u32>) {
    let mut start = vec![0usize; n + 1];
    for t in tris {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut vt = vec![0u32; start[n]];
    for (m, t) in tris.iter().enumerate() {
        for &v in t {
            vt[fill[v as usize]] = m as u32;
            fill[v as usize] += 1;
        }
    }
    (start, vt)
}

/// What building the bands reads from the template.
struct Context<'a> {
    tris: &'a [[u32; 3]],
    rest: &'a [f32],
    local: &'a [Vec<u32>],
    vt_start: &'a [usize],
    vt: &'a [u32],
    edge_map: HashMap<[u32; 2], Vec<u32>>,
}

/// A band's triangles, edges and graph, as [`Context::cylinder`] reads them.
struct BandMesh {
    /// Band vertices (template ids), sorted; the graph's node numbering.
    vertices: Vec<u32>,
    graph: Graph,
    /// Per band edge: on the boundary, and whether the template triangle across it belongs to
    /// the parent only / the child only.
    boundary_side: Vec<Option<(bool, bool)>>,
    manifold: bool,
}

impl Context<'_> {
    fn vertex_triangles(&self, v: u32) -> &[u32] {
        &self.vt[self.vt_start[v as usize]..self.vt_start[v as usize + 1]]
    }

    fn holds(&self, part: usize, t: &[u32; 3]) -> bool {
        t.iter().all(|&v| self.local[part][v as usize] != NONE)
    }

    /// The band of child `k` and parent `p`: its triangles and edges, and either its cut
    /// structure (a cylinder) or a half-way split with the reason it is not one.
    fn build_band(&self, k: usize, p: usize) -> Band {
        let tris = self.tris;
        let in_both = |v: u32| self.local[k][v as usize] != NONE && self.local[p][v as usize] != NONE;
        let triangles: Vec<u32> =
            (0..tris.len() as u32).filter(|&m| tris[m as usize].iter().all(|&v| in_both(v))).collect();
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|&m| {
                let t = tris[m as usize];
                (0..3).map(move |j| [t[j].min(t[(j + 1) % 3]), t[j].max(t[(j + 1) % 3])])
            })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let edge_index = |a: u32, b: u32| edges.binary_search(&[a.min(b), a.max(b)]).expect("a band edge") as u32;
        let rest_len: Vec<f64> =
            edges.iter().map(|&[a, b]| (at(self.rest, a as usize) - at(self.rest, b as usize)).norm()).collect();
        let tri_edges: Vec<[u32; 3]> = triangles
            .iter()
            .map(|&m| {
                let t = tris[m as usize];
                [edge_index(t[0], t[1]), edge_index(t[1], t[2]), edge_index(t[2], t[0])]
            })
            .collect();
        let mut edge_tris = vec![[NONE, NONE]; edges.len()];
        let mut manifold = true;
        for (i, es) in tri_edges.iter().enumerate() {
            for &e in es {
                let slot = &mut edge_tris[e as usize];
                if slot[0] == NONE {
                    slot[0] = i as u32;
                } else if slot[1] == NONE {
                    slot[1] = i as u32;
                } else {
                    manifold = false;
                }
            }
        }
        let mut vertices: Vec<u32> = edges.iter().flat_map(|e| [e[0], e[1]]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        let vid = |v: u32| vertices.binary_search(&v).expect("a band vertex") as u32;
        let graph_edges: Vec<(u32, u32, u32)> =
            edges.iter().enumerate().map(|(e, &[a, b])| (vid(a), vid(b), e as u32)).collect();
        let graph = Graph::new(vertices.len(), &graph_edges);
        let boundary_side: Vec<Option<(bool, bool)>> = (0..edges.len())
            .map(|e| {
                if edge_tris[e][1] != NONE {
                    return None;
                }
                let mut s = (false, false);
                for &m in self.edge_map.get(&edges[e]).map(Vec::as_slice).unwrap_or(&[]) {
                    let t = &tris[m as usize];
                    s.0 |= self.holds(p, t) && !self.holds(k, t);
                    s.1 |= self.holds(k, t) && !self.holds(p, t);
                }
                Some(s)
            })
            .collect();
        let mut band = Band {
            child: k,
            parent: p,
            triangles,
            edges,
            rest_len,
            tri_edges,
            edge_tris,
            kind: BandKind::Midway { reason: String::new(), child_side: Vec::new() },
        };
        if band.triangles.is_empty() {
            band.kind =
                BandKind::Midway { reason: "the overlap holds no whole triangle".into(), child_side: Vec::new() };
            return band;
        }
        let mesh = BandMesh { vertices, graph, boundary_side, manifold };
        band.kind = match cylinder(&band, &mesh) {
            Ok(cut) => BandKind::Cylinder(cut),
            Err(reason) => BandKind::Midway { child_side: self.midway(&band, &mesh), reason },
        };
        band
    }

    /// Half-way split of a band that is no cylinder: band vertices next to a parent-only
    /// (child-only) vertex form the parent (child) side; each band triangle goes to the side
    /// nearer in rest geodesic distance (sum over its corners).
    fn midway(&self, band: &Band, mesh: &BandMesh) -> Vec<bool> {
        let (k, p) = (band.child, band.parent);
        let (mut ps, mut cs) = (Vec::new(), Vec::new());
        for (i, &v) in mesh.vertices.iter().enumerate() {
            let (mut np, mut nc) = (false, false);
            for &m in self.vertex_triangles(v) {
                for &w in &self.tris[m as usize] {
                    let (a, b) = (self.local[p][w as usize] != NONE, self.local[k][w as usize] != NONE);
                    np |= a && !b;
                    nc |= b && !a;
                }
            }
            if np {
                ps.push(i as u32);
            }
            if nc {
                cs.push(i as u32);
            }
        }
        if ps.is_empty() || cs.is_empty() {
            return vec![ps.is_empty(); band.triangles.len()];
        }
        let (dp, _, _) = mesh.graph.dijkstra(&ps, &band.rest_len, |_| false);
        let (dc, _, _) = mesh.graph.dijkstra(&cs, &band.rest_len, |_| false);
        let vid = |v: u32| mesh.vertices.binary_search(&v).expect("a band vertex");
        band.triangles
            .iter()
            .map(|&m| {
                let t = self.tris[m as usize];
                let sp: f64 = t.iter().map(|&v| dp[vid(v)]).sum();
                let sc: f64 = t.iter().map(|&v| dc[vid(v)]).sum();
                sc < sp
            })
            .collect()
    }
}

/// The cut structure of a cylinder band, or why the band is not one.
fn cylinder(band: &Band, mesh: &BandMesh) -> std::result::Result<CutBand, String> {
    if !mesh.manifold {
        return Err("an edge of the overlap is shared by more than two of its triangles (non-manifold)".into());
    }
    let nv = mesh.vertices.len();
    let vid = |v: u32| mesh.vertices.binary_search(&v).expect("a band vertex") as u32;
    // One piece.
    let mut uf: Vec<u32> = (0..nv as u32).collect();
    for &[a, b] in &band.edges {
        union(&mut uf, vid(a), vid(b));
    }
    let pieces = (0..nv as u32).filter(|&v| find(&mut uf, v) == v).count();
    if pieces != 1 {
        return Err(format!("the overlap is in {pieces} pieces: expected one band"));
    }
    // Two boundary loops, one on each side.
    let boundary: Vec<usize> = (0..band.edges.len()).filter(|&e| mesh.boundary_side[e].is_some()).collect();
    let mut degree = vec![0u32; nv];
    let mut uf: Vec<u32> = (0..nv as u32).collect();
    for &e in &boundary {
        let [a, b] = band.edges[e];
        degree[vid(a) as usize] += 1;
        degree[vid(b) as usize] += 1;
        union(&mut uf, vid(a), vid(b));
    }
    if let Some(v) = degree.iter().position(|&d| d != 0 && d != 2) {
        return Err(format!(
            "vertex {} of the overlap's boundary is on {} boundary edges: expected 2 (the band is pinched)",
            mesh.vertices[v], degree[v]
        ));
    }
    let mut loops: Vec<(u32, bool, bool)> = Vec::new();
    for &e in &boundary {
        let root = find(&mut uf, vid(band.edges[e][0]));
        let (sp, sc) = mesh.boundary_side[e].unwrap_or_default();
        match loops.iter_mut().find(|l| l.0 == root) {
            Some(l) => {
                l.1 |= sp;
                l.2 |= sc;
            }
            None => loops.push((root, sp, sc)),
        }
    }
    if loops.len() != 2 {
        return Err(format!(
            "the overlap's boundary has {} loops: expected 2 (a cylinder between the parent's side and the child's)",
            loops.len()
        ));
    }
    let parent_loop = loops.iter().find(|l| l.1 && !l.2).map(|l| l.0);
    let child_loop = loops.iter().find(|l| l.2 && !l.1).map(|l| l.0);
    let (Some(parent_loop), Some(child_loop)) = (parent_loop, child_loop) else {
        return Err("the overlap's two boundary loops are not one on the parent's side and one on the child's".into());
    };
    let chi = nv as i64 - band.edges.len() as i64 + band.triangles.len() as i64;
    if chi != 0 {
        return Err(format!("the overlap is not a cylinder: Euler characteristic {chi}, expected 0"));
    }
    let loop_of = |uf: &mut Vec<u32>, v: u32| if degree[v as usize] == 2 { Some(find(uf, v)) } else { None };
    let parent_boundary: Vec<bool> = (0..band.edges.len())
        .map(|e| mesh.boundary_side[e].is_some() && loop_of(&mut uf, vid(band.edges[e][0])) == Some(parent_loop))
        .collect();
    let sources: Vec<u32> = (0..nv as u32).filter(|&v| loop_of(&mut uf, v) == Some(parent_loop)).collect();
    let on_child: Vec<bool> = (0..nv as u32).map(|v| loop_of(&mut uf, v) == Some(child_loop)).collect();
    // The seam: shortest path (rest lengths) from the parent's loop to the child's.
    let (_, pred, end) = mesh.graph.dijkstra(&sources, &band.rest_len, |v| on_child[v as usize]);
    let Some(end) = end else {
        return Err("no path inside the overlap from the parent's side to the child's".into());
    };
    let mut seam = vec![end];
    let mut seam_edges: Vec<u32> = Vec::new();
    let mut x = end;
    while pred[x as usize].0 != NONE {
        let (p, e) = pred[x as usize];
        seam_edges.push(e);
        seam.push(p);
        x = p;
    }
    seam.reverse();
    seam_edges.reverse();
    if seam_edges.is_empty() {
        return Err("the parent's and the child's boundary loops touch".into());
    }
    // Band triangles around each band vertex.
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (t, es) in band.tri_edges.iter().enumerate() {
        let mut corners: Vec<u32> = es.iter().flat_map(|&e| band.edges[e as usize]).map(vid).collect();
        corners.sort_unstable();
        corners.dedup();
        for c in corners {
            around[c as usize].push(t as u32);
        }
    }
    // Side of each triangle around each seam vertex: the fan split by the seam's edges, left
    // propagated along the seam through the triangles two consecutive seam vertices share.
    let mut right_of: Vec<Vec<u32>> = Vec::with_capacity(seam.len());
    let mut left_tri = NONE;
    for (i, &s) in seam.iter().enumerate() {
        let fan = &around[s as usize];
        let cut: Vec<u32> =
            [i.checked_sub(1).map(|j| seam_edges[j]), seam_edges.get(i).copied()].into_iter().flatten().collect();
        let mut uf: Vec<u32> = (0..fan.len() as u32).collect();
        for (a, &ta) in fan.iter().enumerate() {
            for (b, &tb) in fan.iter().enumerate().skip(a + 1) {
                let shared = band.tri_edges[ta as usize].iter().any(|e| {
                    !cut.contains(e)
                        && band.tri_edges[tb as usize].contains(e)
                        && band.edges[*e as usize].contains(&mesh.vertices[s as usize])
                });
                if shared {
                    union(&mut uf, a as u32, b as u32);
                }
            }
        }
        let sides = (0..fan.len() as u32).filter(|&a| find(&mut uf, a) == a).count();
        if sides != 2 {
            return Err(format!(
                "vertex {} of the overlap has {sides} sides along the seam: expected 2 (a non-manifold vertex)",
                mesh.vertices[s as usize]
            ));
        }
        let pos = |t: u32| fan.iter().position(|&x| x == t).map(|a| a as u32);
        if i == 0 {
            left_tri = band.edge_tris[seam_edges[0] as usize][0];
        }
        let Some(left) = pos(left_tri) else {
            return Err("the seam's sides could not be told apart".into());
        };
        let left_root = find(&mut uf, left);
        if let Some(&e) = seam_edges.get(i) {
            let [t0, t1] = band.edge_tris[e as usize];
            let in_left = |uf: &mut Vec<u32>, t: u32| t != NONE && pos(t).is_some_and(|a| find(uf, a) == left_root);
            left_tri = match (in_left(&mut uf, t0), in_left(&mut uf, t1)) {
                (true, false) => t0,
                (false, true) => t1,
                _ => return Err("the seam's sides could not be told apart".into()),
            };
        }
        right_of.push(
            fan.iter().enumerate().filter(|&(a, _)| find(&mut uf, a as u32) != left_root).map(|(_, &t)| t).collect(),
        );
    }
    // The cut band: each seam vertex's right triangles use its right copy (node nv + i).
    let seam_index: HashMap<u32, usize> = seam.iter().enumerate().map(|(i, &s)| (s, i)).collect();
    let node = |t: u32, v: u32| -> u32 {
        match seam_index.get(&v) {
            Some(&i) if right_of[i].contains(&t) => (nv + i) as u32,
            _ => v,
        }
    };
    let mut cut_edges: Vec<(u32, u32, u32)> = Vec::new();
    for (t, es) in band.tri_edges.iter().enumerate() {
        for &e in es {
            let [a, b] = band.edges[e as usize];
            let (na, nb) = (node(t as u32, vid(a)), node(t as u32, vid(b)));
            cut_edges.push((na.min(nb), na.max(nb), e));
        }
    }
    cut_edges.sort_unstable();
    cut_edges.dedup();
    let mut node_vertex = mesh.vertices.clone();
    node_vertex.extend(seam.iter().map(|&s| mesh.vertices[s as usize]));
    Ok(CutBand {
        graph: Graph::new(nv + seam.len(), &cut_edges),
        node_vertex,
        seam: seam.iter().enumerate().map(|(i, &s)| (s, (nv + i) as u32)).collect(),
        parent_boundary,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body_parts::Part;
    use surfcap_geometry::rotation_log_exp::exp_rotation;

    const AROUND: usize = 16;
    const RINGS: usize = 21;

    /// An open tube along z: 21 rings of 16 vertices from z = 0 to 1 (spacing 0.05), radius 0.2;
    /// vertex (ring r, k) is 16 r + k.
    fn tube() -> (Topology, Vec<f32>) {
        let mut p = Vec::new();
        for r in 0..RINGS {
            for k in 0..AROUND {
                let a = std::f32::consts::TAU * k as f32 / AROUND as f32;
                p.extend_from_slice(&[0.2 * a.cos(), 0.2 * a.sin(), r as f32 / (RINGS - 1) as f32]);
            }
        }
        let mut t = Vec::new();
        for r in 0..RINGS - 1 {
            for k in 0..AROUND {
                let (a, b) = ((r * AROUND + k) as u32, (r * AROUND + (k + 1) % AROUND) as u32);
                t.push([a, b, b + AROUND as u32]);
                t.push([a, b + AROUND as u32, a + AROUND as u32]);
            }
        }
        (Topology::new(AROUND * RINGS, t, None).unwrap(), p)
    }

    fn map(p: &[f32], f: impl Fn(Vector3<f64>) -> Vector3<f64>) -> Vec<f32> {
        p.chunks_exact(3)
            .flat_map(|q| {
                let w = f(Vector3::new(q[0] as f64, q[1] as f64, q[2] as f64));
                [w.x as f32, w.y as f32, w.z as f32]
            })
            .collect()
    }

    /// Turned by `angle * smoothstep((z - 0.3) / 0.4)` about the x axis through (0, 0, 0.5).
    fn bend(p: &[f32], angle: f64) -> Vec<f32> {
        map(p, |v| {
            let x = ((v.z - 0.3) / 0.4).clamp(0.0, 1.0);
            let pivot = Vector3::new(0.0, 0.0, 0.5);
            exp_rotation(&Vector3::new(angle * x * x * (3.0 - 2.0 * x), 0.0, 0.0)) * (v - pivot) + pivot
        })
    }

    fn rings(r: std::ops::RangeInclusive<usize>) -> Vec<u32> {
        r.flat_map(|r| (0..AROUND).map(move |k| (r * AROUND + k) as u32)).collect()
    }

    fn part(name: &str, parent: Option<&str>, vertices: Vec<u32>) -> Part {
        Part { name: name.into(), parent: parent.map(Into::into), vertices }
    }

    /// Lower rings 0-12 (root), upper rings 8-20: an overlap of rings 8-12 (a cylinder).
    fn two_parts() -> BodyParts {
        BodyParts::new(
            AROUND * RINGS,
            vec![part("lower", None, rings(0..=12)), part("upper", Some("lower"), rings(8..=20))],
        )
        .unwrap()
    }

    fn cut_out(parts: &BodyParts, p: &[f32]) -> Vec<Vec<f32>> {
        parts
            .parts
            .iter()
            .map(|q| q.vertices.iter().flat_map(|&v| p[3 * v as usize..3 * v as usize + 3].to_vec()).collect())
            .collect()
    }

    fn max_diff(a: &[f32], b: &[f32]) -> f32 {
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
    }

    #[test]
    fn parts_of_one_true_pose_stitch_back_into_it_even_moved_rigidly() {
        let (t, rest) = tube();
        let parts = two_parts();
        let truth = bend(&rest, 0.9);
        let s = Stitcher::new(&t, &rest, &parts).unwrap().aligning_children(true);
        let (out, report) = s.stitch(&cut_out(&parts, &truth)).unwrap();
        assert!(max_diff(&out, &truth) < 1e-5, "{}", max_diff(&out, &truth));
        assert_eq!(report.parts[0].cut, Cut::Root);
        let Cut::Loop { vertices, mismatch, band_triangles, .. } = &report.parts[1].cut else {
            panic!("{:?}", report.parts[1].cut)
        };
        assert_eq!(*band_triangles, 4 * 2 * AROUND);
        assert_eq!(vertices.len(), AROUND, "a shortest closed curve is one ring: {vertices:?}");
        assert!(*mismatch < 1e-5);
        // The child moved rigidly is aligned back onto its parent.
        let mut moved = cut_out(&parts, &truth);
        let r = exp_rotation(&Vector3::new(0.2, 0.1, -0.3));
        moved[1] = map(&moved[1], |v| r * v + Vector3::new(0.3, -0.1, 0.2));
        let (out, report) = s.stitch(&moved).unwrap();
        assert!(max_diff(&out, &truth) < 1e-5, "{}", max_diff(&out, &truth));
        assert!(report.parts[1].overlap_rms < 1e-5);
        let e = edge_distortion_by_region(&t, &parts, &out, &truth).unwrap();
        assert!(e.boundary_max < 1e-4 && e.inside_max < 1e-4, "{e:?}");
        assert_eq!(e.boundary_edges, 5 * AROUND + 6 * 2 * AROUND);
        // Without alignment the averaged baseline is torn apart; with it, it is exact.
        let torn = average_overlaps(&parts, &moved, false).unwrap();
        assert!(edge_distortion_by_region(&t, &parts, &torn, &truth).unwrap().boundary_max > 0.5);
        assert!(max_diff(&average_overlaps(&parts, &moved, true).unwrap(), &truth) < 1e-5);
    }

    #[test]
    fn the_curve_runs_where_the_two_copies_agree() {
        let (t, rest) = tube();
        let parts = two_parts();
        let truth = bend(&rest, 0.0);
        // The child is swollen radially except at z = 0.5 (ring 10, mid-band).
        let swollen = map(&truth, |v| {
            let s = 1.0 + 20.0 * (v.z - 0.5).powi(2);
            Vector3::new(s * v.x, s * v.y, v.z)
        });
        let mut ps = cut_out(&parts, &truth);
        ps[1] = cut_out(&parts, &swollen)[1].clone();
        let (out, report) = stitch(&t, &rest, &parts, &ps).unwrap();
        let Cut::Loop { vertices, mismatch, child_triangles, .. } = &report.parts[1].cut else {
            panic!("{:?}", report.parts[1].cut)
        };
        let mut ring: Vec<usize> = vertices.iter().map(|&v| v as usize / AROUND).collect();
        ring.dedup();
        assert_eq!(ring, vec![10], "{vertices:?}");
        assert!(*mismatch < 1e-5, "{mismatch}");
        assert_eq!(*child_triangles, 2 * 2 * AROUND);
        // Merged where both agree: no seam; the averaged baseline has one at the band's edge.
        let stitched = edge_distortion_by_region(&t, &parts, &out, &truth).unwrap();
        let averaged =
            edge_distortion_by_region(&t, &parts, &average_overlaps(&parts, &ps, true).unwrap(), &truth).unwrap();
        let mid =
            |p: &[f32], r: usize| (0..AROUND).map(|k| at(p, r * AROUND + k).xy().norm()).sum::<f64>() / AROUND as f64;
        assert!((mid(&out, 10) - 0.2).abs() < 1e-3, "{}", mid(&out, 10));
        assert!(stitched.boundary_max < averaged.boundary_max, "{stitched:?} {averaged:?}");
        assert!(out.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn a_band_that_is_not_a_cylinder_is_split_half_way() {
        let (t, rest) = tube();
        // The child is a strip of half the circumference above ring 8, the root the rest
        // (rings 0-12 whole): their overlap, rings 8-12 of the strip, is a disk.
        let in_strip = |v: usize| v / AROUND >= 8 && v % AROUND <= AROUND / 2;
        let upper: Vec<u32> = (0..AROUND * RINGS).filter(|&v| in_strip(v)).map(|v| v as u32).collect();
        let lower: Vec<u32> =
            (0..AROUND * RINGS).filter(|&v| v / AROUND <= 12 || !in_strip(v)).map(|v| v as u32).collect();
        let parts =
            BodyParts::new(AROUND * RINGS, vec![part("lower", None, lower), part("upper", Some("lower"), upper)])
                .unwrap();
        let truth = bend(&rest, 0.7);
        let (out, report) = stitch(&t, &rest, &parts, &cut_out(&parts, &truth)).unwrap();
        let Cut::Midway { reason, band_triangles, child_triangles } = &report.parts[1].cut else {
            panic!("{:?}", report.parts[1].cut)
        };
        assert!(reason.contains("expected 2"), "{reason}");
        assert!(*child_triangles > 0 && child_triangles < band_triangles, "{child_triangles} of {band_triangles}");
        assert!(max_diff(&out, &truth) < 1e-5);
    }

    #[test]
    fn a_chain_of_parts_moved_rigidly_is_put_back_top_down() {
        let (t, rest) = tube();
        let parts = BodyParts::new(
            AROUND * RINGS,
            vec![
                part("top", Some("mid"), rings(12..=20)),
                part("base", None, rings(0..=8)),
                part("mid", Some("base"), rings(5..=15)),
            ],
        )
        .unwrap();
        let truth = bend(&rest, 1.2);
        let mut ps = cut_out(&parts, &truth);
        ps[0] = map(&ps[0], |v| exp_rotation(&Vector3::new(0.0, 0.5, 0.1)) * v + Vector3::new(1.0, 0.0, 0.0));
        ps[2] = map(&ps[2], |v| exp_rotation(&Vector3::new(-0.3, 0.0, 0.2)) * v + Vector3::new(0.0, 2.0, 0.0));
        let (out, report) = Stitcher::new(&t, &rest, &parts).unwrap().aligning_children(true).stitch(&ps).unwrap();
        assert!(max_diff(&out, &truth) < 2e-5, "{}", max_diff(&out, &truth));
        assert!(matches!(report.parts[0].cut, Cut::Loop { .. }) && matches!(report.parts[2].cut, Cut::Loop { .. }));
        assert_eq!(report.parts[1].cut, Cut::Root);
        assert_eq!(report.parts[0].parent.as_deref(), Some("mid"));
    }

    #[test]
    fn a_part_without_overlap_keeps_its_predicted_placement() {
        // Two separate tubes (two components), the second a child sharing no vertex.
        let (t1, rest1) = tube();
        let n1 = t1.n_vertices() as u32;
        let mut tris = t1.triangles().to_vec();
        tris.extend(t1.triangles().iter().map(|t| t.map(|v| v + n1)));
        let t = Topology::new(2 * n1 as usize, tris, None).unwrap();
        let mut rest = rest1.clone();
        rest.extend(map(&rest1, |v| v + Vector3::new(1.0, 0.0, 0.0)));
        // Built without validation: a child without overlap is what KayKit's meshes give.
        let parts = BodyParts {
            format: crate::body_parts::FORMAT.into(),
            version: crate::body_parts::VERSION,
            n_vertices: 2 * n1 as usize,
            parts: vec![part("body", None, (0..n1).collect()), part("head", Some("body"), (n1..2 * n1).collect())],
        };
        let truth = map(&rest, |v| v + Vector3::new(0.0, 0.0, 0.1 * v.x));
        let mut ps = cut_out(&parts, &truth);
        ps[1] = map(&ps[1], |v| v + Vector3::new(0.0, 3.0, 0.0));
        let (out, report) = stitch(&t, &rest, &parts, &ps).unwrap();
        assert_eq!(report.parts[1].cut, Cut::NoOverlap);
        assert_eq!(report.parts[1].overlap_vertices, 0);
        assert!(max_diff(&out[..3 * n1 as usize], &truth[..3 * n1 as usize]) < 1e-5);
        assert!(max_diff(&out[3 * n1 as usize..], &ps[1]) < 1e-5);
        let e = edge_distortion_by_region(&t, &parts, &out, &truth).unwrap();
        assert_eq!(e.boundary_edges, 0);
        assert!(e.inside_max < 1e-4, "{e:?}");
    }

    #[test]
    fn degenerate_triangles_do_not_make_nan() {
        let (t, rest) = tube();
        let parts = two_parts();
        let mut truth = bend(&rest, 0.5);
        // Ring 10 (mid-band) collapsed onto one point, ring 16 (child only) too.
        for r in [10, 16] {
            for k in 0..AROUND {
                for d in 0..3 {
                    truth[3 * (r * AROUND + k) + d] = truth[3 * r * AROUND + d];
                }
            }
        }
        let (out, _) = stitch(&t, &rest, &parts, &cut_out(&parts, &truth)).unwrap();
        assert!(out.iter().all(|x| x.is_finite()));
        assert!(max_diff(&out, &truth) < 1e-4, "{}", max_diff(&out, &truth));
        let mut flat_rest = rest.clone();
        for k in 0..AROUND {
            for d in 0..3 {
                flat_rest[3 * (12 * AROUND + k) + d] = flat_rest[3 * 12 * AROUND + d];
            }
        }
        let (out, _) = stitch(&t, &flat_rest, &parts, &cut_out(&parts, &truth)).unwrap();
        assert!(out.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn bad_input_is_refused_with_the_reason() {
        let (t, rest) = tube();
        let parts = two_parts();
        let s = Stitcher::new(&t, &rest, &parts).unwrap();
        let good = cut_out(&parts, &rest);
        let e = s.stitch(&good[..1]).unwrap_err().to_string();
        assert!(e.contains("1 part meshes: expected 2 (one per body part: lower, upper)"), "{e}");
        let mut bad = good.clone();
        bad[1].pop();
        let e = s.stitch(&bad).unwrap_err().to_string();
        assert!(e.contains("part \"upper\" has 623 coordinates: expected 3 x 208 = 624"), "{e}");
        let mut bad = good.clone();
        bad[0][5] = f32::INFINITY;
        let e = s.stitch(&bad).unwrap_err().to_string();
        assert!(e.contains("part \"lower\" has a non-finite coordinate at vertex 1"), "{e}");
        let small = BodyParts::whole_body(10);
        let e = Stitcher::new(&t, &rest, &small).err().unwrap().to_string();
        assert!(e.contains("made for a template of 10 vertices, but the topology has 336"), "{e}");
        let mut out_of_range = parts.clone();
        out_of_range.parts[1].vertices.push(336);
        let e = Stitcher::new(&t, &rest, &out_of_range).err().unwrap().to_string();
        assert!(e.contains("part \"upper\" has vertex 336: expected 0 to 335"), "{e}");
        let e = average_overlaps(&out_of_range, &good, true).unwrap_err().to_string();
        assert!(e.contains("has vertex 336"), "{e}");
        let e = Stitcher::new(&t, &rest[3..], &parts).err().unwrap().to_string();
        assert!(e.contains("the template's rest pose has 1005 coordinates: expected 3 x 336 = 1008"), "{e}");
        let e = average_overlaps(&parts, &bad, true).unwrap_err().to_string();
        assert!(e.contains("non-finite"), "{e}");
        let e = edge_distortion_by_region(&t, &parts, &rest[3..], &rest).unwrap_err().to_string();
        assert!(e.contains("the stitched mesh has 1005 coordinates"), "{e}");
    }

    #[test]
    fn same_answer_whatever_the_thread_count_and_shareable_across_threads() {
        fn shareable<T: Send + Sync>(_: &T) {}
        let (t, rest) = tube();
        let parts = two_parts();
        let s = Stitcher::new(&t, &rest, &parts).unwrap();
        shareable(&s);
        let mut ps = cut_out(&parts, &bend(&rest, 0.6));
        ps[1] = map(&ps[1], |v| Vector3::new(1.1 * v.x, v.y + 0.05 * v.z * v.z, v.z));
        let run =
            |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| s.stitch(&ps).unwrap());
        let (a, ra) = run(1);
        let (b, rb) = run(2);
        assert_eq!(a, b);
        assert_eq!(ra, rb);
    }
}

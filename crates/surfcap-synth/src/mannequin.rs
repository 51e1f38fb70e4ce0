//! The built-in mannequin: a closed, watertight, 2-manifold triangle mesh of a human body built
//! around a skeleton, with linear-blend-skinning weights.
//!
//! Shape: each bone is a capsule (a segment with a radius); the body is the smooth union of the
//! capsules (polynomial smooth minimum of their signed distances, so limbs blend into the torso
//! instead of being disjoint boxes). Surface: marching tetrahedra on a regular grid (each cube
//! split into six tetrahedra along its main diagonal, the same split in every cube, so the
//! surface is closed and every edge has exactly two triangles); edge crossings are clamped to the
//! middle 80% of their grid edge so that no triangle degenerates. The grid step is chosen so that
//! the vertex count lands near the requested one; two different body shapes give different
//! vertex counts and connectivity (no correspondence).
//!
//! Skinning weights: inverse fourth power of the distance to each bone, the four largest kept
//! and normalised.

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3, Vector3};
use surfcap_mesh::{Error, ErrorKind, Result, Topology};

/// Body shape parameters (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyShape {
    pub height: f64,
    /// Radius multipliers.
    pub torso_girth: f64,
    pub limb_girth: f64,
    /// Leg length as a fraction of the height (0.45-0.55 for people).
    pub leg_ratio: f64,
    /// Shoulder half-width as a fraction of the height.
    pub shoulder_ratio: f64,
}

impl BodyShape {
    /// An average adult.
    pub fn average() -> Self {
        BodyShape { height: 1.75, torso_girth: 1.0, limb_girth: 1.0, leg_ratio: 0.5, shoulder_ratio: 0.11 }
    }

    /// A tall, slim build.
    pub fn slim() -> Self {
        BodyShape { height: 1.9, torso_girth: 0.8, limb_girth: 0.8, leg_ratio: 0.53, shoulder_ratio: 0.1 }
    }

    /// A short, heavy build.
    pub fn heavy() -> Self {
        BodyShape { height: 1.62, torso_girth: 1.35, limb_girth: 1.25, leg_ratio: 0.47, shoulder_ratio: 0.125 }
    }

    /// `average`, `slim` or `heavy`.
    pub fn named(name: &str) -> Option<Self> {
        match name {
            "average" => Some(Self::average()),
            "slim" => Some(Self::slim()),
            "heavy" => Some(Self::heavy()),
            _ => None,
        }
    }
}

/// The mannequin's skeleton: joint names (CMU ASF style), parents and rest positions (y up,
/// facing +z, arms out along x: a T-pose), and the bones (joint -> child) with radii.
#[derive(Debug, Clone)]
pub struct Skeleton {
    pub names: Vec<&'static str>,
    pub parents: Vec<Option<usize>>,
    pub rest: Vec<Point3<f64>>,
    /// (from joint, to joint or end point, radius at from, radius at to).
    pub bones: Vec<Bone>,
}

/// A capsule bone.
#[derive(Debug, Clone)]
pub struct Bone {
    /// The joint whose transform moves this bone.
    pub joint: usize,
    pub a: Point3<f64>,
    pub b: Point3<f64>,
    pub radius: f64,
}

/// Builds the skeleton of a body shape.
pub fn skeleton(s: &BodyShape) -> Skeleton {
    let h = s.height;
    let leg = s.leg_ratio * h;
    let hip_y = leg;
    let (thigh, shin) = (0.52 * leg, 0.43 * leg);
    let sh = s.shoulder_ratio * h;
    let (upper_arm, forearm) = (0.17 * h, 0.15 * h);
    let p = Point3::new;
    // name, parent, position
    let joints: Vec<(&'static str, Option<usize>, Point3<f64>)> = vec![
        ("pelvis", None, p(0.0, hip_y, 0.0)),
        ("lfemur", Some(0), p(0.09 * h / 1.75, hip_y - 0.03 * h, 0.0)),
        ("ltibia", Some(1), p(0.09 * h / 1.75, hip_y - 0.03 * h - thigh, 0.0)),
        ("lfoot", Some(2), p(0.09 * h / 1.75, hip_y - 0.03 * h - thigh - shin, 0.0)),
        ("rfemur", Some(0), p(-0.09 * h / 1.75, hip_y - 0.03 * h, 0.0)),
        ("rtibia", Some(4), p(-0.09 * h / 1.75, hip_y - 0.03 * h - thigh, 0.0)),
        ("rfoot", Some(5), p(-0.09 * h / 1.75, hip_y - 0.03 * h - thigh - shin, 0.0)),
        ("thorax", Some(0), p(0.0, hip_y + 0.17 * h, 0.0)),
        ("head", Some(7), p(0.0, hip_y + 0.31 * h, 0.0)),
        ("lhumerus", Some(7), p(sh, hip_y + 0.27 * h, 0.0)),
        ("lradius", Some(9), p(sh + upper_arm, hip_y + 0.27 * h, 0.0)),
        ("lhand", Some(10), p(sh + upper_arm + forearm, hip_y + 0.27 * h, 0.0)),
        ("rhumerus", Some(7), p(-sh, hip_y + 0.27 * h, 0.0)),
        ("rradius", Some(12), p(-sh - upper_arm, hip_y + 0.27 * h, 0.0)),
        ("rhand", Some(13), p(-sh - upper_arm - forearm, hip_y + 0.27 * h, 0.0)),
    ];
    let names = joints.iter().map(|j| j.0).collect();
    let parents = joints.iter().map(|j| j.1).collect();
    let rest: Vec<Point3<f64>> = joints.iter().map(|j| j.2).collect();
    let (tg, lg) = (s.torso_girth * h / 1.75, s.limb_girth * h / 1.75);
    let bone = |joint: usize, a: Point3<f64>, b: Point3<f64>, r: f64| Bone { joint, a, b, radius: r };
    let head_top = rest[8] + Vector3::new(0.0, 0.11 * h, 0.0);
    let toe = |f: usize| rest[f] + Vector3::new(0.0, 0.02 * h, 0.14 * h);
    let bones = vec![
        bone(0, rest[4], rest[1], 0.085 * tg),                                   // hips
        bone(0, rest[0], rest[7], 0.11 * tg),                                    // belly
        bone(7, rest[7], rest[7] + Vector3::new(0.0, 0.1 * h, 0.0), 0.12 * tg),  // chest
        bone(7, rest[12], rest[9], 0.06 * tg),                                   // shoulders
        bone(7, rest[7] + Vector3::new(0.0, 0.1 * h, 0.0), rest[8], 0.045 * lg), // neck
        bone(8, rest[8] + Vector3::new(0.0, 0.04 * h, 0.0), head_top - Vector3::new(0.0, 0.03 * h, 0.0), 0.065 * lg), // head
        bone(1, rest[1], rest[2], 0.07 * lg),
        bone(2, rest[2], rest[3], 0.05 * lg),
        bone(3, rest[3], toe(3), 0.035 * lg),
        bone(4, rest[4], rest[5], 0.07 * lg),
        bone(5, rest[5], rest[6], 0.05 * lg),
        bone(6, rest[6], toe(6), 0.035 * lg),
        bone(9, rest[9], rest[10], 0.042 * lg),
        bone(10, rest[10], rest[11], 0.035 * lg),
        bone(11, rest[11], rest[11] + Vector3::new(0.08 * h, 0.0, 0.0), 0.03 * lg),
        bone(12, rest[12], rest[13], 0.042 * lg),
        bone(13, rest[13], rest[14], 0.035 * lg),
        bone(14, rest[14], rest[14] - Vector3::new(0.08 * h, 0.0, 0.0), 0.03 * lg),
    ];
    Skeleton { names, parents, rest, bones }
}

fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-18)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Polynomial smooth minimum (Quilez) with blend radius k.
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b * (1.0 - h) + a * h - k * h * (1.0 - h)
}

/// Signed distance (approximately) of the body: negative inside.
pub fn body_sdf(sk: &Skeleton, p: &Point3<f64>, blend: f64) -> f64 {
    sk.bones
        .iter()
        .map(|b| segment_distance(p, &b.a, &b.b) - b.radius)
        .fold(f64::INFINITY, |acc, d| if acc.is_infinite() { d } else { smooth_min(acc, d, blend) })
}

/// The mannequin mesh in its rest pose.
#[derive(Debug, Clone)]
pub struct Mannequin {
    pub skeleton: Skeleton,
    pub topology: Topology,
    /// Rest positions `[vertices][3]`.
    pub positions: Vec<f32>,
    /// Up to four (bone index, weight) per vertex, weights summing to 1.
    pub weights: Vec<[(u16, f32); 4]>,
}

/// Marching tetrahedra of `f` over a grid of step `h` on the box [lo, hi].
fn polygonise(f: &dyn Fn(&Point3<f64>) -> f64, lo: Point3<f64>, hi: Point3<f64>, h: f64) -> (Vec<f32>, Vec<[u32; 3]>) {
    let dims = ((hi - lo) / h).map(|x| x.ceil() as usize + 1);
    let (nx, ny, nz) = (dims.x, dims.y, dims.z);
    let at = |i: usize, j: usize, k: usize| lo + Vector3::new(i as f64, j as f64, k as f64) * h;
    let mut vals = vec![0.0f64; nx * ny * nz];
    let id = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let v = f(&at(i, j, k));
                // No sample exactly on the surface: keeps every case unambiguous.
                vals[id(i, j, k)] = if v == 0.0 { 1e-12 } else { v };
            }
        }
    }
    // Six tetrahedra per cube around the diagonal 0-7 (cube corners by bits x, y, z).
    const TETS: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]];
    let mut positions: Vec<f32> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    let mut edge_vertex: HashMap<(usize, usize), u32> = HashMap::new();
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            for k in 0..nz - 1 {
                let corner = |c: usize| (i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                for tet in TETS {
                    let g: [usize; 4] = tet.map(|c| {
                        let (a, b, cc) = corner(c);
                        id(a, b, cc)
                    });
                    let inside: Vec<usize> = (0..4).filter(|&q| vals[g[q]] < 0.0).collect();
                    if inside.is_empty() || inside.len() == 4 {
                        continue;
                    }
                    let pos_of = |gi: usize| {
                        let (a, rem) = (gi / (ny * nz), gi % (ny * nz));
                        at(a, rem / nz, rem % nz)
                    };
                    let mut vertex = |a: usize, b: usize| -> u32 {
                        let key = (g[a].min(g[b]), g[a].max(g[b]));
                        *edge_vertex.entry(key).or_insert_with(|| {
                            let (fa, fb) = (vals[g[a]], vals[g[b]]);
                            let t = (fa / (fa - fb)).clamp(0.1, 0.9);
                            let p = pos_of(g[a]) + (pos_of(g[b]) - pos_of(g[a])) * t;
                            positions.extend_from_slice(&[p.x as f32, p.y as f32, p.z as f32]);
                            (positions.len() / 3 - 1) as u32
                        })
                    };
                    let outside: Vec<usize> = (0..4).filter(|&q| vals[g[q]] >= 0.0).collect();
                    let out_dir = {
                        let ci =
                            inside.iter().map(|&q| pos_of(g[q]).coords).sum::<Vector3<f64>>() / inside.len() as f64;
                        let co =
                            outside.iter().map(|&q| pos_of(g[q]).coords).sum::<Vector3<f64>>() / outside.len() as f64;
                        co - ci
                    };
                    let mut faces: Vec<[u32; 3]> = Vec::new();
                    if inside.len() == 1 || inside.len() == 3 {
                        let (lone, others) =
                            if inside.len() == 1 { (inside[0], outside.clone()) } else { (outside[0], inside.clone()) };
                        faces.push([vertex(lone, others[0]), vertex(lone, others[1]), vertex(lone, others[2])]);
                    } else {
                        let (a, b) = (inside[0], inside[1]);
                        let (c, d) = (outside[0], outside[1]);
                        let (ac, ad, bc, bd) = (vertex(a, c), vertex(a, d), vertex(b, c), vertex(b, d));
                        faces.push([ac, ad, bd]);
                        faces.push([ac, bd, bc]);
                    }
                    for mut t in faces {
                        let p = |v: u32| {
                            Vector3::new(
                                positions[3 * v as usize] as f64,
                                positions[3 * v as usize + 1] as f64,
                                positions[3 * v as usize + 2] as f64,
                            )
                        };
                        let n = (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0])));
                        if n.dot(&out_dir) < 0.0 {
                            t.swap(1, 2);
                        }
                        tris.push(t);
                    }
                }
            }
        }
    }
    (positions, tris)
}

/// Builds the mannequin of `shape` with about `target_vertices` vertices (1,000 to 20,000).
pub fn mannequin(shape: &BodyShape, target_vertices: usize) -> Result<Mannequin> {
    if !(1000..=20000).contains(&target_vertices) {
        return Err(Error::new(
            ErrorKind::Unsupported,
            format!("{target_vertices} vertices: expected 1,000 to 20,000"),
        ));
    }
    let sk = skeleton(shape);
    let blend = 0.03 * shape.height;
    let f = |p: &Point3<f64>| body_sdf(&sk, p, blend);
    let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for b in &sk.bones {
        for q in [b.a, b.b] {
            lo = lo.inf(&(q - Vector3::repeat(b.radius)));
            hi = hi.sup(&(q + Vector3::repeat(b.radius)));
        }
    }
    let margin = Vector3::repeat(0.05 * shape.height);
    let (lo, hi) = (lo - margin, hi + margin);
    // Surface area estimate for the first step, then refine the step from the count obtained.
    let area: f64 =
        sk.bones.iter().map(|b| 2.0 * std::f64::consts::PI * b.radius * ((b.b - b.a).norm() + 2.0 * b.radius)).sum();
    let mut h = (area / (1.2 * target_vertices as f64)).sqrt();
    let mut best: Option<(Vec<f32>, Vec<[u32; 3]>)> = None;
    for _ in 0..4 {
        let (p, t) = polygonise(&f, lo, hi, h);
        let n = p.len() / 3;
        let ratio = n as f64 / target_vertices as f64;
        let done = (0.9..=1.1).contains(&ratio);
        best = Some((p, t));
        if done {
            break;
        }
        h *= ratio.sqrt();
    }
    let (positions, tris) = best.expect("at least one pass");
    let nv = positions.len() / 3;
    let topology = Topology::new(nv, tris, None)?;
    let weights = positions
        .chunks_exact(3)
        .map(|v| {
            let p = Point3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            let mut w: Vec<(u16, f64)> = sk
                .bones
                .iter()
                .enumerate()
                .map(|(bi, b)| (bi as u16, 1.0 / (segment_distance(&p, &b.a, &b.b).max(1e-4 * shape.height)).powi(4)))
                .collect();
            w.sort_by(|a, b| b.1.total_cmp(&a.1));
            w.truncate(4);
            let s: f64 = w.iter().map(|x| x.1).sum();
            let mut out = [(0u16, 0f32); 4];
            for (k, &(bi, x)) in w.iter().enumerate() {
                out[k] = (bi, (x / s) as f32);
            }
            out
        })
        .collect();
    Ok(Mannequin { skeleton: sk, topology, positions, weights })
}

impl Mannequin {
    /// Rest world transforms of the joints (T-pose: no rotation, at the rest positions).
    pub fn rest_transforms(&self) -> Vec<Isometry3<f64>> {
        self.skeleton.rest.iter().map(|p| Isometry3::translation(p.x, p.y, p.z)).collect()
    }

    /// Linear blend skinning: the mesh posed by the joints' world transforms `world` (one per
    /// skeleton joint): v' = sum_b w_b W_b W_b,rest^-1 v over the vertex's bones.
    pub fn pose(&self, world: &[Isometry3<f64>]) -> Vec<f32> {
        let rest = self.rest_transforms();
        let skin: Vec<Isometry3<f64>> =
            self.skeleton.bones.iter().map(|b| world[b.joint] * rest[b.joint].inverse()).collect();
        self.positions
            .chunks_exact(3)
            .zip(&self.weights)
            .flat_map(|(v, w)| {
                let p = Point3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                let q = w.iter().fold(Vector3::zeros(), |acc, &(b, x)| acc + (skin[b as usize] * p).coords * x as f64);
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// Every undirected edge is used by exactly two triangles, once in each direction.
    fn closed_two_manifold(t: &Topology) -> bool {
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for tri in t.triangles() {
            for k in 0..3 {
                *directed.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
            }
        }
        directed.iter().all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
    }

    #[test]
    fn watertight_manifold_and_shape_dependent() {
        let a = mannequin(&BodyShape::average(), 3000).unwrap();
        let b = mannequin(&BodyShape::heavy(), 3000).unwrap();
        for m in [&a, &b] {
            let n = m.topology.n_vertices();
            assert!((2400..=3600).contains(&n), "{n} vertices for a target of 3000");
            assert!(closed_two_manifold(&m.topology), "not a closed 2-manifold");
            assert_eq!(surfcap_mesh::connected_components(&m.topology).count, 1, "one body");
            assert_eq!(m.topology.count_degenerate_triangles(&m.positions, 1e-12), 0);
            assert!(m.weights.iter().all(|w| (w.iter().map(|x| x.1).sum::<f32>() - 1.0).abs() < 1e-4));
            // Closed and outward: positive enclosed volume.
            let vol: f64 = m
                .topology
                .triangles()
                .iter()
                .map(|t| {
                    let p = |i: u32| {
                        Vector3::new(
                            m.positions[3 * i as usize] as f64,
                            m.positions[3 * i as usize + 1] as f64,
                            m.positions[3 * i as usize + 2] as f64,
                        )
                    };
                    p(t[0]).dot(&p(t[1]).cross(&p(t[2]))) / 6.0
                })
                .sum();
            assert!(vol > 0.02 && vol < 0.2, "body volume {vol} m^3");
        }
        assert_ne!(a.topology.n_vertices(), b.topology.n_vertices(), "two shapes, two topologies");
        let big = mannequin(&BodyShape::slim(), 12000).unwrap();
        assert!((10000..=14000).contains(&big.topology.n_vertices()), "{}", big.topology.n_vertices());
        assert!(closed_two_manifold(&big.topology));
        assert!(mannequin(&BodyShape::average(), 500).is_err());
    }

    #[test]
    fn skinning_moves_rigidly_with_the_whole_skeleton_and_bends_an_elbow() {
        let m = mannequin(&BodyShape::average(), 2000).unwrap();
        let rest = m.pose(&m.rest_transforms());
        assert!(rest.iter().zip(&m.positions).all(|(a, b)| (a - b).abs() < 1e-6), "the rest pose is the mesh");
        // The whole body turned and moved: every vertex follows exactly (weights sum to one).
        let g = Isometry3::from_parts(
            Vector3::new(1.0, 0.0, -2.0).into(),
            UnitQuaternion::from_euler_angles(0.0, 0.7, 0.0),
        );
        let world: Vec<Isometry3<f64>> = m.rest_transforms().iter().map(|r| g * r).collect();
        let moved = m.pose(&world);
        for (a, b) in moved.chunks(3).zip(m.positions.chunks(3)) {
            let want = g * Point3::new(b[0] as f64, b[1] as f64, b[2] as f64);
            assert!((Vector3::new(a[0] as f64, a[1] as f64, a[2] as f64) - want.coords).norm() < 1e-5);
        }
        // Bend the left elbow by 1 rad: no triangle flips, no edge stretches past 2.5x.
        let mut world = m.rest_transforms();
        let elbow = m.skeleton.names.iter().position(|&n| n == "lradius").unwrap();
        // 1 rad passes; with these weights bends past ~1.2 rad fold the inner crease (triangles
        // flip there): smoother joint-region weights are the next step of the mannequin.
        let bend = UnitQuaternion::from_euler_angles(0.0, 0.0, 1.0);
        let pivot = m.skeleton.rest[elbow];
        for j in [elbow, elbow + 1] {
            let local = world[j];
            world[j] = Isometry3::translation(pivot.x, pivot.y, pivot.z)
                * bend
                * Isometry3::translation(-pivot.x, -pivot.y, -pivot.z)
                * local;
        }
        let bent = m.pose(&world);
        let p = |s: &[f32], i: u32| {
            Vector3::new(s[3 * i as usize] as f64, s[3 * i as usize + 1] as f64, s[3 * i as usize + 2] as f64)
        };
        for t in m.topology.triangles() {
            let n0 =
                (p(&m.positions, t[1]) - p(&m.positions, t[0])).cross(&(p(&m.positions, t[2]) - p(&m.positions, t[0])));
            let n1 = (p(&bent, t[1]) - p(&bent, t[0])).cross(&(p(&bent, t[2]) - p(&bent, t[0])));
            assert!(n0.dot(&n1) > 0.0 || n1.norm() < 1e-9, "a triangle flipped");
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let r = (p(&bent, a) - p(&bent, b)).norm() / (p(&m.positions, a) - p(&m.positions, b)).norm();
                assert!(r < 2.5, "edge stretched {r}x");
            }
        }
    }
}

//! The built-in mannequin: a closed, watertight, 2-manifold triangle mesh of a human body built
//! around a skeleton, with linear-blend-skinning weights.
//!
//! Shape: each bone is a capsule (a segment with a radius). The capsules of the torso (hips,
//! belly, chest, shoulders, neck, head) are blended into one smooth body, each limb's capsules
//! into one smooth limb, and each limb into the torso (polynomial smooth minimum of signed
//! distances, so limbs grow out of the torso instead of being disjoint boxes); the limbs are not
//! blended with each other, so the legs stay two legs. Surface: marching tetrahedra on a regular grid (each cube
//! split into six tetrahedra along its main diagonal, the same split in every cube, so the
//! surface is closed and every edge has exactly two triangles); edge crossings are clamped to the
//! middle 80% of their grid edge so that no triangle degenerates. The grid step is chosen so that
//! the vertex count lands near the requested one; two different body shapes give different
//! vertex counts and connectivity (no correspondence).
//!
//! Skinning weights: each vertex first belongs wholly to the joint of its nearest skeleton
//! segment; the
//! weights are then diffused over the surface (heat flow along the mesh, so they never leak
//! between two limbs that are close in space but far apart on the skin), which gives every
//! joint a smooth blend zone a few centimetres wide; the four largest are kept and normalised.
//! Posing uses dual-quaternion skinning (Kavan et al. 2007), which keeps bent elbows and knees
//! from collapsing the way linear blend skinning does.

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};
use surfcap_mesh::{Error, ErrorKind, Result, Topology};

use crate::frame_remeshing::{collapse_short_edges, flip_edges, mean_edge_length, vertex_neighbours};

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

    /// `average`, `slim`, `heavy`, or `key=value` pairs separated by commas changing the
    /// average (`height=1.8,torso_girth=1.2`; keys: height, torso_girth, limb_girth,
    /// leg_ratio, shoulder_ratio), optionally after a named shape (`slim,height=2`).
    pub fn parse(text: &str) -> Result<Self> {
        let bad = |msg: String| Error::new(ErrorKind::Unsupported, format!("body shape {text:?}: {msg}"));
        let mut shape = BodyShape::average();
        for (i, part) in text.split(',').map(str::trim).enumerate() {
            let Some((key, value)) = part.split_once('=') else {
                match Self::named(part) {
                    Some(s) if i == 0 => shape = s,
                    _ => return Err(bad(format!("{part:?}: expected average, slim, heavy or key=value"))),
                }
                continue;
            };
            let v: f64 = value.trim().parse().map_err(|_| bad(format!("{value:?} is not a number")))?;
            let (field, range) = match key.trim() {
                "height" => (&mut shape.height, 0.5..=2.5),
                "torso_girth" => (&mut shape.torso_girth, 0.5..=2.0),
                "limb_girth" => (&mut shape.limb_girth, 0.5..=2.0),
                "leg_ratio" => (&mut shape.leg_ratio, 0.35..=0.6),
                "shoulder_ratio" => (&mut shape.shoulder_ratio, 0.08..=0.15),
                k => {
                    return Err(bad(format!(
                        "unknown key {k:?}: expected height, torso_girth, limb_girth, leg_ratio or shoulder_ratio"
                    )));
                }
            };
            if !range.contains(&v) {
                return Err(bad(format!("{key} = {v}: expected {} to {}", range.start(), range.end())));
            }
            *field = v;
        }
        Ok(shape)
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
/// facing +z, arms out to the sides and 40 degrees down: an A-pose), and the bones (joint -> child) with radii.
#[derive(Debug, Clone)]
pub struct Skeleton {
    pub names: Vec<&'static str>,
    pub parents: Vec<Option<usize>>,
    pub rest: Vec<Point3<f64>>,
    /// (from joint, to joint or end point, radius at from, radius at to).
    pub bones: Vec<Bone>,
}

/// Which part of the body a capsule belongs to: capsules of one part blend smoothly; each limb
/// blends with the torso, never with another limb.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Torso,
    Limb(u8),
}

/// A capsule bone.
#[derive(Debug, Clone)]
pub struct Bone {
    /// The joint whose transform moves this bone.
    pub joint: usize,
    pub part: Part,
    pub a: Point3<f64>,
    pub b: Point3<f64>,
    pub radius: f64,
}

/// The rest pose's arms: this far below the horizontal (radians).
pub const ARM_DROP: f64 = 0.7;

/// Builds the skeleton of a body shape.
pub fn skeleton(s: &BodyShape) -> Skeleton {
    let h = s.height;
    let leg = s.leg_ratio * h;
    let hip_y = leg;
    let (tg, lg) = (s.torso_girth * h / 1.75, s.limb_girth * h / 1.75);
    let thigh_r = 0.07 * lg;
    // Hip joints far enough apart that the thighs never touch, even on the coarsest grid (a
    // gap of 10 cm at 1.75 m): touching thighs would be meshed and skinned as one.
    let hip_x = thigh_r + 0.05 * h / 1.75;
    // The ankle sits one shin radius above the ground (y = 0), so that the rest mesh stands on
    // it; the shin takes what the thigh leaves of the leg.
    let ankle_y = 0.05 * lg;
    let thigh = 0.52 * leg;
    let shin = hip_y - 0.03 * h - thigh - ankle_y;
    let sh = s.shoulder_ratio * h;
    let (upper_arm, forearm) = (0.17 * h, 0.15 * h);
    // Arms hang ARM_DROP below the horizontal (an A-pose): captured arms spend most of their time
    // down, and a rest pose halfway there halves the turn the armpit's skin must absorb.
    let (down_x, down_y) = (ARM_DROP.cos(), -ARM_DROP.sin());
    let shoulder_y = hip_y + 0.27 * h;
    let p = Point3::new;
    let arm = |sign: f64, along: f64| p(sign * (sh + along * down_x), shoulder_y + along * down_y, 0.0);
    // name, parent, position
    let joints: Vec<(&'static str, Option<usize>, Point3<f64>)> = vec![
        ("pelvis", None, p(0.0, hip_y, 0.0)),
        ("lfemur", Some(0), p(hip_x, hip_y - 0.03 * h, 0.0)),
        ("ltibia", Some(1), p(hip_x, hip_y - 0.03 * h - thigh, 0.0)),
        ("lfoot", Some(2), p(hip_x, hip_y - 0.03 * h - thigh - shin, 0.0)),
        ("rfemur", Some(0), p(-hip_x, hip_y - 0.03 * h, 0.0)),
        ("rtibia", Some(4), p(-hip_x, hip_y - 0.03 * h - thigh, 0.0)),
        ("rfoot", Some(5), p(-hip_x, hip_y - 0.03 * h - thigh - shin, 0.0)),
        ("thorax", Some(0), p(0.0, hip_y + 0.17 * h, 0.0)),
        ("head", Some(7), p(0.0, hip_y + 0.31 * h, 0.0)),
        ("lhumerus", Some(7), arm(1.0, 0.0)),
        ("lradius", Some(9), arm(1.0, upper_arm)),
        ("lhand", Some(10), arm(1.0, upper_arm + forearm)),
        ("rhumerus", Some(7), arm(-1.0, 0.0)),
        ("rradius", Some(12), arm(-1.0, upper_arm)),
        ("rhand", Some(13), arm(-1.0, upper_arm + forearm)),
    ];
    let names = joints.iter().map(|j| j.0).collect();
    let parents = joints.iter().map(|j| j.1).collect();
    let rest: Vec<Point3<f64>> = joints.iter().map(|j| j.2).collect();
    let bone = |joint: usize, a: Point3<f64>, b: Point3<f64>, r: f64| {
        // Joints 1-6 are the legs (three per leg), 9-14 the arms; the rest is the torso.
        let part = match joint {
            1..=3 => Part::Limb(0),
            4..=6 => Part::Limb(1),
            9..=11 => Part::Limb(2),
            12..=14 => Part::Limb(3),
            _ => Part::Torso,
        };
        Bone { joint, part, a, b, radius: r }
    };
    let head_top = rest[8] + Vector3::new(0.0, 0.11 * h, 0.0);
    let toe = |f: usize| rest[f] + Vector3::new(0.0, 0.02 * h, 0.14 * h);
    let bones = vec![
        bone(0, rest[4], rest[1], 0.085 * tg),                                   // hips
        bone(0, rest[0], rest[7], 0.11 * tg),                                    // belly
        bone(7, rest[7], rest[7] + Vector3::new(0.0, 0.1 * h, 0.0), 0.12 * tg),  // chest
        bone(7, rest[12], rest[9], 0.06 * tg),                                   // shoulders
        bone(7, rest[7] + Vector3::new(0.0, 0.1 * h, 0.0), rest[8], 0.045 * lg), // neck
        bone(8, rest[8] + Vector3::new(0.0, 0.04 * h, 0.0), head_top - Vector3::new(0.0, 0.03 * h, 0.0), 0.065 * lg), // head
        bone(1, rest[1], rest[2], thigh_r),
        bone(2, rest[2], rest[3], 0.05 * lg),
        bone(3, rest[3], toe(3), 0.035 * lg),
        bone(4, rest[4], rest[5], thigh_r),
        bone(5, rest[5], rest[6], 0.05 * lg),
        bone(6, rest[6], toe(6), 0.035 * lg),
        bone(9, rest[9], rest[10], 0.042 * lg),
        bone(10, rest[10], rest[11], 0.035 * lg),
        bone(11, rest[11], arm(1.0, upper_arm + forearm + 0.08 * h), 0.03 * lg),
        bone(12, rest[12], rest[13], 0.042 * lg),
        bone(13, rest[13], rest[14], 0.035 * lg),
        bone(14, rest[14], arm(-1.0, upper_arm + forearm + 0.08 * h), 0.03 * lg),
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

/// Signed distance (approximately) of the body: negative inside. The smooth union of the torso's
/// capsules, and of each limb's, then `min` over limbs of (torso smoothly united with the limb).
pub fn body_sdf(sk: &Skeleton, p: &Point3<f64>, blend: f64) -> f64 {
    let union_of = |part: Part| {
        sk.bones
            .iter()
            .filter(|b| b.part == part)
            .map(|b| segment_distance(p, &b.a, &b.b) - b.radius)
            .fold(f64::INFINITY, |acc, d| if acc.is_infinite() { d } else { smooth_min(acc, d, blend) })
    };
    let torso = union_of(Part::Torso);
    (0..4).map(|k| smooth_min(torso, union_of(Part::Limb(k)), blend)).fold(torso, f64::min)
}

/// Evens out the triangles that marching tetrahedra leaves (its edges range over 15x in
/// length; slivers would make any skinning look like extreme stretching): each round moves
/// every vertex halfway to the centroid of its neighbours within the tangent plane, then back
/// onto the surface `f = 0` by two Newton steps along the gradient (tangential Laplacian
/// smoothing with reprojection). Connectivity is unchanged, so the mesh stays closed.
fn relax(f: &dyn Fn(&Point3<f64>) -> f64, positions: &mut [f32], neighbours: &[Vec<u32>], rounds: usize, step: f64) {
    let gradient = |p: &Point3<f64>| {
        let e = |k: usize| Vector3::ith(k, step);
        Vector3::from_fn(|k, _| (f(&(p + e(k))) - f(&(p - e(k)))) / (2.0 * step))
    };
    let at = |s: &[f32], i: usize| Point3::new(s[3 * i] as f64, s[3 * i + 1] as f64, s[3 * i + 2] as f64);
    let floor = 0.5 * mean_edge_length(positions, neighbours);
    let shortest = |s: &[f32], p: &Point3<f64>, nb: &[u32]| {
        nb.iter().map(|&n| (at(s, n as usize) - p).norm()).fold(f64::INFINITY, f64::min)
    };
    for _ in 0..rounds {
        // In place (Gauss-Seidel), so the guard below sees the neighbours where they are.
        for (i, nb) in neighbours.iter().enumerate() {
            let p = at(positions, i);
            let c = nb.iter().map(|&n| at(positions, n as usize).coords).sum::<Vector3<f64>>() / nb.len() as f64;
            let n = gradient(&p).normalize();
            let d = c - p.coords;
            let mut q = p + 0.5 * (d - n * n.dot(&d));
            for _ in 0..2 {
                let g = gradient(&q);
                q -= g * (f(&q) / g.norm_squared().max(1e-12));
            }
            // Guard: a move may not bring a neighbour closer than half the mean edge (or than
            // it already was). Without it, the few vertices round the tip of a thin capsule
            // (hands, toes) slide together over the rounds.
            if shortest(positions, &q, nb) >= shortest(positions, &p, nb).min(floor) {
                positions[3 * i..3 * i + 3].copy_from_slice(&[q.x as f32, q.y as f32, q.z as f32]);
            }
        }
    }
}

/// Skinning weights by diffusion over the surface: one-hot on the joint of the nearest segment,
/// then `iterations` rounds of averaging each vertex with its neighbours (explicit heat flow
/// with the uniform graph Laplacian); the four largest weights kept and normalised.
fn diffused_weights(sk: &Skeleton, positions: &[f32], neighbours: &[Vec<u32>], width: f64) -> Vec<[(u16, f32); 4]> {
    let nj = sk.names.len();
    let nv = positions.len() / 3;
    let mut w = vec![0.0f64; nv * nj];
    // The skeleton's segments, each owned by the joint it leaves: joint -> each child joint, and
    // for a joint without children (head, hands, feet) joint -> the far end of its capsule. A
    // vertex belongs to the nearest segment: the crotch to the pelvis's hip segments, the
    // armpit to the thorax's collar segments, as in a hand-made rig. (The nearest capsule would
    // not do: where capsules blend, the nearest one is often a neighbour's.)
    let segments: Vec<(usize, Point3<f64>, Point3<f64>)> = (0..nj)
        .flat_map(|j| {
            let children: Vec<(usize, Point3<f64>, Point3<f64>)> =
                (0..nj).filter(|&c| sk.parents[c] == Some(j)).map(|c| (j, sk.rest[j], sk.rest[c])).collect();
            if children.is_empty() {
                let end = sk
                    .bones
                    .iter()
                    .filter(|b| b.joint == j)
                    .map(|b| b.b)
                    .max_by(|a, b| (a - sk.rest[j]).norm().total_cmp(&(b - sk.rest[j]).norm()))
                    .expect("every leaf joint has a capsule");
                vec![(j, sk.rest[j], end)]
            } else {
                children
            }
        })
        .collect();
    for (i, v) in positions.chunks_exact(3).enumerate() {
        let p = Point3::new(v[0] as f64, v[1] as f64, v[2] as f64);
        let nearest = segments
            .iter()
            .min_by(|a, b| segment_distance(&p, &a.1, &a.2).total_cmp(&segment_distance(&p, &b.1, &b.2)))
            .expect("the skeleton has bones");
        w[i * nj + nearest.0] = 1.0;
    }
    let mean_edge = mean_edge_length(positions, neighbours);
    // Averaging with the neighbours (half weight on the vertex itself) spreads a spike by a
    // variance of about mean_edge^2 / 4 per round: enough rounds for a standard deviation of
    // `width`.
    let iterations = (4.0 * (width / mean_edge).powi(2)).ceil() as usize;
    let mut next = w.clone();
    for _ in 0..iterations {
        for (i, nb) in neighbours.iter().enumerate() {
            let inv = 0.5 / nb.len() as f64;
            for j in 0..nj {
                let s: f64 = nb.iter().map(|&n| w[n as usize * nj + j]).sum();
                next[i * nj + j] = 0.5 * w[i * nj + j] + inv * s;
            }
        }
        std::mem::swap(&mut w, &mut next);
    }
    w.chunks_exact(nj)
        .map(|row| {
            let mut ranked: Vec<(u16, f64)> = row.iter().enumerate().map(|(j, &x)| (j as u16, x)).collect();
            ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
            ranked.truncate(4);
            let s: f64 = ranked.iter().map(|x| x.1).sum();
            let mut out = [(0u16, 0f32); 4];
            for (k, &(j, x)) in ranked.iter().enumerate() {
                out[k] = (j, (x / s) as f32);
            }
            out
        })
        .collect()
}

/// The mannequin mesh in its rest pose.
#[derive(Debug, Clone)]
pub struct Mannequin {
    pub skeleton: Skeleton,
    pub topology: Topology,
    /// Rest positions `[vertices][3]`.
    pub positions: Vec<f32>,
    /// Up to four (skeleton joint, weight) per vertex, weights summing to 1.
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

/// Standard deviation of the weights' diffusion, as a fraction of the height (times the limb
/// girth when above one: thicker limbs need wider blend zones not to fold, a bend of angle a
/// folding the inside of a limb of radius r when the zone is shorter than a r): the blend zone
/// across each joint is a few times this wide.
const SKIN_BLEND_WIDTH: f64 = 0.04;

/// Rounds of edge flips, each followed by two of tangential smoothing, after marching
/// tetrahedra.
const RELAX_ROUNDS: usize = 6;

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
    // Marching tetrahedra on a grid fine enough for the thinnest capsule (so that wrists and
    // ankles are never cut), then edge collapses down to the requested vertex count: edges
    // shorter than 4/5 of the target length merge (isotropic remeshing), the target length
    // refined from the count obtained.
    let area: f64 =
        sk.bones.iter().map(|b| 2.0 * std::f64::consts::PI * b.radius * ((b.b - b.a).norm() + 2.0 * b.radius)).sum();
    let thinnest = sk.bones.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    let mut grid = (area / (1.5 * target_vertices as f64)).sqrt().min(0.5 * thinnest);
    let (fine_p, fine_t) = loop {
        let (p, t) = polygonise(&f, lo, hi, grid);
        if p.len() / 3 >= target_vertices * 5 / 4 {
            break (p, t);
        }
        grid *= 0.8;
    };
    // A closed triangle mesh has about twice as many triangles as vertices.
    let mut edge = (4.0 * area / (3f64.sqrt() * 2.0 * target_vertices as f64)).sqrt();
    let mut best: Option<(Vec<f32>, Vec<[u32; 3]>)> = None;
    for _ in 0..6 {
        let (p, t) = collapse_short_edges(&fine_p, &fine_t, 0.8 * edge, None);
        let ratio = (p.len() / 3) as f64 / target_vertices as f64;
        best = Some((p, t));
        if (0.93..=1.07).contains(&ratio) {
            break;
        }
        edge *= ratio.sqrt();
    }
    let (mut positions, mut tris) = best.expect("at least one pass");
    let nv = positions.len() / 3;
    // Then rounds of edge flips, each followed by two rounds of tangential smoothing.
    for _ in 0..RELAX_ROUNDS {
        flip_edges(&positions, &mut tris);
        relax(&f, &mut positions, &vertex_neighbours(nv, &tris), 2, 1e-3 * shape.height);
    }
    let neighbours = vertex_neighbours(nv, &tris);
    let topology = Topology::new(nv, tris, None)?;
    let weights =
        diffused_weights(&sk, &positions, &neighbours, SKIN_BLEND_WIDTH * shape.height * shape.limb_girth.max(1.0));
    Ok(Mannequin { skeleton: sk, topology, positions, weights })
}

impl Mannequin {
    /// Rest world transforms of the joints (the A-pose: no rotation, at the rest positions).
    pub fn rest_transforms(&self) -> Vec<Isometry3<f64>> {
        self.skeleton.rest.iter().map(|p| Isometry3::translation(p.x, p.y, p.z)).collect()
    }

    /// Dual-quaternion skinning: the mesh posed by the joints' world transforms `world` (one per
    /// skeleton joint). Each joint's skinning transform `W_j W_j,rest^-1` as a unit dual
    /// quaternion; a vertex blends those of its joints (signs aligned with its first joint's),
    /// normalises, and applies the rigid transform obtained (Kavan et al. 2007, eq. 4-5).
    pub fn pose(&self, world: &[Isometry3<f64>]) -> Vec<f32> {
        self.positions
            .chunks_exact(3)
            .zip(self.vertex_dual_quaternions(world))
            .flat_map(|(v, (real, du))| {
                let (rv, dv) = (real.imag(), du.imag());
                let p = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                let q =
                    p + 2.0 * rv.cross(&(rv.cross(&p) + real.w * p)) + 2.0 * (real.w * dv - du.w * rv + rv.cross(&dv));
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect()
    }

    /// The rotation that skinning applies at each vertex for the pose `world` (the real part of
    /// its blended dual quaternion): what a rest normal there should turn into. A triangle
    /// whose posed normal points against its vertices' rotated rest normal has folded over.
    pub fn vertex_rotations(&self, world: &[Isometry3<f64>]) -> Vec<UnitQuaternion<f64>> {
        self.vertex_dual_quaternions(world).map(|(real, _)| UnitQuaternion::new_unchecked(real)).collect()
    }

    /// Each vertex's blended, normalised dual quaternion (real, dual).
    fn vertex_dual_quaternions(
        &self,
        world: &[Isometry3<f64>],
    ) -> impl Iterator<Item = (Quaternion<f64>, Quaternion<f64>)> + '_ {
        assert_eq!(world.len(), self.skeleton.names.len(), "one transform per skeleton joint");
        let joints: Vec<(Quaternion<f64>, Quaternion<f64>)> = world
            .iter()
            .zip(self.rest_transforms())
            .map(|(w, r)| {
                let s = w * r.inverse();
                let q = *s.rotation.quaternion();
                (q, Quaternion::from_imag(s.translation.vector) * q * 0.5)
            })
            .collect();
        self.weights.iter().map(move |w| {
            let q0 = joints[w[0].0 as usize].0;
            let zero = Quaternion::new(0.0, 0.0, 0.0, 0.0);
            let (mut real, mut du) = (zero, zero);
            for &(j, x) in w {
                let (q, d) = joints[j as usize];
                // q and -q are the same rotation: blend on q0's side.
                let x = if q.dot(&q0) < 0.0 { -(x as f64) } else { x as f64 };
                real += q * x;
                du += d * x;
            }
            let n = real.norm();
            (real / n, du / n)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_parse_from_names_and_parameters() {
        assert_eq!(BodyShape::parse("heavy").unwrap(), BodyShape::heavy());
        let s = BodyShape::parse("slim, height=2.0,limb_girth=0.9").unwrap();
        assert_eq!((s.height, s.limb_girth, s.torso_girth), (2.0, 0.9, BodyShape::slim().torso_girth));
        for bad in ["tall", "height=abc", "height=9", "girth=1", "height=1.8,slim"] {
            assert!(BodyShape::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn watertight_manifold_and_shape_dependent() {
        let a = mannequin(&BodyShape::average(), 3000).unwrap();
        let b = mannequin(&BodyShape::heavy(), 3000).unwrap();
        for m in [&a, &b] {
            let n = m.topology.n_vertices();
            assert!((2400..=3600).contains(&n), "{n} vertices for a target of 3000");
            assert!(m.topology.is_closed_manifold(), "not a closed 2-manifold");
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
        assert!(big.topology.is_closed_manifold());
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
        // Bend the left elbow by 2 rad: no triangle flips, no edge stretches past 2.5x.
        let mut world = m.rest_transforms();
        let elbow = m.skeleton.names.iter().position(|&n| n == "lradius").unwrap();
        let bend = UnitQuaternion::from_euler_angles(0.0, 0.0, 2.0);
        let pivot = m.skeleton.rest[elbow];
        for j in [elbow, elbow + 1] {
            let local = world[j];
            world[j] = Isometry3::translation(pivot.x, pivot.y, pivot.z)
                * bend
                * Isometry3::translation(-pivot.x, -pivot.y, -pivot.z)
                * local;
        }
        let bent = m.pose(&world);
        let turn = m.vertex_rotations(&world);
        let p = |s: &[f32], i: u32| {
            Vector3::new(s[3 * i as usize] as f64, s[3 * i as usize + 1] as f64, s[3 * i as usize + 2] as f64)
        };
        for t in m.topology.triangles() {
            let n0 =
                (p(&m.positions, t[1]) - p(&m.positions, t[0])).cross(&(p(&m.positions, t[2]) - p(&m.positions, t[0])));
            let n1 = (p(&bent, t[1]) - p(&bent, t[0])).cross(&(p(&bent, t[2]) - p(&bent, t[0])));
            // Against the rest normal as the skinning turns it (the forearm's normals turn by 2 rad).
            let expected: Vector3<f64> = t.iter().map(|&v| turn[v as usize] * n0).sum();
            assert!(expected.dot(&n1) > 0.0, "a triangle folded over");
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let r = (p(&bent, a) - p(&bent, b)).norm() / (p(&m.positions, a) - p(&m.positions, b)).norm();
                assert!(r < 2.5, "edge stretched {r}x");
            }
        }
    }
}

//! Correspondence densification (thesis 5.5.1) on real data with a known answer: the KayKit
//! knight's and barbarian's `Walking_A` are the same skeletal motion on two bodies (different
//! meshes and vertex counts), so re-timing the barbarian's clip gives a target whose true map to
//! the knight's frames is the re-timing itself. Five key pairs, a per-part PCA (torso, arms,
//! legs), and the densified map is compared with the truth frame by frame.

use faer::Mat;
use surfcap_formats::shared_layout::read_layout_sequence;
use surfcap_learn::pca::{Pca, PcaMethod};
use surfcap_transfer::correspondence_densification::{DensifyOptions, Span, constrained_path, densify};

/// A sequence's frames (f64, F x 3N) and its vertices cut into the thesis's N = 5 parts
/// (torso with head, two arms, two legs): each vertex goes to the part of the nearest bone of
/// the shared rig at frame 0 (both characters carry the same skeleton, so their parts
/// correspond; the meshes' connected components do not: 15 pieces on the knight, 14 on the
/// barbarian).
struct Clip {
    frames: Vec<Vec<f64>>,
    parts: Vec<Vec<usize>>,
}

/// The part of the bone ending at joint `j` (the rig's joint order, meta.json), if skinned.
fn part_of_joint(name: &str) -> Option<usize> {
    Some(match name {
        "spine" | "chest" | "head" => 0,
        "upperarm.l" | "lowerarm.l" | "wrist.l" | "hand.l" => 1,
        "upperarm.r" | "lowerarm.r" | "wrist.r" | "hand.r" => 2,
        "upperleg.l" | "lowerleg.l" | "foot.l" | "toes.l" => 3,
        "upperleg.r" | "lowerleg.r" | "foot.r" | "toes.r" => 4,
        _ => return None,
    })
}

fn clip(data: &std::path::Path, name: &str) -> Clip {
    let seq = read_layout_sequence(&data.join("kaykit_adventurers").join(name)).unwrap();
    let nv = seq.topology.n_vertices();
    let frames: Vec<Vec<f64>> = seq.positions.chunks(3 * nv).map(|f| f.iter().map(|&x| x as f64).collect()).collect();
    let joints = seq.joints.expect("KayKit clips carry joints.npy");
    let at = |j: usize| {
        let m = &joints.matrices[16 * j..16 * j + 16];
        [m[3] as f64, m[7] as f64, m[11] as f64]
    };
    // Bones (parent joint -> joint) of the skinned joints, with their part.
    let bones: Vec<([f64; 3], [f64; 3], usize)> = (0..joints.names.len())
        .filter_map(|j| Some((at(joints.parents[j]?), at(j), part_of_joint(&joints.names[j])?)))
        .collect();
    assert_eq!(bones.len(), 19, "{name}: the rig's skinned bones");
    let dist2 = |p: &[f64], (a, b, _): &([f64; 3], [f64; 3], usize)| {
        let ab: Vec<f64> = (0..3).map(|k| b[k] - a[k]).collect();
        let ap: Vec<f64> = (0..3).map(|k| p[k] - a[k]).collect();
        let len2: f64 = ab.iter().map(|x| x * x).sum();
        let t =
            if len2 > 0.0 { (ab.iter().zip(&ap).map(|(x, y)| x * y).sum::<f64>() / len2).clamp(0.0, 1.0) } else { 0.0 };
        (0..3).map(|k| (ap[k] - t * ab[k]).powi(2)).sum::<f64>()
    };
    let mut parts = vec![Vec::new(); 5];
    for v in 0..nv {
        let p = &frames[0][3 * v..3 * v + 3];
        let nearest = bones.iter().min_by(|x, y| dist2(p, x).total_cmp(&dist2(p, y))).unwrap();
        parts[nearest.2].push(v);
    }
    Clip { frames, parts }
}

/// The clip played at source time `warp(t)` for t = 0, 1, ... while within the clip (linear
/// blends of the two nearest frames).
fn retimed(c: &Clip, warp: impl Fn(f64) -> f64) -> Clip {
    let last = (c.frames.len() - 1) as f64;
    let mut frames = Vec::new();
    for t in 0.. {
        let tau = warp(t as f64);
        if tau > last + 1e-9 {
            break;
        }
        let (a, w) = (tau.floor() as usize, tau - tau.floor());
        let b = (a + 1).min(c.frames.len() - 1);
        frames.push(c.frames[a].iter().zip(&c.frames[b]).map(|(x, y)| (1.0 - w) * x + w * y).collect());
    }
    Clip { frames, parts: c.parts.clone() }
}

/// Per part: PCA coefficients (up to 20) of the part's vertices after removing each frame's
/// centroid (the clips are in place; this removes the body's bob and sway from every part).
fn coefficients(c: &Clip) -> Vec<Mat<f64>> {
    let nv = c.frames[0].len() / 3;
    let centred: Vec<Vec<f64>> = c
        .frames
        .iter()
        .map(|f| {
            let mut m = [0.0; 3];
            for v in 0..nv {
                for k in 0..3 {
                    m[k] += f[3 * v + k] / nv as f64;
                }
            }
            f.iter().enumerate().map(|(i, x)| x - m[i % 3]).collect()
        })
        .collect();
    c.parts
        .iter()
        .map(|p| {
            let y = Mat::from_fn(centred.len(), 3 * p.len(), |i, j| centred[i][3 * p[j / 3] + j % 3]);
            let pca = Pca::fit(y.as_ref(), 20, PcaMethod::Auto).unwrap();
            pca.project(y.as_ref()).unwrap()
        })
        .collect()
}

/// The whole body as one part (for comparison).
fn coefficients_whole(c: &Clip) -> Mat<f64> {
    let all: Vec<usize> = (0..c.frames[0].len() / 3).collect();
    coefficients(&Clip { frames: c.frames.clone(), parts: vec![all] }).remove(0)
}

/// Mean and max of |i - warp(j)| over the path's nodes (source frames).
fn errors(pairs: &[(usize, usize)], warp: impl Fn(f64) -> f64) -> (f64, f64) {
    let e: Vec<f64> = pairs.iter().map(|&(i, j)| (i as f64 - warp(j as f64)).abs()).collect();
    (e.iter().sum::<f64>() / e.len() as f64, e.iter().cloned().fold(0.0, f64::max))
}

/// The best path with the same constraints through a cost `|i - map(j)|`: with the true warp,
/// the floor any frame-to-frame map has (source frames fall between target frames); with the
/// map interpolating linearly between the keys, what a learner without densification would
/// guess, on the same grid.
fn path_following(map: impl Fn(f64) -> f64, keys: &[(usize, usize)], fs: usize, ft: usize) -> Vec<(usize, usize)> {
    let c = Mat::from_fn(fs, ft, |i, j| (i as f64 - map(j as f64)).abs());
    constrained_path(c.as_ref(), keys, 3, Span::Ends).unwrap().pairs
}

/// The first and last frames count as keys here, as they do for the path (`Span::Ends`).
fn linear_between_keys(keys: &[(usize, usize)], last: (usize, usize), j: f64) -> f64 {
    let mut anchors = vec![(0, 0)];
    anchors.extend(keys.iter().filter(|&&k| k != (0, 0) && k != last));
    anchors.push(last);
    let w = anchors.windows(2).find(|w| w[0].1 as f64 <= j && j <= w[1].1 as f64).unwrap();
    let ((a, b), (c, d)) = (w[0], w[1]);
    a as f64 + (c - a) as f64 * (j - b as f64) / (d - b) as f64
}

/// Densifies knight `clip` against the barbarian's re-timed by 1.3x and by 1.3x with a wobble;
/// returns per warp (name, densified mean and max error, the best path's on the truth, the
/// linear-between-keys path's), after printing them.
fn measure(data: &std::path::Path, clip_name: &str) -> Vec<(&'static str, [f64; 6])> {
    let knight = clip(data, &format!("knight_{clip_name}"));
    let barbarian = clip(data, &format!("barbarian_{clip_name}"));
    for c in [&knight, &barbarian] {
        let sizes: Vec<usize> = c.parts.iter().map(Vec::len).collect();
        assert!(sizes.iter().all(|&n| n > 100), "{clip_name}: every part has vertices: {sizes:?}");
    }
    let xs = coefficients(&knight);
    let fs = knight.frames.len();
    let mut out = Vec::new();
    for (name, warp) in [
        ("1.3x", Box::new(|t: f64| 1.3 * t) as Box<dyn Fn(f64) -> f64>),
        // 1.3x with a 12-frame wobble of +-1.5 source frames that vanishes at the keys (every
        // 6 target frames): a map linear between keys misses it, the densified map must not.
        ("1.3x + wobble", Box::new(|t: f64| 1.3 * t + 1.5 * (std::f64::consts::TAU * t / 12.0).sin())),
    ] {
        let target = retimed(&barbarian, &warp);
        let ys = coefficients(&target);
        let ft = target.frames.len();
        // Five key pairs at target frames that are multiples of 6, spread from the first to the
        // last, each paired with the nearest knight frame.
        let sixes = (ft - 1) / 6;
        let keys: Vec<(usize, usize)> = (0..5)
            .map(|k| {
                let j = 6 * ((k * sixes) as f64 / 4.0).round() as usize;
                (warp(j as f64).round() as usize, j)
            })
            .collect();
        let d = densify(&xs, &ys, &keys, &DensifyOptions::default()).unwrap();
        assert_eq!((d.pairs[0], *d.pairs.last().unwrap()), ((0, 0), (fs - 1, ft - 1)));
        let (mean, max) = errors(&d.pairs, &warp);
        let (floor_mean, floor_max) = errors(&path_following(&warp, &keys, fs, ft), &warp);
        let (lin_mean, lin_max) =
            errors(&path_following(|j| linear_between_keys(&keys, (fs - 1, ft - 1), j), &keys, fs, ft), &warp);
        let whole: Vec<Mat<f64>> = vec![coefficients_whole(&knight), coefficients_whole(&target)];
        let w = densify(&whole[..1], &whole[1..], &keys, &DensifyOptions::default()).unwrap();
        let (whole_mean, whole_max) = errors(&w.pairs, &warp);
        eprintln!(
            "{clip_name} {name}: knight {fs} frames, barbarian re-timed {ft} frames, {} parts, keys {keys:?}: {} \
             pairs, cost {:.1}; error |i - warp(j)| in source frames: mean {mean:.3} max {max:.3} (whole body as \
             one part: {whole_mean:.3} / {whole_max:.3}; linear between keys: {lin_mean:.3} / {lin_max:.3}; best \
             path on the truth: {floor_mean:.3} / {floor_max:.3})",
            xs.len(),
            d.pairs.len(),
            d.cost
        );
        out.push((name, [mean, max, floor_mean, floor_max, lin_mean, lin_max]));
    }
    out
}

#[test]
fn knight_and_retimed_barbarian_walks_are_matched_within_a_frame() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    for clip_name in ["Walking_A", "Walking_C", "Cheer"] {
        for (name, [mean, max, floor_mean, _, lin_mean, _]) in measure(&data, clip_name) {
            assert!(mean < 1.0, "{clip_name} {name}: mean error {mean} source frames");
            assert!(max < 2.0, "{clip_name} {name}: max error {max} source frames");
            // Within a fifth of a frame of the best any path on this grid can do.
            assert!(mean < floor_mean + 0.2, "{clip_name} {name}: mean error {mean}, best path {floor_mean}");
            if name != "1.3x" {
                assert!(mean < 0.7 * lin_mean, "{clip_name} {name}: mean error {mean}, linear between keys {lin_mean}");
            }
        }
    }
}

//! A closed tube whose centre line bends like a swimming snake (a travelling wave of heading
//! angle along the body) while it crawls forward on the ground plane.
//!
//! Centre line: heading `phi(s, t) = a * sin(2 pi (s / wavelength - frequency t) + phase)` at arc
//! length `s`; position is the integral of `(cos phi, 0, sin phi)` ds, plus a forward travel of
//! `speed * t` along the mean heading. Rings of `segments` vertices lie in the plane normal to
//! the centre line, radius tapering to the ends; one apex vertex closes each end, so the mesh is
//! closed and 2-manifold.

use surfcap_mesh::{Error, Sequence, Subject, Topology, Units, UpAxis};

/// Shape and motion of the built-in tube.
#[derive(Debug, Clone)]
pub struct WormParams {
    /// Rings along the body (>= 2).
    pub rings: usize,
    /// Vertices per ring (>= 3).
    pub segments: usize,
    /// Frames per sequence.
    pub frames: usize,
    pub fps: f64,
    /// Body length and radius, metres.
    pub length: f64,
    pub radius: f64,
    /// Phase offset of the motion; different seeds give different but reproducible motions.
    pub seed: u64,
}

impl Default for WormParams {
    fn default() -> Self {
        WormParams { rings: 40, segments: 16, frames: 60, fps: 30.0, length: 1.2, radius: 0.08, seed: 0 }
    }
}

struct Motion {
    amplitude: f64,
    wavelength: f64,
    frequency: f64,
    speed: f64,
}

fn topology(p: &WormParams) -> Result<Topology, Error> {
    let (r, s) = (p.rings, p.segments);
    let ring = |i: usize, j: usize| (i * s + (j % s)) as u32;
    let (head, tail) = ((r * s) as u32, (r * s + 1) as u32);
    let mut t = Vec::with_capacity(2 * r * s);
    for i in 0..r - 1 {
        for j in 0..s {
            t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
            t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
        }
    }
    for j in 0..s {
        t.push([head, ring(0, j), ring(0, j + 1)]);
        t.push([tail, ring(r - 1, j + 1), ring(r - 1, j)]);
    }
    Topology::new(r * s + 2, t, None)
}

fn frame(p: &WormParams, m: &Motion, time: f64, phase: f64, out: &mut Vec<f32>) {
    let (r, s) = (p.rings, p.segments);
    let ds = p.length / (r - 1) as f64;
    let heading =
        |sa: f64| m.amplitude * (std::f64::consts::TAU * (sa / m.wavelength - m.frequency * time) + phase).sin();
    // Integrate the centre line (midpoint rule), then centre it and add the travel.
    let mut centre = Vec::with_capacity(r);
    let mut c = [0.0f64, 0.0];
    for i in 0..r {
        let phi = heading(i as f64 * ds);
        centre.push((c, phi));
        let mid = heading((i as f64 + 0.5) * ds);
        c[0] += ds * mid.cos();
        c[1] += ds * mid.sin();
    }
    let travel = m.speed * time;
    let height = p.radius * 1.05;
    let start = out.len();
    let radius = |i: usize| {
        let u = i as f64 / (r - 1) as f64;
        p.radius * (0.35 + 0.65 * (std::f64::consts::PI * u).sin().powf(0.5))
    };
    for (i, &(c, phi)) in centre.iter().enumerate() {
        let (n, rad) = ([-phi.sin(), phi.cos()], radius(i));
        for j in 0..s {
            let th = std::f64::consts::TAU * j as f64 / s as f64;
            let (a, b) = (th.cos() * rad, th.sin() * rad);
            out.extend_from_slice(&[(c[0] + travel + a * n[0]) as f32, (height + b) as f32, (c[1] + a * n[1]) as f32]);
        }
    }
    for (i, sign) in [(0usize, -1.0f64), (r - 1, 1.0)] {
        let (c, phi) = centre[i];
        let d = sign * radius(i) * 0.8;
        out.extend_from_slice(&[(c[0] + travel + d * phi.cos()) as f32, height as f32, (c[1] + d * phi.sin()) as f32]);
    }
    debug_assert_eq!(out.len() - start, 3 * (r * s + 2));
}

/// The built-in subject: sequences `slither` (travelling wave, crawling forward) and `curl`
/// (slow large bends in place), at `params.fps`, +y up, metres.
pub fn worm_subject(params: &WormParams) -> Result<Subject, Error> {
    if params.rings < 2 || params.segments < 3 || params.frames == 0 {
        return Err(surfcap_mesh::Error::new(
            surfcap_mesh::ErrorKind::Unsupported,
            "the built-in tube needs at least 2 rings, 3 segments and 1 frame",
        ));
    }
    let topo = topology(params)?;
    // A seed only shifts the phase: small, reproducible, platform-independent.
    let phase = (params.seed % 1000) as f64 * 0.001 * std::f64::consts::TAU;
    let motions = [
        ("slither", Motion { amplitude: 0.5, wavelength: params.length * 0.8, frequency: 1.0, speed: 0.25 }),
        ("curl", Motion { amplitude: 1.2, wavelength: params.length * 2.0, frequency: 0.4, speed: 0.0 }),
    ];
    let mut seqs = Vec::new();
    for (name, m) in &motions {
        let mut pos = Vec::with_capacity(params.frames * 3 * topo.n_vertices());
        for f in 0..params.frames {
            frame(params, m, f as f64 / params.fps, phase, &mut pos);
        }
        seqs.push(Sequence::new(*name, topo.n_vertices(), pos)?.with_tags(vec![name.to_string()]));
    }
    Subject::new("worm", topo, seqs, params.fps, UpAxis::PosY, Units::metres())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_two_manifold_and_deterministic() {
        let p = WormParams { rings: 6, segments: 5, frames: 4, ..Default::default() };
        let s = worm_subject(&p).unwrap();
        assert!(s.topology().is_closed_manifold());
        assert_eq!(surfcap_mesh::connected_components(s.topology()).count, 1);
        assert_eq!(worm_subject(&p).unwrap(), s);
        assert_ne!(worm_subject(&WormParams { seed: 7, ..p }).unwrap(), s);
        // It crawls forward.
        let seq = &s.sequences()[0];
        let x0: f32 = seq.frame(0).chunks(3).map(|v| v[0]).sum();
        let x1: f32 = seq.frame(3).chunks(3).map(|v| v[0]).sum();
        assert!(x1 > x0);
    }
}

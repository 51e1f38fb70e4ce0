//! The triangle topology shared by every frame of a subject.

use crate::error::{Error, ErrorKind, Location, Result, err};

/// Optional texture atlas: per-corner texture coordinates (OBJ `vt` + `f a/b`).
#[derive(Debug, Clone, PartialEq)]
pub struct UvAtlas {
    /// Texture coordinates (u, v).
    pub coords: Vec<[f32; 2]>,
    /// For each triangle, the index into `coords` of each corner.
    pub corners: Vec<[u32; 3]>,
}

/// One triangle topology: vertex count, triangles (0-based, counter-clockwise), optional UVs.
///
/// Invariants (checked by [`Topology::new`]): every index is below `n_vertices`; no triangle
/// repeats a vertex; there is at least one triangle; a UV atlas has one corner triple per triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    n_vertices: usize,
    triangles: Vec<[u32; 3]>,
    uv: Option<UvAtlas>,
}

impl Topology {
    pub fn new(n_vertices: usize, triangles: Vec<[u32; 3]>, uv: Option<UvAtlas>) -> Result<Self> {
        if n_vertices == 0 {
            return Err(err!(Empty, "a topology needs at least one vertex"));
        }
        if n_vertices > u32::MAX as usize {
            return Err(err!(Unsupported, "{n_vertices} vertices exceed the 32-bit index limit"));
        }
        if triangles.is_empty() {
            return Err(err!(Empty, "no triangles: expected at least one face"));
        }
        for (i, t) in triangles.iter().enumerate() {
            check_triangle(t, n_vertices).map_err(|e| e.at(Location::Face(i)))?;
        }
        if let Some(uv) = &uv {
            if uv.corners.len() != triangles.len() {
                return Err(err!(
                    Shape,
                    "UV atlas has {} corner triples, expected one per triangle ({})",
                    uv.corners.len(),
                    triangles.len()
                ));
            }
            for (i, c) in uv.corners.iter().enumerate() {
                if let Some(&bad) = c.iter().find(|&&k| k as usize >= uv.coords.len()) {
                    return Err(err!(
                        IndexOutOfRange,
                        "texture coordinate index {bad} out of range (there are {})",
                        uv.coords.len()
                    )
                    .at(Location::Face(i)));
                }
            }
        }
        Ok(Topology { n_vertices, triangles, uv })
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    pub fn uv(&self) -> Option<&UvAtlas> {
        self.uv.as_ref()
    }

    /// Whether the surface is closed and 2-manifold with consistent orientation: every
    /// directed edge is used by exactly one triangle and its reverse by exactly one other (no
    /// boundary, no edge shared by three triangles, no flipped neighbour).
    pub fn is_closed_manifold(&self) -> bool {
        let mut directed: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        directed.iter().all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
    }

    /// Index of the first triangle that differs from `other`'s, or a vertex-count mismatch.
    /// `None` when both topologies have the same vertex count and the same triangles in order.
    pub fn first_difference(&self, other: &Topology) -> Option<String> {
        if self.n_vertices != other.n_vertices {
            return Some(format!("{} vertices, expected {} as in the template", other.n_vertices, self.n_vertices));
        }
        first_triangle_difference(&self.triangles, &other.triangles)
    }

    /// Number of triangles whose area is zero (or below `rel_eps` times the squared bounding-box
    /// diagonal) in the given frame positions. Real captures have some (quantised vertices); the
    /// data layer reports them, algorithms decide how to treat them.
    pub fn count_degenerate_triangles(&self, positions: &[f32], rel_eps: f64) -> usize {
        let p = |i: u32| {
            let k = 3 * i as usize;
            [positions[k] as f64, positions[k + 1] as f64, positions[k + 2] as f64]
        };
        let (lo, hi) = crate::bounding_box(positions);
        let diag2: f64 = (0..3).map(|k| ((hi[k] - lo[k]) as f64).powi(2)).sum();
        let eps = rel_eps * diag2;
        self.triangles
            .iter()
            .filter(|t| {
                let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
                (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() * 0.5 <= eps
            })
            .count()
    }
}

/// Check one triangle's indices against the vertex count.
pub fn check_triangle(t: &[u32; 3], n_vertices: usize) -> Result<()> {
    if let Some(&bad) = t.iter().find(|&&k| k as usize >= n_vertices) {
        return Err(err!(
            IndexOutOfRange,
            "vertex index {} out of range: expected 1..={} (1-based)",
            bad as u64 + 1,
            n_vertices
        ));
    }
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return Err(Error::new(
            ErrorKind::DegenerateFace,
            format!(
                "degenerate triangle ({}, {}, {}) uses a vertex twice: expected three distinct vertices",
                t[0] + 1,
                t[1] + 1,
                t[2] + 1
            ),
        ));
    }
    Ok(())
}

/// Where two triangle lists first differ, in words (`None` when they are equal): the first
/// triangle that differs, else the counts.
pub fn first_triangle_difference(expected: &[[u32; 3]], got: &[[u32; 3]]) -> Option<String> {
    if let Some(i) = expected.iter().zip(got).position(|(a, b)| a != b) {
        let (a, b) = (expected[i], got[i]);
        return Some(format!(
            "triangle {i} is ({}, {}, {}), expected ({}, {}, {}) as in the template (1-based)",
            b[0] + 1,
            b[1] + 1,
            b[2] + 1,
            a[0] + 1,
            a[1] + 1,
            a[2] + 1
        ));
    }
    if expected.len() != got.len() {
        return Some(format!("{} triangles, expected {} as in the template", got.len(), expected.len()));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_manifold_detects_boundaries_and_flips() {
        // A tetrahedron is closed; without a face it has a boundary; with a face reversed its
        // orientation is inconsistent.
        let tet = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        assert!(Topology::new(4, tet.clone(), None).unwrap().is_closed_manifold());
        assert!(!Topology::new(4, tet[..3].to_vec(), None).unwrap().is_closed_manifold());
        let mut flipped = tet;
        flipped[0] = [0, 1, 2];
        assert!(!Topology::new(4, flipped, None).unwrap().is_closed_manifold());
    }

    #[test]
    fn rejects_bad_triangles() {
        let e = Topology::new(3, vec![[0, 1, 3]], None).unwrap_err();
        assert_eq!(e.kind, ErrorKind::IndexOutOfRange);
        assert_eq!(e.location, Some(Location::Face(0)));
        let e = Topology::new(3, vec![[0, 1, 2], [0, 0, 2]], None).unwrap_err();
        assert_eq!(e.kind, ErrorKind::DegenerateFace);
        assert_eq!(e.location, Some(Location::Face(1)));
        assert_eq!(Topology::new(3, vec![], None).unwrap_err().kind, ErrorKind::Empty);
    }

    #[test]
    fn reports_first_difference() {
        let a = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], None).unwrap();
        let b = Topology::new(4, vec![[0, 1, 2], [0, 3, 2]], None).unwrap();
        assert!(a.first_difference(&a).is_none());
        assert!(a.first_difference(&b).unwrap().starts_with("triangle 1"));
    }

    #[test]
    fn counts_zero_area_triangles() {
        let t = Topology::new(4, vec![[0, 1, 2], [0, 1, 3]], None).unwrap();
        let p = [0., 0., 0., 1., 0., 0., 0., 1., 0., 2., 0., 0.];
        assert_eq!(t.count_degenerate_triangles(&p, 0.0), 1);
    }
}

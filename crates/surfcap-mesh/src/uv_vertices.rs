//! A mesh with a UV atlas (texture coordinates indexed per triangle corner, as OBJ's `vt` and
//! [`UvAtlas`] hold them) laid out as GPUs and glTF need it: one vertex per distinct
//! (vertex, texture coordinate) pair, every attribute indexed by one index buffer.
//!
//! Along a seam of the atlas a vertex has several texture coordinates, so it is copied once per
//! extra coordinate. The layout keeps the mesh's own vertices first and in order: vertex `v`
//! stays at index `v` with the coordinate of the first corner (in triangle order) that uses it
//! (a vertex no triangle uses gets coordinate 0), and the copies follow, in the order their
//! corners first appear, each remembering the vertex it copies ([`UvVertices::copies`]). So the
//! mesh's positions and triangles come back exactly from the split ones
//! ([`UvVertices::source`]), and splitting a split mesh again changes nothing.

use crate::topology::{Topology, UvAtlas};

/// The split layout of one topology with a UV atlas (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct UvVertices {
    /// Vertices of the mesh itself (the first `n_vertices` split vertices).
    pub n_vertices: usize,
    /// For each copy (split vertex `n_vertices + j`), the mesh vertex it copies.
    pub copies: Vec<u32>,
    /// Triangles over the split vertices.
    pub triangles: Vec<[u32; 3]>,
    /// For each split vertex, its index into the atlas's coordinates (`None`: a vertex no
    /// triangle uses).
    pub uv_index: Vec<Option<u32>>,
}

impl UvVertices {
    /// Splits `topology`'s vertices along its atlas's seams; `None` when it has no atlas.
    pub fn new(topology: &Topology) -> Option<UvVertices> {
        let uv = topology.uv()?;
        let n = topology.n_vertices();
        let mut uv_index: Vec<Option<u32>> = vec![None; n];
        let mut copies = Vec::new();
        // Per vertex, the (coordinate, split vertex) pairs of its copies: seams are short, so a
        // vertex has few and a linear search beats a hash map.
        let mut seen: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        let mut triangles = Vec::with_capacity(topology.n_triangles());
        for (t, c) in topology.triangles().iter().zip(&uv.corners) {
            let mut out = [0u32; 3];
            for k in 0..3 {
                let (v, tc) = (t[k] as usize, c[k]);
                out[k] = match uv_index[v] {
                    None => {
                        uv_index[v] = Some(tc);
                        v as u32
                    }
                    Some(first) if first == tc => v as u32,
                    Some(_) => match seen[v].iter().find(|(c, _)| *c == tc) {
                        Some(&(_, s)) => s,
                        None => {
                            let s = (n + copies.len()) as u32;
                            copies.push(v as u32);
                            seen[v].push((tc, s));
                            s
                        }
                    },
                };
            }
            triangles.push(out);
        }
        uv_index.resize(n + copies.len(), None);
        // The copies' coordinates, from the pairs recorded above.
        for pairs in &seen {
            for &(tc, s) in pairs {
                uv_index[s as usize] = Some(tc);
            }
        }
        Some(UvVertices { n_vertices: n, copies, triangles, uv_index })
    }

    /// Number of split vertices.
    pub fn len(&self) -> usize {
        self.n_vertices + self.copies.len()
    }

    /// Whether there are no vertices (never, for a valid topology).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The mesh vertex behind split vertex `k`.
    pub fn source(&self, k: usize) -> usize {
        if k < self.n_vertices { k } else { self.copies[k - self.n_vertices] as usize }
    }

    /// `[split vertices][3]` positions from the mesh's `[vertices][3]`.
    pub fn positions(&self, positions: &[f32]) -> Vec<f32> {
        let mut out = Vec::with_capacity(3 * self.len());
        out.extend_from_slice(&positions[..3 * self.n_vertices]);
        for &v in &self.copies {
            out.extend_from_slice(&positions[3 * v as usize..3 * v as usize + 3]);
        }
        out
    }

    /// `[split vertices]` texture coordinates (u, v) from the atlas (0, 0 for an unused vertex).
    pub fn coords(&self, atlas: &UvAtlas) -> Vec<[f32; 2]> {
        self.uv_index.iter().map(|t| t.map_or([0.0, 0.0], |t| atlas.coords[t as usize])).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing the edge 0-2, whose second triangle's corners use other
    /// coordinates at vertex 2 (a seam), and an unused vertex 4.
    fn seam() -> Topology {
        let uv = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 0.5], [0.0, 1.0]],
            corners: vec![[0, 1, 2], [0, 3, 4]],
        };
        Topology::new(5, vec![[0, 1, 2], [0, 2, 3]], Some(uv)).unwrap()
    }

    #[test]
    fn seam_vertices_are_copied_after_the_mesh_vertices() {
        let t = seam();
        let s = UvVertices::new(&t).unwrap();
        assert_eq!(s.n_vertices, 5);
        // Vertex 2 has coordinate 2 then 3; vertex 3 first appears with coordinate 4.
        assert_eq!(s.copies, vec![2]);
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 5, 3]]);
        assert_eq!(s.uv_index, vec![Some(0), Some(1), Some(2), Some(4), None, Some(3)]);
        let coords = s.coords(t.uv().unwrap());
        assert_eq!(coords[5], [0.5, 0.5]);
        assert_eq!(coords[4], [0.0, 0.0]);
        let p: Vec<f32> = (0..15).map(|i| i as f32).collect();
        let sp = s.positions(&p);
        assert_eq!(&sp[15..18], &p[6..9]);
        // The mesh's triangles, back through the copies.
        let back: Vec<[u32; 3]> = s.triangles.iter().map(|t| t.map(|k| s.source(k as usize) as u32)).collect();
        assert_eq!(back, t.triangles());
        // Every corner keeps its coordinate.
        for ((st, c), _) in s.triangles.iter().zip(&t.uv().unwrap().corners).zip(t.triangles()) {
            for k in 0..3 {
                assert_eq!(coords[st[k] as usize], t.uv().unwrap().coords[c[k] as usize]);
            }
        }
    }

    #[test]
    fn no_atlas_no_split() {
        let t = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        assert!(UvVertices::new(&t).is_none());
    }
}

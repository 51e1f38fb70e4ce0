//! Overlapping body parts of a subject's template (thesis 5.4.2, Fig. 5.2; CVPR 2017 sec. 4.2).
//!
//! A part is a set of template vertices; contiguous parts share an overlap region (the band the
//! user's curves delimit in the thesis). The parts form a tree: the root (the torso in the
//! thesis's N = 5 layout) and children (two arms, two legs) that each overlap their parent.
//! During learning every part includes its overlaps; at reconstruction the overlap of a child
//! and its parent is where they are stitched (5.6.2).
//!
//! This module holds the canonical form (every part's full vertex list) and what the other
//! stages ask of it. The ways a user or a proposal produces parts (labels grown into overlaps,
//! cutting planes, vertex loops, skinning weights, connected components, rigidity) all end in
//! [`BodyParts`].

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};
use surfcap_mesh::Topology;

use crate::error::{Error, Result};

/// The `format` field of a canonical parts file.
pub const FORMAT: &str = "surfcap-parts";
/// The version of the canonical parts file written by surfcap.
pub const VERSION: u32 = 1;

/// One body part.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    pub name: String,
    /// The part it hangs from (its name); `None` for the root.
    pub parent: Option<String>,
    /// Template vertices of the part, overlaps included, sorted and unique.
    pub vertices: Vec<u32>,
}

/// A subject's body parts: a tree of overlapping vertex sets covering the template. Unknown
/// fields are refused when read, as in every other parts form.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyParts {
    /// Always [`FORMAT`] in a file.
    pub format: String,
    pub version: u32,
    /// Vertices of the template the parts were made for.
    pub n_vertices: usize,
    pub parts: Vec<Part>,
}

/// A part cut out of the template: its own topology (the triangles whose three corners are in
/// the part) and, for each of its vertices, the template vertex.
#[derive(Debug, Clone)]
pub struct Submesh {
    pub topology: Topology,
    /// `vertices[k]` is the template vertex of the submesh's vertex k.
    pub vertices: Vec<u32>,
}

impl Submesh {
    /// The submesh's positions `[k][3]` taken from whole-template positions.
    pub fn gather(&self, positions: &[f32]) -> Vec<f32> {
        let mut out = Vec::with_capacity(3 * self.vertices.len());
        for &v in &self.vertices {
            let v = v as usize;
            out.extend_from_slice(&positions[3 * v..3 * v + 3]);
        }
        out
    }
}

impl BodyParts {
    /// Checks the parts and builds them: names unique and non-empty, vertices in range,
    /// sorted and unique within a part, every template vertex in some part, one root, parents
    /// named and acyclic. Whether a child that shares no vertex with its parent is allowed
    /// depends on the template's edges, so [`BodyParts::check_fits`] checks it.
    pub fn new(n_vertices: usize, mut parts: Vec<Part>) -> Result<BodyParts> {
        if parts.is_empty() {
            return Err(Error::Parts("no parts: expected at least one".into()));
        }
        for p in &mut parts {
            p.vertices.sort_unstable();
            p.vertices.dedup();
        }
        let b = BodyParts { format: FORMAT.into(), version: VERSION, n_vertices, parts };
        b.validate()?;
        Ok(b)
    }

    /// One part holding every vertex: the whole-body representation (Fig. 5.10's baseline).
    pub fn whole_body(n_vertices: usize) -> BodyParts {
        let part = Part { name: "body".into(), parent: None, vertices: (0..n_vertices as u32).collect() };
        BodyParts { format: FORMAT.into(), version: VERSION, n_vertices, parts: vec![part] }
    }

    /// Checks what [`BodyParts::new`] promises (used after reading a file too).
    pub fn validate(&self) -> Result<()> {
        if self.format != FORMAT {
            return Err(Error::Parts(format!("format \"{}\": expected \"{FORMAT}\"", self.format)));
        }
        if self.version != VERSION {
            return Err(Error::Parts(format!("version {}: expected {VERSION}", self.version)));
        }
        let mut covered = vec![false; self.n_vertices];
        for (k, p) in self.parts.iter().enumerate() {
            if p.name.trim().is_empty() {
                return Err(Error::Parts(format!("part {k} has an empty name")));
            }
            if self.parts[..k].iter().any(|q| q.name == p.name) {
                return Err(Error::Parts(format!("part name \"{}\" appears twice", p.name)));
            }
            if p.vertices.is_empty() {
                return Err(Error::Parts(format!("part \"{}\" has no vertices", p.name)));
            }
            if !p.vertices.windows(2).all(|w| w[0] < w[1]) {
                return Err(Error::Parts(format!("part \"{}\": vertices must be sorted and unique", p.name)));
            }
            for &v in &p.vertices {
                let Some(c) = covered.get_mut(v as usize) else {
                    return Err(Error::Parts(format!(
                        "part \"{}\" has vertex {v}: expected 0 to {} (the template has {} vertices)",
                        p.name,
                        self.n_vertices.saturating_sub(1),
                        self.n_vertices
                    )));
                };
                *c = true;
            }
        }
        if let Some(v) = covered.iter().position(|c| !c) {
            let missing = covered.iter().filter(|c| !**c).count();
            return Err(Error::Parts(format!(
                "{missing} template vertices are in no part (the first is vertex {v}): every vertex must belong to a part"
            )));
        }
        let roots: Vec<&str> = self.parts.iter().filter(|p| p.parent.is_none()).map(|p| p.name.as_str()).collect();
        if roots.len() != 1 {
            return Err(Error::Parts(format!(
                "{} root parts ({}): expected exactly one part without a parent",
                roots.len(),
                roots.join(", ")
            )));
        }
        for (k, p) in self.parts.iter().enumerate() {
            let Some(parent) = &p.parent else { continue };
            let Some(pi) = self.index(parent) else {
                return Err(Error::Parts(format!("part \"{}\" has parent \"{parent}\", which is not a part", p.name)));
            };
            if pi == k {
                return Err(Error::Parts(format!("part \"{}\" is its own parent", p.name)));
            }
        }
        // Acyclic: walking up from any part reaches the root within n steps.
        for k in 0..self.parts.len() {
            let mut at = k;
            for _ in 0..=self.parts.len() {
                match self.parent(at) {
                    Some(p) => at = p,
                    None => break,
                }
            }
            if self.parent(at).is_some() {
                return Err(Error::Parts(format!("the parents of part \"{}\" form a cycle", self.parts[k].name)));
            }
        }
        Ok(())
    }

    /// Checks the parts fit a template of `topology`.
    pub fn check_fits(&self, topology: &Topology) -> Result<()> {
        if topology.n_vertices() != self.n_vertices {
            return Err(Error::Parts(format!(
                "made for a template of {} vertices, but the subject has {}",
                self.n_vertices,
                topology.n_vertices()
            )));
        }
        for p in &self.parts {
            let whole = topology.triangles().iter().any(|t| t.iter().all(|v| p.vertices.binary_search(v).is_ok()));
            if !whole {
                return Err(Error::Parts(format!("part \"{}\" contains no whole triangle of the template", p.name)));
            }
        }
        // A child must overlap its parent where the template joins them (that is where they are
        // stitched, thesis 5.6.2). Parts on separate pieces of the template (KayKit's arms and
        // body are separate meshes) cannot share a vertex and are never stitched: no overlap is
        // then allowed.
        let mut member = vec![false; self.n_vertices];
        for k in 0..self.parts.len() {
            let Some(pi) = self.parent(k) else { continue };
            if !self.overlap(k).is_empty() {
                continue;
            }
            for &v in &self.parts[pi].vertices {
                member[v as usize] = true;
            }
            let child = &self.parts[k].vertices;
            let joined = topology.triangles().iter().find_map(|t| {
                (0..3).find_map(|e| {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    let (ia, ib) = (child.binary_search(&a).is_ok(), child.binary_search(&b).is_ok());
                    if ia && member[b as usize] {
                        Some((a, b))
                    } else if ib && member[a as usize] {
                        Some((b, a))
                    } else {
                        None
                    }
                })
            });
            for &v in &self.parts[pi].vertices {
                member[v as usize] = false;
            }
            if let Some((a, b)) = joined {
                return Err(Error::Parts(format!(
                    "part \"{}\" shares no vertex with its parent \"{}\", but the template's edge {a}-{b} joins them: \
                     contiguous parts must overlap (thesis 5.4.2)",
                    self.parts[k].name, self.parts[pi].name
                )));
            }
        }
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.parts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    pub fn names(&self) -> Vec<&str> {
        self.parts.iter().map(|p| p.name.as_str()).collect()
    }

    /// The index of the part named `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.parts.iter().position(|p| p.name == name)
    }

    /// The index of part `k`'s parent.
    pub fn parent(&self, k: usize) -> Option<usize> {
        self.parts[k].parent.as_deref().and_then(|p| self.index(p))
    }

    /// The root's index.
    pub fn root(&self) -> usize {
        self.parts.iter().position(|p| p.parent.is_none()).unwrap_or(0)
    }

    /// Parts in an order where every parent comes before its children (breadth-first from the root).
    pub fn top_down(&self) -> Vec<usize> {
        let mut order = vec![self.root()];
        let mut queue: VecDeque<usize> = order.iter().copied().collect();
        while let Some(p) = queue.pop_front() {
            for c in 0..self.parts.len() {
                if self.parent(c) == Some(p) {
                    order.push(c);
                    queue.push_back(c);
                }
            }
        }
        order
    }

    /// Template vertices shared by part `k` and its parent (empty for the root), sorted.
    pub fn overlap(&self, k: usize) -> Vec<u32> {
        let Some(p) = self.parent(k) else { return Vec::new() };
        intersect(&self.parts[k].vertices, &self.parts[p].vertices)
    }

    /// Per template vertex, how many parts hold it.
    pub fn multiplicity(&self) -> Vec<u16> {
        let mut m = vec![0u16; self.n_vertices];
        for p in &self.parts {
            for &v in &p.vertices {
                m[v as usize] += 1;
            }
        }
        m
    }

    /// Per template vertex, one part for colouring: the deepest part holding it (a child's
    /// overlap shows as the child), and whether the vertex is in an overlap.
    pub fn display_labels(&self) -> (Vec<u16>, Vec<bool>) {
        let mut label = vec![0u16; self.n_vertices];
        for k in self.top_down() {
            for &v in &self.parts[k].vertices {
                label[v as usize] = k as u16;
            }
        }
        let overlap = self.multiplicity().iter().map(|&m| m > 1).collect();
        (label, overlap)
    }

    /// Part `k` cut out of the template.
    pub fn submesh(&self, topology: &Topology, k: usize) -> Submesh {
        let verts = &self.parts[k].vertices;
        let mut local = vec![u32::MAX; self.n_vertices];
        for (i, &v) in verts.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        let triangles: Vec<[u32; 3]> = topology
            .triangles()
            .iter()
            .filter_map(|t| {
                let l = t.map(|v| local[v as usize]);
                (l.iter().all(|&x| x != u32::MAX)).then_some(l)
            })
            .collect();
        // Vertices in no whole triangle of the part stay as isolated vertices: Topology accepts
        // them, and the part's vertex count keeps matching its vertex list.
        let topology = Topology::new(verts.len(), triangles, None).expect("a subset of a valid topology is valid");
        Submesh { topology, vertices: verts.clone() }
    }

    /// Parses the canonical JSON form.
    pub fn from_json(text: &str) -> Result<BodyParts> {
        let b: BodyParts = serde_json::from_str(text).map_err(|e| Error::Parts(format!("{e}")))?;
        b.validate()?;
        Ok(b)
    }

    /// The canonical JSON form (vertex lists on one line each).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("parts serialise")
    }
}

/// Sorted intersection of two sorted lists.
pub fn intersect(a: &[u32], b: &[u32]) -> Vec<u32> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of 6 vertices, 4 triangles: 0-1-2 / 3-4-5.
    fn strip() -> Topology {
        Topology::new(6, vec![[0, 1, 3], [1, 4, 3], [1, 2, 4], [2, 5, 4]], None).unwrap()
    }

    fn part(name: &str, parent: Option<&str>, v: &[u32]) -> Part {
        Part { name: name.into(), parent: parent.map(Into::into), vertices: v.to_vec() }
    }

    #[test]
    fn overlapping_tree_validates_and_cuts_submeshes() {
        let b = BodyParts::new(6, vec![part("torso", None, &[0, 1, 3, 4]), part("arm", Some("torso"), &[4, 1, 2, 5])])
            .unwrap();
        b.check_fits(&strip()).unwrap();
        assert_eq!(b.overlap(1), vec![1, 4]);
        assert_eq!(b.top_down(), vec![0, 1]);
        let s = b.submesh(&strip(), 1);
        assert_eq!(s.vertices, vec![1, 2, 4, 5]);
        assert_eq!(s.topology.n_triangles(), 2);
        let (labels, overlap) = b.display_labels();
        assert_eq!(labels, vec![0, 1, 1, 0, 1, 1]);
        assert_eq!(overlap, vec![false, true, false, false, true, false]);
        let back = BodyParts::from_json(&b.to_json()).unwrap();
        assert_eq!(back, b);
    }

    #[test]
    fn bad_parts_are_refused_with_the_reason() {
        let e = BodyParts::new(6, vec![part("torso", None, &[0, 1, 3, 4])]).unwrap_err().to_string();
        assert!(e.contains("2 template vertices are in no part (the first is vertex 2)"), "{e}");
        let b =
            BodyParts::new(6, vec![part("torso", None, &[0, 1, 3]), part("arm", Some("torso"), &[2, 4, 5])]).unwrap();
        let e = b.check_fits(&strip()).unwrap_err().to_string();
        assert!(
            e.contains("shares no vertex with its parent \"torso\", but the template's edge 4-1 joins them"),
            "{e}"
        );
        let b =
            BodyParts::new(6, vec![part("torso", None, &[0, 1, 3, 4]), part("arm", Some("torso"), &[2, 5])]).unwrap();
        let e = b.check_fits(&strip()).unwrap_err().to_string();
        assert!(e.contains("part \"arm\" contains no whole triangle of the template"), "{e}");
        let e = BodyParts::new(6, vec![part("a", None, &[0, 1, 2, 3, 4, 5, 9])]).unwrap_err().to_string();
        assert!(e.contains("vertex 9: expected 0 to 5"), "{e}");
        let e = BodyParts::new(
            6,
            vec![part("a", Some("b"), &[0, 1, 2, 3]), part("b", Some("a"), &[3, 4, 5]), part("c", None, &[0])],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("cycle"), "{e}");
        let e = BodyParts::new(6, vec![part("a", None, &[0, 1, 2, 3, 4, 5]), part("b", None, &[0])])
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 root parts"), "{e}");
    }

    #[test]
    fn separate_pieces_need_no_overlap_but_joined_ones_do() {
        // Two separate triangles: 0-1-2 and 3-4-5 (as KayKit's separate body-part meshes).
        let two = Topology::new(6, vec![[0, 1, 2], [3, 4, 5]], None).unwrap();
        let b = BodyParts::new(6, vec![part("body", None, &[0, 1, 2]), part("arm", Some("body"), &[3, 4, 5])]).unwrap();
        assert!(b.overlap(1).is_empty());
        b.check_fits(&two).unwrap();
        // The same parts on a strip whose edges join them are refused.
        let strip = Topology::new(6, vec![[0, 1, 2], [1, 3, 2], [3, 4, 5]], None).unwrap();
        let e = b.check_fits(&strip).unwrap_err().to_string();
        assert!(e.contains("part \"arm\" shares no vertex with its parent \"body\""), "{e}");
    }
}

//! Body parts from one core label per template vertex, grown into overlap bands (thesis 5.4.2,
//! Fig. 5.2: "the user defines the parts by drawing curves; contiguous parts share an overlap").
//!
//! The thesis has the user draw two curves per boundary and takes the strip between them as the
//! overlap. A label per vertex is easier to produce (a paint tool, a skinning export, a proposal)
//! but has no strip: the boundary between a child's core and its parent's core is one line of
//! edges. We grow it into a band of `overlap_rings` edge rings on BOTH sides (rings counted from
//! the boundary: ring 1 is the row of vertices touching the other part), and both parts hold the
//! band, so the band is `2 * overlap_rings` vertex rows wide, centred on the labelled boundary.
//! Only a part's own parent and children share bands: two siblings that happen to touch (a hand
//! on a thigh at rest) are not stitched to each other (5.6.2 stitches children to parents only).
//! The rings are grown through the two parts' cores only, never through a third part.

use std::collections::VecDeque;

use surfcap_mesh::Topology;

use crate::body_parts::{BodyParts, Part};
use crate::error::{Error, Result};

/// Vertex neighbours of a topology (sorted, unique per vertex).
pub fn vertex_neighbours(topology: &Topology) -> Vec<Vec<u32>> {
    let mut adj = vec![Vec::new(); topology.n_vertices()];
    for t in topology.triangles() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            adj[a as usize].push(b);
            adj[b as usize].push(a);
        }
    }
    for n in &mut adj {
        n.sort_unstable();
        n.dedup();
    }
    adj
}

/// Vertices labelled `into` within `rings` edge rings of the vertices labelled `from`, walking
/// only through vertices labelled `into` (ring 1 touches `from`).
fn band_side(adj: &[Vec<u32>], labels: &[u16], from: u16, into: u16, rings: usize) -> Vec<u32> {
    let mut dist = vec![usize::MAX; labels.len()];
    let mut queue = VecDeque::new();
    for (v, &l) in labels.iter().enumerate() {
        if l == into && adj[v].iter().any(|&w| labels[w as usize] == from) {
            dist[v] = 1;
            queue.push_back(v);
        }
    }
    let mut out = Vec::new();
    while let Some(v) = queue.pop_front() {
        if dist[v] > rings {
            continue;
        }
        out.push(v as u32);
        for &w in &adj[v] {
            let w = w as usize;
            if labels[w] == into && dist[w] == usize::MAX {
                dist[w] = dist[v] + 1;
                queue.push_back(w);
            }
        }
    }
    out.sort_unstable();
    out
}

/// Checks names and parents: as many of each, parents in range and not the part itself.
pub(crate) fn check_tree(names: &[String], parents: &[Option<usize>]) -> Result<()> {
    if names.is_empty() {
        return Err(Error::Parts("no part names: expected at least one".into()));
    }
    if parents.len() != names.len() {
        return Err(Error::Parts(format!(
            "{} parents for {} part names: expected one parent (or none for the root) per part",
            parents.len(),
            names.len()
        )));
    }
    for (k, p) in parents.iter().enumerate() {
        if let Some(p) = *p {
            if p >= names.len() {
                return Err(Error::Parts(format!(
                    "part \"{}\" has parent {p}: expected 0 to {}",
                    names[k],
                    names.len() - 1
                )));
            }
            if p == k {
                return Err(Error::Parts(format!("part \"{}\" is its own parent", names[k])));
            }
        }
    }
    Ok(())
}

/// Builds parts from core labels plus, per part, extra vertices (its overlap bands), then
/// checks them against the topology.
pub(crate) fn assemble(
    topology: &Topology,
    labels: &[u16],
    names: &[String],
    parents: &[Option<usize>],
    extra: &[Vec<u32>],
) -> Result<BodyParts> {
    let mut vertices: Vec<Vec<u32>> = extra.to_vec();
    for (v, &l) in labels.iter().enumerate() {
        vertices[l as usize].push(v as u32);
    }
    for (k, list) in vertices.iter().enumerate() {
        if list.is_empty() {
            return Err(Error::Parts(format!("part \"{}\" (label {k}) has no vertex", names[k])));
        }
    }
    let parts = names
        .iter()
        .zip(parents)
        .zip(vertices)
        .map(|((name, parent), vertices)| Part {
            name: name.clone(),
            parent: parent.map(|p| names[p].clone()),
            vertices,
        })
        .collect();
    let b = BodyParts::new(topology.n_vertices(), parts)?;
    b.check_fits(topology)?;
    Ok(b)
}

impl BodyParts {
    /// Parts from a core label per template vertex (`labels[v]` indexes `names`), a parent per
    /// part (`None` for the root), and overlap bands of `overlap_rings` edge rings on both sides
    /// of each child/parent boundary (see the module's doc). `overlap_rings` 0 gives no overlap,
    /// which [`BodyParts::check_fits`] refuses where a child touches its parent.
    pub fn from_labels(
        topology: &Topology,
        labels: &[u16],
        names: Vec<String>,
        parents: Vec<Option<usize>>,
        overlap_rings: usize,
    ) -> Result<BodyParts> {
        let n = topology.n_vertices();
        if labels.len() != n {
            return Err(Error::Parts(format!("{} labels: expected one per template vertex ({n})", labels.len())));
        }
        check_tree(&names, &parents)?;
        if let Some((v, &l)) = labels.iter().enumerate().find(|(_, l)| **l as usize >= names.len()) {
            return Err(Error::Parts(format!(
                "vertex {v} has label {l}: expected 0 to {} (one label per part name)",
                names.len() - 1
            )));
        }
        let adj = vertex_neighbours(topology);
        let mut extra = vec![Vec::new(); names.len()];
        for (c, p) in parents.iter().enumerate() {
            let Some(p) = *p else { continue };
            let (c16, p16) = (c as u16, p as u16);
            let mut band = band_side(&adj, labels, c16, p16, overlap_rings);
            band.extend(band_side(&adj, labels, p16, c16, overlap_rings));
            extra[c].extend(band.iter().filter(|&&v| labels[v as usize] == p16));
            extra[p].extend(band.iter().filter(|&&v| labels[v as usize] == c16));
        }
        assemble(topology, labels, &names, &parents, &extra).map_err(|e| match e {
            Error::Parts(m) if overlap_rings == 0 && m.contains("shares no vertex") => {
                Error::Parts(format!("{m} (overlap rings 0: expected at least 1)"))
            }
            e => e,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of 2 x 8 vertices: top row 0..8, bottom row 8..16, 14 triangles.
    pub(crate) fn strip(len: u32) -> Topology {
        let mut t = Vec::new();
        for i in 0..len - 1 {
            t.push([i, i + 1, len + i]);
            t.push([i + 1, len + i + 1, len + i]);
        }
        Topology::new(2 * len as usize, t, None).unwrap()
    }

    #[test]
    fn labels_grow_bands_on_both_sides_of_the_boundary() {
        let topo = strip(8);
        // Columns 0..4 torso, 4..8 arm.
        let labels: Vec<u16> = (0..16).map(|v| u16::from(v % 8 >= 4)).collect();
        let names = vec!["torso".to_string(), "arm".to_string()];
        let b = BodyParts::from_labels(&topo, &labels, names.clone(), vec![None, Some(0)], 1).unwrap();
        // One ring each side: columns 3 and 4 shared.
        assert_eq!(b.overlap(1), vec![3, 4, 11, 12]);
        let b2 = BodyParts::from_labels(&topo, &labels, names.clone(), vec![None, Some(0)], 2).unwrap();
        assert_eq!(b2.overlap(1), vec![2, 3, 4, 5, 10, 11, 12, 13]);
        assert_eq!(b2.parts[0].vertices, vec![0, 1, 2, 3, 4, 5, 8, 9, 10, 11, 12, 13]);
        // Rings 0: no overlap, refused because the strip joins the parts.
        let e = BodyParts::from_labels(&topo, &labels, names.clone(), vec![None, Some(0)], 0).unwrap_err().to_string();
        assert!(e.contains("shares no vertex") && e.contains("overlap rings 0"), "{e}");
    }

    #[test]
    fn bands_do_not_cross_a_third_part_or_join_siblings() {
        let topo = strip(8);
        // torso in the middle (2..6), a at 0..2, b at 6..8: a and b never touch.
        let labels: Vec<u16> = (0..16)
            .map(|v| match v % 8 {
                0 | 1 => 1,
                6 | 7 => 2,
                _ => 0,
            })
            .collect();
        let names = vec!["torso".into(), "a".into(), "b".into()];
        let b = BodyParts::from_labels(&topo, &labels, names, vec![None, Some(0), Some(0)], 3).unwrap();
        // a's band reaches 3 rings into the torso (columns 2, 3, 4) and all of a.
        assert_eq!(b.parts[1].vertices, vec![0, 1, 2, 3, 4, 8, 9, 10, 11, 12]);
        assert_eq!(b.parts[0].vertices.len(), 16);
    }

    #[test]
    fn bad_labels_are_refused() {
        let topo = strip(4);
        let names = vec!["torso".to_string(), "arm".to_string()];
        let e = BodyParts::from_labels(&topo, &[0; 7], names.clone(), vec![None, Some(0)], 1).unwrap_err();
        assert!(e.to_string().contains("7 labels: expected one per template vertex (8)"), "{e}");
        let mut l = vec![0u16; 8];
        l[5] = 4;
        let e = BodyParts::from_labels(&topo, &l, names.clone(), vec![None, Some(0)], 1).unwrap_err();
        assert!(e.to_string().contains("vertex 5 has label 4: expected 0 to 1"), "{e}");
        let e = BodyParts::from_labels(&topo, &[0; 8], names.clone(), vec![None, Some(0)], 1).unwrap_err();
        assert!(e.to_string().contains("part \"arm\" (label 1) has no vertex"), "{e}");
        let e = BodyParts::from_labels(&topo, &[0; 8], names, vec![None, Some(7)], 1).unwrap_err();
        assert!(e.to_string().contains("part \"arm\" has parent 7: expected 0 to 1"), "{e}");
    }
}

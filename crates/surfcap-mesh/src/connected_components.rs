//! Connected components of a triangle topology (vertices joined by triangle edges).
//!
//! Needed wherever a Poisson system fixes one translation per component (thesis 2.4, eq. 2.48):
//! the KayKit and robot meshes have several disconnected body parts.

use crate::topology::Topology;

/// Component label of every vertex, labels numbered 0.. in order of first vertex; isolated
/// vertices (in no triangle) get a component of their own.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    pub labels: Vec<u32>,
    pub count: usize,
}

impl Components {
    /// Vertex count of each component.
    pub fn sizes(&self) -> Vec<usize> {
        let mut s = vec![0; self.count];
        for &l in &self.labels {
            s[l as usize] += 1;
        }
        s
    }
}

/// Union-find over the triangles' edges, with path halving and union by size.
pub fn connected_components(topology: &Topology) -> Components {
    let n = topology.n_vertices();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut size = vec![1u32; n];
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let gp = parent[parent[x as usize] as usize];
            parent[x as usize] = gp;
            x = gp;
        }
        x
    }
    for t in topology.triangles() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2])] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                let (big, small) = if size[ra as usize] >= size[rb as usize] { (ra, rb) } else { (rb, ra) };
                parent[small as usize] = big;
                size[big as usize] += size[small as usize];
            }
        }
    }
    let mut label_of_root = vec![u32::MAX; n];
    let mut labels = vec![0u32; n];
    let mut count = 0u32;
    for v in 0..n as u32 {
        let r = find(&mut parent, v) as usize;
        if label_of_root[r] == u32::MAX {
            label_of_root[r] = count;
            count += 1;
        }
        labels[v as usize] = label_of_root[r];
    }
    Components { labels, count: count as usize }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_and_an_isolated_vertex() {
        let t = Topology::new(7, vec![[0, 1, 2], [3, 4, 5], [2, 1, 0]], None).unwrap();
        let c = connected_components(&t);
        assert_eq!(c.count, 3);
        assert_eq!(c.labels, vec![0, 0, 0, 1, 1, 1, 2]);
        assert_eq!(c.sizes(), vec![3, 3, 1]);
    }

    #[test]
    fn a_strip_is_one_component() {
        let t = Topology::new(5, vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]], None).unwrap();
        assert_eq!(connected_components(&t).count, 1);
    }
}

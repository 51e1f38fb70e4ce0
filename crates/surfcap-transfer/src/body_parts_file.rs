//! Body parts a user writes by hand or exports from a tool (thesis 5.4.2, Fig. 5.2: the user
//! draws two curves per boundary; the strip between them is the overlap of the two parts).
//!
//! [`read_parts_file`] reads five forms, told apart by their content (documented in
//! docs/formats.md, "Body parts files"):
//! - the canonical JSON (`"format": "surfcap-parts"`, every part's full vertex list);
//! - per-vertex labels in JSON: `{"labels": [...], "names": [...], "parents": [...],
//!   "overlap_rings": k}`, only `labels` required ([`BodyParts::from_labels`] grows the bands);
//! - per-vertex labels as plain text: one integer per line (`#` comments and blank lines
//!   skipped), names and parents defaulted;
//! - cutting planes: `{"root": "torso", "overlap_width": w, "planes": [{"name", "parent",
//!   "point", "normal", "overlap_width"}]}`: a child is the connected region on the normal's side
//!   of the plane reached from the vertex nearest the plane point, taken from its parent; the
//!   overlap is the band `|distance to the plane| <= width / 2` grown from the boundary;
//! - vertex loops, the thesis's curves: `{"root": "torso", "loops": [{"name", "parent",
//!   "parent_loop": [...], "child_loop": [...]}]}`: the parent loop separates the child from its
//!   parent, the child loop lies on the child's side, and the overlap is the strip between them,
//!   both loops included.
//!
//! Defaults where the thesis says nothing: missing names are `part_0`, `part_1`... except that
//! exactly five labels 0-4 take the humanoid names in the order `surfcap parts propose` writes
//! them (`torso, arm_left, arm_right, leg_left, leg_right`); a missing parent list makes label
//! 0 the root and every other part its child (the thesis's torso-and-limbs tree); missing
//! overlap rings are 2. Planes and loops apply in the order given, each cutting its child out of
//! its parent as the earlier cuts left it; a band always holds at least the vertex row on each
//! side of the boundary, so a width smaller than an edge still gives an overlap. Unknown JSON
//! fields are refused (a misspelt `overlap_ring` must not silently fall back to a default).

use std::collections::VecDeque;
use std::path::Path;

use serde::Deserialize;
use surfcap_mesh::Topology;

use crate::body_parts::BodyParts;
use crate::body_parts_from_labels::{assemble, check_tree, vertex_neighbours};
use crate::body_parts_proposal::HUMANOID_NAMES;
use crate::error::{Error, Result};

/// Overlap rings when a labels file gives none.
pub const DEFAULT_OVERLAP_RINGS: usize = 2;

/// A parent given by name or by index.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum ParentRef {
    Index(usize),
    Name(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LabelsFile {
    labels: Vec<u16>,
    #[serde(default)]
    names: Option<Vec<String>>,
    #[serde(default)]
    parents: Option<Vec<Option<ParentRef>>>,
    #[serde(default)]
    overlap_rings: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanesFile {
    #[serde(default = "default_root")]
    root: String,
    #[serde(default)]
    overlap_width: Option<f64>,
    planes: Vec<Plane>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Plane {
    name: String,
    #[serde(default)]
    parent: Option<String>,
    point: [f64; 3],
    normal: [f64; 3],
    #[serde(default)]
    overlap_width: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LoopsFile {
    #[serde(default = "default_root")]
    root: String,
    loops: Vec<LoopCut>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LoopCut {
    name: String,
    #[serde(default)]
    parent: Option<String>,
    parent_loop: Vec<u32>,
    child_loop: Vec<u32>,
}

fn default_root() -> String {
    "torso".into()
}

/// Reads a body-parts file in any of the module's forms and checks it against the template
/// (`positions` its `[vertices][3]` positions, used by cutting planes). Errors name the file.
pub fn read_parts_file(path: &Path, topology: &Topology, positions: &[f32]) -> Result<BodyParts> {
    let name = path.display().to_string();
    // A FIFO, folder or device is refused by name, as a parts file (not as "mesh data").
    let bytes = surfcap_mesh::read_regular_file(path).map_err(|e| Error::Parts(format!("{name}: {}", e.message)))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        Error::Parts(format!(
            "{name}: byte {}: not UTF-8 text (expected JSON or one label per line)",
            e.utf8_error().valid_up_to()
        ))
    })?;
    parse_parts(&text, topology, positions).map_err(|e| match e {
        Error::Parts(m) => Error::Parts(format!("{name}: {m}")),
        e => e,
    })
}

/// [`read_parts_file`] on text already read.
pub fn parse_parts(text: &str, topology: &Topology, positions: &[f32]) -> Result<BodyParts> {
    if positions.len() != 3 * topology.n_vertices() {
        return Err(Error::Invalid(format!(
            "{} template coordinates: expected 3 per vertex ({})",
            positions.len(),
            3 * topology.n_vertices()
        )));
    }
    let trimmed = text.trim_start();
    if !trimmed.starts_with('{') {
        return text_labels(text, topology);
    }
    let json = |e: serde_json::Error| Error::Parts(format!("line {}, column {}: {e}", e.line(), e.column()));
    let value: serde_json::Value = serde_json::from_str(text).map_err(json)?;
    let has = |k: &str| value.get(k).is_some();
    let parsed = if has("format") {
        let b: BodyParts = serde_json::from_str(text).map_err(json)?;
        b.validate()?;
        b.check_fits(topology)?;
        b
    } else if has("labels") {
        labels_json(serde_json::from_str(text).map_err(json)?, topology)?
    } else if has("planes") {
        planes(serde_json::from_str(text).map_err(json)?, topology, positions)?
    } else if has("loops") {
        loops(serde_json::from_str(text).map_err(json)?, topology)?
    } else {
        return Err(Error::Parts(
            "a JSON object without \"format\", \"labels\", \"planes\" or \"loops\": expected a canonical parts file \
             (\"format\": \"surfcap-parts\"), per-vertex labels, cutting planes or vertex loops"
                .into(),
        ));
    };
    Ok(parsed)
}

/// Default names: humanoid for exactly five labels, else `part_k`.
fn default_names(n: usize) -> Vec<String> {
    if n == HUMANOID_NAMES.len() {
        HUMANOID_NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        (0..n).map(|k| format!("part_{k}")).collect()
    }
}

/// Label 0 the root, every other part its child.
fn star(n: usize) -> Vec<Option<usize>> {
    (0..n).map(|k| (k > 0).then_some(0)).collect()
}

fn text_labels(text: &str, topology: &Topology) -> Result<BodyParts> {
    let mut labels = Vec::with_capacity(topology.n_vertices());
    for (i, line) in text.lines().enumerate() {
        let l = line.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            continue;
        }
        let x: u16 = l.parse().map_err(|_| {
            Error::Parts(format!("line {}: \"{l}\": expected one whole-number label (0 to 65535) per line", i + 1))
        })?;
        labels.push(x);
    }
    let n = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    BodyParts::from_labels(topology, &labels, default_names(n), star(n), DEFAULT_OVERLAP_RINGS)
}

fn labels_json(f: LabelsFile, topology: &Topology) -> Result<BodyParts> {
    let n_labels = f.labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let names = match f.names {
        Some(n) => n,
        None => default_names(n_labels),
    };
    let parents = match f.parents {
        None => star(names.len()),
        Some(ps) => ps
            .into_iter()
            .enumerate()
            .map(|(k, p)| match p {
                None => Ok(None),
                Some(ParentRef::Index(i)) => Ok(Some(i)),
                Some(ParentRef::Name(s)) => names.iter().position(|x| *x == s).map(Some).ok_or_else(|| {
                    Error::Parts(format!(
                        "parents[{k}] is \"{s}\", which is not a part name: expected one of {}",
                        names.join(", ")
                    ))
                }),
            })
            .collect::<Result<_>>()?,
    };
    BodyParts::from_labels(topology, &f.labels, names, parents, f.overlap_rings.unwrap_or(DEFAULT_OVERLAP_RINGS))
}

/// Vertices labelled `into` reached from the row touching `from`, through `into` vertices that
/// `keep` accepts (the touching row always included).
fn band_where(adj: &[Vec<u32>], labels: &[u16], from: u16, into: u16, keep: impl Fn(usize) -> bool) -> Vec<u32> {
    let mut seen = vec![false; labels.len()];
    let mut queue = VecDeque::new();
    for v in 0..labels.len() {
        if labels[v] == into && adj[v].iter().any(|&w| labels[w as usize] == from) {
            seen[v] = true;
            queue.push_back(v);
        }
    }
    let mut out = Vec::new();
    while let Some(v) = queue.pop_front() {
        out.push(v as u32);
        for &w in &adj[v] {
            let w = w as usize;
            if !seen[w] && labels[w] == into && keep(w) {
                seen[w] = true;
                queue.push_back(w);
            }
        }
    }
    out
}

/// Index of the part named `name` among `names`, for a cut of part `child`.
fn parent_index(names: &[String], parent: &Option<String>, root: &str, child: &str) -> Result<usize> {
    let p = parent.as_deref().unwrap_or(root);
    names.iter().position(|n| n == p).ok_or_else(|| {
        Error::Parts(format!(
            "part \"{child}\" has parent \"{p}\": expected the root or a part defined before it ({})",
            names.join(", ")
        ))
    })
}

fn new_name(names: &[String], name: &str) -> Result<()> {
    if name.trim().is_empty() {
        return Err(Error::Parts("a part with an empty name: expected a name".into()));
    }
    if names.iter().any(|n| n == name) {
        return Err(Error::Parts(format!("part name \"{name}\" appears twice")));
    }
    Ok(())
}

fn planes(f: PlanesFile, topology: &Topology, positions: &[f32]) -> Result<BodyParts> {
    let n = topology.n_vertices();
    let adj = vertex_neighbours(topology);
    let mut names = vec![f.root.clone()];
    new_name(&[], &f.root)?;
    let mut parents = vec![None];
    let mut labels = vec![0u16; n];
    let at = |v: usize| [positions[3 * v] as f64, positions[3 * v + 1] as f64, positions[3 * v + 2] as f64];
    let mut cuts = Vec::new();
    for c in &f.planes {
        new_name(&names, &c.name)?;
        let pi = parent_index(&names, &c.parent, &f.root, &c.name)?;
        let len = (c.normal.iter().map(|x| x * x).sum::<f64>()).sqrt();
        if !(len.is_finite() && len > 0.0) || c.point.iter().any(|x| !x.is_finite()) {
            return Err(Error::Parts(format!(
                "plane of part \"{}\": point {:?}, normal {:?}: expected finite numbers and a non-zero normal",
                c.name, c.point, c.normal
            )));
        }
        let width = c.overlap_width.or(f.overlap_width).unwrap_or(0.0);
        if !(width.is_finite() && width >= 0.0) {
            return Err(Error::Parts(format!("part \"{}\": overlap width {width}: expected 0 or more", c.name)));
        }
        let normal = c.normal.map(|x| x / len);
        let dist: Vec<f64> = (0..n).map(|v| (0..3).map(|k| (at(v)[k] - c.point[k]) * normal[k]).sum::<f64>()).collect();
        let k = names.len() as u16;
        let pl = pi as u16;
        let side = |v: usize| labels[v] == pl && dist[v] >= 0.0;
        let near = |v: usize| (0..3).map(|i| (at(v)[i] - c.point[i]).powi(2)).sum::<f64>();
        let Some(seed) = (0..n).filter(|&v| side(v)).min_by(|&a, &b| near(a).total_cmp(&near(b)).then(a.cmp(&b)))
        else {
            return Err(Error::Parts(format!(
                "plane of part \"{}\": no vertex of \"{}\" on the normal's side: expected the normal to point into the child",
                c.name, names[pi]
            )));
        };
        let mut region = vec![seed];
        let mut inside = vec![false; n];
        inside[seed] = true;
        let mut i = 0;
        while i < region.len() {
            for &w in &adj[region[i]] {
                let w = w as usize;
                if !inside[w] && side(w) {
                    inside[w] = true;
                    region.push(w);
                }
            }
            i += 1;
        }
        if region.len() == labels.iter().filter(|&&l| l == pl).count() {
            return Err(Error::Parts(format!(
                "plane of part \"{}\" leaves nothing of \"{}\": expected the plane to cut it in two",
                c.name, names[pi]
            )));
        }
        for &v in &region {
            labels[v] = k;
        }
        names.push(c.name.clone());
        parents.push(Some(pi));
        cuts.push((k, pl, dist, width));
    }
    let mut extra = vec![Vec::new(); names.len()];
    for (k, pl, dist, width) in cuts {
        let h = width / 2.0;
        let child_side = band_where(&adj, &labels, pl, k, |v| dist[v] <= h);
        let parent_side = band_where(&adj, &labels, k, pl, |v| dist[v] >= -h);
        extra[pl as usize].extend(child_side);
        extra[k as usize].extend(parent_side);
    }
    assemble(topology, &labels, &names, &parents, &extra)
}

/// Checks a loop: vertices in range, consecutive ones (and the last and the first) joined by an
/// edge. A repeated first vertex at the end is accepted.
fn check_loop(adj: &[Vec<u32>], part: &str, which: &str, lp: &[u32]) -> Result<Vec<u32>> {
    let mut lp = lp.to_vec();
    if lp.len() > 1 && lp.first() == lp.last() {
        lp.pop();
    }
    if lp.len() < 3 {
        return Err(Error::Parts(format!(
            "{which} of part \"{part}\" has {} vertices: expected a closed loop of at least 3",
            lp.len()
        )));
    }
    for &v in &lp {
        if v as usize >= adj.len() {
            return Err(Error::Parts(format!(
                "{which} of part \"{part}\" has vertex {v}: expected 0 to {}",
                adj.len().saturating_sub(1)
            )));
        }
    }
    for i in 0..lp.len() {
        let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
        if adj[a as usize].binary_search(&b).is_err() {
            return Err(Error::Parts(format!(
                "{which} of part \"{part}\": vertices {a} and {b} are not joined by an edge (expected a closed loop of edges, in order)"
            )));
        }
    }
    Ok(lp)
}

fn loops(f: LoopsFile, topology: &Topology) -> Result<BodyParts> {
    let n = topology.n_vertices();
    let adj = vertex_neighbours(topology);
    new_name(&[], &f.root)?;
    let mut names = vec![f.root.clone()];
    let mut parents = vec![None];
    let mut labels = vec![0u16; n];
    let mut extra: Vec<Vec<u32>> = vec![Vec::new()];
    for c in &f.loops {
        new_name(&names, &c.name)?;
        let pi = parent_index(&names, &c.parent, &f.root, &c.name)?;
        let pl = pi as u16;
        let outer = check_loop(&adj, &c.name, "parent_loop", &c.parent_loop)?;
        let inner = check_loop(&adj, &c.name, "child_loop", &c.child_loop)?;
        let mut on_outer = vec![false; n];
        for &v in &outer {
            on_outer[v as usize] = true;
        }
        for &v in outer.iter().chain(&inner) {
            if labels[v as usize] != pl {
                return Err(Error::Parts(format!(
                    "the loops of part \"{}\" have vertex {v}, which is in part \"{}\": expected vertices of its parent \"{}\"",
                    c.name, names[labels[v as usize] as usize], names[pi]
                )));
            }
            if on_outer[v as usize] && inner.contains(&v) {
                return Err(Error::Parts(format!(
                    "the loops of part \"{}\" share vertex {v}: expected two separate loops",
                    c.name
                )));
            }
        }
        // The child's side: reached from the child loop without crossing the parent loop.
        let flood = |starts: &[u32], stop: &dyn Fn(usize) -> bool, allowed: &dyn Fn(usize) -> bool| -> Vec<bool> {
            let mut seen = vec![false; n];
            let mut queue: VecDeque<usize> = starts.iter().map(|&v| v as usize).collect();
            for &v in starts {
                seen[v as usize] = true;
            }
            while let Some(v) = queue.pop_front() {
                for &w in &adj[v] {
                    let w = w as usize;
                    if !seen[w] && allowed(w) && !stop(w) {
                        seen[w] = true;
                        queue.push_back(w);
                    }
                }
            }
            seen
        };
        let child = flood(&inner, &|v| on_outer[v], &|v| labels[v] == pl);
        let left = (0..n).filter(|&v| labels[v] == pl && !child[v] && !on_outer[v]).count();
        if left == 0 {
            return Err(Error::Parts(format!(
                "parent_loop of part \"{}\" does not cut \"{}\" in two: from the child loop every vertex is reached without crossing it",
                c.name, names[pi]
            )));
        }
        let mut on_inner = vec![false; n];
        for &v in &inner {
            on_inner[v as usize] = true;
        }
        // The strip: from the parent loop into the child's side, not past the child loop.
        let strip = flood(&outer, &|v| on_inner[v], &|v| child[v]);
        let k = names.len() as u16;
        let mut mine = Vec::new();
        for v in 0..n {
            if child[v] {
                labels[v] = k;
                if strip[v] || on_inner[v] {
                    extra[pi].push(v as u32);
                }
            }
            if on_outer[v] {
                mine.push(v as u32);
            }
        }
        names.push(c.name.clone());
        parents.push(Some(pi));
        extra.push(mine);
    }
    check_tree(&names, &parents)?;
    assemble(topology, &labels, &names, &parents, &extra)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tube of `rings` rings of 4 vertices along x (ring i at x = i), closed around.
    fn tube(rings: u32) -> (Topology, Vec<f32>) {
        let mut t = Vec::new();
        for i in 0..rings - 1 {
            for j in 0..4 {
                let (a, b) = (4 * i + j, 4 * i + (j + 1) % 4);
                t.push([a, b, a + 4]);
                t.push([b, b + 4, a + 4]);
            }
        }
        let p = (0..rings)
            .flat_map(|i| {
                (0..4).flat_map(move |j| {
                    let a = j as f32 * std::f32::consts::FRAC_PI_2;
                    [i as f32, a.cos(), a.sin()]
                })
            })
            .collect();
        (Topology::new(4 * rings as usize, t, None).unwrap(), p)
    }

    #[test]
    fn text_labels_default_to_a_star_of_parts() {
        let (topo, p) = tube(6);
        let text: String = (0..24).map(|v| format!("{}\n", u8::from(v >= 12))).collect();
        let b = parse_parts(&format!("# two parts\n{text}\n"), &topo, &p).unwrap();
        assert_eq!(b.names(), vec!["part_0", "part_1"]);
        assert_eq!(b.parent(1), Some(0));
        // Two rings each side: rings 1-4 shared.
        assert_eq!(b.overlap(1).len(), 16);
        let e = parse_parts("0\n1\nx\n", &topo, &p).unwrap_err().to_string();
        assert!(e.contains("line 3: \"x\": expected one whole-number label"), "{e}");
        let e = parse_parts("0\n1\n", &topo, &p).unwrap_err().to_string();
        assert!(e.contains("2 labels: expected one per template vertex (24)"), "{e}");
    }

    #[test]
    fn labels_json_takes_names_parents_by_name_and_rings() {
        let (topo, p) = tube(6);
        let labels: Vec<u16> = (0..24).map(|v| u16::from(v >= 12)).collect();
        let j = serde_json::json!({"labels": labels, "names": ["body", "tail"], "parents": [null, "body"], "overlap_rings": 1});
        let b = parse_parts(&j.to_string(), &topo, &p).unwrap();
        assert_eq!(b.names(), vec!["body", "tail"]);
        assert_eq!(b.overlap(1), (8..16).collect::<Vec<u32>>());
        let j = serde_json::json!({"labels": labels, "names": ["body", "tail"], "parents": [null, "head"]});
        let e = parse_parts(&j.to_string(), &topo, &p).unwrap_err().to_string();
        assert!(e.contains("parents[1] is \"head\", which is not a part name: expected one of body, tail"), "{e}");
        let j = serde_json::json!({"labels": labels, "overlap_ring": 1});
        let e = parse_parts(&j.to_string(), &topo, &p).unwrap_err().to_string();
        assert!(e.contains("unknown field `overlap_ring`") && e.contains("line 1, column"), "{e}");
    }

    #[test]
    fn a_cutting_plane_takes_the_far_side_with_a_band_of_the_given_width() {
        let (topo, p) = tube(8);
        let j = r#"{"root": "body", "overlap_width": 2.2,
            "planes": [{"name": "tail", "point": [4.5, 0, 0], "normal": [1, 0, 0]}]}"#;
        let b = parse_parts(j, &topo, &p).unwrap();
        // Tail: rings 5-7 plus the band |x - 4.5| <= 1.1: rings 4 and 5.
        assert_eq!(b.parts[1].vertices, (16..32).collect::<Vec<u32>>());
        assert_eq!(b.parts[0].vertices, (0..24).collect::<Vec<u32>>());
        let e = parse_parts(r#"{"planes": [{"name": "tail", "point": [9, 0, 0], "normal": [1, 0, 0]}]}"#, &topo, &p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no vertex of \"torso\" on the normal's side"), "{e}");
        let e = parse_parts(r#"{"planes": [{"name": "tail", "point": [1, 0, 0], "normal": [0, 0, 0]}]}"#, &topo, &p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("expected finite numbers and a non-zero normal"), "{e}");
    }

    #[test]
    fn two_loops_delimit_the_overlap_strip() {
        let (topo, p) = tube(8);
        let j = r#"{"root": "body", "loops": [{"name": "tail", "parent_loop": [12, 13, 14, 15], "child_loop": [20, 21, 22, 23, 20]}]}"#;
        let b = parse_parts(j, &topo, &p).unwrap();
        assert_eq!(b.overlap(1), (12..24).collect::<Vec<u32>>());
        assert_eq!(b.parts[1].vertices, (12..32).collect::<Vec<u32>>());
        assert_eq!(b.parts[0].vertices, (0..24).collect::<Vec<u32>>());
        let j = r#"{"loops": [{"name": "tail", "parent_loop": [12, 14, 13, 15], "child_loop": [20, 21, 22, 23]}]}"#;
        let e = parse_parts(j, &topo, &p).unwrap_err().to_string();
        assert!(e.contains("parent_loop of part \"tail\": vertices 12 and 14 are not joined by an edge"), "{e}");
        let j = r#"{"loops": [{"name": "tail", "parent_loop": [0, 1, 2, 3], "child_loop": [20, 21, 22, 23]}]}"#;
        let e = parse_parts(j, &topo, &p).unwrap_err().to_string();
        assert!(e.contains("does not cut \"torso\" in two"), "{e}");
    }

    #[test]
    fn unknown_json_and_files_are_named() {
        let (topo, p) = tube(3);
        let e = parse_parts(r#"{"parts": []}"#, &topo, &p).unwrap_err().to_string();
        assert!(e.contains("without \"format\", \"labels\", \"planes\" or \"loops\""), "{e}");
        let d = std::env::temp_dir().join(format!("surfcap-parts-test-{}.json", std::process::id()));
        std::fs::write(&d, "{\"labels\": [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 9]}").unwrap();
        let e = read_parts_file(&d, &topo, &p).unwrap_err().to_string();
        std::fs::remove_file(&d).unwrap();
        assert!(e.contains(&format!("{}: part \"part_1\" (label 1) has no vertex", d.display())), "{e}");
        let b = BodyParts::whole_body(12);
        let b2 = parse_parts(&b.to_json(), &topo, &p).unwrap();
        assert_eq!(b, b2);
    }

    /// The canonical form refuses unknown fields, as the other forms do, naming the file and
    /// the field (a misspelt key must not be silently ignored).
    #[test]
    fn the_canonical_form_refuses_unknown_fields() {
        let (topo, p) = tube(3);
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("knight.parts.json");
        let good = BodyParts::whole_body(12).to_json();
        for (from, to, field) in [
            ("\"version\"", "\"colour\": \"red\",\n  \"version\"", "colour"),
            ("\"parent\"", "\"parnet\": null,\n      \"parent\"", "parnet"),
        ] {
            std::fs::write(&f, good.replacen(from, to, 1)).unwrap();
            let e = read_parts_file(&f, &topo, &p).unwrap_err().to_string();
            assert!(
                e.contains(&format!("{}: line", f.display())) && e.contains(&format!("unknown field `{field}`")),
                "{e}"
            );
        }
    }

    /// A FIFO (or folder) given as the parts file is refused naming the file and what it is.
    #[test]
    fn a_fifo_as_the_parts_file_is_named() {
        let (topo, p) = tube(3);
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("parts.json");
        assert!(std::process::Command::new("mkfifo").arg(&f).status().unwrap().success());
        let e = read_parts_file(&f, &topo, &p).unwrap_err().to_string();
        assert!(e.contains(&format!("{}: is a FIFO", f.display())) && e.starts_with("body parts: "), "{e}");
    }
}

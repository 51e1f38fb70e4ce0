//! The derived-product chain of one subject: pose distances -> transition table -> edge weights
//! -> essential or motion graph -> walk model, each produced lazily, once per process, and read
//! from the on-disk cache when it is there.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
use surfcap_mesh::derived_cache::{DerivedCache, subject_hash};
use surfcap_mesh::npy::NpyArray;
use surfcap_mesh::{Progress, Subject};
use surfcap_motion::clip_loops::{ClipLoop, clip_loops, segment_bounds_for_clips};
use surfcap_motion::edge_weights::{Alpha, EdgeWeights, edge_weights};
use surfcap_motion::essential_graph::essential_graph;
use surfcap_motion::graph::{Edge, Graph};
use surfcap_motion::motion_graph::motion_graph;
use surfcap_motion::sparse_essential_graph::sparse_essential_graph;
use surfcap_motion::transition_table::{TableParams, TransitionTable, check_distances, transition_table};
use surfcap_motion::walk_sequence::WalkModel;

use crate::error::{Error, Result};
use crate::graph_kind::GraphKind;
use crate::product_key::{DistanceKey, GraphKey, ProductKey, TableKey, WalkModelKey};

/// Where derived products are kept between runs.
#[derive(Debug, Clone)]
pub struct CacheStore {
    /// The cache folder; `None` computes everything and keeps it in memory only.
    pub cache: Option<DerivedCache>,
    /// Recompute (and replace) what is on disk, once per product and process (`--no-cache`).
    pub refresh: bool,
}

/// The cache folder every front end uses unless told otherwise, so that the command line and
/// the Python package share results: `$XDG_CACHE_HOME/surfcap`, else `~/.cache/surfcap`, else
/// `.cache/surfcap` (no home).
pub fn default_cache_dir() -> PathBuf {
    std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from(".cache"))
        .join("surfcap")
}

impl CacheStore {
    pub fn in_folder(dir: impl Into<PathBuf>, refresh: bool) -> Self {
        CacheStore { cache: Some(DerivedCache::new(dir)), refresh }
    }

    /// No disk cache: every product is computed (once per pipeline).
    pub fn memory_only() -> Self {
        CacheStore { cache: None, refresh: false }
    }
}

/// A product, whether it came from the disk cache, and its cache file.
#[derive(Debug)]
pub struct Fetched<T> {
    pub value: Arc<T>,
    pub from_cache: bool,
    pub file: Option<PathBuf>,
}

impl<T> Clone for Fetched<T> {
    fn clone(&self) -> Self {
        Fetched { value: self.value.clone(), from_cache: self.from_cache, file: self.file.clone() }
    }
}

/// The all-pairs pose distances of a subject.
///
/// On disk: `distance-<metric>-<key>.npy`, f64 `[F, F]`, row-major over the global frame index.
/// (Not geometry's `DistanceMatrix`: its count of skipped zero-area triangles is not stored, so a
/// matrix read from the cache could not fill it truthfully.)
#[derive(Debug, Clone, PartialEq)]
pub struct PoseDistances {
    pub n: usize,
    pub values: Vec<f64>,
}

/// Parameters of a graph over the frames (thesis 3.3).
#[derive(Debug, Clone, PartialEq)]
pub struct GraphParams {
    pub table: TableParams,
    pub kind: GraphKind,
    /// Tolerance between deformation and duration (eq. 3.2-3.3).
    pub alpha: Alpha,
}

/// Products of one kind already produced in this process, by key.
struct Memo<K, V>(Mutex<Vec<(K, Fetched<V>)>>);

impl<K: PartialEq + Clone, V> Memo<K, V> {
    fn new() -> Self {
        Memo(Mutex::new(Vec::new()))
    }

    fn get(&self, key: &K) -> Option<Fetched<V>> {
        self.0.lock().expect("memo lock").iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
    }

    fn get_or_try(&self, key: &K, make: impl FnOnce() -> Result<Fetched<V>>) -> Result<Fetched<V>> {
        if let Some((_, v)) = self.0.lock().expect("memo lock").iter().find(|(k, _)| k == key) {
            return Ok(v.clone());
        }
        let v = make()?;
        self.0.lock().expect("memo lock").push((key.clone(), v.clone()));
        Ok(v)
    }
}

/// One subject's derived products, produced lazily and once: from the disk cache when an entry
/// is there and decodes for this subject, computed (with progress) and stored otherwise.
///
/// The chain's distance matrix (the one transition tables, graphs and walk models are built
/// on) is the deformation distance with w = 0.01 (thesis eq. 2.13) unless
/// [`Pipeline::with_chain_distance`] says otherwise.
pub struct Pipeline {
    subject: Subject,
    store: CacheStore,
    progress: Box<dyn Progress + Send>,
    chain_distance: DistanceParams,
    hash: OnceLock<blake3::Hash>,
    /// The subject's looping clips, detected once.
    loops: OnceLock<Vec<ClipLoop>>,
    distances: Memo<DistanceKey, PoseDistances>,
    tables: Memo<TableKey, TransitionTable>,
    /// The edge weights of the last (table, alpha) asked for: the essential and the motion graph
    /// of one alpha share them.
    weights: Mutex<Option<(TableKey, Alpha, Arc<EdgeWeights>)>>,
    graphs: Memo<GraphKey, Graph>,
    walk_models: Memo<WalkModelKey, WalkModel>,
}

impl Pipeline {
    pub fn new(subject: Subject, store: CacheStore, progress: Box<dyn Progress + Send>) -> Self {
        Pipeline {
            subject,
            store,
            progress,
            chain_distance: DistanceParams::default(),
            hash: OnceLock::new(),
            loops: OnceLock::new(),
            distances: Memo::new(),
            tables: Memo::new(),
            weights: Mutex::new(None),
            graphs: Memo::new(),
            walk_models: Memo::new(),
        }
    }

    /// Builds tables, graphs and walk models on this distance instead of the default.
    pub fn with_chain_distance(mut self, p: DistanceParams) -> Self {
        self.chain_distance = p;
        self
    }

    pub fn subject(&self) -> &Subject {
        &self.subject
    }

    /// The subject's looping clips ([`surfcap_motion::clip_loops`]), detected on first use and
    /// kept: the wrap edges, the walk model and every front end's defaults share them.
    pub fn loops(&self) -> &[ClipLoop] {
        self.loops.get_or_init(|| clip_loops(&self.subject))
    }

    /// Default segment bounds (shortest, longest window, frames) for the subject: the thesis's
    /// third of a second to two seconds, the longest at most half the shortest looping clip
    /// ([`segment_bounds_for_clips`]).
    pub fn segment_bounds(&self) -> (usize, usize) {
        segment_bounds_for_clips(self.subject.fps, self.subject.frame_index(), self.loops())
    }

    /// Gives the subject back (the products are dropped).
    pub fn into_subject(self) -> Subject {
        self.subject
    }

    pub fn store(&self) -> &CacheStore {
        &self.store
    }

    pub fn chain_distance(&self) -> &DistanceParams {
        &self.chain_distance
    }

    fn subject_hash(&self) -> &blake3::Hash {
        self.hash.get_or_init(|| subject_hash(&self.subject))
    }

    /// The cache file of a product key (whether or not it exists yet), `None` without a cache.
    pub fn cache_file(&self, key: &impl ProductKey) -> Option<PathBuf> {
        self.store.cache.as_ref().map(|c| key.path(c, self.subject_hash()))
    }

    /// Reads, or computes and stores, one product (see [`DerivedCache::fetch`]).
    fn fetch<T, V>(
        &self,
        key: &impl ProductKey,
        compute: impl Fn() -> Result<NpyArray<T>>,
        decode: impl Fn(NpyArray<T>) -> Result<V>,
    ) -> Result<Fetched<V>>
    where
        T: surfcap_mesh::npy::NpyElement + npyz::AutoSerialize,
    {
        match (&self.store.cache, self.cache_file(key)) {
            (Some(cache), Some(file)) => {
                let (v, from_cache) = cache.fetch(&file, self.store.refresh, &*self.progress, compute, decode)?;
                Ok(Fetched { value: Arc::new(v), from_cache, file: Some(file) })
            }
            _ => Ok(Fetched { value: Arc::new(decode(compute()?)?), from_cache: false, file: None }),
        }
    }

    /// The all-pairs pose distance matrix (thesis eq. 2.2, 2.13, 2.14) with `p`.
    pub fn distances(&self, p: &DistanceParams) -> Result<Fetched<PoseDistances>> {
        check_distance(p)?;
        let key = DistanceKey::new(p);
        let n = self.subject.n_frames();
        // Set once the matrix is computed here: only a matrix read from the cache is suspected
        // of being zeros it should not be (a subject whose frames differ only rigidly does
        // compute to zeros under the deformation distances).
        let computed = std::cell::Cell::new(false);
        self.distances.get_or_try(&key, || {
            self.fetch(
                &key,
                || {
                    computed.set(true);
                    let d = distance_matrix(&self.subject, p, &*self.progress);
                    Ok(NpyArray { shape: vec![d.n, d.n], data: d.values })
                },
                |a: NpyArray<f64>| {
                    check_shape(&a.shape, &[n, n], "distance matrix")?;
                    check_distances(&a.data, self.subject.frame_index())?;
                    if !computed.get() {
                        check_distances_make_sense(&a.data, n)?;
                    }
                    Ok(PoseDistances { n, values: a.data })
                },
            )
        })
    }

    /// One entry d(i, j) of [`Pipeline::distances`] with `p`, the same bits as the matrix's:
    /// read from the matrix when this pipeline has already produced it, computed for the pair
    /// alone otherwise ([`surfcap_geometry::distance_matrix::pair_distance`]).
    pub fn pose_distance(&self, p: &DistanceParams, i: usize, j: usize) -> Result<f64> {
        check_distance(p)?;
        let n = self.subject.n_frames();
        if i >= n || j >= n {
            return Err(Error::Parameter {
                name: "frame",
                value: i.max(j).to_string(),
                expected: "expected a frame of the subject",
            });
        }
        if let Some(d) = self.distances.get(&DistanceKey::new(p)) {
            return Ok(d.value.values[i * n + j]);
        }
        Ok(surfcap_geometry::distance_matrix::pair_distance(&self.subject, p, i, j).expect("frames checked"))
    }

    /// The chain's distance matrix (see [`Pipeline::with_chain_distance`]).
    pub fn chain_distances(&self) -> Result<Fetched<PoseDistances>> {
        self.distances(&self.chain_distance.clone())
    }

    /// The all-pairs transition table (thesis 2.5.3-2.5.4) on the chain's distances.
    ///
    /// On disk: `transitions-<key>.npy`, f64 `[4, F, F]`: the normalised cost (infinity where
    /// no transition fits), the duration L, and the segment lengths l^i and l^j.
    pub fn table(&self, p: &TableParams) -> Result<Fetched<TransitionTable>> {
        check_table(p)?;
        let key = TableKey::new(&self.chain_distance, p);
        let n = self.subject.n_frames();
        self.tables.get_or_try(&key, || {
            self.fetch(
                &key,
                || {
                    let d = self.chain_distances()?;
                    let t = transition_table(&d.value.values, self.subject.frame_index(), p, &*self.progress)?;
                    let mut data = t.cost;
                    data.extend(t.len.iter().map(|&x| x as f64));
                    data.extend(t.li.iter().map(|&x| x as f64));
                    data.extend(t.lj.iter().map(|&x| x as f64));
                    Ok(NpyArray { shape: vec![4, n, n], data })
                },
                |a: NpyArray<f64>| {
                    check_shape(&a.shape, &[4, n, n], "transition table")?;
                    let part = |k: usize| &a.data[k * n * n..(k + 1) * n * n];
                    // Counts stored as f64: whole numbers that fit a u32, or the table is refused
                    // (rather than NaN or -1 silently becoming 0).
                    let whole = |k: usize| -> Result<Vec<u32>> {
                        let count = |x: f64| (x >= 0.0 && x <= u32::MAX as f64 && x.fract() == 0.0).then_some(x as u32);
                        let bad = |x: f64| Error::Product {
                            kind: "transition table",
                            reason: format!("length {x} in layer {k}, expected a whole number >= 0"),
                        };
                        part(k).iter().map(|&x| count(x).ok_or_else(|| bad(x))).collect()
                    };
                    let t = TransitionTable { n, cost: part(0).to_vec(), len: whole(1)?, li: whole(2)?, lj: whole(3)? };
                    t.check(self.subject.frame_index(), p.l_min..=p.l_max)?;
                    Ok(t)
                },
            )
        })
    }

    /// Edge weights of the table at `alpha` (Algorithm 1) with the wrap edges of looping clips
    /// ([`surfcap_motion::clip_loops`]) at the weight of a successive step; kept for the last
    /// (table, alpha).
    pub fn edge_weights(&self, p: &TableParams, alpha: Alpha) -> Result<Arc<EdgeWeights>> {
        let key = TableKey::new(&self.chain_distance, p);
        if let Some((k, a, w)) = self.weights.lock().expect("weights lock").as_ref()
            && *k == key
            && *a == alpha
        {
            return Ok(w.clone());
        }
        let mut w = edge_weights(&self.table(p)?.value, self.subject.frame_index(), alpha)?;
        // Looping clips play their last frame into their start as a successive step.
        surfcap_motion::clip_loops::add_wrap_edges(&mut w, self.loops());
        let w = Arc::new(w);
        *self.weights.lock().expect("weights lock") = Some((key, alpha, w.clone()));
        Ok(w)
    }

    fn graph_key(&self, p: &GraphParams) -> GraphKey {
        GraphKey { table: TableKey::new(&self.chain_distance, &p.table), kind: p.kind, alpha: p.alpha }
    }

    /// The essential graph, the sparse essential graph or the motion graph (thesis 3.3)
    /// over all frames.
    ///
    /// On disk: `graph-<key>.npy`, f64 `[E, 3]`: from, to, weight of every edge.
    pub fn graph(&self, p: &GraphParams) -> Result<Fetched<Graph>> {
        check_table(&p.table)?;
        let key = self.graph_key(p);
        let n = self.subject.n_frames();
        self.graphs.get_or_try(&key, || {
            self.fetch(
                &key,
                || {
                    let w = self.edge_weights(&p.table, p.alpha)?;
                    let g = match p.kind {
                        GraphKind::Essential => essential_graph(&w, &*self.progress).graph,
                        GraphKind::Motion => motion_graph(&w, self.subject.frame_index()).graph,
                        GraphKind::SparseEssential { k } => {
                            sparse_essential_graph(&w, self.subject.frame_index(), k, &*self.progress).graph
                        }
                    };
                    let data = g.edges().iter().flat_map(|e| [e.from as f64, e.to as f64, e.weight]).collect();
                    Ok(NpyArray { shape: vec![g.edges().len(), 3], data })
                },
                |a: NpyArray<f64>| {
                    if a.shape.len() != 2 || a.shape[1] != 3 {
                        return Err(shape_error(&a.shape, "[E, 3]", "graph"));
                    }
                    let mut edges = Vec::with_capacity(a.shape[0]);
                    for (k, e) in a.data.chunks_exact(3).enumerate() {
                        let node = |x: f64| (x >= 0.0 && x < n as f64 && x.fract() == 0.0).then_some(x as u32);
                        let (Some(from), Some(to)) = (node(e[0]), node(e[1])) else {
                            return Err(shape_error(&a.shape, "edges between this subject's frames", "graph"));
                        };
                        if !(e[2].is_finite() && e[2] >= 0.0) {
                            let reason = format!("edge {k} has weight {}, expected a finite weight >= 0", e[2]);
                            return Err(Error::Product { kind: "graph", reason });
                        }
                        edges.push(Edge { from, to, weight: e[2] });
                    }
                    Ok(Graph::new(n, edges))
                },
            )
        })
    }

    /// The walk model of a graph: every transition's rigid track (the centres of its Blend
    /// frames and its end placement) of the centre of `tracked` (all vertices when `None`).
    ///
    /// On disk: `walkmodel-<key>.npy`, f32 `[R, 3]` rows
    /// ([`WalkModel::tracks_to_rows`] documents them). A freshly computed model is read back
    /// from its f32 rows too, so a cached and an uncached run search the same numbers and find
    /// the same walk (f32 keeps frame numbers exact below 2^24). On a dense graph it costs as
    /// much as the graph itself (one DTW per transition); transition warps are not stored but
    /// recomputed from the distance matrix when a walk is played.
    pub fn walk_model(&self, p: &GraphParams, tracked: Option<&[usize]>) -> Result<Fetched<WalkModel>> {
        let s = &self.subject;
        if s.n_frames() >= 1 << 24 {
            return Err(Error::Request(format!("{} frames: the walk model cache holds fewer than 2^24", s.n_frames())));
        }
        if let Some(ids) = tracked {
            let nv = s.topology().n_vertices();
            if let Some(v) = ids.iter().find(|&&v| v >= nv) {
                return Err(Error::Request(format!("tracked vertex {v}: the subject has vertices 0 to {}", nv - 1)));
            }
        }
        let captured_placement = surfcap_motion::subject_placement::subject_travel(s).placement
            == surfcap_motion::subject_placement::Placement::Captured;
        let key =
            WalkModelKey { graph: self.graph_key(p), tracked: tracked.map(<[usize]>::to_vec), captured_placement };
        let slope = p.table.slope;
        self.walk_models.get_or_try(&key, || {
            self.fetch(
                &key,
                || {
                    let graph = self.graph(p)?;
                    let table = self.table(&p.table)?;
                    let d = self.chain_distances()?;
                    let rows =
                        WalkModel::new(s, self.loops(), &graph.value, &table.value, &d.value.values, slope, tracked)
                            .tracks_to_rows()
                            .iter()
                            .map(|&x| x as f32)
                            .collect::<Vec<f32>>();
                    Ok(NpyArray { shape: vec![rows.len() / 3, 3], data: rows })
                },
                |a: NpyArray<f32>| {
                    if a.shape.len() != 2 || a.shape[1] != 3 {
                        return Err(shape_error(&a.shape, "[R, 3]", "walk model"));
                    }
                    let rows: Vec<f64> = a.data.iter().map(|&x| x as f64).collect();
                    WalkModel::from_rows(s, &rows, tracked, slope)
                        .map_err(|e| Error::Product { kind: "walk model", reason: e.to_string() })
                },
            )
        })
    }
}

/// What a stored distance matrix must be besides finite and >= 0: zero on its diagonal and,
/// over more than one frame, not zero between every pair of frames (an all-zero matrix makes
/// every transition free).
fn check_distances_make_sense(d: &[f64], n: usize) -> Result<()> {
    if let Some(i) = (0..n).find(|&i| d[i * n + i] != 0.0) {
        let reason = format!("distance {} from frame {i} to itself, expected 0", d[i * n + i]);
        return Err(Error::Product { kind: "distance matrix", reason });
    }
    if n > 1 && d.iter().all(|&x| x == 0.0) {
        let reason = format!("all {n} x {n} distances are 0: expected distances between different poses");
        return Err(Error::Product { kind: "distance matrix", reason });
    }
    Ok(())
}

fn shape_error(shape: &[usize], expected: &str, what: &'static str) -> Error {
    Error::Product { kind: what, reason: format!("shape {shape:?}, expected {expected}") }
}

fn check_shape(shape: &[usize], expected: &[usize], what: &'static str) -> Result<()> {
    if shape == expected { Ok(()) } else { Err(shape_error(shape, &format!("{expected:?}"), what)) }
}

/// The stretch weight of a distance: finite and >= 0.
fn check_distance(p: &DistanceParams) -> Result<()> {
    if p.w.is_finite() && p.w >= 0.0 {
        Ok(())
    } else {
        Err(Error::Parameter { name: "w", value: p.w.to_string(), expected: "expected a finite number >= 0" })
    }
}

pub(crate) fn check_table(p: &TableParams) -> Result<()> {
    if 1 <= p.l_min && p.l_min <= p.l_max {
        Ok(())
    } else {
        Err(Error::Parameter {
            name: "segment lengths",
            value: format!("{}..{}", p.l_min, p.l_max),
            expected: "expected 1 <= l-min <= l-max",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_builtin::{WormParams, worm_subject};
    use surfcap_mesh::NoProgress;

    fn worm() -> Subject {
        worm_subject(&WormParams { rings: 8, segments: 6, frames: 24, ..Default::default() }).unwrap()
    }

    fn params() -> GraphParams {
        GraphParams {
            table: TableParams { l_min: 3, l_max: 6, slope: Some(3) },
            kind: GraphKind::Essential,
            alpha: Alpha::new(0.05).unwrap(),
        }
    }

    #[test]
    fn products_are_computed_once_then_read_from_the_cache_identically() {
        let dir = tempfile::tempdir().unwrap();
        let p = params();
        let first = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let model = first.walk_model(&p, None).unwrap();
        assert!(!model.from_cache);
        assert!(!first.graph(&p).unwrap().from_cache, "computed once in this process, remembered as computed");
        let files: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        // Every entry has its content hash beside it.
        for f in files.iter().filter(|f| f.ends_with(".npy")) {
            assert!(files.contains(&format!("{f}.b3")), "{f} has no content hash in {files:?}");
        }
        let files: Vec<&String> = files.iter().filter(|f| f.ends_with(".npy")).collect();
        for kind in ["distance-deformation-", "transitions-", "graph-", "walkmodel-"] {
            assert_eq!(files.iter().filter(|f| f.starts_with(kind)).count(), 1, "{kind} in {files:?}");
        }
        let second = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let again = second.walk_model(&p, None).unwrap();
        assert!(again.from_cache);
        assert_eq!(again.value.tracks_to_rows(), model.value.tracks_to_rows());
        assert_eq!(second.graph(&p).unwrap().value.edges(), first.graph(&p).unwrap().value.edges());
        assert_eq!(*second.table(&p.table).unwrap().value, *first.table(&p.table).unwrap().value);
        // Without a cache folder the same numbers come out.
        let memory = Pipeline::new(worm(), CacheStore::memory_only(), Box::new(NoProgress));
        assert_eq!(memory.walk_model(&p, None).unwrap().value.tracks_to_rows(), model.value.tracks_to_rows());
        // Refresh recomputes what is on disk.
        let refresh = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), true), Box::new(NoProgress));
        assert!(!refresh.chain_distances().unwrap().from_cache);
    }

    #[test]
    fn one_pose_distance_is_the_matrix_entry_before_and_after_the_matrix_is_made() {
        let pipe = Pipeline::new(worm(), CacheStore::memory_only(), Box::new(NoProgress));
        let p = DistanceParams::default();
        let n = pipe.subject().n_frames();
        let alone: Vec<f64> = (0..n).map(|j| pipe.pose_distance(&p, 3, j).unwrap()).collect();
        let m = pipe.distances(&p).unwrap().value;
        for (j, d) in alone.iter().enumerate() {
            assert_eq!(d.to_bits(), m.values[3 * n + j].to_bits(), "pair (3, {j})");
            assert_eq!(pipe.pose_distance(&p, j, 3).unwrap().to_bits(), m.values[j * n + 3].to_bits());
        }
        let bad = DistanceParams { w: f64::NAN, ..DistanceParams::default() };
        assert_eq!(pipe.pose_distance(&bad, 0, 1).unwrap_err().to_string(), "w NaN: expected a finite number >= 0");
        let e = pipe.pose_distance(&p, 0, n).unwrap_err().to_string();
        assert!(e.starts_with(&format!("frame {n}:")), "{e}");
    }

    /// The sparse essential graph is a product of its own, keyed by k: with every transition
    /// kept it is the exact essential graph, with few it has other edges, and both are cached.
    #[test]
    fn the_sparse_essential_graph_is_cached_per_k() {
        let dir = tempfile::tempdir().unwrap();
        let pipe = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let n = pipe.subject().n_frames();
        let with = |kind| GraphParams { kind, ..params() };
        let exact = pipe.graph(&params()).unwrap().value;
        let all = pipe.graph(&with(GraphKind::SparseEssential { k: n })).unwrap().value;
        let few = pipe.graph(&with(GraphKind::SparseEssential { k: 1 })).unwrap().value;
        assert_eq!(all.edges(), exact.edges());
        assert_ne!(few.edges(), exact.edges());
        let graphs = std::fs::read_dir(dir.path())
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with("graph-"));
        assert_eq!(graphs.count(), 6, "three entries and their content hashes");
        let again = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let cached = again.graph(&with(GraphKind::SparseEssential { k: 1 })).unwrap();
        assert!(cached.from_cache);
        assert_eq!(cached.value.edges(), few.edges());
    }

    #[test]
    fn a_damaged_or_misfitting_entry_is_recomputed() {
        let dir = tempfile::tempdir().unwrap();
        let p = params();
        let pipe = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let table = pipe.table(&p.table).unwrap();
        let file = table.file.clone().unwrap();
        surfcap_mesh::atomic::write_file(&file, |w| surfcap_mesh::npy::write_npy(w, &[2], &[1.0f64, 2.0])).unwrap();
        let fresh = Pipeline::new(worm(), CacheStore::in_folder(dir.path(), false), Box::new(NoProgress));
        let again = fresh.table(&p.table).unwrap();
        assert!(!again.from_cache);
        assert_eq!(*again.value, *table.value);
    }

    #[test]
    fn bad_parameters_are_refused() {
        let pipe = Pipeline::new(worm(), CacheStore::memory_only(), Box::new(NoProgress));
        // A graph cannot be asked for with alpha 0: it is refused where it is made.
        assert!(Alpha::new(0.0).unwrap_err().to_string().contains("alpha 0"));
        let bad_lengths = GraphParams { table: TableParams { l_min: 5, l_max: 4, slope: None }, ..params() };
        assert!(pipe.graph(&bad_lengths).unwrap_err().to_string().contains("l-min"));
        let n = pipe.subject().topology().n_vertices();
        assert!(pipe.walk_model(&params(), Some(&[n])).unwrap_err().to_string().contains(&format!("{n}")));
    }
}

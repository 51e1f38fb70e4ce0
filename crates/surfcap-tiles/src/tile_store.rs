//! The on-disk store of a work folder: Zarr v3 arrays whose chunks are the tiles, for the large
//! products (numpy/xarray users open them with `zarr.open` without loading everything), and
//! small `.npy`/JSON files for the rest:
//!
//! ```text
//! plan.json                    the plan (tile_plan.rs)
//! distances.zarr               f64 [n, n], chunks [tile, tile]: the symmetric pose distances
//!                              (each upper tile written with its mirror image)
//! table/cost.zarr              f64 [n, n]: the transition costs D (eq. 2.55; inf: no windows fit)
//! table/len.zarr, li.zarr, lj.zarr   u32 [n, n]: L, l^i, l^j
//! scale.json                   the median of the finite D (Algorithm 1's scale)
//! candidates/edges_<k>.npy     f64 [m, 3]: (from, to, weight) kept for source rows block k
//! paths/costs.zarr             f64 [n, n]: shortest-path costs on the sparse graph
//! paths/tree_<k>.npy           u32 [m, 2]: (predecessor, node) edges of block k's trees
//! jobs/<stage>/<index>.json    a job's record, written last: the plan's hash and each output's
//!                              size and BLAKE3; the job is done when it is there and they match
//! ```
//!
//! Every chunk and file is written atomically (temporary + rename, `surfcap_mesh::atomic`): a
//! chunk is encoded by zarrs into memory and its bytes renamed into place, so a killed job never
//! leaves a half-written chunk, and a job rerun rewrites identical bytes. Chunks are stored
//! uncompressed (the `bytes` codec, little endian): distances do not compress well and the
//! chunk's size is then known from the tile alone.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use zarrs::array::{Array, ArrayBuilder, CodecOptions, DataType, data_type};
use zarrs::filesystem::FilesystemStore;
use zarrs::storage::store::MemoryStore;
use zarrs::storage::{ReadableStorageTraits, ReadableWritableListableStorage};

use crate::error::{Error, Result};
use crate::tile_plan::{Plan, Stage};

/// An n x n array of the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Matrix {
    Distances,
    TableCost,
    TableLen,
    TableLi,
    TableLj,
    PathCosts,
}

impl Matrix {
    pub const ALL: [Matrix; 6] =
        [Matrix::Distances, Matrix::TableCost, Matrix::TableLen, Matrix::TableLi, Matrix::TableLj, Matrix::PathCosts];

    /// Folder of the array inside the work folder.
    pub fn dir(self) -> &'static str {
        match self {
            Matrix::Distances => "distances.zarr",
            Matrix::TableCost => "table/cost.zarr",
            Matrix::TableLen => "table/len.zarr",
            Matrix::TableLi => "table/li.zarr",
            Matrix::TableLj => "table/lj.zarr",
            Matrix::PathCosts => "paths/costs.zarr",
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Matrix::Distances | Matrix::TableCost | Matrix::PathCosts)
    }

    fn data_type(self) -> DataType {
        if self.is_float() { data_type::float64() } else { data_type::uint32() }
    }
}

/// One file a job wrote: its place in the work folder, size and content hash.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputHash {
    /// Path relative to the work folder, `/`-separated (`distances.zarr/c/1/3`).
    pub file: String,
    pub bytes: u64,
    /// BLAKE3 of the file's bytes.
    pub blake3: String,
}

impl OutputHash {
    /// The hash of `bytes` written at `file`.
    pub fn of(file: String, bytes: &[u8]) -> OutputHash {
        OutputHash { file, bytes: bytes.len() as u64, blake3: blake3::hash(bytes).to_hex().to_string() }
    }
}

/// A job's record: written last, so its presence means the job's results are all in place, as
/// long as every output it lists still has its size and hash (`tile_verify.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobRecord {
    /// The hash of the plan the job ran for ([`Plan::hash`]).
    pub plan: String,
    pub stage: Stage,
    pub index: usize,
    /// What the job covered, in the user's terms (frames of the tile).
    pub span: String,
    /// The pose-distance kernel that computed distances (`distances` stage), else empty.
    pub kernel: String,
    pub seconds: f64,
    /// Peak resident memory of the process that ran the job, bytes (0 where unknown).
    pub peak_bytes: u64,
    /// Stage-specific numbers (skipped triangles, edges kept...).
    pub details: serde_json::Value,
    /// Every file the job wrote, in the order written.
    pub outputs: Vec<OutputHash>,
}

/// A work folder's store.
pub struct Store {
    root: PathBuf,
    n: usize,
    tile: usize,
    fs: ReadableWritableListableStorage,
}

fn zarr_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Zarr { path: path.to_path_buf(), message: e.to_string() }
}

impl Store {
    /// Opens the store of the work folder `root` planned by `plan`.
    pub fn open(root: &Path, plan: &Plan) -> Result<Store> {
        let fs = FilesystemStore::new(root).map_err(|e| zarr_err(root, e))?;
        Ok(Store { root: root.to_path_buf(), n: plan.frames(), tile: plan.tile, fs: Arc::new(fs) })
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    fn builder(&self, m: Matrix) -> ArrayBuilder {
        let (n, t) = (self.n as u64, self.tile.min(self.n.max(1)) as u64);
        let mut b = if m.is_float() {
            // NaN marks a chunk never written (a missing tile reads as NaN, never as a distance).
            ArrayBuilder::new(vec![n, n], vec![t, t], m.data_type(), f64::NAN)
        } else {
            ArrayBuilder::new(vec![n, n], vec![t, t], m.data_type(), 0u32)
        };
        b.dimension_names(["row_frame", "col_frame"].into());
        b
    }

    fn array(&self, m: Matrix) -> Result<Array<dyn zarrs::storage::ReadableWritableListableStorageTraits>> {
        self.builder(m)
            .build(self.fs.clone(), &format!("/{}", m.dir()))
            .map_err(|e| zarr_err(&self.root.join(m.dir()), e))
    }

    /// Writes every array's metadata (`zarr.json`), at planning.
    pub fn create_arrays(&self) -> Result<()> {
        for m in Matrix::ALL {
            let a = self.array(m)?;
            let bytes = serde_json::to_vec_pretty(a.metadata()).map_err(|e| zarr_err(&self.root, e))?;
            let path = self.root.join(m.dir()).join("zarr.json");
            surfcap_mesh::atomic::write_file(&path, |w| w.write_all(&bytes))?;
        }
        // The groups above the arrays, so `zarr.open(work)` lists them.
        for group in ["", "table", "paths"] {
            let path = self.root.join(group).join("zarr.json");
            let text = br#"{"zarr_format": 3, "node_type": "group", "attributes": {}}"#;
            surfcap_mesh::atomic::write_file(&path, |w| w.write_all(text))?;
        }
        Ok(())
    }

    /// The file of chunk (ci, cj) of `m`.
    pub fn chunk_path(&self, m: Matrix, ci: usize, cj: usize) -> Result<PathBuf> {
        Ok(self.root.join(self.chunk_file(m, ci, cj)))
    }

    /// The file of chunk (ci, cj) of `m`, relative to the work folder, `/`-separated (the
    /// default Zarr v3 chunk key `c/ci/cj` under the array's folder).
    pub fn chunk_file(&self, m: Matrix, ci: usize, cj: usize) -> String {
        format!("{}/c/{ci}/{cj}", m.dir())
    }

    /// Bytes of every chunk of `m` (uncompressed: the tile's cells times the element size).
    pub fn chunk_bytes(&self, m: Matrix) -> u64 {
        let t = self.tile.min(self.n.max(1)) as u64;
        t * t * if m.is_float() { 8 } else { 4 }
    }

    /// Frames per side of the whole array and of a chunk.
    pub fn shape(&self) -> (usize, usize) {
        (self.n, self.tile.min(self.n.max(1)))
    }

    /// The metadata (`zarr.json`) of array `m` as this plan makes it.
    pub fn expected_metadata(&self, m: Matrix) -> Result<serde_json::Value> {
        let a = self.array(m)?;
        serde_json::to_value(a.metadata()).map_err(|e| zarr_err(&self.root, e))
    }

    /// Writes chunk (ci, cj) of a float array from a rows x cols block (padded to the chunk shape
    /// with the fill value), atomically.
    pub fn write_chunk_f64(
        &self,
        m: Matrix,
        ci: usize,
        cj: usize,
        rows: usize,
        cols: usize,
        values: &[f64],
    ) -> Result<OutputHash> {
        self.write_chunk(m, ci, cj, rows, cols, values, f64::NAN)
    }

    /// [`Store::write_chunk_f64`] for the u32 arrays.
    pub fn write_chunk_u32(
        &self,
        m: Matrix,
        ci: usize,
        cj: usize,
        rows: usize,
        cols: usize,
        values: &[u32],
    ) -> Result<OutputHash> {
        self.write_chunk(m, ci, cj, rows, cols, values, 0)
    }

    #[allow(clippy::too_many_arguments)]
    fn write_chunk<T: zarrs::array::Element + Copy>(
        &self,
        m: Matrix,
        ci: usize,
        cj: usize,
        rows: usize,
        cols: usize,
        values: &[T],
        fill: T,
    ) -> Result<OutputHash> {
        let t = self.tile.min(self.n.max(1));
        let mut chunk = vec![fill; t * t];
        for r in 0..rows {
            chunk[r * t..r * t + cols].copy_from_slice(&values[r * cols..(r + 1) * cols]);
        }
        self.write_encoded(m, ci, cj, |a| a.store_chunk_opt(&[ci as u64, cj as u64], chunk.as_slice(), &keep_all()))
    }

    /// Encodes a chunk with zarrs into memory, then renames its bytes into place.
    fn write_encoded(
        &self,
        m: Matrix,
        ci: usize,
        cj: usize,
        store: impl FnOnce(&Array<MemoryStore>) -> std::result::Result<(), zarrs::array::ArrayError>,
    ) -> Result<OutputHash> {
        let dir = self.root.join(m.dir());
        let mem = Arc::new(MemoryStore::new());
        let a = self.builder(m).build(mem.clone(), "/").map_err(|e| zarr_err(&dir, e))?;
        store(&a).map_err(|e| zarr_err(&dir, e))?;
        let key = a.chunk_key(&[ci as u64, cj as u64]);
        let bytes = mem.get(&key).map_err(|e| zarr_err(&dir, e))?.ok_or_else(|| zarr_err(&dir, "chunk not encoded"))?;
        let file = self.chunk_file(m, ci, cj);
        debug_assert_eq!(file, format!("{}/{}", m.dir(), key.as_str()), "the chunk key encoding");
        surfcap_mesh::atomic::write_file(&self.root.join(&file), |w| w.write_all(&bytes))?;
        Ok(OutputHash::of(file, &bytes))
    }

    /// Writes a small file of the store (`relative` `/`-separated) atomically, returning its hash.
    pub fn write_file(&self, relative: &str, bytes: &[u8]) -> Result<OutputHash> {
        surfcap_mesh::atomic::write_file(&self.file(relative), |w| w.write_all(bytes))?;
        Ok(OutputHash::of(relative.to_string(), bytes))
    }

    /// Whether every chunk covering rows x cols of `m` has been written: a regular file (not a
    /// link or a folder) of the chunk's size. (Contents are checked against the job records
    /// by `tile_verify.rs`.)
    pub fn has_region(&self, m: Matrix, rows: &std::ops::Range<usize>, cols: &std::ops::Range<usize>) -> Result<bool> {
        let t = self.tile;
        let size = self.chunk_bytes(m);
        for ci in rows.start / t..rows.end.div_ceil(t) {
            for cj in cols.start / t..cols.end.div_ceil(t) {
                match std::fs::symlink_metadata(self.chunk_path(m, ci, cj)?) {
                    Ok(md) if md.is_file() && md.len() == size => {}
                    _ => return Ok(false),
                }
            }
        }
        Ok(true)
    }

    /// Reads rows x cols of a float array, refusing a region with chunks never written.
    pub fn read_f64(&self, m: Matrix, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Result<Vec<f64>> {
        self.read(m, rows, cols)
    }

    /// Reads rows x cols of a u32 array, refusing a region with chunks never written.
    pub fn read_u32(&self, m: Matrix, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Result<Vec<u32>> {
        self.read(m, rows, cols)
    }

    fn read<T: zarrs::array::ElementOwned>(
        &self,
        m: Matrix,
        rows: std::ops::Range<usize>,
        cols: std::ops::Range<usize>,
    ) -> Result<Vec<T>> {
        self.require(m, &rows, &cols)?;
        let a = self.array(m)?;
        let subset = [rows.start as u64..rows.end as u64, cols.start as u64..cols.end as u64];
        a.retrieve_array_subset_opt::<Vec<T>>(&subset, &CodecOptions::default())
            .map_err(|e| zarr_err(&self.root.join(m.dir()), e))
    }

    fn require(&self, m: Matrix, rows: &std::ops::Range<usize>, cols: &std::ops::Range<usize>) -> Result<()> {
        if !self.has_region(m, rows, cols)? {
            return Err(Error::Job(format!(
                "{}: frames {}..{} x {}..{} are not all computed yet: run the earlier stage's jobs first",
                self.root.join(m.dir()).display(),
                rows.start,
                rows.end,
                cols.start,
                cols.end
            )));
        }
        Ok(())
    }

    /// The record file of a job.
    pub fn record_path(&self, stage: Stage, index: usize) -> PathBuf {
        self.root.join("jobs").join(stage.name()).join(format!("{index}.json"))
    }

    /// The job's record if it is there (its outputs not checked: see `tile_verify.rs`).
    pub fn record(&self, stage: Stage, index: usize) -> Result<Option<JobRecord>> {
        let p = self.record_path(stage, index);
        match read_regular(&p) {
            Ok(bytes) => serde_json::from_slice(&bytes).map(Some).map_err(|e| Error::Plan {
                path: p,
                message: format!("damaged job record ({e}): delete it to run the job again"),
            }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(surfcap_mesh::Error::io(&p, "read", e).into()),
        }
    }

    /// Writes a job's record (last, atomically).
    pub fn write_record(&self, r: &JobRecord) -> Result<()> {
        let bytes = serde_json::to_vec_pretty(r).expect("records are plain data");
        surfcap_mesh::atomic::write_file(&self.record_path(r.stage, r.index), |w| w.write_all(&bytes))?;
        Ok(())
    }

    /// Path of a small file of the store.
    pub fn file(&self, relative: &str) -> PathBuf {
        self.root.join(relative)
    }
}

/// Reads a regular file without following a symlink at its place; a folder or anything else
/// there is an error naming it.
pub(crate) fn read_regular(p: &Path) -> std::io::Result<Vec<u8>> {
    let md = std::fs::symlink_metadata(p)?;
    if !md.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not a regular file (a folder, link or device is there)",
        ));
    }
    std::fs::read(p)
}

/// Codec options that write a chunk even when it holds only the fill value (zarrs skips those
/// by default; a tile of the table where no windows fit would then look missing).
fn keep_all() -> CodecOptions {
    CodecOptions::default().with_store_empty_chunks(true)
}

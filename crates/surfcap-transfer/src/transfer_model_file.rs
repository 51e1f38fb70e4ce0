//! A trained transfer on disk, so it is trained once and applied many times (the
//! trained model is a derived product, cached and reloadable).
//!
//! A folder (surfcap's marked folder output of kind [`KIND`]) holding:
//! - `model.json`: [`MotionTransfer`] (both subjects' references, parts and per-part PCA, the
//!   GP inputs, outputs and fitted hyper-parameters; the GP factorisations are recomputed on
//!   load, a few milliseconds for hundreds of pairs), with a `format`/`version` header;
//! - `target_training.npy`: f32 `[N, V, 3]`, the target's aligned training poses, the examples
//!   the part correction of 5.6.1 draws its nearest meshes from (numpy opens it).
//!
//! A Baran et al. model ([`BaranTransfer`], `transfer train --method baran`) is a folder of the
//! same kind holding `model.json` (format `surfcap-transfer-baran-model`: the subjects and the
//! source's triangles) and `source_keys.npy` / `target_keys.npy`, f32 `[K, V, 3]`, the key
//! poses. [`read_any`] reads either.

use std::path::Path;

use serde::{Deserialize, Serialize};
use surfcap_mesh::npy::{expect_shape, read_npy, write_npy};

use crate::baran_transfer::BaranTransfer;
use crate::error::{Error, Result};
use crate::motion_transfer::MotionTransfer;

/// The folder kind of a saved model (its `.surfcap-output.json` marker).
pub const KIND: &str = "transfer-model";
const FORMAT: &str = "surfcap-transfer-model";
const VERSION: u32 = 1;
const BARAN_FORMAT: &str = "surfcap-transfer-baran-model";

/// What a Baran et al. model's `model.json` holds besides the subjects.
#[derive(Serialize, Deserialize)]
struct BaranMeta {
    method: String,
    key_pairs: usize,
    source_vertices: usize,
    target_vertices: usize,
    source_triangles: Vec<[u32; 3]>,
}

#[derive(Serialize, Deserialize)]
struct Envelope<M, S> {
    format: String,
    version: u32,
    subjects: S,
    model: M,
}

/// What a saved model remembers of the two subjects besides their pose spaces: the target's
/// mesh and time base (a transferred motion is written as the target), and names for reports.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SubjectsMeta {
    pub source_name: String,
    pub source_fps: f64,
    /// [`mesh_fingerprint`] of the source's mesh: a motion to transfer must be on it.
    pub source_mesh: String,
    pub target_name: String,
    pub target_triangles: Vec<[u32; 3]>,
    pub target_fps: f64,
    pub target_up_axis: surfcap_mesh::UpAxis,
    pub target_units: surfcap_mesh::Units,
}

impl SubjectsMeta {
    pub fn new(source: &surfcap_mesh::Subject, target: &surfcap_mesh::Subject) -> SubjectsMeta {
        SubjectsMeta {
            source_name: source.name.clone(),
            source_fps: source.fps,
            source_mesh: mesh_fingerprint(source.topology()),
            target_name: target.name.clone(),
            target_triangles: target.topology().triangles().to_vec(),
            target_fps: target.fps,
            target_up_axis: target.up_axis,
            target_units: target.units.clone(),
        }
    }
}

/// A short fingerprint of a mesh's connectivity (vertex count and triangles; FNV-1a, 64 bits,
/// hex), so a motion on another mesh with the same vertex count is refused rather than
/// transferred into nonsense.
pub fn mesh_fingerprint(topology: &surfcap_mesh::Topology) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    // The same mesh with its triangles listed in another order, or each started at another
    // corner, is the same mesh: each triangle is turned to start at its smallest index
    // (keeping its orientation) and the list sorted.
    let mut tris: Vec<[u32; 3]> = topology
        .triangles()
        .iter()
        .map(|t| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    tris.sort_unstable();
    eat(topology.n_vertices() as u32);
    for t in &tris {
        t.iter().for_each(|&v| eat(v));
    }
    format!("{h:016x}")
}

/// A model read back.
pub struct SavedModel {
    pub model: MotionTransfer,
    pub subjects: SubjectsMeta,
    /// The target's aligned training poses.
    pub target_training: Vec<Vec<f32>>,
}

/// Writes `model.json` and `target_training.npy` into `dir` (which the caller has claimed).
pub fn write_model(
    dir: &Path,
    model: &MotionTransfer,
    subjects: &SubjectsMeta,
    target_training: &[Vec<f32>],
) -> Result<()> {
    let nv = model.target.reference.len() / 3;
    if let Some(bad) = target_training.iter().position(|p| p.len() != 3 * nv) {
        return Err(Error::Invalid(format!("target training pose {bad}: expected {nv} vertices")));
    }
    let env = Envelope { format: FORMAT.into(), version: VERSION, subjects, model };
    surfcap_mesh::atomic::write_file(&dir.join("model.json"), |w| {
        serde_json::to_writer(&mut *w, &env).map_err(std::io::Error::other)
    })?;
    let flat: Vec<f32> = target_training.iter().flatten().copied().collect();
    surfcap_mesh::atomic::write_file(&dir.join("target_training.npy"), |w| {
        write_npy(w, &[target_training.len(), nv, 3], &flat)
    })?;
    Ok(())
}

/// Reads a model written by [`write_model`]; errors name the file and what was expected.
pub fn read_model(dir: &Path) -> Result<SavedModel> {
    let path = dir.join("model.json");
    let bytes = surfcap_mesh::read_regular_file(&path)?;
    let bad = |why: String| Error::Invalid(format!("{}: {why}", path.display()));
    let head: Envelope<serde::de::IgnoredAny, serde::de::IgnoredAny> = serde_json::from_slice(&bytes)
        .map_err(|e| bad(format!("{e}: expected a model written by surfcap transfer train")))?;
    if head.format != FORMAT || head.version != VERSION {
        return Err(bad(format!(
            "format {:?} version {}: expected {FORMAT:?} version {VERSION} (retrain with this surfcap)",
            head.format, head.version
        )));
    }
    let env: Envelope<MotionTransfer, SubjectsMeta> =
        serde_json::from_slice(&bytes).map_err(|e| bad(format!("{e}")))?;
    let model = env.model;
    model.source.parts.validate().map_err(|e| bad(format!("source {e}")))?;
    model.target.parts.validate().map_err(|e| bad(format!("target {e}")))?;
    let nv = model.target.reference.len() / 3;
    let npy_path = dir.join("target_training.npy");
    let a = read_npy::<f32>(&npy_path)?;
    expect_shape(&a, &[None, Some(nv), Some(3)], "the target's training poses").map_err(|e| e.in_file(&npy_path))?;
    if let Some(k) = a.data.iter().position(|x| !x.is_finite()) {
        return Err(Error::Invalid(format!(
            "{}: training pose {}, vertex {}: coordinate {}: expected finite coordinates",
            npy_path.display(),
            k / (3 * nv),
            (k / 3) % nv,
            a.data[k]
        )));
    }
    if env.subjects.target_triangles.iter().flatten().any(|&v| v as usize >= nv) {
        return Err(bad(format!("the target's triangles name vertices beyond its {nv}")));
    }
    let target_training = a.data.chunks_exact(3 * nv).map(<[f32]>::to_vec).collect();
    Ok(SavedModel { model, subjects: env.subjects, target_training })
}

/// A Baran et al. model read back.
pub struct SavedBaran {
    pub model: BaranTransfer,
    pub subjects: SubjectsMeta,
}

/// Either kind of saved model.
pub enum SavedTransfer {
    /// GP regression on body parts.
    Gp(Box<SavedModel>),
    /// Baran et al. 2009.
    Baran(Box<SavedBaran>),
}

/// Writes a Baran et al. model (`model.json`, `source_keys.npy`, `target_keys.npy`) into `dir`
/// (which the caller has claimed).
pub fn write_baran_model(dir: &Path, model: &BaranTransfer, subjects: &SubjectsMeta) -> Result<()> {
    let (ns, nt) = (model.source_vertices(), model.target_vertices());
    let k = model.source_keys.len();
    if k == 0 || model.target_keys.len() != k {
        return Err(Error::Invalid(format!(
            "{k} source and {} target key poses: expected the same number, at least one",
            model.target_keys.len()
        )));
    }
    let meta = BaranMeta {
        method: "baran".into(),
        key_pairs: k,
        source_vertices: ns,
        target_vertices: nt,
        source_triangles: model.source_triangles.clone(),
    };
    let env = Envelope { format: BARAN_FORMAT.into(), version: VERSION, subjects, model: meta };
    surfcap_mesh::atomic::write_file(&dir.join("model.json"), |w| {
        serde_json::to_writer(&mut *w, &env).map_err(std::io::Error::other)
    })?;
    for (name, keys, nv) in [("source_keys.npy", &model.source_keys, ns), ("target_keys.npy", &model.target_keys, nt)] {
        if let Some(bad) = keys.iter().position(|p| p.len() != 3 * nv) {
            return Err(Error::Invalid(format!("key pose {bad} of {name}: expected {nv} vertices")));
        }
        let flat: Vec<f32> = keys.iter().flatten().copied().collect();
        surfcap_mesh::atomic::write_file(&dir.join(name), |w| write_npy(w, &[k, nv, 3], &flat))?;
    }
    Ok(())
}

/// Reads a model written by [`write_model`] or [`write_baran_model`]; errors name the file and
/// what was expected.
pub fn read_any(dir: &Path) -> Result<SavedTransfer> {
    let path = dir.join("model.json");
    let bytes = surfcap_mesh::read_regular_file(&path)?;
    let bad = |why: String| Error::Invalid(format!("{}: {why}", path.display()));
    let head: Envelope<serde::de::IgnoredAny, serde::de::IgnoredAny> = serde_json::from_slice(&bytes)
        .map_err(|e| bad(format!("{e}: expected a model written by surfcap transfer train")))?;
    if head.format != BARAN_FORMAT {
        return read_model(dir).map(|m| SavedTransfer::Gp(Box::new(m)));
    }
    if head.version != VERSION {
        return Err(bad(format!(
            "format {:?} version {}: expected version {VERSION} (retrain with this surfcap)",
            head.format, head.version
        )));
    }
    let env: Envelope<BaranMeta, SubjectsMeta> = serde_json::from_slice(&bytes).map_err(|e| bad(format!("{e}")))?;
    let meta = env.model;
    let read_keys = |name: &str, nv: usize| -> Result<Vec<Vec<f32>>> {
        let p = dir.join(name);
        let a = read_npy::<f32>(&p)?;
        expect_shape(&a, &[Some(meta.key_pairs), Some(nv), Some(3)], "the key poses").map_err(|e| e.in_file(&p))?;
        if let Some(k) = a.data.iter().position(|x| !x.is_finite()) {
            return Err(Error::Invalid(format!(
                "{}: key pose {}, vertex {}: coordinate {}: expected finite coordinates",
                p.display(),
                k / (3 * nv),
                (k / 3) % nv,
                a.data[k]
            )));
        }
        Ok(a.data.chunks_exact(3 * nv.max(1)).map(<[f32]>::to_vec).collect())
    };
    for (tris, nv, who) in [
        (&meta.source_triangles, meta.source_vertices, "source"),
        (&env.subjects.target_triangles, meta.target_vertices, "target"),
    ] {
        if tris.iter().flatten().any(|&v| v as usize >= nv) {
            return Err(bad(format!("the {who}'s triangles name vertices beyond its {nv}")));
        }
    }
    let model = BaranTransfer {
        source_triangles: meta.source_triangles.clone(),
        target_triangles: env.subjects.target_triangles.clone(),
        source_keys: read_keys("source_keys.npy", meta.source_vertices)?,
        target_keys: read_keys("target_keys.npy", meta.target_vertices)?,
    };
    Ok(SavedTransfer::Baran(Box::new(SavedBaran { model, subjects: env.subjects })))
}

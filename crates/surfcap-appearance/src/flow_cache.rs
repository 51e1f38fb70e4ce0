//! Optical flows between texture maps cached on disk (like every
//! product of the appearance model: flows, warps, the eigen model). A flow is the most expensive per-pair product of the appearance
//! pipeline (thesis 4.4.1: forward and backward warps for every frame, again at every medoid
//! shift), and a rebuilt model with other component counts or a re-run evaluation asks for the
//! same pairs again.
//!
//! An entry is `texture-flow-<16 hex>.npy` (f32 [2, height, width]: u then v) in the derived
//! cache folder, keyed by a BLAKE3 hash of both images' texels, the active texels and the
//! caller's parameter text (the flow and pre-processing options), so any change recomputes.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use surfcap_mesh::Progress;
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::npy::NpyArray;

use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;
use crate::texture_preprocessing::PreprocessOptions;
use crate::texture_preprocessing::preprocess;
use crate::tv_l1_flow::{FlowOptions, tv_l1_flow};

/// Layout version of the entries: bump when the flow's meaning or the file layout changes.
const LAYOUT: u32 = 1;

/// Where flows are kept: a cache folder, or nowhere (computed every time).
pub struct FlowCache<'a> {
    cache: Option<DerivedCache>,
    refresh: bool,
    progress: &'a dyn Progress,
}

fn hash_image(h: &mut blake3::Hasher, image: &TextureImage) {
    h.update(&(image.width() as u64).to_le_bytes());
    h.update(&(image.height() as u64).to_le_bytes());
    h.update(&(image.channels() as u64).to_le_bytes());
    for v in image.data() {
        h.update(&v.to_le_bytes());
    }
}

impl<'a> FlowCache<'a> {
    /// A cache in `dir` (`None`: no cache); `refresh` recomputes and replaces entries.
    pub fn new(dir: Option<&std::path::Path>, refresh: bool, progress: &'a dyn Progress) -> FlowCache<'a> {
        FlowCache { cache: dir.map(DerivedCache::new), refresh, progress }
    }

    /// The flow under `key` ([`pair_key`] of the two maps and the active texels) and `params`
    /// (text naming every option `compute` uses), a `w x h` field read from the cache or
    /// computed and stored.
    pub fn flow(
        &self,
        key: &blake3::Hash,
        w: usize,
        h: usize,
        params: &str,
        compute: impl Fn() -> Result<FlowField>,
    ) -> Result<FlowField> {
        let Some(cache) = &self.cache else { return compute() };
        let path = cache.path("texture-flow", key, params);
        let encode = || -> Result<NpyArray<f32>> {
            let f = compute()?;
            f.check_size(w, h, "the computed flow")?;
            let mut data = f.u;
            data.extend_from_slice(&f.v);
            Ok(NpyArray { shape: vec![2, h, w], data })
        };
        let decode = |a: NpyArray<f32>| -> Result<FlowField> {
            if a.shape != [2, h, w] {
                return Err(Error::Mismatch(format!("shape {:?}, expected [2, {h}, {w}]", a.shape)));
            }
            if a.data.iter().any(|v| !v.is_finite()) {
                return Err(Error::Invalid("a displacement is not finite".into()));
            }
            let mut u = a.data;
            let v = u.split_off(w * h);
            Ok(FlowField { width: w, height: h, u, v })
        };
        let (flow, _) = cache.fetch(&path, self.refresh, self.progress, encode, decode)?;
        Ok(flow)
    }
}

/// The content hash of a texture map (size, channels, every texel).
pub fn image_hash(image: &TextureImage) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    hash_image(&mut h, image);
    h.finalize()
}

/// The cache key of a flow between two maps (by their [`image_hash`]) over `mask`.
pub fn pair_key(reference: &blake3::Hash, target: &blake3::Hash, mask: &TexelMask) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    h.update(reference.as_bytes());
    h.update(target.as_bytes());
    for i in mask.index() {
        h.update(&i.to_le_bytes());
    }
    h.finalize()
}

/// How many pre-processed maps [`TextureFlow`] keeps in memory (grey f32 planes: 4 MB each at
/// 1024 x 1024).
const PREPROCESSED_KEPT: usize = 128;

/// The thesis's flow (pre-processing, then TV-L1 on the grey images, 4.4.1) through a cache:
/// the estimator every appearance command hands to the model. Each map is pre-processed once
/// and its grey image kept in memory (the medoid shift flows every frame against a new
/// reference at each iteration, and the bilateral filter costs as much as a half-resolution
/// flow), up to [`PREPROCESSED_KEPT`] maps, the oldest dropped first.
pub struct TextureFlow<'a> {
    cache: FlowCache<'a>,
    preprocess: PreprocessOptions,
    options: FlowOptions,
    kept: Mutex<VecDeque<(blake3::Hash, Arc<Vec<f32>>)>>,
}

impl<'a> TextureFlow<'a> {
    pub fn new(cache: FlowCache<'a>, preprocess: PreprocessOptions, options: FlowOptions) -> TextureFlow<'a> {
        TextureFlow { cache, preprocess, options, kept: Mutex::new(VecDeque::new()) }
    }

    pub fn options(&self) -> &FlowOptions {
        &self.options
    }

    /// The parameter text of the cache key: every option the flow depends on.
    fn params(&self) -> String {
        format!("layout {LAYOUT}; {:?}; {:?}", self.preprocess, self.options)
    }

    /// The pre-processed grey image of `image` over `mask` (keyed by the map and the mask).
    fn grey(&self, image: &TextureImage, key: blake3::Hash, mask: &TexelMask) -> Result<Arc<Vec<f32>>> {
        let key = pair_key(&key, &key, mask);
        if let Some((_, g)) = self.kept.lock().expect("no panic holds the lock").iter().find(|(k, _)| *k == key) {
            return Ok(g.clone());
        }
        let g = Arc::new(preprocess(image, mask, &self.preprocess)?.grey());
        let mut kept = self.kept.lock().expect("no panic holds the lock");
        if !kept.iter().any(|(k, _)| *k == key) {
            if kept.len() >= PREPROCESSED_KEPT {
                kept.pop_front();
            }
            kept.push_back((key, g.clone()));
        }
        Ok(g)
    }

    /// `w` with `reference(x) ~ target(x + w(x))` over the active texels of `mask`.
    pub fn estimate(&self, reference: &TextureImage, target: &TextureImage, mask: &TexelMask) -> Result<FlowField> {
        reference.check_same_shape(target, "the target texture")?;
        mask.check_size(reference.width(), reference.height(), "the reference texture")?;
        let (hr, ht) = (image_hash(reference), image_hash(target));
        let (w, h) = (reference.width(), reference.height());
        self.cache.flow(&pair_key(&hr, &ht, mask), w, h, &self.params(), || {
            let a = self.grey(reference, hr, mask)?;
            let b = self.grey(target, ht, mask)?;
            tv_l1_flow(&a, &b, w, h, Some(mask), &self.options)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn a_flow_is_computed_once_and_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let cache = FlowCache::new(Some(dir.path()), false, &surfcap_mesh::NoProgress);
        let a = TextureImage::from_planes(3, 2, 1, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        let b = TextureImage::from_planes(3, 2, 1, vec![2.0, 3.0, 4.0, 5.0, 6.0, 7.0]).unwrap();
        let mask = TexelMask::full(3, 2);
        let calls = Cell::new(0);
        let compute = || {
            calls.set(calls.get() + 1);
            let mut f = FlowField::zeros(3, 2);
            f.u[1] = 0.25;
            f.v[4] = -1.5;
            Ok(f)
        };
        let key = |r: &TextureImage, t: &TextureImage| pair_key(&image_hash(r), &image_hash(t), &mask);
        let first = cache.flow(&key(&a, &b), 3, 2, "p", compute).unwrap();
        let second = cache.flow(&key(&a, &b), 3, 2, "p", compute).unwrap();
        assert_eq!(first, second);
        assert_eq!(calls.get(), 1);
        // Other options, or the pair the other way round, are other entries.
        cache.flow(&key(&a, &b), 3, 2, "q", compute).unwrap();
        cache.flow(&key(&b, &a), 3, 2, "p", compute).unwrap();
        assert_eq!(calls.get(), 3);
    }

    #[test]
    fn the_estimator_gives_texture_flow_s_result_and_reads_it_back() {
        let (w, h) = (24, 20);
        let plane = |dx: f32| -> Vec<f32> {
            (0..w * h)
                .map(|i| 128.0 + 60.0 * (((i % w) as f32 + dx) * 0.5).sin() * ((i / w) as f32 * 0.4).cos())
                .collect()
        };
        let data = |dx: f32| [plane(dx), plane(dx), plane(dx)].concat();
        let a = TextureImage::from_planes(w, h, 3, data(0.0)).unwrap();
        let b = TextureImage::from_planes(w, h, 3, data(1.0)).unwrap();
        let mask = TexelMask::full(w, h);
        let pre = PreprocessOptions::none();
        let opts = FlowOptions::default();
        let direct = crate::tv_l1_flow::texture_flow(&a, &b, &mask, &pre, &opts).unwrap();
        let dir = tempfile::tempdir().unwrap();
        for _ in 0..2 {
            let est = TextureFlow::new(FlowCache::new(Some(dir.path()), false, &surfcap_mesh::NoProgress), pre, opts);
            assert_eq!(est.estimate(&a, &b, &mask).unwrap(), direct);
        }
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names.len(), 2, "one entry and its content hash: {names:?}");
        assert_eq!(names[1], format!("{}.b3", names[0]));
    }
}

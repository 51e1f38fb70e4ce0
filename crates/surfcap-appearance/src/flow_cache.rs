//! Optical flows between texture maps cached on disk (issue 20: "products (flows, warps, the
//! eigen model) are cached"). A flow is the most expensive per-pair product of the appearance
//! pipeline (thesis 4.4.1: forward and backward warps for every frame, again at every medoid
//! shift), and a rebuilt model with other component counts or a re-run evaluation asks for the
//! same pairs again.
//!
//! An entry is `texture-flow-<16 hex>.npy` (f32 [2, height, width]: u then v) in the derived
//! cache folder, keyed by a BLAKE3 hash of both images' texels, the active texels and the
//! caller's parameter text (the flow and pre-processing options), so any change recomputes.

use surfcap_mesh::Progress;
use surfcap_mesh::derived_cache::DerivedCache;
use surfcap_mesh::io::npy::NpyArray;

use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;
use crate::texture_preprocessing::PreprocessOptions;
use crate::tv_l1_flow::{FlowOptions, texture_flow};

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

    /// The flow from `reference` to `target` (reference(x) ~ target(x + w(x))) under `params`
    /// (text naming every option `compute` uses), read from the cache or computed and stored.
    pub fn flow(
        &self,
        reference: &TextureImage,
        target: &TextureImage,
        mask: &TexelMask,
        params: &str,
        compute: impl Fn() -> Result<FlowField>,
    ) -> Result<FlowField> {
        let Some(cache) = &self.cache else { return compute() };
        let (w, h) = (reference.width(), reference.height());
        let mut hasher = blake3::Hasher::new();
        hash_image(&mut hasher, reference);
        hash_image(&mut hasher, target);
        for i in mask.index() {
            hasher.update(&i.to_le_bytes());
        }
        let key = hasher.finalize();
        let path = cache.path("texture-flow", &key, params);
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

/// The thesis's flow (pre-processing, then TV-L1 on the grey images, 4.4.1) through a cache:
/// the estimator every appearance command hands to the model.
pub struct TextureFlow<'a> {
    pub cache: FlowCache<'a>,
    pub preprocess: PreprocessOptions,
    pub options: FlowOptions,
}

impl TextureFlow<'_> {
    /// The parameter text of the cache key: every option the flow depends on.
    fn params(&self) -> String {
        format!("layout {LAYOUT}; {:?}; {:?}", self.preprocess, self.options)
    }

    /// `w` with `reference(x) ~ target(x + w(x))` over the active texels of `mask`.
    pub fn estimate(&self, reference: &TextureImage, target: &TextureImage, mask: &TexelMask) -> Result<FlowField> {
        self.cache.flow(reference, target, mask, &self.params(), || texture_flow(reference, target, mask, &self.preprocess, &self.options))
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
        let first = cache.flow(&a, &b, &mask, "p", compute).unwrap();
        let second = cache.flow(&a, &b, &mask, "p", compute).unwrap();
        assert_eq!(first, second);
        assert_eq!(calls.get(), 1);
        // Other options, or the pair the other way round, are other entries.
        cache.flow(&a, &b, &mask, "q", compute).unwrap();
        cache.flow(&b, &a, &mask, "p", compute).unwrap();
        assert_eq!(calls.get(), 3);
    }
}

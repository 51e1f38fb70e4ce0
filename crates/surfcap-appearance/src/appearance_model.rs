//! The eigen appearance model of a subject (thesis 4.4-4.6, Boukhayma 2017): eigen textures of
//! the aligned textures and eigen warps of the backward warps, instantiated from coefficients
//! (4.4.3), interpolated in coefficient space (4.6.1) and used to complete textures with
//! unobserved texels (4.6.2); saved as a folder numpy opens.
//!
//! Build ([`build_appearance_model`]): the textures are aligned by medoid shift (Algorithm 4,
//! [`crate::medoid_shift_alignment`]); the backward warp of frame k is `w_k = flow(I_k, A_k)`, so
//! that `I_k ≈ A_k(x + w_k)` (4.4.1); both sets are reduced by PCA through the F x F Gram matrix
//! ([`crate::eigen_maps`], eq. 4.4-4.11). Vectors hold the active texels only, channel after
//! channel for textures (3 x N) and u then v for warps (2 x N), all f32.
//!
//! Instantiation (4.4.3): `A = Ā + Σ c_i T_i`, `w = w̄ + Σ d_i W_i`, texture = A warped by w
//! (Poisson or direct, as built). Inactive texels of an instantiated texture are 0.
//!
//! Folder (kind [`KIND`], written atomically by `surfcap_mesh::atomic::write_dir`):
//! `model.json` (format, version, size, reference, frame names, λ, warping, eigenvalues) and
//! `mask.npy` (u32 [N]: row-major texel of each active texel), `mean_texture.npy` (f32 [C, N]),
//! `eigen_textures.npy` (f32 [k_t, C, N]), `reference_texture.npy` (f32 [C, N], the reference
//! frame's texture, which completion aligns to), `mean_warp.npy` (f32 [2, N]), `eigen_warps.npy`
//! (f32 [k_w, 2, N]), `texture_coefficients.npy` (f64 [F, k_t]), `warp_coefficients.npy` (f64
//! [F, k_w]). The Poisson factorisation is not saved: it is rebuilt on load from the mask
//! (about 14 s at 1024x1024 for the head atlas; its factor would be 1.5 GB on disk).

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use surfcap_mesh::Progress;
use surfcap_mesh::npy::{NpyElement, expect_shape, read_npy, write_npy};

use crate::eigen_maps::EigenBasis;
use crate::error::{Error, Result};
use crate::flow_field::FlowField;
use crate::medoid_shift_alignment::{FlowEstimator, active_vector, check_textures, medoid_shift};
use crate::poisson_texture_warp::{DEFAULT_LAMBDA, TextureWarper, Warping, reads_only_valid, warp_direct_reading};
use crate::texel_mask::TexelMask;
use crate::texture_image::TextureImage;

/// Widest and tallest texture map a model file may declare: 4 times the 16384 texels
/// `appearance generate` makes at most, so that an edited size is refused before any
/// allocation.
pub const MAX_MODEL_SIDE: usize = 65_536;

/// Largest Poisson warp weight a model file may declare (the command line's bound on
/// `appearance build --lambda`; the thesis uses 0.02).
pub const MAX_MODEL_LAMBDA: f64 = 1000.0;

/// The folder kind of a saved model (its marker).
pub const KIND: &str = "appearance-model";
const FORMAT: &str = "surfcap-appearance-model";
const VERSION: u32 = 1;

/// A flow estimator restricted to some texels: `flow(reference, target, domain) = w` with
/// `reference(x) ≈ target(x + w(x))` for x in `domain` (texels of the reference).
pub type MaskedFlowEstimator<'a> = dyn Fn(&TextureImage, &TextureImage, &TexelMask) -> Result<FlowField> + Sync + 'a;

/// Options of [`build_appearance_model`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AppearanceOptions {
    /// Weight of the intensity term of the Poisson warp (eq. 4.1-4.3).
    pub lambda: f64,
    /// Eigen textures kept (at most F - 1 exist).
    pub n_textures: usize,
    /// Eigen warps kept (at most F - 1 exist).
    pub n_warps: usize,
    pub warping: Warping,
    /// Alignments the medoid shift may run (Algorithm 4).
    pub max_medoid_iterations: usize,
    /// The warping of the medoid shift's search for the reference. Algorithm 4 aligns with
    /// the model's warping at every iteration; a Poisson warp of a 1024 x 1024 map costs 1.2 s
    /// against 0.06 s for a direct one, and every iteration warps every frame, so by default
    /// the search warps directly and only the chosen reference's alignment is redone with
    /// `warping` (the error that drives the search is then the direct warp's). `warping` here
    /// is Algorithm 4 to the letter.
    pub selection_warping: Warping,
}

impl Default for AppearanceOptions {
    /// λ = 0.02, every component, Poisson warping, at most 5 medoid-shift alignments searched
    /// with direct warps.
    fn default() -> Self {
        AppearanceOptions {
            lambda: DEFAULT_LAMBDA,
            n_textures: usize::MAX,
            n_warps: usize::MAX,
            warping: Warping::Poisson,
            max_medoid_iterations: 5,
            selection_warping: Warping::Direct,
        }
    }
}

/// Splits a total of `k` eigen maps into eigen textures and eigen warps, two thirds textures
/// (rounded up) and one third warps: the proportion thesis 4.5.1 found nearly optimal.
pub fn split_components(k: usize) -> (usize, usize) {
    let textures = (2 * k).div_ceil(3);
    (textures, k - textures)
}

/// Wall-clock seconds of each stage of a build.
#[derive(Debug, Clone, Default, Serialize)]
pub struct BuildTimings {
    /// The Poisson warp's normal equations (eq. 4.3).
    pub factorisation: f64,
    /// The medoid shift (Algorithm 4): forward flows, warps, the Gram matrix per iteration.
    pub alignment: f64,
    /// Every frame warped to the chosen reference with the model's warping (when the search
    /// warped otherwise), then its backward flow.
    pub backward_flows: f64,
    pub texture_pca: f64,
    pub warp_pca: f64,
    pub total: f64,
}

/// What a build did.
#[derive(Debug, Clone, Serialize)]
pub struct BuildReport {
    pub frames: usize,
    pub active_texels: usize,
    pub reference: usize,
    /// The reference of each medoid-shift iteration and its total alignment error.
    pub medoid_references: Vec<usize>,
    pub medoid_errors: Vec<f64>,
    /// Fraction of the variance each kept eigen texture / eigen warp explains.
    pub texture_explained_variance: Vec<f64>,
    pub warp_explained_variance: Vec<f64>,
    pub seconds: BuildTimings,
}

/// Eigen textures and eigen warps of a subject's textures.
#[derive(Debug)]
pub struct AppearanceModel {
    mask: TexelMask,
    channels: usize,
    reference: usize,
    names: Vec<String>,
    lambda: f64,
    /// Active texels of the reference frame's texture (channel after channel).
    reference_texture: Vec<f32>,
    textures: EigenBasis,
    warps: EigenBasis,
    warper: TextureWarper,
}

fn progress_stage<T>(progress: &dyn Progress, label: &str, f: impl FnOnce() -> T) -> (T, f64) {
    progress.start(label, 1);
    let t = Instant::now();
    let out = f();
    progress.advance(1);
    progress.finish();
    (out, t.elapsed().as_secs_f64())
}

/// The active texels of a flow: u then v.
fn warp_vector(flow: &FlowField, mask: &TexelMask) -> Vec<f32> {
    let mut v = mask.gather(&flow.u);
    v.extend(mask.gather(&flow.v));
    v
}

/// Builds the model of `textures` (one per frame, named by `names`, e.g. `sequence:frame`).
pub fn build_appearance_model(
    textures: &[TextureImage],
    names: &[String],
    mask: &TexelMask,
    options: &AppearanceOptions,
    flow: &FlowEstimator<'_>,
    progress: &dyn Progress,
) -> Result<(AppearanceModel, BuildReport)> {
    let start = Instant::now();
    if names.len() != textures.len() {
        return Err(Error::Mismatch(format!("{} frame names for {} textures", names.len(), textures.len())));
    }
    check_textures(textures, mask, Some(names))?;
    if textures.len() < 2 {
        return Err(Error::Invalid(format!("an appearance model needs at least 2 frames: got {}", textures.len())));
    }
    let mut seconds = BuildTimings::default();
    let (warper, t) = progress_stage(progress, "factorising the Poisson warp (eq. 4.3)", || {
        TextureWarper::new(options.warping, mask, options.lambda)
    });
    let warper = warper?;
    seconds.factorisation = t;
    let t = Instant::now();
    // With another warping for the search, only its flows are kept and every frame is warped
    // again with the model's warping below, one frame at a time (no set of aligned maps held).
    let rewarp = options.selection_warping != options.warping;
    let alignment = if rewarp {
        let selection = TextureWarper::new(options.selection_warping, mask, options.lambda)?;
        medoid_shift(textures, mask, &selection, flow, options.max_medoid_iterations, progress, false)?
    } else {
        medoid_shift(textures, mask, &warper, flow, options.max_medoid_iterations, progress, true)?
    };
    let reference = alignment.reference;
    let (w, h) = (mask.width(), mask.height());
    let t_back = Instant::now();
    let label = if rewarp {
        format!("aligning to frame {} ({:?} warping) and backward warps", names[reference], options.warping)
    } else {
        "backward warps".to_string()
    };
    progress.start(&label, textures.len() as u64);
    let mut aligned_maps = alignment.aligned.into_iter();
    let forward = alignment.forward;
    let pairs: Vec<(Vec<f32>, Vec<f32>)> = textures
        .par_iter()
        .zip(forward.into_par_iter())
        .zip((0..textures.len()).map(|_| aligned_maps.next()).collect::<Vec<_>>().into_par_iter())
        .enumerate()
        .map(|(k, ((t, fw), kept))| {
            let a = match kept {
                Some(a) => a,
                None if k == reference => t.clone(),
                None => warper.warp(t, &fw)?,
            };
            drop(fw);
            let bw = if k == reference {
                FlowField::zeros(w, h)
            } else {
                let bw =
                    flow(t, &a).map_err(|e| Error::Invalid(format!("backward warp of frame {}: {e}", names[k])))?;
                bw.check_size(w, h, &format!("the backward warp of frame {}", names[k]))?;
                bw
            };
            progress.advance(1);
            Ok((active_vector(&a, mask), warp_vector(&bw, mask)))
        })
        .collect::<Result<_>>()?;
    progress.finish();
    seconds.backward_flows = t_back.elapsed().as_secs_f64();
    seconds.alignment = t.elapsed().as_secs_f64() - seconds.backward_flows;
    let (aligned, warps): (Vec<Vec<f32>>, Vec<Vec<f32>>) = pairs.into_iter().unzip();
    let reference_texture = aligned[reference].clone();
    let (texture_basis, t) = progress_stage(progress, "eigen textures (eq. 4.4-4.7)", || {
        let refs: Vec<&[f32]> = aligned.iter().map(Vec::as_slice).collect();
        EigenBasis::new(&refs, options.n_textures, "aligned textures")
    });
    let texture_basis = texture_basis?;
    seconds.texture_pca = t;
    drop(aligned);
    let (warp_basis, t) = progress_stage(progress, "eigen warps (eq. 4.8-4.11)", || {
        let refs: Vec<&[f32]> = warps.iter().map(Vec::as_slice).collect();
        EigenBasis::new(&refs, options.n_warps, "backward warps")
    });
    let warp_basis = warp_basis?;
    seconds.warp_pca = t;
    seconds.total = start.elapsed().as_secs_f64();
    let report = BuildReport {
        frames: textures.len(),
        active_texels: mask.len(),
        reference,
        medoid_references: alignment.references,
        medoid_errors: alignment.errors,
        texture_explained_variance: texture_basis.explained_variance(),
        warp_explained_variance: warp_basis.explained_variance(),
        seconds,
    };
    let model = AppearanceModel {
        mask: mask.clone(),
        channels: textures[0].channels(),
        reference,
        names: names.to_vec(),
        lambda: options.lambda,
        reference_texture,
        textures: texture_basis,
        warps: warp_basis,
        warper,
    };
    Ok((model, report))
}

impl AppearanceModel {
    pub fn mask(&self) -> &TexelMask {
        &self.mask
    }
    pub fn channels(&self) -> usize {
        self.channels
    }
    /// The reference frame of the alignment.
    pub fn reference(&self) -> usize {
        self.reference
    }
    /// Names of the training frames.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    pub fn n_frames(&self) -> usize {
        self.names.len()
    }
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    pub fn warping(&self) -> Warping {
        self.warper.mode()
    }
    /// Eigen textures kept.
    pub fn n_textures(&self) -> usize {
        self.textures.n_components()
    }
    /// Eigen warps kept.
    pub fn n_warps(&self) -> usize {
        self.warps.n_components()
    }
    /// The basis of the aligned textures (mean, eigen textures, eigenvalues, coefficients).
    pub fn texture_basis(&self) -> &EigenBasis {
        &self.textures
    }
    /// The basis of the backward warps.
    pub fn warp_basis(&self) -> &EigenBasis {
        &self.warps
    }
    /// Texture and warp coefficients of training frame `frame`.
    pub fn frame_coefficients(&self, frame: usize) -> Result<(&[f64], &[f64])> {
        self.check_frame(frame)?;
        Ok((self.textures.frame_coefficients(frame), self.warps.frame_coefficients(frame)))
    }

    fn check_frame(&self, frame: usize) -> Result<()> {
        if frame < self.n_frames() {
            return Ok(());
        }
        Err(Error::Invalid(format!("frame {frame}: the model has {} training frames", self.n_frames())))
    }

    /// The same model with its first `n_textures` eigen textures and `n_warps` eigen warps (all
    /// of them when more are asked), sharing nothing mutable (the Poisson system is
    /// refactorised: use [`Self::instantiate`] with fewer coefficients to avoid that).
    pub fn truncated(&self, n_textures: usize, n_warps: usize) -> Result<AppearanceModel> {
        Ok(AppearanceModel {
            mask: self.mask.clone(),
            channels: self.channels,
            reference: self.reference,
            names: self.names.clone(),
            lambda: self.lambda,
            reference_texture: self.reference_texture.clone(),
            textures: self.textures.truncated(n_textures),
            warps: self.warps.truncated(n_warps),
            warper: TextureWarper::new(self.warper.mode(), &self.mask, self.lambda)?,
        })
    }

    /// The aligned texture `Ā + Σ c_i T_i` as an image (inactive texels 0), with the first
    /// `coefficients.len()` eigen textures.
    pub fn aligned_texture(&self, coefficients: &[f64]) -> Result<TextureImage> {
        let a = self.textures.reconstruct(coefficients).map_err(|e| Error::Invalid(format!("texture {e}")))?;
        Ok(self.texture_image(&a))
    }

    /// The backward warp `w̄ + Σ d_i W_i` (zero on inactive texels), with the first
    /// `coefficients.len()` eigen warps.
    pub fn backward_warp(&self, coefficients: &[f64]) -> Result<FlowField> {
        let v = self.warps.reconstruct(coefficients).map_err(|e| Error::Invalid(format!("warp {e}")))?;
        let (w, h) = (self.mask.width(), self.mask.height());
        let n = self.mask.len();
        let mut flow = FlowField::zeros(w, h);
        self.mask.scatter(&v[..n], &mut flow.u);
        self.mask.scatter(&v[n..], &mut flow.v);
        Ok(flow)
    }

    fn texture_image(&self, active: &[f32]) -> TextureImage {
        let (w, h) = (self.mask.width(), self.mask.height());
        let n = self.mask.len();
        let mut img = TextureImage::zeros(w, h, self.channels);
        for c in 0..self.channels {
            self.mask.scatter(&active[c * n..(c + 1) * n], img.plane_mut(c));
        }
        img
    }

    /// A texture from coefficients (4.4.3): the aligned texture de-aligned by the backward
    /// warp. Fewer coefficients than components use the first ones only (the evaluation's
    /// sweep over the number of eigen maps).
    pub fn instantiate(&self, texture_coefficients: &[f64], warp_coefficients: &[f64]) -> Result<TextureImage> {
        let a = self.aligned_texture(texture_coefficients)?;
        let w = self.backward_warp(warp_coefficients)?;
        self.warper.warp(&a, &w)
    }

    /// Training frame `frame` from its own coefficients.
    pub fn reconstruct(&self, frame: usize) -> Result<TextureImage> {
        let (t, w) = self.frame_coefficients(frame)?;
        self.instantiate(t, w)
    }

    /// Coefficients of an aligned texture and its backward warp (`Tᵀ (A - Ā)`, `Wᵀ (w - w̄)`).
    pub fn project(&self, aligned_texture: &TextureImage, backward_warp: &FlowField) -> Result<(Vec<f64>, Vec<f64>)> {
        self.check_texture(aligned_texture, "the aligned texture")?;
        backward_warp.check_size(self.mask.width(), self.mask.height(), "the backward warp")?;
        let t = self.textures.project(&active_vector(aligned_texture, &self.mask))?;
        let w = self.warps.project(&warp_vector(backward_warp, &self.mask))?;
        Ok((t, w))
    }

    fn check_texture(&self, texture: &TextureImage, what: &str) -> Result<()> {
        self.mask.check_size(texture.width(), texture.height(), what)?;
        if texture.channels() != self.channels {
            return Err(Error::Mismatch(format!(
                "{what} has {} channels: expected {} like the model",
                texture.channels(),
                self.channels
            )));
        }
        Ok(())
    }

    /// Coefficients blended from training frames (4.6.1): `Σ weight_k c_k` for textures and
    /// warps alike. The weights must sum to 1 (within 1e-6: they are normalised), any number
    /// of frames.
    pub fn interpolated_coefficients(&self, weights: &[(usize, f64)]) -> Result<(Vec<f64>, Vec<f64>)> {
        if weights.is_empty() {
            return Err(Error::Invalid("no frame to interpolate: expected (frame, weight) pairs".into()));
        }
        let sum: f64 = weights.iter().map(|w| w.1).sum();
        if weights.iter().any(|w| !w.1.is_finite()) || (sum - 1.0).abs() > 1e-6 {
            let list: Vec<String> = weights.iter().map(|(k, w)| format!("{k}: {w}")).collect();
            return Err(Error::Invalid(format!(
                "interpolation weights {{{}}} sum to {sum}: expected finite weights summing to 1",
                list.join(", ")
            )));
        }
        let mut t = vec![0.0f64; self.n_textures()];
        let mut w = vec![0.0f64; self.n_warps()];
        for &(k, wk) in weights {
            let (tk, dk) = self.frame_coefficients(k)?;
            t.iter_mut().zip(tk).for_each(|(a, b)| *a += wk / sum * b);
            w.iter_mut().zip(dk).for_each(|(a, b)| *a += wk / sum * b);
        }
        Ok((t, w))
    }

    /// The texture blended from training frames in coefficient space (4.6.1).
    pub fn interpolate(&self, weights: &[(usize, f64)]) -> Result<TextureImage> {
        let (t, w) = self.interpolated_coefficients(weights)?;
        self.instantiate(&t, &w)
    }

    /// Completes a texture observed only where `observed` is true (4.6.2): aligned to the
    /// reference frame by `flow` estimated on the observed texels (direct warping reading only
    /// observed texels: the Poisson solve would spread the unobserved values into the observed
    /// ones), its backward warp estimated on the observed texels, both projected by least
    /// squares on the texels they are known at, and the coefficients instantiated. Returns the
    /// model's texture everywhere (paste the observed texels back if they are to be kept).
    pub fn complete(
        &self,
        texture: &TextureImage,
        observed: &[bool],
        flow: &MaskedFlowEstimator<'_>,
    ) -> Result<TextureImage> {
        Ok(self.complete_coefficients(texture, observed, flow)?.0)
    }

    /// [`Self::complete`] returning the texture and the coefficients (texture, warp).
    pub fn complete_coefficients(
        &self,
        texture: &TextureImage,
        observed: &[bool],
        flow: &MaskedFlowEstimator<'_>,
    ) -> Result<(TextureImage, Vec<f64>, Vec<f64>)> {
        self.check_texture(texture, "the texture to complete")?;
        let (w, h) = (self.mask.width(), self.mask.height());
        if observed.len() != w * h {
            return Err(Error::Mismatch(format!(
                "{} observed flags for a {w}x{h} texture: expected one per texel",
                observed.len()
            )));
        }
        let valid: Vec<bool> = (0..w * h).map(|t| observed[t] && self.mask.is_active(t)).collect();
        let domain = TexelMask::from_flags(w, h, &valid)
            .map_err(|_| Error::Invalid("the texture to complete has no observed active texel".into()))?;
        let reference = self.texture_image(&self.reference_texture);
        let forward = flow(&reference, texture, &domain)?;
        forward.check_size(w, h, "the forward flow of the texture to complete")?;
        let aligned = warp_direct_reading(texture, &forward, &valid)?;
        let backward = flow(texture, &aligned, &domain)?;
        backward.check_size(w, h, "the backward warp of the texture to complete")?;
        let n = self.mask.len();
        let index = self.mask.index();
        let aligned_known: Vec<bool> =
            index.iter().map(|&t| valid[t as usize] && reads_only_valid(&forward, &valid, t as usize)).collect();
        let texture_known: Vec<bool> = (0..self.channels).flat_map(|_| aligned_known.iter().copied()).collect();
        let warp_known: Vec<bool> = (0..2).flat_map(|_| index.iter().map(|&t| valid[t as usize])).collect();
        debug_assert_eq!(texture_known.len(), self.channels * n);
        let tc = self.textures.project_observed(&active_vector(&aligned, &self.mask), &texture_known)?;
        let wc = self.warps.project_observed(&warp_vector(&backward, &self.mask), &warp_known)?;
        let out = self.instantiate(&tc, &wc)?;
        Ok((out, tc, wc))
    }

    /// Writes the model folder at `path` (see the module documentation); `force` lets it
    /// replace a folder that is not an earlier model.
    pub fn save(&self, path: &Path, force: bool) -> Result<()> {
        surfcap_mesh::atomic::write_dir(path, KIND, force, |dir| self.write_files(dir).map_err(to_mesh_error))?;
        Ok(())
    }

    fn write_files(&self, dir: &Path) -> Result<()> {
        let n = self.mask.len();
        let c = self.channels;
        let (kt, kw, f) = (self.n_textures(), self.n_warps(), self.n_frames());
        let header = Header {
            format: FORMAT.into(),
            version: VERSION,
            width: self.mask.width(),
            height: self.mask.height(),
            channels: c,
            active_texels: n,
            reference: self.reference,
            frames: self.names.clone(),
            lambda: self.lambda,
            warping: self.warper.mode(),
            texture_eigenvalues: self.textures.eigenvalues.clone(),
            texture_total_variance: self.textures.total_variance,
            warp_eigenvalues: self.warps.eigenvalues.clone(),
            warp_total_variance: self.warps.total_variance,
        };
        surfcap_mesh::atomic::write_file(&dir.join("model.json"), |w| {
            serde_json::to_writer_pretty(&mut *w, &header).map_err(std::io::Error::other)
        })?;
        let npy = |name: &str, shape: &[usize], data: &[f32]| -> Result<()> {
            surfcap_mesh::atomic::write_file(&dir.join(name), |w| write_npy(w, shape, data))?;
            Ok(())
        };
        surfcap_mesh::atomic::write_file(&dir.join("mask.npy"), |w| write_npy(w, &[n], self.mask.index()))?;
        npy("mean_texture.npy", &[c, n], &self.textures.mean)?;
        npy("eigen_textures.npy", &[kt, c, n], &self.textures.components)?;
        npy("reference_texture.npy", &[c, n], &self.reference_texture)?;
        npy("mean_warp.npy", &[2, n], &self.warps.mean)?;
        npy("eigen_warps.npy", &[kw, 2, n], &self.warps.components)?;
        surfcap_mesh::atomic::write_file(&dir.join("texture_coefficients.npy"), |w| {
            write_npy(w, &[f, kt], &self.textures.coefficients)
        })?;
        surfcap_mesh::atomic::write_file(&dir.join("warp_coefficients.npy"), |w| {
            write_npy(w, &[f, kw], &self.warps.coefficients)
        })?;
        Ok(())
    }

    /// Reads a model folder written by [`Self::save`], checking every array's shape (errors
    /// name the file), and refactorises the Poisson system.
    pub fn load(dir: &Path) -> Result<AppearanceModel> {
        let path = dir.join("model.json");
        let bytes = surfcap_mesh::read_regular_file(&path)?;
        let bad = |why: String| Error::Invalid(format!("{}: {why}", path.display()));
        let head: Header = serde_json::from_slice(&bytes)
            .map_err(|e| bad(format!("{e}: expected a model written by surfcap appearance build")))?;
        if head.format != FORMAT || head.version != VERSION {
            return Err(bad(format!(
                "format {:?} version {}: expected {FORMAT:?} version {VERSION} (rebuild with this surfcap)",
                head.format, head.version
            )));
        }
        let (n, c, f) = (head.active_texels, head.channels, head.frames.len());
        let (kt, kw) = (head.texture_eigenvalues.len(), head.warp_eigenvalues.len());
        if head.reference >= f {
            return Err(bad(format!("reference frame {} of {f} frames", head.reference)));
        }
        if c == 0 || f < 2 || head.width == 0 || head.height == 0 {
            return Err(bad(format!(
                "{}x{} texels, {c} channels, {f} frames: expected a positive size, channels and at least 2 frames",
                head.width, head.height
            )));
        }
        // The size is checked against the limit and the mask's file before the texel flags are
        // allocated: an edited width of 1e9 is an error naming the file, never an abort.
        if head.width > MAX_MODEL_SIDE || head.height > MAX_MODEL_SIDE {
            return Err(bad(format!(
                "{}x{} texels: expected a width and height of at most {MAX_MODEL_SIDE}",
                head.width, head.height
            )));
        }
        let mask_path = dir.join("mask.npy");
        let index = load_array::<u32>(&mask_path, &[Some(n)], "the active texels")?;
        if n > head.width * head.height {
            return Err(bad(format!(
                "{n} active texels in {}x{} texels: expected at most one per texel",
                head.width, head.height
            )));
        }
        if !(head.lambda.is_finite() && head.lambda > 0.0 && head.lambda <= MAX_MODEL_LAMBDA) {
            return Err(bad(format!("lambda {:?}: expected a number > 0 and at most {MAX_MODEL_LAMBDA}", head.lambda)));
        }
        let mut flags = surfcap_mesh::sizing::try_vec(
            head.width * head.height,
            false,
            &format!("the texel flags of {} ({}x{})", path.display(), head.width, head.height),
        )
        .map_err(|e| Error::Invalid(e.to_string()))?;
        let mut last: Option<u32> = None;
        for &t in &index {
            if t as usize >= flags.len() || last.is_some_and(|l| t <= l) {
                return Err(Error::Invalid(format!(
                    "{}: texel {t}: expected increasing texels below {}",
                    mask_path.display(),
                    flags.len()
                )));
            }
            flags[t as usize] = true;
            last = Some(t);
        }
        let mask = TexelMask::from_flags(head.width, head.height, &flags)
            .map_err(|e| Error::Invalid(format!("{}: {e}", mask_path.display())))?;
        let f32s = |name: &str, shape: &[usize], what: &str| -> Result<Vec<f32>> {
            let pattern: Vec<Option<usize>> = shape.iter().map(|&d| Some(d)).collect();
            load_array::<f32>(&dir.join(name), &pattern, what)
        };
        let f64s = |name: &str, shape: &[usize], what: &str| -> Result<Vec<f64>> {
            let pattern: Vec<Option<usize>> = shape.iter().map(|&d| Some(d)).collect();
            load_array::<f64>(&dir.join(name), &pattern, what)
        };
        let textures = EigenBasis {
            dim: c * n,
            mean: f32s("mean_texture.npy", &[c, n], "the mean aligned texture")?,
            components: f32s("eigen_textures.npy", &[kt, c, n], "the eigen textures")?,
            eigenvalues: head.texture_eigenvalues,
            total_variance: head.texture_total_variance,
            coefficients: f64s("texture_coefficients.npy", &[f, kt], "the frames' texture coefficients")?,
        };
        let reference_texture = f32s("reference_texture.npy", &[c, n], "the reference frame's texture")?;
        let warps = EigenBasis {
            dim: 2 * n,
            mean: f32s("mean_warp.npy", &[2, n], "the mean backward warp")?,
            components: f32s("eigen_warps.npy", &[kw, 2, n], "the eigen warps")?,
            eigenvalues: head.warp_eigenvalues,
            total_variance: head.warp_total_variance,
            coefficients: f64s("warp_coefficients.npy", &[f, kw], "the frames' warp coefficients")?,
        };
        let warper = TextureWarper::new(head.warping, &mask, head.lambda)
            .map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
        Ok(AppearanceModel {
            mask,
            channels: c,
            reference: head.reference,
            names: head.frames,
            lambda: head.lambda,
            reference_texture,
            textures,
            warps,
            warper,
        })
    }
}

/// Reads an array of the expected shape; errors name the file and every value must be finite.
fn load_array<T: NpyElement + IsFinite>(path: &Path, shape: &[Option<usize>], what: &str) -> Result<Vec<T>> {
    let a = read_npy::<T>(path)?;
    expect_shape(&a, shape, what).map_err(|e| e.in_file(path))?;
    if let Some(i) = a.data.iter().position(|x| !x.finite()) {
        return Err(Error::Invalid(format!("{}: value {i} of {what} is not finite", path.display())));
    }
    Ok(a.data)
}

trait IsFinite {
    fn finite(&self) -> bool;
}
impl IsFinite for f32 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}
impl IsFinite for f64 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}
impl IsFinite for u32 {
    fn finite(&self) -> bool {
        true
    }
}

fn to_mesh_error(e: Error) -> surfcap_mesh::Error {
    match e {
        Error::Mesh(m) => m,
        other => surfcap_mesh::Error::new(surfcap_mesh::ErrorKind::Metadata, other.to_string()),
    }
}

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    width: usize,
    height: usize,
    channels: usize,
    active_texels: usize,
    reference: usize,
    frames: Vec<String>,
    lambda: f64,
    warping: Warping,
    texture_eigenvalues: Vec<f64>,
    texture_total_variance: f64,
    warp_eigenvalues: Vec<f64>,
    warp_total_variance: f64,
}

#[cfg(test)]
mod tests {
    #![allow(clippy::needless_range_loop)]
    use super::*;
    use crate::medoid_shift_alignment::{align_by_medoid_shift, gram_matrix};
    use crate::test_support::{disc_mask, head_crop, known_warp, mse, quadratic_flow, synthetic_frame};
    use surfcap_mesh::NoProgress;

    fn estimator(a: &TextureImage, b: &TextureImage) -> Result<FlowField> {
        quadratic_flow(a, b, None)
    }

    fn masked_estimator(a: &TextureImage, b: &TextureImage, m: &TexelMask) -> Result<FlowField> {
        quadratic_flow(a, b, Some(m))
    }

    fn names(f: usize) -> Vec<String> {
        (0..f).map(|k| format!("synthetic:{k}")).collect()
    }

    fn synthetic_model(frames: &[u64]) -> (TexelMask, Vec<TextureImage>, AppearanceModel, BuildReport) {
        let mask = disc_mask(32);
        let textures: Vec<TextureImage> = frames.iter().map(|&k| synthetic_frame(&mask, k, 1.2)).collect();
        let (model, report) = build_appearance_model(
            &textures,
            &names(frames.len()),
            &mask,
            &AppearanceOptions::default(),
            &estimator,
            &NoProgress,
        )
        .unwrap();
        (mask, textures, model, report)
    }

    #[test]
    fn the_medoid_from_the_gram_matrix_is_the_brute_force_one() {
        let vs: Vec<Vec<f32>> =
            (0..7).map(|k| (0..50).map(|i| ((i * (k + 3)) % 17) as f32 + k as f32).collect()).collect();
        let refs: Vec<&[f32]> = vs.iter().map(Vec::as_slice).collect();
        let f = vs.len();
        let g = gram_matrix(&refs, Some(&vs[2]));
        let trace: f64 = (0..f).map(|l| g[l * f + l]).sum();
        let spread: Vec<f64> =
            (0..f).map(|k| f as f64 * g[k * f + k] + trace - 2.0 * g[k * f..(k + 1) * f].iter().sum::<f64>()).collect();
        for k in 0..f {
            let brute: f64 =
                (0..f).map(|l| vs[k].iter().zip(&vs[l]).map(|(a, b)| ((a - b) as f64).powi(2)).sum::<f64>()).sum();
            assert!((spread[k] - brute).abs() < 1e-6 * brute.max(1.0), "frame {k}: {} vs {brute}", spread[k]);
        }
    }

    #[test]
    fn every_training_frame_is_rebuilt_up_to_the_warping_error() {
        let (mask, textures, model, report) = synthetic_model(&[0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(model.n_textures(), 7);
        assert_eq!(model.n_warps(), 7);
        assert!(!report.medoid_errors.is_empty());
        let ev: f64 = report.texture_explained_variance.iter().sum();
        assert!((ev - 1.0).abs() < 1e-6, "{ev}");
        // The same alignment and backward warps, recomputed as the build does them (the search
        // with direct warps, then each frame warped by Poisson): the warping error alone.
        let warper = TextureWarper::new(Warping::Poisson, &mask, DEFAULT_LAMBDA).unwrap();
        let search = TextureWarper::new(Warping::Direct, &mask, DEFAULT_LAMBDA).unwrap();
        let al = align_by_medoid_shift(&textures, &mask, &search, &estimator, 5, &NoProgress).unwrap();
        assert_eq!(al.reference, model.reference());
        let active = |i: usize| mask.is_active(i);
        for k in 0..textures.len() {
            let aligned = if k == al.reference {
                textures[k].clone()
            } else {
                warper.warp(&textures[k], &al.forward[k]).unwrap()
            };
            let bw =
                if k == al.reference { FlowField::zeros(32, 32) } else { estimator(&textures[k], &aligned).unwrap() };
            let round_trip = warper.warp(&aligned, &bw).unwrap();
            let warping_error = mse(&round_trip, &textures[k], active);
            let rebuilt = model.reconstruct(k).unwrap();
            let model_error = mse(&rebuilt, &textures[k], active);
            assert!(
                model_error <= warping_error * 1.01 + 1e-3,
                "frame {k}: model {model_error}, warping alone {warping_error}"
            );
            let variance = mse(&textures[k], &model.aligned_texture(&[]).unwrap(), active);
            assert!(
                model_error < 0.15 * variance,
                "frame {k}: error {model_error}, variance about the mean {variance}"
            );
            // Fewer components, more error.
            let mean_only = mse(&model.instantiate(&[], &[]).unwrap(), &textures[k], active);
            assert!(model_error < mean_only, "frame {k}: all components {model_error}, none {mean_only}");
        }
    }

    #[test]
    fn interpolation_with_weights_one_and_zero_gives_the_frame() {
        let (_, _, model, _) = synthetic_model(&[0, 1, 2, 3, 4, 5]);
        let frame = model.reconstruct(2).unwrap();
        let blend = model.interpolate(&[(2, 1.0), (4, 0.0)]).unwrap();
        let worst = frame.data().iter().zip(blend.data()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "{worst}");
        let mid = model.interpolate(&[(2, 0.5), (4, 0.25), (1, 0.25)]).unwrap();
        assert!(mid.data().iter().zip(frame.data()).any(|(a, b)| (a - b).abs() > 1.0));
        let e = model.interpolate(&[(2, 0.5), (4, 0.2)]).unwrap_err().to_string();
        assert!(e.contains("sum to 0.7") && e.contains("summing to 1"), "{e}");
        let e = model.interpolate(&[(9, 1.0)]).unwrap_err().to_string();
        assert!(e.contains("frame 9: the model has 6 training frames"), "{e}");
    }

    #[test]
    fn completion_fills_a_hole_closer_to_the_truth_than_the_holed_input() {
        // Frame 3 of the training set seen with a hole (an unseen frame generalises poorly
        // from 8 tiny frames: see `surfcap eval appearance`).
        let (mask, _, model, _) = synthetic_model(&[0, 1, 2, 3, 4, 5, 6, 7]);
        let truth = synthetic_frame(&mask, 3, 1.2);
        let hole = |i: usize| (10..18).contains(&(i % 32)) && (12..20).contains(&(i / 32));
        let observed: Vec<bool> = (0..32 * 32).map(|i| !hole(i)).collect();
        let mut holed = truth.clone();
        for c in 0..3 {
            for i in (0..32 * 32).filter(|&i| hole(i)) {
                holed.plane_mut(c)[i] = 0.0;
            }
        }
        let done = model.complete(&holed, &observed, &masked_estimator).unwrap();
        let in_hole = |i: usize| hole(i) && mask.is_active(i);
        let (before, after) = (mse(&holed, &truth, in_hole), mse(&done, &truth, in_hole));
        let mean_fill = mse(&model.instantiate(&[], &[]).unwrap(), &truth, in_hole);
        eprintln!("hole MSE: holed {before:.1}, mean texture {mean_fill:.1}, completed {after:.1}");
        assert!(after < 0.05 * before, "completed {after}, holed {before}");
        // Measured: holed 17027, the mean texture 33.5, completed 44.3 with the PPCA prior of
        // `project_observed` (49.0 by plain least squares): 8 tiny frames give the prior
        // little to learn from; `surfcap eval appearance` measures completion on real maps.
    }

    #[test]
    fn a_saved_model_instantiates_the_same_and_a_damaged_array_is_named() {
        let (_, _, model, _) = synthetic_model(&[0, 1, 2, 3, 4]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("head.appearance");
        model.save(&path, false).unwrap();
        let back = AppearanceModel::load(&path).unwrap();
        assert_eq!(back.names(), model.names());
        assert_eq!(back.reference(), model.reference());
        let (t, w) = model.frame_coefficients(1).unwrap();
        let coeffs = (t.to_vec(), w[..2].to_vec());
        assert_eq!(back.instantiate(&coeffs.0, &coeffs.1).unwrap(), model.instantiate(&coeffs.0, &coeffs.1).unwrap());
        // Saving again over its own folder is allowed.
        model.save(&path, false).unwrap();
        let npy = path.join("eigen_textures.npy");
        let bytes = std::fs::read(&npy).unwrap();
        std::fs::write(&npy, &bytes[..bytes.len() - 40]).unwrap();
        let e = AppearanceModel::load(&path).unwrap_err().to_string();
        assert!(e.contains("eigen_textures.npy"), "{e}");
        std::fs::write(&npy, &bytes).unwrap();
        surfcap_mesh::atomic::write_file(&path.join("mean_warp.npy"), |w| write_npy(w, &[3, 4], &[0.0f32; 12]))
            .unwrap();
        let e = AppearanceModel::load(&path).unwrap_err().to_string();
        assert!(e.contains("mean_warp.npy") && e.contains("the mean backward warp"), "{e}");
    }

    #[test]
    fn a_model_file_whose_size_or_lambda_was_edited_is_refused_by_name_before_allocating() {
        let (_, _, model, _) = synthetic_model(&[0, 1, 2]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.appearance");
        model.save(&path, false).unwrap();
        let json_path = path.join("model.json");
        let text = std::fs::read_to_string(&json_path).unwrap();
        let head: serde_json::Value = serde_json::from_str(&text).unwrap();
        for (field, value, expected) in [
            ("width", serde_json::json!(1_000_000_000u64), "expected a width and height of at most 65536"),
            ("height", serde_json::json!(4_000_000_000u64), "expected a width and height of at most 65536"),
            ("width", serde_json::json!(1), "active texels in 1x"),
            ("lambda", serde_json::json!(1e308), "lambda 1e308: expected a number > 0 and at most 1000"),
        ] {
            let mut edited = head.clone();
            edited[field] = value;
            std::fs::write(&json_path, serde_json::to_vec(&edited).unwrap()).unwrap();
            let Err(e) = AppearanceModel::load(&path) else { panic!("{field}: accepted") };
            let e = e.to_string();
            assert!(e.contains("model.json") && e.contains(expected), "{field}: {e}");
        }
        std::fs::write(&json_path, text).unwrap();
        assert!(AppearanceModel::load(&path).is_ok());
    }

    #[test]
    fn frames_of_another_size_are_refused_by_name() {
        let mask = disc_mask(16);
        let textures = vec![synthetic_frame(&mask, 0, 1.0), TextureImage::zeros(16, 12, 3)];
        let names = vec!["walk:0".to_string(), "walk:1".to_string()];
        let e =
            build_appearance_model(&textures, &names, &mask, &AppearanceOptions::default(), &estimator, &NoProgress)
                .unwrap_err()
                .to_string();
        assert!(e.contains("frame walk:1 is 16x12x3: expected 16x16x3"), "{e}");
    }

    #[test]
    fn the_naive_pca_reconstructs_with_all_components_and_loses_with_fewer() {
        let mask = disc_mask(32);
        let textures: Vec<TextureImage> = (0..6).map(|k| synthetic_frame(&mask, k, 1.2)).collect();
        let pca = crate::NaiveTexturePca::new(&textures, &mask, 100).unwrap();
        assert_eq!(pca.n_components(), 5);
        let active = |i: usize| mask.is_active(i);
        let full = mse(&pca.reconstruct(3, 5).unwrap(), &textures[3], active);
        let one = mse(&pca.reconstruct(3, 1).unwrap(), &textures[3], active);
        assert!(full < 1e-4 && one > 1.0, "all {full}, one {one}");
    }

    /// Real texture: five frames made from a 64x64 crop of the head's colour map (its 256x256
    /// face region averaged by 4) by known smooth warps and gains; the model with every
    /// component rebuilds each frame far better than its mean.
    #[test]
    fn a_model_of_warped_real_texture_rebuilds_its_frames() {
        let Some(base) = head_crop(256, 256, 64, 4) else { return };
        let mask = TexelMask::full(64, 64);
        let textures: Vec<TextureImage> = (0..5u64)
            .map(|k| {
                let mut t = crate::flow_field::warp_direct(&base, &known_warp(64, 1.5, k + 1)).unwrap();
                let gain = 1.0 + 0.04 * (k as f32 - 2.0);
                t.data_mut().iter_mut().for_each(|v| *v *= gain);
                t
            })
            .collect();
        let (model, report) =
            build_appearance_model(&textures, &names(5), &mask, &AppearanceOptions::default(), &estimator, &NoProgress)
                .unwrap();
        let pca = crate::NaiveTexturePca::new(&textures, &mask, 100).unwrap();
        let keep = |i: usize| {
            let (x, y) = (i % 64, i / 64);
            (4..60).contains(&x) && (4..60).contains(&y)
        };
        let (mut ours1, mut naive1) = (0.0, 0.0);
        for k in 0..5 {
            let all = mse(&model.reconstruct(k).unwrap(), &textures[k], keep);
            let mean = mse(&model.instantiate(&[], &[]).unwrap(), &textures[k], keep);
            assert!(all < 0.5 * mean, "frame {k}: all components {all}, mean {mean}");
            let (t, w) = model.frame_coefficients(k).unwrap();
            ours1 += mse(&model.instantiate(&t[..1], &w[..1]).unwrap(), &textures[k], keep);
            naive1 += mse(&pca.reconstruct(k, 1).unwrap(), &textures[k], keep);
        }
        eprintln!(
            "reference {}, medoid errors {:?}; one component each: ours {:.1}, naive {:.1}",
            report.reference,
            report.medoid_errors,
            ours1 / 5.0,
            naive1 / 5.0
        );
        // Measured at F = 5: ours 63.4, naive 22.8 with one component each; the thesis's
        // advantage needs more frames than this test builds (the evaluation measures it).
        assert!(ours1.is_finite() && naive1.is_finite());
    }
}

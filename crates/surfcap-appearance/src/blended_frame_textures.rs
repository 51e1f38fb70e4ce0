//! A texture for every frame of a synthesised animation (thesis Fig. 7.1: shape and appearance
//! animated together). Each output frame is a captured frame, or a transition frame blending two
//! captured frames with the weight Blend (Algorithm 2) gives the geometry there; its texture is
//! the model's reconstruction of the captured frame (4.4.3), or the two frames interpolated in
//! the eigen spaces with the same weights (4.6.1: `Σ w_k c_k` for the texture and warp
//! coefficients, then instantiated), so the appearance follows the geometry.
//!
//! Every distinct texture is instantiated once (a captured frame shown several times, or a
//! transition played twice, shares one image), in parallel, and encoded as PNG as soon as it is
//! made: only one float texture per thread is alive at a time, never the whole animation's.

use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;
use surfcap_mesh::Progress;

use crate::appearance_model::AppearanceModel;
use crate::error::{Error, Result};

/// What an output frame's texture is made of: training frame `from` (indices into the model's
/// frames) with weight `1 - weight` and `to` with `weight`. A captured frame is itself with
/// weight 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureMix {
    pub from: usize,
    pub to: usize,
    pub weight: f64,
}

impl TextureMix {
    /// A captured frame's own texture.
    pub fn original(frame: usize) -> TextureMix {
        TextureMix { from: frame, to: frame, weight: 0.0 }
    }

    /// The one training frame the mix is exactly (weight 0, weight 1, or the same frame twice):
    /// its coefficients are then that frame's to the bit, so its texture is the reconstruction.
    pub fn single_frame(&self) -> Option<usize> {
        if self.from == self.to || self.weight == 0.0 {
            Some(self.from)
        } else if self.weight == 1.0 {
            Some(self.to)
        } else {
            None
        }
    }
}

/// A distinct texture to make: a training frame's reconstruction, or a blend of two frames
/// (the weight's bits, so equal weights share one texture).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Source {
    Frame(usize),
    Blend(usize, usize, u64),
}

/// The textures of an animation.
#[derive(Debug, Clone)]
pub struct BlendedTextures {
    /// Each distinct texture once, as an encoded 8-bit RGB PNG file, in the order the frames
    /// first show them.
    pub images: Vec<Vec<u8>>,
    /// The index into `images` of every output frame's texture.
    pub frame_texture: Vec<usize>,
    /// Distinct training frames reconstructed.
    pub reconstructed: usize,
    /// Distinct blends interpolated.
    pub interpolated: usize,
    /// Time spent instantiating and encoding.
    pub seconds: f64,
}

/// The texture of every frame of `mixes` from `model`: reconstructions for captured frames,
/// interpolations `[(from, 1 - weight), (to, weight)]` for blends. An index past the model's
/// frames or a weight outside [0, 1] is refused, naming the output frame. `progress` counts the
/// distinct textures.
pub fn blended_frame_textures(
    model: &AppearanceModel,
    mixes: &[TextureMix],
    progress: &dyn Progress,
) -> Result<BlendedTextures> {
    let t0 = Instant::now();
    let n = model.n_frames();
    let mut index: HashMap<Source, usize> = HashMap::new();
    let mut sources: Vec<Source> = Vec::new();
    let mut frame_texture = Vec::with_capacity(mixes.len());
    for (k, m) in mixes.iter().enumerate() {
        if m.from >= n || m.to >= n {
            return Err(Error::Invalid(format!(
                "output frame {k}: training frames {} and {}: the model has {n} frames",
                m.from, m.to
            )));
        }
        if !(0.0..=1.0).contains(&m.weight) {
            return Err(Error::Invalid(format!("output frame {k}: weight {}: expected a number in [0, 1]", m.weight)));
        }
        let source = match m.single_frame() {
            Some(f) => Source::Frame(f),
            None => Source::Blend(m.from, m.to, m.weight.to_bits()),
        };
        let next = sources.len();
        let t = *index.entry(source).or_insert_with(|| {
            sources.push(source);
            next
        });
        frame_texture.push(t);
    }
    progress.start("instantiating textures", sources.len() as u64);
    let images = sources
        .par_iter()
        .map(|s| {
            let texture = match *s {
                Source::Frame(f) => model.reconstruct(f)?,
                Source::Blend(a, b, w) => {
                    let w = f64::from_bits(w);
                    model.interpolate(&[(a, 1.0 - w), (b, w)])?
                }
            };
            let png = texture.to_png_bytes().map_err(|e| Error::Invalid(format!("cannot encode a texture: {e}")))?;
            progress.advance(1);
            Ok(png)
        })
        .collect::<Result<Vec<Vec<u8>>>>()?;
    progress.finish();
    let reconstructed = sources.iter().filter(|s| matches!(s, Source::Frame(_))).count();
    Ok(BlendedTextures {
        images,
        frame_texture,
        reconstructed,
        interpolated: sources.len() - reconstructed,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::appearance_model::{AppearanceOptions, build_appearance_model};
    use crate::test_support::{disc_mask, quadratic_flow, synthetic_frame};
    use crate::{FlowField, TextureImage};
    use surfcap_mesh::NoProgress;

    fn rgb8(png: &[u8]) -> Vec<u8> {
        image::load_from_memory(png).unwrap().to_rgb8().into_raw()
    }

    #[test]
    fn transition_frames_are_the_models_interpolation_with_the_blend_weight() {
        let mask = disc_mask(32);
        let textures: Vec<TextureImage> = [1u64, 4, 9].iter().map(|&k| synthetic_frame(&mask, k, 1.2)).collect();
        let names: Vec<String> = (0..3).map(|k| format!("s:{k}")).collect();
        let flow = |a: &TextureImage, b: &TextureImage| -> Result<FlowField> { quadratic_flow(a, b, None) };
        let (model, _) =
            build_appearance_model(&textures, &names, &mask, &AppearanceOptions::default(), &flow, &NoProgress)
                .unwrap();
        let blend = |w: f64| TextureMix { from: 0, to: 2, weight: w };
        let mixes = [
            TextureMix::original(0),
            blend(0.0),
            blend(0.25),
            blend(0.75),
            blend(1.0),
            TextureMix::original(2),
            TextureMix::original(0),
            blend(0.25),
        ];
        let out = blended_frame_textures(&model, &mixes, &NoProgress).unwrap();
        // Frames 0, 1 and 6 are frame 0; 4 and 5 frame 2; 2 and 7 one blend.
        assert_eq!(out.frame_texture, vec![0, 0, 1, 2, 3, 3, 0, 1]);
        assert_eq!((out.images.len(), out.reconstructed, out.interpolated), (4, 2, 2));
        assert_eq!(rgb8(&out.images[0]), model.reconstruct(0).unwrap().to_rgb8());
        assert_eq!(rgb8(&out.images[3]), model.reconstruct(2).unwrap().to_rgb8());
        for (image, w) in [(1, 0.25), (2, 0.75)] {
            let expected = model.interpolate(&[(0, 1.0 - w), (2, w)]).unwrap().to_rgb8();
            assert_eq!(rgb8(&out.images[image]), expected, "weight {w}");
            assert_ne!(rgb8(&out.images[image]), rgb8(&out.images[0]), "a blend differs from its source");
            assert_ne!(rgb8(&out.images[image]), rgb8(&out.images[3]), "a blend differs from its destination");
        }
        // The same whatever the thread count.
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let again = one.install(|| blended_frame_textures(&model, &mixes, &NoProgress).unwrap());
        assert_eq!(again.images, out.images);
        // Bad input names the output frame.
        let e = blended_frame_textures(&model, &[TextureMix::original(0), TextureMix::original(3)], &NoProgress)
            .unwrap_err()
            .to_string();
        assert!(e.contains("output frame 1") && e.contains("3 frames"), "{e}");
        let e = blended_frame_textures(&model, &[blend(1.5)], &NoProgress).unwrap_err().to_string();
        assert!(e.contains("output frame 0") && e.contains("[0, 1]"), "{e}");
    }
}

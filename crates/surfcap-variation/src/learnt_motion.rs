//! The motion a variant varies, without sampling (what a variant is measured against): a learnt
//! sequence's latent trajectory reconstructed (thesis 6.6), or for a blend of two learnt
//! sequences at a weight the latent interpolation of the two learnt trajectories around the
//! weight (6.7), reconstructed; in the body frame on the reference's frames, and
//! placed in the world at the motion's own timing.

use crate::VariationModel;
use crate::error::Result;
use crate::motion_parametrisation::{blend_ladder, bounding_rungs, interpolate_latents, interpolated_timing};
use crate::variation_sampling::{place_and_retime, reconstruct_aligned};

/// A learnt motion's poses.
pub struct LearntMotion {
    /// Body-frame poses on the reference's frames.
    pub aligned: Vec<Vec<f32>>,
    /// World poses at the motion's own timing.
    pub world: Vec<Vec<f32>>,
}

/// The learnt trajectory of the sequence `name`, reconstructed.
pub fn learnt_sequence(model: &VariationModel, name: &str) -> Result<LearntMotion> {
    let j = model.sequence_index(name)?;
    let (aligned, disp) = reconstruct_aligned(model, &model.learnt_latents(j)?)?;
    let s = &model.sequences[j];
    let world = place_and_retime(&aligned, &disp, &s.first_placement, &s.times, s.own_frames)?;
    Ok(LearntMotion { aligned, world })
}

/// The blend of the learnt sequences `a` and `b` at weight `w` in [0, 1]: the two learnt
/// trajectories around `w` interpolated in the latent space, reconstructed, started where `a`
/// starts.
pub fn learnt_blend(model: &VariationModel, a: &str, b: &str, w: f64) -> Result<LearntMotion> {
    let ladder = blend_ladder(model, a, b)?;
    let (r1, r2) = bounding_rungs(&ladder, w)?;
    let lat = interpolate_latents(&model.learnt_latents(r1.sequence)?, &model.learnt_latents(r2.sequence)?, r1, r2, w);
    let (aligned, disp) = reconstruct_aligned(model, &lat)?;
    let (own, times) = interpolated_timing(model, r1, r2, w);
    let start = model.sequences[model.sequence_index(a)?].first_placement;
    let world = place_and_retime(&aligned, &disp, &start, &times, own)?;
    Ok(LearntMotion { aligned, world })
}

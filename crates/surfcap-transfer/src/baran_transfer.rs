//! Baran et al. 2009 (semantic deformation transfer, [`crate::semantic_deformation_transfer`])
//! as a trained model a user applies to whole motions, next to the GP transfer of
//! [`crate::motion_transfer`]: the key pose pairs are the whole model (the shape spaces and the
//! target's Poisson factorisation are rebuilt from them when it is applied).
//!
//! Applying it to a motion: each source frame is transferred by the key poses' affine weights
//! (rotation-invariant, so the frame's placement in the world does not matter), aligned onto
//! the target's first key pose, and moved in the world as the GP transfer moves its poses: from
//! the target's first key placement, by the source's own rigid displacement from frame to
//! frame (eq. 5.3) with its translation scaled by the size ratio of the subjects (RMS distance
//! to the centroid of their first key poses). Baran et al. transfer poses, not travel; this
//! placement is ours.

use crate::error::{Error, Result, check_positions};
use crate::motion_transfer::TransferredMotion;
use crate::pose_representation::{align_motion, align_to_reference};
use crate::semantic_deformation_transfer::SemanticDeformationTransfer;

/// A trained Baran et al. transfer: corresponding key poses of the two subjects (world
/// positions as the subjects hold them) and both meshes.
#[derive(Debug, Clone, PartialEq)]
pub struct BaranTransfer {
    pub source_triangles: Vec<[u32; 3]>,
    pub target_triangles: Vec<[u32; 3]>,
    pub source_keys: Vec<Vec<f32>>,
    pub target_keys: Vec<Vec<f32>>,
}

/// RMS distance of a pose's vertices to their centroid.
fn size(p: &[f32]) -> f64 {
    let n = (p.len() / 3).max(1) as f64;
    let mut c = [0.0f64; 3];
    for v in p.chunks_exact(3) {
        for k in 0..3 {
            c[k] += v[k] as f64 / n;
        }
    }
    let s: f64 = p.chunks_exact(3).map(|v| (0..3).map(|k| (v[k] as f64 - c[k]).powi(2)).sum::<f64>()).sum();
    (s / n).sqrt()
}

impl BaranTransfer {
    /// The model of the key pose pairs `(source global frame, target global frame)`.
    pub fn train(
        source: &surfcap_mesh::Subject,
        target: &surfcap_mesh::Subject,
        keys: &[(usize, usize)],
    ) -> Result<BaranTransfer> {
        if keys.is_empty() {
            return Err(Error::Invalid("no key pose pairs: expected at least one".into()));
        }
        let pose = |s: &surfcap_mesh::Subject, g: usize, side: &str| -> Result<Vec<f32>> {
            s.frame(g).map(<[f32]>::to_vec).ok_or_else(|| {
                Error::Invalid(format!("{side} frame {g}: the {side} subject {:?} has no such frame", s.name))
            })
        };
        let model = BaranTransfer {
            source_triangles: source.topology().triangles().to_vec(),
            target_triangles: target.topology().triangles().to_vec(),
            source_keys: keys.iter().map(|k| pose(source, k.0, "source")).collect::<Result<_>>()?,
            target_keys: keys.iter().map(|k| pose(target, k.1, "target")).collect::<Result<_>>()?,
        };
        model.build()?;
        Ok(model)
    }

    pub fn source_vertices(&self) -> usize {
        self.source_keys.first().map_or(0, |p| p.len() / 3)
    }

    pub fn target_vertices(&self) -> usize {
        self.target_keys.first().map_or(0, |p| p.len() / 3)
    }

    /// The shape spaces and the target's Poisson factorisation (what applying needs).
    pub fn build(&self) -> Result<SemanticDeformationTransfer> {
        let topo = |t: &[[u32; 3]], keys: &[Vec<f32>]| {
            surfcap_mesh::Topology::new(keys.first().map_or(0, |p| p.len() / 3), t.to_vec(), None)
        };
        SemanticDeformationTransfer::new(
            &topo(&self.source_triangles, &self.source_keys)?,
            &self.source_keys,
            &topo(&self.target_triangles, &self.target_keys)?,
            &self.target_keys,
        )
    }

    /// Transfers a motion of the source (frames in order) with `sdt` (from [`Self::build`]):
    /// the target's aligned poses and world poses (see the module's doc); no parts.
    pub fn transfer(&self, sdt: &SemanticDeformationTransfer, frames: &[&[f32]]) -> Result<TransferredMotion> {
        let (Some(s0), Some(t0)) = (self.source_keys.first(), self.target_keys.first()) else {
            return Err(Error::Invalid("no key pose pairs: expected at least one".into()));
        };
        for (f, p) in frames.iter().enumerate() {
            check_positions(p, self.source_vertices(), &format!("source frame {f}"))?;
        }
        let motion = align_motion(s0, frames);
        let scale = {
            let (a, b) = (size(s0), size(t0));
            if a > 0.0 && b.is_finite() { b / a } else { 1.0 }
        };
        let mut aligned = Vec::with_capacity(frames.len());
        for f in frames {
            aligned.push(align_to_reference(t0, &sdt.transfer(f)?).0);
        }
        let displacements: Vec<[f64; 6]> =
            motion.displacements.iter().map(|d| [d[0] * scale, d[1] * scale, d[2] * scale, d[3], d[4], d[5]]).collect();
        Ok(TransferredMotion::placed(vec![Vec::new(); aligned.len()], aligned, displacements))
    }
}

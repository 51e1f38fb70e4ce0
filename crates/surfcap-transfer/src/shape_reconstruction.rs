//! Shape pose reconstruction (thesis 5.6): the predicted body parts put back together into one
//! target mesh. Each part is first corrected against its nearest training meshes (5.6.1,
//! [`crate::part_correction`]), then the parts are stitched along optimal cuts inside their
//! overlaps with a Poisson merge (5.6.2, [`crate::part_stitching`]). The global rigid
//! displacement is applied afterwards by [`crate::motion_transfer::MotionTransfer::transfer`].
//!
//! The expensive part (one Poisson factorisation per part for the correction, one for the
//! whole template for the stitching) is built once per model in [`Reconstructor::new`]; the
//! per-frame work is [`Reconstructor::reconstruct`].

use rayon::prelude::*;
use surfcap_mesh::Topology;

use crate::error::{Error, Result};
use crate::motion_transfer::MotionTransfer;
use crate::part_correction::PartCorrector;
use crate::part_stitching::{StitchReport, Stitcher};

/// How the predicted parts become one mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReconstructionOptions {
    /// Correct each part against its nearest training meshes (5.6.1).
    pub correction: bool,
    /// The number of nearest training meshes (M = 3 in the thesis).
    pub m_nearest: usize,
}

/// Without the correction: `surfcap eval transfer` measured it never lowering the error of
/// motions absent from training against the truth, and raising the largest edge-length change
/// inside parts (see `transfer apply --correction`); it stays one option away.
impl Default for ReconstructionOptions {
    fn default() -> Self {
        ReconstructionOptions { correction: false, m_nearest: crate::part_correction::DEFAULT_M_NEAREST }
    }
}

/// Corrects and stitches the parts a [`MotionTransfer`] predicts.
pub struct Reconstructor {
    correctors: Option<Vec<PartCorrector>>,
    stitcher: Stitcher,
}

impl Reconstructor {
    /// Factorises what every frame shares. `target_training` are the target's aligned training
    /// poses (whole template), the examples of the correction.
    pub fn new(
        model: &MotionTransfer,
        target_topology: &Topology,
        target_training: &[Vec<f32>],
        opts: &ReconstructionOptions,
    ) -> Result<Reconstructor> {
        let parts = &model.target.parts;
        let rest = &model.target.reference;
        if target_topology.n_vertices() != parts.n_vertices {
            return Err(Error::Invalid(format!(
                "target mesh of {} vertices: expected {} (the model's)",
                target_topology.n_vertices(),
                parts.n_vertices
            )));
        }
        let correctors = if opts.correction {
            if target_training.is_empty() {
                return Err(Error::Invalid("no target training poses: the part correction needs examples".into()));
            }
            let made: Vec<PartCorrector> = (0..parts.len())
                .into_par_iter()
                .map(|k| {
                    let sub = parts.submesh(target_topology, k);
                    let examples = target_training.iter().map(|p| sub.gather(p)).collect();
                    PartCorrector::new(&sub.topology, &sub.gather(rest), examples, opts.m_nearest)
                })
                .collect::<Result<_>>()?;
            Some(made)
        } else {
            None
        };
        let stitcher = Stitcher::new(target_topology, rest, parts)?;
        Ok(Reconstructor { correctors, stitcher })
    }

    /// One frame: each part corrected (when asked), then the parts stitched.
    pub fn reconstruct(&self, part_positions: &[Vec<f32>]) -> Result<(Vec<f32>, StitchReport)> {
        match &self.correctors {
            Some(c) => {
                if c.len() != part_positions.len() {
                    return Err(Error::Invalid(format!("{} part poses: expected {}", part_positions.len(), c.len())));
                }
                let corrected: Vec<Vec<f32>> =
                    c.par_iter().zip(part_positions.par_iter()).map(|(c, p)| c.correct(p)).collect::<Result<_>>()?;
                self.stitcher.stitch(&corrected)
            }
            None => self.stitcher.stitch(part_positions),
        }
    }
}

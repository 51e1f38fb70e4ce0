//! How a walk is played besides its geometry: textured from an appearance model (thesis Fig.
//! 7.1) and with learned variants on its repeated runs (thesis chapter 6). Asked for as paths
//! ([`Playback`]), opened and checked against the subject and the output before any search
//! ([`Playback::open`]), then attached to the prepared subject ([`OpenedPlayback::prepare`]).

use std::path::PathBuf;
use std::sync::Arc;

use surfcap_mesh::Subject;
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::error::Result;
use crate::frame_appearance::SubjectAppearance;
use crate::prepared::{Output, Prepared};
use crate::walk_variants::Variation;

/// What a walk is played with.
#[derive(Debug, Clone, Default)]
pub struct Playback {
    /// An appearance model of the subject's frames (`surfcap appearance build MAPS --mesh
    /// SUBJECT -o MODEL`): a texture per output frame, written as a glb.
    pub appearance: Option<PathBuf>,
    /// Learned variants on the walk's repeated runs.
    pub variation: Option<Variation>,
}

/// A [`Playback`] whose appearance model is open and checked.
pub struct OpenedPlayback {
    pub appearance: Option<SubjectAppearance>,
    pub variation: Option<Variation>,
}

impl Playback {
    /// Opens the appearance model (refused when the output cannot carry a texture per frame,
    /// the subject has no UV atlas or the model's frames are not the subject's) and checks the
    /// variation model's folder, before any search.
    pub fn open(&self, subject: &Subject, out: &Output) -> Result<OpenedPlayback> {
        let appearance = match (&self.appearance, &out.path) {
            (Some(path), Some(output)) => Some(SubjectAppearance::open(path, subject, out.format(), output)?),
            (Some(path), None) => crate::error::refuse!(
                "--appearance {}: a textured animation is written as a glb with a texture per frame: expected an output",
                path.display()
            ),
            (None, _) => None,
        };
        if let Some(v) = &self.variation {
            v.check(out.path.as_deref())?;
        }
        Ok(OpenedPlayback { appearance, variation: self.variation.clone() })
    }
}

impl OpenedPlayback {
    /// The subject of `pipe` prepared ([`Prepared::new`]) and played with this.
    pub fn prepare(
        self,
        pipe: impl Into<Arc<Pipeline>>,
        params: GraphParams,
        tracked: Option<&[usize]>,
    ) -> Result<Prepared> {
        Ok(Prepared::new(pipe, params, tracked)?.with_appearance(self.appearance).with_variation(self.variation))
    }
}

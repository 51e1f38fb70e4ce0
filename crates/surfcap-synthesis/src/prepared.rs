//! A subject prepared for synthesis (thesis 3.5): its graph and walk model read from the
//! pipeline's cache or built once, then any number of queries answered on it
//! ([`Prepared::follow_path`], [`Prepared::time_key_poses`], [`Prepared::reach`]), each played
//! and written with the same appearance model and variants, if any.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use surfcap_formats::export::{ExportFormat, ExportOptions};
use surfcap_mesh::{Subject, UpAxis};
use surfcap_motion::graph::Graph;
use surfcap_motion::walk_sequence::WalkModel;
use surfcap_pipeline::{GraphParams, Pipeline};

use crate::constraint::Tolerances;
use crate::error::{Result, refuse};
use crate::frame_appearance::SubjectAppearance;
use crate::walk_variants::Variation;

/// A subject with its graph and walk model, and how its walks are played.
pub struct Prepared {
    pub pipe: Pipeline,
    pub params: GraphParams,
    pub graph: Arc<Graph>,
    pub model: Arc<WalkModel>,
    /// The vertices whose centre is followed (`None`: all).
    pub tracked: Option<Vec<usize>>,
    /// Time to read or build the graph and the walk model.
    pub seconds: f64,
    /// Where every output frame's texture comes from, if anywhere.
    pub appearance: Option<SubjectAppearance>,
    /// Learned variants shown when a walk repeats frames, if asked.
    pub variation: Option<Variation>,
}

impl Prepared {
    /// Reads (or builds) the graph and walk model of `params` from the pipeline; the walk
    /// model follows the centre of `tracked` (all vertices when `None`).
    pub fn new(pipe: Pipeline, params: GraphParams, tracked: Option<&[usize]>) -> Result<Self> {
        let t0 = Instant::now();
        if let Some(ids) = tracked {
            let nv = pipe.subject().topology().n_vertices();
            if let Some(v) = ids.iter().find(|&&v| v >= nv) {
                refuse!("--track {v}: the subject has vertices 0 to {}", nv - 1);
            }
        }
        let graph = pipe.graph(&params)?.value;
        let model = pipe.walk_model(&params, tracked)?.value;
        let tracked = tracked.map(<[usize]>::to_vec);
        Ok(Prepared {
            pipe,
            params,
            graph,
            model,
            tracked,
            seconds: t0.elapsed().as_secs_f64(),
            appearance: None,
            variation: None,
        })
    }

    /// The same, texturing every output frame from `appearance` (opened and checked against
    /// the subject by [`SubjectAppearance::open`]).
    pub fn with_appearance(mut self, appearance: Option<SubjectAppearance>) -> Self {
        self.appearance = appearance;
        self
    }

    /// The same, playing learned variants where a walk repeats frames.
    pub fn with_variation(mut self, variation: Option<Variation>) -> Self {
        self.variation = variation;
        self
    }

    pub fn subject(&self) -> &Subject {
        self.pipe.subject()
    }

    pub fn up(&self) -> UpAxis {
        self.subject().up_axis
    }
}

/// Where an animation goes and how its constraints are judged.
#[derive(Debug, Clone)]
pub struct Output {
    /// A .glb, .usda or .abc file, a folder for obj, ply, pc2 or npy, or a `.frames` folder;
    /// the report goes beside it ([`crate::animation_output::report_path`]).
    pub path: PathBuf,
    /// The format (default: from the extension, else glb).
    pub format: Option<ExportFormat>,
    /// A folder output may replace a folder surfcap did not write.
    pub force: bool,
    pub tolerances: Tolerances,
}

impl Output {
    /// An output at `path` in the format its extension says, with the default tolerances.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Output { path: path.into(), format: None, force: false, tolerances: Tolerances::default() }
    }

    /// The format written: the given one, else the extension's, else glb.
    pub fn format(&self) -> ExportFormat {
        crate::animation_output::output_format(self.format, &self.path)
    }

    pub(crate) fn export_options(&self) -> ExportOptions {
        ExportOptions { force: self.force, ..Default::default() }
    }
}

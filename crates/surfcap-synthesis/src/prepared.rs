//! A subject prepared for synthesis (thesis 3.5): its graph and walk model read from the
//! pipeline's cache or built once, then any number of queries answered on it
//! ([`Prepared::follow_path`], [`Prepared::time_key_poses`], [`Prepared::reach`]), each played
//! with the same appearance model and variants, if any, and written when its [`Output`] has a
//! path (kept in memory only otherwise: the outcome holds the animation and its report).
//!
//! The pipeline is shared ([`Arc`]): a front end that keeps a subject's pipeline (the Python
//! `Subject`) prepares it without giving it up, and the products it caches serve both.

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
    /// The subject's derived products, shared with whoever else holds them.
    pub pipe: Arc<Pipeline>,
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
    /// model follows the centre of `tracked` (all vertices when `None`). `pipe` is a
    /// [`Pipeline`] or an `Arc` of one that others keep using.
    pub fn new(pipe: impl Into<Arc<Pipeline>>, params: GraphParams, tracked: Option<&[usize]>) -> Result<Self> {
        let pipe: Arc<Pipeline> = pipe.into();
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
    /// the report goes beside it ([`crate::animation_output::report_path`]). `None`: nothing is
    /// written; the animation and its report are only returned ([`Output::in_memory`]).
    pub path: Option<PathBuf>,
    /// The format (default: from the extension, else glb).
    pub format: Option<ExportFormat>,
    /// A folder output may replace a folder surfcap did not write.
    pub force: bool,
    pub tolerances: Tolerances,
}

impl Output {
    /// An output at `path` in the format its extension says, with the default tolerances.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Output { path: Some(path.into()), format: None, force: false, tolerances: Tolerances::default() }
    }

    /// No file: the animation is played and measured, and returned with its report.
    pub fn in_memory(tolerances: Tolerances) -> Self {
        Output { path: None, format: None, force: false, tolerances }
    }

    /// The format written: the given one, else the extension's, else glb (also when nothing is
    /// written: the size checks then hold the animation to what a glb could carry).
    pub fn format(&self) -> ExportFormat {
        crate::animation_output::output_format(self.format, self.path.as_deref().unwrap_or(std::path::Path::new("")))
    }

    /// Where the report goes, when anything is written.
    pub fn report_path(&self) -> Option<PathBuf> {
        self.path.as_deref().map(crate::animation_output::report_path)
    }

    pub(crate) fn export_options(&self) -> ExportOptions {
        ExportOptions { force: self.force, ..Default::default() }
    }
}

//! A walk found by a search played (thesis Algorithm 3: original frames as captured,
//! transitions blended), with learned variants on its repeated runs and a texture per frame
//! when the prepared subject has them, and written when the output has a path (returned only,
//! otherwise); what every synthesis report says about it ([`WalkReport`]).

use std::path::PathBuf;

use serde::Serialize;
use surfcap_geometry::motion_plane_alignment::PlaneMotion;
use surfcap_mesh::{Progress, Subject};
use surfcap_motion::edge_weights::Alpha;
use surfcap_pipeline::GraphKind;
use surfcap_pipeline::walk_playback::{SequenceVariation, WalkSegment, play_walk, play_walk_with};

use crate::animation_output::{Animation, write_animation};
use crate::error::Result;
use crate::frame_appearance::{AppearanceReport, write_textured};
use crate::prepared::{Output, Prepared};
use crate::walk_variants::variants_for_walk;
use crate::words::count_of;

/// The report's `graph`: which graph the walk was found in.
#[derive(Debug, Clone, Serialize)]
pub struct GraphReport {
    pub kind: GraphKind,
    pub alpha: Alpha,
    pub edges: usize,
    pub transitions: usize,
    pub prepare_seconds: f64,
}

/// The report's `variation`: what the walk repeated and how much of it variants showed.
#[derive(Debug, Clone, Serialize)]
pub struct VariationReport {
    pub seed: u64,
    pub model: PathBuf,
    pub frames: usize,
    pub repeats: usize,
    pub played_as_variants: usize,
    pub sequences: Vec<SequenceVariation>,
    /// Per variant shown, what the foot-skate clean-up did (its sliding before and after).
    pub foot_skate_cleanup: Vec<crate::walk_variants::VariantCleanup>,
}

/// What every synthesis report says about the played walk (its fields sit in the report
/// between the query's own and what the query measured on the written frames).
#[derive(Debug, Clone, Serialize)]
pub struct WalkReport {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub appearance: Option<AppearanceReport>,
    pub subject: String,
    pub graph: GraphReport,
    pub fps: f64,
    pub frames: usize,
    pub original_frames: usize,
    pub synthetic_frames: usize,
    pub transitions: usize,
    /// How the transitions placed the subject: `aligned` (Algorithm 2's rigid re-placement, for
    /// a subject that travels) or `captured` (where its frames were captured, for one that does
    /// not; surfcap-motion's `subject_placement`).
    pub placement: surfcap_motion::subject_placement::Placement,
    pub blend_seconds: f64,
    pub repeated_frames: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variation: Option<VariationReport>,
    /// The walk, global frames.
    pub walk: Vec<u32>,
    pub segments: Vec<WalkSegment>,
    /// The files written (none when the output has no path).
    pub outputs: Vec<PathBuf>,
}

/// A played (and, when the output has a path, written) walk.
pub struct Played {
    pub written: Vec<PathBuf>,
    /// Where the report is written; `None` when nothing is.
    pub report_path: Option<PathBuf>,
    pub report: WalkReport,
    /// Tracked centre of every output frame, from the written positions.
    pub centres: Vec<[f64; 3]>,
    /// The animation as written (one sequence), for measures at its frames.
    pub output: Subject,
    pub transitions: usize,
}

/// Plays `walk` placed by `start` as the sequence `name` and writes the animation to `out`
/// when it has a path (textured when the prepared subject has an appearance model, with
/// variants on repeated runs when it has a variation model); without a path nothing is
/// written and [`Played::output`] is the animation.
pub fn play_and_write(
    prep: &Prepared,
    walk: &[u32],
    start: &PlaneMotion,
    name: &str,
    out: &Output,
    progress: &dyn Progress,
) -> Result<Played> {
    let s = prep.subject();
    let tracked = prep.tracked.as_deref();
    let (variants, cleanups) = match &prep.variation {
        Some(v) => {
            let (fv, c) = variants_for_walk(prep, v, walk, progress)?;
            (Some(fv), c)
        }
        None => (None, Vec::new()),
    };
    let played = match &variants {
        Some(v) => play_walk_with(&prep.pipe, &prep.params, tracked, walk, start, name, v)?,
        None => play_walk(&prep.pipe, &prep.params, tracked, walk, start, name)?,
    };
    let repeats = played.repeat_summary(s);
    let frames = played.frames();
    let result = s.derived(format!("{}-{name}", s.name), played.sequence)?;
    let (written, appearance) = match (&prep.appearance, &out.path) {
        // Thesis Fig. 7.1: each frame's texture blended with the geometry's weights.
        (Some(a), Some(path)) => {
            let textured = a.textures(&played.mix, progress)?;
            (write_textured(&result, &textured, path, progress)?, Some(textured.report))
        }
        (None, Some(path)) => {
            (write_animation(Animation::Subject(&result), out.format, path, out.export_options(), progress)?, None)
        }
        // (An appearance model needs an output: `Playback::open` refuses it without one.)
        (_, None) => (Vec::new(), None),
    };
    let variation = prep.variation.as_ref().map(|v| {
        progress.note(&format!(
            "{} of {} were repeats; {} played as variants",
            repeats.repeats,
            count_of(frames, "frame"),
            repeats.played_as_variants
        ));
        VariationReport {
            seed: v.seed,
            model: v.model.clone(),
            frames: repeats.frames,
            repeats: repeats.repeats,
            played_as_variants: repeats.played_as_variants,
            sequences: repeats.sequences.clone(),
            foot_skate_cleanup: cleanups.clone(),
        }
    });
    let report = WalkReport {
        appearance,
        subject: s.name.clone(),
        graph: GraphReport {
            kind: prep.params.kind,
            alpha: prep.params.alpha,
            edges: prep.graph.edges().len(),
            transitions: prep.model.n_transitions(),
            prepare_seconds: prep.seconds,
        },
        fps: s.fps,
        frames,
        original_frames: played.original_frames,
        synthetic_frames: played.synthetic_frames,
        transitions: played.transitions,
        placement: prep.model.placement(),
        blend_seconds: played.blend_seconds,
        repeated_frames: repeats.repeats,
        variation,
        walk: walk.to_vec(),
        segments: played.segments,
        outputs: written.clone(),
    };
    Ok(Played {
        written,
        report_path: out.report_path(),
        report,
        centres: played.centres,
        output: result,
        transitions: played.transitions,
    })
}

/// Pose distance (thesis eq. 2.13, the graph's metric) between a frame of the subject and a
/// frame of the written output: 0 when the output shows that very pose. The two frames are
/// compared as a two-frame subject, so the motion-plane alignment is the matrix's.
pub fn pose_distance_to_output(prep: &Prepared, output: &Subject, source: u32, out_frame: usize) -> Result<f64> {
    let s = prep.subject();
    let mut positions = s.frame(source as usize).expect("a resolved frame").to_vec();
    let Some(shown) = output.frame(out_frame) else {
        crate::error::refuse!("output frame {out_frame} is past the output's {} frames", output.n_frames());
    };
    positions.extend_from_slice(shown);
    let pair = s.derived("pair", surfcap_mesh::Sequence::new("pair", s.topology().n_vertices(), positions)?)?;
    let d = surfcap_geometry::distance_matrix::distance_matrix(
        &pair,
        &surfcap_geometry::distance_matrix::DistanceParams::default(),
        &surfcap_mesh::NoProgress,
    );
    Ok(d.get(0, 1))
}

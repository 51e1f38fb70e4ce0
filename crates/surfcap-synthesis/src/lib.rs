//! Synthesis as a library: everything a front end (the command line, Python bindings, an
//! interactive player) needs to make an animation from a subject, so that none copies it.
//!
//! It sits above `surfcap-pipeline` (the derived products of one subject: distances,
//! transition table, graphs, walk model), `surfcap-variation`, `surfcap-appearance` and
//! `surfcap-smg`, beside `surfcap-eval`, below the front ends. Front ends parse arguments,
//! show progress ([`surfcap_mesh::Progress`]: this crate never prints) and print what the runs
//! return; they map [`ConstraintsMissed`] to their own failure (the command line: exit 3).
//!
//! # Where to start reading
//! - [`Prepared`] (`prepared.rs`): a subject with its graph and walk model (its pipeline shared
//!   with the front end), answering many queries; [`Output`] says where an animation goes (or
//!   that it stays in memory, [`Output::in_memory`]) and how its constraints are judged. Each
//!   request checks itself before any work (`PathRequest::check`, [`check_key_poses`],
//!   `ReachRequest::check`), so a prepared subject answers it as the one-call form does.
//! - The queries, one file each, each returning a typed outcome whose report is a `Serialize`
//!   struct written beside the animation as `<output>.report.json`:
//!   - [`path_run`]: path following (thesis 3.5.1), [`Prepared::follow_path`];
//!   - [`keyposes_run`]: key-pose timing (thesis 3.5.2, Fig. 3.18), [`Prepared::time_key_poses`];
//!   - [`reach_run`]: a distance in a time between two frames (Huang et al. 2009's
//!     constraint in the essential graph), [`Prepared::reach`];
//!   - [`smg_query`]: Huang et al. 2009's surface motion graph (its own engine, on subjects and
//!     frame sets), [`SmgGraph::query`].
//!
//!   `synthesize_path | synthesize_keyposes | synthesize_reach` are the one-call forms a command
//!   uses: the request checked and sized before any work, the subject prepared, the query run.
//! - [`walk_output`]: a walk played (thesis Algorithm 3) and written, with a texture per frame
//!   ([`frame_appearance`], thesis Fig. 7.1) and learned variants on its repeated runs
//!   ([`walk_variants`], thesis chapter 6), chosen by [`Playback`]; [`walk_output::WalkReport`]
//!   is what every report says about the walk.
//! - [`transfer_run`]: motion transfer (thesis chapter 5): a model trained with its report, a
//!   motion transferred with a trained model (the body parts a per-part run learns on:
//!   `surfcap_transfer::body_parts_choice`).
//! - [`interpolation_run`] and [`transition_run`]: poses between two frames (thesis 2.4) and
//!   one optimal transition between two frames (2.5.4, Algorithm 2), as `surfcap interpolate`
//!   and `surfcap transition` make them.
//! - [`rig_run`]: a subject as a skinned rig (`surfcap_skinning`'s SSDR) written as a glTF
//!   skin, with per-frame reconstruction errors, size and time.
//! - [`constraint`]: soft constraints and how closely they were met.
//! - [`controller`]: a character steered live by a stream of inputs (motion matching on the
//!   essential graph, with parametric blending of same-kind clips for in-between speeds and
//!   turn rates): [`controller::Controller::step`] gives the frames to show.
//! - [`request_size`] and [`travel_check`]: requests refused before any work (too many frames,
//!   too much memory, a glb over 4 GiB; a path or distance asked of clips that stay in place).
//! - [`variation_training`] and [`variant_samples`]: a variation model learnt from a subject
//!   (thesis 6.4-6.5, 6.7) and variants of a learnt sequence or blend sampled from it (6.6-6.7),
//!   written with reports (each variant measured against the learnt motion).
//!
//! Errors are [`Error`]: messages name the option or file a request came from and what was
//! expected; a message that adds context keeps the lower layer's error as its source.

pub mod animation_output;
pub mod constraint;
pub mod controller;
pub mod error;
pub mod frame_appearance;
pub mod interpolation_run;
pub mod keyposes_run;
pub mod path_run;
pub mod playback;
pub mod prepared;
pub mod reach_run;
pub mod request_size;
pub mod rig_run;
pub mod smg_query;
pub mod transfer_run;
pub mod transition_run;
pub mod travel_check;
pub mod variant_samples;
pub mod variation_training;
pub mod walk_output;
pub mod walk_variants;
pub mod words;

pub use animation_output::{
    Animation, REPORT_KIND, plan_animation, plan_animation_and_report, report_path, write_animation, write_report,
};
pub use constraint::{Constraint, ConstraintsMissed, Tolerances};
pub use error::{Error, Result};
pub use interpolation_run::{Interpolation, InterpolationMethod, interpolate};
pub use keyposes_run::{KeyposesOutcome, KeyposesReport, check_key_poses, synthesize_keyposes};
pub use path_run::{CheckedPath, CurveSource, PathOutcome, PathQuery, PathReport, PathRequest, synthesize_path};
pub use playback::{OpenedPlayback, Playback};
pub use prepared::{Output, Prepared};
pub use reach_run::{ReachOutcome, ReachQuery, ReachReport, ReachRequest, synthesize_reach};
pub use request_size::SizeLimits;
pub use smg_query::{SmgGraph, SmgQuery, SmgQueryReport};
pub use transition_run::{Transition, TransitionReport, transition};
pub use walk_variants::Variation;

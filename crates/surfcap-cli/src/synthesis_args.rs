//! The command line's side of synthesis (`synth path | keyposes | reach`, `smg query`,
//! `interpolate`): the options that choose how a walk is played (`--appearance`, `--vary`),
//! turned into `surfcap_synthesis` values, and how missed constraints are shown (warnings on
//! stderr, `--strict`: exit 3 through `surfcap_synthesis::ConstraintsMissed`). The synthesis
//! itself is `surfcap_synthesis`'s.

use std::path::{Path, PathBuf};

use surfcap_formats::export::ExportFormat;
use surfcap_mesh::Subject;
use surfcap_synthesis::frame_appearance::SubjectAppearance;
use surfcap_synthesis::{Constraint, ConstraintsMissed, Output, Playback, Variation};

use crate::options::{ConstraintOpts, OutOpts};

/// The appearance model an animation's textures come from.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct AppearanceOpts {
    /// An appearance model of the subject's frames (`surfcap appearance build MAPS --mesh
    /// SUBJECT -o MODEL`, its frames named by the subject's `sequence:frame`): every output frame
    /// gets a texture (captured frames their reconstruction, transition frames interpolated in
    /// the eigen spaces with the geometry's blend weight), written as a glb with a texture per
    /// frame (the only format that can carry one).
    #[arg(long)]
    pub appearance: Option<PathBuf>,
}

impl AppearanceOpts {
    /// Opens the model when one is given (`SubjectAppearance::open` says what is refused).
    pub fn open(
        &self,
        subject: &Subject,
        format: ExportFormat,
        output: &Path,
    ) -> anyhow::Result<Option<SubjectAppearance>> {
        let Some(path) = &self.appearance else { return Ok(None) };
        Ok(Some(SubjectAppearance::open(path, subject, format, output)?))
    }
}

/// `--vary SEED --variation-model DIR` of `synth path | keyposes | reach`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct VaryOpts {
    /// Show learned variants of the captured motion (thesis chapter 6) each time the walk plays
    /// frames it has already shown, instead of the same poses again (transitions still blended,
    /// the walk placed as without); SEED seeds the variants' sampling (same seed, same
    /// animation). Needs --variation-model.
    #[arg(long, value_name = "SEED", requires = "variation_model")]
    pub vary: Option<u64>,
    /// The variation model the variants are sampled from (the folder `surfcap vary train
    /// SUBJECT -o DIR` writes, trained on this subject's sequences).
    #[arg(long, value_name = "DIR", requires = "vary")]
    pub variation_model: Option<PathBuf>,
}

/// The files `--appearance` and `--variation-model` name (inputs no output may overlap).
pub fn playback_inputs<'a>(appearance: &'a AppearanceOpts, vary: &'a VaryOpts) -> Vec<&'a Path> {
    appearance.appearance.iter().chain(&vary.variation_model).map(PathBuf::as_path).collect()
}

/// How the walk is played: `--appearance` and `--vary`.
pub fn playback(appearance: &AppearanceOpts, vary: &VaryOpts) -> Playback {
    let variation = match (vary.vary, &vary.variation_model) {
        (Some(seed), Some(model)) => Some(Variation { seed, model: model.clone() }),
        _ => None,
    };
    Playback { appearance: appearance.appearance.clone(), variation }
}

impl OutOpts {
    /// Where the animation goes, honouring `--force`.
    pub fn output(&self, ctx: &crate::Ctx) -> Output {
        Output {
            path: Some(self.output.clone()),
            format: self.format,
            force: ctx.force,
            tolerances: self.constraints.tolerances(),
        }
    }
}

/// Warns about every missed constraint on stderr (also under --quiet: it is part of the
/// result; under --json the report's `constraints` says it), then fails with
/// [`ConstraintsMissed`] under `--strict`.
pub fn check_constraints(ctx: &crate::Ctx, opts: &ConstraintOpts, constraints: &[Constraint]) -> anyhow::Result<()> {
    if !ctx.json {
        for c in constraints.iter().filter(|c| c.missed) {
            eprintln!("warning: {}; --tolerance/--frame-tolerance set it)", c.missed_text());
        }
    }
    match ConstraintsMissed::check(constraints) {
        Err(missed) if opts.strict => Err(missed.into()),
        _ => Ok(()),
    }
}

//! Variants of a learnt motion written as animations (thesis 6.6-6.7): a learnt sequence's, or
//! a blend's of two learnt sequences at any weight, sampled by Hybrid Monte Carlo from a
//! variation model (`surfcap vary train`), one glb per variant, with a report measuring each
//! against the learnt motion it varies (`surfcap_variation::learnt_motion`: body-frame distance,
//! where it ends, how far it travels) and the command that shows them next to the source.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use surfcap_formats::export::{ExportFormat, ExportOptions, export};
use surfcap_mesh::{FrameLabel, Progress, Sequence, Subject};
use surfcap_variation::VariationModel;
use surfcap_variation::centroid_path_length::centroid_path_length;
use surfcap_variation::learnt_motion::{LearntMotion, learnt_blend, learnt_sequence};
use surfcap_variation::mean_vertex_distance::mean_vertex_distance;
use surfcap_variation::motion_parametrisation::{Rung, blend_ladder, bounding_rungs, sample_blend_variants};
use surfcap_variation::pose_centroid::{centroid, distance3};
use surfcap_variation::variation_sampling::{ChainStart, ChainSummary, SamplingOptions, VariantPath, sample_variants};

use crate::animation_output::write_report;
use crate::error::Result;
use crate::words::count_of;

/// The folder kind of the output (its marker).
pub const SAMPLES_KIND: &str = "variation-samples";

/// What is varied: a learnt sequence, or the blend of two at weight `w` in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub enum Varied {
    Sequence(String),
    Blend { a: String, b: String, w: f64 },
}

/// A sampling request.
#[derive(Debug, Clone)]
pub struct SampleRequest {
    /// The model folder (`surfcap vary train`).
    pub model: PathBuf,
    pub varied: Varied,
    pub count: usize,
    /// Seed of the HMC chains (same seed, same files, whatever the thread count).
    pub seed: u64,
    pub options: SamplingOptions,
    /// The output folder: `<name>-variant-<k>.glb` per variant and `report.json`.
    pub output: PathBuf,
    /// The output folder may replace a folder surfcap did not write.
    pub force: bool,
}

/// The report's `blend`.
#[derive(Debug, Clone, Serialize)]
pub struct BlendReport {
    pub a: String,
    pub b: String,
    pub w: f64,
    pub lower: Rung,
    pub upper: Rung,
    pub pairing: Vec<usize>,
    pub lower_sequence: String,
    pub upper_sequence: String,
}

/// The report's `options`.
#[derive(Debug, Clone, Serialize)]
pub struct OptionsReport {
    pub start: &'static str,
    pub path: &'static str,
    pub smoothing: usize,
    pub deviation_smoothing: usize,
    pub warmup: usize,
    pub thin: usize,
    pub max_leapfrog: usize,
    pub foot_skate_cleanup: bool,
    /// Whether the clean-up moved the whole body with the planted feet (off with the hips held).
    pub move_root: bool,
    pub learnt_stretch: bool,
    pub carry_pins: bool,
}

/// The report's `learnt`: the motion the variants vary.
#[derive(Debug, Clone, Serialize)]
pub struct LearntReport {
    pub frames: usize,
    pub path_length: f64,
    pub what: &'static str,
}

/// One variant.
#[derive(Debug, Clone, Serialize)]
pub struct VariantReport {
    /// The glb written (none while the variant is only in memory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    pub sequence: String,
    pub frames: usize,
    /// Mean per-vertex distance from the learnt motion, body frame.
    pub body_frame_distance: f64,
    /// Distance between its last centroid and the learnt motion's.
    pub end_distance: f64,
    pub path_length: f64,
    /// What the foot-skate clean-up did (`None` when it was off): sliding before and after,
    /// the pinned vertices' drift from their pins before and after.
    pub cleanup: Option<surfcap_variation::foot_skate_cleanup::CleanupReport>,
}

/// The report of a sampling (`report.json` in the output folder).
#[derive(Debug, Clone, Serialize)]
pub struct SampleReport {
    /// The model folder (none for a model only in memory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<PathBuf>,
    pub subject: String,
    pub units: String,
    pub sequence: Option<String>,
    pub blend: Option<BlendReport>,
    pub seed: u64,
    pub count: usize,
    pub options: OptionsReport,
    pub chains: Vec<ChainSummary>,
    pub learnt: LearntReport,
    pub variants: Vec<VariantReport>,
    pub load_seconds: f64,
    pub sample_seconds: f64,
    pub write_seconds: f64,
    pub total_seconds: f64,
    /// The command that shows the variants next to the source (once they are written).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<String>,
}

/// A sampling's outcome.
pub struct SampleOutcome {
    pub report: SampleReport,
    /// The varied motion's name (`walk`, `walk+jog@0.5`).
    pub name: String,
    pub out_dir: PathBuf,
    /// The model's length unit, as messages give it.
    pub unit: String,
}

/// A file-name-safe form of a name (letters, digits, `.`, `_`, `-`; anything else `_`).
fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || "._-".contains(c) { c } else { '_' }).collect()
}

/// The subject path `vary train` recorded in the model folder's `report.json`, if any.
fn trained_subject_path(model: &Path) -> Option<PathBuf> {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(model.join("report.json")).ok()?).ok()?;
    v["subject_path"].as_str().map(PathBuf::from)
}

/// A shell word for `p` (quoted when it holds anything but plain path characters).
fn shell_word(p: &str) -> String {
    if !p.is_empty() && p.chars().all(|c| c.is_ascii_alphanumeric() || "/._-~+@:=,".contains(c)) {
        p.to_string()
    } else {
        format!("'{}'", p.replace('\'', "'\\''"))
    }
}

/// Largest leapfrog step count of one part's HMC chain: (warm-up + variants x thinning) x the
/// longest path. The defaults take 900 (about a second a part); thesis 6.6 samples a handful of
/// variants with short chains, and 2,000,000 (the former defaults' 3,750 times 500) covers every
/// use and bounds the time.
pub const MAX_LEAPFROG_STEPS: f64 = 2_000_000.0;

/// Checks a sampling's numbers as `surfcap vary sample` does before any work: the variant count
/// (1 to 1000), the HMC settings' ranges, and the chain's length against
/// [`MAX_LEAPFROG_STEPS`].
pub fn check_sampling(count: usize, o: &SamplingOptions) -> Result<()> {
    let ranges: [(&str, usize, usize, usize); 6] = [
        ("--count", count, 1, 1000),
        ("--smoothing", o.smoothing, 0, 1000),
        ("--deviation-smoothing", o.deviation_smoothing, 0, 1000),
        ("--warmup", o.warmup, 1, 100_000),
        ("--thin", o.thin, 1, 10_000),
        ("--max-leapfrog", o.max_leapfrog, 1, 10_000),
    ];
    for (option, v, lo, hi) in ranges {
        if !(lo..=hi).contains(&v) {
            crate::error::refuse!("{option} {v}: expected a whole number from {lo} to {hi}");
        }
    }
    let steps = (o.warmup as f64 + count as f64 * o.thin as f64) * o.max_leapfrog as f64;
    if steps > MAX_LEAPFROG_STEPS {
        crate::error::refuse!(
            "--warmup {} + --count {} x --thin {} HMC iterations of up to --max-leapfrog {} steps are {steps:.3e} leapfrog steps per body part, above the {MAX_LEAPFROG_STEPS:.0} allowed; lower --warmup, --count, --thin or --max-leapfrog",
            o.warmup,
            count,
            o.thin,
            o.max_leapfrog
        );
    }
    Ok(())
}

/// Variants sampled in memory ([`sample_variants_of`]), to be returned or written
/// ([`write_variants`]).
pub struct SampledVariants {
    /// One subject per variant: the model's topology, one sequence `<name>~<k>`.
    pub variants: Vec<Subject>,
    /// The report (no files and no view command until the variants are written).
    pub report: SampleReport,
    /// The varied motion's name (`walk`, `walk+jog@0.5`).
    pub name: String,
    /// The model's length unit, as messages give it.
    pub unit: String,
    /// The file names' stem, and the sequences the variants vary (for the view command).
    stem: String,
    sources: Vec<String>,
}

/// The file stem, name and source sequences of what `varied` asks, checked against the model
/// (a note when a blend's pair was not learnt as one).
fn check_varied(
    model: &VariationModel,
    varied: &Varied,
    progress: &dyn Progress,
) -> Result<(String, String, Vec<String>)> {
    Ok(match varied {
        Varied::Sequence(name) => {
            model.sequence_index(name)?;
            (file_safe(name), name.clone(), vec![name.clone()])
        }
        Varied::Blend { a, b, w } => {
            let ladder = blend_ladder(model, a, b)?;
            bounding_rungs(&ladder, *w)?;
            if ladder.len() == 2 && *w > 0.0 && *w < 1.0 {
                progress.note(&format!(
                    "the model learnt no blend of {a} and {b}: variants of the two are interpolated directly (train with --blend {a}:{b} for the thesis's learnt blends)"
                ));
            }
            (file_safe(&format!("{a}-{b}-{w}")), format!("{a}+{b}@{w}"), vec![a.clone(), b.clone()])
        }
    })
}

/// Samples `count` variants of `varied` from `model` with `seed` (same seed, same variants,
/// whatever the thread count), each measured against the learnt motion it varies. `model_path`
/// is the model's folder when it has one (the report's `model`).
pub fn sample_variants_of(
    model: &VariationModel,
    model_path: Option<&Path>,
    varied: &Varied,
    count: usize,
    seed: u64,
    opts: &SamplingOptions,
    progress: &dyn Progress,
) -> Result<SampledVariants> {
    check_sampling(count, opts)?;
    let (stem, name, sources) = check_varied(model, varied, progress)?;
    sample_checked(model, model_path, varied, count, seed, opts, (stem, name, sources), progress)
}

#[allow(clippy::too_many_arguments)]
fn sample_checked(
    model: &VariationModel,
    model_path: Option<&Path>,
    varied: &Varied,
    count: usize,
    seed: u64,
    opts: &SamplingOptions,
    (stem, name, sources): (String, String, Vec<String>),
    progress: &dyn Progress,
) -> Result<SampledVariants> {
    progress.start(
        &format!(
            "sampling {} of {} (seed {}, warm-up {}, thin {}) ...",
            count_of(count, "variant"),
            name,
            seed,
            opts.warmup,
            opts.thin
        ),
        1,
    );
    let t_sample = Instant::now();
    let (variants, chains, blend, learnt): (_, _, _, LearntMotion) = match varied {
        Varied::Sequence(name) => {
            let (v, c) = sample_variants(model, name, count, seed, opts)?;
            (v, c, None, learnt_sequence(model, name)?)
        }
        Varied::Blend { a, b, w } => {
            let (v, s) = sample_blend_variants(model, a, b, *w, count, seed, opts)?;
            let chains = s.chains.clone();
            (v, chains, Some(s), learnt_blend(model, a, b, *w)?)
        }
    };
    progress.advance(1);
    progress.finish();
    let sample_seconds = t_sample.elapsed().as_secs_f64();

    let nv = model.topology.n_vertices();
    let learnt_end = learnt.world.last().map(|p| centroid(p)).unwrap_or_default();
    let mut subjects = Vec::with_capacity(variants.len());
    let mut per_variant = Vec::with_capacity(variants.len());
    for (k, v) in variants.iter().enumerate() {
        let variant_name = format!("{name}~{}", k + 1);
        let frames = v.world.len();
        let positions: Vec<f32> = v.world.iter().flatten().copied().collect();
        let seq = Sequence::new(variant_name.clone(), nv, positions)?
            .with_labels(vec![FrameLabel::Synthetic; frames])?
            .with_tags(vec!["variation".into()]);
        subjects.push(Subject::new(
            variant_name.clone(),
            model.topology.clone(),
            vec![seq],
            model.fps,
            model.up_axis,
            model.units.clone(),
        )?);
        let end = v.world.last().map(|p| centroid(p)).unwrap_or_default();
        per_variant.push(VariantReport {
            file: None,
            sequence: variant_name,
            frames,
            body_frame_distance: mean_vertex_distance(&v.aligned, &learnt.aligned),
            end_distance: distance3(end, learnt_end),
            path_length: centroid_path_length(&v.world),
            cleanup: v.cleanup,
        });
    }
    let report = SampleReport {
        model: model_path.map(Path::to_path_buf),
        subject: model.subject.clone(),
        units: model.units.symbol().to_string(),
        sequence: match varied {
            Varied::Sequence(name) => Some(name.clone()),
            Varied::Blend { .. } => None,
        },
        blend: blend.as_ref().map(|b| BlendReport {
            a: b.a.clone(),
            b: b.b.clone(),
            w: b.w,
            lower: b.lower,
            upper: b.upper,
            pairing: b.pairing.clone(),
            lower_sequence: model.sequences[b.lower.sequence].name.clone(),
            upper_sequence: model.sequences[b.upper.sequence].name.clone(),
        }),
        seed,
        count,
        options: OptionsReport {
            start: match opts.start {
                ChainStart::Learnt => "learnt",
                ChainStart::MeanPrediction => "mean",
            },
            path: match opts.path {
                VariantPath::Source => "source",
                VariantPath::Sampled => "sampled",
                VariantPath::Contacts => "contacts",
            },
            smoothing: opts.smoothing,
            deviation_smoothing: opts.deviation_smoothing,
            warmup: opts.warmup,
            thin: opts.thin,
            max_leapfrog: opts.max_leapfrog,
            foot_skate_cleanup: opts.foot_skate_cleanup,
            move_root: opts.foot_skate_cleanup && opts.move_root,
            learnt_stretch: opts.learnt_stretch,
            carry_pins: opts.carry_pins,
        },
        chains,
        learnt: LearntReport {
            frames: learnt.world.len(),
            path_length: centroid_path_length(&learnt.world),
            what: if blend.is_some() {
                "the latent interpolation of the two learnt trajectories around the weight, reconstructed"
            } else {
                "the learnt trajectory, reconstructed"
            },
        },
        variants: per_variant,
        load_seconds: 0.0,
        sample_seconds,
        write_seconds: 0.0,
        total_seconds: sample_seconds,
        view: None,
    };
    let unit = crate::words::unit_name(&model.units).to_string();
    Ok(SampledVariants { variants: subjects, report, name, unit, stem, sources })
}

/// Writes sampled variants into the folder `output` as `surfcap vary sample` does
/// (`<stem>-variant-<k>.glb` per variant and `report.json`, whose files and view command are
/// filled in here). The folder is planned (`surfcap_mesh::output_set`) unless the caller planned
/// it, filled in its temporary and put in place whole, so a failed run leaves the place as it
/// was. `inputs` are the paths the folder must not replace; `force` lets it replace a folder
/// surfcap did not write. Returns the resolved folder.
pub fn write_variants(
    s: &mut SampledVariants,
    output: &Path,
    inputs: &[&Path],
    force: bool,
    progress: &dyn Progress,
) -> Result<PathBuf> {
    let own = if surfcap_mesh::output_set::is_planned(output) {
        None
    } else {
        let mut set = surfcap_mesh::output_set::OutputSet::new(inputs);
        set.dir(output, SAMPLES_KIND, force)?;
        Some(set)
    };
    let out_dir = write_into(s, output, force, None, progress)?;
    if let Some(set) = own {
        set.commit()?;
    }
    Ok(out_dir)
}

/// [`write_variants`] into a folder already planned; the report's `total_seconds` counts from
/// `started` (else it is the load, sampling and writing times' sum).
fn write_into(
    s: &mut SampledVariants,
    output: &Path,
    force: bool,
    started: Option<Instant>,
    progress: &dyn Progress,
) -> Result<PathBuf> {
    let out_dir = surfcap_mesh::output_path::claim_dir(output, SAMPLES_KIND, force)?;
    let t_write = Instant::now();
    let mut files = Vec::new();
    let export_options = ExportOptions { force, ..Default::default() };
    for (k, (subject, v)) in s.variants.iter().zip(&mut s.report.variants).enumerate() {
        let file = out_dir.join(format!("{}-variant-{}.glb", s.stem, k + 1));
        files.extend(export(subject, ExportFormat::Glb, &file, export_options, progress)?);
        v.file = Some(file);
    }
    let r = &mut s.report;
    r.write_seconds = t_write.elapsed().as_secs_f64();
    let subject_path = r
        .model
        .as_deref()
        .and_then(trained_subject_path)
        .map_or_else(|| "SUBJECT".to_string(), |p| p.display().to_string());
    let mut view = vec!["surfcap".to_string(), "view".into(), shell_word(&subject_path)];
    view.extend(
        files
            .iter()
            .filter(|f| f.extension().is_some_and(|x| x == "glb"))
            .map(|f| shell_word(&f.display().to_string())),
    );
    let mut names = s.sources.clone();
    names.extend(r.variants.iter().map(|v| v.sequence.clone()));
    view.push("--sequences".into());
    view.push(shell_word(&names.join(",")));
    r.view = Some(view.join(" "));
    r.total_seconds =
        started.map_or(r.load_seconds + r.sample_seconds + r.write_seconds, |t| t.elapsed().as_secs_f64());
    write_report(&out_dir.join("report.json"), &*r)?;
    Ok(out_dir)
}

/// Samples the request's variants and writes them with their report; the output folder is
/// planned (`surfcap_mesh::output_set`) and the request checked against the model before
/// anything is sampled. The folder is filled in its temporary and put in place whole at the end
/// (by the caller's output set when it planned the folder, else here), so a failed run leaves
/// the place as it was.
pub fn sample_variants_to_folder(r: &SampleRequest, progress: &dyn Progress) -> Result<SampleOutcome> {
    check_sampling(r.count, &r.options)?;
    let own = if surfcap_mesh::output_set::is_planned(&r.output) {
        None
    } else {
        let mut set = surfcap_mesh::output_set::OutputSet::new(&[&r.model]);
        set.dir(&r.output, SAMPLES_KIND, r.force)?;
        Some(set)
    };
    let t0 = Instant::now();
    let model = VariationModel::load(&r.model)?;
    let load_seconds = t0.elapsed().as_secs_f64();
    let checked = check_varied(&model, &r.varied, progress)?;
    let mut sampled =
        sample_checked(&model, Some(&r.model), &r.varied, r.count, r.seed, &r.options, checked, progress)?;
    sampled.report.load_seconds = load_seconds;
    let out_dir = write_into(&mut sampled, &r.output, r.force, Some(t0), progress)?;
    if let Some(set) = own {
        set.commit()?;
    }
    let SampledVariants { report, name, unit, .. } = sampled;
    Ok(SampleOutcome { report, name, out_dir, unit })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sampling_outside_the_commands_ranges_is_refused_naming_the_option() {
        let o = SamplingOptions::default();
        assert!(check_sampling(5, &o).is_ok());
        let m = check_sampling(0, &o).unwrap_err().to_string();
        assert_eq!(m, "--count 0: expected a whole number from 1 to 1000");
        let m = check_sampling(5, &SamplingOptions { thin: 0, ..o }).unwrap_err().to_string();
        assert_eq!(m, "--thin 0: expected a whole number from 1 to 10000");
        let m = check_sampling(1000, &SamplingOptions { thin: 100, ..o }).unwrap_err().to_string();
        assert!(m.contains("leapfrog steps per body part, above the 2000000 allowed"), "{m}");
        // Moving the root is part of the clean-up: without it, the default options stay valid.
        assert!(check_sampling(5, &SamplingOptions { foot_skate_cleanup: false, ..o }).is_ok());
    }
}

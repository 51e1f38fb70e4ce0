//! `surfcap eval vary`: motion variation synthesis evaluated (thesis chapter 6;
//! `surfcap_eval::variation_eval` computes it). Writes `vary.json`, per case the
//! reconstruction errors of Fig. 6.4, the interpolation curves of Fig. 6.7 and each part's
//! latent trajectories with the reference sequence's variants (Fig. 6.5), prints the tables,
//! and fails (exit 1, after writing everything) when a variation criterion is missed.

use std::path::{Path, PathBuf};

use surfcap_eval::variation_eval::{
    CaseEval, VariationCase, VariationEvalOptions, cmu_case, kaykit_case, variation_eval,
};
use surfcap_plot::{LineChart, Series, write_line_chart};

const PALETTE: [(u8, u8, u8); 6] =
    [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0), (120, 60, 170), (90, 90, 90)];

fn series(name: &str, points: Vec<(f64, f64)>, color: (u8, u8, u8), dashed: bool, markers: bool) -> Series {
    Series { name: name.into(), points, color, dashed, markers }
}

/// Fig. 6.4 (x: part, the last the stitched mesh), Fig. 6.7b, and the latent trajectories.
fn plots(dir: &Path, c: &CaseEval) -> anyhow::Result<Vec<PathBuf>> {
    let r = &c.reconstruction;
    let rows: Vec<_> = r.parts.iter().chain(std::iter::once(&r.overall)).collect();
    let pts = |f: &dyn Fn(&surfcap_eval::variation_eval::ReconstructionErrors) -> f64| -> Vec<(f64, f64)> {
        rows.iter().enumerate().map(|(k, e)| (k as f64, f(e))).collect()
    };
    let labels: Vec<String> = rows.iter().enumerate().map(|(k, e)| format!("{k} {}", e.part)).collect();
    let fig64 = LineChart {
        title: format!(
            "{}: mean per-vertex reconstruction error, GPDM vs PCA (d = {}), Fig. 6.4",
            c.name, r.latent_dim
        ),
        x_label: format!("part: {}", labels.join(", ")),
        y_label: format!("mean vertex error ({})", c.units),
        series: vec![
            series("GPDM, training frames", pts(&|e| e.gpdm_training), PALETTE[0], false, true),
            series("PCA, training frames", pts(&|e| e.pca_training), PALETTE[1], false, true),
            series("GPDM, held-out frames", pts(&|e| e.gpdm_held_out), PALETTE[0], true, true),
            series("PCA, held-out frames", pts(&|e| e.pca_held_out), PALETTE[1], true, true),
        ],
    };
    let mut written = write_line_chart(&dir.join(format!("{}_fig6_4", c.name)), &fig64)?;
    let b = &c.blend;
    let curve = |v: &[f64]| v.iter().enumerate().map(|(i, &d)| (i as f64, d)).collect();
    let fig67 = LineChart {
        title: format!(
            "{}: latent interpolation of {} and {} at w = {} vs the mesh blend, Fig. 6.7",
            c.name, b.a, b.b, b.w
        ),
        x_label: "frame (reference timing)".into(),
        y_label: format!("mean vertex distance ({})", c.units),
        series: vec![
            series(&format!("direct ({} - {})", b.a, b.b), curve(&b.direct), PALETTE[1], false, false),
            series(
                &format!("guided ({} - {})", b.guided_between[0].0, b.guided_between[1].0),
                curve(&b.guided),
                PALETTE[2],
                false,
                false,
            ),
        ],
    };
    written.extend(write_line_chart(&dir.join(format!("{}_fig6_7", c.name)), &fig67)?);
    for p in &c.latents {
        let two = |m: &surfcap_learn::Mat<f64>| -> Vec<(f64, f64)> {
            (0..m.nrows()).map(|i| (m[(i, 0)], if m.ncols() > 1 { m[(i, 1)] } else { i as f64 })).collect()
        };
        let mut s: Vec<Series> = p
            .learnt
            .iter()
            .enumerate()
            .map(|(k, (n, x))| series(n, two(x), PALETTE[k % PALETTE.len()], false, false))
            .collect();
        for (k, v) in p.variants.iter().enumerate() {
            let name = if k == 0 { format!("variants of {}", p.learnt[0].0) } else { String::new() };
            s.push(series(&name, two(v), (150, 150, 150), true, false));
        }
        let chart = LineChart {
            title: format!("{}: {} latent trajectories (dimensions 1 and 2) and variants, Fig. 6.5", c.name, p.part),
            x_label: "x1".into(),
            y_label: "x2".into(),
            series: s,
        };
        written.extend(write_line_chart(&dir.join(format!("{}_latent_{}", c.name, p.part)), &chart)?);
    }
    Ok(written)
}

fn print_case(c: &CaseEval, tolerance: f64) {
    let u = &c.units;
    println!(
        "== {} ({}: {} vertices, height {:.3} {u}; {} learnt sequences of {} frames; parts {}); trained in {:.1} s",
        c.name,
        c.subject,
        c.vertices,
        c.height,
        c.sequences.len(),
        c.reference_frames,
        c.parts.join(", "),
        c.train_seconds
    );
    let r = &c.reconstruction;
    println!(
        "Fig. 6.4: mean per-vertex error ({u}), d = {}; training {} frames; held out {} frames (model of {} frames, latent = {})",
        r.latent_dim, r.training_frames, r.held_out_frames, r.held_out_training_frames, r.held_out_latent
    );
    println!("{:<20} {:>10} {:>10} {:>10} {:>10}", "part", "GPDM train", "PCA train", "GPDM held", "PCA held");
    for e in r.parts.iter().chain(std::iter::once(&r.overall)) {
        println!(
            "{:<20} {:>10.5} {:>10.5} {:>10.5} {:>10.5}",
            e.part, e.gpdm_training, e.pca_training, e.gpdm_held_out, e.pca_held_out
        );
    }
    let b = &c.blend;
    println!(
        "Fig. 6.7: {} - {} at w = {} against the mesh blend: direct {:.5} {u}, guided by {}@{} - {}@{}: {:.5} {u} ({})",
        b.a,
        b.b,
        b.w,
        b.direct_mean,
        b.guided_between[0].0,
        b.guided_between[0].1,
        b.guided_between[1].0,
        b.guided_between[1].1,
        b.guided_mean,
        if b.guided_mean < b.direct_mean { "guided closer, as in Fig. 6.7" } else { "direct closer" }
    );
    println!(
        "variation ({} variants each; distances mean per vertex in {u}; sliding in {u}/s; edge distortion mean |l/l0 - 1|; tolerance +{:.0}%)",
        c.variation.first().map_or(0, |v| v.variants),
        100.0 * tolerance
    );
    println!(
        "{:<18} {:>7} {:>7} {:>7} {:>7} {:>7} {:>16} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}  verdict",
        "sequence",
        "floorB",
        "minB",
        "floorW",
        "minW",
        "ownL",
        "nearest other",
        "edgeIn",
        "edgeMax",
        "edgeWMx",
        "slideIn",
        "slideB4",
        "slideMx",
        "minPair"
    );
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    for v in &c.variation {
        let near = v.nearest_other.iter().min_by(|a, b| a.1.total_cmp(&b.1)).expect("a variant");
        let p = &v.passes;
        let failed: Vec<&str> = [
            (p.differs, "(i) differs"),
            (p.closest_to_source, "(ii) closest to source"),
            (p.edge_distortion, "(iii) edge distortion"),
            (p.foot_sliding, "(iv) foot sliding"),
            (p.distinct, "(v) distinct"),
        ]
        .iter()
        .filter(|x| !x.0)
        .map(|x| x.1)
        .collect();
        let short: String = near.0.chars().take(9).collect();
        println!(
            "{:<18} {:>7.4} {:>7.4} {:>7.4} {:>7.4} {:>7.4} {:>9} {:>6.4} {:>7.4} {:>7.4} {:>7.4} {:>7.4} {:>7} {:>7.4} {:>7.4}  {}",
            v.sequence,
            v.floor_body,
            min(&v.distance_body),
            v.floor_world,
            min(&v.distance_world),
            max(&v.distance_learnt),
            short,
            near.1,
            v.edge_distortion_input,
            max(&v.edge_distortion),
            max(&v.edge_distortion_world),
            v.sliding_input.speed,
            if v.sliding_before_cleanup.is_empty() {
                "-".to_string()
            } else {
                format!("{:.4}", max(&v.sliding_before_cleanup.iter().map(|s| s.speed).collect::<Vec<_>>()))
            },
            max(&v.sliding.iter().map(|s| s.speed).collect::<Vec<_>>()),
            v.min_pair_distance,
            if failed.is_empty() { "pass".to_string() } else { format!("MISSED: {}", failed.join(", ")) }
        );
    }
}

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("CMU clips and the KayKit knight"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Only one case: cmu (the mannequin driven by CMU clips) or kaykit (the knight).
    #[arg(long)]
    pub only: Option<String>,
    /// CMU clips of the cmu case (in cmu_bvh; the first is the reference, the first two
    /// are blended).
    #[arg(long, value_delimiter = ',', default_value = "16_15,16_36,16_17,16_19,16_07")]
    pub cmu_clips: Vec<String>,
    /// KayKit knight clips of the kaykit case (the first is the reference, the first two
    /// are blended).
    #[arg(long, value_delimiter = ',', default_value = "Walking_A,Running_A,Walking_B,Walking_C,Running_B")]
    pub kaykit_clips: Vec<String>,
    /// Target vertex count of the mannequin (1000 to 20000).
    #[arg(long, default_value_t = 1500, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Variants per captured sequence.
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub variants: usize,
    /// Seed of the variants.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// L-BFGS iterations at most of every GPDM, 1 to 10000 (default 400; as `vary train
    /// --iterations`).
    #[arg(long, value_parser = |s: &str| crate::options::whole_in(s, 1, 10_000))]
    pub iterations: Option<usize>,
    /// Where the variants go in the world, the world criteria judged there: source (the
    /// source's path, `vary sample`'s default) or sampled (the torso GP's displacements,
    /// thesis 6.6.2).
    #[arg(long, default_value = "source")]
    pub path: crate::options::PathArg,
    /// Radius of the moving average over sampled latent trajectories (`vary sample
    /// --smoothing`).
    #[arg(long, default_value_t = 2)]
    pub smoothing: usize,
    /// Radius of the moving average over each variant's deviation from the learnt motion
    /// (`vary sample --deviation-smoothing`).
    #[arg(long, default_value_t = 4)]
    pub deviation_smoothing: usize,
    /// Judge the variants as sampled, without the foot-skate clean-up (`vary sample
    /// --no-foot-skate-cleanup`).
    #[arg(long)]
    pub no_foot_skate_cleanup: bool,
    /// Keep the hips where they are in the foot-skate clean-up, the legs alone reaching the
    /// pins (by default the whole body moves along the ground with the planted feet, Kovar et
    /// al. 2002's root adjustment, so a planted foot is reached without stretching its leg).
    #[arg(long, conflicts_with = "no_foot_skate_cleanup")]
    pub hold_hips: bool,
    /// Use the stitched reconstruction-GP means as they are: by default every triangle of a
    /// sampled pose keeps its rotation and takes the learnt motion's stretch at the same frame
    /// (one Poisson solve per frame), as linear blends of training poses shrink the surface.
    #[arg(long)]
    pub no_learnt_stretch: bool,
    /// In the foot-skate clean-up, pin each step where the foot comes down and let the body
    /// go on with its planted feet (the legs keep their lengths; the body then leaves the
    /// source's path, by 2.1-2.4 m over the 4.5 m CMU walks of `surfcap eval vary`). By default
    /// each step is pinned where the foot is mid-contact, on the source's path.
    #[arg(long, conflicts_with_all = ["no_foot_skate_cleanup", "hold_hips"])]
    pub carry_pins: bool,
    /// Folder for vary.json and the plots.
    #[arg(short, long, default_value = "vary-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.data], "eval-vary")?;
    let (cmu, kaykit) = match a.only.as_deref() {
        None => (true, true),
        Some("cmu") => (true, false),
        Some("kaykit") => (false, true),
        Some(other) => anyhow::bail!("--only {other}: expected cmu or kaykit"),
    };
    let mut cases = Vec::new();
    if cmu {
        cases.push(cmu_case(&a.data, a.vertices, &a.cmu_clips)?);
    }
    if kaykit {
        cases.push(kaykit_case(&a.data, &a.kaykit_clips)?);
    }
    let mut opts =
        VariationEvalOptions { variants: a.variants, seed: a.seed, iterations: a.iterations, ..Default::default() };
    opts.sampling.path = a.path.0;
    opts.sampling.smoothing = a.smoothing;
    opts.sampling.deviation_smoothing = a.deviation_smoothing;
    opts.sampling.foot_skate_cleanup = !a.no_foot_skate_cleanup;
    opts.sampling.move_root = !a.hold_hips && !a.no_foot_skate_cleanup;
    opts.sampling.learnt_stretch = !a.no_learnt_stretch;
    opts.sampling.carry_pins = a.carry_pins;
    let missed = evaluate(ctx, cases, &opts, &a.output)?;
    // The report is the result even when a criterion is missed: it is committed first.
    ctx.commit(outs)?;
    if let Some(missed) = missed {
        anyhow::bail!(missed);
    }
    Ok(())
}

fn evaluate(
    ctx: &crate::Ctx,
    cases: Vec<VariationCase>,
    opts: &VariationEvalOptions,
    output: &Path,
) -> anyhow::Result<Option<String>> {
    let r = variation_eval(&cases, opts)?;
    let place = surfcap_mesh::output_set::write_place(output);
    std::fs::create_dir_all(&place).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", output.display()))?;
    let mut written = Vec::new();
    for c in &r.cases {
        written.extend(plots(output, c)?);
    }
    let (report, path) = super::folder::save_report(output, "vary.json", &r, "written", &written)?;
    ctx.result(&report, || {
        for c in &r.cases {
            print_case(c, r.criteria.tolerance);
        }
        println!(
            "columns: floorB/floorW the floors of (i) (max({} x the learnt reconstruction error, {} x height)), minB/minW the \
             smallest variant-source distance (body frame, world), ownL the largest distance to the source's learnt \
             reconstruction, nearest other (ii), edgeIn/edgeMax/edgeWMx the source's and the worst variant's edge distortion \
             (iii; body frame, and world frames as delivered), slideIn/slideB4/slideMx foot sliding (iv): the source's, the \
             worst variant's before the foot-skate clean-up and after (on the capture's ground travel for in-place captures), minPair the closest two variants (v, floor {} x height)",
            r.criteria.floor_factor, r.criteria.min_floor, r.criteria.min_floor
        );
        println!("wrote {} and {} plots in {:.1} s", path.display(), written.len(), r.seconds);
    });
    Ok((r.missed > 0).then(|| format!("{} variation criteria MISSED (see {})", r.missed, path.display())))
}

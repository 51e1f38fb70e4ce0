//! `surfcap eval transfer`: motion transfer against ground truth (thesis 5.7, Fig. 5.8-5.10;
//! `surfcap_eval::transfer_eval` computes it). Writes `transfer.json`, one learning-curve plot
//! per case and variant, and prints the cross-validation errors per method and size.

use std::path::{Path, PathBuf};

use surfcap_builtin::mannequin::BodyShape;
use surfcap_eval::transfer_eval::{
    CaseEval, CaseParts, TransferCase, TransferEvalOptions, catlion_subjects, kaykit_case, leave_one_out_eval,
    mannequin_case, transfer_case_eval,
};
use surfcap_mesh::Subject;
use surfcap_plot::{LineChart, Series, write_line_chart};

const PALETTE: [(u8, u8, u8); 6] =
    [(31, 95, 191), (208, 48, 48), (46, 158, 68), (224, 138, 0), (120, 60, 170), (90, 90, 90)];

/// Learning curves of one variant: solid cross-validation, dashed training error.
fn curve_plot(dir: &Path, c: &CaseEval, variants: &[&str], stem: &str, title: &str) -> anyhow::Result<Vec<PathBuf>> {
    let mut series = Vec::new();
    for (k, curve) in c.curves.iter().filter(|x| variants.contains(&x.variant.as_str())).enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let label =
            if variants.len() > 1 { format!("{} ({})", curve.method, curve.variant) } else { curve.method.clone() };
        series.push(Series {
            name: format!("{label}, cross-validation"),
            points: curve.points.iter().map(|p| (p.size as f64, p.cv_percent)).collect(),
            color,
            dashed: false,
            markers: true,
        });
        series.push(Series {
            name: format!("{label}, training"),
            points: curve.points.iter().map(|p| (p.size as f64, p.train_percent)).collect(),
            color,
            dashed: true,
            markers: true,
        });
    }
    if series.is_empty() {
        return Ok(Vec::new());
    }
    let chart = LineChart {
        title: format!("{}: {title}", c.name),
        x_label: "training pairs".into(),
        y_label: "RMS per-vertex error (% of target height)".into(),
        series,
    };
    let slug: String = c.name.chars().map(|ch| if ch.is_ascii_alphanumeric() { ch } else { '_' }).collect();
    Ok(write_line_chart(&dir.join(format!("{slug}_{stem}")), &chart)?)
}

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("KayKit characters and CMU clips"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Cases: barbarian, mage, rogue (the KayKit knight to each), mannequins (an average
    /// mannequin of 3,000 vertices to a heavy one of 5,000) and catlion (Sumner's 9 cat and
    /// lion poses, leave-one-out).
    #[arg(long, value_delimiter = ',', default_value = "barbarian,mage,rogue,mannequins,catlion")]
    pub cases: Vec<String>,
    /// Training-set sizes of the learning curves (pairs).
    #[arg(long, value_delimiter = ',', default_value = "10,25,50,100,200,350", value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub sizes: Vec<usize>,
    /// PCA components per part.
    #[arg(long, default_value_t = 20, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub components: usize,
    /// Seed of the 70/30 split and the fits' restarts.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluate on the whole body only (one part), instead of five proposed parts (plus the
    /// whole-body comparison curve).
    #[arg(long)]
    pub whole_body: bool,
    /// Directions: forward (the knight to each character, the average mannequin to the heavy
    /// one), backward (the other way round) or both, as the thesis evaluates.
    #[arg(long, default_value = "both", value_parser = ["forward", "backward", "both"])]
    pub direction: String,
    /// Overlap of the proposed parts, in edge rings.
    #[arg(long, default_value_t = 2, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub overlap_rings: usize,
    #[arg(short, long, default_value = "transfer-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let outs = super::folder::claim(ctx, &a.output, &[&a.data], "eval-transfer")?;
    let Args { data, cases, sizes, components, seed, whole_body, direction, overlap_rings, output } = a;
    let parts = if whole_body { CaseParts::WholeBody } else { CaseParts::Proposed { overlap_rings } };
    let opts = TransferEvalOptions { sizes, seed, components, ..TransferEvalOptions::default() };
    let mut built = Vec::new();
    let mut catlion = None;
    for c in &cases {
        if c == "catlion" {
            catlion = Some(catlion_subjects(&data)?);
            continue;
        }
        built.push(match c.as_str() {
            "barbarian" | "mage" | "rogue" => kaykit_case(&data, c, parts)?,
            "mannequins" => mannequin_case(
                &data,
                ("mannequin-average-3k", &BodyShape::average(), 3000),
                ("mannequin-heavy-5k", &BodyShape::heavy(), 5000),
                parts,
            )?,
            other => anyhow::bail!("--cases {other}: expected barbarian, mage, rogue, mannequins or catlion"),
        });
    }
    built = built
        .into_iter()
        .flat_map(|c| match direction.as_str() {
            "forward" => vec![c],
            "backward" => vec![c.reversed()],
            _ => {
                let r = c.reversed();
                vec![c, r]
            }
        })
        .collect();
    evaluate(ctx, built, catlion, &opts, &output)?;
    ctx.commit(outs)
}

fn evaluate(
    ctx: &crate::Ctx,
    cases: Vec<TransferCase>,
    catlion: Option<(Subject, Subject)>,
    opts: &TransferEvalOptions,
    output: &Path,
) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let mut results = Vec::new();
    let mut plots = Vec::new();
    for case in &cases {
        ctx.say(&format!(
            "{}: {} -> {} vertices, {} parts ...",
            case.name,
            case.source.topology().n_vertices(),
            case.target.topology().n_vertices(),
            case.target_parts.len()
        ));
        let r = transfer_case_eval(case, opts)?;
        plots.extend(curve_plot(output, &r, &["random"], "learning_curves", "learning curves (Fig. 5.8)")?);
        plots.extend(curve_plot(
            output,
            &r,
            &["key-seeded"],
            "key_seeded",
            "training subsets seeded with key poses (Fig. 5.9)",
        )?);
        if r.curves.iter().any(|c| c.variant == "whole-body") {
            let parts: Vec<&str> = vec!["whole-body"];
            let mut both = r.clone();
            both.curves
                .retain(|c| c.method == "GP-NN" && (c.variant == "random" || parts.contains(&c.variant.as_str())));
            for c in &mut both.curves {
                if c.variant == "random" {
                    c.variant = "parts".into();
                }
            }
            plots.extend(curve_plot(
                output,
                &both,
                &["parts", "whole-body"],
                "parts",
                "GP-NN with and without body parts (Fig. 5.10)",
            )?);
        }
        results.push(r);
    }
    let loo = match &catlion {
        Some((cat, lion)) => {
            ctx.say("cat -> lion: leave-one-out over 9 poses ...");
            Some(leave_one_out_eval("cat -> lion", cat, lion, opts.seed)?)
        }
        None => None,
    };
    let report = serde_json::json!({ "cases": results, "leave_one_out": loo, "seconds": t0.elapsed().as_secs_f64() });
    let (report, path) = super::folder::save_report(output, "transfer.json", &report, "plots", &plots)?;
    ctx.result(&report, || {
        for r in &results {
            println!(
                "{}: {} pool pairs ({} held out), target height {:.3} {}; RMS per-vertex error, % of height (training / cross-validation)",
                r.name, r.pool_pairs, r.test_pairs, r.target_height, r.units
            );
            for c in &r.curves {
                let cells: Vec<String> = c
                    .points
                    .iter()
                    .map(|p| format!("n={} {:.2}/{:.2}", p.size, p.train_percent, p.cv_percent))
                    .collect();
                println!("  {:<8} {:<11} {}", c.method, c.variant, cells.join("  "));
            }
            println!(
                "  densification: {} key pairs -> {} pairs, frame error {:.2} +- {:.2} (truth: equal frames)",
                r.key_pairs, r.densified_pairs, r.densify_frame_error.mean, r.densify_frame_error.std
            );
            println!("  reconstruction of the motions absent from training (GP-NN, every true pair), against the truth:");
            for x in &r.reconstruction {
                let b = match (x.boundary_max, x.boundary_mean) {
                    (Some(m), Some(a)) => format!("boundary edges max {:.1}% mean {:.2}%", 100.0 * m, 100.0 * a),
                    _ => "no overlaps".to_string(),
                };
                println!(
                    "    {:<17} {:>6.2}% of height; edge-length change: {b}, inside parts max {:.1}% mean {:.2}%",
                    x.reconstruction,
                    x.rms_percent,
                    100.0 * x.inside_max,
                    100.0 * x.inside_mean
                );
            }
            println!("  motions absent from training, side by side (% of height; GP-NN / Baran / nearest pose):");
            let mut keys: Vec<(&str, &str)> = Vec::new();
            for u in &r.unseen {
                if !keys.contains(&(u.training.as_str(), u.motion.as_str())) {
                    keys.push((u.training.as_str(), u.motion.as_str()));
                }
            }
            for (training, motion) in keys {
                let of = |m: &str| {
                    r.unseen
                        .iter()
                        .find(|u| u.method == m && u.training == training && u.motion == motion)
                        .map_or("-".to_string(), |u| format!("{:.2}", u.rms_percent))
                };
                println!(
                    "    {:<28} {:<15} {:>6} / {:>6} / {:>6}",
                    motion,
                    training,
                    of("GP-NN"),
                    of("Baran"),
                    of("nearest pose")
                );
            }
            println!("  motions absent from training, % of height, by training set:");
            for u in &r.unseen {
                println!(
                    "    {:<16} {:<15} ({:>3} pairs) {:<28} {:>4} frames {:>6.2}%",
                    u.method, u.training, u.training_pairs, u.motion, u.frames, u.rms_percent
                );
            }
        }
        if let Some(l) = &loo {
            println!(
                "{} ({} -> {} vertices), leave-one-out, RMS per-vertex error % of height; nearest training pose {:.2}%",
                l.name, l.source_vertices, l.target_vertices, l.nearest_training_percent
            );
            for (m, e) in &l.mean_percent {
                println!("  {m:<8} mean {e:>6.2}%");
            }
        }
        super::folder::print_wrote(&path, &plots);
    });
    Ok(())
}

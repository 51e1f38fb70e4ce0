//! `surfcap eval appearance`: the evaluation of eigen appearance maps (thesis 4.5-4.6, Fig.
//! 4.5-4.6 and 4.9-4.12) on a generated sequence with ground truth: flow accuracy, Poisson vs
//! direct warping, compactness against naive PCA in the texture and image domains,
//! generalisation with held-out frames, completion of occluded texels, an interpolation example.
//! `surfcap_eval::appearance_eval` computes it; this command generates (or reuses) the frames,
//! writes `appearance.json`, the plots (SVG and PNG) and the example images, and prints the
//! tables.

use std::path::{Path, PathBuf};

use anyhow::Context;
use surfcap_appearance::TextureImage;
use surfcap_appearance::generated_frames::GeneratedFrames;
use surfcap_appearance::image_similarity::Similarity;
use surfcap_appearance::texture_generator::{GeneratorOptions, write_generated_frames};
use surfcap_eval::appearance_eval::{AppearanceEval, AppearanceEvalOptions, appearance_eval};
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{CacheOpts, FlowArgs};

/// Where the frames come from: generated from the shared data's head scan, or an existing
/// folder of `surfcap appearance generate`.
enum Frames {
    Generate { data: PathBuf, frames: usize, size: usize, seed: u64, lighting: bool },
    Existing(PathBuf),
}

/// The head scan of the shared data the frames are generated from.
const HEAD: &str = "leeperrysmith_head";

const OURS: (u8, u8, u8) = (31, 95, 191);
const DIRECT: (u8, u8, u8) = (46, 158, 68);
const NAIVE: (u8, u8, u8) = (208, 48, 48);

fn series(name: &str, points: Vec<(f64, f64)>, color: (u8, u8, u8), dashed: bool) -> Series {
    Series { name: name.into(), points, color, dashed, markers: true }
}

/// The compactness and generalisation plots (Fig. 4.9-4.12), and the warping comparison.
fn plots(dir: &Path, r: &AppearanceEval) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    type Pick = fn(&Similarity) -> f64;
    let metrics: [(&str, &str, Pick); 2] = [("ssim", "SSIM", |s| s.ssim), ("mse", "MSE (0-255 scale)", |s| s.mse)];
    let k = |row: &surfcap_eval::appearance_eval::CompactnessRow| row.components as f64;
    for (stem, label, pick) in metrics {
        // Texture domain: ours (Poisson, direct) and naive PCA, against the input and the clean frames.
        let c = &r.compactness;
        let chart = LineChart {
            title: format!("Compactness, texture domain ({} training frames): {label}", r.complete_frames),
            x_label: "eigen maps (ours: 2/3 textures, 1/3 warps)".into(),
            y_label: label.into(),
            series: vec![
                series("ours (Poisson) vs input", c.iter().map(|x| (k(x), pick(&x.ours.input))).collect(), OURS, false),
                series(
                    "ours (direct) vs input",
                    c.iter().map(|x| (k(x), pick(&x.ours_direct.input))).collect(),
                    DIRECT,
                    false,
                ),
                series("naive PCA vs input", c.iter().map(|x| (k(x), pick(&x.naive.input))).collect(), NAIVE, false),
                series("ours (Poisson) vs clean", c.iter().map(|x| (k(x), pick(&x.ours.clean))).collect(), OURS, true),
                series("naive PCA vs clean", c.iter().map(|x| (k(x), pick(&x.naive.clean))).collect(), NAIVE, true),
            ],
        };
        written.extend(write_line_chart(&dir.join(format!("compactness-texture-{stem}")), &chart)?);
        let image: Vec<_> = c.iter().filter_map(|x| x.image.map(|i| (k(x), i))).collect();
        if !image.is_empty() {
            let chart = LineChart {
                title: format!(
                    "Compactness, image domain ({} views, {} frames): {label}",
                    r.options.views,
                    r.image_frames.len()
                ),
                x_label: "eigen maps (ours: 2/3 textures, 1/3 warps)".into(),
                y_label: label.into(),
                series: vec![
                    series("ours", image.iter().map(|(x, i)| (*x, pick(&i.ours))).collect(), OURS, false),
                    series("naive PCA", image.iter().map(|(x, i)| (*x, pick(&i.naive))).collect(), NAIVE, false),
                ],
            };
            written.extend(write_line_chart(&dir.join(format!("compactness-image-{stem}")), &chart)?);
        }
        let g = &r.generalisation;
        let pct = |row: &surfcap_eval::appearance_eval::GeneralisationRow| 100.0 * row.held_out_fraction;
        let mut s = vec![
            series("ours, texture", g.iter().map(|x| (pct(x), pick(&x.ours.input))).collect(), OURS, false),
            series("naive PCA, texture", g.iter().map(|x| (pct(x), pick(&x.naive.input))).collect(), NAIVE, false),
        ];
        let gi: Vec<_> = g.iter().filter_map(|x| x.image.map(|i| (pct(x), i))).collect();
        if !gi.is_empty() {
            s.push(series("ours, image", gi.iter().map(|(x, i)| (*x, pick(&i.ours))).collect(), OURS, true));
            s.push(series("naive PCA, image", gi.iter().map(|(x, i)| (*x, pick(&i.naive))).collect(), NAIVE, true));
        }
        let chart = LineChart {
            title: format!("Generalisation: held-out frames projected ({label}, vs input)"),
            x_label: "frames held out of training (%)".into(),
            y_label: label.into(),
            series: s,
        };
        written.extend(write_line_chart(&dir.join(format!("generalisation-{stem}")), &chart)?);
    }
    Ok(written)
}

fn sim(s: &Similarity) -> String {
    format!("{:.4} {:>8.2}", s.ssim, s.mse)
}

fn print_tables(r: &AppearanceEval) {
    println!(
        "{} generated frames of {}x{} ({} active texels); {} without a hole train every model, {} with a hole are completed",
        r.frames,
        r.width,
        r.height,
        r.active_texels,
        r.complete_frames,
        r.hole_frames.len()
    );
    let f = &r.flow;
    println!(
        "flow accuracy ({}), reference {}: end-point error mean {:.3}, median {:.3}, max {:.3} texels over {} frames (zero flow: {:.3})",
        f.estimator,
        f.reference,
        f.errors.mean,
        f.errors.median,
        f.errors.max,
        f.errors.frames,
        f.errors.zero_flow_mean
    );
    if let (Some(n), Some(e)) = (&f.second_estimator, &f.second) {
        println!(
            "  {n}: mean {:.3}, median {:.3}, max {:.3} texels over {} frames (zero flow: {:.3})",
            e.mean, e.median, e.max, e.frames, e.zero_flow_mean
        );
    }
    println!("warping (Fig. 4.5-4.6), every component, texture domain:   SSIM      MSE");
    for w in &r.warping {
        println!(
            "  {:<8} ({} textures + {} warps, reference {}, built in {:.1} s)  vs input {}  vs clean {}",
            format!("{:?}", w.warping),
            w.eigen_textures,
            w.eigen_warps,
            w.reference,
            w.build_seconds,
            sim(&w.all_components.input),
            sim(&w.all_components.clean)
        );
    }
    println!(
        "compactness (Fig. 4.9-4.10), SSIM and MSE; texture domain vs the input frames (clean in brackets), image domain vs renders of the input"
    );
    println!(
        "{:>4} {:>6}  {:<17} {:<17} {:<17} {:<17} | {:<15} {:<15}",
        "K", "kt+kw", "ours (Poisson)", "ours (direct)", "naive PCA", "ours/naive clean", "image ours", "image naive"
    );
    for c in &r.compactness {
        let (io, inv) = match &c.image {
            Some(i) => (sim(&i.ours), sim(&i.naive)),
            None => ("-".into(), "-".into()),
        };
        println!(
            "{:>4} {:>6}  {:<17} {:<17} {:<17} {:<17} | {:<15} {:<15}",
            c.components,
            format!("{}+{}", c.eigen_textures, c.eigen_warps),
            sim(&c.ours.input),
            sim(&c.ours_direct.input),
            sim(&c.naive.input),
            format!("({:.4}/{:.4})", c.ours.clean.ssim, c.naive.clean.ssim),
            io,
            inv
        );
    }
    println!(
        "generalisation (Fig. 4.11-4.12): held-out frames projected, SSIM and MSE vs input (image domain on the first frames)"
    );
    for g in &r.generalisation {
        let (io, inv) = match &g.image {
            Some(i) => (sim(&i.ours), sim(&i.naive)),
            None => ("-".into(), "-".into()),
        };
        println!(
            "  {:>3.0}% held out ({:>3} train, {:>3} test{}): ours {}  naive {} | image ours {}  naive {}",
            100.0 * g.held_out_fraction,
            g.training_frames,
            g.test_frames.len(),
            if g.held_out_fraction == 0.0 { ", every frame" } else { "" },
            sim(&g.ours.input),
            sim(&g.naive.input),
            io,
            inv
        );
    }
    let c = &r.completion;
    match (&c.completed, &c.mean_texture, &c.holed_input) {
        (Some(done), Some(mean), Some(holed)) => println!(
            "completion (4.6.2), inside the holes of {} frames vs the clean frames (SSIM MSE): completed {}, mean texture {}, holed input {}",
            c.frames.len(),
            sim(done),
            sim(mean),
            sim(holed)
        ),
        _ => println!("completion (4.6.2): no frame with a hole"),
    }
    let s = &r.seconds;
    println!(
        "seconds: builds {:.1}, flow accuracy {:.1}, compactness {:.1} + image {:.1}, generalisation {:.1}, completion {:.1}, total {:.1}",
        s.builds, s.flow_accuracy, s.compactness_texture, s.compactness_image, s.generalisation, s.completion, s.total
    );
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The shared data folder (its leeperrysmith_head: template.obj and Map-COL.jpg).
    #[arg(long, default_value = "../shared/data")]
    pub data: PathBuf,
    /// Use this folder of `surfcap appearance generate` instead of generating one.
    #[arg(long, conflicts_with_all = ["frames", "size"])]
    pub frames_dir: Option<PathBuf>,
    /// Frames to generate.
    #[arg(long, default_value_t = 100, value_parser = |s: &str| crate::options::at_least(s, 6))]
    pub frames: usize,
    /// Width of the generated textures in texels.
    #[arg(long, default_value_t = 256, value_parser = |s: &str| crate::options::whole_in(s, 16, 4096))]
    pub size: usize,
    /// Generate the frames without the moving light (constant shading): the flow then sees
    /// only the drift (with the light, TV-L1 follows the shading and the model suffers).
    #[arg(long, conflicts_with = "frames_dir")]
    pub no_lighting: bool,
    /// Seed of the generated frames and of the held-out split.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Total eigen maps K of the compactness sweep (those of at least the training frames are
    /// dropped; all the model has is always added).
    #[arg(long, value_delimiter = ',', default_value = "3,6,12,24,48", value_parser = crate::options::count)]
    pub components: Vec<usize>,
    /// Fractions of the frames held out of training (generalisation).
    #[arg(long, value_delimiter = ',', default_value = "0,0.2,0.4,0.6", value_parser = crate::options::fraction)]
    pub held_out: Vec<f64>,
    /// Frames rendered for the image domain (evenly spaced; per held-out fraction, the
    /// first held-out ones); 0: texture domain only.
    #[arg(long, default_value_t = 10)]
    pub image_frames: usize,
    /// Virtual cameras on a ring around the mesh.
    #[arg(long, default_value_t = 8, value_parser = crate::options::count)]
    pub views: usize,
    /// Width and height of the renders, pixels.
    #[arg(long, default_value_t = 256, value_parser = |s: &str| crate::options::whole_in(s, 16, 4096))]
    pub image_size: usize,
    /// Frames whose forward flow is also estimated at full resolution for the end-point error
    /// (with --flow-scale above 0).
    #[arg(long, default_value_t = 0)]
    pub full_resolution_flows: usize,
    #[command(flatten)]
    pub flow: FlowArgs,
    #[command(flatten)]
    pub cache: CacheOpts,
    /// Folder for appearance.json, the plots and the example images (and the generated
    /// frames, in frames/).
    #[arg(short, long, default_value = "appearance-eval")]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = vec![&a.data];
    inputs.extend(a.frames_dir.as_deref());
    let outs = super::folder::claim(ctx, &a.output, &inputs, "eval-appearance")?;
    let source = match a.frames_dir {
        Some(d) => Frames::Existing(d),
        None => {
            Frames::Generate { data: a.data, frames: a.frames, size: a.size, seed: a.seed, lighting: !a.no_lighting }
        }
    };
    let opts = AppearanceEvalOptions {
        components: a.components,
        held_out: a.held_out,
        seed: a.seed,
        image_frames: a.image_frames,
        views: a.views,
        image_size: a.image_size,
        ..Default::default()
    };
    evaluate(ctx, source, &opts, &a.flow, a.full_resolution_flows, &a.cache, &a.output)?;
    ctx.commit(outs)
}

fn evaluate(
    ctx: &crate::Ctx,
    frames: Frames,
    opts: &AppearanceEvalOptions,
    flow: &FlowArgs,
    full_resolution_flows: usize,
    cache: &CacheOpts,
    output: &Path,
) -> anyhow::Result<()> {
    let bar = crate::progress::Bar::new(ctx);
    let dir = match frames {
        Frames::Existing(d) => d,
        Frames::Generate { data, frames, size, seed, lighting } => {
            let head = data.join(HEAD);
            anyhow::ensure!(
                head.is_dir(),
                "{}: no such folder: expected the shared data's head scan (give --data FOLDER, or --frames-dir)",
                head.display()
            );
            let out = output.join("frames");
            let d = GeneratorOptions::default();
            let options = GeneratorOptions {
                frames,
                seed,
                size: Some(size),
                ambient: if lighting { d.ambient } else { 1.0 },
                diffuse: if lighting { d.diffuse } else { 0.0 },
                tint: if lighting { d.tint } else { 0.0 },
                ..d
            };
            write_generated_frames(
                &head.join("template.obj"),
                &head.join("Map-COL.jpg"),
                &options,
                &out,
                ctx.force,
                false,
                &bar,
            )
            .with_context(|| format!("cannot generate texture frames into {}", out.display()))?;
            out
        }
    };
    // Frames generated into the output folder are read back from its temporary (the folder
    // reaches its place at the commit).
    let generated = GeneratedFrames::open(&surfcap_mesh::output_set::write_place(&dir))
        .with_context(|| format!("{}: not a folder of `surfcap appearance generate`", dir.display()))?;
    let estimator = flow.estimator(cache, &bar)?;
    let estimate = |r: &TextureImage, t: &TextureImage, m: &surfcap_appearance::TexelMask| estimator.estimate(r, t, m);
    let name = format!(
        "TV-L1, finest scale {} ({}){}",
        flow.flow_scale,
        if flow.flow_scale == 0 { "full resolution" } else { "1/2^scale resolution, upsampled" },
        if flow.no_preprocess { ", no pre-processing" } else { "" }
    );
    let full = FlowArgs { flow_scale: 0, ..flow.clone() };
    let full_estimator = full.estimator(cache, &bar)?;
    let full_estimate =
        |r: &TextureImage, t: &TextureImage, m: &surfcap_appearance::TexelMask| full_estimator.estimate(r, t, m);
    let opts = AppearanceEvalOptions { second_flow_frames: full_resolution_flows, ..opts.clone() };
    let second = (full_resolution_flows > 0 && flow.flow_scale != 0).then_some((
        &full_estimate as &surfcap_appearance::appearance_model::MaskedFlowEstimator<'_>,
        "TV-L1 at full resolution",
    ));
    let r = appearance_eval(&generated, &opts, &estimate, &name, second, &bar)?;
    let mut written = plots(output, &r)?;
    for (stem, image) in &r.images {
        let path = output.join(format!("{stem}.png"));
        image.write_png(&path)?;
        written.push(path);
    }
    let mut report = serde_json::to_value(&r)?;
    report["frames_dir"] = serde_json::to_value(&dir)?;
    report["written"] = serde_json::to_value(&written)?;
    let path = output.join("appearance.json");
    crate::output::write_json(&path, &report)?;
    ctx.result(&report, || {
        print_tables(&r);
        super::folder::print_wrote(&path, &written);
    });
    Ok(())
}

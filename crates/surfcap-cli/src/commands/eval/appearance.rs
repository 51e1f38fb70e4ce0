//! `surfcap eval appearance`: the evaluation of eigen appearance maps (thesis 4.5-4.6, Fig.
//! 4.5-4.6 and 4.9-4.12) on a generated sequence with ground truth: flow accuracy, Poisson vs
//! direct warping, compactness against naive PCA in the texture and image domains,
//! generalisation with held-out frames, completion of occluded texels, an interpolation example.
//! `surfcap_eval::appearance_eval` computes it; this command generates (or reuses) the frames,
//! writes `appearance.json`, the plots (SVG and PNG) and the example images, and prints the
//! tables. Two benchmarks: `smooth` (generated drift of a few texels, a moving light, blur,
//! noise) and `capture` (the head rendered from a camera ring with specular shading and
//! re-projected into the atlas through calibration and tracking error, as multi-view capture
//! makes textures; `surfcap_appearance::capture_benchmark`).

use std::path::{Path, PathBuf};

use anyhow::Context;
use surfcap_appearance::TextureImage;
use surfcap_appearance::capture_benchmark::{CaptureBenchmark, CaptureOptions};
use surfcap_appearance::generated_frames::GeneratedFrames;
use surfcap_appearance::image_similarity::Similarity;
use surfcap_appearance::texture_generator::{GeneratorOptions, read_uv_mesh, write_generated_frames};
use surfcap_eval::appearance_eval::{
    AppearanceEval, AppearanceEvalOptions, AppearanceSequence, CaptureSequence, appearance_eval,
};
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{CacheOpts, FlowArgs};

/// Where the frames come from: generated from the shared data's head scan, or an existing
/// folder of `surfcap appearance generate`.
enum Frames {
    Generate { data: PathBuf, frames: usize, size: usize, seed: u64, lighting: bool },
    Existing(PathBuf),
    Capture { data: PathBuf, options: CaptureOptions },
}

/// Which benchmark the frames come from.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Benchmark {
    /// Generated drift of at most a few texels, a moving light, blur and noise.
    Smooth,
    /// Camera-ring renders (specular shading, sensor noise) re-projected into the atlas through
    /// per-camera calibration error and per-frame tracking error.
    Capture,
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
    println!("input frames vs their clean truth: {}", sim(&r.input_vs_clean));
    let f = &r.flow;
    match &f.errors {
        Some(e) => println!(
            "flow accuracy ({}), reference {}: end-point error mean {:.3}, median {:.3}, max {:.3} texels over {} frames (zero flow: {:.3})",
            f.estimator, f.reference, e.mean, e.median, e.max, e.frames, e.zero_flow_mean
        ),
        None => println!("flow accuracy ({}), reference {}: the benchmark has no true flow", f.estimator, f.reference),
    }
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
    if let Some(t) = &r.warp_truth {
        println!(
            "true content displacement (texels; over the defined texels, mean and median, mean over frames): cause, displacement, ghosting spread, median displacement, median spread, defined share"
        );
        for c in &t.causes {
            println!(
                "  {:<12} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>6.1}%",
                c.cause,
                c.displacement,
                c.spread,
                c.median_displacement,
                c.median_spread,
                100.0 * c.defined_share
            );
        }
        let warps: Vec<String> = t
            .backward
            .iter()
            .map(|b| format!("{} warps {:.3} / {:.3}", b.eigen_warps, b.end_point_error, b.median_end_point_error))
            .collect();
        println!(
            "backward warps vs the true ones, reference {}: end-point error (mean / median) {} texels (zero flow {:.3} / {:.3})",
            t.reference,
            warps.join(", "),
            t.backward_zero_flow,
            t.backward_zero_flow_median
        );
        println!(
            "variance left after alignment: {:.1}% with the estimated flows, {:.1}% with the true ones",
            100.0 * t.aligned_variance_share,
            100.0 * t.true_aligned_variance_share
        );
        println!(
            "model on the true flows (reference {}), every component: vs input {}  vs clean {}",
            t.true_warps_reference,
            sim(&t.true_warps_all_components.input),
            sim(&t.true_warps_all_components.clean)
        );
        println!("splits of K, texture domain vs input (clean SSIM in brackets): estimated flows | true flows");
        for row in &t.splits {
            println!(
                "{:>4} {:>6}  {:<17} ({:.4}) | {:<17} ({:.4})",
                row.components,
                format!("{}+{}", row.eigen_textures, row.eigen_warps),
                sim(&row.ours.input),
                row.ours.clean.ssim,
                sim(&row.true_warps.input),
                row.true_warps.clean.ssim
            );
        }
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
        "seconds: builds {:.1}, flow accuracy {:.1}, compactness {:.1} + image {:.1}, warps against the truth {:.1}, generalisation {:.1}, completion {:.1}, total {:.1}",
        s.builds,
        s.flow_accuracy,
        s.compactness_texture,
        s.compactness_image,
        s.warp_truth,
        s.generalisation,
        s.completion,
        s.total
    );
}

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("its leeperrysmith_head: template.obj and Map-COL.jpg"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// The benchmark generated: `smooth` (drift of a few texels, a moving light) or `capture`
    /// (camera-ring renders re-projected through calibration and tracking error).
    #[arg(long, value_enum, default_value_t = Benchmark::Smooth)]
    pub benchmark: Benchmark,
    /// Use this folder of `surfcap appearance generate` instead of generating one.
    #[arg(long, conflicts_with_all = ["frames", "size", "benchmark"])]
    pub frames_dir: Option<PathBuf>,
    /// Capture benchmark: cameras on the ring.
    #[arg(long, default_value_t = 12, value_parser = crate::options::count)]
    pub cameras: usize,
    /// Capture benchmark: RMS tracking error per frame, in radii of the head's bounding sphere.
    #[arg(long, default_value_t = 0.02)]
    pub tracking: f64,
    /// Capture benchmark: per-camera calibration error (view and roll angle), degrees.
    #[arg(long, default_value_t = 0.3)]
    pub calibration_deg: f64,
    /// Capture benchmark: specular strength (0: diffuse only).
    #[arg(long, default_value_t = 0.25)]
    pub specular: f64,
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
    for (name, v) in [("--tracking", a.tracking), ("--calibration-deg", a.calibration_deg), ("--specular", a.specular)]
    {
        anyhow::ensure!(v.is_finite() && v >= 0.0, "{name} {v}: expected a finite value of at least 0");
    }
    let source = match (a.frames_dir, a.benchmark) {
        (Some(d), _) => Frames::Existing(d),
        (None, Benchmark::Smooth) => {
            Frames::Generate { data: a.data, frames: a.frames, size: a.size, seed: a.seed, lighting: !a.no_lighting }
        }
        (None, Benchmark::Capture) => {
            let d = CaptureOptions::default();
            let options = CaptureOptions {
                frames: a.frames,
                seed: a.seed,
                size: a.size,
                cameras: a.cameras,
                image_size: a.image_size,
                tracking: a.tracking,
                calibration_deg: a.calibration_deg,
                specular: a.specular,
                ambient: if a.no_lighting { 1.0 } else { d.ambient },
                diffuse: if a.no_lighting { 0.0 } else { d.diffuse },
                ..d
            };
            Frames::Capture { data: a.data, options }
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
    let mut capture = None;
    let dir = match frames {
        Frames::Existing(d) => d,
        Frames::Capture { data, options } => {
            let head = data.join(HEAD);
            anyhow::ensure!(
                head.is_dir(),
                "{}: no such folder: expected the shared data's head scan (give --data FOLDER)",
                head.display()
            );
            let (topology, positions) = read_uv_mesh(&head.join("template.obj"))?;
            let texture = TextureImage::read(&head.join("Map-COL.jpg"))?;
            let bench = CaptureBenchmark::new(&topology, &positions, &texture, &options)
                .with_context(|| format!("{}: cannot set up the capture benchmark", head.display()))?;
            let seq = CaptureSequence::generate(&bench, &topology, &positions, &head.display().to_string(), &bar)?;
            capture = Some((bench, seq));
            head
        }
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
    let generated = match capture {
        Some(_) => None,
        None => Some(
            GeneratedFrames::open(&surfcap_mesh::output_set::write_place(&dir))
                .with_context(|| format!("{}: not a folder of `surfcap appearance generate`", dir.display()))?,
        ),
    };
    let sequence: &dyn AppearanceSequence = match (&capture, &generated) {
        (Some((_, seq)), _) => seq,
        (None, Some(g)) => g,
        (None, None) => unreachable!("a sequence is generated, read or made in memory"),
    };
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
    let r = appearance_eval(sequence, &opts, &estimate, &name, second, &bar)?;
    let mut written = plots(output, &r)?;
    if let Some((bench, seq)) = &capture {
        // What the capture looks like: one frame's camera images, its re-projected texture and
        // its clean truth.
        let k = seq.frames.len() / 2;
        let views: Vec<TextureImage> =
            (0..bench.actual_cameras().len().min(4)).map(|j| bench.render(k, j)).collect::<Result<_, _>>()?;
        let refs: Vec<&TextureImage> = views.iter().collect();
        let path = output.join("capture-views.png");
        side_by_side(&refs)?.write_png(&path)?;
        written.push(path);
        let path = output.join("capture-frame-vs-clean.png");
        side_by_side(&[&seq.frames[k].frame, &seq.frames[k].clean])?.write_png(&path)?;
        written.push(path);
    }
    for (stem, image) in &r.images {
        let path = output.join(format!("{stem}.png"));
        image.write_png(&path)?;
        written.push(path);
    }
    let mut report = serde_json::to_value(&r)?;
    report["frames_dir"] = serde_json::to_value(&dir)?;
    report["benchmark"] = serde_json::to_value(if capture.is_some() { "capture" } else { "smooth" })?;
    if let Some((bench, seq)) = &capture {
        report["capture"] = serde_json::to_value(bench.options())?;
        let seen: Vec<f64> = seq
            .frames
            .iter()
            .map(|f| {
                let m = bench.mask();
                let s = (0..f.seen.len()).filter(|&i| m.is_active(i) && f.seen[i]).count();
                s as f64 / m.len().max(1) as f64
            })
            .collect();
        report["capture_seen_share"] = serde_json::to_value(seen.iter().sum::<f64>() / seen.len().max(1) as f64)?;
    }
    report["written"] = serde_json::to_value(&written)?;
    let path = output.join("appearance.json");
    crate::output::write_json(&path, &report)?;
    ctx.result(&report, || {
        print_tables(&r);
        super::folder::print_wrote(&path, &written);
    });
    Ok(())
}

/// Images of one height side by side.
fn side_by_side(images: &[&TextureImage]) -> anyhow::Result<TextureImage> {
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let c = images.first().map_or(3, |i| i.channels());
    let w: usize = images.iter().map(|i| i.width()).sum();
    let mut out = TextureImage::zeros(w, h, c);
    let mut x0 = 0;
    for img in images {
        for ch in 0..c.min(img.channels()) {
            let src = img.plane(ch);
            let dst = out.plane_mut(ch);
            for y in 0..img.height() {
                dst[y * w + x0..y * w + x0 + img.width()].copy_from_slice(&src[y * img.width()..(y + 1) * img.width()]);
            }
        }
        x0 += img.width();
    }
    Ok(out)
}

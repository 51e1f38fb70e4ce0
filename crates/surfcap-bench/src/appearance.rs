//! `surfcap-bench appearance`: the speed and memory targets of eigen appearance maps (thesis
//! chapter 4) on 2 cores: optical flow between two 1024 x 1024 maps under 5 s; building the model
//! of 100 maps of 1024 x 1024 under 5 minutes with peak memory under 8 GB; instantiating one
//! texture (4.4.3: eigen textures and warps combined, then the Poisson de-alignment) under 1 s.
//!
//! The maps are the benchmark sequence of `surfcap appearance generate` (the real head scan
//! and its texture, with known drift, moving light, blur, noise and holes), generated in
//! memory before anything is timed. The build runs as `surfcap appearance build` does by
//! default (flows at `--flow-scale`, the medoid search with direct warps, Poisson warping,
//! every component) with no disk cache, so every flow is computed. Peak memory is the
//! process's high-water mark (VmHWM), the generated maps included, as a build that reads them
//! from files holds them too.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use rayon::prelude::*;
use serde_json::json;
use surfcap_appearance::flow_cache::{FlowCache, TextureFlow};
use surfcap_appearance::texture_generator::{GeneratorOptions, TextureGenerator, read_uv_mesh};
use surfcap_appearance::{
    AppearanceOptions, FlowOptions, PreprocessOptions, TexelMask, TextureImage, build_appearance_model,
};

use crate::measure::{peak_rss, verdict};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the head scan: leeperrysmith_head"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// Texture maps in the model.
    #[arg(long, default_value_t = 100, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub frames: usize,
    /// Width and height of the maps, texels.
    #[arg(long, default_value_t = 1024, value_parser = |s: &str| crate::options::whole_in(s, 16, 8192))]
    pub size: usize,
    /// Finest scale of the build's flows (0: full resolution; 1: half, `appearance build`'s
    /// default).
    #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 0, 4))]
    pub flow_scale: usize,
    /// Instantiations timed (the mean and the worst are reported).
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::whole_in(s, 1, 100))]
    pub repeat: usize,
    /// Seed of the generated sequence.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}

fn gib(bytes: Option<u64>) -> f64 {
    bytes.map_or(f64::NAN, |b| b as f64 / (1u64 << 30) as f64)
}

pub fn run(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<()> {
    // The maps in memory (RGB f32), their flows, warps and the model's matrices: about four
    // times the maps.
    let (f, t) = (a.frames as f64, a.size as f64 * a.size as f64);
    let what = format!("--frames {} --size {}", a.frames, a.size);
    crate::check_size(ctx, what, f * t * 12.0 * 4.0, f * t * 6.0, "--frames or --size")?;
    let head = a.data.join("leeperrysmith_head");
    let mesh = head.join("template.obj");
    let (topology, positions) = read_uv_mesh(&mesh).with_context(|| format!("{}: the head scan", head.display()))?;
    let texture = TextureImage::read(&head.join("Map-COL.jpg"))?;
    let options =
        GeneratorOptions { frames: a.frames, seed: a.seed, size: Some(a.size), ..GeneratorOptions::default() };
    ctx.say(&format!("generating {} maps of {}x{} from the head scan (not timed) ...", a.frames, a.size, a.size));
    let generator = TextureGenerator::new(&topology, &positions, &texture, &options)?;
    let maps: Vec<TextureImage> =
        (0..a.frames).into_par_iter().map(|k| generator.frame(k).map(|f| f.frame)).collect::<Result<_, _>>()?;
    drop(generator);
    let (w, h) = (maps[0].width(), maps[0].height());
    let atlas = topology.uv().context("the head scan has a UV atlas")?;
    let mask = TexelMask::from_atlas(atlas, w, h, 1)?;
    let names: Vec<String> = (0..a.frames).map(|k| format!("frame_{k:03}")).collect();
    let rss_maps = peak_rss();

    // Flow between two maps, pre-processing included, at full resolution and at the build's
    // scale (no cache: `FlowCache::new(None, ..)`).
    let mut flow_rows = Vec::new();
    for scale in [0, a.flow_scale] {
        let est = TextureFlow::new(
            FlowCache::new(None, false, &surfcap_mesh::NoProgress),
            PreprocessOptions::default(),
            FlowOptions { finest_scale: scale, ..FlowOptions::default() },
        );
        let t = Instant::now();
        est.estimate(&maps[0], &maps[1], &mask)?;
        let seconds = t.elapsed().as_secs_f64();
        flow_rows.push(
            json!({"finest_scale": scale, "seconds": seconds, "target_seconds": 5.0, "verdict": verdict(seconds, 5.0)}),
        );
        ctx.say(&format!("flow {w}x{h} (finest scale {scale}): {seconds:.2} s ({})", verdict(seconds, 5.0)));
        if a.flow_scale == 0 {
            break;
        }
    }

    ctx.say(&format!("building the model of {} maps ...", a.frames));
    let bar = crate::progress::Bar::new(ctx);
    let est = TextureFlow::new(
        FlowCache::new(None, false, &surfcap_mesh::NoProgress),
        PreprocessOptions::default(),
        FlowOptions { finest_scale: a.flow_scale, ..FlowOptions::default() },
    );
    let estimate = |r: &TextureImage, t: &TextureImage| est.estimate(r, t, &mask);
    let t = Instant::now();
    let (model, report) = build_appearance_model(&maps, &names, &mask, &AppearanceOptions::default(), &estimate, &bar)?;
    let build_seconds = t.elapsed().as_secs_f64();
    drop(est);
    let rss_build = peak_rss();
    drop(maps);
    ctx.say(&format!("built in {build_seconds:.1} s, peak memory {:.2} GiB", gib(rss_build)));

    let mut times = Vec::new();
    for r in 0..a.repeat {
        let frame = (r * 37 + 11) % a.frames;
        let t = Instant::now();
        model.reconstruct(frame)?;
        times.push(t.elapsed().as_secs_f64());
    }
    let mean = times.iter().sum::<f64>() / times.len().max(1) as f64;
    let worst = times.iter().copied().fold(0.0, f64::max);
    ctx.say(&format!("instantiating one map: mean {mean:.3} s, worst {worst:.3} s ({})", verdict(worst, 1.0)));

    let value = json!({
        "frames": a.frames, "size": [w, h], "active_texels": mask.len(), "threads": rayon::current_num_threads(),
        "flow": flow_rows,
        "build": {
            "seconds": build_seconds, "target_seconds": 300.0, "verdict": verdict(build_seconds, 300.0),
            "peak_memory_gib": gib(rss_build), "target_gib": 8.0, "verdict_memory": verdict(gib(rss_build), 8.0),
            "peak_memory_gib_before_build": gib(rss_maps),
            "flow_scale": a.flow_scale, "stages": report.seconds, "medoid_alignments": report.medoid_errors.len(),
            "eigen_textures": model.n_textures(), "eigen_warps": model.n_warps(),
        },
        "instantiate": {"mean_seconds": mean, "worst_seconds": worst, "repeat": times.len(), "target_seconds": 1.0, "verdict": verdict(worst, 1.0)},
    });
    ctx.result(&value, || {
        println!("| what | measured | target | |");
        println!("|---|---|---|---|");
        for r in &flow_rows {
            println!(
                "| flow {w}x{h}, finest scale {} | {:.2} s | < 5 s | {} |",
                r["finest_scale"],
                r["seconds"].as_f64().unwrap_or(f64::NAN),
                r["verdict"].as_str().unwrap_or("")
            );
        }
        println!("| build, {} maps | {build_seconds:.1} s | < 300 s | {} |", a.frames, verdict(build_seconds, 300.0));
        println!("| build, peak memory | {:.2} GiB | < 8 GiB | {} |", gib(rss_build), verdict(gib(rss_build), 8.0));
        println!("| instantiate one map (worst of {}) | {worst:.3} s | < 1 s | {} |", times.len(), verdict(worst, 1.0));
    });
    Ok(())
}

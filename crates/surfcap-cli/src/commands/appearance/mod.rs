//! `surfcap appearance ...`: eigen appearance maps (thesis chapter 4).
//!
//! `surfcap appearance generate [--data ../shared/data | --mesh M --texture T] --frames 100
//! --seed 7 [--size 1024] -o out/`: benchmark texture sequences with ground truth
//! (`surfcap_appearance::texture_generator`): per-frame textures of a real UV-mapped
//! mesh drifting by known smooth warps, lit by a moving light, blurred, noisy and with
//! occlusion holes in some frames, with the clean frames, the hole masks and the known drift
//! (the folder's layout: `surfcap_appearance::generated_frames`). `--mesh` may be a subject
//! with texture coordinates (its first frame; as many maps as it has frames by default).
//! `surfcap appearance paint --mesh M --size 256 -o base.png`: a base texture painted from the
//! mesh's 3D positions (`surfcap_appearance::solid_texture`), for a mesh that has none.

mod model;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_appearance::TextureImage;
use surfcap_appearance::atlas_raster::AtlasRaster;
use surfcap_appearance::solid_texture::solid_texture;
use surfcap_appearance::solid_texture::solid_texture_size;
use surfcap_appearance::texture_generator::{
    GeneratorOptions, GeneratorSource, MAX_BLUR_SIGMA, MAX_DRIFT, MAX_NOISE_SIGMA, generated_frames_size,
    write_generated_frames, write_generated_frames_of,
};
use surfcap_mesh::Subject;

use crate::options::{SourceOpts, open};

/// The head scan of the shared data, the default source of `generate`.
const HEAD: &str = "leeperrysmith_head";

#[derive(clap::Subcommand, Debug)]
pub enum AppearanceCmd {
    /// Benchmark textures with ground truth: F per-frame textures from a UV-mapped mesh and its
    /// texture (default: the real head scan of the shared data), with known drift, moving
    /// light, blur, noise and occlusion holes; the clean frames and hole masks kept.
    Generate(GenerateArgs),
    /// A base texture painted from a UV-mapped mesh's 3D positions (garment bands, a checker
    /// and noise, continuous across the atlas's seams): the texture of a mesh that has none,
    /// e.g. the mannequin of `surfcap make mannequin --uv-atlas`, for `generate --texture`.
    Paint(PaintArgs),
    /// Eigen textures and eigen warps of per-frame texture maps (thesis 4.4): flows to a
    /// reference chosen by medoid shift, Poisson warping, PCA; written as a model folder.
    Build(model::BuildArgs),
    /// A training frame's texture rebuilt from its coefficients (4.4.3), with all or fewer
    /// eigen maps.
    Reconstruct(model::ReconstructArgs),
    /// A texture blended from two or more frames in the eigen spaces (4.6.1).
    Interpolate(model::InterpolateArgs),
    /// An incomplete texture map (occluded texels) completed by projection (4.6.2).
    Complete(model::CompleteArgs),
}

#[derive(clap::Args, Debug)]
pub struct GenerateArgs {
    #[arg(long, value_name = "DIR", help = crate::options::data_help("the mesh and texture default to its leeperrysmith_head (template.obj, Map-COL.jpg)"),
          default_value_os_t = crate::options::default_data_dir())]
    pub data: PathBuf,
    /// A UV-mapped mesh instead of the head scan: an OBJ (with `vt` on every face corner), or a
    /// subject with texture coordinates (`surfcap make head`, `--uv-atlas`), whose first
    /// frame is used and whose frame count is the default of --frames, so `appearance build
    /// --mesh SUBJECT` names the maps by its frames.
    #[arg(long, requires = "texture")]
    pub mesh: Option<PathBuf>,
    /// The mesh's texture map (PNG or JPEG; `surfcap appearance paint` makes one for a mesh
    /// that has none).
    #[arg(long, requires = "mesh")]
    pub texture: Option<PathBuf>,
    /// Frames to generate (default: the subject's frame count with a subject --mesh, else 100).
    /// The memory and disk the frames take are estimated before any work and checked against
    /// --max-memory and --max-disk.
    #[arg(long, value_parser = crate::options::count)]
    pub frames: Option<usize>,
    /// Seed of every random choice (drift, light, holes, noise): the same seed gives the same
    /// frames, whatever the thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Width of the generated textures in texels (the height keeps the texture's aspect;
    /// default: the texture's own size).
    #[arg(long, value_parser = |s: &str| crate::options::whole_in(s, 8, 16384))]
    pub size: Option<usize>,
    /// Largest drift, texels of the generated size, 0 to 64 (real texture drift is a few texels).
    #[arg(long, default_value_t = 3.0, value_parser = |s: &str| crate::options::number_from(s, 0.0, MAX_DRIFT))]
    pub max_drift: f64,
    /// Gaussian blur, texels, 0 (none) to 32 (a smear).
    #[arg(long, default_value_t = 0.6, value_parser = |s: &str| crate::options::number_from(s, 0.0, MAX_BLUR_SIGMA))]
    pub blur: f64,
    /// Gaussian noise, on the 0-255 scale, 0 (none) to 255.
    #[arg(long, default_value_t = 2.0, value_parser = |s: &str| crate::options::number_from(s, 0.0, MAX_NOISE_SIGMA))]
    pub noise: f64,
    /// Share of frames with an occlusion hole.
    #[arg(long, default_value_t = 0.15, value_parser = crate::options::fraction)]
    pub hole_fraction: f64,
    /// No illumination change: constant shading (ambient 1, no diffuse term, no colour tint).
    #[arg(long)]
    pub no_lighting: bool,
    /// Also write displacement.npy (f32 [F, 2, H, W]: 800 MB for 100 frames at 1024); without
    /// it the drift is stored as its waves in frames.json, from which it is recomputed exactly.
    #[arg(long)]
    pub displacement_npy: bool,
    /// The folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(ctx: &crate::Ctx, cmd: AppearanceCmd) -> anyhow::Result<()> {
    match cmd {
        AppearanceCmd::Generate(a) => generate(ctx, a),
        AppearanceCmd::Paint(a) => paint(ctx, &a),
        AppearanceCmd::Build(a) => model::build(ctx, &a),
        AppearanceCmd::Reconstruct(a) => model::reconstruct(ctx, &a),
        AppearanceCmd::Interpolate(a) => model::interpolate(ctx, &a),
        AppearanceCmd::Complete(a) => model::complete(ctx, &a),
    }
}

fn generate(ctx: &crate::Ctx, a: GenerateArgs) -> anyhow::Result<()> {
    let (mesh, texture) = match (&a.mesh, &a.texture) {
        (Some(m), Some(t)) => (m.clone(), t.clone()),
        _ => {
            let head = a.data.join(HEAD);
            if !head.is_dir() {
                anyhow::bail!(
                    "{}: no such folder: expected the shared data's head scan (give --data FOLDER, or --mesh and --texture)",
                    head.display()
                );
            }
            (head.join("template.obj"), head.join("Map-COL.jpg"))
        }
    };
    surfcap_mesh::output_path::check_not_input(&a.output, &[&mesh, &texture])?;
    // A subject (anything but an OBJ) gives its first frame and its frame count.
    let subject = if is_obj(&mesh) { None } else { Some(open(ctx, &mesh, &SourceOpts::default())?) };
    let defaults = GeneratorOptions::default();
    let options = GeneratorOptions {
        frames: a.frames.unwrap_or(subject.as_ref().map_or(100, Subject::n_frames)),
        seed: a.seed,
        size: a.size,
        max_drift: a.max_drift,
        blur_sigma: a.blur,
        noise_sigma: a.noise,
        hole_fraction: a.hole_fraction,
        ambient: if a.no_lighting { 1.0 } else { defaults.ambient },
        diffuse: if a.no_lighting { 0.0 } else { defaults.diffuse },
        tint: if a.no_lighting { 0.0 } else { defaults.tint },
        ..defaults
    };
    // Sized before any work, so a refusal leaves nothing behind.
    let texture_size = TextureImage::dimensions(&texture)?;
    let estimate = generated_frames_size(&options, texture_size, a.displacement_npy, rayon::current_num_threads());
    ctx.check_size(&estimate, Some(&a.output))?;
    let t0 = Instant::now();
    let bar = crate::progress::Bar::new(ctx);
    let header = match &subject {
        None => write_generated_frames(&mesh, &texture, &options, &a.output, ctx.force, a.displacement_npy, &bar),
        Some(s) => {
            let (topology, positions) = (s.topology(), s.frame(0).expect("a subject has frames"));
            anyhow::ensure!(
                topology.uv().is_some(),
                "{}: the subject has no texture coordinates: expected a UV-mapped mesh (e.g. `surfcap make head` or `--uv-atlas`)",
                mesh.display()
            );
            let mut obj = Vec::new();
            surfcap_formats::obj::write_obj(&mut obj, topology, positions)?;
            let source = GeneratorSource {
                topology,
                positions,
                texture: &TextureImage::read(&texture)?,
                mesh_name: &mesh,
                texture_name: &texture,
                mesh_obj: &obj,
            };
            write_generated_frames_of(&source, &options, &a.output, ctx.force, a.displacement_npy, &bar)
        }
    }
    .with_context(|| format!("cannot generate texture frames into {}", a.output.display()))?;
    let seconds = t0.elapsed().as_secs_f64();
    let bytes: u64 = std::fs::read_dir(&a.output)
        .map(|d| d.filter_map(|e| e.ok()?.metadata().ok()).map(|m| m.len()).sum())
        .unwrap_or(0);
    ctx.result(
        &json!({
            "output": a.output,
            "mesh": mesh,
            "texture": texture,
            "frames": header.frames,
            "seed": header.seed,
            "width": header.width,
            "height": header.height,
            "hole_frames": header.hole_frames,
            "drift_bound_texels": header.drift_bound,
            "displacement_npy": header.displacement_file.is_some(),
            "bytes": bytes,
            "seconds": seconds,
        }),
        || {
            println!(
                "generated {} of {}x{} from {} and {} ({} with holes, drift up to {:.2} texels) -> {} ({:.0} MB, {seconds:.1} s)",
                crate::output::count_of(header.frames, "frame"),
                header.width,
                header.height,
                mesh.display(),
                texture.display(),
                header.hole_frames.len(),
                header.drift_bound,
                a.output.display(),
                bytes as f64 / 1e6
            );
        },
    );
    Ok(())
}

fn is_obj(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

#[derive(clap::Args, Debug)]
pub struct PaintArgs {
    /// A UV-mapped mesh: a subject with texture coordinates (its first frame is painted, in
    /// its up axis) or an OBJ with `vt` (+y up).
    #[arg(long)]
    pub mesh: PathBuf,
    /// Width and height of the texture, texels (its memory is checked against --max-memory
    /// before any work).
    #[arg(long, default_value_t = 1024, value_parser = |s: &str| crate::options::whole_in(s, 8, 16384))]
    pub size: usize,
    /// The image to write: .png, .jpg or .jpeg (the format follows the extension).
    #[arg(short, long, value_parser = crate::options::image_output)]
    pub output: PathBuf,
}

fn paint(ctx: &crate::Ctx, a: &PaintArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.mesh])?;
    ctx.check_size(&solid_texture_size(a.size), Some(&a.output))?;
    let t0 = Instant::now();
    let (topology, positions, up) = if is_obj(&a.mesh) {
        let obj = surfcap_formats::obj::read_obj(&a.mesh)?;
        (obj.topology().map_err(|e| e.in_file(&a.mesh))?, obj.positions, 1)
    } else {
        let s = open(ctx, &a.mesh, &SourceOpts::default())?;
        let positions = s.frame(0).expect("a subject has frames").to_vec();
        (s.topology().clone(), positions, s.up_axis.axis_and_sign().0)
    };
    let atlas = topology.uv().with_context(|| {
        format!(
            "{}: the mesh has no texture coordinates: expected a UV atlas (OBJ `vt`, `surfcap make mannequin --uv-atlas`)",
            a.mesh.display()
        )
    })?;
    let raster =
        AtlasRaster::new(atlas, a.size, a.size).with_context(|| format!("{}: the UV atlas", a.mesh.display()))?;
    let texture = solid_texture(&raster, topology.triangles(), &positions, up)?;
    texture.write(&a.output)?;
    let seconds = t0.elapsed().as_secs_f64();
    ctx.result(&json!({ "mesh": a.mesh, "size": a.size, "output": a.output, "seconds": seconds }), || {
        println!("painted a {0}x{0} texture from {1} in {seconds:.2} s", a.size, a.mesh.display())
    });
    ctx.wrote([&a.output]);
    Ok(())
}

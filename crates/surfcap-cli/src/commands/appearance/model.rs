//! `surfcap appearance build | reconstruct | interpolate | complete`: eigen appearance maps of
//! a subject's per-frame textures (thesis chapter 4; `surfcap-appearance`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use serde_json::json;
use surfcap_appearance::appearance_requests;
use surfcap_appearance::texture_folder::{frame_name, read_textures};
use surfcap_appearance::{
    AppearanceModel, AppearanceOptions, TexelMask, TextureImage, Warping, build_appearance_model,
};

use crate::options::{CacheOpts, FlowArgs, SourceOpts, open};

/// Parses `poisson` or `direct`.
pub fn parse_warping(s: &str) -> Result<Warping, String> {
    appearance_requests::parse_warping(s).ok_or_else(|| format!("{s}: expected poisson (thesis eq. 4.1-4.3) or direct"))
}

#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    /// A folder of per-frame texture maps (PNG or JPEG, natural order of their names; in a
    /// folder written by `surfcap appearance generate`, its `frame_*` maps).
    pub textures: PathBuf,
    /// The UV-mapped mesh whose atlas the maps follow (an OBJ with `vt`, or any subject
    /// `surfcap import` reads that has texture coordinates). With a subject of as many frames
    /// as maps, the frames are named `sequence:frame` in the subject's order, so `synth
    /// --appearance` can give every output frame its texture; otherwise by the maps' file
    /// names. Default: the folder's `template.obj` (as `generate` writes it).
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Eigen maps kept in total, two thirds eigen textures and one third eigen warps (thesis
    /// 4.5.1); default: every component (at most one per frame less one of each kind).
    #[arg(long, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub components: Option<usize>,
    /// Weight of the intensity term of the Poisson warp (thesis eq. 4.1-4.3), above 0 and at
    /// most 1000 (the thesis uses 0.02).
    #[arg(long, default_value_t = 0.02, value_parser = |s: &str| crate::options::positive_at_most(s, 1000.0))]
    pub lambda: f64,
    /// How textures are warped: poisson (thesis) or direct (the baseline of Fig. 4.5).
    #[arg(long, default_value = "poisson", value_parser = parse_warping)]
    pub warping: Warping,
    /// How the medoid shift's search for the reference warps (Algorithm 4 uses --warping;
    /// direct solves no Poisson system per frame, and the chosen reference's alignment is redone
    /// with --warping).
    #[arg(long, default_value = "direct", value_parser = parse_warping)]
    pub search_warping: Warping,
    /// Alignments the medoid shift may run (Algorithm 4).
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::at_least(s, 1))]
    pub medoid_iterations: usize,
    /// With a folder of `surfcap appearance generate`, keep the frames with occlusion holes in
    /// the model (by default they are left out, as thesis 4.6.2 does, to be completed).
    #[arg(long)]
    pub keep_holed: bool,
    /// Rings of texels added around the atlas's covered texels.
    #[arg(long, default_value_t = 1, value_parser = |s: &str| crate::options::whole_in(s, 0, 8))]
    pub dilation: usize,
    #[command(flatten)]
    pub flow: FlowArgs,
    /// The model folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// The texture files of `dir` (`surfcap_appearance::appearance_requests::texture_files`), its
/// notes printed.
pub fn texture_files(ctx: &crate::Ctx, dir: &Path, keep_holed: bool) -> anyhow::Result<Vec<PathBuf>> {
    Ok(appearance_requests::texture_files(dir, keep_holed, &Notes(ctx))?)
}

/// Notes of the library's request helpers, printed as `note:` lines (`ctx.note`).
struct Notes<'a>(&'a crate::Ctx);

impl surfcap_mesh::Progress for Notes<'_> {
    fn note(&self, text: &str) {
        self.0.note(text);
    }
}

/// The active texels of `mesh`'s atlas at the maps' size, and the frame names the mesh gives
/// (`sequence:frame` when it is a subject of `frames` frames).
pub fn atlas_mask(
    ctx: &crate::Ctx,
    mesh: &Path,
    source: &SourceOpts,
    width: usize,
    height: usize,
    dilation: usize,
    frames: usize,
) -> anyhow::Result<(TexelMask, Option<Vec<String>>)> {
    // A single OBJ is a mesh, not a subject (no frame rate to ask for); anything else is
    // opened as a subject, whose frames may name the maps.
    if appearance_requests::is_obj(mesh) {
        let topology = surfcap_formats::obj::read_obj(mesh)?.topology()?;
        return Ok(appearance_requests::atlas_mask(mesh, &topology, None, width, height, dilation, frames)?);
    }
    let s = open(ctx, mesh, source)?;
    Ok(appearance_requests::atlas_mask(mesh, s.topology(), Some(&s), width, height, dilation, frames)?)
}

/// Splits `k` eigen maps two thirds textures, one third warps (thesis 4.5.1).
pub use surfcap_appearance::appearance_model::split_components;

/// The mesh of a texture folder: `--mesh`, else the folder's `template.obj`.
pub fn mesh_of(textures: &Path, mesh: Option<&Path>) -> anyhow::Result<PathBuf> {
    Ok(appearance_requests::mesh_of(textures, mesh)?)
}

pub fn build(ctx: &crate::Ctx, a: &BuildArgs) -> anyhow::Result<()> {
    let mesh = mesh_of(&a.textures, a.mesh.as_deref())?;
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.textures, &mesh])?;
    crate::options::record_input(&a.textures);
    let t0 = Instant::now();
    let bar = crate::progress::Bar::new(ctx);
    let files = texture_files(ctx, &a.textures, a.keep_holed)?;
    let textures = read_textures(&files, &bar)?;
    let (w, h) = (textures[0].width(), textures[0].height());
    let (mask, subject_names) = atlas_mask(ctx, &mesh, &a.source, w, h, a.dilation, textures.len())?;
    let names: Vec<String> = subject_names.unwrap_or_else(|| files.iter().map(|f| frame_name(f)).collect());
    let (n_textures, n_warps) = a.components.map_or((usize::MAX, usize::MAX), split_components);
    let options = AppearanceOptions {
        lambda: a.lambda,
        n_textures,
        n_warps,
        warping: a.warping,
        max_medoid_iterations: a.medoid_iterations,
        selection_warping: a.search_warping,
    };
    ctx.say(&format!(
        "{} texture maps of {w}x{h}, {} active texels ({:.1}%)",
        textures.len(),
        mask.len(),
        100.0 * mask.len() as f64 / (w * h) as f64
    ));
    let flow = a.flow.estimator(&a.cache, &bar)?;
    let estimate = |r: &TextureImage, t: &TextureImage| flow.estimate(r, t, &mask);
    let (model, report) = build_appearance_model(&textures, &names, &mask, &options, &estimate, &bar)?;
    drop(textures);
    model.save(&a.output, ctx.force)?;
    let seconds = t0.elapsed().as_secs_f64();
    let value = appearance_requests::build_summary(&model, &report, Some(&a.output), seconds);
    ctx.result(&value, || {
        println!(
            "reference {} (medoid shift: {} alignment{}), {} eigen textures ({:.1}% of the variance), {} eigen warps ({:.1}%)",
            names[report.reference],
            report.medoid_errors.len(),
            if report.medoid_errors.len() == 1 { "" } else { "s" },
            model.n_textures(),
            100.0 * report.texture_explained_variance.iter().sum::<f64>(),
            model.n_warps(),
            100.0 * report.warp_explained_variance.iter().sum::<f64>()
        );
        println!("built in {seconds:.1} s");
    });
    ctx.wrote([&a.output]);
    Ok(())
}

/// The model's frame named `name` (as `model.json` lists them).
pub fn frame_of(model: &AppearanceModel, name: &str) -> anyhow::Result<usize> {
    Ok(appearance_requests::frame_of(model, name)?)
}

fn load(path: &Path) -> anyhow::Result<AppearanceModel> {
    AppearanceModel::load(path).with_context(|| format!("{}: cannot open the appearance model", path.display()))
}

#[derive(clap::Args, Debug)]
pub struct ReconstructArgs {
    /// The model folder (`surfcap appearance build`).
    pub model: PathBuf,
    /// The frame to rebuild from its coefficients (a name the model lists, e.g. `walk:12`).
    #[arg(long)]
    pub frame: String,
    /// Eigen maps used (two thirds textures, one third warps); default: all the model has.
    #[arg(long, value_parser = |s: &str| crate::options::at_least(s, 0))]
    pub components: Option<usize>,
    /// The texture map to write: .png, .jpg or .jpeg (the format follows the extension).
    #[arg(short, long, value_parser = crate::options::image_output)]
    pub output: PathBuf,
}

pub fn reconstruct(ctx: &crate::Ctx, a: &ReconstructArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.model])?;
    let model = load(&a.model)?;
    let k = frame_of(&model, &a.frame)?;
    let (tc, wc) = model.frame_coefficients(k)?;
    let (nt, nw) = a.components.map_or((tc.len(), wc.len()), split_components);
    let t = Instant::now();
    let texture = model.instantiate(&tc[..nt.min(tc.len())], &wc[..nw.min(wc.len())])?;
    let seconds = t.elapsed().as_secs_f64();
    texture.write(&a.output)?;
    let value = json!({"frame": a.frame, "eigen_textures": nt.min(tc.len()), "eigen_warps": nw.min(wc.len()), "seconds": seconds, "output": a.output});
    ctx.result(&value, || {
        println!(
            "frame {} from {} eigen textures and {} eigen warps in {seconds:.2} s",
            a.frame,
            nt.min(tc.len()),
            nw.min(wc.len())
        )
    });
    ctx.wrote([&a.output]);
    Ok(())
}

#[derive(clap::Args, Debug)]
pub struct InterpolateArgs {
    /// The model folder.
    pub model: PathBuf,
    /// The frames to blend, comma-separated, each `NAME=WEIGHT` (weights summing to 1) or
    /// `NAME` alone for equal weights, e.g. `walk:3=0.25,run:7=0.75` (thesis 4.6.1).
    #[arg(long, value_delimiter = ',', required = true)]
    pub frames: Vec<String>,
    /// The texture map to write: .png, .jpg or .jpeg (the format follows the extension).
    #[arg(short, long, value_parser = crate::options::image_output)]
    pub output: PathBuf,
}

/// `NAME=WEIGHT` or `NAME` items into (frame, weight), equal weights when none is given.
pub fn parse_weights(model: &AppearanceModel, items: &[String]) -> anyhow::Result<Vec<(usize, f64)>> {
    Ok(appearance_requests::frame_weights(model, &appearance_requests::parse_frame_weights(items)?)?)
}

pub fn interpolate(ctx: &crate::Ctx, a: &InterpolateArgs) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.model])?;
    let model = load(&a.model)?;
    let weights = parse_weights(&model, &a.frames)?;
    let t = Instant::now();
    let texture = model.interpolate(&weights)?;
    let seconds = t.elapsed().as_secs_f64();
    texture.write(&a.output)?;
    let frames: Vec<_> = weights.iter().map(|&(k, w)| json!({"frame": model.names()[k], "weight": w})).collect();
    ctx.result(&json!({"frames": frames, "seconds": seconds, "output": a.output}), || {
        println!("blended {} frames in the eigen spaces in {seconds:.2} s", weights.len())
    });
    ctx.wrote([&a.output]);
    Ok(())
}

#[derive(clap::Args, Debug)]
pub struct CompleteArgs {
    /// The model folder.
    pub model: PathBuf,
    /// The incomplete texture map (PNG or JPEG, the model's size).
    pub texture: PathBuf,
    /// Which texels were observed: an image of the map's size, observed where it is not black;
    /// default: every texel of the map that is not pure black (how occluded texels are left by
    /// texturing tools and by `surfcap appearance generate`).
    #[arg(long)]
    pub observed: Option<PathBuf>,
    /// Keep the observed texels as they are and fill only the missing ones (default: the
    /// model's whole texture, as thesis 4.6.2 shows it).
    #[arg(long)]
    pub keep_observed: bool,
    #[command(flatten)]
    pub flow: FlowArgs,
    #[command(flatten)]
    pub cache: CacheOpts,
    /// The texture map to write: .png, .jpg or .jpeg (the format follows the extension).
    #[arg(short, long, value_parser = crate::options::image_output)]
    pub output: PathBuf,
}

pub fn complete(ctx: &crate::Ctx, a: &CompleteArgs) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = vec![&a.model, &a.texture];
    if let Some(o) = &a.observed {
        inputs.push(o);
    }
    surfcap_mesh::output_path::check_not_input(&a.output, &inputs)?;
    let model = load(&a.model)?;
    let texture = TextureImage::read(&a.texture)?;
    let mask = model.mask();
    let observed_image = a.observed.as_deref().map(TextureImage::read).transpose()?;
    let observed_name = a.observed.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
    let (observed, missing) = appearance_requests::observed_texels(
        &model,
        &texture,
        &a.texture.display().to_string(),
        observed_image.as_ref().map(|o| (o, observed_name.as_str())),
    )?;
    let bar = crate::progress::Bar::new(ctx);
    let flow = a.flow.estimator(&a.cache, &bar)?;
    let estimate = |r: &TextureImage, t: &TextureImage, m: &TexelMask| flow.estimate(r, t, m);
    let t = Instant::now();
    let mut out = model.complete(&texture, &observed, &estimate)?;
    let seconds = t.elapsed().as_secs_f64();
    if a.keep_observed {
        appearance_requests::keep_observed(&mut out, &texture, &observed);
    }
    out.write(&a.output)?;
    let value = json!({"missing_texels": missing, "active_texels": mask.len(), "seconds": seconds, "output": a.output});
    ctx.result(&value, || {
        println!(
            "completed {missing} missing texels of {} ({:.1}%) in {seconds:.2} s",
            mask.len(),
            100.0 * missing as f64 / mask.len() as f64
        )
    });
    ctx.wrote([&a.output]);
    Ok(())
}

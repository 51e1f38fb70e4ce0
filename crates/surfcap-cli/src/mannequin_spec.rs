//! The built-in mannequin as the command line describes it (`surfcap synth` and `demo`): BVH
//! files and/or procedural motions, a body shape, a vertex count; notes on guessed BVH units.

use std::path::PathBuf;

use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::locomotion::Gait;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, clip_frames, mannequin_subject, mannequin_subject_size};
use surfcap_mesh::Subject;

#[derive(clap::Args, Debug, Clone)]
pub struct MannequinArgs {
    /// BVH files to retarget onto the mannequin (joints matched by CMU names), one sequence each.
    #[arg(long, num_args = 1..)]
    pub bvh: Vec<PathBuf>,
    /// Procedural motions, comma-separated: walk, jog, turn_left, turn_right, jump, idle.
    #[arg(long, value_delimiter = ',')]
    pub procedural: Vec<String>,
    /// Body shape: average, slim, heavy, or key=value pairs (height, torso_girth, limb_girth,
    /// leg_ratio, shoulder_ratio), e.g. "slim,height=1.95".
    #[arg(long, default_value = "average")]
    pub shape: String,
    /// Target vertex count of the mannequin (1,000 to 20,000).
    #[arg(long, default_value_t = 3000, value_parser = |s: &str| crate::options::whole_in(s, 1000, 20000))]
    pub vertices: usize,
    /// Seed of the procedural motions (same seed, same motion).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Frame rate of the subject, 0.1 to 10000 fps (default: 30, or the first BVH file's).
    #[arg(long, value_parser = crate::options::frame_rate)]
    pub fps: Option<f64>,
    /// Duration of each procedural motion in seconds, at most 3600 (default: 3, the jump 2).
    /// The subject's size is estimated before any work and checked against --max-memory and
    /// --max-disk.
    #[arg(long, value_parser = |s: &str| crate::options::positive_at_most(s, 3600.0))]
    pub duration: Option<f64>,
    /// Metres per BVH unit, 0.0001 to 100 (default: guessed from each file's rest-pose height
    /// and printed).
    #[arg(long, value_parser = |s: &str| crate::options::number_from(s, 1e-4, 100.0))]
    pub bvh_units: Option<f64>,
    /// Keep a UV atlas in the mannequin's topology (a cylindrical chart per bone,
    /// `surfcap_builtin::mannequin_atlas`), so it can carry a texture per frame (`surfcap
    /// appearance paint | generate | build`, then `synth ... --appearance`).
    #[arg(long)]
    pub uv_atlas: bool,
    /// Subject name (default: mannequin-<shape>).
    #[arg(long)]
    pub name: Option<String>,
    /// The subject cache folder to write.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Builds the subject the arguments describe.
pub fn build(ctx: &crate::Ctx, a: &MannequinArgs) -> anyhow::Result<Subject> {
    if a.bvh.is_empty() && a.procedural.is_empty() {
        anyhow::bail!("nothing to synthesise: give --bvh <files...> and/or --procedural walk,jog,...");
    }
    let gaits: Vec<Gait> = a.procedural.iter().map(|g| Gait::parse(g)).collect::<Result<_, _>>()?;
    let shape = BodyShape::parse(&a.shape)?;
    let mut m = mannequin(&shape, a.vertices)?;
    if a.uv_atlas {
        let atlas = surfcap_builtin::mannequin_atlas::mannequin_uv_atlas(&m);
        m.topology =
            surfcap_mesh::Topology::new(m.topology.n_vertices(), m.topology.triangles().to_vec(), Some(atlas))?;
    }
    let bvhs: Vec<_> = a.bvh.iter().map(|p| read_bvh(p)).collect::<Result<_, _>>()?;
    let fps = a.fps.unwrap_or_else(|| bvhs.first().map_or(30.0, |b| b.fps()));
    // Clips recorded at another rate are resampled to the subject's: said aloud, with where the
    // rate came from, so a 120 fps clip first in the list does not silently quadruple the rest.
    let other: Vec<String> = a
        .bvh
        .iter()
        .zip(&bvhs)
        .filter(|(_, b)| (b.fps() - fps).abs() > 1e-6 * fps)
        .map(|(p, b)| format!("{} ({} fps)", p.display(), surfcap_synthesis::words::fmt_number(b.fps())))
        .collect();
    if !other.is_empty() {
        let from = match (a.fps, a.bvh.first()) {
            (Some(_), _) => "--fps".to_string(),
            (None, Some(first)) => format!("the first file's, {}", first.display()),
            (None, None) => "the default".to_string(),
        };
        ctx.note(&format!(
            "the clips' frame rates differ: {} resampled to {} fps ({from}); --fps sets the subject's rate",
            other.join(", "),
            surfcap_synthesis::words::fmt_number(fps)
        ));
    }
    // The subject's size before any clip is made: every clip resampled to `fps`.
    let mut frames: Vec<f64> =
        bvhs.iter().map(|b| clip_frames(b.n_frames().saturating_sub(1) as f64 * b.frame_time, fps)).collect();
    frames.extend(gaits.iter().map(|g| clip_frames(a.duration.unwrap_or(g.duration()), fps)));
    let total: f64 = frames.iter().sum();
    let what = format!(
        "synthesising {total:.0} frames of {} vertices at {fps} fps{}",
        m.topology.n_vertices(),
        a.duration.map(|d| format!(" ({d} s per procedural motion)")).unwrap_or_default()
    );
    let mut lower = vec!["--fps", "--vertices"];
    if !gaits.is_empty() {
        lower.insert(0, "--duration");
    }
    ctx.check_size(&mannequin_subject_size(&m, &frames, what, lower.join(", ")), a.output.as_deref())?;
    let mut clips = Vec::new();
    for (path, b) in a.bvh.iter().zip(&bvhs) {
        let mpu = match a.bvh_units {
            Some(u) => u,
            None => {
                let (u, unit) = b.guess_metres_per_unit();
                ctx.note(&format!(
                    "{}: unit guessed as {unit} ({u} m; rest pose {:.2} m tall); --bvh-units overrides",
                    path.display(),
                    b.rest_height() * u
                ));
                u
            }
        };
        clips.push(Clip::from_bvh(path, b, &m, mpu)?);
    }
    for g in gaits {
        clips.push(Clip::procedural(&m, g, fps, a.duration.unwrap_or(g.duration()), a.seed)?);
    }
    let default_name = format!("mannequin-{}", a.shape.split(',').next().unwrap_or("custom"));
    Ok(mannequin_subject(a.name.as_deref().unwrap_or(&default_name), &m, &clips, fps)?)
}

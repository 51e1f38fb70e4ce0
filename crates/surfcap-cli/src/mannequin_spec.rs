//! The built-in subjects as the command line describes them (`surfcap make`, `demo`, and the
//! older flat `surfcap synth --bvh | --procedural | --head`): the mannequin from BVH files and/or
//! procedural motions, a body shape, a vertex count, with notes on guessed BVH units; the head
//! scan bent into its sequences; and the subject cache they are written to.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use surfcap_builtin::head_motion::{head_motion_size, head_motion_subject};

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
        anyhow::bail!("nothing to build: give --bvh <files...> and/or --procedural walk,jog,...");
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

/// The head scan of `head` (a folder's `template.obj`, or an OBJ) bent into nod, turn and tilt
/// sequences of `frames_per_sequence` frames (`surfcap_builtin::head_motion`), keeping its UV
/// atlas; its size is checked against --max-memory and --max-disk before any frame is made.
pub fn head_subject(
    ctx: &crate::Ctx,
    head: &Path,
    frames_per_sequence: usize,
    name: Option<&str>,
    output: &Path,
) -> anyhow::Result<Subject> {
    let obj = if head.is_dir() { head.join("template.obj") } else { head.to_path_buf() };
    let mesh = surfcap_formats::obj::read_obj(&obj)?;
    let topology = mesh.topology().map_err(|e| e.in_file(&obj))?;
    anyhow::ensure!(
        topology.uv().is_some(),
        "{}: the scan has no texture coordinates: expected a UV-mapped mesh (`vt` on every face corner)",
        obj.display()
    );
    ctx.check_size(&head_motion_size(topology.n_vertices(), frames_per_sequence), Some(output))?;
    let mut s = head_motion_subject(&topology, &mesh.positions, frames_per_sequence, "arbitrary")
        .map_err(|e| e.in_file(&obj))?;
    if let Some(n) = name {
        s.name = n.to_string();
    }
    Ok(s)
}

/// What to build: the mannequin, or the head scan with its frames per sequence.
pub enum Built<'a> {
    Mannequin(&'a MannequinArgs),
    Head { scan: &'a Path, frames_per_sequence: usize, name: Option<&'a str> },
}

/// Builds a built-in subject and writes it as a subject cache at `output` (never over one of
/// its inputs), then prints what it holds (or its JSON).
pub fn build_and_write(ctx: &crate::Ctx, what: Built, output: &Path) -> anyhow::Result<()> {
    let inputs: Vec<&Path> = match &what {
        Built::Mannequin(a) => a.bvh.iter().map(|p| p.as_path()).collect(),
        Built::Head { scan, .. } => vec![*scan],
    };
    surfcap_mesh::output_path::check_not_input(output, &inputs)?;
    let t0 = Instant::now();
    let s = match what {
        Built::Head { scan, frames_per_sequence, name } => head_subject(ctx, scan, frames_per_sequence, name, output)?,
        Built::Mannequin(a) => build(ctx, a)?,
    };
    let bar = crate::progress::Bar::new(ctx);
    surfcap_mesh::cache::write_cache(output, &s, ctx.force, &bar)?;
    let secs = t0.elapsed().as_secs_f64();
    let sequences: Vec<serde_json::Value> =
        s.sequences().iter().map(|q| json!({ "name": q.name, "frames": q.n_frames(), "tags": q.tags })).collect();
    let result = json!({
        "subject": s.name,
        "output": output,
        "fps": s.fps,
        "vertices": s.topology().n_vertices(),
        "triangles": s.topology().n_triangles(),
        "sequences": sequences,
        "seconds": secs,
    });
    ctx.result(&result, || {
        println!(
            "made {:?}: {} vertices, {} triangles, {} fps -> {} ({secs:.2} s)",
            s.name,
            s.topology().n_vertices(),
            s.topology().n_triangles(),
            s.fps,
            output.display()
        );
        for q in s.sequences() {
            println!(
                "  {:<12} {:>12}  tags {}",
                q.name,
                crate::output::count_of(q.n_frames(), "frame"),
                q.tags.join(", ")
            );
        }
    });
    Ok(())
}

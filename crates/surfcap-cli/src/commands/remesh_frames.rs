//! `surfcap remesh-frames <subject> -o out.frames --seed S [--vertices N] [--sequences a,b]
//! [--frames K]`: a frame set with known answers: every frame of a
//! shared-topology subject re-meshed on its own (Botsch-Kobbelt isotropic re-meshing onto the
//! frame's surface, `surfcap_builtin::frame_remeshing`), so each frame has its own vertices and
//! triangles, as the per-frame reconstructions of Huang et al. 2009; each new vertex's source
//! triangle and barycentric coordinates are written as `correspondence_<k>.npy`.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_builtin::frame_remeshing::{RemeshFramesOptions, remesh_subject_frames, remeshed_frames_size};

use crate::options::{SourceOpts, open};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject (one topology): a subject cache or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// The frame set folder to write (`.frames`).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Seed of the per-frame variation (target edge length within +-10%, processing and vertex
    /// order): the same seed gives the same frames, whatever the thread count.
    #[arg(long, default_value = "0")]
    pub seed: u64,
    /// Vertices wanted per frame before the +-10% edge-length variation (default: the subject's
    /// vertex count); the frame set's size is checked against --max-memory and --max-disk before
    /// any work.
    #[arg(long, value_parser = crate::options::count)]
    pub vertices: Option<usize>,
    /// Only these sequences, in this order (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    /// Only the first K frames of each sequence.
    #[arg(long, value_parser = crate::options::count)]
    pub frames: Option<usize>,
    /// Re-meshing rounds (split, collapse, flip, smooth and project), 1 to 100: the edge
    /// lengths settle within the default 5 to 10 rounds, so 100 bounds the time with room to spare.
    #[arg(long, default_value = "5", value_parser = |s: &str| crate::options::whole_in(s, 1, 100))]
    pub iterations: usize,
    #[command(flatten)]
    pub source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    surfcap_mesh::output_path::check_not_input(&a.output, &[&a.subject])?;
    let s = open(ctx, &a.subject, &a.source)?;
    let frames: usize = s
        .sequences()
        .iter()
        .filter(|q| a.sequences.is_empty() || a.sequences.contains(&q.name))
        .map(|q| a.frames.map_or(q.n_frames(), |k| k.min(q.n_frames())))
        .sum();
    let vertices = a.vertices.unwrap_or(s.topology().n_vertices());
    ctx.check_size(&remeshed_frames_size(frames, vertices, rayon::current_num_threads()), Some(&a.output))?;
    let t0 = Instant::now();
    let opts = RemeshFramesOptions {
        seed: a.seed,
        target_vertices: a.vertices,
        sequences: a.sequences.clone(),
        frames: a.frames,
        iterations: a.iterations,
    };
    let bar = crate::progress::Bar::new(ctx);
    let set = remesh_subject_frames(&s, &opts, &bar)?;
    let remesh_secs = t0.elapsed().as_secs_f64();
    surfcap_mesh::frame_set_cache::write_frame_set(&a.output, &set, ctx.force, &bar)?;
    let (vlo, vhi) = set.vertex_count_range();
    let (tlo, thi) = set.triangle_count_range();
    let per_frame = remesh_secs / set.frame_count() as f64;
    ctx.result(
        &json!({
            "frame_set": set.name,
            "output": a.output,
            "seed": a.seed,
            "source_vertices": s.topology().n_vertices(),
            "source_triangles": s.topology().n_triangles(),
            "sequences": set.sequences().iter().map(|q| q.name.clone()).collect::<Vec<_>>(),
            "frames": set.frame_count(),
            "vertices": { "min": vlo, "max": vhi },
            "triangles": { "min": tlo, "max": thi },
            "remesh_seconds": remesh_secs,
            "seconds_per_frame": per_frame,
        }),
        || {
            println!(
                "re-meshed {} of {:?} ({} vertices each) on their own: {vlo}-{vhi} vertices, {tlo}-{thi} triangles per frame -> {} ({remesh_secs:.2} s, {per_frame:.2} s per frame)",
                crate::output::count_of(set.frame_count(), "frame"),
                s.name,
                s.topology().n_vertices(),
                a.output.display()
            );
        },
    );
    Ok(())
}

//! `surfcap import <sources...> -o <subject>`

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use crate::options::SourceOpts;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Sources: shared-data sequence or dataset folders (template.obj + positions.npy), folders
    /// of OBJ or PLY frames, .obj/.ply/.glb files, surfcap.toml manifests, subject caches.
    #[arg(required = true)]
    pub sources: Vec<PathBuf>,
    /// The subject cache folder to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Subject name (default: from the manifest or the first source).
    #[arg(long)]
    pub name: Option<String>,
    #[command(flatten)]
    pub source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let bar = crate::progress::Bar::new(ctx);
    let imported = surfcap_mesh::import::import(&a.sources, &a.source.to_import(a.name.clone())?, &bar)?;
    for n in &imported.notes {
        ctx.note(n);
    }
    // What each source was read as, so a folder read in an unexpected way is seen.
    for src in &imported.sources {
        ctx.say(&format!(
            "read {}: {} -> sequence {:?}, {} frame{}",
            src.origin.display(),
            src.layout,
            src.sequence,
            src.frames,
            if src.frames == 1 { "" } else { "s" }
        ));
    }
    let s = &imported.subject;
    surfcap_mesh::cache::write_cache(&a.output, s, &bar)?;
    let secs = t0.elapsed().as_secs_f64();
    ctx.result(
        &json!({
            "subject": s.name,
            "output": a.output,
            "sequences": s.sequences().len(),
            "frames": s.n_frames(),
            "vertices": s.topology().n_vertices(),
            "triangles": s.topology().n_triangles(),
            "notes": imported.notes,
            "sources": imported.sources.iter().map(|src| json!({
                "sequence": src.sequence,
                "origin": src.origin,
                "layout": src.layout.to_string(),
                "frames": src.frames,
            })).collect::<Vec<_>>(),
            "seconds": secs,
        }),
        || {
            println!(
                "imported {:?}: {} sequences, {} frames, {} vertices, {} triangles -> {} ({secs:.2} s)",
                s.name,
                s.sequences().len(),
                s.n_frames(),
                s.topology().n_vertices(),
                s.topology().n_triangles(),
                a.output.display()
            );
        },
    );
    Ok(())
}

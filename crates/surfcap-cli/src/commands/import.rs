//! `surfcap import <sources...> -o <subject>`: a subject cache, or a `.frames` folder when the
//! sources are a frame set (every frame its own vertices and triangles, as in Huang et al.
//! 2009) or `--as-frame-set` is given.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use surfcap_formats::import::{ImportedData, ImportedFrames};
use surfcap_mesh::FrameSet;

use crate::options::SourceOpts;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Sources: shared-data sequence or dataset folders (template.obj + positions.npy), folders
    /// of OBJ or PLY frames, .obj/.ply/.glb files, surfcap.toml manifests, subject caches.
    #[arg(required = true)]
    pub sources: Vec<PathBuf>,
    /// The subject cache folder to write; for a frame set (sources whose frames have their own
    /// vertices and triangles), a `.frames` folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write a subject as a frame set (`.frames`: every frame with its own copy of the
    /// triangles), as Huang et al.'s surface motion graph reads them. Implied by `-o x.frames`.
    #[arg(long)]
    pub as_frame_set: bool,
    /// Subject name (default: from the manifest; else what the sources' names share, a prefix
    /// ending at a word or the folder they lie in; else the first source's name).
    #[arg(long)]
    pub name: Option<String>,
    /// Give in-place clips (centre of mass not travelling, as game clips are authored) the
    /// travel their feet imply: `contacts` recovers it from the vertices' ground contacts
    /// (low, vertically still vertices; the step that keeps the planted foot still). Clips
    /// that travel are left as they are; changed ones get the tag root_motion_from_contacts.
    #[arg(long, value_enum, default_value = "none")]
    pub root_motion: RootMotion,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// Where in-place clips get root motion from.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RootMotion {
    /// Keep the clips as they are.
    None,
    /// Recover it from ground contacts.
    Contacts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let inputs: Vec<&std::path::Path> = a.sources.iter().map(PathBuf::as_path).collect();
    surfcap_mesh::output_path::check_not_input(&a.output, &inputs)?;
    let t0 = Instant::now();
    let bar = crate::progress::Bar::new(ctx);
    let opts = a.source.to_import(a.name.clone())?;
    let imported = match surfcap_formats::import::import_any(&a.sources, &opts, &bar)? {
        ImportedData::Subject(i) => i,
        ImportedData::FrameSet(f) => return write_frame_set(ctx, &a, f, t0),
    };
    for n in &imported.notes {
        ctx.note(n);
    }
    // What each source was read as, so a folder read in an unexpected way is seen.
    for src in &imported.sources {
        ctx.say(&format!(
            "read {}: {} -> sequence {:?}, {}",
            src.origin.display(),
            src.layout,
            src.sequence,
            crate::output::count_of(src.frames, "frame")
        ));
    }
    // Several sources: say which name the subject got and why, as it names every output.
    if a.name.is_none() && a.sources.len() > 1 {
        let (name, from) = surfcap_formats::import::default_subject_name(&a.sources);
        if imported.subject.name == name {
            ctx.note(&format!("subject named {name:?} after {from}; --name gives it another"));
        }
    }
    let mut s = imported.subject;
    let mut recovered = Vec::new();
    if a.root_motion == RootMotion::Contacts {
        let params = surfcap_geometry::root_motion_from_contacts::ContactParams::default();
        (s, recovered) = surfcap_motion::in_place_root_motion::recover_in_place_root_motion(s, &params)?;
        if recovered.is_empty() {
            ctx.note("--root-motion contacts: no clip is in place; nothing changed");
        }
        for r in &recovered {
            ctx.note(&format!(
                "{}: root motion recovered from ground contacts ({} of {} frame steps with contact): net displacement {} -> {}",
                r.sequence,
                r.contact_steps,
                r.frames.saturating_sub(1),
                crate::output::length(r.before, &s.units, 2),
                crate::output::length(r.after, &s.units, 2)
            ));
        }
    }
    let s = &s;
    if a.as_frame_set || is_frames_path(&a.output) {
        let mut notes = imported.notes;
        for q in s.sequences().iter().filter(|q| q.joints.is_some()) {
            notes.push(format!(
                "sequence {:?}: its ground-truth joints are not kept in a frame set (they belong to one topology)",
                q.name
            ));
        }
        let f = ImportedFrames {
            frame_set: FrameSet::from_subject(s),
            notes,
            sources: imported.sources,
            frame_set_origin: None,
        };
        return write_frame_set(ctx, &a, f, t0);
    }
    surfcap_mesh::cache::write_cache(&a.output, s, ctx.force, &bar)?;
    // Clips authored as loops (last pose within the clip's largest step of the first, in the
    // body frame): synthesis plays their last frame into their start.
    let loops: Vec<&str> =
        surfcap_motion::clip_loops::clip_loops(s).iter().map(|l| s.sequences()[l.sequence].name.as_str()).collect();
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
            "loops": loops,
            "root_motion_from_contacts": recovered.iter().map(|r| json!({ "sequence": r.sequence,
                "net_displacement_before": r.before, "net_displacement_after": r.after,
                "contact_steps": r.contact_steps, "frames": r.frames })).collect::<Vec<_>>(),
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
                "imported {:?}: {}, {}, {} vertices, {} triangles -> {} ({secs:.2} s)",
                s.name,
                crate::output::count_of(s.sequences().len(), "sequence"),
                crate::output::count_of(s.n_frames(), "frame"),
                s.topology().n_vertices(),
                s.topology().n_triangles(),
                a.output.display()
            );
            if !loops.is_empty() {
                println!("loops: {} (played seamlessly from the last frame to the first)", loops.join(", "));
            }
        },
    );
    Ok(())
}

fn is_frames_path(p: &std::path::Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("frames"))
}

/// Writes a frame set folder, refusing an output named like a subject cache.
fn write_frame_set(ctx: &crate::Ctx, a: &Args, f: ImportedFrames, t0: Instant) -> anyhow::Result<()> {
    if a.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("subject")) {
        let first = f.notes.first().map(|n| format!(" ({n})")).unwrap_or_default();
        anyhow::bail!(
            "{}: the sources are a frame set, not a subject{first}: write it as a frame set folder, e.g. -o {}",
            a.output.display(),
            a.output.with_extension("frames").display()
        );
    }
    if a.root_motion == RootMotion::Contacts {
        anyhow::bail!("--root-motion contacts needs one shared topology: these sources are a frame set");
    }
    for n in &f.notes {
        ctx.note(n);
    }
    for src in &f.sources {
        ctx.say(&format!(
            "read {}: {} -> sequence {:?}, {}",
            src.origin.display(),
            src.layout,
            src.sequence,
            crate::output::count_of(src.frames, "frame")
        ));
    }
    let set = &f.frame_set;
    let bar = crate::progress::Bar::new(ctx);
    surfcap_mesh::frame_set_cache::write_frame_set(&a.output, set, ctx.force, &bar)?;
    let secs = t0.elapsed().as_secs_f64();
    let (vlo, vhi) = set.vertex_count_range();
    let (tlo, thi) = set.triangle_count_range();
    ctx.result(
        &json!({
            "frame_set": set.name,
            "output": a.output,
            "sequences": set.sequences().len(),
            "frames": set.frame_count(),
            "vertices": { "min": vlo, "max": vhi },
            "triangles": { "min": tlo, "max": thi },
            "notes": f.notes,
            "sources": f.sources.iter().map(|src| json!({
                "sequence": src.sequence,
                "origin": src.origin,
                "layout": src.layout.to_string(),
                "frames": src.frames,
            })).collect::<Vec<_>>(),
            "seconds": secs,
        }),
        || {
            println!(
                "imported frame set {:?}: {}, {}, {vlo}-{vhi} vertices, {tlo}-{thi} triangles per frame -> {} ({secs:.2} s)",
                set.name,
                crate::output::count_of(set.sequences().len(), "sequence"),
                crate::output::count_of(set.frame_count(), "frame"),
                a.output.display()
            );
        },
    );
    Ok(())
}

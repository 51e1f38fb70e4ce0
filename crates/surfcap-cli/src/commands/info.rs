//! `surfcap info <subject | frame set>`: a subject's summary, or a frame set's (sequences,
//! frames, the range of vertex and triangle counts per frame: every frame its own mesh).

use std::path::PathBuf;

use serde_json::json;
use surfcap_formats::import::ImportedData;
use surfcap_mesh::FrameSet;

use crate::options::SourceOpts;
use crate::subject_summary::{describe, print_summary};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, a frame set folder (`.frames`), or any source `surfcap import` reads.
    pub subject: PathBuf,
    #[command(flatten)]
    pub source: SourceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let bar = crate::progress::Bar::new(ctx);
    match surfcap_formats::import::open_any(&a.subject, &a.source.to_import(None)?, &bar)? {
        ImportedData::Subject(i) => {
            for n in &i.notes {
                ctx.note(n);
            }
            let s = i.subject;
            let d = describe(&s);
            ctx.result(&d, || print_summary(&s, &d));
        }
        ImportedData::FrameSet(f) => {
            for n in &f.notes {
                ctx.note(n);
            }
            let d = describe_frame_set(&f.frame_set);
            ctx.result(&d, || print_frame_set(&f.frame_set));
        }
    }
    Ok(())
}

/// A frame set's summary as JSON.
fn describe_frame_set(s: &FrameSet) -> serde_json::Value {
    let range = |(lo, hi): (usize, usize)| json!({ "min": lo, "max": hi });
    json!({
        "frame_set": s.name,
        "fps": s.fps,
        "up_axis": s.up_axis.as_str(),
        "units": s.units,
        "frames": s.frame_count(),
        "shared_topology": s.first_topology_difference().is_none(),
        "vertices": range(s.vertex_count_range()),
        "triangles": range(s.triangle_count_range()),
        "sequences": s.sequences().iter().map(|q| json!({
            "name": q.name,
            "frames": q.n_frames(),
            "seconds": q.n_frames() as f64 / s.fps,
            "tags": q.tags,
            "vertices": range(q.vertex_count_range()),
            "triangles": range(q.triangle_count_range()),
            "known_correspondence": q.correspondence().is_some(),
        })).collect::<Vec<_>>(),
    })
}

fn print_frame_set(s: &FrameSet) {
    let (vlo, vhi) = s.vertex_count_range();
    let (tlo, thi) = s.triangle_count_range();
    println!("frame set   {} (every frame has its own vertices and triangles)", s.name);
    println!(
        "frames      {} in {} at {} fps",
        s.frame_count(),
        crate::output::count_of(s.sequences().len(), "sequence"),
        s.fps
    );
    println!("vertices    {vlo} to {vhi} per frame");
    println!("triangles   {tlo} to {thi} per frame");
    println!("up axis     {}", s.up_axis.as_str());
    println!("units       {}", crate::output::units_line(&s.units));
    println!("sequences");
    let w = s.sequences().iter().map(|q| q.name.len()).max().unwrap_or(4).max(4);
    for q in s.sequences() {
        let (vlo, vhi) = q.vertex_count_range();
        let (tlo, thi) = q.triangle_count_range();
        let known = if q.correspondence().is_some() { "  known correspondence" } else { "" };
        let tags = if q.tags.is_empty() { String::new() } else { format!("  [{}]", q.tags.join(", ")) };
        println!(
            "  {:w$}  {:5} frames  {:7.2} s  vertices {vlo}-{vhi}  triangles {tlo}-{thi}{tags}{known}",
            q.name,
            q.n_frames(),
            q.n_frames() as f64 / s.fps
        );
    }
}

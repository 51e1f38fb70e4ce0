//! `surfcap view`: plays sequences in the browser (see `surfcap-view`). Accepts anything
//! `surfcap import` reads (a glb, a subject cache, a capture folder, a frame set: a `.frames`
//! folder or its glb, every frame its own mesh) and report folders written by `surfcap report`
//! or `surfcap demo`; several at once play side by side. A synthesis output (`x.glb`,
//! `x.frames`) shows what its report `x.report.json` holds (see [`overlay_of`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use surfcap_formats::import::ImportedData;
use surfcap_view::server::{ServeOptions, serve};
use surfcap_view::{Overlay, ViewItem};

use crate::options::{PortOpt, SourceOpts};
use crate::output::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to play: .glb files, subject caches, frame sets (.frames), capture folders, or a report folder.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    #[command(flatten)]
    pub port: PortOpt,
    /// Only these sequences (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    #[command(flatten)]
    pub source: SourceOpts,
}

/// Whether `p` is a report folder (an `index.html` and no subject cache).
fn is_report(p: &Path) -> bool {
    p.is_dir() && p.join("index.html").is_file() && !surfcap_mesh::cache::is_cache(p)
}

/// What a synthesis report (`x.report.json` next to the output `x.glb` or `x.frames`) adds to
/// the animation: the achieved centres (one per frame), the requested path when there is one,
/// the frames where a transition lands, and a line per constraint.
fn overlay_of(output: &Path, frames: usize) -> Option<Overlay> {
    let report = surfcap_synthesis::report_path(output);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(report).ok()?).ok()?;
    let points = |x: &serde_json::Value| -> Option<Vec<[f64; 3]>> {
        x.as_array()?.iter().map(|p| Some([p[0].as_f64()?, p[1].as_f64()?, p[2].as_f64()?])).collect()
    };
    let curve = points(&v["curve"]);
    let centres = points(&v["per_frame"]["centre"])?;
    let transitions: Vec<usize> = v["transition_frames"]
        .as_array()
        .map(|t| t.iter().filter_map(|f| f.as_u64().map(|f| f as usize)).filter(|&f| f < frames).collect())
        .unwrap_or_default();
    let constraints = serde_json::from_value::<Vec<surfcap_synthesis::Constraint>>(v["constraints"].clone())
        .map(|c| c.iter().map(surfcap_synthesis::Constraint::summary).collect())
        .unwrap_or_default();
    (centres.len() == frames).then_some(Overlay { curve, centres, transitions, constraints })
}

/// Whether `p` may be a synthesis output with a report beside it (a `.glb` or a `.frames` folder).
fn is_output(p: &Path) -> bool {
    p.extension().is_some_and(|x| x == "glb" || x == "frames")
}

/// The frames' textures of a frame-set glb with a texture per frame (written by
/// `surfcap_formats::glb_frame_set::write_glb_frame_set_textured`, which counts them in the
/// root's `extras.surfcap.textures`); `None` for anything else. The file is read a second time
/// only when it has textures.
fn glb_textures(p: &Path) -> anyhow::Result<Option<surfcap_mesh::FrameTextures>> {
    if !p.extension().is_some_and(|x| x.eq_ignore_ascii_case("glb")) {
        return Ok(None);
    }
    let bytes = surfcap_mesh::read_regular_file(p)?;
    let textured = surfcap_formats::glb_frame_set::frame_set_meta(&bytes)
        .is_some_and(|m| m["textures"].as_u64().is_some_and(|n| n > 0));
    if !textured {
        return Ok(None);
    }
    let (_, textures) =
        surfcap_formats::glb_frame_set::parse_glb_frame_set_textured(&bytes, "").map_err(|e| e.in_file(p))?;
    Ok(textures)
}

/// The items of what `p` holds (a subject's or a frame set's), with the overlay of the report
/// beside `output` when it has one sequence; the names of all its sequences are added to
/// `names` (for the message when a `--sequences` name is none of them).
fn open_items(
    ctx: &crate::Ctx,
    p: &Path,
    a: &Args,
    output: Option<&Path>,
    names: &mut Vec<String>,
) -> anyhow::Result<Vec<ViewItem>> {
    let bar = crate::progress::Bar::new(ctx);
    let mut items = match surfcap_formats::import::open_any(p, &a.source.to_import(None)?, &bar)? {
        ImportedData::Subject(i) => {
            for n in &i.notes {
                ctx.note(n);
            }
            let single = i.subject.sequences().len() == 1;
            names.extend(i.subject.sequences().iter().map(|q| q.name.clone()));
            (crate::view_items::view_items(&i.subject, &a.sequences), single)
        }
        ImportedData::FrameSet(f) => {
            let single = f.frame_set.sequences().len() == 1;
            names.extend(f.frame_set.sequences().iter().map(|q| q.name.clone()));
            // A textured glb of a subject (every frame the same mesh, written as a frame set so
            // that each frame has its material) plays with one topology: one index array.
            match glb_textures(p)? {
                Some(t) if f.frame_set.first_topology_difference().is_none() => {
                    let s = f.frame_set.into_subject()?;
                    (crate::view_items::view_items_textured(&s, &t, &a.sequences)?, single)
                }
                t => (crate::view_items::frame_set_items(&f.frame_set, t.as_ref(), &a.sequences)?, single),
            }
        }
    };
    for item in &mut items.0 {
        item.overlay = output.filter(|_| items.1).and_then(|g| overlay_of(g, item.n_frames));
    }
    Ok(items.0)
}

/// The items of what `a` names and the report folder among them, if any: what `surfcap view`
/// serves and `surfcap render` renders.
pub fn load(ctx: &crate::Ctx, a: &Args) -> anyhow::Result<(Vec<ViewItem>, Option<PathBuf>)> {
    let mut items = Vec::new();
    let mut report = None;
    let mut names = Vec::new();
    for p in &a.paths {
        anyhow::ensure!(p.exists(), "view {}: no such file or folder", p.display());
        if is_report(p) {
            anyhow::ensure!(report.is_none(), "view {}: only one report folder at a time", p.display());
            let glbs = crate::files::files_under(p, &["glb"])?;
            anyhow::ensure!(!glbs.is_empty(), "view {}: the report folder holds no .glb animation", p.display());
            for g in glbs {
                items.extend(open_items(ctx, &g, a, Some(&g), &mut names)?);
            }
            report = Some(p.clone());
        } else {
            items.extend(open_items(ctx, p, a, is_output(p).then_some(p.as_path()), &mut names)?);
        }
    }
    // Every name asked for must exist: a misspelt one is named with the sequences there are,
    // rather than silently left out.
    let mut known: Vec<String> = Vec::new();
    for n in names {
        if !known.contains(&n) {
            known.push(n);
        }
    }
    if let Some(missing) = a.sequences.iter().find(|n| !known.contains(n)) {
        anyhow::bail!("--sequences: no sequence named {missing:?} in what was given; it has {}", known.join(", "));
    }
    anyhow::ensure!(!items.is_empty(), "view: nothing to play in what was given");
    Ok((items, report))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (items, report) = load(ctx, &a)?;
    let n = items.len();
    let json = ctx.json;
    serve(items, ServeOptions { port: a.port.port, report }, |addr| {
        let url = format!("http://{addr}/");
        if json {
            print_json(&serde_json::json!({ "url": url, "sequences": n }));
        } else {
            println!("{url}");
            eprintln!("surfcap view: playing {} at {url} (Ctrl-C to stop)", crate::output::count_of(n, "sequence"));
        }
        let _ = std::io::stdout().flush();
    })?;
    Ok(())
}

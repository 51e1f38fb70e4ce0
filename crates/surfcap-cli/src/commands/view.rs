//! `surfcap view`: plays sequences in the browser (see `surfcap-view`). Accepts anything
//! `surfcap import` reads (a glb, a subject cache, a capture folder, a frame set: a `.frames`
//! folder or its glb, every frame its own mesh) and report folders written by `surfcap report`
//! or `surfcap demo`; several at once play side by side. A synthesis output (`x.glb`,
//! `x.frames`) shows what its report `x.report.json` holds (see [`overlay_of`]). A compact
//! stream (`.scstream`) or a skinned rig (`surfcap rig`'s glb) is decoded and played by the
//! page itself (see `view_played`).

use std::io::Write;
use std::path::{Path, PathBuf};

use surfcap_formats::import::ImportedData;
use surfcap_view::server::{ServeOptions, serve_directed};
use surfcap_view::{Overlay, ViewItem};

use crate::options::{PortOpt, SourceOpts};
use crate::output::print_json;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub shown: Shown,
    #[command(flatten)]
    pub port: PortOpt,
    #[command(flatten)]
    pub source: SourceOpts,
    #[command(flatten)]
    pub direct: crate::view_director::DirectOpts,
}

/// What is shown and how it is coloured: the options `view` and `render` share.
#[derive(clap::Args, Debug, Clone)]
pub struct Shown {
    /// What to play: .glb files (skinned rigs too), compact streams (.scstream), subject caches, frame sets (.frames), capture folders, or a report folder.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Only these sequences (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    /// The labels drawn over the figures, one per sequence shown, in order (comma-separated;
    /// default: each sequence's name).
    #[arg(long, value_delimiter = ',')]
    pub labels: Vec<String>,
    /// Colour every vertex by its distance from the same vertex of this ground truth (anything
    /// `import` reads, same mesh), frame by frame after the rigid alignment that fits the truth
    /// best: a transfer's error against the target's own motion. With a colour bar in the
    /// subject's unit.
    #[arg(long, value_name = "TRUTH", conflicts_with_all = ["distance_from", "strain"])]
    pub error_against: Option<PathBuf>,
    /// Colour every vertex by its distance from the same vertex of the motion it was made from
    /// (a variant's source; same mesh), frame by frame after the best rigid alignment (the body
    /// frame), in the subject's unit.
    #[arg(long, value_name = "SOURCE", conflicts_with = "strain")]
    pub distance_from: Option<PathBuf>,
    /// The sequence of --error-against or --distance-from to compare with (default: the one of
    /// the shown sequence's name, else its only sequence).
    #[arg(long, value_name = "NAME")]
    pub reference_sequence: Option<String>,
    /// Colour every vertex by its edge-length strain against the sequence's first frame: the
    /// mean over the edges meeting there of |length / first-frame length - 1|, in percent (10:
    /// edges 10% longer or shorter; 0 where the surface only moves rigidly).
    #[arg(long)]
    pub strain: bool,
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
    let centre_errors: Option<Vec<f64>> =
        v["per_frame"]["error"].as_array().and_then(|e| e.iter().map(|x| x.as_f64()).collect());
    let transitions: Vec<usize> = v["transition_frames"]
        .as_array()
        .map(|t| t.iter().filter_map(|f| f.as_u64().map(|f| f as usize)).filter(|&f| f < frames).collect())
        .unwrap_or_default();
    let constraints = serde_json::from_value::<Vec<surfcap_synthesis::Constraint>>(v["constraints"].clone())
        .map(|c| c.iter().map(surfcap_synthesis::Constraint::summary).collect())
        .unwrap_or_default();
    let centre_errors = centre_errors.filter(|e| e.len() == frames);
    (centres.len() == frames).then_some(Overlay { curve, centres, transitions, constraints, centre_errors })
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
    a: &Shown,
    source: &SourceOpts,
    output: Option<&Path>,
    names: &mut Vec<String>,
) -> anyhow::Result<Vec<ViewItem>> {
    let bar = crate::progress::Bar::new(ctx);
    let mut items = match surfcap_formats::import::open_any(p, &source.to_import(None)?, &bar)? {
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
pub fn load(ctx: &crate::Ctx, a: &Shown, source: &SourceOpts) -> anyhow::Result<(Vec<ViewItem>, Option<PathBuf>)> {
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
                items.extend(open_items(ctx, &g, a, source, Some(&g), &mut names)?);
            }
            report = Some(p.clone());
        } else if let Some(played) = crate::view_played::played_items(p, &a.sequences, &mut names)? {
            // A stream or a rig, decoded by the page; a rig from synthesis shows its report.
            let single = played.len() == 1 && is_output(p);
            items.extend(played.into_iter().map(|mut it| {
                it.overlay = overlay_of(p, it.n_frames).filter(|_| single);
                it
            }));
        } else {
            items.extend(open_items(ctx, p, a, source, is_output(p).then_some(p.as_path()), &mut names)?);
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
    if !a.labels.is_empty() {
        anyhow::ensure!(
            a.labels.len() == items.len(),
            "--labels: {} given for {} (one per sequence shown, in order: {})",
            a.labels.len(),
            crate::output::count_of(items.len(), "sequence"),
            items.iter().map(|it| it.name.as_str()).collect::<Vec<_>>().join(", ")
        );
        for (it, l) in items.iter_mut().zip(&a.labels) {
            it.label = Some(l.clone());
        }
    }
    add_colour_maps(ctx, a, source, &mut items)?;
    Ok((items, report))
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (items, report) = load(ctx, &a.shown, &a.source)?;
    let n = items.len();
    let json = ctx.json;
    let director = crate::view_director::director(ctx, &a.direct, &a.shown.paths, &a.source)?;
    serve_directed(items, ServeOptions { port: a.port.port, report }, director, |addr| {
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

/// What the colour-map options ask for, given to every item: the distance from a reference
/// (`--error-against`, `--distance-from`) or the edge strain (`--strain`).
fn add_colour_maps(ctx: &crate::Ctx, a: &Shown, source: &SourceOpts, items: &mut [ViewItem]) -> anyhow::Result<()> {
    use rayon::prelude::*;
    use surfcap_geometry::vertex_edge_strain::{unique_edges, vertex_edge_strain};
    use surfcap_geometry::vertex_rigid_distance::vertex_rigid_distance;
    use surfcap_view::VertexField;
    let reference = match (&a.error_against, &a.distance_from) {
        (Some(p), _) => Some(("--error-against", p, "transfer error against")),
        (None, Some(p)) => Some(("--distance-from", p, "distance from")),
        _ => None,
    };
    if reference.is_none() && a.reference_sequence.is_some() {
        anyhow::bail!("--reference-sequence: give --error-against or --distance-from too");
    }
    if reference.is_none() && !a.strain {
        return Ok(());
    }
    for it in items.iter() {
        anyhow::ensure!(
            it.played.is_none(),
            "{}: a colour map is computed from positions decoded here; a stream or a rig is decoded by the page (view its source instead)",
            it.name
        );
        anyhow::ensure!(
            it.frame_vertices.is_none(),
            "{}: a colour map needs one mesh for every frame; this is a frame set (every frame its own mesh)",
            it.name
        );
    }
    let nv = |it: &ViewItem| it.n_vertices;
    let frame = |it: &ViewItem, f: usize| -> Vec<f32> {
        // Textured items have their vertices split along seams: colour maps use the mesh's own.
        it.positions[3 * nv(it) * f..3 * nv(it) * (f + 1)].to_vec()
    };
    if a.strain {
        for it in items.iter_mut() {
            anyhow::ensure!(!it.faces.is_empty(), "{}: --strain needs the mesh's triangles", it.name);
            let t = surfcap_mesh::Topology::new(
                it.n_vertices,
                it.faces.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                None,
            )?;
            let edges = unique_edges(&t);
            let rest = frame(it, 0);
            // In percent: 10 = edges 10% longer or shorter than at the first frame.
            let values: Vec<f32> = (0..it.n_frames)
                .into_par_iter()
                .flat_map_iter(|f| vertex_edge_strain(&edges, &rest, &frame(it, f)).into_iter().map(|s| 100.0 * s))
                .collect();
            it.field = Some(VertexField::new(
                "edge-length strain against the first frame".into(),
                "%".into(),
                format!("per vertex, the mean over its edges of |length / length at {}:0 - 1|, in percent", it.name),
                values,
            ));
        }
        return Ok(());
    }
    let (option, path, what) = reference.expect("checked above");
    let bar = crate::progress::Bar::new(ctx);
    let subject = match surfcap_formats::import::open_any(path, &source.to_import(None)?, &bar)
        .map_err(|e| anyhow::anyhow!("{option} {}: {e}", path.display()))?
    {
        ImportedData::Subject(i) => i.subject,
        ImportedData::FrameSet(f) => f.frame_set.into_subject().map_err(|e| {
            anyhow::anyhow!("{option} {}: a reference must have one mesh for every frame: {e}", path.display())
        })?,
    };
    let names: Vec<&str> = subject.sequences().iter().map(|q| q.name.as_str()).collect();
    for it in items.iter_mut() {
        let q = match &a.reference_sequence {
            Some(n) => subject.sequence(n).map(|(_, q)| q).ok_or_else(|| {
                anyhow::anyhow!(
                    "--reference-sequence: no sequence {n:?} in {}; it has {}",
                    path.display(),
                    names.join(", ")
                )
            })?,
            None => match subject.sequence(&it.name) {
                Some((_, q)) => q,
                None if names.len() == 1 => &subject.sequences()[0],
                None => anyhow::bail!(
                    "{option} {}: no sequence named {:?} there and more than one to choose from; name one with --reference-sequence ({})",
                    path.display(),
                    it.name,
                    names.join(", ")
                ),
            },
        };
        anyhow::ensure!(
            q.n_vertices() == it.n_vertices && !it.has_uvs(),
            "{option} {}: {} has {} vertices, {} has {}: a colour map compares vertex by vertex on the same mesh",
            path.display(),
            q.name,
            q.n_vertices(),
            it.name,
            it.n_vertices
        );
        let (n, m) = (it.n_frames, q.n_frames());
        if n != m {
            ctx.note(&format!(
                "{}: {} frames against {} of {}: each frame is compared with the reference frame at the same fraction of the sequence",
                it.name, n, m, q.name
            ));
        }
        // Frame f of the item against the reference's frame at the same fraction of its length.
        let at = |f: usize| if n <= 1 { 0 } else { ((f * (m - 1)) as f64 / (n - 1) as f64).round() as usize };
        let values: Vec<f32> =
            (0..n).into_par_iter().flat_map_iter(|f| vertex_rigid_distance(&frame(it, f), q.frame(at(f)))).collect();
        it.field = Some(VertexField::new(
            format!("{what} {}", q.name),
            it.units.clone(),
            format!(
                "per vertex, the distance from the same vertex of {} after the rigid alignment that fits that frame best",
                q.name
            ),
            values,
        ));
    }
    Ok(())
}

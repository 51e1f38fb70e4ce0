//! `surfcap parts propose|check|show`: a subject's body parts for motion transfer (thesis 5.4.2,
//! Fig. 5.2: a torso and four limbs that overlap their parent). `propose` writes the canonical
//! parts file from the subject's joints, connected components or the rigidity of its motion;
//! `check` reads a user's file (canonical, labels, cutting planes or vertex loops: see docs/formats.md,
//! "Body parts files") against the subject; `show` plays the subject in the viewer with one colour per
//! part and the overlaps shaded darker.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use serde::Serialize;
use surfcap_mesh::Subject;
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_file::read_parts_file;
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_view::ViewItem;
use surfcap_view::server::{ServeOptions, serve};

use crate::options::{PortOpt, SubjectArgs, count};
use crate::output::{count_of, print_json};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(clap::Subcommand, Debug)]
pub enum What {
    /// Propose parts (torso, arm_left, arm_right, leg_left, leg_right for 5) and write them as
    /// the canonical parts file.
    Propose {
        /// auto (joints if the sequences have them, else components if there are enough, else
        /// rigidity), joints, components or rigidity.
        #[arg(long, default_value = "auto", value_parser = parse_method)]
        method: Method,
        /// Number of parts: the torso and N - 1 limbs.
        #[arg(long, default_value_t = 5, value_parser = count)]
        parts: usize,
        /// Overlap: edge rings on each side of a child/parent boundary.
        #[arg(long, default_value_t = 2)]
        overlap_rings: usize,
        /// The parts file to write (JSON).
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        subject: SubjectArgs,
    },
    /// Check a parts file against a subject and print each part's vertices and overlap.
    Check {
        /// The parts file: canonical JSON, labels (JSON or one per line), planes or loops.
        #[arg(long)]
        parts: PathBuf,
        #[command(flatten)]
        subject: SubjectArgs,
    },
    /// Play the subject in the browser with one colour per part, overlaps darker.
    Show {
        /// The parts file (any form `check` reads).
        #[arg(long)]
        parts: PathBuf,
        #[command(flatten)]
        port: PortOpt,
        #[command(flatten)]
        subject: SubjectArgs,
    },
}

fn parse_method(s: &str) -> Result<Method, String> {
    s.parse::<Method>().map_err(|_| "expected one of auto, joints, components, rigidity".into())
}

/// One part, as reported.
#[derive(Debug, Serialize)]
struct PartRow {
    name: String,
    parent: Option<String>,
    vertices: usize,
    triangles: usize,
    overlap: usize,
}

fn rows(b: &BodyParts, s: &Subject) -> Vec<PartRow> {
    (0..b.len())
        .map(|k| PartRow {
            name: b.parts[k].name.clone(),
            parent: b.parts[k].parent.clone(),
            vertices: b.parts[k].vertices.len(),
            triangles: b.submesh(s.topology(), k).topology.n_triangles(),
            overlap: b.overlap(k).len(),
        })
        .collect()
}

fn print_rows(rows: &[PartRow]) {
    for r in rows {
        let parent = match &r.parent {
            Some(p) => format!(
                "child of {p}, {} {} shared with it",
                r.overlap,
                if r.overlap == 1 { "vertex" } else { "vertices" }
            ),
            None => "root".into(),
        };
        println!("  {:<12} {:>7} vertices {:>7} triangles  ({parent})", r.name, r.vertices, r.triangles);
    }
}

/// Reads a user's parts file against the subject's template (first frame).
fn read(s: &Subject, path: &std::path::Path) -> anyhow::Result<BodyParts> {
    let p0 = s.frame(0).unwrap_or_default();
    Ok(read_parts_file(path, s.topology(), p0)?)
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    match a.what {
        What::Propose { method, parts, overlap_rings, output, subject } => {
            surfcap_mesh::output_path::check_not_input(&output, &[&subject.path])?;
            let s = subject.open(ctx)?;
            let (b, report) = propose(&s, method, parts, overlap_rings)
                .with_context(|| format!("proposing {parts} parts for {}", subject.path.display()))?;
            let text = b.to_json();
            surfcap_mesh::atomic::write_file(&output, |w| {
                w.write_all(text.as_bytes())?;
                w.write_all(b"\n")
            })
            .with_context(|| format!("writing {}", output.display()))?;
            for n in &report.notes {
                ctx.note(n);
            }
            let rows = rows(&b, &s);
            let result = serde_json::json!({ "output": output, "subject": s.name, "report": report, "parts": rows });
            ctx.result(&result, || {
                println!(
                    "{} by {} ({} considered, {} frames) -> {}",
                    count_of(b.len(), "part"),
                    report.method.as_str(),
                    count_of(report.candidates, "candidate region"),
                    report.frames_used,
                    output.display()
                );
                print_rows(&rows);
            });
        }
        What::Check { parts, subject } => {
            let s = subject.open(ctx)?;
            let b = read(&s, &parts)?;
            let rows = rows(&b, &s);
            let shared = b.multiplicity().iter().filter(|&&m| m > 1).count();
            let result = serde_json::json!({
                "parts_file": parts, "subject": s.name, "vertices": b.n_vertices,
                "vertices_in_overlaps": shared, "parts": rows,
            });
            ctx.result(&result, || {
                println!(
                    "{}: {} fit {} ({} vertices, {shared} in overlaps)",
                    parts.display(),
                    count_of(b.len(), "part"),
                    s.name,
                    b.n_vertices
                );
                print_rows(&rows);
            });
        }
        What::Show { parts, port, subject } => {
            let s = subject.open(ctx)?;
            let b = read(&s, &parts)?;
            let items = items(&s, &b);
            let n = items.len();
            let json = ctx.json;
            serve(items, ServeOptions { port: port.port, report: None }, |addr| {
                let url = format!("http://{addr}/");
                if json {
                    print_json(&serde_json::json!({ "url": url, "sequences": n, "parts": b.len() }));
                } else {
                    println!("{url}");
                    eprintln!(
                        "surfcap parts show: {} of {} at {url} (Ctrl-C to stop)",
                        count_of(b.len(), "part"),
                        s.name
                    );
                }
                let _ = std::io::stdout().flush();
            })?;
        }
    }
    Ok(())
}

/// Part colours (sRGB), repeated for more parts.
const PALETTE: [u32; 8] = [0x9aa5b1, 0xd9822b, 0x2b8ad9, 0x3fae5a, 0xc94fb0, 0xd1c22e, 0x6c4fc9, 0x2ec1c1];
/// Overlap vertices are drawn at this fraction of their part's colour.
const OVERLAP_SHADE: f32 = 0.3;

fn linear(c: u32) -> [f32; 3] {
    [(c >> 16) & 255, (c >> 8) & 255, c & 255].map(|x| {
        let x = x as f32 / 255.0;
        if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) }
    })
}

/// The per-vertex colours of the parts (each vertex its deepest part, overlaps darker) and the
/// legend.
pub fn part_colours(b: &BodyParts) -> (Vec<f32>, Vec<[String; 2]>) {
    let (label, overlap) = b.display_labels();
    let mut colours = Vec::with_capacity(3 * label.len());
    for (l, o) in label.iter().zip(&overlap) {
        let c = linear(PALETTE[*l as usize % PALETTE.len()]);
        colours.extend(c.map(|x| if *o { x * OVERLAP_SHADE } else { x }));
    }
    let mut legend: Vec<[String; 2]> = b
        .parts
        .iter()
        .enumerate()
        .map(|(k, p)| [format!("#{:06x}", PALETTE[k % PALETTE.len()]), p.name.clone()])
        .collect();
    legend.push(["#4d5258".into(), "overlap (darker)".into()]);
    (colours, legend)
}

fn items(s: &Subject, b: &BodyParts) -> Vec<ViewItem> {
    let (colours, legend) = part_colours(b);
    let mut items = crate::view_items::view_items(s, &[]);
    for item in &mut items {
        item.colours = Some(colours.clone());
        item.colour_legend = legend.clone();
    }
    items
}

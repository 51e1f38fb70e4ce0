//! `surfcap transition <subject> --from seq:frame --to seq:frame -o out.glb`: one optimal
//! transition (thesis 2.5.4 for its lengths and warp, Algorithm 2 for its frames).

use std::path::PathBuf;

use serde_json::json;
use surfcap_formats::export::{ExportFormat, export};

use crate::options::{CacheOpts, SubjectArgs, TableOpts};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Source frame i (sequence:frame or a global frame): the source segment starts there.
    #[arg(long)]
    pub from: String,
    /// Destination frame j: the destination segment ends there.
    #[arg(long)]
    pub to: String,
    /// Output .glb (plus a .json sidecar and <output>.transition.json with lengths, warp, cost).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub cache: CacheOpts,
    #[command(flatten)]
    pub subject: SubjectArgs,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    // The glb, its sidecar, the report and the plot, planned before any work.
    let rp = a.output.with_extension("transition.json");
    let stem = a.output.file_stem().map(|x| x.to_string_lossy().into_owned()).unwrap_or_default();
    let plot = a.output.with_file_name(format!("{stem}-dtw"));
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&[&a.subject.path]);
    surfcap_formats::export::plan_export(&mut outs, ExportFormat::Glb, &a.output, ctx.force)?;
    outs.side_file(&rp, surfcap_synthesis::REPORT_KIND)?;
    outs.file(&plot.with_extension("svg"))?;
    outs.file(&plot.with_extension("png"))?;
    let s = a.subject.open(ctx)?;
    let (i, j) = (s.resolve_frame(&a.from)?, s.resolve_frame(&a.to)?);
    let pipe = a.cache.pipeline(ctx, s)?;
    let p = a.table.params_for(&pipe)?;
    let t = surfcap_synthesis::transition_run::transition(&pipe, (i, &a.from), (j, &a.to), &p)?;
    let (out, report, warp, d) = (t.animation, t.report, t.warp, t.distances);
    let (li, lj, secs, n) = (report.source_length, report.destination_length, report.blend_seconds, d.n);
    // Frames as users write them (`sequence:frame`) in the text and the plot; the report keeps
    // the global numbers too.
    let (from, to) = (report.from_frame.clone(), report.to_frame.clone());
    let bar = crate::progress::Bar::new(ctx);
    let mut written = export(&out, ExportFormat::Glb, &a.output, ctx.export_options(), &bar)?;
    surfcap_synthesis::write_report(&rp, &report)?;
    written.push(rp);
    // The distance matrix around the transition with its DTW warp on it (thesis Fig. 2.10):
    // source frames down, destination frames across, a margin of a few frames around both
    // segments (kept inside the matrix).
    let margin = li.max(lj) / 2 + 2;
    let (r0, r1) = (i.saturating_sub(margin), (i + li + margin).min(n));
    let (c0, c1) = ((j + 1 - lj).saturating_sub(margin), (j + 1 + margin).min(n));
    let heat = surfcap_plot::HeatMap {
        title: format!("pose distances and DTW warp, {from} -> {to}"),
        x_label: "destination frame".into(),
        y_label: "source frame".into(),
        values: (r0..r1).flat_map(|r| (c0..c1).map(move |c| (r, c))).map(|(r, c)| d.values[r * n + c]).collect(),
        rows: r1 - r0,
        cols: c1 - c0,
        origin: (r0, c0),
        range: None,
        path: warp.path.clone(),
        value_label: "pose distance".into(),
    };
    written.extend(surfcap_plot::write_heat_map(&plot, &heat)?);
    ctx.commit(outs)?;
    ctx.result(&json!({ "transition": report, "written": written }), || {
        println!(
            "transition {from} -> {to}: source segment {li} frames, destination {lj}, duration {} frames, normalised cost {:.3}; blended in {secs:.2} s",
            warp.len, warp.cost
        );
    });
    ctx.wrote(&written);
    Ok(())
}

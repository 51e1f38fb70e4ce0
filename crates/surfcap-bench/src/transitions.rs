//! `surfcap-bench transitions`: the transition table and its speed-up over naive DTW.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use surfcap_builtin::{WormParams, worm_subject};

use crate::measure::FpsOpt;
use crate::options::TableOpts;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject; default: the built-in tube, two sequences, --frames frames in all.
    #[arg(long)]
    pub subject: Option<PathBuf>,
    #[arg(long, default_value_t = 350, value_parser = crate::options::count)]
    pub frames: usize,
    /// Frame pairs timed with the naive loop.
    #[arg(long, default_value_t = 12, value_parser = crate::options::count)]
    pub sample: usize,
    #[command(flatten)]
    pub table: TableOpts,
    #[command(flatten)]
    pub fps: FpsOpt,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    use surfcap_geometry::distance_matrix::{DistanceParams, distance_matrix};
    use surfcap_motion::transition_table::{SegmentRoom, naive_transition, transition_table};
    let Args { subject, frames, sample, table, fps } = a;
    if subject.is_none() {
        // The distance matrix and the table's cost and length matrices (f64 each), and more.
        let f = frames as f64;
        crate::check_size(ctx, format!("--frames {frames}"), f * f * 8.0 * 4.0, 0.0, "--frames")?;
    }
    let s = match subject {
        Some(p) => fps.open_quietly(&p)?,
        None => worm_subject(&WormParams { frames: frames.div_ceil(2), ..Default::default() })?,
    };
    let p = table.params(s.fps)?;
    let bar = crate::progress::Bar::new(ctx);
    let t0 = Instant::now();
    let d = distance_matrix(&s, &DistanceParams::default(), &bar);
    let dist_secs = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let t = transition_table(&d.values, s.frame_index(), &p, &bar)?;
    let table_secs = t1.elapsed().as_secs_f64();
    let n = t.n;
    let candidates: Vec<usize> = (0..n * n).filter(|&k| t.cost[k].is_finite()).collect();
    anyhow::ensure!(!candidates.is_empty(), "no frame pair has room for a transition");
    // Pairs spread over the whole table (a fixed multiplicative hash of the sample index): evenly
    // spaced row-major picks would all sit at the start of their rows, where windows are short.
    let picks: Vec<usize> = (0..sample.max(1) as u64)
        .map(|k| candidates[(k.wrapping_mul(2_654_435_761) % candidates.len() as u64) as usize])
        .collect();
    let room = SegmentRoom::new(s.frame_index());
    let t2 = Instant::now();
    let mut mismatches = 0;
    for &k in &picks {
        let naive = naive_transition(&d.values, &room, k / n, k % n, &p);
        if naive.is_none_or(|(c, ..)| (c - t.cost[k]).abs() > 1e-9 * c.abs().max(1.0)) {
            mismatches += 1;
        }
    }
    let per_pair = t2.elapsed().as_secs_f64() / picks.len() as f64;
    let naive_total = per_pair * candidates.len() as f64;
    let report = json!({
        "frames": n, "fps": s.fps, "l_min": p.l_min, "l_max": p.l_max, "slope": p.slope,
        "distance_seconds": dist_secs, "table_seconds": table_secs,
        "pairs_with_transitions": candidates.len(), "naive_seconds_per_pair": per_pair,
        "naive_seconds_estimated": naive_total, "speed_up": naive_total / table_secs,
        "naive_pairs_checked": picks.len(), "naive_mismatches": mismatches, "threads": rayon::current_num_threads(),
    });
    ctx.result(&report, || {
        println!(
            "{n} frames at {} fps, segments {}..{}, slope {}: table {table_secs:.2} s on {} threads (distances {dist_secs:.2} s); \
             naive one-DTW-per-length: {:.3} s per pair on {} sampled pairs (all agree: {}), ~{:.0} s for all {} pairs: speed-up {:.0}x",
            s.fps,
            p.l_min,
            p.l_max,
            p.slope.map_or("inf".into(), |p| p.to_string()),
            rayon::current_num_threads(),
            per_pair,
            picks.len(),
            mismatches == 0,
            naive_total,
            candidates.len(),
            naive_total / table_secs
        );
    });
    Ok(())
}

//! `surfcap eval transitions <subject>`: thesis 2.5.5, Fig. 2.15.
//!
//! For every ordered frame pair where all three transitions exist: the standard transition (no
//! warping, l^i = l^j = the fixed length), DTW with that fixed length, and DTW with variable
//! segment lengths (the transition table), for each slope constraint. The fixed length defaults
//! to one second of frames (clamped to the segment bounds): the thesis does not give the
//! standard transition's length.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde_json::json;
use surfcap_geometry::distance_matrix::DistanceParams;
use surfcap_motion::dtw::dtw_window;
use surfcap_motion::segment_bounds;
use surfcap_motion::transition_table::{SegmentRoom, TableParams, fixed_length_dtw, standard_transition};
use surfcap_plot::{LineChart, Series, write_line_chart};

use crate::options::{CacheOpts, SourceOpts, open};
use crate::output::print_json;

pub struct Opts {
    pub slopes: Vec<usize>,
    pub fixed: Option<usize>,
    pub plot_pairs: usize,
    pub output: PathBuf,
    pub cache: CacheOpts,
}

/// Mean and (population) standard deviation; (0, 0) for no values.
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt())
}

pub fn run(ctx: &crate::Ctx, path: &Path, source: &SourceOpts, o: &Opts) -> anyhow::Result<()> {
    anyhow::ensure!(!o.slopes.is_empty() && o.slopes.iter().all(|&p| p >= 1), "--slopes: expected whole numbers >= 1");
    let s = open(ctx, path, source)?;
    let pipe = o.cache.pipeline(ctx, s);
    let s = pipe.subject();
    let (l_min, l_max) = segment_bounds(s.fps);
    let fixed = o.fixed.unwrap_or(s.fps.round() as usize).clamp(l_min, l_max);
    let d = pipe.distances(&DistanceParams::default())?.value;
    let d = &d.values;
    let n = s.n_frames();
    let room = SegmentRoom::new(s.frame_index());
    let standard: Vec<Option<f64>> =
        (0..n * n).into_par_iter().map(|k| standard_transition(d, &room, k / n, k % n, fixed)).collect();
    let mut rows = Vec::new();
    let mut plot_data = None;
    for &p in &o.slopes {
        let params = TableParams { l_min, l_max, slope: Some(p) };
        let table = pipe.table(&params)?.value;
        let dtw: Vec<Option<(f64, u32)>> =
            (0..n * n).into_par_iter().map(|k| fixed_length_dtw(d, &room, k / n, k % n, fixed, Some(p))).collect();
        let pairs: Vec<usize> =
            (0..n * n).filter(|&k| standard[k].is_some() && dtw[k].is_some() && table.cost[k].is_finite()).collect();
        let pick = |f: &dyn Fn(usize) -> f64| pairs.iter().map(|&k| f(k)).collect::<Vec<f64>>();
        let (sm, ss) = mean_std(&pick(&|k| standard[k].expect("filtered")));
        let (dm, ds) = mean_std(&pick(&|k| dtw[k].expect("filtered").0));
        let (vm, vs) = mean_std(&pick(&|k| table.cost[k]));
        let (lm, _) = mean_std(&pick(&|k| table.len[k] as f64));
        rows.push(json!({
            "slope": p, "pairs": pairs.len(),
            "standard": {"mean": sm, "std": ss}, "dtw": {"mean": dm, "std": ds}, "dtw_vls": {"mean": vm, "std": vs},
            "dtw_vls_mean_duration": lm,
        }));
        if p == 3 || plot_data.is_none() {
            let step = (pairs.len() / o.plot_pairs.max(1)).max(1);
            let sample: Vec<usize> = pairs.iter().step_by(step).take(o.plot_pairs).copied().collect();
            // The cheapest transition whose source and destination segments do not overlap
            // (overlapping ones replay nearly the same frames), drawn on the distance matrix
            // (thesis Fig. 2.10).
            let disjoint = |k: usize| {
                let (i, j, li, lj) = (k / n, k % n, table.li[k] as usize, table.lj[k] as usize);
                j < i || j + 1 >= i + li + lj
            };
            let shown = pairs
                .iter()
                .copied()
                .filter(|&k| disjoint(k))
                .min_by(|&a, &b| table.cost[a].total_cmp(&table.cost[b]))
                .map(|k| (k / n, table.li[k] as usize, k % n, table.lj[k] as usize));
            plot_data = Some((
                p,
                sample
                    .iter()
                    .map(|&k| (standard[k].expect("filtered"), table.cost[k], table.len[k]))
                    .collect::<Vec<_>>(),
                shown,
            ));
        }
    }
    let (p_plot, sample, shown) = plot_data.expect("at least one slope");
    let xs = |f: &dyn Fn(&(f64, f64, u32)) -> f64| {
        sample.iter().enumerate().map(|(x, v)| (x as f64, f(v))).collect::<Vec<_>>()
    };
    let series = |name: String, points, color| Series { name, points, color, dashed: false, markers: false };
    let costs = LineChart {
        title: format!("Normalised transition costs, {} ({} pairs)", s.name, sample.len()),
        x_label: "frame pair (sample)".into(),
        y_label: "normalised deformation cost".into(),
        series: vec![
            series(format!("standard (l = {fixed})"), xs(&|v| v.0), (30, 70, 210)),
            series(format!("DTW + variable lengths (p = {p_plot})"), xs(&|v| v.1), (210, 30, 30)),
        ],
    };
    let durations = LineChart {
        title: format!("Transition durations, {}", s.name),
        x_label: "frame pair (sample)".into(),
        y_label: "frames".into(),
        series: vec![
            series(format!("standard (l = {fixed})"), xs(&|_| fixed as f64), (30, 70, 210)),
            series(format!("DTW + variable lengths (p = {p_plot})"), xs(&|v| v.2 as f64), (210, 30, 30)),
        ],
    };
    let mut plots = write_line_chart(&o.output.join("costs"), &costs).map_err(|e| anyhow::anyhow!("{e}"))?;
    plots.extend(write_line_chart(&o.output.join("durations"), &durations).map_err(|e| anyhow::anyhow!("{e}"))?);
    let warp = shown.and_then(|(i, li, j, lj)| Some((i, j, dtw_window(d, n, i, li, j, lj, Some(p_plot))?)));
    let heat = surfcap_plot::HeatMap {
        title: match &warp {
            Some((i, j, _)) => format!("{}: pose distances, DTW warp of transition {i} -> {j} (p = {p_plot})", s.name),
            None => format!("{}: pose distances", s.name),
        },
        x_label: "destination frame".into(),
        y_label: "source frame".into(),
        values: d.clone(),
        rows: n,
        cols: n,
        origin: (0, 0),
        path: warp.map(|w| w.2.path).unwrap_or_default(),
    };
    plots.extend(surfcap_plot::write_heat_map(&o.output.join("distances"), &heat)?);
    let report = json!({
        "subject": s.name, "frames": n, "fps": s.fps, "l_min": l_min, "l_max": l_max, "fixed_length": fixed,
        "rows": rows, "plots": plots,
    });
    let rp = o.output.join("transitions.json");
    surfcap_mesh::atomic::write_file(&rp, |w| {
        serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)
    })?;
    if ctx.json {
        print_json(&report);
        return Ok(());
    }
    println!(
        "subject {}: {n} frames at {} fps; segments {l_min}..{l_max}; standard and DTW-only length {fixed}",
        s.name, s.fps
    );
    println!(
        "{:>6} {:>8} {:>22} {:>22} {:>22} {:>10}",
        "slope", "pairs", "standard mean (std)", "DTW mean (std)", "DTW+VLS mean (std)", "VLS L"
    );
    for r in &rows {
        let f = |k: &str| {
            format!(
                "{:.2} ({:.2})",
                r[k]["mean"].as_f64().unwrap_or(f64::NAN),
                r[k]["std"].as_f64().unwrap_or(f64::NAN)
            )
        };
        println!(
            "{:>6} {:>8} {:>22} {:>22} {:>22} {:>10.1}",
            r["slope"].as_u64().unwrap_or(0),
            r["pairs"].as_u64().unwrap_or(0),
            f("standard"),
            f("dtw"),
            f("dtw_vls"),
            r["dtw_vls_mean_duration"].as_f64().unwrap_or(f64::NAN)
        );
    }
    println!(
        "wrote {}, {}",
        rp.display(),
        plots.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}

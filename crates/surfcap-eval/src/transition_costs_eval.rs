//! Standard transitions vs DTW vs DTW with variable segment lengths (thesis 2.5.5, Fig. 2.15).
//!
//! For every ordered frame pair where all three transitions exist: the standard transition (no
//! warping, l^i = l^j = the fixed length), DTW with that fixed length, and DTW with variable
//! segment lengths (the transition table), for each slope constraint. The fixed length defaults
//! to one second of frames (clamped to the segment bounds): the thesis does not give the
//! standard transition's length.
//!
//! The DTW's first step has two readings (PAPER-NOTES on eq. 2.53): surfcap's (up to p - 1
//! straight steps may open the path, the default) and the literal one (a diagonal first);
//! [`TransitionCostsOptions::first_step`] picks one and the report records it. So does the
//! DTW's normalisation (PAPER-NOTES on eq. 2.55 vs 2.50): surfcap's DP minimises the summed cost
//! and divides by the path length (the default); the exact reading finds the path of least
//! ratio ([`TransitionCostsOptions::normalisation`]). The tables of a reading other than
//! surfcap's are computed here, not cached by the pipeline.

use std::sync::Arc;

use rayon::prelude::*;
use serde::Serialize;
use surfcap_mesh::NoProgress;
use surfcap_motion::dtw::{DtwReading, FirstStep, Normalisation, dtw_window_from};
use surfcap_motion::segment_bounds;
use surfcap_motion::transition_table::{
    SegmentRoom, TableParams, fixed_length_dtw_from, standard_transition, transition_table_from,
};
use surfcap_pipeline::{Pipeline, PoseDistances};

use crate::MeanStd;
use crate::error::{Error, Result};

/// Options of [`transition_costs_eval`] (`surfcap eval transitions`).
#[derive(Debug, Clone)]
pub struct TransitionCostsOptions {
    /// Slope constraints to compare (each >= 1).
    pub slopes: Vec<usize>,
    /// Fixed segment length of the standard and DTW-only transitions (default: one second of
    /// frames), clamped to the segment bounds.
    pub fixed: Option<usize>,
    /// Frame pairs in the sampled curves ([`TransitionPlotData::sample`]).
    pub plot_pairs: usize,
    /// Reading of the DTW's first step (eq. 2.53): surfcap's (the default) or the literal one.
    pub first_step: FirstStep,
    /// Normalisation of the DTW's cost (eq. 2.50, 2.55): surfcap's sum then divide (the
    /// default) or the exact least ratio.
    pub normalisation: Normalisation,
}

/// The three kinds of transition at one slope constraint, over the pairs where all exist.
#[derive(Debug, Clone, Serialize)]
pub struct SlopeRow {
    pub slope: usize,
    /// Ordered frame pairs compared.
    pub pairs: usize,
    /// Normalised cost of the standard transitions.
    pub standard: MeanStd,
    /// Normalised cost of DTW with the fixed length.
    pub dtw: MeanStd,
    /// Normalised cost of DTW with variable segment lengths (the transition table).
    pub dtw_vls: MeanStd,
    /// Mean duration L of the variable-length transitions, frames.
    pub dtw_vls_mean_duration: f64,
}

/// One sampled frame pair of the cost and duration curves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SampledTransition {
    /// Standard transition's normalised cost (its duration is the fixed length).
    pub standard: f64,
    /// DTW + variable lengths: normalised cost and duration L.
    pub dtw_vls: f64,
    pub duration: u32,
}

/// The transition drawn on the distance matrix: the cheapest variable-length transition whose
/// source and destination segments do not overlap (thesis Fig. 2.10), with its DTW warp.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShownWarp {
    /// Source start frame i and segment length l^i.
    pub source: usize,
    pub source_len: usize,
    /// Destination frame j (the segment's last frame) and segment length l^j.
    pub destination: usize,
    pub destination_len: usize,
    /// The warp path as pairs of global frames (source, destination).
    pub path: Vec<(usize, usize)>,
}

/// What the plots of `surfcap eval transitions` draw (`costs`, `durations`, `distances`).
#[derive(Debug, Clone, Serialize)]
pub struct TransitionPlotData {
    /// The slope constraint plotted: 3 when compared, else the first.
    pub slope: usize,
    /// Evenly spaced compared pairs at that slope, at most `plot_pairs`.
    pub sample: Vec<SampledTransition>,
    /// The transition drawn on the heat map, `None` when there is none to draw.
    pub shown: Option<ShownWarp>,
    /// The pose distance matrix the transitions were built on (the heat map).
    #[serde(skip)]
    pub distances: Arc<PoseDistances>,
}

/// Result of [`transition_costs_eval`]; serialised, the report `transitions.json` without its
/// `plots`.
#[derive(Debug, Clone, Serialize)]
pub struct TransitionCostsEval {
    pub subject: String,
    pub frames: usize,
    pub fps: f64,
    pub l_min: usize,
    pub l_max: usize,
    /// Segment length of the standard and DTW-only transitions.
    pub fixed_length: usize,
    /// Reading of the DTW's first step: "surfcap" (up to p - 1 straight steps may open the
    /// path) or "literal" (eq. 2.53 read from g(1, 1): a diagonal first).
    pub dtw_first_step: &'static str,
    /// Normalisation of the DTW's cost: "surfcap" (the least summed cost, divided by its path
    /// length) or "exact" (the least ratio of summed cost to path length, eq. 2.55).
    pub dtw_ratio: &'static str,
    pub rows: Vec<SlopeRow>,
    #[serde(skip)]
    pub plot: TransitionPlotData,
}

/// Thesis 2.5.5, Fig. 2.15: mean and standard deviation of the normalised costs of standard,
/// DTW and DTW + variable-length transitions for each slope constraint, on the pipeline's
/// chain distances (the ones its transition tables are built on).
pub fn transition_costs_eval(pipe: &Pipeline, o: &TransitionCostsOptions) -> Result<TransitionCostsEval> {
    if o.slopes.is_empty() || o.slopes.iter().any(|&p| p < 1) {
        return Err(Error::parameter("--slopes", None, "expected whole numbers >= 1"));
    }
    let s = pipe.subject();
    let (l_min, l_max) = segment_bounds(s.fps);
    let fixed = o.fixed.unwrap_or(s.fps.round() as usize).clamp(l_min, l_max);
    let d = pipe.chain_distances()?.value;
    let n = s.n_frames();
    let room = SegmentRoom::new(s.frame_index());
    let standard: Vec<Option<f64>> =
        (0..n * n).into_par_iter().map(|k| standard_transition(&d.values, &room, k / n, k % n, fixed)).collect();
    let mut rows = Vec::new();
    let mut plot_data = None;
    let reading = DtwReading { first_step: o.first_step, normalisation: o.normalisation };
    for &p in &o.slopes {
        let params = TableParams { l_min, l_max, slope: Some(p) };
        let table = if reading == DtwReading::default() {
            pipe.table(&params)?.value
        } else {
            let t = transition_table_from(&d.values, s.frame_index(), &params, reading, &NoProgress);
            Arc::new(t.map_err(surfcap_pipeline::Error::from)?)
        };
        let dtw: Vec<Option<(f64, u32)>> = (0..n * n)
            .into_par_iter()
            .map(|k| fixed_length_dtw_from(&d.values, &room, (k / n, k % n), fixed, Some(p), reading))
            .collect();
        let pairs: Vec<usize> =
            (0..n * n).filter(|&k| standard[k].is_some() && dtw[k].is_some() && table.cost[k].is_finite()).collect();
        let pick = |f: &dyn Fn(usize) -> f64| pairs.iter().map(|&k| f(k)).collect::<Vec<f64>>();
        let standard_stats = MeanStd::of(&pick(&|k| standard[k].expect("filtered")));
        let dtw_stats = MeanStd::of(&pick(&|k| dtw[k].expect("filtered").0));
        let vls_stats = MeanStd::of(&pick(&|k| table.cost[k]));
        let duration = MeanStd::of(&pick(&|k| table.len[k] as f64)).mean;
        rows.push(SlopeRow {
            slope: p,
            pairs: pairs.len(),
            standard: standard_stats,
            dtw: dtw_stats,
            dtw_vls: vls_stats,
            dtw_vls_mean_duration: duration,
        });
        if p == 3 || plot_data.is_none() {
            let step = (pairs.len() / o.plot_pairs.max(1)).max(1);
            let sample = pairs
                .iter()
                .step_by(step)
                .take(o.plot_pairs)
                .map(|&k| SampledTransition {
                    standard: standard[k].expect("filtered"),
                    dtw_vls: table.cost[k],
                    duration: table.len[k],
                })
                .collect::<Vec<_>>();
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
            plot_data = Some((p, sample, shown));
        }
    }
    let (p_plot, sample, shown) = plot_data.expect("at least one slope");
    let shown = shown.and_then(|(i, li, j, lj)| {
        let warp = dtw_window_from(&d.values, n, i, li, j, lj, Some(p_plot), reading)?;
        Some(ShownWarp { source: i, source_len: li, destination: j, destination_len: lj, path: warp.path })
    });
    Ok(TransitionCostsEval {
        subject: s.name.clone(),
        frames: n,
        fps: s.fps,
        l_min,
        l_max,
        fixed_length: fixed,
        dtw_first_step: o.first_step.name(),
        dtw_ratio: o.normalisation.name(),
        rows,
        plot: TransitionPlotData { slope: p_plot, sample, shown, distances: d },
    })
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::test_subjects::{pipeline, worm};

    #[test]
    fn variable_lengths_cost_least_and_the_report_is_the_cli_json() {
        // 9 fps: segments of 3..18 frames, standard length 9, in 24 frames.
        let pipe = pipeline(worm(9.0));
        let o = TransitionCostsOptions {
            slopes: vec![2, 3],
            fixed: None,
            plot_pairs: 10,
            first_step: FirstStep::default(),
            normalisation: Normalisation::default(),
        };
        let r = transition_costs_eval(&pipe, &o).unwrap();
        let n = pipe.subject().n_frames();
        assert_eq!((r.frames, r.l_min, r.l_max, r.fixed_length), (n, 3, 18, 9));
        assert_eq!(r.rows.iter().map(|x| x.slope).collect::<Vec<_>>(), [2, 3]);
        for row in &r.rows {
            assert!(row.pairs > 0);
            // Thesis Fig. 2.15: DTW + variable lengths <= DTW <= standard.
            assert!(row.dtw_vls.mean <= row.dtw.mean && row.dtw.mean <= row.standard.mean, "{row:?}");
            assert!(row.dtw_vls_mean_duration >= r.l_min as f64);
        }
        let plot = &r.plot;
        assert_eq!(plot.slope, 3, "slope 3 is plotted when compared");
        assert!(!plot.sample.is_empty() && plot.sample.len() <= 10);
        assert_eq!(plot.distances.n, n);
        let w = plot.shown.as_ref().expect("a transition to draw");
        assert!(w.destination < w.source || w.destination + 1 >= w.source + w.source_len + w.destination_len);
        assert_eq!(w.path.first(), Some(&(w.source, w.destination + 1 - w.destination_len)));
        assert_eq!(w.path.last(), Some(&(w.source + w.source_len - 1, w.destination)));
        // transitions.json as the CLI wrote it, without "plots".
        let rows: Vec<_> = r
            .rows
            .iter()
            .map(|x| {
                json!({
                    "slope": x.slope, "pairs": x.pairs,
                    "standard": {"mean": x.standard.mean, "std": x.standard.std}, "dtw": {"mean": x.dtw.mean, "std": x.dtw.std},
                    "dtw_vls": {"mean": x.dtw_vls.mean, "std": x.dtw_vls.std},
                    "dtw_vls_mean_duration": x.dtw_vls_mean_duration,
                })
            })
            .collect();
        let cli = json!({
            "subject": r.subject, "frames": n, "fps": 9.0, "l_min": 3, "l_max": 18, "fixed_length": 9,
            "dtw_first_step": "surfcap", "dtw_ratio": "surfcap", "rows": rows,
        });
        assert_eq!(serde_json::to_value(&r).unwrap(), cli);
    }

    #[test]
    fn slopes_must_be_whole_numbers_from_one() {
        let pipe = pipeline(worm(9.0));
        for slopes in [vec![], vec![2, 0]] {
            let o = TransitionCostsOptions {
                slopes,
                fixed: None,
                plot_pairs: 10,
                first_step: FirstStep::default(),
                normalisation: Normalisation::default(),
            };
            assert_eq!(
                transition_costs_eval(&pipe, &o).unwrap_err().to_string(),
                "--slopes: expected whole numbers >= 1"
            );
        }
    }

    #[test]
    fn the_literal_dtw_first_step_changes_the_costs_and_is_recorded() {
        let pipe = pipeline(worm(9.0));
        let run = |first_step| {
            let normalisation = Normalisation::default();
            let o =
                TransitionCostsOptions { slopes: vec![2, 3], fixed: None, plot_pairs: 10, first_step, normalisation };
            transition_costs_eval(&pipe, &o).unwrap()
        };
        let (ours, literal) = (run(FirstStep::default()), run(FirstStep::Diagonal));
        assert_eq!(FirstStep::default(), FirstStep::Straight);
        assert_eq!((ours.dtw_first_step, literal.dtw_first_step), ("surfcap", "literal"));
        assert_eq!(serde_json::to_value(&literal).unwrap()["dtw_first_step"], "literal");
        for (a, b) in ours.rows.iter().zip(&literal.rows) {
            // The standard transition has no warp; the warped ones change with the reading.
            assert_eq!(a.standard.mean, b.standard.mean);
            assert_ne!(a.dtw_vls.mean, b.dtw_vls.mean, "slope {}", a.slope);
        }
    }

    #[test]
    fn the_exact_ratio_never_costs_more_and_is_recorded() {
        let pipe = pipeline(worm(9.0));
        let run = |normalisation| {
            let first_step = FirstStep::default();
            let o =
                TransitionCostsOptions { slopes: vec![2, 3], fixed: None, plot_pairs: 10, first_step, normalisation };
            transition_costs_eval(&pipe, &o).unwrap()
        };
        let (ours, exact) = (run(Normalisation::SumThenDivide), run(Normalisation::ExactRatio));
        assert_eq!((ours.dtw_ratio, exact.dtw_ratio), ("surfcap", "exact"));
        assert_eq!(serde_json::to_value(&exact).unwrap()["dtw_ratio"], "exact");
        for (a, b) in ours.rows.iter().zip(&exact.rows) {
            assert_eq!((a.standard.mean, a.pairs), (b.standard.mean, b.pairs));
            // The least ratio is at most the ratio of the least sum, pair by pair.
            assert!(b.dtw_vls.mean <= a.dtw_vls.mean && b.dtw.mean <= a.dtw.mean, "{a:?} vs {b:?}");
        }
        assert!(ours.rows.iter().zip(&exact.rows).any(|(a, b)| b.dtw_vls.mean < a.dtw_vls.mean));
        let w = exact.plot.shown.as_ref().expect("a transition to draw");
        assert_eq!(w.path.last(), Some(&(w.source + w.source_len - 1, w.destination)));
    }
}

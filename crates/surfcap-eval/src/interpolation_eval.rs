//! Linear vs non-linear interpolation of pose pairs (thesis 2.4, Fig. 2.8): edge-length
//! distortion and volume change at one lambda, relative to the linear blend of the inputs' own
//! measures, and optionally both measures over lambda = 0, 0.1, ..., 1.

use std::time::Instant;

use serde::Serialize;
use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
use surfcap_geometry::shape_distortion::{edge_length_distortion, volume_change};
use surfcap_mesh::Subject;

use crate::error::{Error, Result};

/// Options of [`interpolation_eval`] (`surfcap eval interpolation`).
#[derive(Debug, Clone)]
pub struct InterpolationOptions {
    /// Pose pairs as `FROM,TO`, each a `sequence:frame` or a global frame.
    pub pairs: Vec<String>,
    /// Interpolation parameter of the rows.
    pub lambda: f64,
    /// Stretch interpolation: linear (eq. 2.45) or log (eq. 2.46).
    pub stretch: StretchInterpolation,
    /// Also sample both measures over lambda = 0, 0.1, ..., 1 ([`InterpolationEval::sweeps`]).
    pub sweeps: bool,
}

/// Edge-length distortion and volume change of one interpolated pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Distortion {
    pub edge_distortion: f64,
    pub volume_change: f64,
}

/// One pose pair at the options' lambda.
#[derive(Debug, Clone, Serialize)]
pub struct InterpolationRow {
    /// The pair as given (`FROM,TO`).
    pub pair: String,
    pub lambda: f64,
    pub linear: Distortion,
    pub nonlinear: Distortion,
    /// Time of the non-linear interpolation (set-up and one pose), seconds.
    pub nonlinear_seconds: f64,
}

/// Both measures of both interpolations at one lambda; serialised as the array
/// `[lambda, linear edge, non-linear edge, linear volume, non-linear volume]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(into = "[f64; 5]")]
pub struct SweepPoint {
    pub lambda: f64,
    pub linear_edge_distortion: f64,
    pub nonlinear_edge_distortion: f64,
    pub linear_volume_change: f64,
    pub nonlinear_volume_change: f64,
}

impl From<SweepPoint> for [f64; 5] {
    fn from(p: SweepPoint) -> Self {
        [
            p.lambda,
            p.linear_edge_distortion,
            p.nonlinear_edge_distortion,
            p.linear_volume_change,
            p.nonlinear_volume_change,
        ]
    }
}

/// One pair's measures over lambda = 0, 0.1, ..., 1 (the curves of `distortion.svg` and
/// `volume.svg`).
#[derive(Debug, Clone, Serialize)]
pub struct InterpolationSweep {
    pub pair: String,
    #[serde(rename = "lambda_linear_edge_nonlinear_edge_linear_volume_nonlinear_volume")]
    pub points: Vec<SweepPoint>,
}

/// Result of [`interpolation_eval`]. Serialised, it is `interpolation.json`; without
/// `sweeps` (the `--json` output) it is `{subject, rows}`.
#[derive(Debug, Clone, Serialize)]
pub struct InterpolationEval {
    pub subject: String,
    /// The mesh's size (printed beside the table; not in the JSON).
    #[serde(skip)]
    pub n_vertices: usize,
    #[serde(skip)]
    pub n_triangles: usize,
    pub rows: Vec<InterpolationRow>,
    /// One per pair when [`InterpolationOptions::sweeps`] was set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweeps: Option<Vec<InterpolationSweep>>,
}

/// Linear vs non-linear interpolation at lambda (thesis 2.4, Fig. 2.8): for every pair, the
/// edge-length distortion and volume change of the linear blend and of the non-linear
/// interpolation, relative to the linear blend of the inputs' own measures.
pub fn interpolation_eval(s: &Subject, o: &InterpolationOptions) -> Result<InterpolationEval> {
    if !(0.0..=1.0).contains(&o.lambda) {
        return Err(Error::parameter("--lambda", Some(o.lambda.to_string()), "expected a number in [0, 1]"));
    }
    let topo = s.topology();
    let mut rows = Vec::new();
    let mut sweeps = Vec::new();
    for pair in &o.pairs {
        let (from, to) = pair
            .split_once(',')
            .ok_or_else(|| Error::parameter("--pair", Some(format!("{pair:?}")), "expected FROM,TO"))?;
        let (gi, gj) = (s.resolve_frame(from)?, s.resolve_frame(to)?);
        let pi = s.frame(gi).expect("resolved");
        let t0 = Instant::now();
        let interp = NonlinearInterpolator::new(topo, pi, s.frame(gj).expect("resolved"), s.up_axis)?;
        let nonlinear = interp.at(o.lambda, o.stretch);
        let secs = t0.elapsed().as_secs_f64();
        let linear = interp.linear(o.lambda);
        let pj = interp.aligned_target();
        let measure = |p: &[f32]| Distortion {
            edge_distortion: edge_length_distortion(topo, pi, pj, p, o.lambda),
            volume_change: volume_change(topo, pi, pj, p, o.lambda),
        };
        rows.push(InterpolationRow {
            pair: pair.clone(),
            lambda: o.lambda,
            linear: measure(&linear),
            nonlinear: measure(&nonlinear),
            nonlinear_seconds: secs,
        });
        if o.sweeps {
            let points = (0..=10)
                .map(|k| {
                    let l = k as f64 / 10.0;
                    let (lin, non) = (interp.linear(l), interp.at(l, o.stretch));
                    SweepPoint {
                        lambda: l,
                        linear_edge_distortion: edge_length_distortion(topo, pi, pj, &lin, l),
                        nonlinear_edge_distortion: edge_length_distortion(topo, pi, pj, &non, l),
                        linear_volume_change: volume_change(topo, pi, pj, &lin, l),
                        nonlinear_volume_change: volume_change(topo, pi, pj, &non, l),
                    }
                })
                .collect();
            sweeps.push(InterpolationSweep { pair: pair.clone(), points });
        }
    }
    Ok(InterpolationEval {
        subject: s.name.clone(),
        n_vertices: topo.n_vertices(),
        n_triangles: topo.n_triangles(),
        rows,
        sweeps: o.sweeps.then_some(sweeps),
    })
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::test_subjects::{keys, worm};

    fn options(sweeps: bool) -> InterpolationOptions {
        InterpolationOptions {
            pairs: vec!["0,12".into(), "3,20".into()],
            lambda: 0.5,
            stretch: StretchInterpolation::Linear,
            sweeps,
        }
    }

    #[test]
    fn rows_and_sweeps_serialise_as_the_cli_json() {
        let s = worm(30.0);
        let r = interpolation_eval(&s, &options(true)).unwrap();
        assert_eq!(r.rows.len(), 2);
        assert_eq!((r.n_vertices, r.n_triangles), (s.topology().n_vertices(), s.topology().n_triangles()));
        let sweeps = r.sweeps.as_ref().unwrap();
        assert_eq!(sweeps.len(), 2);
        for sweep in sweeps {
            assert_eq!(sweep.points.len(), 11);
            for end in [&sweep.points[0], &sweep.points[10]] {
                assert!(end.linear_edge_distortion.abs() < 1e-3 && end.nonlinear_edge_distortion.abs() < 1e-3);
            }
        }
        for row in &r.rows {
            // The tube bends: the linear blend shortens its edges, the non-linear one far less.
            assert!(row.nonlinear.edge_distortion < row.linear.edge_distortion, "{row:?}");
            // The sweep at lambda = 0.5 is the row.
            let mid = sweeps.iter().find(|w| w.pair == row.pair).unwrap().points[5];
            assert_eq!(mid.linear_edge_distortion, row.linear.edge_distortion);
            assert_eq!(mid.nonlinear_volume_change, row.nonlinear.volume_change);
        }
        // interpolation.json as the CLI wrote it.
        let v = serde_json::to_value(&r).unwrap();
        let cli_rows: Vec<_> = r
            .rows
            .iter()
            .map(|x| {
                json!({
                    "pair": x.pair,
                    "lambda": x.lambda,
                    "linear": { "edge_distortion": x.linear.edge_distortion, "volume_change": x.linear.volume_change },
                    "nonlinear": { "edge_distortion": x.nonlinear.edge_distortion, "volume_change": x.nonlinear.volume_change },
                    "nonlinear_seconds": x.nonlinear_seconds,
                })
            })
            .collect();
        let cli_sweeps: Vec<_> = sweeps
            .iter()
            .map(|w| {
                let a: Vec<[f64; 5]> = w.points.iter().map(|&p| p.into()).collect();
                json!({ "pair": w.pair, "lambda_linear_edge_nonlinear_edge_linear_volume_nonlinear_volume": a })
            })
            .collect();
        assert_eq!(v, json!({ "subject": s.name, "rows": cli_rows, "sweeps": cli_sweeps }));
        // Without sweeps: the `--json` output.
        let r = interpolation_eval(&s, &options(false)).unwrap();
        assert_eq!(keys(&serde_json::to_value(&r).unwrap()), ["rows", "subject"]);
    }

    #[test]
    fn a_pair_without_a_comma_names_the_option() {
        let o = InterpolationOptions { pairs: vec!["0-12".into()], ..options(false) };
        let e = interpolation_eval(&worm(30.0), &o).unwrap_err();
        assert_eq!(e.to_string(), "--pair \"0-12\": expected FROM,TO");
        let o = InterpolationOptions { pairs: vec!["0,99".into()], ..options(false) };
        assert!(matches!(interpolation_eval(&worm(30.0), &o).unwrap_err(), Error::Data(_)));
    }
}

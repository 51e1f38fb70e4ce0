//! `surfcap bench interpolate`: one non-linear interpolation, set-up and per-lambda times.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use super::open_quietly;

pub(super) fn run(
    ctx: &crate::Ctx,
    subject: PathBuf,
    from: &str,
    to: &str,
    repeat: usize,
    fps: Option<f64>,
) -> anyhow::Result<()> {
    use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
    let s = open_quietly(&subject, fps)?;
    let (gi, gj) = (s.resolve_frame(from)?, s.resolve_frame(to)?);
    let (pi, pj) = (s.frame(gi).expect("resolved"), s.frame(gj).expect("resolved"));
    let mut setup = Vec::new();
    let mut solve = Vec::new();
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        let it = NonlinearInterpolator::new(s.topology(), pi, pj, s.up_axis)?;
        setup.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        std::hint::black_box(it.at(0.5, StretchInterpolation::Linear));
        solve.push(t1.elapsed().as_secs_f64());
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (su, so) = (med(&mut setup), med(&mut solve));
    let report = json!({
        "vertices": s.topology().n_vertices(), "triangles": s.topology().n_triangles(),
        "setup_seconds_median": su, "lambda_seconds_median": so, "total_seconds_median": su + so,
        "runs": repeat.max(1),
    });
    ctx.result(&report, || {
        println!(
            "non-linear interpolation, {} vertices: set-up (alignment, polar factors, 1 symbolic + 2 numeric Cholesky) \
             {:.1} ms, one lambda (2 x Poisson solves) {:.1} ms, total {:.1} ms (medians of {})",
            s.topology().n_vertices(),
            su * 1e3,
            so * 1e3,
            (su + so) * 1e3,
            repeat.max(1)
        );
    });
    Ok(())
}

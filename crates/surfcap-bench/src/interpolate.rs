//! `surfcap-bench interpolate`: one non-linear interpolation, set-up and per-lambda times.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use crate::measure::FpsOpt;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache or source.
    pub subject: PathBuf,
    #[arg(long)]
    pub from: String,
    #[arg(long)]
    pub to: String,
    /// Repetitions, 1 to 100.
    #[arg(long, default_value_t = 5, value_parser = |s: &str| crate::options::whole_in(s, 1, 100))]
    pub repeat: usize,
    #[command(flatten)]
    pub fps: FpsOpt,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    use surfcap_geometry::pose_interpolation::{NonlinearInterpolator, StretchInterpolation};
    let Args { subject, from, to, repeat, fps } = a;
    let s = fps.open_quietly(&subject)?;
    let (gi, gj) = (s.resolve_frame(&from)?, s.resolve_frame(&to)?);
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

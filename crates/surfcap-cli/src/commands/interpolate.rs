//! `surfcap interpolate <subject> --from seq:frame --to seq:frame --steps K -o out.glb`

use std::path::PathBuf;

use serde_json::json;
use surfcap_formats::export::{ExportFormat, export};
use surfcap_geometry::pose_interpolation::StretchInterpolation;
use surfcap_synthesis::interpolation_run::{InterpolationMethod, interpolate};

use crate::limits::{LimitOpts, Request};
use crate::options::{SourceOpts, open};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A subject cache, or any source `surfcap import` reads.
    pub subject: PathBuf,
    /// First pose: sequence:frame (0-based) or a global frame number.
    #[arg(long)]
    pub from: String,
    /// Last pose.
    #[arg(long)]
    pub to: String,
    /// Number of poses written, both ends included (>= 2).
    #[arg(long, default_value_t = 10, value_parser = |s: &str| crate::options::at_least(s, 2))]
    pub steps: usize,
    /// nonlinear (thesis eq. 2.45-2.49) or linear (eq. 2.23).
    #[arg(long, default_value = "nonlinear")]
    pub method: InterpolationMethod,
    /// Stretch interpolation of the non-linear method: linear (eq. 2.45) or log (eq. 2.46).
    #[arg(long, default_value = "linear")]
    pub stretch: StretchInterpolation,
    /// Output .glb (a sidecar .json is written next to it); .npy, .obj folders via --format.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format: glb, obj, ply, pc2, npy, usda or abc.
    #[arg(long, default_value = "glb")]
    pub format: ExportFormat,
    #[command(flatten)]
    pub source: SourceOpts,
    #[command(flatten)]
    pub limits: LimitOpts,
    /// With --appearance, the in-between poses' textures are the two frames interpolated in the
    /// eigen spaces with the same weight as the geometry (thesis 4.6.1, Fig. 7.1).
    #[command(flatten)]
    pub appearance: crate::synthesis_args::AppearanceOpts,
}

pub fn run(ctx: &crate::Ctx, a: Args) -> anyhow::Result<()> {
    let (format, stretch, nonlinear) = (a.format, a.stretch, a.method == InterpolationMethod::Nonlinear);
    let mut inputs = vec![a.subject.as_path()];
    inputs.extend(a.appearance.appearance.as_deref());
    let mut outs = surfcap_mesh::output_set::OutputSet::new(&inputs);
    surfcap_formats::export::plan_export(&mut outs, format, &a.output, ctx.force)?;
    let s = open(ctx, &a.subject, &a.source)?;
    let what = format!("--steps {}", a.steps);
    a.limits.check(ctx, &a.output, &Request { what, frames: a.steps as f64, subject: &s, search_bytes: 0, format })?;
    let (gi, gj) = (s.resolve_frame(&a.from)?, s.resolve_frame(&a.to)?);
    let appearance = a.appearance.open(&s, format, &a.output)?;
    let t0 = std::time::Instant::now();
    let made = interpolate(&s, (gi, &a.from), (gj, &a.to), a.steps, a.method, stretch)?;
    let (out, mix, setup) = (made.animation, made.mix, made.setup_seconds);
    let bar = crate::progress::Bar::new(ctx);
    let (written, textures) = match &appearance {
        Some(app) => {
            let textured = app.textures(&mix, &bar)?;
            (
                surfcap_synthesis::frame_appearance::write_textured(&out, &textured, &a.output, &bar)?,
                Some(textured.report),
            )
        }
        None => (export(&out, format, &a.output, ctx.export_options(), &bar)?, None),
    };
    drop(bar);
    ctx.commit(outs)?;
    // Frames as users write them (`sequence:frame`); the JSON keeps the global numbers too.
    let (from, to) = (s.frame_index().label(gi), s.frame_index().label(gj));
    let mut result = json!({ "written": written, "from": gi, "to": gj, "from_frame": from, "to_frame": to, "steps": a.steps, "setup_seconds": setup, "total_seconds": t0.elapsed().as_secs_f64() });
    if let Some(t) = textures {
        result["appearance"] = serde_json::to_value(t)?;
    }
    ctx.result(&result, || {
        println!(
            "{} interpolation of {from} -> {to} in {} poses -> {} (set-up {:.3} s, total {:.3} s)",
            if nonlinear { "nonlinear" } else { "linear" },
            a.steps,
            a.output.display(),
            setup,
            t0.elapsed().as_secs_f64()
        );
    });
    Ok(())
}

//! `surfcap eval smg`: Huang et al. 2009's Table 1 for the surface motion graph on the
//! CMU-driven mannequin (`surfcap_eval::smg_eval` computes it; this command writes `smg.json`
//! and prints one row per key-frame pair beside the paper's own figures).

use std::path::Path;

use surfcap_eval::smg_eval::{
    LOCOMOTION_CONNECTIONS, LOCOMOTION_KEY_PAIRS, SmgEvalOptions, locomotion_subject, smg_eval,
};
use surfcap_smg::motion_frames::MotionFrames;

pub fn run(
    ctx: &crate::Ctx,
    data: &Path,
    vertices: usize,
    remeshed: Option<u64>,
    cache: &crate::options::CacheOpts,
    output: &Path,
) -> anyhow::Result<()> {
    let subject = locomotion_subject(data, vertices)?;
    let bar = crate::progress::Bar::new(ctx);
    // Either the shared topology, or every frame re-meshed on its own (issue 17 item 1): the
    // same motion without any correspondence between frames.
    let (frames, form) = match remeshed {
        None => (MotionFrames::from_subject(&subject), "shared topology".to_string()),
        Some(seed) => {
            let opts = surfcap_synth::frame_remeshing::RemeshFramesOptions { seed, ..Default::default() };
            let set = surfcap_synth::frame_remeshing::remesh_subject_frames(&subject, &opts, &bar)?;
            (MotionFrames::from_frame_set(&set), format!("every frame re-meshed (seed {seed})"))
        }
    };
    let store = surfcap_mesh::derived_cache::DerivedCache::new(cache.dir());
    let r = smg_eval(
        &frames,
        &form,
        &LOCOMOTION_CONNECTIONS,
        &LOCOMOTION_KEY_PAIRS,
        &SmgEvalOptions::default(),
        Some((&store, cache.no_cache)),
        &bar,
    )?;
    let (report, path) = super::save_report(output, "smg.json", &r, "written", &[])?;
    ctx.result(&report, || {
        println!(
            "surface motion graph ({}): {} frames of {}-{} vertices, {} nodes, {} edges; similarity {:.1} s{}",
            r.form,
            r.frames,
            r.vertices_min,
            r.vertices_max,
            r.graph_nodes,
            r.graph_edges,
            r.similarity_seconds,
            if r.similarity_cached { " (cached)" } else { "" }
        );
        for t in &r.transitions {
            println!("  transition {} -> {} (window {}, cost {:.4}, smoothness {:.1} cm)", t.from, t.to, t.window, t.cost, 100.0 * t.smoothness);
        }
        println!(
            "{:<22} {:>7} {:>7} {:>7} {:>7} {:>7} {:>6} {:>6} {:>6} {:>14}",
            "key frames", "smooth", "(cm)", "dist", "err", "(m)", "time", "err", "(fr)", "cpu ms"
        );
        println!("{:<22} {:>7} {:>7} {:>7} {:>7} {:>7} {:>6} {:>6} {:>6} {:>14}", "", "min", "max", "min", "rms", "max", "min", "rms", "max", "mean +- std");
        for p in &r.pairs {
            println!(
                "{:<22} {:>7.1} {:>7.1} {:>7.3} {:>7.2} {:>7.2} {:>6.0} {:>6.1} {:>6.0} {:>7.2} +- {:<5.2}",
                format!("{} -> {}", p.from, p.to),
                100.0 * p.smoothness_min,
                100.0 * p.smoothness_max,
                p.distance_error.min,
                p.distance_error.rms,
                p.distance_error.max,
                p.time_error_frames.min,
                p.time_error_frames.rms,
                p.time_error_frames.max,
                1e3 * p.cpu_seconds.mean,
                1e3 * p.cpu_seconds.std
            );
        }
        println!(
            "Huang et al. 2009 (Table 1): distance error rms 0.17-0.47 m, max < 1 m; time error max 22-25 frames; 5.7-15.0 s per query (Matlab)"
        );
        println!("wrote {}", path.display());
    });
    Ok(())
}

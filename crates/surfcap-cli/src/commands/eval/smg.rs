//! `surfcap eval smg`: Huang et al. 2009's Table 1 for the surface motion graph on the
//! CMU-driven mannequin, or on any subject or frame set (`--input` with `--connect` and `--pair`) (`surfcap_eval::smg_eval` computes it; this command writes `smg.json`
//! and prints one row per key-frame pair beside the paper's own figures).

use std::path::{Path, PathBuf};

use surfcap_mesh::import::{ImportedData, open_any};

use surfcap_eval::smg_eval::{
    LOCOMOTION_CONNECTIONS, LOCOMOTION_KEY_PAIRS, SmgEvalOptions, locomotion_subject, smg_eval,
};
use surfcap_smg::motion_frames::MotionFrames;

/// A user's subject or frame set to evaluate instead of the mannequin.
pub struct Input {
    pub path: PathBuf,
    pub connect: Vec<String>,
    pub pairs: Vec<String>,
    pub source: crate::options::SourceOpts,
}

/// `A<sep>B` split at its last `sep`.
fn split_pair(text: &str, sep: char, option: &str, expected: &str) -> anyhow::Result<(String, String)> {
    text.rsplit_once(sep)
        .map(|(a, b)| (a.trim().to_string(), b.trim().to_string()))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty())
        .ok_or_else(|| anyhow::anyhow!("{option} {text:?}: expected {expected}"))
}

/// The evaluation's choices: the mannequin's vertices, re-meshing, transitions per connection.
pub struct Options {
    pub vertices: usize,
    pub remeshed: Option<u64>,
    pub transitions: usize,
}

pub fn run(
    ctx: &crate::Ctx,
    data: &Path,
    Options { vertices, remeshed, transitions }: Options,
    input: Option<Input>,
    cache: &crate::options::CacheOpts,
    output: &Path,
) -> anyhow::Result<()> {
    let bar = crate::progress::Bar::new(ctx);
    // The subject: the CMU mannequin, or the user's; a frame set is used as it is.
    let data = match &input {
        None => ImportedData::Subject(surfcap_mesh::import::Imported {
            subject: locomotion_subject(data, vertices)?,
            notes: Vec::new(),
            sources: Vec::new(),
        }),
        Some(i) => open_any(&i.path, &i.source.to_import(None)?, &bar)?,
    };
    // Either the shared topology, or every frame re-meshed on its own (issue 17 item 1): the
    // same motion without any correspondence between frames.
    let (frames, form) = match (data, remeshed) {
        (ImportedData::FrameSet(f), _) => (MotionFrames::from_frame_set(&f.frame_set), "frame set".to_string()),
        (ImportedData::Subject(s), None) => (MotionFrames::from_subject(&s.subject), "shared topology".to_string()),
        (ImportedData::Subject(s), Some(seed)) => {
            let opts = surfcap_synth::frame_remeshing::RemeshFramesOptions { seed, ..Default::default() };
            let set = surfcap_synth::frame_remeshing::remesh_subject_frames(&s.subject, &opts, &bar)?;
            (MotionFrames::from_frame_set(&set), format!("every frame re-meshed (seed {seed})"))
        }
    };
    // Sequence pairs of the higher-level graph, and key-frame pairs.
    type Pairs = Vec<(String, String)>;
    let (connections, pairs): (Pairs, Pairs) = match &input {
        None => (
            LOCOMOTION_CONNECTIONS.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
            LOCOMOTION_KEY_PAIRS.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ),
        Some(i) => {
            if i.connect.is_empty() || i.pairs.is_empty() {
                anyhow::bail!("--input needs --connect FROM:TO and --pair FROM,TO (each sequence:frame)");
            }
            let c =
                i.connect.iter().map(|t| split_pair(t, ':', "--connect", "FROM:TO")).collect::<anyhow::Result<_>>()?;
            let p = i
                .pairs
                .iter()
                .map(|t| split_pair(t, ',', "--pair", "FROM,TO (each sequence:frame)"))
                .collect::<anyhow::Result<_>>()?;
            (c, p)
        }
    };
    let connections: Vec<(&str, &str)> = connections.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let pairs: Vec<(&str, &str)> = pairs.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let store = surfcap_mesh::derived_cache::DerivedCache::new(cache.dir());
    let r = smg_eval(
        &frames,
        &form,
        &connections,
        &pairs,
        &SmgEvalOptions { per_connection: transitions, ..SmgEvalOptions::default() },
        Some((&store, cache.no_cache)),
        &bar,
    )?;
    let (report, path) = super::save_report(output, "smg.json", &r, "written", &[])?;
    ctx.result(&report, || {
        println!(
            "surface motion graph ({}, {} transition(s) per connection): {} frames of {}-{} vertices, {} nodes, {} edges; similarity {:.1} s{}",
            r.form,
            r.per_connection,
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
        for p in &r.pairs {
            let g = &p.goal;
            let why: Vec<String> = g.unreachable.iter().map(|(k, n)| format!("{n} {k}")).collect();
            println!(
                "goal ({}% and {} frame): {} -> {}: {} of {} targets met (worst {:.2}% and {} frame(s)); unreachable: {}; cpu {:.2} +- {:.2} ms",
                100.0 * g.tolerance.distance_relative,
                g.tolerance.frames,
                p.from,
                p.to,
                g.met,
                p.queries,
                100.0 * g.met_distance_relative_max,
                g.met_time_error_max,
                if why.is_empty() { "none".to_string() } else { why.join(", ") },
                1e3 * g.cpu_seconds.mean,
                1e3 * g.cpu_seconds.std
            );
        }
        println!(
            "Huang et al. 2009 (Table 1): distance error rms 0.17-0.47 m, max < 1 m; time error max 22-25 frames; 5.7-15.0 s per query (Matlab)"
        );
        println!("wrote {}", path.display());
    });
    Ok(())
}

//! What `surfcap info` (and the demo) say about a subject: sequences, frames, vertices,
//! triangles, components, bounding box, which clips loop.

use serde_json::json;
use surfcap_mesh::{Subject, bounding_box, connected_components};

/// Everything `info` reports, as JSON.
pub fn describe(s: &Subject) -> serde_json::Value {
    let topo = s.topology();
    let comps = connected_components(topo);
    let mut sizes = comps.sizes();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut degenerate_frames = 0usize;
    let mut seqs = Vec::new();
    let loops = surfcap_motion::clip_loops::clip_loops(s);
    for (k, q) in s.sequences().iter().enumerate() {
        let wrap = loops.iter().find(|l| l.sequence == k);
        let (a, b) = bounding_box(q.positions());
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
        let mut zero_area = 0usize;
        for f in 0..q.n_frames() {
            let n = topo.count_degenerate_triangles(q.frame(f), 0.0);
            if n > 0 {
                degenerate_frames += 1;
                zero_area = zero_area.max(n);
            }
        }
        let synthetic = q.labels.iter().filter(|l| **l == surfcap_mesh::FrameLabel::Synthetic).count();
        seqs.push(json!({
            "name": q.name,
            "frames": q.n_frames(),
            "seconds": q.n_frames() as f64 / s.fps,
            "tags": q.tags,
            "synthetic_frames": synthetic,
            "joints": q.joints.as_ref().map(|j| j.n_joints()),
            "max_zero_area_triangles_in_a_frame": zero_area,
            // Authored as a loop: last pose within the clip's largest step of the first (in
            // the body frame); synthesis plays its last frame into its start.
            "loops": wrap.is_some(),
            "loop_wraps_to_frame": wrap.map(|l| l.first as usize - s.frame_index().range(k).start),
        }));
    }
    json!({
        "subject": s.name,
        "fps": s.fps,
        "up_axis": s.up_axis.as_str(),
        "units": s.units,
        "sequences": seqs,
        "frames": s.n_frames(),
        "vertices": topo.n_vertices(),
        "triangles": topo.n_triangles(),
        "has_uv": topo.uv().is_some(),
        "connected_components": comps.count,
        "component_sizes": sizes,
        "bounding_box": { "min": lo, "max": hi },
        "frames_with_zero_area_triangles": degenerate_frames,
    })
}

/// Prints the summary `describe` computed, for humans.
pub fn print_summary(s: &Subject, d: &serde_json::Value) {
    let units = &s.units;
    println!("subject     {}", s.name);
    println!(
        "frames      {} in {} at {} fps",
        s.n_frames(),
        crate::output::count_of(s.sequences().len(), "sequence"),
        s.fps
    );
    println!("vertices    {}", d["vertices"]);
    println!("triangles   {}", d["triangles"]);
    let comps_count = d["connected_components"].as_u64().unwrap_or(0);
    let sizes: Vec<String> = d["component_sizes"].as_array().unwrap().iter().take(8).map(|x| x.to_string()).collect();
    let more = if comps_count > 8 { ", ..." } else { "" };
    println!("components  {} (vertices: {}{more})", d["connected_components"], sizes.join(", "));
    let bb = |k: &str| -> String {
        let v: Vec<String> = d["bounding_box"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| format!("{:.4}", x.as_f64().unwrap_or(0.0)))
            .collect();
        format!("({})", v.join(", "))
    };
    println!("bounds      {} .. {} {}", bb("min"), bb("max"), units.symbol());
    println!("up axis     {}", s.up_axis.as_str());
    println!("units       {}", crate::output::units_line(units));
    if d["frames_with_zero_area_triangles"].as_u64() != Some(0) {
        println!(
            "note        {} frames contain zero-area triangles (in the data)",
            d["frames_with_zero_area_triangles"]
        );
    }
    println!("sequences");
    let w = s.sequences().iter().map(|q| q.name.len()).max().unwrap_or(4).max(4);
    for q in d["sequences"].as_array().unwrap() {
        let tags: Vec<&str> = q["tags"].as_array().unwrap().iter().filter_map(|t| t.as_str()).collect();
        let joints = q["joints"].as_u64().map(|j| format!("  {j} joints")).unwrap_or_default();
        let synth = match q["synthetic_frames"].as_u64() {
            Some(0) | None => String::new(),
            Some(n) => format!("  {n} synthetic"),
        };
        let loops = if q["loops"].as_bool() == Some(true) { "  loops" } else { "" };
        println!(
            "  {:w$}  {:5} frames  {:7.2} s{}{}{}{loops}",
            q["name"].as_str().unwrap_or(""),
            q["frames"],
            q["seconds"].as_f64().unwrap_or(0.0),
            if tags.is_empty() { String::new() } else { format!("  [{}]", tags.join(", ")) },
            joints,
            synth,
        );
    }
}

//! Files `surfcap view` hands to the page to decode and play itself, rather than decoding them
//! here: a compact stream (`.scstream`) and a skinned rig (a glb written by `surfcap rig` or
//! `synth --format rig-glb`). One item per sequence (a stream's) or animation (a rig's), all
//! sharing the file's bytes; see `surfcap_view::PlayedFile`.
//!
//! Here only the file's header is read (a stream's JSON header, topology and frame table; a
//! rig's glTF JSON), so a bad file is refused with its name before the page opens; the frames
//! themselves are decoded in the page, frame by frame, so a long stream starts playing at once
//! and is never held whole in memory twice.

use std::path::Path;
use std::sync::Arc;

use surfcap_formats::stream::StreamFile;
use surfcap_mesh::{FrameLabel, Units};
use surfcap_view::{PlayedFile, PlayedKind, ViewItem};

/// What a played item shares with every other item.
fn item(name: &str, fps: f64, up: &str, units: &Units, n_vertices: usize, synthetic: Vec<bool>) -> ViewItem {
    ViewItem {
        name: name.to_string(),
        fps,
        up: up.to_string(),
        units: units.symbol().to_string(),
        metres_per_unit: units.metres_per_unit,
        n_vertices,
        n_frames: synthetic.len(),
        synthetic,
        ..ViewItem::default()
    }
}

/// The items of `p` when the page plays it itself (a `.scstream`, or a glb holding a surfcap
/// rig), restricted to the sequences `only` names (all when empty), every sequence's name added
/// to `names`; `None` for any other file.
pub fn played_items(p: &Path, only: &[String], names: &mut Vec<String>) -> anyhow::Result<Option<Vec<ViewItem>>> {
    let ext = p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("scstream") => {
            let bytes = surfcap_mesh::read_regular_file(p)?;
            stream_items(p, bytes, only, names).map(Some)
        }
        Some("glb") if p.is_file() => {
            let bytes = surfcap_mesh::read_regular_file(p)?;
            let Some(doc) = rig_json(&bytes) else { return Ok(None) };
            rig_items(p, &doc, bytes, only, names).map(Some)
        }
        _ => Ok(None),
    }
}

/// A stream's items: each sequence played from its key frame, framed by the stream's grid box.
fn stream_items(p: &Path, bytes: Vec<u8>, only: &[String], names: &mut Vec<String>) -> anyhow::Result<Vec<ViewItem>> {
    let h = StreamFile::parse(&bytes).map_err(|e| e.in_file(p))?.header;
    // Every position is min + q * step with q on the grid (0 to 2^bits - 1).
    let top = ((1u64 << h.bits) - 1) as f64;
    let max = [0, 1, 2].map(|a| h.min[a] + top * h.step[a]);
    let bytes = Arc::new(bytes);
    let mut items = Vec::new();
    for (index, q) in h.sequences.iter().enumerate() {
        names.push(q.name.clone());
        if !(only.is_empty() || only.contains(&q.name)) {
            continue;
        }
        let synthetic = q.labels.iter().map(|l| *l == FrameLabel::Synthetic).collect();
        let mut it = item(&q.name, h.fps, h.up_axis.as_str(), &h.units, h.vertices, synthetic);
        it.played =
            Some(PlayedFile { kind: PlayedKind::Stream, index, bounds: Some([h.min, max]), bytes: bytes.clone() });
        items.push(it);
    }
    Ok(items)
}

/// The glTF JSON of a glb that holds a surfcap rig (a skin and `extras.surfcap.rig`), else `None`.
fn rig_json(bytes: &[u8]) -> Option<serde_json::Value> {
    if bytes.len() < 20 || &bytes[..4] != b"glTF" || &bytes[16..20] != b"JSON" {
        return None;
    }
    let len = u32::from_le_bytes(bytes[12..16].try_into().ok()?) as usize;
    let doc: serde_json::Value = serde_json::from_slice(bytes.get(20..20 + len)?).ok()?;
    let skinned = doc["skins"].as_array().is_some_and(|s| !s.is_empty());
    (skinned && doc["extras"]["surfcap"]["rig"].is_object()).then_some(doc)
}

/// A rig's items: one per animation, with the rig's fps, up axis and units.
fn rig_items(
    p: &Path,
    doc: &serde_json::Value,
    bytes: Vec<u8>,
    only: &[String],
    names: &mut Vec<String>,
) -> anyhow::Result<Vec<ViewItem>> {
    let bad = |what: &str| anyhow::anyhow!("{}: a skinned rig whose {what}", p.display());
    let meta = &doc["extras"]["surfcap"];
    let fps = meta["fps"].as_f64().filter(|f| *f > 0.0).ok_or_else(|| bad("extras.surfcap.fps is not a frame rate"))?;
    let up = meta["up_axis"].as_str().ok_or_else(|| bad("extras.surfcap.up_axis is missing"))?;
    let units: Units =
        serde_json::from_value(meta["units"].clone()).map_err(|e| bad(&format!("units cannot be read: {e}")))?;
    let prim = &doc["meshes"][0]["primitives"][0]["attributes"];
    if !prim["JOINTS_1"].is_null() {
        anyhow::bail!(
            "{}: the rig moves some vertices by more than 4 bones (JOINTS_1); three.js, which the viewer plays rigs with, takes at most 4: rig it again with --max-influences 4 to view it",
            p.display()
        );
    }
    let n_vertices = prim["POSITION"]
        .as_u64()
        .and_then(|a| doc["accessors"][a as usize]["count"].as_u64())
        .ok_or_else(|| bad("mesh has no POSITION accessor"))? as usize;
    let animations = doc["animations"].as_array().filter(|a| !a.is_empty()).ok_or_else(|| bad("has no animation"))?;
    let bytes = Arc::new(bytes);
    let mut items = Vec::new();
    for (index, a) in animations.iter().enumerate() {
        let name = a["name"].as_str().ok_or_else(|| bad(&format!("animation {index} has no name")))?;
        names.push(name.to_string());
        if !(only.is_empty() || only.contains(&name.to_string())) {
            continue;
        }
        let frames = a["extras"]["surfcap"]["frames"]
            .as_u64()
            .filter(|&n| n > 0)
            .ok_or_else(|| bad(&format!("animation {name:?} does not say its frames (extras.surfcap.frames)")))?;
        let mut it = item(name, fps, up, &units, n_vertices, vec![false; frames as usize]);
        it.played = Some(PlayedFile { kind: PlayedKind::Rig, index, bounds: None, bytes: bytes.clone() });
        items.push(it);
    }
    Ok(items)
}

//! A subject's or a frame set's sequences as the viewer's items (what `view` and `parts show`
//! serve): one item per sequence with its frames, faces, frame labels and the units; no overlay
//! or colours (the commands add theirs).

use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::{FrameLabel, Subject};
use surfcap_view::ViewItem;

/// Items of the sequences of `s` named in `only` (every sequence when empty).
pub fn view_items(s: &Subject, only: &[String]) -> Vec<ViewItem> {
    let faces: Vec<u32> = s.topology().triangles().iter().flatten().copied().collect();
    s.sequences()
        .iter()
        .filter(|q| only.is_empty() || only.contains(&q.name))
        .map(|q| ViewItem {
            name: q.name.clone(),
            fps: s.fps,
            up: s.up_axis.as_str().to_string(),
            units: s.units.name.clone(),
            metres_per_unit: s.units.metres_per_unit,
            n_vertices: q.n_vertices(),
            n_frames: q.n_frames(),
            frame_vertices: None,
            frame_triangles: None,
            synthetic: q.labels.iter().map(|l| *l == FrameLabel::Synthetic).collect(),
            faces: faces.clone(),
            positions: q.positions().to_vec(),
            overlay: None,
            colours: None,
            colour_legend: Vec::new(),
        })
        .collect()
}

/// Items of a frame set's sequences named in `only` (every sequence when empty): each frame's
/// own mesh, one after the other, with the per-frame counts the page steps through.
pub fn frame_set_items(s: &FrameSet, only: &[String]) -> Vec<ViewItem> {
    s.sequences()
        .iter()
        .filter(|q| only.is_empty() || only.contains(&q.name))
        .map(|q| {
            let frames = q.frames();
            ViewItem {
                name: q.name.clone(),
                fps: s.fps,
                up: s.up_axis.as_str().to_string(),
                units: s.units.name.clone(),
                metres_per_unit: s.units.metres_per_unit,
                n_vertices: q.vertex_count_range().1,
                n_frames: q.n_frames(),
                frame_vertices: Some(frames.iter().map(|f| f.n_vertices()).collect()),
                frame_triangles: Some(frames.iter().map(|f| f.n_triangles()).collect()),
                synthetic: q.labels().iter().map(|l| *l == FrameLabel::Synthetic).collect(),
                faces: frames.iter().flat_map(|f| f.topology().triangles().iter().flatten().copied()).collect(),
                positions: frames.iter().flat_map(|f| f.positions().iter().copied()).collect(),
                overlay: None,
                colours: None,
                colour_legend: Vec::new(),
            }
        })
        .collect()
}

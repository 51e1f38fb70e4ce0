//! A subject's or a frame set's sequences as the viewer's items (what `view` and `parts show`
//! serve): one item per sequence with its frames, faces, frame labels and the units, and, given
//! a texture per frame, its texture coordinates and textures; no overlay or colours (the
//! commands add theirs).

use anyhow::Context;
use surfcap_mesh::frame_set::FrameSet;
use surfcap_mesh::{FrameLabel, FrameTextures, Subject, UvVertices};
use surfcap_view::ViewItem;

/// Items of the sequences of `s` named in `only` (every sequence when empty).
pub fn view_items(s: &Subject, only: &[String]) -> Vec<ViewItem> {
    let faces: Vec<u32> = s.topology().triangles().iter().flatten().copied().collect();
    s.sequences()
        .iter()
        .filter(|q| only.is_empty() || only.contains(&q.name))
        .map(|q| ViewItem {
            name: q.name.clone(),
            label: None,
            fps: s.fps,
            up: s.up_axis.as_str().to_string(),
            units: s.units.symbol().to_string(),
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
            uvs: None,
            textures: Vec::new(),
            frame_textures: None,
            field: None,
            played: None,
        })
        .collect()
}

/// [`view_items`] with a texture per frame (`textures`, one index per frame of every sequence of
/// `s`): the subject's vertices split along its atlas's seams ([`UvVertices`]), so each carries
/// one texture coordinate, and each item the textures with its frames' indices. An error when
/// the subject has no UV atlas or the textures do not have one index per frame.
pub fn view_items_textured(s: &Subject, textures: &FrameTextures, only: &[String]) -> anyhow::Result<Vec<ViewItem>> {
    textures.check_frames(s.frame_index())?;
    let split = UvVertices::new(s.topology())
        .with_context(|| format!("{}: textures given but the subject has no texture coordinates", s.name))?;
    let uvs: Vec<f32> = split.coords(s.topology().uv().expect("split")).into_iter().flatten().collect();
    let faces: Vec<u32> = split.triangles.iter().flatten().copied().collect();
    let mut items = Vec::new();
    for (k, (q, mut it)) in s.sequences().iter().zip(view_items(s, &[])).enumerate() {
        if !(only.is_empty() || only.contains(&q.name)) {
            continue;
        }
        it.n_vertices = split.len();
        it.positions = (0..q.n_frames()).flat_map(|f| split.positions(q.frame(f))).collect();
        it.faces = faces.clone();
        it.uvs = Some(uvs.clone());
        it.textures = textures.images().to_vec();
        it.frame_textures = Some(textures.frames()[k].clone());
        items.push(it);
    }
    Ok(items)
}

/// Items of a frame set's sequences named in `only` (every sequence when empty): each frame's
/// own mesh, one after the other, with the per-frame counts the page steps through. With
/// `textures` (one index per frame), every frame's vertices are split along its atlas's seams
/// and carry their texture coordinates; an error when a frame has no atlas.
pub fn frame_set_items(
    s: &FrameSet,
    textures: Option<&FrameTextures>,
    only: &[String],
) -> anyhow::Result<Vec<ViewItem>> {
    if let Some(t) = textures {
        t.check_frames(s.frame_index())?;
    }
    let ix = s.frame_index();
    let mut items = Vec::new();
    for (k, q) in s.sequences().iter().enumerate() {
        if !(only.is_empty() || only.contains(&q.name)) {
            continue;
        }
        let frames = q.frames();
        let mut item = ViewItem {
            name: q.name.clone(),
            label: None,
            fps: s.fps,
            up: s.up_axis.as_str().to_string(),
            units: s.units.symbol().to_string(),
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
            uvs: None,
            textures: Vec::new(),
            frame_textures: None,
            field: None,
            played: None,
        };
        if let Some(t) = textures {
            let (mut nv, mut faces, mut positions, mut uvs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (f, frame) in frames.iter().enumerate() {
                let sp = UvVertices::new(frame.topology()).with_context(|| {
                    format!("frame {} has a texture but no texture coordinates", ix.label(ix.range(k).start + f))
                })?;
                nv.push(sp.len());
                faces.extend(sp.triangles.iter().flatten());
                positions.extend(sp.positions(frame.positions()));
                uvs.extend(sp.coords(frame.topology().uv().expect("split")).into_iter().flatten());
            }
            item.n_vertices = nv.iter().copied().max().unwrap_or(0);
            item.frame_vertices = Some(nv);
            (item.faces, item.positions, item.uvs) = (faces, positions, Some(uvs));
            item.textures = t.images().to_vec();
            item.frame_textures = Some(t.frames()[k].clone());
        }
        items.push(item);
    }
    Ok(items)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{FrameSetSequence, Topology, Units, UpAxis, UvAtlas};

    /// A quad whose atlas has a seam at vertex 2, over two frames.
    fn quad() -> (Topology, Vec<f32>) {
        let uv = UvAtlas {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.3, 0.7], [0.1, 0.9]],
            corners: vec![[0, 1, 2], [0, 3, 4]],
        };
        let t = Topology::new(4, vec![[0, 1, 2], [0, 2, 3]], Some(uv)).unwrap();
        (t, vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.])
    }

    fn png() -> Vec<u8> {
        // Only the signature and an IHDR of 1 x 1 are read here.
        let mut b = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13];
        b.extend_from_slice(b"IHDR");
        b.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 1, 8, 2, 0, 0, 0]);
        b
    }

    #[test]
    fn textured_items_carry_split_vertices_uvs_and_frame_textures() {
        let (t, p) = quad();
        let textures = FrameTextures::new(vec![png(), png()], vec![vec![1, 0]]).unwrap();
        let set = FrameSet::new(
            "q",
            vec![FrameSetSequence::from_frames("a", vec![(t.clone(), p.clone()), (t, p)]).unwrap()],
            25.0,
            UpAxis::PosY,
            Units::metres(),
        )
        .unwrap();
        let items = frame_set_items(&set, Some(&textures), &[]).unwrap();
        let it = &items[0];
        it.check().unwrap();
        // 4 vertices + 1 seam copy per frame.
        assert_eq!((it.n_vertices, it.frame_vertices.as_deref()), (5, Some(&[5, 5][..])));
        assert_eq!(it.uvs.as_ref().unwrap().len(), 2 * 10);
        assert_eq!(it.frame_textures.as_deref(), Some(&[1, 0][..]));
        let s = set.into_subject().unwrap();
        let shared = view_items_textured(&s, &textures, &[]).unwrap();
        shared[0].check().unwrap();
        assert_eq!((shared[0].n_vertices, shared[0].positions.len()), (5, 2 * 15));
        assert_eq!(shared[0].uvs.as_ref().unwrap()[..10], it.uvs.as_ref().unwrap()[..10]);
        // Without UVs, a texture cannot be shown: the error names the frame.
        let plain = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let set = FrameSet::new(
            "p",
            vec![FrameSetSequence::from_frames("b", vec![(plain, vec![0.; 9])]).unwrap()],
            25.0,
            UpAxis::PosY,
            Units::metres(),
        )
        .unwrap();
        let one = FrameTextures::new(vec![png()], vec![vec![0]]).unwrap();
        let e = frame_set_items(&set, Some(&one), &[]).unwrap_err();
        assert!(e.to_string().contains("frame b:0 has a texture but no texture coordinates"), "{e}");
    }
}

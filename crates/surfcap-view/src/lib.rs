//! surfcap's viewer: a local web server bound to 127.0.0.1 serving a three.js page that plays mesh
//! sequences, colours original frames green and synthetic frames red (as the thesis's figures do),
//! overlays a user's path and the achieved centre-of-mass trajectory on the ground, colours
//! meshes by a per-vertex field with a colour bar, and plays several sequences side by side or
//! overlaid.
//!
//! The server ([`server`], axum on a current-thread tokio runtime) answers GET: the page, its
//! embedded assets ([`assets`]), the items' positions, faces, optional per-vertex colours (body
//! parts), per-vertex scalar fields ([`VertexField`]), UVs and textures as little-endian binary
//! (`/api/...`), and the files of one report folder (`/report/...`, paths confined to it);
//! anything else is 404. A `Host` header other than `127.0.0.1`, `localhost` or `[::1]` with its
//! port gets 403, against DNS rebinding. Given a [`direct::Director`] (`server::serve_directed`),
//! it also takes directions as JSON POSTs from its own page only (same `Origin`, `Content-Type:
//! application/json`): a path drawn on the ground, key poses at new times, a distance in a time,
//! or one transition of the graph, each synthesised by the front end and played in place of the
//! items ([`direct`]). An item may instead carry a file the page decodes and plays itself
//! ([`PlayedFile`], served as `/api/items/{id}/file`): a compact stream, decoded frame by frame
//! so the first frames play before the rest is decoded, or a skinned rig, played by three.js as
//! a skinned mesh (`web/formats_player.js`).
//!
//! [`play::serve_play`] serves another page, `web/play.html`, on which a keyboard or a gamepad
//! steers a captured character live: a front end's [`play::Player`] decides and blends, the
//! page streams the meshes (see [`play`]). Both servers keep to 127.0.0.1 in one way
//! ([`local_guard`]): the `Host` check, own-page JSON POSTs and the response helpers.
//!
//! The page (`web/`): play/pause, speed, arrow-key stepping, frame entry (`57` or
//! `sequence:frame`), a loop range, a timeline of original and synthetic spans with transition
//! marks; the requested path and the achieved centre track projected onto the ground plane (the
//! grid's), the centre at hip height optional, the constraints' lines and the centre's distance
//! from the path (this frame's and the largest, with the unit) from a synthesis report; view
//! presets (top, front, side, three-quarter) and a follow camera; labels over the figures; frame
//! colours, neutral, matcap or colour-map looks, wireframe, onion skin of neighbouring frames;
//! frame sets (each frame's own mesh swapped in, checked frame by frame on the server); a texture
//! per frame (each decoded once and bound at its frames); a ground grid in the subject's unit; a
//! legend of only what is drawn. The camera fits every frame's box into the part of the view the
//! info panel leaves free (`setViewOffset`, so orbiting still turns about the scene).
//!
//! For scripts (`surfcap render`, tests) the page sets `window.surfcapViewer` once everything is
//! loaded (`ready`, `nFrames`, `fps`, `setFrame(i)` and `setView(preset)` that render before
//! returning, `scene`, `camera`, `renderer`, `controls`, `groundY`, `unitSymbol`, `reload()`) and
//! dispatches the `surfcap-ready` event; `?view=<preset>&frame=<i>&ui=0` (the bare scene) and
//! `?loop=a-b` set the same from the address.
//!
//! three.js 0.187 is installed from npm at build time (`build.rs` runs `npm ci` against
//! `web/package-lock.json` when missing) and embedded with `include_str!`, so the page works
//! offline. Nothing of surfcap is a dependency: the front end turns subjects into [`ViewItem`]s.

pub mod assets;
pub mod direct;
pub mod local_guard;
// ---- live play ----
pub mod play;
// ---- end live play ----
pub mod server;

use serde::Serialize;

/// One playable sequence.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ViewItem {
    pub name: String,
    /// The figure label drawn over the item (side by side, several figures look alike); `None`:
    /// its name.
    pub label: Option<String>,
    pub fps: f64,
    /// Subject up axis as `+y`, `-z`...: the page turns it onto its own +Y.
    pub up: String,
    /// Length unit of the positions as surfcap writes it (`surfcap_mesh::Units::symbol`: `m`,
    /// `cm`, ..., or `units` when the size is unknown): the grid is labelled in it.
    pub units: String,
    /// Metres per unit, `None` for arbitrary units.
    pub metres_per_unit: Option<f64>,
    /// Vertices of a frame; for a frame set (every frame its own mesh) the largest frame's.
    pub n_vertices: usize,
    pub n_frames: usize,
    /// A frame set's vertex and triangle counts, frame by frame: `positions` then holds the
    /// frames one after the other (`[sum of vertices][3]`) and `faces` their triangles, indices
    /// local to the frame. `None` for one shared topology.
    pub frame_vertices: Option<Vec<usize>>,
    pub frame_triangles: Option<Vec<usize>>,
    /// One flag per frame: whether surfcap made it (red) rather than captured it (green).
    pub synthetic: Vec<bool>,
    #[serde(skip)]
    pub faces: Vec<u32>,
    /// `[frames][vertices][3]` positions (a frame set's: see `frame_vertices`).
    #[serde(skip)]
    pub positions: Vec<f32>,
    /// The centre trajectory a synthesis achieved, with the path it was asked to follow if any.
    pub overlay: Option<Overlay>,
    /// Optional `[vertices][3]` RGB colours in 0..1 (body parts, say), served little-endian like
    /// the positions; when given, the page draws them instead of the green/red frame colour.
    #[serde(skip)]
    pub colours: Option<Vec<f32>>,
    /// What the colours mean: `[css colour, text]` rows added to the legend.
    pub colour_legend: Vec<[String; 2]>,
    /// Optional `[vertices][2]` texture coordinates laid out as the positions are (a frame set's:
    /// every frame's one after the other), in OBJ's convention (`v` = 1 at the image's top row;
    /// the page keeps three.js's `flipY`). One per vertex, so a mesh whose atlas has seams comes
    /// with its vertices split along them (`surfcap_mesh::UvVertices`).
    #[serde(skip)]
    pub uvs: Option<Vec<f32>>,
    /// The distinct textures, encoded PNG files, served as `/api/items/{id}/textures/{k}`.
    #[serde(skip)]
    pub textures: Vec<Vec<u8>>,
    /// Per frame, the index into `textures` of the texture it shows (thesis Fig. 7.1: shape and
    /// appearance played together); `None` when the item is not textured. Drawn instead of the
    /// frame colour.
    pub frame_textures: Option<Vec<usize>>,
    /// An optional per-frame per-vertex scalar field the page can colour the mesh by, with a
    /// colour bar (one shared topology only).
    pub field: Option<VertexField>,
    /// A file the page decodes and plays itself; then `positions` and `faces` are empty (the
    /// file holds them) and the item has no colours, UVs, field or frame set.
    #[serde(skip)]
    pub played: Option<PlayedFile>,
}

/// A scalar per vertex and frame (an error, a distance, a strain) drawn as a colour map: the
/// values are served little-endian as `/api/items/{id}/field`, `[frames][vertices]` f32.
#[derive(Debug, Clone, Default, Serialize)]
pub struct VertexField {
    /// What the values are, as the colour bar says it (`transfer error against barbarian`).
    pub name: String,
    /// Their unit's symbol (`m`, `units`), or `%` for a ratio in percent (a strain).
    pub unit: String,
    /// How the values were computed, one sentence for the panel.
    pub about: String,
    /// The colour bar's range: the lowest value over every frame and the 99th percentile, so
    /// that a few outliers (a tracking glitch, a collapsed triangle) do not leave every other
    /// vertex at the bottom of the scale; values above it are drawn at the top colour.
    pub range: [f32; 2],
    /// The highest value (the bar says "≥" at its top when it is above `range[1]`).
    pub max: f32,
    #[serde(skip)]
    pub values: Vec<f32>,
}

/// A file the page decodes and plays itself, instead of positions decoded here: a compact
/// stream (`.scstream`, decoded frame by frame by `web/stream_decode.js`, so the first frames
/// play before the whole file is decoded) or a skinned rig (a glb with a skin, played by
/// three.js as a skinned mesh: its joint animation evaluated at each frame). Served as
/// `/api/items/{id}/file`; items of one file share its bytes and the page fetches them once.
#[derive(Debug, Clone, Serialize)]
pub struct PlayedFile {
    /// `stream` or `rig`.
    pub kind: PlayedKind,
    /// Which of the file's sequences (a stream's) or animations (a rig's) the item plays.
    pub index: usize,
    /// The grid box of a stream (`[min, max]` in the item's coordinates, every frame inside
    /// it), which the page frames before any frame is decoded; `None` for a rig (the page
    /// measures its frames).
    pub bounds: Option<[[f64; 3]; 2]>,
    #[serde(skip)]
    pub bytes: std::sync::Arc<Vec<u8>>,
}

/// The kinds of [`PlayedFile`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PlayedKind {
    Stream,
    Rig,
}

impl VertexField {
    /// A field of `values` with its range set from them (finite values only; NaN: no value).
    pub fn new(name: String, unit: String, about: String, values: Vec<f32>) -> VertexField {
        let mut finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if finite.is_empty() {
            return VertexField { name, unit, about, range: [0.0, 0.0], max: 0.0, values };
        }
        let lo = finite.iter().copied().fold(f32::INFINITY, f32::min);
        let max = finite.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let k = ((finite.len() - 1) as f64 * 0.99).round() as usize;
        let (_, p99, _) = finite.select_nth_unstable_by(k, f32::total_cmp);
        VertexField { name, unit, about, range: [lo, *p99], max, values }
    }
}

impl ViewItem {
    /// Whether the item carries per-vertex colours (what the page reads to fetch them).
    pub fn has_colours(&self) -> bool {
        self.colours.is_some()
    }

    /// Whether the item carries a per-vertex scalar field (served as `/api/items/{id}/field`).
    pub fn has_field(&self) -> bool {
        self.field.is_some()
    }

    /// Whether the item carries texture coordinates (served as `/api/items/{id}/uvs`).
    pub fn has_uvs(&self) -> bool {
        self.uvs.is_some()
    }
}

/// The 8 bytes every PNG file starts with.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// What a synthesis report adds to its animation: `centres` has one point per frame; `curve`
/// is there only for path following (`reach` has a distance to cover, not a path).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Overlay {
    pub curve: Option<Vec<[f64; 3]>>,
    pub centres: Vec<[f64; 3]>,
    /// Frames at which the animation jumps to another part of the data (the surface motion
    /// graph's transitions, which play captured frames only): marked on the timeline.
    pub transitions: Vec<usize>,
    /// What was asked and achieved, one line per constraint (`distance: 3.02 of 3 m asked`),
    /// shown in the panel.
    pub constraints: Vec<String>,
    /// Per frame, the centre's distance from the requested path (path following only), in the
    /// item's unit: the panel shows the current frame's and the largest.
    pub centre_errors: Option<Vec<f64>>,
}

/// Why an item cannot be shown.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("{0}: {1} positions is not frames x vertices x 3 with {2} vertices")]
    Shape(String, usize, usize),
    #[error("{0}: {1} frame labels for {2} frames")]
    Labels(String, usize, usize),
    #[error("{0}: face index {1} is not a vertex (expected 0 to {last})", last = .2.saturating_sub(1))]
    Face(String, u32, usize),
    #[error("{0}: {1} per-frame counts for {2} frames, or they do not add up to the positions and faces")]
    FrameCounts(String, usize, usize),
    #[error("{0}: transition mark at frame {1}, past the last frame ({2})")]
    Transition(String, usize, usize),
    #[error("{0}: {1} colour-map values: expected one per vertex and frame ({2}), for one shared mesh")]
    Field(String, usize, usize),
    #[error("{0}: {1} colour values: expected 3 per vertex ({2})")]
    Colours(String, usize, usize),
    #[error("{0}: {1} texture coordinates: expected 2 per vertex ({2}), finite")]
    Uvs(String, usize, usize),
    #[error("{0}: {1}")]
    Textures(String, String),
    #[error("{0}: a file the page plays itself (a stream or a rig) carries its own positions and faces; {1}")]
    Played(String, String),
    #[error("{0}: the sequence has no frames")]
    Empty(String),
    #[error("nothing to show: no sequence was given")]
    NoItems,
    #[error("cannot listen on {0}: {1}")]
    Bind(String, std::io::Error),
    #[error("report folder {0}: {1}")]
    Report(String, std::io::Error),
    #[error("the server stopped: {0}")]
    Serve(std::io::Error),
}

impl ViewItem {
    /// Checks that the arrays agree (so the page never reads past an array).
    pub fn check(&self) -> Result<(), ViewError> {
        let per_frame = 3 * self.n_vertices;
        if self.n_frames == 0 {
            return Err(ViewError::Empty(self.name.clone()));
        }
        if let Some(o) = &self.overlay
            && let Some(&t) = o.transitions.iter().find(|&&t| t >= self.n_frames)
        {
            return Err(ViewError::Transition(self.name.clone(), t, self.n_frames - 1));
        }
        if let Some(p) = &self.played {
            return self.check_played(p);
        }
        self.check_textures()?;
        if let Some(f) = &self.field
            && (self.frame_vertices.is_some() || f.values.len() != self.n_vertices * self.n_frames)
        {
            return Err(ViewError::Field(self.name.clone(), f.values.len(), self.n_vertices * self.n_frames));
        }
        if let (Some(nv), Some(nt)) = (&self.frame_vertices, &self.frame_triangles) {
            return self.check_frames(nv, nt);
        }
        if self.frame_vertices.is_some() || self.frame_triangles.is_some() {
            return Err(ViewError::FrameCounts(self.name.clone(), 0, self.n_frames));
        }
        if per_frame == 0 || self.positions.len() != per_frame * self.n_frames {
            return Err(ViewError::Shape(self.name.clone(), self.positions.len(), self.n_vertices));
        }
        if self.synthetic.len() != self.n_frames {
            return Err(ViewError::Labels(self.name.clone(), self.synthetic.len(), self.n_frames));
        }
        if let Some(&f) = self.faces.iter().find(|&&f| f as usize >= self.n_vertices) {
            return Err(ViewError::Face(self.name.clone(), f, self.n_vertices));
        }
        if let Some(c) = &self.colours
            && (c.len() != per_frame || c.iter().any(|x| !x.is_finite()))
        {
            return Err(ViewError::Colours(self.name.clone(), c.len(), per_frame));
        }
        Ok(())
    }

    /// [`ViewItem::check`] for an item whose file the page plays: its counts and labels, and
    /// nothing the file does not carry.
    fn check_played(&self, p: &PlayedFile) -> Result<(), ViewError> {
        let bad = |why: &str| Err(ViewError::Played(self.name.clone(), why.to_string()));
        if self.n_vertices == 0 || p.bytes.is_empty() {
            return bad("expected vertices and the file's bytes");
        }
        if !self.positions.is_empty() || !self.faces.is_empty() {
            return bad("expected no positions or faces beside it");
        }
        if self.colours.is_some() || self.uvs.is_some() || self.field.is_some() || !self.textures.is_empty() {
            return bad("colours, texture coordinates, textures and colour maps are not played from it");
        }
        if self.frame_vertices.is_some() || self.frame_triangles.is_some() {
            return bad("a frame set is not played from it");
        }
        if self.synthetic.len() != self.n_frames {
            return Err(ViewError::Labels(self.name.clone(), self.synthetic.len(), self.n_frames));
        }
        Ok(())
    }

    /// [`ViewItem::check`] for the texture coordinates and textures: two finite numbers per
    /// vertex of the positions, one PNG index per frame, UVs wherever there are textures.
    fn check_textures(&self) -> Result<(), ViewError> {
        let bad = |why: String| Err(ViewError::Textures(self.name.clone(), why));
        if let Some(uv) = &self.uvs {
            // One topology: the vertices of a frame; a frame set: every frame's.
            let nv = if self.frame_vertices.is_some() { self.positions.len() / 3 } else { self.n_vertices };
            if uv.len() != 2 * nv || uv.iter().any(|x| !x.is_finite()) {
                return Err(ViewError::Uvs(self.name.clone(), uv.len(), nv));
            }
        }
        if let Some(k) = self.textures.iter().position(|t| t.len() < 8 || t[..8] != PNG_SIGNATURE) {
            return bad(format!("texture {k} is not a PNG file"));
        }
        match &self.frame_textures {
            None if !self.textures.is_empty() => bad("textures given without a texture per frame".into()),
            None => Ok(()),
            Some(_) if self.uvs.is_none() => bad("textures given without texture coordinates".into()),
            Some(t) if t.len() != self.n_frames => {
                bad(format!("{} texture indices for {} frames: expected one per frame", t.len(), self.n_frames))
            }
            Some(t) => match t.iter().enumerate().find(|&(_, &k)| k >= self.textures.len()) {
                Some((f, k)) => bad(format!("frame {f} shows texture {k}, expected below {}", self.textures.len())),
                None => Ok(()),
            },
        }
    }

    /// [`ViewItem::check`] for a frame set: counts per frame that add up, every frame's face
    /// indices inside its own vertices, `n_vertices` the largest frame's, one label per frame.
    fn check_frames(&self, nv: &[usize], nt: &[usize]) -> Result<(), ViewError> {
        let bad = || ViewError::FrameCounts(self.name.clone(), nv.len(), self.n_frames);
        if nv.len() != self.n_frames || nt.len() != self.n_frames || self.colours.is_some() {
            return Err(bad());
        }
        if nv.iter().sum::<usize>() * 3 != self.positions.len()
            || nt.iter().sum::<usize>() * 3 != self.faces.len()
            || nv.iter().max() != Some(&self.n_vertices)
            || self.n_vertices == 0
        {
            return Err(bad());
        }
        if self.synthetic.len() != self.n_frames {
            return Err(ViewError::Labels(self.name.clone(), self.synthetic.len(), self.n_frames));
        }
        let mut at = 0;
        for (&v, &t) in nv.iter().zip(nt) {
            if let Some(&f) = self.faces[at..at + 3 * t].iter().find(|&&f| f as usize >= v) {
                return Err(ViewError::Face(self.name.clone(), f, v));
            }
            at += 3 * t;
        }
        Ok(())
    }
}

#[cfg(test)]
mod message_tests {
    use super::{ViewError, ViewItem};

    /// A frame set's item: a triangle, then a quad of two triangles.
    fn frames() -> ViewItem {
        ViewItem {
            name: "set".into(),
            label: None,
            fps: 25.0,
            up: "+y".into(),
            units: "m".into(),
            metres_per_unit: Some(1.0),
            n_vertices: 4,
            n_frames: 2,
            frame_vertices: Some(vec![3, 4]),
            frame_triangles: Some(vec![1, 2]),
            synthetic: vec![false, false],
            faces: vec![0, 1, 2, 0, 1, 2, 0, 2, 3],
            positions: vec![0.0; 21],
            overlay: None,
            colours: None,
            colour_legend: Vec::new(),
            uvs: None,
            textures: Vec::new(),
            frame_textures: None,
            field: None,
            played: None,
        }
    }

    #[test]
    fn a_field_needs_one_value_per_vertex_and_frame_of_one_mesh() {
        let field = |n: usize| Some(super::VertexField::new("e".into(), "m".into(), String::new(), vec![0.5; n]));
        let mut one = frames();
        (one.frame_vertices, one.frame_triangles, one.n_vertices, one.positions) = (None, None, 3, vec![0.0; 18]);
        one.faces.truncate(3);
        one.field = field(6);
        one.check().unwrap();
        assert_eq!(one.field.as_ref().unwrap().range, [0.5, 0.5]);
        one.field = field(5);
        assert_eq!(
            one.check().unwrap_err().to_string(),
            "set: 5 colour-map values: expected one per vertex and frame (6), for one shared mesh"
        );
        let mut set = frames();
        set.field = field(8);
        assert!(matches!(set.check(), Err(ViewError::Field(..))));
        let f = super::VertexField::new("e".into(), "m".into(), String::new(), vec![2.0, f32::NAN, -1.0]);
        assert_eq!((f.range, f.max), ([-1.0, 2.0], 2.0));
        // One outlier in 1,000 leaves the bar's range at the 99th percentile.
        let mut v: Vec<f32> = (0..1000).map(|i| i as f32 / 1000.0).collect();
        v[500] = 50.0;
        let f = super::VertexField::new("e".into(), "m".into(), String::new(), v);
        assert_eq!((f.range[0], f.max), (0.0, 50.0));
        assert!((f.range[1] - 0.99).abs() < 0.002, "{:?}", f.range);
    }

    #[test]
    fn textures_are_checked_against_the_frames_and_uvs() {
        let png = |c: u8| [&super::PNG_SIGNATURE[..], &[c]].concat();
        let mut t = frames();
        t.uvs = Some(vec![0.5; 14]);
        t.textures = vec![png(0), png(1)];
        t.frame_textures = Some(vec![1, 0]);
        t.check().unwrap();
        let mut e = t.clone();
        e.frame_textures = Some(vec![0, 2]);
        assert_eq!(e.check().unwrap_err().to_string(), "set: frame 1 shows texture 2, expected below 2");
        let mut e = t.clone();
        e.uvs = None;
        assert_eq!(e.check().unwrap_err().to_string(), "set: textures given without texture coordinates");
        let mut e = t.clone();
        e.uvs = Some(vec![0.5; 12]);
        assert!(matches!(e.check(), Err(ViewError::Uvs(_, 12, 7))));
        let mut e = t.clone();
        e.textures[1] = b"GIF89a".to_vec();
        assert_eq!(e.check().unwrap_err().to_string(), "set: texture 1 is not a PNG file");
    }

    #[test]
    fn a_frame_set_item_is_checked_frame_by_frame() {
        frames().check().unwrap();
        // Index 3 is a vertex of frame 1 but not of frame 0.
        let mut bad = frames();
        bad.faces[2] = 3;
        assert_eq!(bad.check().unwrap_err().to_string(), "set: face index 3 is not a vertex (expected 0 to 2)");
        let mut short = frames();
        short.positions.pop();
        assert!(matches!(short.check(), Err(ViewError::FrameCounts(..))));
        let mut counts = frames();
        counts.frame_triangles = None;
        assert!(matches!(counts.check(), Err(ViewError::FrameCounts(..))));
    }

    #[test]
    fn a_played_item_carries_no_positions_of_its_own() {
        let mut it = frames();
        (it.frame_vertices, it.frame_triangles, it.positions, it.faces) = (None, None, Vec::new(), Vec::new());
        let file = super::PlayedFile {
            kind: super::PlayedKind::Stream,
            index: 0,
            bounds: Some([[0.0; 3], [1.0; 3]]),
            bytes: std::sync::Arc::new(b"SCSTRM".to_vec()),
        };
        it.played = Some(file.clone());
        it.check().unwrap();
        assert_eq!(serde_json::to_value(&file).unwrap()["kind"], "stream");
        let mut both = it.clone();
        both.positions = vec![0.0; 24];
        assert_eq!(
            both.check().unwrap_err().to_string(),
            "set: a file the page plays itself (a stream or a rig) carries its own positions and faces; expected no positions or faces beside it"
        );
        let mut labels = it.clone();
        labels.synthetic.pop();
        assert!(matches!(labels.check(), Err(ViewError::Labels(..))));
        let mut empty = it;
        empty.played = Some(super::PlayedFile { bytes: std::sync::Arc::new(Vec::new()), ..file });
        assert!(matches!(empty.check(), Err(ViewError::Played(..))));
    }

    #[test]
    fn a_bad_face_index_names_the_last_valid_vertex() {
        let e = ViewError::Face("crane".into(), 494, 494);
        assert_eq!(e.to_string(), "crane: face index 494 is not a vertex (expected 0 to 493)");
    }
}

//! Directing from the page: what the page may ask the server to synthesise (a [`Direction`]),
//! the subject's motion graph as a timeline the page draws ([`GraphTimeline`]), and the
//! [`Director`] a front end implements to answer them. This crate knows nothing of surfcap's
//! synthesis: the command line implements the trait on a subject prepared once (its graph and
//! walk model kept in memory), so each request costs only its search and playback.
//!
//! The server answers directions on `POST /api/direct` (JSON), returns the graph on
//! `GET /api/direct/graph` and the last result as a file on `GET /api/direct/export/{format}`
//! (see [`crate::server`]); the result replaces the items the page plays, and
//! `POST /api/direct/reset` brings the subject's own sequences back.

use serde::{Deserialize, Serialize};

use crate::ViewItem;

/// What the page asks for (the JSON body of `POST /api/direct`, tagged by `kind`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Direction {
    /// Follow a path drawn on the ground: points in the subject's own axes and units (x, y, z),
    /// followed on the ground plane (their height is ignored).
    Path { points: Vec<[f64; 3]> },
    /// Key poses moved to new times: each a frame (`sequence:frame`) and the output frame at
    /// which it should be shown (thesis 3.5.2).
    Keyposes { keys: Vec<KeyAsk> },
    /// From one frame to another covering a ground distance (subject units) in a time
    /// (seconds).
    Reach { from: String, to: String, distance: f64, seconds: f64 },
    /// One transition of the graph played: the blended transition from `from` to `to`
    /// (`sequence:frame`), as `surfcap transition` makes it.
    Transition { from: String, to: String },
}

/// One key pose of [`Direction::Keyposes`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyAsk {
    /// The frame as users write it, `sequence:frame`.
    pub frame: String,
    /// The output frame it is asked at.
    pub time: i64,
}

/// The subject's motion graph as the page draws it: one row per sequence (its frames, in
/// order), and an arc per transition edge between two frames.
#[derive(Debug, Clone, Serialize)]
pub struct GraphTimeline {
    pub subject: String,
    pub fps: f64,
    /// Length unit symbol (`m`, `cm`, ... or `units`).
    pub units: String,
    /// Which graph, in words (`essential graph, alpha 0.05: 912 edges, 40 transitions`).
    pub graph: String,
    pub sequences: Vec<TimelineSequence>,
    pub transitions: Vec<TimelineArc>,
}

/// A row of the timeline: a sequence and where its frames start among the subject's.
#[derive(Debug, Clone, Serialize)]
pub struct TimelineSequence {
    pub name: String,
    /// Global number of its first frame.
    pub first: usize,
    pub frames: usize,
    /// Whether the clip loops (its last frame plays into its start).
    pub looping: bool,
}

/// A transition edge of the graph: from a frame to another, with its weight.
#[derive(Debug, Clone, Serialize)]
pub struct TimelineArc {
    /// Global frame numbers.
    pub from: usize,
    pub to: usize,
    /// The same frames as users write them, `sequence:frame`.
    pub from_frame: String,
    pub to_frame: String,
    /// The edge's weight in the graph (the transition's cost plus alpha times its duration).
    pub weight: f64,
}

/// A direction's result: the animation the page plays next, with what to say about it.
#[derive(Debug, Clone)]
pub struct Directed {
    pub item: ViewItem,
    /// Lines for the panel (what was asked and achieved, in the user's units and frames).
    pub summary: Vec<String>,
    /// Time the synthesis took (search, playback, measures), seconds.
    pub seconds: f64,
}

/// A file of the last result, as the page downloads it.
#[derive(Debug, Clone)]
pub struct Exported {
    /// File name offered to the browser (`path.glb`).
    pub name: String,
    pub content_type: &'static str,
    pub bytes: Vec<u8>,
}

/// What answers the page's directions: implemented by a front end on a prepared subject.
/// Calls come from the server's worker threads one at a time per request; an implementation
/// keeps its last result for [`Director::export`].
pub trait Director: Send + Sync {
    /// The graph the directions are searched in, as a timeline.
    fn timeline(&self) -> &GraphTimeline;
    /// Synthesises what `direction` asks; an error is a message for the user (what was asked
    /// and why it cannot be made).
    fn direct(&self, direction: &Direction) -> Result<Directed, String>;
    /// The last result written as `format` (`glb`, `abc` or `usda`); an error when there is no
    /// result yet or the format is not one of them.
    fn export(&self, format: &str) -> Result<Exported, String>;
}

pub use crate::local_guard::{is_json, is_same_origin};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_this_servers_origin_may_direct() {
        for ok in ["http://127.0.0.1:8080", "http://localhost:8080", "http://[::1]:8080"] {
            assert!(is_same_origin(ok, 8080), "{ok}");
        }
        for bad in [
            "null",
            "",
            "https://127.0.0.1:8080",
            "http://127.0.0.1:8081",
            "http://127.0.0.1",
            "http://evil.example:8080",
            "http://127.0.0.1:8080/x",
            "http://localhost.evil.example:8080",
        ] {
            assert!(!is_same_origin(bad, 8080), "{bad}");
        }
    }

    #[test]
    fn only_json_bodies_are_accepted() {
        assert!(is_json("application/json"));
        assert!(is_json("application/json; charset=utf-8"));
        for bad in ["text/plain", "application/x-www-form-urlencoded", "multipart/form-data", ""] {
            assert!(!is_json(bad), "{bad}");
        }
    }

    #[test]
    fn directions_parse_from_the_pages_json() {
        let d: Direction = serde_json::from_str(r#"{"kind":"path","points":[[0,0,0],[1,0,2]]}"#).unwrap();
        assert_eq!(d, Direction::Path { points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 2.0]] });
        let d: Direction =
            serde_json::from_str(r#"{"kind":"reach","from":"a:0","to":"b:3","distance":2.5,"seconds":3}"#).unwrap();
        assert_eq!(d, Direction::Reach { from: "a:0".into(), to: "b:3".into(), distance: 2.5, seconds: 3.0 });
        let d: Direction =
            serde_json::from_str(r#"{"kind":"keyposes","keys":[{"frame":"a:0","time":0},{"frame":"a:9","time":40}]}"#)
                .unwrap();
        assert!(matches!(d, Direction::Keyposes { keys } if keys[1].time == 40));
        for bad in [r#"{"kind":"delete"}"#, r#"{"kind":"path"}"#, r#"{"kind":"path","points":[],"x":1}"#] {
            assert!(serde_json::from_str::<Direction>(bad).is_err(), "{bad}");
        }
    }
}

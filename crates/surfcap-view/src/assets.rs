//! The page's files, embedded at build time: our page and script, and three.js (with its
//! orbit controls) from the npm package `build.rs` installs.

/// (route under `/assets/`, content type, bytes).
pub const ASSETS: &[(&str, &str, &str)] = &[
    ("viewer.js", JS, include_str!("../web/viewer.js")),
    // ---- director ----
    ("director.js", JS, include_str!("../web/director.js")),
    ("graph_timeline.js", JS, include_str!("../web/graph_timeline.js")),
    // ---- end director ----
    ("three.module.js", JS, include_str!("../web/node_modules/three/build/three.module.js")),
    ("three.core.js", JS, include_str!("../web/node_modules/three/build/three.core.js")),
    (
        "addons/controls/OrbitControls.js",
        JS,
        include_str!("../web/node_modules/three/examples/jsm/controls/OrbitControls.js"),
    ),
    // ---- stream: the compact stream's decoder ----
    ("stream_decode.js", JS, include_str!("../web/stream_decode.js")),
    // ---- played files: streams and skinned rigs decoded by the page ----
    ("formats_player.js", JS, include_str!("../web/formats_player.js")),
    ("addons/loaders/GLTFLoader.js", JS, include_str!("../web/node_modules/three/examples/jsm/loaders/GLTFLoader.js")),
    (
        "addons/utils/BufferGeometryUtils.js",
        JS,
        include_str!("../web/node_modules/three/examples/jsm/utils/BufferGeometryUtils.js"),
    ),
    (
        "addons/utils/SkeletonUtils.js",
        JS,
        include_str!("../web/node_modules/three/examples/jsm/utils/SkeletonUtils.js"),
    ),
    // ---- play: the live play page's script ----
    ("play.js", JS, include_str!("../web/play.js")),
];

const JS: &str = "text/javascript; charset=utf-8";

pub const INDEX_HTML: &str = include_str!("../web/index.html");

/// The asset at `route`, if there is one.
pub fn asset(route: &str) -> Option<(&'static str, &'static str)> {
    ASSETS.iter().find(|(r, _, _)| *r == route).map(|(_, t, b)| (*t, *b))
}

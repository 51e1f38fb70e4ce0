//! Live play: the page `web/play.html` steers a captured character from the keyboard or a
//! gamepad, and the server answers with the frames to show. This crate knows nothing of
//! surfcap's synthesis: a front end implements [`Player`] on a prepared subject (the command
//! line does, with the interactive controller), and [`serve_play`] serves the page and its
//! routes.
//!
//! Where the work is done, and why: every decision and every blend runs in the server
//! (Rust). The controller's precomputation (the future trajectory of every move, hundreds of
//! thousands on a dense graph) and Blend's factorisation of each transition are Rust code over
//! the subject's whole distance matrix; a WebAssembly build would have to ship the matrix, the
//! graph and those solvers to the browser (tens of MB more before the first frame) for no gain on
//! a local machine, where a request's round trip is about a millisecond.
//!
//! Transport: small JSON POSTs over HTTP/1.1 keep-alive (`POST /api/play/step`, one per
//! animation frame of the page, one in flight at a time), not a WebSocket: the page's clock
//! drives the controller, so the server never pushes; the page measures every round trip and
//! shows it.
//!
//! Meshes, quantised and delta-coded by the compact stream (`.scstream`, decoded by
//! `web/stream_decode.js`):
//! - `GET /api/play/stream`: every captured frame, coded once at start-up; the page reads it
//!   progressively and decodes it key-frame block by key-frame block (a block starts with a key
//!   frame, so it decodes on its own), the block of the start frame first, so it plays as soon
//!   as that block is in;
//! - `GET /api/play/blend/{id}`: the frames of one transition, blended by the server on a worker
//!   thread as soon as the controller chooses it (the newest chosen first: an older one's frames
//!   may be past), frame by frame in playing order, coded as a stream of their own in the
//!   coordinates where the transition's source frame is unmoved; the page places them as the
//!   step says. `GET /api/play/blend/{id}/from/{k}` gives the frames from k on made so far, so
//!   the page gets the first frames while the later ones are being solved.
//! - A transition's first frame is due about 0.1-0.2 s after it is chosen (its lead-in frames
//!   and the page's display delay), less than Blend's solves take on a large mesh. So each
//!   blended frame in a step also carries its stand-in (`surfcap_synthesis`'s display blend: the
//!   two captured frames Blend mixes, placed, and the weight), which the page draws at once from
//!   the captured frames it holds, by linear interpolation (eq. 2.23); the exact frame is drawn
//!   instead whenever it has arrived. The page counts the blended frames shown exact, as
//!   stand-ins, and late (neither: the last mesh moved along the centre track).
//!
//! Routes: `GET /` the page, `/assets/...`, `GET /api/play/info`, the two above,
//! `POST /api/play/step` (JSON [`StepAsk`]) and `POST /api/play/restart`. POSTs are taken only
//! from the page's own origin with `Content-Type: application/json`, and every request must name
//! this server in its `Host` header, as in [`crate::server`].

use std::net::SocketAddr;
use std::sync::Arc;

use axum::Router;
use axum::body::Body;
use axum::extract::{Path as UrlPath, State};
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde::Deserialize;

use crate::ViewError;
use crate::assets::asset;
use crate::local_guard::{json_answer, refuse_foreign, respond, serve_local};

/// The page.
pub const PLAY_HTML: &str = include_str!("../web/play.html");

/// One step of the page's clock: what the player asks for now and the seconds since the last
/// step (the body of `POST /api/play/step`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepAsk {
    /// The ground direction asked, in the subject's two ground axes (the first ground axis,
    /// then the second), of length 0 (stop) to 1 (full speed of the gait).
    pub direction: [f64; 2],
    /// Run (shift held, or a gamepad button) rather than walk.
    #[serde(default)]
    pub run: bool,
    /// Seconds since the page's previous step (the page clamps long pauses).
    pub dt: f64,
}

/// What answers the page: implemented by a front end on a prepared subject. Calls come from
/// the server's worker threads.
pub trait Player: Send + Sync {
    /// The subject and the session, as JSON for the page (name, fps, unit, up axis, ground
    /// axes, the start frame, the frame labels...).
    fn info(&self) -> serde_json::Value;
    /// Every captured frame as a compact stream.
    fn captured_stream(&self) -> Arc<Vec<u8>>;
    /// Advances the controller by `ask.dt` under the asked input; the JSON the page reads (the
    /// frames that fell due with their placement, the decisions, the blends started, what cannot
    /// be followed); an error is a message for the user.
    fn step(&self, ask: &StepAsk) -> Result<serde_json::Value, String>;
    /// Blend `id`'s frames as a compact stream, waiting for its worker (`None`: no such blend,
    /// or it failed: the message says why).
    fn blend(&self, id: u64) -> Result<Arc<Vec<u8>>, String>;
    /// Blend `id`'s frames from frame `from` on that are made so far (at least one: waits for
    /// it), as a compact stream, and the transition's number of frames.
    fn blend_from(&self, id: u64, from: usize) -> Result<(Vec<u8>, usize), String>;
    /// Starts the controller again from its start frame.
    fn restart(&self) -> Result<(), String>;
}

struct App {
    player: Arc<dyn Player>,
    port: u16,
}

/// Serves the play page for `player` on 127.0.0.1:`port` (0: any free port) until the process
/// ends; `ready(address)` is called once it listens.
pub fn serve_play(player: Arc<dyn Player>, port: u16, ready: impl FnOnce(SocketAddr)) -> Result<(), ViewError> {
    serve_local(port, ready, move |port| router(Arc::new(App { player, port })))
}

fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/assets/{*path}", get(assets))
        .route("/api/play/info", get(info))
        .route("/api/play/stream", get(stream))
        .route("/api/play/blend/{id}", get(blend))
        .route("/api/play/blend/{id}/from/{from}", get(blend_from))
        .route("/api/play/step", post(step))
        .route("/api/play/restart", post(restart))
        .fallback(not_found)
        .with_state(app)
}

fn error(status: StatusCode, msg: String) -> Response {
    json_answer(status, &serde_json::json!({ "error": msg }))
}

async fn not_found() -> Response {
    (StatusCode::NOT_FOUND, "not found: this server answers /, /assets/... and /api/play/...\n").into_response()
}

async fn page() -> Response {
    respond("text/html; charset=utf-8", PLAY_HTML)
}

async fn assets(UrlPath(path): UrlPath<String>) -> Response {
    match asset(&path) {
        Some((t, body)) => respond(t, body),
        None => not_found().await,
    }
}

async fn info(State(app): State<Arc<App>>) -> Response {
    json_answer(StatusCode::OK, &app.player.info())
}

async fn stream(State(app): State<Arc<App>>) -> Response {
    let bytes = app.player.captured_stream();
    respond("application/octet-stream", Body::from(bytes.as_ref().clone()))
}

async fn blend(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Ok(id) = id.parse::<u64>() else { return not_found().await };
    let player = app.player.clone();
    match tokio::task::spawn_blocking(move || player.blend(id)).await {
        Ok(Ok(bytes)) => respond("application/octet-stream", Body::from(bytes.as_ref().clone())),
        Ok(Err(msg)) => error(StatusCode::NOT_FOUND, msg),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, format!("the blend stopped: {e}")),
    }
}

/// The frames of a blend made so far from frame `from` on; the header `X-Blend-Frames` says how
/// many frames the transition has, so the page asks again from where this piece ends until it
/// has them all.
async fn blend_from(State(app): State<Arc<App>>, UrlPath((id, from)): UrlPath<(String, String)>) -> Response {
    let (Ok(id), Ok(from)) = (id.parse::<u64>(), from.parse::<usize>()) else { return not_found().await };
    let player = app.player.clone();
    match tokio::task::spawn_blocking(move || player.blend_from(id, from)).await {
        Ok(Ok((bytes, total))) => {
            let mut r = respond("application/octet-stream", Body::from(bytes));
            r.headers_mut().insert("x-blend-frames", total.into());
            r
        }
        Ok(Err(msg)) => error(StatusCode::NOT_FOUND, msg),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, format!("the blend stopped: {e}")),
    }
}

/// Checks a step's numbers: a finite direction of length at most 1 (a little over is
/// rounding), a non-negative finite time step of at most a second.
pub fn check_step(ask: &StepAsk) -> Result<(), String> {
    let [x, y] = ask.direction;
    if !(x.is_finite() && y.is_finite()) || x.hypot(y) > 1.0 + 1e-6 {
        return Err(format!("direction [{x}, {y}]: expected two finite numbers of length 0 to 1"));
    }
    if !(ask.dt.is_finite() && (0.0..=1.0).contains(&ask.dt)) {
        return Err(format!("dt {}: expected 0 to 1 second since the previous step", ask.dt));
    }
    Ok(())
}

async fn step(State(app): State<Arc<App>>, headers: HeaderMap, body: axum::body::Bytes) -> Response {
    if let Some(refused) = refuse_foreign(app.port, &headers, ("steps", "step")) {
        return refused;
    }
    let ask: StepAsk = match serde_json::from_slice(&body) {
        Ok(a) => a,
        Err(e) => {
            let msg = format!("a step is {{\"direction\": [x, y], \"run\": false, \"dt\": seconds}}: {e}");
            return error(StatusCode::BAD_REQUEST, msg);
        }
    };
    if let Err(msg) = check_step(&ask) {
        return error(StatusCode::BAD_REQUEST, msg);
    }
    let player = app.player.clone();
    match tokio::task::spawn_blocking(move || player.step(&ask)).await {
        Ok(Ok(v)) => json_answer(StatusCode::OK, &v),
        Ok(Err(msg)) => error(StatusCode::UNPROCESSABLE_ENTITY, msg),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, format!("the step stopped: {e}")),
    }
}

async fn restart(State(app): State<Arc<App>>, headers: HeaderMap) -> Response {
    if let Some(refused) = refuse_foreign(app.port, &headers, ("steps", "step")) {
        return refused;
    }
    let player = app.player.clone();
    match tokio::task::spawn_blocking(move || player.restart()).await {
        Ok(Ok(())) => json_answer(StatusCode::OK, &serde_json::json!({ "restarted": true })),
        Ok(Err(msg)) => error(StatusCode::UNPROCESSABLE_ENTITY, msg),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, format!("the restart stopped: {e}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_parse_and_bad_numbers_are_refused() {
        let a: StepAsk = serde_json::from_str(r#"{"direction":[0.6,0.8],"run":true,"dt":0.016}"#).unwrap();
        assert_eq!(a, StepAsk { direction: [0.6, 0.8], run: true, dt: 0.016 });
        check_step(&a).unwrap();
        let b: StepAsk = serde_json::from_str(r#"{"direction":[0,0],"dt":0}"#).unwrap();
        assert!(!b.run);
        check_step(&b).unwrap();
        assert!(serde_json::from_str::<StepAsk>(r#"{"direction":[0,0],"dt":0,"x":1}"#).is_err());
        for (d, dt, why) in [
            ([2.0, 0.0], 0.01, "length 0 to 1"),
            ([f64::NAN, 0.0], 0.01, "finite"),
            ([0.0, 0.0], -0.1, "0 to 1 second"),
            ([0.0, 0.0], 5.0, "0 to 1 second"),
        ] {
            let e = check_step(&StepAsk { direction: d, run: false, dt }).unwrap_err();
            assert!(e.contains(why), "{e}");
        }
    }
}

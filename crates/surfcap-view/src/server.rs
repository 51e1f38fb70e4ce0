//! The HTTP server: GET routes for the page, its assets, the items and one report folder; with a
//! [`Director`], the direction routes (`/api/direct...`, see [`crate::direct`]).

use std::net::SocketAddr;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, RwLock};

use axum::Router;
use axum::extract::{Path as UrlPath, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};

use crate::assets::{INDEX_HTML, asset};
use crate::direct::{Direction, Director};
pub use crate::local_guard::is_local_host;
use crate::local_guard::{json_answer, refuse_foreign, respond, serve_local};
use crate::{ViewError, ViewItem};

struct App {
    /// What the page plays: the items given, or a direction's result in their place.
    items: RwLock<Vec<Arc<ViewItem>>>,
    /// The items given, which `POST /api/direct/reset` brings back.
    given: Vec<Arc<ViewItem>>,
    director: Option<Arc<dyn Director>>,
    report: Option<PathBuf>,
    /// The port the server listens on: requests must name it in their `Host` header.
    port: u16,
}

/// What the page is served with.
pub struct ServeOptions {
    /// Port on 127.0.0.1 (0: any free one).
    pub port: u16,
    /// A report folder whose files are served under `/report/` (its `index.html` is linked).
    pub report: Option<PathBuf>,
}

/// Serves `items` until the process ends; `ready(address)` is called once it listens.
pub fn serve(items: Vec<ViewItem>, opts: ServeOptions, ready: impl FnOnce(SocketAddr)) -> Result<(), ViewError> {
    serve_directed(items, opts, None, ready)
}

/// [`serve`], with a [`Director`] answering the page's directions when one is given.
pub fn serve_directed(
    items: Vec<ViewItem>,
    opts: ServeOptions,
    director: Option<Arc<dyn Director>>,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ViewError> {
    if items.is_empty() {
        return Err(ViewError::NoItems);
    }
    for it in &items {
        it.check()?;
    }
    let report = match opts.report {
        Some(r) => Some(r.canonicalize().map_err(|e| ViewError::Report(r.display().to_string(), e))?),
        None => None,
    };
    let given: Vec<Arc<ViewItem>> = items.into_iter().map(Arc::new).collect();
    serve_local(opts.port, ready, move |port| {
        router(Arc::new(App { items: RwLock::new(given.clone()), given, director, report, port }))
    })
}

fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/assets/{*path}", get(assets))
        .route("/api/items", get(items))
        .route("/api/items/{id}/positions", get(positions))
        .route("/api/items/{id}/faces", get(faces))
        .route("/api/items/{id}/colours", get(colours))
        .route("/api/items/{id}/uvs", get(uvs))
        .route("/api/items/{id}/file", get(played_file))
        .route("/api/items/{id}/field", get(field))
        .route("/api/items/{id}/textures/{k}", get(texture))
        .route("/report/{*path}", get(report))
        // ---- direction routes ----
        .route("/api/direct", post(direct))
        .route("/api/direct/reset", post(direct_reset))
        .route("/api/direct/graph", get(direct_graph))
        .route("/api/direct/export/{format}", get(direct_export))
        // ---- end of direction routes ----
        .fallback(not_found)
        .with_state(app)
}

async fn not_found() -> Response {
    (StatusCode::NOT_FOUND, "not found: this server answers /, /assets/..., /api/items... and /report/...\n")
        .into_response()
}

async fn index() -> Response {
    respond("text/html; charset=utf-8", INDEX_HTML)
}

async fn assets(UrlPath(path): UrlPath<String>) -> Response {
    match asset(&path) {
        Some((t, body)) => respond(t, body),
        None => not_found().await,
    }
}

async fn items(State(app): State<Arc<App>>) -> Response {
    let all = app.items();
    let items: Vec<serde_json::Value> = all
        .iter()
        .map(|it| {
            let mut v = serde_json::to_value(&**it).expect("items serialise");
            v["has_colours"] = it.has_colours().into();
            v["has_uvs"] = it.has_uvs().into();
            v["has_field"] = it.has_field().into();
            v["n_textures"] = it.textures.len().into();
            v["played"] = played_json(&all, it);
            v
        })
        .collect();
    // `direct`: whether the direction routes answer (the page asks for the graph only then, so a
    // viewer that only plays makes no request that fails).
    let v = serde_json::json!({
        "items": items,
        "report": app.report.as_ref().map(|_| "/report/index.html"),
        "direct": app.director.is_some(),
    });
    respond("application/json", serde_json::to_vec(&v).expect("JSON values serialise"))
}

impl App {
    /// The items played now.
    fn items(&self) -> Vec<Arc<ViewItem>> {
        self.items.read().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Item `id` of those played now.
fn item(app: &App, id: &str) -> Option<Arc<ViewItem>> {
    let k = id.parse::<usize>().ok()?;
    app.items().get(k).cloned()
}

// ---- played files: streams and rigs the page decodes itself (see crate::PlayedFile) ----

/// An item's played file as the page reads it: kind, index in the file, a stream's box, and
/// the address of its bytes (the first item's of the same file, so the page fetches it once).
fn played_json(all: &[Arc<ViewItem>], it: &ViewItem) -> serde_json::Value {
    let Some(p) = &it.played else { return serde_json::Value::Null };
    let first = all
        .iter()
        .position(|o| o.played.as_ref().is_some_and(|q| Arc::ptr_eq(&q.bytes, &p.bytes)))
        .expect("the item is one of them");
    let mut v = serde_json::to_value(p).expect("a played file serialises");
    v["url"] = format!("/api/items/{first}/file").into();
    v
}

/// The bytes of the file the item's page decodes (a stream or a rig), else 404.
async fn played_file(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let Some(p) = &it.played else { return not_found().await };
    let kind = match p.kind {
        crate::PlayedKind::Stream => "application/octet-stream",
        crate::PlayedKind::Rig => "model/gltf-binary",
    };
    respond(kind, p.bytes.as_ref().clone())
}

// ---- end played files ----

async fn positions(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let bytes: Vec<u8> = it.positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    respond("application/octet-stream", bytes)
}

async fn faces(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let bytes: Vec<u8> = it.faces.iter().flat_map(|x| x.to_le_bytes()).collect();
    respond("application/octet-stream", bytes)
}

/// The item's per-vertex colours, when it has some (else 404).
async fn colours(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let Some(c) = &it.colours else { return not_found().await };
    let bytes: Vec<u8> = c.iter().flat_map(|x| x.to_le_bytes()).collect();
    respond("application/octet-stream", bytes)
}

/// The item's texture coordinates, when it has some (else 404).
async fn uvs(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let Some(uv) = &it.uvs else { return not_found().await };
    let bytes: Vec<u8> = uv.iter().flat_map(|x| x.to_le_bytes()).collect();
    respond("application/octet-stream", bytes)
}

/// The item's per-vertex scalar field (`[frames][vertices]` f32), when it has one (else 404).
async fn field(State(app): State<Arc<App>>, UrlPath(id): UrlPath<String>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let Some(f) = &it.field else { return not_found().await };
    let bytes: Vec<u8> = f.values.iter().flat_map(|x| x.to_le_bytes()).collect();
    respond("application/octet-stream", bytes)
}

/// Texture `t` of the item (a PNG file held in memory, never a path), else 404.
async fn texture(State(app): State<Arc<App>>, UrlPath((id, t)): UrlPath<(String, String)>) -> Response {
    let Some(it) = item(&app, &id) else { return not_found().await };
    let Some(png) = t.parse::<usize>().ok().and_then(|t| it.textures.get(t)) else {
        return not_found().await;
    };
    respond("image/png", png.clone())
}

/// The report file at `rel`, when `rel` is a plain relative path (no `..`, no root) naming a
/// file inside the report folder (also after resolving links).
pub fn report_file(root: &Path, rel: &str) -> Option<PathBuf> {
    let rel = Path::new(rel);
    if rel.components().any(|c| !matches!(c, Component::Normal(_))) {
        return None;
    }
    let p = root.join(rel).canonicalize().ok()?;
    (p.starts_with(root) && p.is_file()).then_some(p)
}

fn content_type(p: &Path) -> &'static str {
    match p.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "json" => "application/json",
        "csv" | "txt" => "text/plain; charset=utf-8",
        "css" => "text/css",
        "glb" => "model/gltf-binary",
        _ => "application/octet-stream",
    }
}

async fn report(State(app): State<Arc<App>>, UrlPath(path): UrlPath<String>) -> Response {
    let Some(root) = &app.report else { return not_found().await };
    let Some(file) = report_file(root, &path) else { return not_found().await };
    match std::fs::read(&file) {
        Ok(bytes) => respond(content_type(&file), bytes),
        Err(_) => not_found().await,
    }
}

// ---- direction handlers (see crate::direct) ----

fn no_director() -> Response {
    let msg = "this viewer plays only: start it with `surfcap view SUBJECT --direct` to direct a subject";
    json_answer(StatusCode::NOT_FOUND, &serde_json::json!({ "error": msg }))
}

/// `POST /api/direct`: synthesises what the page asks (on a worker thread, so the page's other
/// requests are answered meanwhile) and plays the result in place of the items.
async fn direct(State(app): State<Arc<App>>, headers: axum::http::HeaderMap, body: axum::body::Bytes) -> Response {
    if let Some(refused) = refuse_foreign(app.port, &headers, ("directions", "direction")) {
        return refused;
    }
    let Some(director) = app.director.clone() else { return no_director() };
    let direction: Direction = match serde_json::from_slice(&body) {
        Ok(d) => d,
        Err(e) => {
            let msg = format!("the direction is not one this server takes (path, keyposes, reach or transition): {e}");
            return json_answer(StatusCode::BAD_REQUEST, &serde_json::json!({ "error": msg }));
        }
    };
    let done = tokio::task::spawn_blocking(move || director.direct(&direction)).await;
    match done {
        Ok(Ok(d)) => {
            if let Err(e) = d.item.check() {
                let msg = format!("the result cannot be shown: {e}");
                return json_answer(StatusCode::INTERNAL_SERVER_ERROR, &serde_json::json!({ "error": msg }));
            }
            let answer = serde_json::json!({
                "name": d.item.name,
                "frames": d.item.n_frames,
                "summary": d.summary,
                "seconds": d.seconds,
            });
            *app.items.write().unwrap_or_else(|e| e.into_inner()) = vec![Arc::new(d.item)];
            json_answer(StatusCode::OK, &answer)
        }
        Ok(Err(msg)) => json_answer(StatusCode::UNPROCESSABLE_ENTITY, &serde_json::json!({ "error": msg })),
        Err(e) => {
            let msg = format!("the synthesis stopped: {e}");
            json_answer(StatusCode::INTERNAL_SERVER_ERROR, &serde_json::json!({ "error": msg }))
        }
    }
}

/// `POST /api/direct/reset`: the items given play again.
async fn direct_reset(State(app): State<Arc<App>>, headers: axum::http::HeaderMap) -> Response {
    if let Some(refused) = refuse_foreign(app.port, &headers, ("directions", "direction")) {
        return refused;
    }
    if app.director.is_none() {
        return no_director();
    }
    *app.items.write().unwrap_or_else(|e| e.into_inner()) = app.given.clone();
    json_answer(StatusCode::OK, &serde_json::json!({ "items": app.given.len() }))
}

/// `GET /api/direct/graph`: the motion graph as a timeline (404 without a director).
async fn direct_graph(State(app): State<Arc<App>>) -> Response {
    match &app.director {
        Some(d) => respond("application/json", serde_json::to_vec(d.timeline()).expect("the timeline serialises")),
        None => no_director(),
    }
}

/// `GET /api/direct/export/{format}`: the last result as a file to download.
async fn direct_export(State(app): State<Arc<App>>, UrlPath(format): UrlPath<String>) -> Response {
    let Some(director) = app.director.clone() else { return no_director() };
    match tokio::task::spawn_blocking(move || director.export(&format)).await {
        Ok(Ok(file)) => {
            let name: String =
                file.name.chars().filter(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_')).collect();
            let disposition = format!("attachment; filename=\"{name}\"");
            (
                [
                    (header::CONTENT_TYPE, file.content_type.to_string()),
                    (header::CACHE_CONTROL, "no-store".into()),
                    (header::CONTENT_DISPOSITION, disposition),
                ],
                file.bytes,
            )
                .into_response()
        }
        Ok(Err(msg)) => json_answer(StatusCode::NOT_FOUND, &serde_json::json!({ "error": msg })),
        Err(e) => json_answer(StatusCode::INTERNAL_SERVER_ERROR, &serde_json::json!({ "error": e.to_string() })),
    }
}

// ---- end of direction handlers ----

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_local_host_headers_are_answered() {
        for ok in ["127.0.0.1:8080", "localhost:8080", "LocalHost:8080", "[::1]:8080"] {
            assert!(is_local_host(ok, 8080), "{ok}");
        }
        for bad in [
            "",
            "127.0.0.1",
            "127.0.0.1:8081",
            "evil.example:8080",
            "localhost.evil.example:8080",
            "127.0.0.1.nip.io:8080",
            "[::1]",
            "::1:8080",
            "localhost:8080:8080",
            "localhost:",
        ] {
            assert!(!is_local_host(bad, 8080), "{bad}");
        }
        assert!(is_local_host("localhost", 80));
    }

    #[test]
    fn report_paths_stay_inside_the_folder() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path().join("r");
        std::fs::create_dir_all(root.join("plots")).unwrap();
        std::fs::write(root.join("index.html"), "x").unwrap();
        std::fs::write(root.join("plots/a.svg"), "x").unwrap();
        std::fs::write(d.path().join("secret.txt"), "x").unwrap();
        let root = root.canonicalize().unwrap();
        assert!(report_file(&root, "index.html").is_some());
        assert!(report_file(&root, "plots/a.svg").is_some());
        for bad in ["../secret.txt", "plots/../../secret.txt", "/etc/passwd", "plots", "missing.html", ""] {
            assert!(report_file(&root, bad).is_none(), "{bad}");
        }
    }
}

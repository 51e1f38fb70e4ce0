//! What keeps surfcap's local servers local, shared by the viewer ([`crate::server`]) and the
//! play page ([`crate::play`]): they listen on 127.0.0.1 only, answer only requests whose `Host`
//! names them (against DNS rebinding), and take POSTs only from their own page with a JSON
//! body (a page of another site cannot send one without a preflight these servers never grant).
//! Also the two small response helpers both use.

use std::net::SocketAddr;

use axum::Router;
use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};

use crate::ViewError;

/// Whether a `Host` header names this server: `127.0.0.1`, `localhost` or `[::1]` with the
/// port it listens on (a missing port means 80). Anything else is refused, so a page on another
/// site that re-binds its DNS name to 127.0.0.1 cannot read the items (DNS rebinding).
pub fn is_local_host(host: &str, port: u16) -> bool {
    let (name, given) = match host.rsplit_once(':') {
        Some((n, p)) if !n.is_empty() && (n.ends_with(']') || !n.contains(':')) => (n, p.parse::<u16>().ok()),
        _ => (host, Some(80)),
    };
    let name_ok = ["127.0.0.1", "localhost", "[::1]"].iter().any(|h| name.eq_ignore_ascii_case(h));
    name_ok && given == Some(port)
}

/// Whether an `Origin` header names this very server (`http://127.0.0.1:PORT`,
/// `http://localhost:PORT` or `http://[::1]:PORT`): a page of another site (or a sandboxed
/// `null` origin) may not drive work on the user's machine.
pub fn is_same_origin(origin: &str, port: u16) -> bool {
    origin.strip_prefix("http://").is_some_and(|host| !host.contains('/') && is_local_host(host, port))
}

/// Whether a `Content-Type` header says JSON (`application/json`, parameters allowed). Browsers
/// send a cross-site JSON POST only after a preflight these servers never grant.
pub fn is_json(content_type: &str) -> bool {
    content_type.split(';').next().is_some_and(|t| t.trim().eq_ignore_ascii_case("application/json"))
}

/// Binds 127.0.0.1:`port` (0: any free port), builds the routes for the port it got, calls
/// `ready(address)` and serves until the process ends. Every request whose `Host` does not name
/// this server is refused (403).
pub(crate) fn serve_local(
    port: u16,
    ready: impl FnOnce(SocketAddr),
    routes: impl FnOnce(u16) -> Router,
) -> Result<(), ViewError> {
    let rt = tokio::runtime::Builder::new_current_thread().enable_io().build().map_err(ViewError::Serve)?;
    rt.block_on(async move {
        let addr = SocketAddr::from(([127, 0, 0, 1], port));
        let listener = tokio::net::TcpListener::bind(addr).await.map_err(|e| ViewError::Bind(addr.to_string(), e))?;
        let bound = listener.local_addr().map_err(ViewError::Serve)?;
        let app = routes(bound.port()).layer(axum::middleware::from_fn_with_state(bound.port(), check_host));
        ready(bound);
        axum::serve(listener, app).await.map_err(ViewError::Serve)
    })
}

async fn check_host(
    State(port): State<u16>,
    request: axum::extract::Request,
    next: axum::middleware::Next,
) -> Response {
    let host = request.headers().get(header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
    if is_local_host(host, port) {
        next.run(request).await
    } else {
        let msg = format!(
            "refused: this server only answers requests addressed to 127.0.0.1:{port}, localhost:{port} or [::1]:{port} (Host was {host:?})\n"
        );
        (StatusCode::FORBIDDEN, msg).into_response()
    }
}

/// A response of `content_type` that the browser must not cache (items and frames change when
/// the page is directed or played).
pub(crate) fn respond(content_type: &str, body: impl Into<Body>) -> Response {
    ([(header::CONTENT_TYPE, content_type.to_string()), (header::CACHE_CONTROL, "no-store".into())], body.into())
        .into_response()
}

/// A JSON answer with `status`.
pub(crate) fn json_answer(status: StatusCode, v: &serde_json::Value) -> Response {
    let mut r = respond("application/json", serde_json::to_vec(v).expect("JSON values serialise"));
    *r.status_mut() = status;
    r
}

/// Refuses a POST that does not come from this server's own page (an `Origin` of another site,
/// or none but a browser's form content type) or whose body is not JSON. `what` names the
/// requests in the message, in the plural and the singular (`("directions", "direction")`).
pub(crate) fn refuse_foreign(port: u16, headers: &HeaderMap, what: (&str, &str)) -> Option<Response> {
    let (many, one) = what;
    let value = |name: header::HeaderName| headers.get(name).map(|h| h.to_str().unwrap_or("?"));
    if let Some(origin) = value(header::ORIGIN)
        && !is_same_origin(origin, port)
    {
        let msg = format!(
            "refused: {many} are taken only from this server's own page (http://127.0.0.1:{port}/); Origin was {origin:?}"
        );
        return Some(json_answer(StatusCode::FORBIDDEN, &serde_json::json!({ "error": msg })));
    }
    if !value(header::CONTENT_TYPE).is_some_and(is_json) {
        let msg = format!("refused: a {one}'s body must be JSON, sent with Content-Type: application/json");
        return Some(json_answer(StatusCode::UNSUPPORTED_MEDIA_TYPE, &serde_json::json!({ "error": msg })));
    }
    None
}

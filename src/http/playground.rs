//! The playground: `GET /` serves a page of our own where a person edits a
//! scene with the DOM's form controls, sees the render follow, clicks a
//! pixel for its term breakdown, sees two precision tiers side by side, and
//! drops a GLB to see it lit and download its bake.
//! The page is a few ES modules with no build step (in `playground/`),
//! embedded in the binary with the example scenes of `examples/`, and talks
//! only to the public API. A Content-Security-Policy lets it load nothing
//! from any other origin, so it works offline. `--playground false` leaves
//! these routes out (404).

use axum::Router;
use axum::extract::Path;
use axum::http::{HeaderName, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;

use super::AppState;
use super::error::ApiError;

/// What the page may load: its own files, and the images it decodes itself.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; img-src 'self' data: blob:; \
     script-src 'self'; style-src 'self'; connect-src 'self'; object-src 'none'; \
     base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

/// The page itself, served at `/`.
const PAGE: &str = include_str!("playground/index.html");

const JS: &str = "text/javascript; charset=utf-8";
const JSON: &str = "application/json";

/// The files the page loads, under `/playground/`: name, content type, body.
const FILES: [(&str, &str, &str); 13] = [
    (
        "style.css",
        "text/css; charset=utf-8",
        include_str!("playground/style.css"),
    ),
    (
        "icon.svg",
        "image/svg+xml",
        include_str!("playground/icon.svg"),
    ),
    ("main.js", JS, include_str!("playground/main.js")),
    ("request.js", JS, include_str!("playground/request.js")),
    ("controls.js", JS, include_str!("playground/controls.js")),
    ("render.js", JS, include_str!("playground/render.js")),
    ("probe.js", JS, include_str!("playground/probe.js")),
    ("model.js", JS, include_str!("playground/model.js")),
    ("dom.js", JS, include_str!("playground/dom.js")),
    ("candidate.js", JS, include_str!("playground/candidate.js")),
    (
        "spheres.json",
        JSON,
        include_str!("../../examples/spheres.json"),
    ),
    ("mesh.json", JSON, include_str!("../../examples/mesh.json")),
    (
        "triangle.json",
        JSON,
        include_str!("../../examples/triangle.json"),
    ),
];

/// The playground's routes, `page` (`/`) and `assets` (`/playground/{file}`),
/// or none when it is turned off.
pub fn router(enabled: bool, page: &'static str, assets: &'static str) -> Router<AppState> {
    if !enabled {
        return Router::new();
    }
    Router::new()
        .route(
            page,
            get(|| async { file("text/html; charset=utf-8", PAGE) }),
        )
        .route(assets, get(asset))
}

async fn asset(Path(name): Path<String>) -> Result<Response, ApiError> {
    FILES
        .iter()
        .find(|(file, _, _)| *file == name)
        .map(|&(_, content_type, body)| file(content_type, body))
        .ok_or_else(ApiError::not_found)
}

/// A file of the page, with the policy that keeps it to this origin.
fn file(content_type: &'static str, body: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::CONTENT_SECURITY_POLICY, CONTENT_SECURITY_POLICY),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
            (header::REFERRER_POLICY, "no-referrer"),
            (
                HeaderName::from_static("cross-origin-opener-policy"),
                "same-origin",
            ),
            // Embedded in the binary: a new binary may serve new files.
            (header::CACHE_CONTROL, "no-cache"),
        ],
        body,
    )
        .into_response()
}

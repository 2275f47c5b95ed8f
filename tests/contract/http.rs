//! The HTTP service's own answers against the document, over a loopback
//! socket: each operation's documented answer (its body valid against the
//! schema the document names, its content type, `x-request-id`), each
//! error with the status and problem type the document gives it, the
//! choice between a PNG and JSON by `Accept` (with `Vary`), the metrics
//! the document lists, and `/readyz` while shutting down.

use reqwest::header::HeaderMap;
use reqwest::{Method, StatusCode};
use serde_json::{Value, json};

use super::support::{
    DOCUMENT, assert_problem, assert_valid, document, quad_beside_a_sphere, sphere_on_a_floor,
    sphere_on_a_floor_but, validator_in,
};
use crate::http::TestServer;
use crate::support::client;

/// What the server answered.
struct Answer {
    status: StatusCode,
    headers: HeaderMap,
    bytes: Vec<u8>,
}

impl Answer {
    fn content_type(&self) -> String {
        self.headers["content-type"].to_str().unwrap().to_owned()
    }

    fn json(&self) -> Value {
        serde_json::from_slice(&self.bytes).unwrap()
    }

    fn text(&self) -> &str {
        std::str::from_utf8(&self.bytes).unwrap()
    }

    /// Whether the answer varies on `Accept`.
    fn varies_on_accept(&self) -> bool {
        self.headers
            .get_all("vary")
            .iter()
            .any(|v| v.to_str().unwrap().to_ascii_lowercase().contains("accept"))
    }
}

/// `method uri` on `server`, with `body` as JSON declared as
/// `content_type` and `accept`, where given.
async fn call(
    server: &TestServer,
    method: Method,
    uri: &str,
    content_type: Option<&str>,
    accept: Option<&str>,
    body: Option<&Value>,
) -> Answer {
    let mut request = client().request(method, server.url(uri));
    if let Some(content_type) = content_type {
        request = request.header("content-type", content_type);
    }
    if let Some(accept) = accept {
        request = request.header("accept", accept);
    }
    if let Some(body) = body {
        request = request.body(serde_json::to_vec(body).unwrap());
    }
    let response = request.send().await.unwrap();
    Answer {
        status: response.status(),
        headers: response.headers().clone(),
        bytes: response.bytes().await.unwrap().to_vec(),
    }
}

async fn get(server: &TestServer, uri: &str) -> Answer {
    call(server, Method::GET, uri, None, None, None).await
}

/// A render of `body`, accepting `accept` where given.
async fn render(server: &TestServer, accept: Option<&str>, body: &Value) -> Answer {
    let json = Some("application/json");
    call(server, Method::POST, "/v1/render", json, accept, Some(body)).await
}

/// The answer is a problem+json, valid and of a status its type fixes,
/// with that `status` and type `slug`; its body.
fn assert_problem_answer(answer: &Answer, status: u16, slug: &str) -> Value {
    let doc = document();
    assert_eq!(answer.status.as_u16(), status);
    assert_eq!(answer.content_type(), "application/problem+json");
    let body = answer.json();
    assert_problem(&doc, &validator_in(&doc, "Problem"), &body);
    assert_eq!(body["type"], format!("urn:glint:problem:{slug}"));
    body
}

/// The document gives `POST path` the answer `status`.
fn assert_documented(path: &str, status: u16) {
    assert!(
        document()["paths"][path]["post"]["responses"]
            .get(status.to_string())
            .is_some(),
        "{status} is not documented for {path}"
    );
}

/// One vertex under GL_LIGHT0, asking for its terms per vertex.
fn one_vertex() -> Value {
    json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] },
            "lights": [{}], "terms": "per_vertex" })
}

/// A shade of `body` declared as `content_type`.
async fn shade(server: &TestServer, content_type: Option<&str>, body: &Value) -> Answer {
    call(
        server,
        Method::POST,
        "/v1/shade",
        content_type,
        None,
        Some(body),
    )
    .await
}

#[tokio::test]
async fn a_shade_answers_a_shade_response_with_its_request_id() {
    let server = TestServer::start().await;
    let answer = shade(&server, Some("application/json"), &one_vertex()).await;
    assert_eq!(answer.status, StatusCode::OK);
    assert!(answer.headers.contains_key("x-request-id"));
    assert_valid(
        &validator_in(&document(), "ShadeResponse"),
        "ShadeResponse",
        &answer.json(),
    );
}

/// `GET uri` answers 200 with a text body valid against `schema`.
async fn text_answer(uri: &str, schema: &str) -> Answer {
    let server = TestServer::start().await;
    let answer = get(&server, uri).await;
    assert_eq!(answer.status, StatusCode::OK);
    let body = json!(answer.text());
    assert_valid(&validator_in(&document(), schema), schema, &body);
    answer
}

#[tokio::test]
async fn healthz_answers_its_body_as_text() {
    let answer = text_answer("/healthz", "HealthzBody").await;
    assert!(answer.content_type().starts_with("text/plain"));
}

#[tokio::test]
async fn readyz_answers_its_body() {
    text_answer("/readyz", "ReadyzBody").await;
}

#[tokio::test]
async fn openapi_yaml_serves_the_document_as_yaml() {
    let server = TestServer::start().await;
    let answer = get(&server, "/openapi.yaml").await;
    assert_eq!(answer.status, StatusCode::OK);
    assert_eq!(answer.content_type(), "application/yaml");
    assert_eq!(answer.bytes, DOCUMENT.as_bytes());
    let served: Value = serde_norway::from_slice(&answer.bytes).expect("YAML");
    assert_valid(
        &validator_in(&document(), "OpenApiDocument"),
        "OpenApiDocument",
        &served,
    );
}

/// A shade of `body` declared as `content_type` is refused with a problem
/// of `status` and type `slug`, with the request's id, at a status the
/// document gives shades.
async fn assert_refused_shade(content_type: Option<&str>, body: Value, status: u16, slug: &str) {
    let server = TestServer::start().await;
    let answer = shade(&server, content_type, &body).await;
    assert_problem_answer(&answer, status, slug);
    assert!(answer.headers.contains_key("x-request-id"));
    assert_documented("/v1/shade", status);
}

#[tokio::test]
async fn a_malformed_shade_is_400() {
    let body = json!({ "vertices": {} });
    assert_refused_shade(Some("application/json"), body, 400, "malformed").await;
}

#[tokio::test]
async fn a_shade_not_declared_as_json_is_415() {
    for content_type in [Some("text/plain"), None] {
        let slug = "unsupported-media-type";
        assert_refused_shade(content_type, one_vertex(), 415, slug).await;
    }
}

#[tokio::test]
async fn an_invalid_shade_is_422() {
    let body = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } });
    assert_refused_shade(Some("application/json"), body, 422, "invalid").await;
}

#[test]
fn a_render_s_answer_documents_vary() {
    let doc = document();
    let ok = &doc["paths"]["/v1/render"]["post"]["responses"]["200"];
    assert!(
        ok["headers"].get("Vary").is_some(),
        "Vary is not documented"
    );
}

/// The PNG by default and whenever `Accept` does not prefer JSON; it
/// varies on `Accept`.
#[tokio::test]
async fn a_render_is_a_png_unless_json_is_preferred() {
    let doc = document();
    let ok = &doc["paths"]["/v1/render"]["post"]["responses"]["200"];
    assert!(ok["content"].get("image/png").is_some());
    let server = TestServer::start().await;
    for accept in [
        None,
        Some("image/png"),
        Some("*/*"),
        Some("image/png, application/json"),
    ] {
        let answer = render(&server, accept, &sphere_on_a_floor()).await;
        assert_eq!(answer.status, StatusCode::OK, "{accept:?}");
        assert_eq!(answer.content_type(), "image/png", "{accept:?}");
        assert!(answer.headers.contains_key("x-request-id"));
        assert!(answer.varies_on_accept(), "{accept:?}: no Vary: accept");
        assert!(
            answer.bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{accept:?}: not a PNG"
        );
    }
}

/// The JSON form when `Accept` prefers it: a `RenderJsonResponse` of the
/// whole image, its first probe on the first object, its last on the
/// background, warning of the per-pixel fallback of per-vertex shading.
#[tokio::test]
async fn a_render_preferring_json_is_a_render_json_response() {
    let render_json = validator_in(&document(), "RenderJsonResponse");
    let server = TestServer::start().await;
    for (accept, body, per_vertex) in [
        ("application/json", sphere_on_a_floor(), false),
        ("application/json, */*", quad_beside_a_sphere(), true),
    ] {
        let answer = render(&server, Some(accept), &body).await;
        assert_eq!(answer.status, StatusCode::OK, "{accept}");
        assert_eq!(answer.content_type(), "application/json", "{accept}");
        assert!(answer.headers.contains_key("x-request-id"));
        assert!(answer.varies_on_accept(), "{accept}: no Vary: accept");
        let out = answer.json();
        assert_valid(&render_json, "RenderJsonResponse", &out);
        assert_eq!(
            (out["width"].as_u64(), out["height"].as_u64()),
            (Some(32), Some(24))
        );
        let probes = out["terms"]["probes"].as_array().unwrap();
        assert_eq!(probes[0]["hit"]["object"], 0, "{out}");
        assert!(probes.last().unwrap()["hit"].is_null(), "{out}");
        let fallback = out["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "per_pixel_fallback");
        assert_eq!(fallback, per_vertex, "{out}");
    }
}

/// A refused render is a problem, whatever the request accepts, with the
/// request's id and its pointer, at a status the document gives renders.
async fn assert_refused_render(body: Value, status: u16, slug: &str, pointer: &str) {
    let server = TestServer::start().await;
    for accept in [None, Some("application/json")] {
        let answer = render(&server, accept, &body).await;
        assert_eq!(answer.status.as_u16(), status, "{body}");
        let problem = assert_problem_answer(&answer, status, slug);
        assert!(answer.headers.contains_key("x-request-id"));
        assert_eq!(problem["pointer"], pointer, "{problem}");
    }
    assert_documented("/v1/render", status);
}

#[tokio::test]
async fn an_invalid_render_is_422_at_its_pointer() {
    assert_refused_render(
        sphere_on_a_floor_but(&|b| b["lights"] = json!([{ "spot": { "cutoff": 120 } }])),
        422,
        "invalid",
        "/lights/0/spot/cutoff",
    )
    .await;
    assert_refused_render(
        sphere_on_a_floor_but(&|b| b["samples"] = json!(0)),
        422,
        "invalid",
        "/samples",
    )
    .await;
}

#[tokio::test]
async fn a_render_past_the_pixel_limit_is_413_at_camera() {
    let body = sphere_on_a_floor_but(&|b| {
        b["camera"]["width"] = json!(4000);
        b["camera"]["height"] = json!(4000);
    });
    assert_refused_render(body, 413, "over-limit", "/camera").await;
}

#[tokio::test]
async fn a_malformed_render_is_400_at_its_pointer() {
    let body = sphere_on_a_floor_but(&|b| b["colour"] = json!(1));
    assert_refused_render(body, 400, "malformed", "/colour").await;
}

/// `method uri` with a shade as its body, where the service has no such
/// operation: a problem of `status` and type `slug`.
async fn assert_unrouted(method: Method, uri: &str, status: u16, slug: &str) {
    let server = TestServer::start().await;
    let json = Some("application/json");
    let answer = call(&server, method, uri, json, None, Some(&one_vertex())).await;
    assert_problem_answer(&answer, status, slug);
}

#[tokio::test]
async fn an_unknown_path_is_404() {
    assert_unrouted(Method::GET, "/nowhere", 404, "not-found").await;
}

#[tokio::test]
async fn an_unknown_method_is_405() {
    assert_unrouted(Method::DELETE, "/v1/shade", 405, "method-not-allowed").await;
}

/// The metrics the document lists are the ones served, as OpenMetrics,
/// after one request answered and one refused (a family with labels shows
/// once it has a sample).
#[tokio::test]
async fn the_metrics_the_document_lists_are_served() {
    let server = TestServer::start().await;
    let answered = shade(&server, Some("application/json"), &one_vertex()).await;
    assert_eq!(answered.status, StatusCode::OK);
    let refused = shade(&server, Some("text/plain"), &one_vertex()).await;
    assert_eq!(refused.status, StatusCode::UNSUPPORTED_MEDIA_TYPE);
    let answer = get(&server, "/metrics").await;
    assert_eq!(answer.status, StatusCode::OK);
    assert!(
        answer
            .content_type()
            .starts_with("application/openmetrics-text; version=1.0.0")
    );
    let text = answer.text();
    let doc = document();
    let listed = doc["paths"]["/metrics"]["get"]["description"]
        .as_str()
        .unwrap();
    for name in [
        "glint_requests_total{route,status}",
        "glint_request_duration_seconds{route}",
        "glint_vertices_shaded_total",
        "glint_pixels_shaded_total",
        "glint_jobs_queued",
        "glint_jobs_running",
        "glint_rejections_total{reason}",
    ] {
        assert!(listed.contains(name), "the document does not list {name}");
        let family = name.split('{').next().unwrap();
        let family = family.strip_suffix("_total").unwrap_or(family);
        assert!(
            text.contains(&format!("# TYPE {family} ")),
            "/metrics has no {family}:\n{text}"
        );
    }
}

/// Shutting down: `/readyz` answers 503 with a documented problem.
#[tokio::test]
async fn readyz_is_503_while_shutting_down() {
    let server = TestServer::start().await;
    server
        .state
        .shutting_down
        .store(true, std::sync::atomic::Ordering::Relaxed);
    let answer = get(&server, "/readyz").await;
    assert_eq!(answer.status, StatusCode::SERVICE_UNAVAILABLE);
    assert_eq!(answer.content_type(), "application/problem+json");
    assert_problem(
        &document(),
        &validator_in(&document(), "Problem"),
        &answer.json(),
    );
}

//! What a deployment relies on: health, readiness, metrics, the contract,
//! request ids and CORS.

use super::{TestServer, client, one_vertex};

#[tokio::test]
async fn health_and_readiness() {
    let server = TestServer::start().await;
    let health = client().get(server.url("/healthz")).send().await.unwrap();
    assert_eq!(health.status(), 200);
    assert_eq!(health.text().await.unwrap(), "ok");
    let ready = client().get(server.url("/readyz")).send().await.unwrap();
    assert_eq!(ready.status(), 200);
}

#[tokio::test]
async fn metrics_count_requests_vertices_and_rejections() {
    let server = TestServer::start().await;
    assert_eq!(
        server.post_json("/v1/shade", &one_vertex()).await.status(),
        200
    );
    let invalid = serde_json::json!({ "material": { "shininess": -1 }, "vertices": { "positions": [], "normals": [] } });
    assert_eq!(server.post_json("/v1/shade", &invalid).await.status(), 422);
    let response = client().get(server.url("/metrics")).send().await.unwrap();
    assert!(
        response.headers()["content-type"]
            .to_str()
            .unwrap()
            .starts_with("application/openmetrics-text")
    );
    let text = response.text().await.unwrap();
    for line in [
        "glint_requests_total{route=\"/v1/shade\",status=\"200\"} 1",
        "glint_requests_total{route=\"/v1/shade\",status=\"422\"} 1",
        "glint_vertices_shaded_total 1",
        "glint_rejections_total{reason=\"invalid\"} 1",
        "glint_jobs_queued 0",
        "glint_jobs_running 0",
    ] {
        assert!(text.lines().any(|l| l == line), "no `{line}` in\n{text}");
    }
    assert!(text.contains("glint_request_duration_seconds_bucket"));
    assert!(text.contains("glint_pixels_shaded_total"));
}

#[tokio::test]
async fn the_contract_is_served_as_written() {
    let server = TestServer::start().await;
    let response = client()
        .get(server.url("/openapi.yaml"))
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "application/yaml");
    let served = response.text().await.unwrap();
    let on_disk =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/api/openapi.yaml")).unwrap();
    assert!(
        served == on_disk,
        "served {} bytes, the file has {}",
        served.len(),
        on_disk.len()
    );
}

#[tokio::test]
async fn request_ids_are_echoed_or_made() {
    let server = TestServer::start().await;
    let response = client()
        .get(server.url("/healthz"))
        .header("x-request-id", "trace-42")
        .send()
        .await
        .unwrap();
    assert_eq!(response.headers()["x-request-id"], "trace-42");
    let a = client().get(server.url("/healthz")).send().await.unwrap();
    let b = client().get(server.url("/healthz")).send().await.unwrap();
    let (a, b) = (&a.headers()["x-request-id"], &b.headers()["x-request-id"]);
    assert!(!a.is_empty() && a != b, "{a:?} {b:?}");
}

#[tokio::test]
async fn cors_allows_the_configured_origins_only() {
    let server = TestServer::with(|c| c.cors_origins = vec!["https://tool.example".into()]).await;
    let preflight = client()
        .request(reqwest::Method::OPTIONS, server.url("/v1/shade"))
        .header("origin", "https://tool.example")
        .header("access-control-request-method", "POST")
        .header("access-control-request-headers", "content-type")
        .send()
        .await
        .unwrap();
    assert_eq!(
        preflight.headers()["access-control-allow-origin"],
        "https://tool.example"
    );
    let other = client()
        .get(server.url("/healthz"))
        .header("origin", "https://elsewhere.example")
        .send()
        .await
        .unwrap();
    assert!(!other.headers().contains_key("access-control-allow-origin"));
}

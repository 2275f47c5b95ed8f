//! What a deployment relies on: health, readiness, metrics, the contract,
//! request ids and CORS.

use super::{TestServer, one_vertex};
use crate::support::{client, repo};

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
    let on_disk = std::fs::read_to_string(repo().join("api/openapi.yaml")).unwrap();
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

#[tokio::test]
async fn http2_streams_on_one_connection_are_each_answered_with_their_own_request() {
    // A connection's service is called in place for each request: many
    // streams at once on one HTTP/2 connection each get the answer of
    // their own body and their own request id, and the metrics count them.
    use http_body_util::{BodyExt, Full};
    use hyper_util::rt::{TokioExecutor, TokioIo};

    let server = TestServer::start().await;
    let stream = tokio::net::TcpStream::connect(server.addr).await.unwrap();
    let (sender, connection) =
        hyper::client::conn::http2::handshake(TokioExecutor::new(), TokioIo::new(stream))
            .await
            .unwrap();
    tokio::spawn(connection);
    let bodies: Vec<_> = (0..16)
        .map(|i| {
            let x = f64::from(i) / 16.0;
            serde_json::json!({
                "lights": [{}],
                "vertices": { "positions": [[0, 0, 0]], "normals": [[x, 0, 1]] }
            })
        })
        .collect();
    let streams: Vec<_> = bodies
        .iter()
        .enumerate()
        .map(|(i, body)| {
            let request = hyper::Request::post(server.url("/v1/shade"))
                .header("content-type", "application/json")
                .header("x-request-id", format!("stream-{i}"))
                .body(Full::new(axum::body::Bytes::from(body.to_string())))
                .unwrap();
            let mut sender = sender.clone();
            tokio::spawn(async move {
                let response = sender.send_request(request).await.unwrap();
                assert_eq!(response.version(), hyper::Version::HTTP_2);
                assert_eq!(response.status(), 200);
                let id = response.headers()["x-request-id"]
                    .to_str()
                    .unwrap()
                    .to_owned();
                let bytes = response.into_body().collect().await.unwrap().to_bytes();
                let json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                (id, json["colors"][0].clone())
            })
        })
        .collect();
    for (i, (body, stream)) in bodies.iter().zip(streams).enumerate() {
        let (id, color) = stream.await.unwrap();
        assert_eq!(id, format!("stream-{i}"));
        // The same body over HTTP/1.1, on its own.
        let alone: serde_json::Value = server
            .post_json("/v1/shade", body)
            .await
            .json()
            .await
            .unwrap();
        assert_eq!(color, alone["colors"][0]);
    }
    let metrics = client().get(server.url("/metrics")).send().await.unwrap();
    let text = metrics.text().await.unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with(r#"glint_requests_total{route="/v1/shade",status="200"}"#))
        .expect("the shade count");
    assert!(line.ends_with(" 32"), "{line}");
}

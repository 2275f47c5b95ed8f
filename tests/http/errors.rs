//! Every error status of the contract's table, each with its pointer.

use std::time::Duration;

use serde_json::{Value, json};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

use super::{TestServer, expect_problem, one_vertex, pooled_request};
use crate::support::client;

fn with(mut base: Value, pointer: &str, value: Value) -> Value {
    *base
        .pointer_mut(pointer)
        .expect("the pointer exists in the base") = value;
    base
}

#[tokio::test]
async fn a_body_that_is_not_json_is_400() {
    let server = TestServer::start().await;
    let response = client()
        .post(server.url("/v1/shade"))
        .header("content-type", "application/json")
        .body("{\"vertices\": ")
        .send()
        .await
        .unwrap();
    let body = expect_problem(response, 400, "malformed", None).await;
    assert!(
        body["detail"].as_str().unwrap().contains("ends too early"),
        "{body}"
    );
}

#[tokio::test]
async fn a_wrong_type_is_400_at_its_field() {
    let server = TestServer::start().await;
    let request = with(one_vertex(), "/lights/0", json!({ "diffuse": "white" }));
    let response = server.post_json("/v1/shade", &request).await;
    expect_problem(response, 400, "malformed", Some("/lights/0/diffuse")).await;
}

#[tokio::test]
async fn an_unknown_field_is_400_and_named() {
    let server = TestServer::start().await;
    let request = with(
        one_vertex(),
        "/lights/0",
        json!({ "diffuse_colour": [1, 1, 1] }),
    );
    let response = server.post_json("/v1/shade", &request).await;
    let body = expect_problem(response, 400, "malformed", Some("/lights/0/diffuse_colour")).await;
    assert!(
        body["detail"].as_str().unwrap().contains("unknown field"),
        "{body}"
    );
}

#[tokio::test]
async fn a_colour_of_two_numbers_is_400() {
    let server = TestServer::start().await;
    let request = json!({ "material": { "diffuse": [1, 1] }, "vertices": { "positions": [], "normals": [] } });
    let response = server.post_json("/v1/shade", &request).await;
    expect_problem(response, 400, "malformed", Some("/material/diffuse")).await;
}

#[tokio::test]
async fn a_body_over_the_limit_is_413() {
    let server = TestServer::with(|c| c.max_body_bytes = 1024).await;
    let mut request = one_vertex();
    request["vertices"]["positions"] = json!(vec![[0.0, 0.0, 0.0]; 200]);
    request["vertices"]["normals"] = json!(vec![[0.0, 0.0, 1.0]; 200]);
    let response = server.post_json("/v1/shade", &request).await;
    expect_problem(response, 413, "over-limit", Some("")).await;
}

#[tokio::test]
async fn vertices_over_the_limit_are_413_at_the_positions() {
    let server = TestServer::with(|c| c.max_vertices = 2).await;
    let request = json!({ "vertices": { "positions": [[0,0,0],[0,0,0],[0,0,0]], "normals": [[0,0,1],[0,0,1],[0,0,1]] } });
    let response = server.post_json("/v1/shade", &request).await;
    expect_problem(response, 413, "over-limit", Some("/vertices/positions")).await;
}

#[tokio::test]
async fn lights_over_the_limit_are_413() {
    let server = TestServer::with(|c| c.max_lights = 2).await;
    let request = with(one_vertex(), "/lights", json!([{}, {}, {}]));
    let response = server.post_json("/v1/shade", &request).await;
    expect_problem(response, 413, "over-limit", Some("/lights")).await;
}

#[tokio::test]
async fn another_content_type_is_415() {
    let server = TestServer::start().await;
    for content_type in [
        Some("text/plain"),
        Some("application/x-www-form-urlencoded"),
        Some("text/json"),
        Some("application/jsonp"),
        Some("application/json-seq"),
        Some("application/vnd.example.json"),
        Some("application"),
        Some("json"),
        None,
    ] {
        let mut request = client()
            .post(server.url("/v1/shade"))
            .body(one_vertex().to_string());
        if let Some(content_type) = content_type {
            request = request.header("content-type", content_type);
        }
        let response = request.send().await.unwrap();
        expect_problem(response, 415, "unsupported-media-type", None).await;
    }
}

#[tokio::test]
async fn json_is_recognised_in_any_case_with_parameters_and_as_a_suffix() {
    let server = TestServer::start().await;
    for content_type in [
        "application/json",
        "Application/JSON",
        "application/json; charset=utf-8",
        " application/json ;charset=UTF-8",
        "application/problem+json",
        "application/vnd.example+JSON",
    ] {
        let response = client()
            .post(server.url("/v1/shade"))
            .header("content-type", content_type)
            .body(one_vertex().to_string())
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200, "{content_type}");
    }
}

#[tokio::test]
async fn invalid_values_are_422_at_their_fields() {
    let server = TestServer::start().await;
    let cases = [
        (
            with(
                one_vertex(),
                "/lights/0",
                json!({ "spot": { "cutoff": 120 } }),
            ),
            "/lights/0/spot/cutoff",
        ),
        (
            with(
                one_vertex(),
                "/lights/0",
                json!({ "spot": { "exponent": -1 } }),
            ),
            "/lights/0/spot/exponent",
        ),
        (
            with(
                one_vertex(),
                "/lights/0",
                json!({ "attenuation": [0, 0, 0] }),
            ),
            "/lights/0/attenuation",
        ),
        (
            with(
                one_vertex(),
                "/lights/0",
                json!({ "attenuation": [1, -0.5, 0] }),
            ),
            "/lights/0/attenuation/1",
        ),
        (
            with(
                one_vertex(),
                "/lights/0",
                json!({ "position": [0, 0, 0, 0] }),
            ),
            "/lights/0/position",
        ),
        (
            with(one_vertex(), "/vertices/normals", json!([])),
            "/vertices/normals",
        ),
        (
            json!({ "material": { "shininess": -1 }, "vertices": { "positions": [], "normals": [] } }),
            "/material/shininess",
        ),
        (
            json!({ "material": { "diffuse": [1, 1, 1e300] }, "vertices": { "positions": [], "normals": [] } }),
            "/material/diffuse/2",
        ),
        (
            with(one_vertex(), "/vertices/positions/0", json!([0, 1e31, 0])),
            "/vertices/positions/0",
        ),
        (
            json!({ "view": { "eye": [1, 1, 1], "target": [1, 1, 1] }, "vertices": { "positions": [], "normals": [] } }),
            "/view/target",
        ),
    ];
    for (request, pointer) in cases {
        let response = server.post_json("/v1/shade", &request).await;
        expect_problem(response, 422, "invalid", Some(pointer)).await;
    }
}

#[tokio::test]
async fn a_saturated_server_answers_503_with_retry_after_at_once() {
    let server = TestServer::one_job(0, |c| {
        c.retry_after_secs = 7;
    })
    .await;
    let release = server.occupy_workers().await;
    let response = server.post_json("/v1/shade", &pooled_request()).await;
    assert_eq!(response.headers()["retry-after"], "7");
    expect_problem(response, 503, "busy", None).await;
    // A tiny request costs less than handing it over: it is answered on the
    // async side, busy pool or not.
    let tiny = server.post_json("/v1/shade", &one_vertex()).await;
    assert_eq!(tiny.status(), 200, "a tiny request is not shed");
    drop(release);
    // The blocking job ends on its worker thread; wait for its slot to free.
    tokio::time::timeout(std::time::Duration::from_secs(10), async {
        while server.state.pool.running() > 0 {
            tokio::task::yield_now().await;
        }
    })
    .await
    .expect("the released job ends");
    let response = server.post_json("/v1/shade", &pooled_request()).await;
    assert_eq!(
        response.status(),
        200,
        "served again once the worker is free"
    );
}

#[tokio::test]
async fn a_saturated_server_refuses_a_large_body_before_reading_it() {
    // The body timeout is far longer than the test waits: an answer can only
    // come before the body, which is never sent.
    let server = TestServer::one_job(0, |c| {
        c.body_timeout_ms = 600_000;
    })
    .await;
    let _release = server.occupy_workers().await;
    for path in ["/v1/shade", "/v1/render"] {
        let mut stream = tokio::net::TcpStream::connect(server.addr).await.unwrap();
        let head = format!(
            "POST {path} HTTP/1.1\r\nhost: x\r\ncontent-type: application/json\r\n\
             content-length: 50000000\r\n\r\n"
        );
        stream.write_all(head.as_bytes()).await.unwrap();
        let mut answer = vec![0; 4096];
        let read = tokio::time::timeout(Duration::from_secs(20), stream.read(&mut answer))
            .await
            .expect("answered without the body")
            .unwrap();
        let answer = String::from_utf8_lossy(&answer[..read]);
        assert!(answer.starts_with("HTTP/1.1 503"), "{path}: {answer}");
        assert!(
            answer.to_ascii_lowercase().contains("retry-after"),
            "{answer}"
        );
    }
    // What no retry would mend is said first, busy or not.
    let response = client()
        .post(server.url("/v1/render"))
        .header("content-type", "text/plain")
        .body("{}")
        .send()
        .await
        .unwrap();
    expect_problem(response, 415, "unsupported-media-type", None).await;
}

/// Regression: a large body refused while it was being sent lost its 503 to
/// a connection reset. The server answered, then closed with the body's
/// bytes unread, which makes the kernel reset the connection; a client
/// still writing got the reset instead of the answer. The refused body is
/// now read and thrown away after the answer.
#[tokio::test]
async fn a_large_body_refused_while_it_is_sent_gets_its_503_not_a_reset() {
    let server = TestServer::one_job(0, |_| {}).await;
    let _release = server.occupy_workers().await;
    // About 8 MB: far more than the sockets' buffers hold, so the client is
    // still sending when the answer comes.
    let vertices = 200_000;
    let body = json!({
        "lights": [{}],
        "vertices": {
            "positions": vec![[0.125, -0.25, 0.5]; vertices],
            "normals": vec![[0.5, 0.25, -0.125]; vertices],
        }
    })
    .to_string();
    let attempts: Vec<_> = (0..16)
        .map(|attempt| {
            let (url, body) = (server.url("/v1/shade"), body.clone());
            tokio::spawn(async move {
                let response = client()
                    .post(url)
                    .header("content-type", "application/json")
                    .body(body)
                    .send()
                    .await
                    .unwrap_or_else(|e| panic!("attempt {attempt}: {e:?}"));
                expect_problem(response, 503, "busy", None).await;
            })
        })
        .collect();
    for attempt in attempts {
        attempt.await.unwrap();
    }
}

#[tokio::test]
async fn a_request_past_its_deadline_is_503_not_a_half_answer() {
    let server = TestServer::one_job(4, |c| {
        c.request_timeout_ms = 200;
    })
    .await;
    let _release = server.occupy_workers().await;
    let response = server.post_json("/v1/shade", &pooled_request()).await;
    assert!(response.headers().contains_key("retry-after"));
    let body = expect_problem(response, 503, "busy", None).await;
    assert!(
        body["detail"].as_str().unwrap().contains("deadline"),
        "{body}"
    );
}

#[tokio::test]
async fn unknown_paths_and_methods_are_problems_too() {
    let server = TestServer::start().await;
    let response = client().get(server.url("/v2/shade")).send().await.unwrap();
    expect_problem(response, 404, "not-found", None).await;
    let response = client().get(server.url("/v1/shade")).send().await.unwrap();
    expect_problem(response, 405, "method-not-allowed", None).await;
}

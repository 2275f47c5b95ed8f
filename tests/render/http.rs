//! `POST /v1/render` over a real socket: the PNG by default, the JSON form
//! when `Accept` prefers it, problem+json errors with pointers, and the
//! pixel counter.

use std::net::SocketAddr;

use base64::Engine;
use serde_json::{Value, json};

use super::support::decode_png;
use crate::http::TestServer;
use crate::support::client;

fn scene() -> Value {
    json!({
        "materials": { "red": { "diffuse": [1, 0, 0], "specular": [1, 1, 1], "shininess": 10 } },
        "lights": [ { "position": [1, 1, 1, 0] } ],
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 64, "height": 48 },
        "objects": [ { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" } ],
        "probes": [[32, 24]],
    })
}

async fn post(addr: SocketAddr, body: &Value, accept: Option<&str>) -> reqwest::Response {
    let mut request = client().post(format!("http://{addr}/v1/render")).json(body);
    if let Some(accept) = accept {
        request = request.header("accept", accept);
    }
    request.send().await.expect("the server answers")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn render_answers_png_by_default_and_json_on_request() {
    let server = TestServer::start().await;
    let addr = server.addr;

    let response = post(addr, &scene(), None).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "image/png");
    let png = decode_png(&response.bytes().await.unwrap());
    assert_eq!(png.dimensions(), (64, 48));
    assert_ne!(png.get_pixel(32, 24).0, [0, 0, 0, 255], "the sphere is lit");

    let response = post(addr, &scene(), Some("application/json")).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "application/json");
    let body: Value = response.json().await.unwrap();
    assert_eq!(
        (body["width"].as_u64(), body["height"].as_u64()),
        (Some(64), Some(48))
    );
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(body["png_base64"].as_str().unwrap())
        .unwrap();
    assert_eq!(
        decode_png(&bytes),
        png,
        "the JSON form carries the same image"
    );
    assert_eq!(body["terms"]["probes"][0]["hit"]["object"], 0);
    assert_eq!(body["precision"]["mode"], "accurate");

    // A region: the PNG is the region's size.
    let mut tile = scene();
    tile["region"] = json!({ "x": 10, "y": 20, "width": 30, "height": 5 });
    let response = post(addr, &tile, Some("image/png, application/json;q=0.5")).await;
    assert_eq!(response.headers()["content-type"], "image/png");
    let cropped = decode_png(&response.bytes().await.unwrap());
    assert_eq!(cropped.dimensions(), (30, 5));

    // Two full images and one region of 150 pixels.
    let metrics = client()
        .get(format!("http://{addr}/metrics"))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    let line = metrics
        .lines()
        .find(|l| l.starts_with("glint_pixels_shaded_total"))
        .unwrap_or_else(|| panic!("no pixel counter in {metrics}"));
    assert_eq!(
        line.split_whitespace().nth(1),
        Some(&*(2 * 64 * 48 + 150).to_string())
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn render_errors_are_problems_with_pointers() {
    let server = TestServer::with(|c| c.max_pixels = 1000).await;
    let addr = server.addr;
    let check = |response: reqwest::Response, status: u16, pointer: &'static str| async move {
        assert_eq!(response.status().as_u16(), status);
        assert_eq!(
            response.headers()["content-type"],
            "application/problem+json"
        );
        let body: Value = response.json().await.unwrap();
        assert_eq!(body["pointer"], pointer, "{body}");
    };

    // 64 × 48 pixels is over this server's 1000.
    check(post(addr, &scene(), None).await, 413, "/camera").await;

    let mut small = scene();
    small["camera"]["width"] = json!(20);
    small["camera"]["height"] = json!(20);
    small["probes"] = json!([[5, 5]]);
    let response = post(addr, &small, None).await;
    assert_eq!(response.status(), 200);

    let mut bad = small.clone();
    bad["camera"]["fov_y"] = json!(200);
    check(
        post(addr, &bad, Some("application/json")).await,
        422,
        "/camera/fov_y",
    )
    .await;

    let mut bad = small.clone();
    bad["objects"][0]["material"] = json!("blue");
    check(post(addr, &bad, None).await, 422, "/objects/0/material").await;

    let mut bad = small;
    bad["objects"][0]["sphere"]["radius"] = json!("one");
    check(
        post(addr, &bad, None).await,
        400,
        "/objects/0/sphere/radius",
    )
    .await;
}

//! Models over HTTP: `multipart/form-data` as browsers and curl send it,
//! bare `model/gltf-binary` bodies, the answer's form by `Accept`, renders
//! with a model, and every lying model refused with its pointer while the
//! server goes on serving.

use serde_json::{Value, json};

use super::bake::{hierarchy, request};
use super::refused::{cases, tent};
use super::support::{read_glb, warning_codes};
use crate::http::{TestServer, expect_problem, one_vertex};
use crate::support::{Scratch, available, client, debian_program};

const BOUNDARY: &str = "------------------------d74496d66958873e";

/// A form as `curl -F request=<req.json;type=application/json -F
/// model=@model.glb` sends it; `parts` are (name, content type, bytes).
pub(crate) fn form(parts: &[(&str, Option<&str>, &[u8])]) -> Vec<u8> {
    let mut body = Vec::new();
    for (name, content_type, bytes) in parts {
        body.extend(format!("--{BOUNDARY}\r\n").bytes());
        let file = if *name == "model" {
            "; filename=\"model.glb\""
        } else {
            ""
        };
        body.extend(format!("Content-Disposition: form-data; name=\"{name}\"{file}\r\n").bytes());
        if let Some(t) = content_type {
            body.extend(format!("Content-Type: {t}\r\n").bytes());
        }
        body.extend(b"\r\n");
        body.extend(*bytes);
        body.extend(b"\r\n");
    }
    body.extend(format!("--{BOUNDARY}--\r\n").bytes());
    body
}

pub(crate) async fn post(
    server: &TestServer,
    path: &str,
    content_type: &str,
    accept: Option<&str>,
    body: Vec<u8>,
) -> reqwest::Response {
    let mut request = client()
        .post(server.url(path))
        .header("content-type", content_type)
        .body(body);
    if let Some(accept) = accept {
        request = request.header("accept", accept);
    }
    request.send().await.expect("the server answers")
}

pub(crate) fn multipart() -> String {
    format!("multipart/form-data; boundary={BOUNDARY}")
}

/// The server still serves: a JSON shade answers 200.
async fn still_serving(server: &TestServer) {
    let response = server.post_json("/v1/shade", &one_vertex()).await;
    assert_eq!(response.status(), 200);
}

#[tokio::test]
async fn a_form_is_baked_into_the_model_or_answered_as_json() {
    let server = TestServer::start().await;
    let glb = hierarchy().0.glb();
    let request_json = serde_json::to_vec(&request()).unwrap();
    let body = form(&[
        ("request", Some("application/json"), &request_json),
        ("model", Some("application/octet-stream"), &glb),
    ]);
    let response = post(&server, "/v1/shade", &multipart(), None, body.clone()).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "model/gltf-binary");
    assert_eq!(response.headers()["vary"], "accept");
    let baked = read_glb(&response.bytes().await.unwrap());
    assert!(baked.attribute(1, 0, "COLOR_0").is_some());
    assert_eq!(
        baked.json["extras"]["glint"]["precision"]["mode"],
        "accurate"
    );

    let response = post(
        &server,
        "/v1/shade",
        &multipart(),
        Some("application/json"),
        body,
    )
    .await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "application/json");
    let answer: Value = response.json().await.unwrap();
    assert_eq!(answer["primitives"].as_array().unwrap().len(), 4);
    assert_eq!(
        answer["stats"]["vertices"].as_u64().unwrap() as usize,
        answer["colors"].as_array().unwrap().len()
    );
}

#[tokio::test]
async fn a_bare_model_is_baked_with_what_the_model_says() {
    let server = TestServer::start().await;
    let (lit, _) = super::bake::lit_scene();
    let response = post(&server, "/v1/shade", "model/gltf-binary", None, lit.glb()).await;
    assert_eq!(response.status(), 200);
    let baked = read_glb(&response.bytes().await.unwrap());
    let codes = warning_codes(&baked.json["extras"]["glint"]["warnings"]);
    assert!(codes.contains(&"pbr_approximated"), "{codes:?}");
    // Browsers send a form's string field with no content type at all.
    let body = form(&[
        ("request", None, br#"{"color_format":"float"}"#),
        ("model", Some("model/gltf-binary"), &lit.glb()),
    ]);
    let response = post(
        &server,
        "/v1/shade",
        &multipart(),
        Some("application/json, */*"),
        body,
    )
    .await;
    assert_eq!(response.headers()["content-type"], "application/json");
}

#[tokio::test]
async fn a_render_takes_the_model_and_its_camera() {
    let server = TestServer::start().await;
    let (lit, _) = super::bake::lit_scene();
    let request = json!({
        "camera": { "width": 40, "height": 30 },
        "objects": [{ "sphere": { "center": [0, 0, -3], "radius": 1 }, "material": "ball" }],
        "materials": { "ball": { "diffuse": [0, 0, 1] } },
    });
    let request = serde_json::to_vec(&request).unwrap();
    let body = form(&[
        ("request", Some("application/json"), &request),
        ("model", None, &lit.glb()),
    ]);
    let response = post(&server, "/v1/render", &multipart(), None, body.clone()).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "image/png");
    let png = image::load_from_memory(&response.bytes().await.unwrap()).unwrap();
    assert_eq!((png.width(), png.height()), (40, 30));
    let response = post(
        &server,
        "/v1/render",
        &multipart(),
        Some("application/json"),
        body,
    )
    .await;
    let answer: Value = response.json().await.unwrap();
    // The sphere and the tent's four triangles.
    assert_eq!(answer["stats"]["triangles"], 4, "{}", answer["stats"]);
    let codes = warning_codes(&answer["warnings"]);
    assert_eq!(codes, ["spot_falloff_fitted", "pbr_approximated"]);
}

#[tokio::test]
async fn every_lying_model_is_refused_over_http_and_the_server_serves_the_next() {
    let server = TestServer::start().await;
    for case in cases() {
        for path in ["/v1/shade", "/v1/render"] {
            let body = form(&[("model", None, &case.glb)]);
            let response = post(&server, path, &multipart(), None, body).await;
            let status = match case.kind {
                glint::scene::RequestErrorKind::Malformed => 400,
                glint::scene::RequestErrorKind::OverLimit => 413,
                glint::scene::RequestErrorKind::Unsupported => 415,
                glint::scene::RequestErrorKind::Invalid => 422,
            };
            let slug = match status {
                400 => "malformed",
                413 => "over-limit",
                415 => "unsupported-media-type",
                _ => "invalid",
            };
            let problem = expect_problem(response, status, slug, Some(case.pointer)).await;
            assert!(problem["detail"].is_string(), "{}: {problem}", case.name);
            still_serving(&server).await;
        }
    }
    // The bare body too.
    let response = post(&server, "/v1/shade", "model/gltf-binary", None, Vec::new()).await;
    expect_problem(response, 400, "malformed", Some("/model")).await;
    still_serving(&server).await;
}

#[tokio::test]
async fn broken_forms_are_refused_with_the_part_at_fault() {
    let server = TestServer::start().await;
    let glb = tent().glb();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            form(&[("request", Some("application/json"), b"{}")]),
            "/model",
        ),
        (
            form(&[("model", None, &glb), ("model", None, &glb)]),
            "/model",
        ),
        (
            form(&[("request", None, b"{\"lights\": [}"), ("model", None, &glb)]),
            "/request/lights/0",
        ),
        (
            form(&[("request", None, b"not json"), ("model", None, &glb)]),
            "/request",
        ),
        (
            form(&[
                ("request", None, b"{}"),
                ("request", None, b"{}"),
                ("model", None, &glb),
            ]),
            "/request",
        ),
        (
            form(&[("texture", None, b"png"), ("model", None, &glb)]),
            "/texture",
        ),
        (b"no delimiter at all".to_vec(), ""),
    ];
    for (body, pointer) in cases {
        let response = post(&server, "/v1/shade", &multipart(), None, body).await;
        expect_problem(response, 400, "malformed", Some(pointer)).await;
        still_serving(&server).await;
    }
    let response = post(
        &server,
        "/v1/shade",
        "multipart/form-data",
        None,
        Vec::new(),
    )
    .await;
    expect_problem(response, 400, "malformed", Some("")).await;
    let response = post(&server, "/v1/render", "model/gltf", None, glb.clone()).await;
    expect_problem(response, 415, "unsupported-media-type", None).await;
    still_serving(&server).await;
}

#[tokio::test]
async fn a_model_over_the_body_limit_is_refused_before_it_is_read() {
    let server = TestServer::with(|c| c.max_body_bytes = 1024).await;
    let glb = hierarchy().0.glb();
    assert!(glb.len() > 1024);
    let response = post(&server, "/v1/shade", "model/gltf-binary", None, glb).await;
    expect_problem(response, 413, "over-limit", Some("")).await;
    still_serving(&server).await;
}

/// `curl -F` (Debian's curl, installed when missing): the form exactly as
/// it sends it.
#[tokio::test]
async fn curl_sends_a_form_that_is_baked() {
    let test = "gltf::http::curl_sends_a_form_that_is_baked";
    let Some(curl) = available(debian_program("curl", "curl").await, test) else {
        return;
    };
    let version = tokio::process::Command::new(&curl)
        .arg("--version")
        .output()
        .await
        .expect("curl runs");
    assert!(version.status.success());
    let server = TestServer::start().await;
    let scratch = Scratch::new("curl");
    let dir = scratch.path();
    let model = dir.join("model.glb");
    std::fs::write(&model, hierarchy().0.glb()).unwrap();
    let out = dir.join("baked.glb");
    let request = format!("request={};type=application/json", request());
    let status = tokio::process::Command::new(curl)
        .args(["-s", "--fail", "--noproxy", "*", "-o"])
        .arg(&out)
        .args(["-F", &request, "-F"])
        .arg(format!("model=@{}", model.display()))
        .arg(server.url("/v1/shade"))
        .status()
        .await
        .unwrap();
    assert!(status.success());
    let baked = read_glb(&std::fs::read(&out).unwrap());
    assert!(baked.attribute(1, 0, "COLOR_0").is_some());
}

/// Runs the `glint` binary with `args`: (success, stdout, stderr).
async fn glint(args: &[&std::ffi::OsStr]) -> (bool, Vec<u8>, String) {
    let out = tokio::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .output()
        .await
        .unwrap();
    (
        out.status.success(),
        out.stdout,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `glint bake` and `glint render --model` answer what the endpoints answer.
#[tokio::test]
async fn the_command_line_bakes_and_renders_as_the_endpoints_do() {
    let server = TestServer::start().await;
    let scratch = Scratch::new("cli");
    let dir = scratch.path();
    let (model, request_file, out) = (dir.join("m.glb"), dir.join("req.json"), dir.join("out.glb"));
    let glb = hierarchy().0.glb();
    std::fs::write(&model, &glb).unwrap();
    let request_json = serde_json::to_vec(&request()).unwrap();
    std::fs::write(&request_file, &request_json).unwrap();
    let body = form(&[("request", None, &request_json), ("model", None, &glb)]);

    let (ok, _, stderr) = glint(&[
        "bake".as_ref(),
        model.as_os_str(),
        "--request".as_ref(),
        request_file.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ])
    .await;
    assert!(ok, "{stderr}");
    let offline = read_glb(&std::fs::read(&out).unwrap());
    let response = post(&server, "/v1/shade", &multipart(), None, body.clone()).await;
    let online = read_glb(&response.bytes().await.unwrap());
    for (node, primitive) in [(1, 0), (0, 0), (0, 1), (2, 0)] {
        let colors =
            |g: &super::support::Read| g.floats(g.attribute(node, primitive, "COLOR_0").unwrap());
        assert_eq!(colors(&offline), colors(&online));
    }

    let (ok, stdout, stderr) = glint(&[
        "bake".as_ref(),
        model.as_os_str(),
        "--request".as_ref(),
        request_file.as_os_str(),
        "--json".as_ref(),
    ])
    .await;
    assert!(ok, "{stderr}");
    let offline: Value = serde_json::from_slice(&stdout).unwrap();
    let response = post(
        &server,
        "/v1/shade",
        &multipart(),
        Some("application/json"),
        body,
    )
    .await;
    let online: Value = response.json().await.unwrap();
    assert_eq!(offline["colors"], online["colors"]);
    assert_eq!(offline["primitives"], online["primitives"]);

    // A render with the model, as the endpoint renders it.
    let (lit, _) = super::bake::lit_scene();
    std::fs::write(&model, lit.glb()).unwrap();
    let render_request = br#"{"camera":{"width":32,"height":24}}"#;
    std::fs::write(&request_file, render_request).unwrap();
    let png = dir.join("out.png");
    let (ok, _, stderr) = glint(&[
        "render".as_ref(),
        request_file.as_os_str(),
        "--model".as_ref(),
        model.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
    ])
    .await;
    assert!(ok, "{stderr}");
    let body = form(&[
        ("request", None, render_request),
        ("model", None, &lit.glb()),
    ]);
    let response = post(&server, "/v1/render", &multipart(), None, body).await;
    assert_eq!(
        std::fs::read(&png).unwrap(),
        response.bytes().await.unwrap()
    );

    // A lying model: exit 1, its problem on stderr.
    std::fs::write(&model, &cases()[1].glb).unwrap();
    let (ok, _, stderr) = glint(&[
        "bake".as_ref(),
        model.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ])
    .await;
    assert!(!ok);
    let problem: Value = serde_json::from_str(stderr.trim()).unwrap();
    assert_eq!(problem["pointer"], "/model", "{problem}");
}

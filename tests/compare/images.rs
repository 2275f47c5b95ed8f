//! An image compare: a render request and a port's PNG of it. The port is
//! `render_gl.py`, a NumPy ray tracer written apart from glint; its PNG of
//! a scene with Phong's specular is diagnosed with `phong_specular` first,
//! its PNG of GL's equation is within the bound, GL's own PNG has no error
//! at all; the heatmap is read back by Pillow; bad parts are refused at
//! their pointers.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use base64::Engine;
use serde_json::{Value, json};

use super::diagnosis::names;
use crate::gltf::http::{form, multipart, post};
use crate::http::{TestServer, expect_problem};
use crate::support::{PythonTools, Scratch, available, repo, run};

/// The heatmap's ramp at 0 and at its top: the first and last stops of
/// matplotlib's "inferno", as docs/compare.md names them.
const RAMP_BOTTOM: [u8; 3] = [0, 0, 4];
const RAMP_TOP: [u8; 3] = [252, 255, 164];

/// A sphere on a floor under a directional light and an attenuated point
/// light, every value given (the NumPy renderer knows no defaults): one
/// sample per pixel, lit per pixel, linear PNG channels.
fn scene() -> Value {
    json!({
        "light_model": { "ambient": [0.1, 0.1, 0.12, 1.0], "local_viewer": false },
        "materials": {
            "floor": {
                "ambient": [0.2, 0.2, 0.2, 1.0], "diffuse": [0.3, 0.45, 0.3, 1.0],
                "specular": [0.3, 0.3, 0.3, 1.0], "emission": [0.0, 0.0, 0.0, 1.0],
                "shininess": 8.0
            },
            "shiny": {
                "ambient": [0.2, 0.1, 0.1, 1.0], "diffuse": [0.7, 0.2, 0.2, 1.0],
                "specular": [0.8, 0.8, 0.8, 1.0], "emission": [0.05, 0.0, 0.02, 1.0],
                "shininess": 20.0
            }
        },
        "lights": [
            { "position": [0.5, 1.0, 0.8, 0.0], "ambient": [0.05, 0.05, 0.05, 1.0],
              "diffuse": [0.8, 0.8, 0.75, 1.0], "specular": [1.0, 1.0, 1.0, 1.0],
              "attenuation": [1.0, 0.0, 0.0] },
            { "position": [-2.0, 3.0, 2.0, 1.0], "ambient": [0.0, 0.0, 0.0, 1.0],
              "diffuse": [0.4, 0.4, 0.5, 1.0], "specular": [0.6, 0.6, 0.6, 1.0],
              "attenuation": [1.0, 0.1, 0.02] }
        ],
        "camera": { "eye": [0.0, 1.5, 5.0], "target": [0.0, 0.5, 0.0], "up": [0.0, 1.0, 0.0],
                    "fov_y": 45.0, "width": 96, "height": 72 },
        "objects": [
            { "sphere": { "center": [0.0, 0.8, 0.0], "radius": 0.8 }, "material": "shiny" },
            { "plane": { "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0] }, "material": "floor" }
        ],
        "background": [0.05, 0.1, 0.2, 1.0],
        "shading": "per_pixel",
        "samples": 1,
        "precision": "accurate",
        "encoding": "linear"
    })
}

/// `render_gl.py`, which runs in the pinned environment of tests/compare.
fn script() -> PathBuf {
    repo().join("tests/compare/render_gl.py")
}

/// What `render_gl.py` prints with `args`, run in the pinned environment
/// of tests/compare, or `None` (after saying why) where its Python tools
/// cannot be had outside CI.
async fn render_gl(test: &str, args: &[&std::ffi::OsStr]) -> Option<Vec<u8>> {
    let python = available(PythonTools::pinned_by("compare").await, test)?;
    let script = script();
    let mut all = vec![script.as_os_str()];
    all.extend(args);
    let output = run(python.bin("python"), &all, |_| {}, Duration::from_secs(120))
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    Some(output.stdout)
}

/// The NumPy renderer's PNG of `request` with `deviations`.
async fn numpy_png(test: &str, request: &Value, deviations: &[&str]) -> Option<Vec<u8>> {
    let work = Scratch::new(test);
    let request_file = work.path().join("request.json");
    let out = work.path().join("candidate.png");
    std::fs::write(&request_file, request.to_string()).unwrap();
    let mut args = vec![request_file.as_os_str(), out.as_os_str()];
    args.extend(deviations.iter().map(std::ffi::OsStr::new));
    render_gl(test, &args).await?;
    Some(std::fs::read(out).unwrap())
}

/// POSTs the form of `request` and `image` to /v1/compare.
async fn compare(
    server: &TestServer,
    request: &Value,
    image: &[u8],
    accept: Option<&str>,
) -> reqwest::Response {
    let request = serde_json::to_vec(request).unwrap();
    let body = form(&[
        ("request", Some("application/json"), &request),
        ("image", Some("image/png"), image),
    ]);
    post(server, "/v1/compare", &multipart(), accept, body).await
}

async fn compare_json(server: &TestServer, request: &Value, image: &[u8]) -> Value {
    let response = compare(server, request, image, Some("application/json")).await;
    assert_eq!(response.status(), 200);
    response.json().await.unwrap()
}

/// GL's PNG of `request`, as /v1/render answers it.
async fn gl_png(server: &TestServer, request: &Value) -> Vec<u8> {
    let response = server.post_json("/v1/render", request).await;
    assert_eq!(response.status(), 200);
    response.bytes().await.unwrap().to_vec()
}

#[tokio::test]
async fn a_port_s_image_with_phong_specular_is_diagnosed_with_it_first() {
    let test = "a_port_s_image_with_phong_specular_is_diagnosed_with_it_first";
    let request = scene();
    let Some(candidate) = numpy_png(test, &request, &["phong_specular"]).await else {
        return;
    };
    let server = TestServer::start().await;
    let answer = compare_json(&server, &request, &candidate).await;
    let error = &answer["error"];
    assert_eq!(error["within_bound"], false, "{error}");
    assert!(error["psnr_db"].as_f64().unwrap().is_finite(), "{error}");
    let best = &answer["diagnosis"][0];
    assert_eq!(names(best), ["phong_specular"], "{}", answer["diagnosis"]);
    assert_eq!(best["explains"], true, "{best}");
    assert!(
        answer["diagnosis"]
            .as_array()
            .unwrap()
            .iter()
            .skip(1)
            .all(|d| d["explains"] == false || names(d).contains(&"phong_specular")),
        "{}",
        answer["diagnosis"]
    );
    // The worst pixel lies on the sphere (object 0) or the floor, with
    // GL's breakdown there.
    let worst = &answer["worst"][0];
    assert!(worst["hit"]["object"].is_u64(), "{worst}");
    assert!(worst["breakdown"]["lights"].is_array(), "{worst}");
    assert_eq!(answer["worst"].as_array().unwrap().len(), 10);
}

#[tokio::test]
async fn an_independent_image_of_gl_is_within_the_bound_and_explained_by_nothing() {
    let test = "an_independent_image_of_gl_is_within_the_bound_and_explained_by_nothing";
    let request = scene();
    let Some(candidate) = numpy_png(test, &request, &[]).await else {
        return;
    };
    let server = TestServer::start().await;
    let answer = compare_json(&server, &request, &candidate).await;
    let error = &answer["error"];
    // Two 8-bit PNGs rounded from colours within the tier's bound of each
    // other: at most one step apart.
    assert!(
        error["max_abs"].as_f64().unwrap() <= 1.0 / 255.0 + 1e-6,
        "{error}"
    );
    assert_eq!(error["within_bound"], true, "{error}");
    let explaining: Vec<&Value> = answer["diagnosis"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["explains"] == true)
        .collect();
    assert!(explaining.is_empty(), "{explaining:?}");
}

#[tokio::test]
async fn a_port_s_image_without_emission_is_diagnosed_with_it_first() {
    let test = "a_port_s_image_without_emission_is_diagnosed_with_it_first";
    let request = scene();
    let Some(candidate) = numpy_png(test, &request, &["emission_missing"]).await else {
        return;
    };
    let server = TestServer::start().await;
    let answer = compare_json(&server, &request, &candidate).await;
    let best = &answer["diagnosis"][0];
    assert_eq!(names(best), ["emission_missing"], "{}", answer["diagnosis"]);
    assert_eq!(best["explains"], true, "{best}");
}

#[tokio::test]
async fn gl_s_own_image_has_no_error_and_no_explanation() {
    let server = TestServer::start().await;
    let request = scene();
    let png = gl_png(&server, &request).await;
    let answer = compare_json(&server, &request, &png).await;
    let error = &answer["error"];
    assert_eq!(error["max_abs"], 0.0, "{error}");
    assert_eq!(error["differing_8bit"], 0.0, "{error}");
    assert_eq!(error["within_bound"], true, "{error}");
    // Equal images: PSNR is infinite, which JSON writes null.
    assert!(error["psnr_db"].is_null(), "{error}");
    assert!(
        answer["diagnosis"]
            .as_array()
            .unwrap()
            .iter()
            .all(|d| d["explains"] == false),
        "{}",
        answer["diagnosis"]
    );
}

/// Pillow's reading of `png` at pixel `(x, y)`: width, height, mode, RGB.
async fn pillow_reads(test: &str, png: &[u8], x: u64, y: u64) -> Option<Value> {
    let work = Scratch::new(&format!("{test}-read"));
    let file = work.path().join("heatmap.png");
    std::fs::write(&file, png).unwrap();
    let (x, y) = (x.to_string(), y.to_string());
    let args = ["--read".as_ref(), file.as_os_str(), x.as_ref(), y.as_ref()];
    let printed = render_gl(test, &args).await?;
    Some(serde_json::from_slice(&printed).unwrap())
}

#[tokio::test]
async fn the_heatmap_is_a_png_of_the_image_s_size_and_accept_png_gives_it() {
    let test = "the_heatmap_is_a_png_of_the_image_s_size_and_accept_png_gives_it";
    let request = scene();
    let Some(candidate) = numpy_png(test, &request, &["phong_specular"]).await else {
        return;
    };
    let server = TestServer::start().await;
    let answer = compare_json(&server, &request, &candidate).await;
    let heatmap = base64::engine::general_purpose::STANDARD
        .decode(answer["heatmap_png_base64"].as_str().unwrap())
        .unwrap();
    // The worst pixel is drawn at the top of the ramp (its error is the
    // largest, above the bound), the top-left pixel (the background in
    // both images: the camera looks down on the floor) at its bottom.
    let worst = &answer["worst"][0];
    assert!(
        worst["error"].as_f64().unwrap() > answer["error"]["bound"].as_f64().unwrap(),
        "{worst}"
    );
    let [x, y] = [0, 1].map(|i| worst["pixel"][i].as_u64().unwrap());
    let Some(top) = pillow_reads(test, &heatmap, x, y).await else {
        return;
    };
    assert_eq!(
        (top["width"].as_u64(), top["height"].as_u64()),
        (Some(96), Some(72))
    );
    assert_eq!(top["pixel"], json!(RAMP_TOP), "{top}");
    let corner = pillow_reads(test, &heatmap, 0, 0).await.unwrap();
    assert_eq!(corner["pixel"], json!(RAMP_BOTTOM), "{corner}");

    let response = compare(&server, &request, &candidate, Some("image/png")).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "image/png");
    assert_eq!(response.bytes().await.unwrap().to_vec(), heatmap);
    // Without an Accept, or with */*, the answer is JSON.
    let response = compare(&server, &request, &candidate, Some("*/*")).await;
    assert_eq!(response.headers()["content-type"], "application/json");
}

/// A form's part: name, content type, bytes.
type Part<'a> = (&'a str, Option<&'a str>, &'a [u8]);

/// A PNG of `width × height` in one grey.
fn grey_png(width: u32, height: u32) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    image::GrayImage::from_pixel(width, height, image::Luma([128]))
        .write_to(&mut out, image::ImageFormat::Png)
        .unwrap();
    out.into_inner()
}

#[tokio::test]
async fn bad_parts_are_refused_at_their_pointers() {
    let server = TestServer::start().await;
    let request = scene();
    let request_bytes = serde_json::to_vec(&request).unwrap();
    let right = grey_png(96, 72);
    // Another size, smaller and larger (the larger refused from its
    // header: more pixels than the render has).
    for png in [grey_png(48, 36), grey_png(96, 73), grey_png(200, 200)] {
        let response = compare(&server, &request, &png, None).await;
        let problem = expect_problem(response, 422, "invalid", Some("/image")).await;
        assert!(
            problem["detail"].as_str().unwrap().contains("96×72"),
            "{problem}"
        );
    }
    // Not a PNG, and a PNG cut short.
    for bytes in [&b"the notes of a person"[..], &right[..right.len() / 2]] {
        let response = compare(&server, &request, bytes, None).await;
        expect_problem(response, 400, "malformed", Some("/image")).await;
    }
    let cases: Vec<(Vec<Part>, &str)> = vec![
        (vec![("request", None, &request_bytes[..])], "/image"),
        (vec![("image", None, &right[..])], "/request"),
        (
            vec![
                ("request", None, &request_bytes[..]),
                ("image", None, &right[..]),
                ("image", None, &right[..]),
            ],
            "/image",
        ),
        (
            vec![
                ("request", None, &request_bytes[..]),
                ("image", None, &right[..]),
                ("picture", None, &right[..]),
            ],
            "/picture",
        ),
    ];
    for (parts, pointer) in cases {
        let response = post(&server, "/v1/compare", &multipart(), None, form(&parts)).await;
        expect_problem(response, 400, "malformed", Some(pointer)).await;
    }
    // The request part's own faults, under /request.
    let mut adaptive = request.clone();
    adaptive["samples"] = json!({ "max": 16, "tolerance": 0.01 });
    let response = compare(&server, &adaptive, &right, None).await;
    expect_problem(response, 422, "invalid", Some("/request/samples")).await;
    let mut probes = request.clone();
    probes["probes"] = json!([[1, 1]]);
    let response = compare(&server, &probes, &right, None).await;
    expect_problem(response, 400, "malformed", Some("/request/probes")).await;
    let mut worst = request.clone();
    worst["worst"] = json!(1001);
    let response = compare(&server, &worst, &right, None).await;
    expect_problem(response, 422, "invalid", Some("/request/worst")).await;
    // A render refuses the fields of a compare.
    let response = server.post_json("/v1/render", &worst).await;
    expect_problem(response, 400, "malformed", Some("/worst")).await;
}

/// `glint compare REQUEST CANDIDATE.png`: its exit code and stdout.
fn glint_compare(dir: &Path, request: &Value, png: &[u8]) -> (i32, String) {
    let request_file = dir.join("request.json");
    let png_file = dir.join("candidate.png");
    std::fs::write(&request_file, request.to_string()).unwrap();
    std::fs::write(&png_file, png).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("compare")
        .arg(&request_file)
        .arg(&png_file)
        .output()
        .unwrap();
    (
        output.status.code().unwrap(),
        String::from_utf8(output.stdout).unwrap(),
    )
}

#[tokio::test]
async fn the_command_line_compares_a_png() {
    let test = "the_command_line_compares_a_png";
    let request = scene();
    let Some(candidate) = numpy_png(test, &request, &["phong_specular"]).await else {
        return;
    };
    let work = Scratch::new("compare-cli-png");
    let (code, out) = glint_compare(work.path(), &request, &candidate);
    assert_eq!(code, 1, "{out}");
    assert!(out.lines().next().unwrap().contains("PSNR"), "{out}");
    let first = out.lines().nth(1).unwrap();
    assert!(
        first.starts_with('*') && first.contains("phong_specular"),
        "{out}"
    );
    let independent_gl = numpy_png(test, &request, &[]).await.unwrap();
    let (code, out) = glint_compare(work.path(), &request, &independent_gl);
    assert_eq!(code, 0, "{out}");
    let (code, _) = glint_compare(work.path(), &request, &grey_png(3, 3));
    assert_eq!(code, 2);
}

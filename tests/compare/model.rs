//! A compare with a model: the candidate in the GLB's `COLOR_0`, the
//! request in the form's `request` part.

use serde_json::{Value, json};

use super::every_term;
use crate::gltf::http::{form, multipart, post};
use crate::gltf::support::Gltf;
use crate::http::{TestServer, expect_problem};
use crate::support::Scratch;

/// A GLB of one primitive: the scene's vertices (in eye space, no node
/// transform) with `colors` as its COLOR_0 (float VEC4), or none.
fn model(positions: &[[f64; 3]], normals: &[[f64; 3]], colors: Option<&[[f64; 4]]>) -> Vec<u8> {
    let narrow3 =
        |v: &[[f64; 3]]| -> Vec<[f32; 3]> { v.iter().map(|p| p.map(|x| x as f32)).collect() };
    let mut gltf = Gltf::new();
    let position = gltf.vec3s(&narrow3(positions));
    let normal = gltf.vec3s(&narrow3(normals));
    let mut attributes = json!({ "POSITION": position, "NORMAL": normal });
    if let Some(colors) = colors {
        let bytes: Vec<u8> = colors
            .iter()
            .flatten()
            .flat_map(|&c| (c as f32).to_le_bytes())
            .collect();
        let view = gltf.view(&bytes, None);
        let accessor = gltf.accessor(json!({
            "bufferView": view, "componentType": 5126, "count": colors.len(), "type": "VEC4"
        }));
        attributes["COLOR_0"] = json!(accessor);
    }
    let mesh = gltf.mesh(json!([{ "attributes": attributes }]));
    let node = gltf.node(json!({ "mesh": mesh }));
    gltf.scene(&[node]);
    gltf.glb()
}

#[tokio::test]
async fn a_model_s_colours_are_diagnosed_as_a_json_candidate_is() {
    let server = TestServer::start().await;
    let mut scene = every_term();
    // The model holds f32 positions and normals: the candidate is made of
    // those.
    let narrow = |v: &mut Vec<[f64; 3]>| v.iter_mut().for_each(|p| *p = p.map(|x| x as f32 as f64));
    narrow(&mut scene.positions);
    narrow(&mut scene.normals);
    // Three vertices per triangle.
    scene.positions.truncate(scene.positions.len() / 3 * 3);
    scene.normals.truncate(scene.positions.len());
    let colors = scene.colors(&["phong_specular"], false);
    let glb = model(&scene.positions, &scene.normals, Some(&colors));
    let mut request = scene.request("reference");
    request.as_object_mut().unwrap().remove("vertices");
    request["color_space"] = json!("linear");
    let request = serde_json::to_vec(&request).unwrap();
    let body = form(&[
        ("request", Some("application/json"), &request),
        ("model", None, &glb),
    ]);
    let response = post(&server, "/v1/compare", &multipart(), None, body).await;
    assert_eq!(response.status(), 200);
    let answer: Value = response.json().await.unwrap();
    assert_eq!(answer["error"]["within_bound"], false, "{answer}");
    assert_eq!(answer["stats"]["vertices"], scene.positions.len());
    let first = &answer["diagnosis"][0];
    assert_eq!(first["deviations"], json!(["phong_specular"]), "{answer}");
    assert_eq!(first["explains"], true, "{answer}");

    // The command line takes the same two files: the GLB told from JSON
    // by its magic.
    let work = Scratch::new("compare-cli-glb");
    let (request_file, glb_file) = (
        work.path().join("request.json"),
        work.path().join("port.glb"),
    );
    std::fs::write(&request_file, &request).unwrap();
    std::fs::write(&glb_file, &glb).unwrap();
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "compare".as_ref(),
            request_file.as_os_str(),
            glb_file.as_os_str(),
        ])
        .output()
        .unwrap();
    let printed = String::from_utf8(output.stdout).unwrap();
    assert_eq!(output.status.code(), Some(1), "{printed}");
    let line = printed.lines().nth(1).unwrap();
    assert!(
        line.starts_with('*') && line.contains("phong_specular"),
        "{printed}"
    );

    // Without COLOR_0: refused at the primitive's attributes.
    let glb = model(&scene.positions, &scene.normals, None);
    let body = form(&[
        ("request", Some("application/json"), &request),
        ("model", None, &glb),
    ]);
    let response = post(&server, "/v1/compare", &multipart(), None, body).await;
    expect_problem(
        response,
        422,
        "invalid",
        Some("/model/meshes/0/primitives/0/attributes"),
    )
    .await;
}

//! A triangle primitive whose vertex (or index) count is not a multiple of
//! 3: glTF asks for one, and Khronos' validator only warns when it is not,
//! so glint takes such a model as it is. A bake lights every vertex; a
//! render draws the whole triangles and drops the one or two vertices left
//! over; both say so in an `incomplete_triangles` warning.

use glam::{DVec3, DVec4};
use glint::bake::Form;
use glint::render::render_png;
use glint::scene::{Limits, parse_model_render};
use glint_lighting::{
    Light, LightModel, LightPosition, LightSet, Side, SurfaceMaterial, reference,
};
use serde_json::{Value, json};

use super::bake::bake;
use super::support::{Gltf, warning_codes};
use crate::support::Scratch;

/// The corners of a triangle facing +z, and a fourth vertex past it.
const VERTICES: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.5, 1.5, 0.2],
];

/// Unit normals (to f32's precision) leaning differently at each vertex, so
/// their colours differ.
const NORMALS: [[f32; 3]; 4] = [
    [0.0, 0.0, 1.0],
    [0.6, 0.0, 0.8],
    [0.0, 0.6, 0.8],
    [-2.0 / 7.0, 3.0 / 7.0, 6.0 / 7.0],
];

/// A model of two primitives: `VERTICES` without indices (one triangle and
/// one vertex left over), and with the indices `0 1 2 3 2` (one triangle
/// and two indices left over); or, with `whole`, the same with the
/// leftovers removed.
fn model(whole: bool) -> Vec<u8> {
    let mut g = Gltf::new();
    let count = if whole { 3 } else { 4 };
    let positions = g.vec3s(&VERTICES[..count]);
    let normals = g.vec3s(&NORMALS[..count]);
    let all_positions = g.vec3s(&VERTICES);
    let all_normals = g.vec3s(&NORMALS);
    let indices = if whole {
        &[0, 1, 2][..]
    } else {
        &[0, 1, 2, 3, 2][..]
    };
    let indices = g.indices(indices, 5125);
    let mesh = g.mesh(json!([
        { "attributes": { "POSITION": positions, "NORMAL": normals } },
        { "attributes": { "POSITION": all_positions, "NORMAL": all_normals }, "indices": indices },
    ]));
    let node = g.node(json!({ "mesh": mesh }));
    g.scene(&[node]);
    g.glb()
}

fn lighting() -> Value {
    json!({
        "lights": [{ "position": [0.2, 0.4, 1.0, 0.0] }],
        "material": { "diffuse": [0.8, 0.6, 0.4], "specular": [0.5, 0.5, 0.5], "shininess": 10 },
        "precision": "reference",
    })
}

/// The count of the `incomplete_triangles` warning in `warnings`.
fn incomplete(warnings: &Value) -> Option<u64> {
    warnings
        .as_array()?
        .iter()
        .find(|w| w["code"] == "incomplete_triangles")
        .and_then(|w| w["count"].as_u64())
}

#[test]
fn a_bake_lights_every_vertex_of_an_incomplete_triangle_and_says_so() {
    let answer: Value =
        serde_json::from_slice(&bake(&model(false), &lighting(), Form::Json)).unwrap();
    assert_eq!(
        incomplete(&answer["warnings"]),
        Some(2),
        "{}",
        answer["warnings"]
    );
    // Every vertex of both primitives has its colour: the reference's, on
    // the vertex as given (the node has no transform).
    let lights = LightSet::new(
        LightModel::default(),
        vec![Light {
            // The domain type holds the unit direction validation makes.
            position: LightPosition::Directional(DVec3::new(0.2, 0.4, 1.0).normalize()),
            ..Light::default()
        }],
        LightSet::eye_space_viewer(false),
    )
    .unwrap();
    let mut material = SurfaceMaterial::default();
    material.front.diffuse = DVec4::new(0.8, 0.6, 0.4, 1.0);
    material.front.specular = DVec4::new(0.5, 0.5, 0.5, 1.0);
    material.front.shininess = 10.0;
    material.back = material.front;
    let colors = answer["colors"].as_array().unwrap();
    assert_eq!(colors.len(), 8, "four vertices in each primitive");
    for (k, color) in colors.iter().enumerate() {
        let (p, n) = (VERTICES[k % 4], NORMALS[k % 4]);
        let p = DVec3::from_array(p.map(f64::from));
        let n = DVec3::from_array(n.map(f64::from));
        let expected = reference::color(&lights, &material, Side::Front, p, n);
        for c in 0..4 {
            let got = color[c].as_f64().unwrap();
            assert!(
                (got - expected[c]).abs() <= 1e-7,
                "vertex {k}, channel {c}: {got} against {}",
                expected[c]
            );
        }
    }
}

#[test]
fn a_render_draws_the_whole_triangles_only_and_says_so() {
    let request = serde_json::to_vec(&json!({
        "camera": { "eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 60, "width": 48, "height": 40 },
        "lights": [{ "position": [0.2, 0.4, 1.0, 0.0] }],
        "shading": "per_vertex",
    }))
    .unwrap();
    let limits = Limits::default();
    let (scene, warnings) = parse_model_render(Some(&request), &model(false), &limits).unwrap();
    let warnings = serde_json::to_value(&warnings).unwrap();
    assert_eq!(incomplete(&warnings), Some(2), "{warnings}");
    // The same picture as the model without its leftovers.
    let (whole, whole_warnings) =
        parse_model_render(Some(&request), &model(true), &limits).unwrap();
    assert!(
        !warning_codes(&serde_json::to_value(&whole_warnings).unwrap())
            .contains(&"incomplete_triangles")
    );
    assert_eq!(render_png(&scene), render_png(&whole));
}

#[tokio::test]
async fn khronos_validator_only_warns_about_an_incomplete_triangle() {
    let test = "khronos_validator_only_warns_about_an_incomplete_triangle";
    let work = Scratch::new("incomplete-triangles");
    let file = work.path().join("incomplete.glb");
    std::fs::write(&file, model(false)).unwrap();
    let Some(reports) =
        crate::clients::gltf::khronos_reports(std::slice::from_ref(&file), test).await
    else {
        return;
    };
    let report = &reports[file.to_str().unwrap()];
    assert_eq!(report["errors"], 0, "{report}");
    // One warning for each primitive, and that it is about its count.
    let warned: Vec<&Value> = report["messages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["severity"] == 1)
        .map(|m| &m["pointer"])
        .collect();
    assert_eq!(
        warned,
        [
            &json!("/meshes/0/primitives/0"),
            &json!("/meshes/0/primitives/1")
        ],
        "{report}"
    );
}

//! Renders with a model against the same scene sent as JSON, its meshes
//! placed by the test's own matrices: the same image.

use glint::render;
use glint::scene::{Limits, RequestErrorKind, parse_model_render, parse_render};
use serde_json::{Value, json};

use super::bake::{TENT, TENT_INDICES};
use super::support::*;

/// The tent mirrored and stretched by a matrix of exact entries, seen by
/// the model's camera, with the request's plane beside it; and the same
/// scene as a JSON render request, placed by the test.
fn scenes() -> (Vec<u8>, Value, Value) {
    let mut g = Gltf::new();
    let normals: Vec<[f32; 3]> = TENT
        .iter()
        .map(|p| unit([f64::from(p[0]), 0.5, f64::from(p[2])]).map(|x| x as f32))
        .collect();
    let p = g.vec3s(&TENT);
    let n = g.vec3s(&normals);
    let i = g.indices(&TENT_INDICES, 5123);
    let red = g.material(json!({ "name": "red" }));
    let mesh = g.mesh(
        json!([{ "attributes": { "POSITION": p, "NORMAL": n }, "indices": i, "material": red }]),
    );
    // x → −x, y → 2y, then a translation: a mirror (determinant −2).
    let matrix = [
        -1.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.5, -1.0, -0.5, 1.0,
    ];
    let tent = g.node(json!({ "mesh": mesh, "matrix": matrix }));
    g.json["cameras"] = json!([{ "type": "perspective", "perspective": { "yfov": 0.7, "aspectRatio": 1.5, "znear": 0.1 } }]);
    let camera = g.node(json!({ "camera": 0, "translation": [0.0, 0.5, 6.0] }));
    g.scene(&[camera, tent]);

    let lighting = json!({
        "light_model": { "two_side": true },
        "back_material": { "diffuse": [0.1, 0.9, 0.1] },
        "lights": [{ "position": [1, 2, 3, 0] }, { "position": [-2, 1, 2, 1], "diffuse": [0.5, 0.5, 1] }],
        "samples": 4,
    });
    let floor =
        json!({ "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "floor" });
    let mut request = lighting.clone();
    request["materials"] = json!({ "red": { "diffuse": [0.9, 0.2, 0.1], "specular": [1, 1, 1], "shininess": 30 },
                                   "floor": { "diffuse": [0.6, 0.6, 0.6] } });
    request["objects"] = json!([floor]);
    request["camera"] = json!({ "height": 64 });

    let world = from_columns(&matrix);
    let positions: Vec<[f64; 3]> = TENT
        .iter()
        .map(|p| point(&world, p.map(f64::from)))
        .collect();
    let placed_normals: Vec<[f64; 3]> = normals
        .iter()
        .map(|n| unit(normal(&world, n.map(f64::from))))
        .collect();
    // The mirror reverses the winding.
    let indices: Vec<u32> = TENT_INDICES
        .chunks(3)
        .flat_map(|t| [t[0], t[2], t[1]])
        .collect();
    let mut json_request = request.clone();
    json_request["camera"] = json!({
        "eye": [0.0, 0.5, 6.0], "target": [0.0, 0.5, 5.0], "up": [0, 1, 0],
        "fov_y": 0.7f64.to_degrees(), "width": 96, "height": 64
    });
    json_request["objects"] = json!([floor, { "mesh": { "positions": positions, "normals": placed_normals, "indices": indices }, "material": "red" }]);
    (g.glb(), request, json_request)
}

#[test]
fn a_model_renders_as_the_same_scene_sent_as_json() {
    let (glb, request, json_request) = scenes();
    let request = serde_json::to_vec(&request).unwrap();
    let (scene, warnings) = parse_model_render(Some(&request), &glb, &Limits::default()).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let model_png = render::render_png(&scene);
    let json_scene = parse_render(
        &serde_json::to_vec(&json_request).unwrap(),
        &Limits::default(),
    )
    .unwrap();
    let json_png = render::render_png(&json_scene);
    let [a, b] = [model_png, json_png].map(|png| image::load_from_memory(&png).unwrap().to_rgba8());
    assert_eq!(a.dimensions(), (96, 64));
    assert_eq!(a.dimensions(), b.dimensions());
    // The normals are normalised by different code: a channel may round
    // the other way.
    let mut differing = 0;
    for (p, q) in a.pixels().zip(b.pixels()) {
        for k in 0..4 {
            assert!(p[k].abs_diff(q[k]) <= 1, "{p:?} against {q:?}");
        }
        differing += usize::from(p != q);
    }
    assert!(differing < 20, "{differing} pixels differ");
    // The camera sees the outside of the mirrored tent: its front (red),
    // never its back (green), which a winding left unreversed would show.
    assert!(a.pixels().any(|p| p[0] > 150 && p[1] < 100));
    assert!(!a.pixels().any(|p| p[1] > 100 && p[0] < 60));
}

#[test]
fn a_render_needs_a_perspective_camera() {
    let (glb, mut request, _) = scenes();
    let check = |request: &Value, glb: &[u8], pointer: &str| {
        let body = serde_json::to_vec(request).unwrap();
        let e = parse_model_render(Some(&body), glb, &Limits::default())
            .map(|_| ())
            .unwrap_err();
        assert_eq!(
            (e.kind, e.pointer.as_str()),
            (RequestErrorKind::Invalid, pointer),
            "{e}"
        );
    };
    request["camera"] = json!({ "eye": [0, 0, 5], "width": 10 });
    check(&request, &glb, "/request/camera");
    request["camera"] = json!({ "width": 10, "height": 10 });
    let mut model = super::refused::tent();
    check(&request, &model.glb(), "/request/camera");
    model.json["cameras"] = json!([{ "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 1, "znear": 0, "zfar": 1 } }]);
    let camera = model.node(json!({ "camera": 0 }));
    model.json["scenes"][0]["nodes"] = json!([0, camera]);
    check(&request, &model.glb(), "/model/cameras/0/type");
}

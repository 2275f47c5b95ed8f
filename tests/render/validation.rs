//! Refused render requests: the status class and the JSON Pointer of the
//! field at fault.

use glint::scene::{self, Limits, RequestErrorKind};
use glint_trace::Samples;
use serde_json::{Value, json};

use super::support::try_scene;

fn valid() -> Value {
    json!({
        "materials": { "red": { "diffuse": [1, 0, 0] }, "a/b~c": {} },
        "lights": [ { "position": [1, 1, 1, 0] } ],
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 64, "height": 48 },
        "objects": [
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "red" },
            { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                        "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]],
                        "indices": [0, 1, 2] }, "material": "a/b~c" }
        ],
        "probes": [[0, 0], [63, 47]],
    })
}

/// `valid()` with the value at `pointer` replaced (or removed for `None`).
fn with(pointer: &str, value: Option<Value>) -> Value {
    let mut body = valid();
    let (parent, key) = pointer.rsplit_once('/').unwrap();
    let key = key.replace("~1", "/").replace("~0", "~");
    let target = body.pointer_mut(parent).unwrap();
    match (target, value) {
        (Value::Object(map), Some(v)) => {
            map.insert(key, v);
        }
        (Value::Object(map), None) => {
            map.remove(&key);
        }
        (Value::Array(items), Some(v)) => items[key.parse::<usize>().unwrap()] = v,
        (other, _) => panic!("cannot set {pointer} in {other}"),
    }
    body
}

#[track_caller]
fn refused(body: &Value, kind: RequestErrorKind, pointer: &str) {
    match try_scene(body) {
        Ok(_) => panic!("accepted, expected {kind:?} at {pointer}"),
        Err(e) => {
            assert_eq!((e.kind, e.pointer.as_str()), (kind, pointer), "{e}");
            assert!(!e.detail.is_empty());
        }
    }
}

use RequestErrorKind::{Invalid, Malformed, OverLimit};

#[test]
fn the_valid_request_is_accepted_with_its_defaults() {
    let scene = try_scene(&valid()).unwrap();
    assert_eq!(scene.material_names, ["a/b~c", "red"]);
    assert_eq!(scene.samples, Samples::Uniform(1));
    assert!(!scene.shadows);
    assert_eq!(scene.region.pixels(), 64 * 48);
    assert_eq!(scene.background.to_array(), [0.0, 0.0, 0.0, 1.0]);
    assert_eq!(scene.triangles(), 1);
    assert_eq!(scene.shading, glint_trace::ShadingMode::PerPixel);
    assert_eq!(scene.encoding, glint_trace::Encoding::Linear);
}

#[test]
fn camera_errors_name_the_field() {
    refused(
        &with("/camera/fov_y", Some(json!(180))),
        Invalid,
        "/camera/fov_y",
    );
    refused(
        &with("/camera/fov_y", Some(json!(0))),
        Invalid,
        "/camera/fov_y",
    );
    refused(
        &with("/camera/up", Some(json!([0, 0, -2]))),
        Invalid,
        "/camera/up",
    );
    refused(
        &with("/camera/up", Some(json!([0, 0, 0]))),
        Invalid,
        "/camera/up",
    );
    refused(
        &with("/camera/target", Some(json!([0, 0, 5]))),
        Invalid,
        "/camera/target",
    );
    refused(
        &with("/camera/width", Some(json!(0))),
        Invalid,
        "/camera/width",
    );
    refused(
        &with("/camera/width", Some(json!(-1))),
        Malformed,
        "/camera/width",
    );
    refused(
        &with("/camera/width", Some(json!(200_000))),
        OverLimit,
        "/camera",
    );
}

#[test]
fn object_errors_name_the_field() {
    refused(
        &with("/objects/0/sphere/radius", Some(json!(0))),
        Invalid,
        "/objects/0/sphere/radius",
    );
    refused(
        &with("/objects/0/sphere/radius", Some(json!(-2))),
        Invalid,
        "/objects/0/sphere/radius",
    );
    refused(
        &with("/objects/1/plane/normal", Some(json!([0, 0, 0]))),
        Invalid,
        "/objects/1/plane/normal",
    );
    refused(
        &with("/objects/0/material", Some(json!("blue"))),
        Invalid,
        "/objects/0/material",
    );
    // Exactly one shape.
    refused(&with("/objects/0/sphere", None), Invalid, "/objects/0");
    let mut two = valid();
    two["objects"][1]["sphere"] = json!({ "center": [0, 0, 0], "radius": 1 });
    refused(&two, Invalid, "/objects/1");
    // Meshes.
    refused(
        &with("/objects/2/mesh/indices", Some(json!([0, 1]))),
        Invalid,
        "/objects/2/mesh/indices",
    );
    refused(
        &with("/objects/2/mesh/indices", Some(json!([0, 1, 3]))),
        Invalid,
        "/objects/2/mesh/indices/2",
    );
    refused(
        &with("/objects/2/mesh/normals", Some(json!([[0, 0, 1]]))),
        Invalid,
        "/objects/2/mesh/normals",
    );
    refused(
        &with("/objects/2/mesh/positions/1", Some(json!([1, 0, 1e31]))),
        Invalid,
        "/objects/2/mesh/positions/1",
    );
    let mut back = valid();
    back["back_material"] = json!({ "diffuse": [0, 0, f64::NAN.to_string()] });
    refused(&back, Malformed, "/back_material/diffuse/2");
    back["back_material"] = json!({ "shininess": -1 });
    refused(&back, Invalid, "/back_material/shininess");
    // A material's error names the material, escaped as a pointer token.
    refused(
        &with("/materials/a~1b~0c", Some(json!({ "shininess": -1 }))),
        Invalid,
        "/materials/a~1b~0c/shininess",
    );
}

#[test]
fn image_option_errors_name_the_field() {
    refused(&with("/samples", Some(json!(0))), Invalid, "/samples");
    refused(&with("/samples", Some(json!(65))), Invalid, "/samples");
    refused(
        &with(
            "/region",
            Some(json!({ "x": 60, "y": 0, "width": 5, "height": 5 })),
        ),
        Invalid,
        "/region",
    );
    refused(
        &with(
            "/region",
            Some(json!({ "x": 0, "y": 0, "width": 0, "height": 5 })),
        ),
        Invalid,
        "/region/width",
    );
    refused(
        &with("/probes/1", Some(json!([64, 0]))),
        Invalid,
        "/probes/1",
    );
    refused(
        &with("/shading", Some(json!("flat"))),
        Malformed,
        "/shading",
    );
    refused(
        &with("/encoding", Some(json!("gamma"))),
        Malformed,
        "/encoding",
    );
    refused(
        &with("/background", Some(json!([0, 0, 0, f64::MAX]))),
        Invalid,
        "/background/3",
    );
    refused(&with("/typo", Some(json!(1))), Malformed, "/typo");
}

#[test]
fn server_limits_are_413() {
    let body = serde_json::to_vec(&valid()).unwrap();
    let limits = Limits {
        max_pixels: 64 * 48 - 1,
        ..Limits::default()
    };
    let e = scene::parse_render(&body, &limits).unwrap_err();
    assert_eq!((e.kind, e.pointer.as_str()), (OverLimit, "/camera"));
    // Over the limit and against the contract: the contract's answer, 422
    // at its pointer, since no server would take the request.
    let both = serde_json::to_vec(&with("/background", Some(json!([0, 0, 0, f64::MAX])))).unwrap();
    let e = scene::parse_render(&both, &limits).unwrap_err();
    assert_eq!((e.kind, e.pointer.as_str()), (Invalid, "/background/3"));

    let limits = Limits {
        max_samples: 4,
        ..Limits::default()
    };
    let e = scene::parse_render(
        &serde_json::to_vec(&with("/samples", Some(json!(5)))).unwrap(),
        &limits,
    )
    .unwrap_err();
    assert_eq!((e.kind, e.pointer.as_str()), (OverLimit, "/samples"));

    let limits = Limits {
        max_vertices: 2,
        ..Limits::default()
    };
    let e = scene::parse_render(&body, &limits).unwrap_err();
    assert_eq!(
        (e.kind, e.pointer.as_str()),
        (OverLimit, "/objects/2/mesh/positions")
    );

    let limits = Limits {
        max_lights: 0,
        ..Limits::default()
    };
    let e = scene::parse_render(&body, &limits).unwrap_err();
    assert_eq!((e.kind, e.pointer.as_str()), (OverLimit, "/lights"));
}

/// Regression: a million tiny objects or materials were each built into a
/// struct a hundred times the size of their JSON before any limit looked.
#[test]
fn too_many_objects_or_materials_are_422_with_their_true_count() {
    let sphere = json!({ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" });
    let objects = vec![sphere; glint::scene::wire::MAX_OBJECTS + 10];
    refused(&with("/objects", Some(json!(objects))), Invalid, "/objects");
    let e = try_scene(&with("/objects", Some(json!(objects)))).unwrap_err();
    assert!(
        e.detail
            .contains(&(glint::scene::wire::MAX_OBJECTS + 10).to_string()),
        "{e}"
    );

    let materials: serde_json::Map<String, Value> = (0..glint::scene::wire::MAX_MATERIALS + 1)
        .map(|i| (format!("m{i}"), json!({})))
        .chain([("red".to_owned(), json!({ "diffuse": [1, 0, 0] }))])
        .collect();
    refused(
        &with("/materials", Some(Value::Object(materials))),
        Invalid,
        "/materials",
    );
}

#[test]
fn adaptive_samples_are_read_and_their_errors_name_the_field() {
    let adaptive = |value: Value| with("/samples", Some(value));
    let scene = try_scene(&adaptive(json!({ "max": 64, "tolerance": 0.004 }))).unwrap();
    assert_eq!(
        scene.samples,
        Samples::Adaptive {
            max: 64,
            tolerance: 0.004
        }
    );
    // A count written as a float with no fraction is still a count.
    assert_eq!(
        try_scene(&adaptive(json!(4.0))).unwrap().samples,
        Samples::Uniform(4)
    );
    let tolerance = "/samples/tolerance";
    refused(
        &adaptive(json!({ "max": 64, "tolerance": 0 })),
        Invalid,
        tolerance,
    );
    refused(
        &adaptive(json!({ "max": 64, "tolerance": 0.2 })),
        Invalid,
        tolerance,
    );
    refused(
        &adaptive(json!({ "max": 64, "tolerance": -0.01 })),
        Invalid,
        tolerance,
    );
    refused(
        &adaptive(json!({ "max": 0, "tolerance": 0.01 })),
        Invalid,
        "/samples/max",
    );
    refused(
        &adaptive(json!({ "max": 65, "tolerance": 0.01 })),
        Invalid,
        "/samples/max",
    );
    refused(
        &adaptive(json!({ "max": 1.5, "tolerance": 0.01 })),
        Malformed,
        "/samples/max",
    );
    refused(
        &adaptive(json!({ "tolerance": 0.01 })),
        Malformed,
        "/samples",
    );
    refused(&adaptive(json!("many")), Malformed, "/samples");
    let limits = Limits {
        max_samples: 16,
        ..Limits::default()
    };
    let body = adaptive(json!({ "max": 20, "tolerance": 0.01 }));
    let e = scene::parse_render(&serde_json::to_vec(&body).unwrap(), &limits).unwrap_err();
    assert_eq!((e.kind, e.pointer.as_str()), (OverLimit, "/samples/max"));
}

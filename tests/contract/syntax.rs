//! The shape of a request: the bodies the schemas and the parser take
//! whole, and those both refuse as malformed (400) — unknown fields, wrong
//! types, arrays of the wrong length, names outside a closed set, required
//! fields left out, `null` for a field that may be left out, integers that
//! are not whole — the schema `ShadeRequest` or `RenderRequest` and the
//! code (`glint::scene`) answering alike.

use glint::scene::{self, Limits, RequestErrorKind, wire};
use serde_json::{Value, json};

use super::support::{
    Verdict::{Accepted, Malformed},
    assert_valid, check_render, check_shade, document, one_sphere, one_sphere_with,
    one_vertex_with, quad_beside_a_sphere, render_outcome, sphere_on_a_floor, validator,
    validator_in,
};

#[test]
fn a_minimal_shade_is_accepted() {
    let minimal = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] } });
    assert_valid(&validator("ShadeRequest"), "ShadeRequest", &minimal);
    check_shade(vec![(
        "minimal",
        one_vertex_with(json!({})),
        true,
        Accepted,
    )]);
}

#[test]
fn a_shade_with_every_field_is_accepted() {
    check_shade(vec![(
        "everything",
        one_vertex_with(json!({
            "light_model": { "ambient": [0.1, 0.1, 0.1], "local_viewer": true, "two_side": true,
                             "color_control": "separate_specular", "specular_model": "phong",
                             "attenuation_clamp": true, "normalize_normals": false },
            "material": { "ambient": [0.2, 0.2, 0.2, 1], "diffuse": [1, 0, 0, 0.5],
                          "specular": [1, 1, 1], "emission": [0, 0, 0.1], "shininess": 200 },
            "back_material": { "diffuse": [0, 1, 0] },
            "lights": [{ "position": [0, 0, 5, 1], "ambient": [0.1, 0.1, 0.1],
                         "diffuse": [1, 1, 1], "specular": [1, 1, 1], "attenuation": [0, 0, 1],
                         "spot": { "direction": [0, 0, -1], "exponent": 3, "cutoff": 90 } }],
            "view": { "eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0] },
            "precision": "fast",
            "terms": "summary",
        })),
        true,
        Accepted,
    )]);
}

#[test]
fn renders_with_every_field_are_accepted() {
    let mut full = one_sphere();
    full["light_model"] = json!({ "two_side": true });
    full["lights"] = json!([{ "position": [1, 1, 1, 0] }]);
    full["objects"] = json!([
        { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
        { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "red" },
        { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                    "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]], "indices": [0, 1, 2] },
          "material": "red" },
        { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2] },
          "material": "red" },
    ]);
    full["background"] = json!([0, 0, 0]);
    full["shading"] = json!("per_vertex");
    full["samples"] = json!(16);
    full["shadows"] = json!(true);
    full["precision"] = json!("reference");
    full["region"] = json!({ "x": 0, "y": 0, "width": 32, "height": 24 });
    full["probes"] = json!([[1, 2], [30, 20]]);
    full["encoding"] = json!("srgb");
    check_render(vec![
        ("one sphere", one_sphere(), true, Accepted),
        ("every field", full, true, Accepted),
        ("a sphere on a floor", sphere_on_a_floor(), true, Accepted),
        (
            "a quad beside a sphere",
            quad_beside_a_sphere(),
            true,
            Accepted,
        ),
    ]);
}

#[test]
fn an_unknown_field_is_400() {
    check_shade(vec![
        (
            "an unknown colour",
            one_vertex_with(json!({ "colour": [1, 0, 0] })),
            false,
            Malformed,
        ),
        (
            "an unknown field",
            one_vertex_with(json!({ "colour": 1 })),
            false,
            Malformed,
        ),
        (
            "an unknown nested field",
            one_vertex_with(json!({ "light_model": { "two_sided": true } })),
            false,
            Malformed,
        ),
    ]);
    check_render(vec![
        (
            "a shade's material in a render",
            one_sphere_with("material", json!({})),
            false,
            Malformed,
        ),
        (
            "an unknown shape",
            one_sphere_with("objects", json!([{ "cube": {}, "material": "red" }])),
            false,
            Malformed,
        ),
    ]);
}

#[test]
fn a_colour_is_3_or_4_numbers() {
    check_shade(vec![
        (
            "a colour of 2 numbers",
            one_vertex_with(json!({ "material": { "diffuse": [1, 0] } })),
            false,
            Malformed,
        ),
        (
            "a colour of 5 numbers",
            one_vertex_with(json!({ "material": { "diffuse": [1, 0, 0, 1, 1] } })),
            false,
            Malformed,
        ),
    ]);
}

#[test]
fn a_point_is_3_numbers_and_a_pixel_2() {
    check_shade(vec![(
        "a position of 2 numbers",
        json!({ "vertices": { "positions": [[0, 0]], "normals": [[0, 0, 1]] } }),
        false,
        Malformed,
    )]);
    check_render(vec![(
        "a probe of 3 numbers",
        one_sphere_with("probes", json!([[1, 2, 3]])),
        false,
        Malformed,
    )]);
}

#[test]
fn a_name_outside_its_closed_set_is_400() {
    check_shade(vec![
        (
            "an unknown precision",
            one_vertex_with(json!({ "precision": "exact" })),
            false,
            Malformed,
        ),
        (
            "an unknown terms detail",
            one_vertex_with(json!({ "terms": "all" })),
            false,
            Malformed,
        ),
    ]);
    check_render(vec![
        (
            "an unknown shading",
            one_sphere_with("shading", json!("flat")),
            false,
            Malformed,
        ),
        (
            "an unknown encoding",
            one_sphere_with("encoding", json!("gamma")),
            false,
            Malformed,
        ),
    ]);
}

#[test]
fn a_string_for_a_number_is_400() {
    check_shade(vec![(
        "a string for a shininess",
        one_vertex_with(json!({ "material": { "shininess": "10" } })),
        false,
        Malformed,
    )]);
    check_render(vec![(
        "a string for a back shininess",
        one_sphere_with("back_material", json!({ "shininess": "high" })),
        false,
        Malformed,
    )]);
}

#[test]
fn a_required_field_left_out_is_400() {
    check_shade(vec![
        ("no vertices", json!({}), false, Malformed),
        (
            "a view without a target",
            one_vertex_with(json!({ "view": { "eye": [0, 0, 1] } })),
            false,
            Malformed,
        ),
    ]);
    check_render(vec![
        (
            "a region without a height",
            one_sphere_with("region", json!({ "x": 0, "y": 0, "width": 1 })),
            false,
            Malformed,
        ),
        (
            "a sphere without a radius",
            one_sphere_with(
                "objects",
                json!([{ "sphere": { "center": [0, 0, 0] }, "material": "red" }]),
            ),
            false,
            Malformed,
        ),
        (
            "a camera without a field of view or a size",
            one_sphere_with(
                "camera",
                json!({ "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0] }),
            ),
            false,
            Malformed,
        ),
    ]);
}

/// Regression: `null` for a field that may be left out was read as if the
/// field were absent (a request the schema refuses was answered 200), though
/// no schema takes `null`. Now each such field refuses `null` as a wrong
/// type (400) at its own pointer, as its schema does.
#[test]
fn a_null_is_not_an_absent_field() {
    check_shade(vec![
        (
            "a null for a field left out",
            one_vertex_with(json!({ "terms": null })),
            false,
            Malformed,
        ),
        (
            "a null light model",
            one_vertex_with(json!({ "light_model": null })),
            false,
            Malformed,
        ),
    ]);

    let doc = document();
    let material = json!({ "ambient": [0.2, 0.2, 0.2], "diffuse": [0.8, 0.8, 0.8, 1],
                           "specular": [0, 0, 0], "emission": [0, 0, 0], "shininess": 1 });
    let light_model = json!({ "ambient": [0.2, 0.2, 0.2], "local_viewer": false,
                              "two_side": true, "color_control": "single",
                              "specular_model": "phong", "attenuation_clamp": false,
                              "normalize_normals": true });
    let lights = json!([{ "position": [0, 0, 1, 0], "ambient": [0, 0, 0], "diffuse": [1, 1, 1],
                          "specular": [1, 1, 1], "attenuation": [1, 0, 0],
                          "spot": { "direction": [0, 0, -1], "exponent": 0, "cutoff": 180 } }]);
    let shade = json!({
        "light_model": light_model, "material": material, "back_material": material,
        "lights": lights,
        "view": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0] },
        "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] },
        "precision": "accurate", "terms": "none",
    });
    let render = json!({
        "light_model": light_model, "materials": { "red": material }, "back_material": material,
        "lights": lights,
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 8, "height": 6 },
        "objects": [
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                        "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]], "indices": [0, 1, 2] },
              "material": "red" },
        ],
        "background": [0, 0, 0], "shading": "per_pixel", "samples": 1, "shadows": false,
        "precision": "accurate", "region": { "x": 0, "y": 0, "width": 8, "height": 6 },
        "probes": [[1, 1]], "encoding": "linear",
    });

    /// Every member of every object in `value`, by pointer.
    fn members(value: &Value, at: &str, out: &mut Vec<String>) {
        match value {
            Value::Object(map) => {
                for (k, v) in map {
                    let here = format!("{at}/{k}");
                    out.push(here.clone());
                    members(v, &here, out);
                }
            }
            Value::Array(items) => {
                for (i, v) in items.iter().enumerate() {
                    members(v, &format!("{at}/{i}"), out);
                }
            }
            _ => {}
        }
    }
    /// Whether the wire types read the body, or the kind and pointer of
    /// their refusal.
    fn read<T: serde::de::DeserializeOwned>(
        body: &Value,
    ) -> Result<(), (RequestErrorKind, String)> {
        scene::parse_json::<T>(&serde_json::to_vec(body).unwrap())
            .map(|_| ())
            .map_err(|e| (e.kind, e.pointer))
    }
    let mut nulled = 0;
    for (name, body, read) in [
        (
            "ShadeRequest",
            shade,
            read::<wire::ShadeRequest> as fn(&Value) -> _,
        ),
        ("RenderRequest", render, read::<wire::RenderRequest>),
    ] {
        let schema = validator_in(&doc, name);
        assert_valid(&schema, name, &body);
        assert_eq!(read(&body), Ok(()), "{body}");
        let mut pointers = Vec::new();
        members(&body, "", &mut pointers);
        for pointer in pointers {
            let (parent, key) = pointer.rsplit_once('/').unwrap();
            let mut without = body.clone();
            without
                .pointer_mut(parent)
                .and_then(Value::as_object_mut)
                .unwrap()
                .remove(key);
            if read(&without).is_err() {
                continue; // a required field
            }
            let mut null = body.clone();
            *null.pointer_mut(&pointer).unwrap() = Value::Null;
            assert!(
                !schema.is_valid(&null),
                "{name}: the schema takes null at {pointer}"
            );
            assert_eq!(
                read(&null),
                Err((RequestErrorKind::Malformed, pointer.clone())),
                "{name}: null at {pointer}"
            );
            nulled += 1;
        }
    }
    assert!(nulled > 50, "only {nulled} optional fields");
}

/// A render whose integers are all written with a zero fraction, its width
/// `width`.
fn integers_with_fractions(width: Value) -> Value {
    json!({
        "materials": { "red": {} },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": width, "height": 6.0 },
        "objects": [{ "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                                "indices": [0.0, 1.0, 2.0] },
                      "material": "red" }],
        "samples": 4.0,
        "region": { "x": 1.0, "y": 0.0, "width": 2.0, "height": 3.0 },
        "probes": [[7.0, 5.0]],
    })
}

/// Regression: an integer written with a zero fraction (`64.0`), which
/// JSON Schema, and so the contract, counts as the integer 64, was refused
/// as malformed (400) by the render parser. Every integer of a request now
/// takes it.
#[test]
fn an_integer_written_with_a_zero_fraction_is_an_integer() {
    let whole = integers_with_fractions(json!(8.0));
    assert!(whole.to_string().contains("\"width\":8.0"), "{whole}");
    assert_valid(&validator("RenderRequest"), "RenderRequest", &whole);
    let scene = scene::parse_render(&serde_json::to_vec(&whole).unwrap(), &Limits::default())
        .unwrap_or_else(|e| panic!("{whole}: {e}"));
    assert_eq!((scene.camera.width, scene.camera.height), (8, 6));
    assert_eq!(scene.samples, glint_trace::Samples::Uniform(4));
    assert_eq!(
        scene.region,
        glint_trace::Region {
            x: 1,
            y: 0,
            width: 2,
            height: 3
        }
    );
    assert_eq!(scene.probes, [[7, 5]]);
    assert_eq!(scene.triangles(), 1);
}

/// A count, a size or a pixel is a whole number from 0 to u32's greatest:
/// a fraction, a negative number or one past u32 stays malformed.
#[test]
fn an_integer_is_whole_not_negative_and_within_u32() {
    let render = validator("RenderRequest");
    for width in [json!(8.5), json!(-8.0), json!(4294967296.0), json!(1e300)] {
        let wrong = integers_with_fractions(width.clone());
        assert!(
            !render.is_valid(&wrong),
            "the schema takes a width of {width}"
        );
        assert_eq!(
            render_outcome(&wrong, &Limits::default()).map_err(|e| (e.kind, e.pointer)),
            Err((RequestErrorKind::Malformed, "/camera/width".to_owned())),
            "a width of {width}"
        );
    }
    check_render(vec![
        (
            "a negative pixel",
            one_sphere_with("probes", json!([[-1, 2]])),
            false,
            Malformed,
        ),
        (
            "a negative count of samples",
            one_sphere_with("samples", json!(-1)),
            false,
            Malformed,
        ),
    ]);
}

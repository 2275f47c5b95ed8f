//! The rules of colours and materials: every colour within ±1e6 (the
//! code's `MAX_COLOR`), a shininess that is not negative and may pass GL's
//! 128, the materials a render's objects name, and pointers into materials
//! whose names need escaping (RFC 6901).

use serde_json::json;

use super::support::{
    Verdict::{Accepted, Invalid},
    assert_written, check_render, check_shade, nothing_8x6, one_sphere_with, one_vertex_with,
    only_object,
};

#[test]
fn a_colour_is_within_1e6() {
    check_shade(vec![
        (
            "a colour of 1e6",
            one_vertex_with(json!({ "light_model": { "ambient": [1e6, -1e6, 0] } })),
            true,
            Accepted,
        ),
        (
            "a colour over 1e6",
            one_vertex_with(json!({ "light_model": { "ambient": [2e6, 0, 0] } })),
            false,
            Invalid("/light_model/ambient/0"),
        ),
        (
            "a back material colour over 1e6",
            one_vertex_with(json!({ "back_material": { "emission": [0, 0, -2e6] } })),
            false,
            Invalid("/back_material/emission/2"),
        ),
    ]);
    check_render(vec![
        (
            "a material colour over 1e6",
            one_sphere_with("materials", json!({ "red": { "diffuse": [2e6, 0, 0] } })),
            false,
            Invalid("/materials/red/diffuse/0"),
        ),
        (
            "a background over 1e6",
            one_sphere_with("background", json!([0, 0, 2e6])),
            false,
            Invalid("/background/2"),
        ),
        (
            "a background over 1, clamped",
            one_sphere_with("background", json!([2, 0, 0])),
            true,
            Accepted,
        ),
    ]);
}

/// GL caps the specular exponent at 128; the contract takes any exponent
/// that is not negative.
#[test]
fn a_shininess_is_not_negative_and_may_pass_gl_s_128() {
    check_shade(vec![
        (
            "a negative shininess",
            one_vertex_with(json!({ "material": { "shininess": -1 } })),
            false,
            Invalid("/material/shininess"),
        ),
        (
            "a shininess above GL's 128",
            one_vertex_with(json!({ "material": { "shininess": 1000 } })),
            true,
            Accepted,
        ),
    ]);
}

#[test]
fn an_object_s_material_is_one_the_request_names() {
    assert_written(
        "/components/schemas/SceneObject/properties/material/description",
        "/objects/{i}/material",
    );
    let blue = json!({ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "blue" });
    check_render(vec![
        (
            "an unknown material",
            only_object(blue.clone()),
            true,
            Invalid("/objects/0/material"),
        ),
        (
            "an unknown material in an empty scene",
            nothing_8x6(&|b| b["objects"] = json!([blue.clone()])),
            true,
            Invalid("/objects/0/material"),
        ),
    ]);
}

#[test]
fn a_material_name_is_escaped_in_pointers() {
    let mut body = one_sphere_with("materials", json!({ "a/b": { "shininess": -1 } }));
    body["objects"][0]["material"] = json!("a/b");
    check_render(vec![(
        "a material name to escape",
        body,
        false,
        Invalid("/materials/a~1b/shininess"),
    )]);
}

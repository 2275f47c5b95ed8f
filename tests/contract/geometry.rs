//! The rules of geometry: coordinates within ±1e30 (the code's
//! `MAX_COORDINATE`), a normal for each position, long normals refused only
//! where they are used as given (`normalize_normals: false`, bounded by
//! `MAX_RAW_NORMAL`), a render's objects each of one shape, spheres,
//! planes and meshes well made, and the vertices of all meshes counted
//! against the server's vertex limit.

use glint::scene::Limits;
use serde_json::{Value, json};

use super::support::{
    Verdict::{Accepted, Invalid},
    assert_written, check_render, check_render_past, check_shade, nothing_8x6, one_sphere_camera,
    one_sphere_with, one_vertex_with, only_mesh, only_object, triangle,
};

/// A render of nothing but `object`, 8×6 pixels.
fn nothing_but(object: Value) -> Value {
    nothing_8x6(&|b| b["objects"] = json!([object.clone()]))
}

/// [`nothing_but`] a red mesh.
fn nothing_but_mesh(mesh: Value) -> Value {
    nothing_but(json!({ "mesh": mesh, "material": "red" }))
}

#[test]
fn a_coordinate_is_within_1e30() {
    check_shade(vec![
        (
            "a coordinate over 1e30",
            json!({ "vertices": { "positions": [[2e30, 0, 0]], "normals": [[0, 0, 1]] } }),
            false,
            Invalid("/vertices/positions/0"),
        ),
        (
            "an eye over 1e30",
            one_vertex_with(json!({ "view": { "eye": [0, 0, 2e30], "target": [0, 0, 0] } })),
            false,
            Invalid("/view/eye"),
        ),
    ]);
    check_render(vec![(
        "an eye over 1e30",
        one_sphere_camera("eye", json!([0, 0, 2e30])),
        false,
        Invalid("/camera/eye"),
    )]);
}

#[test]
fn a_sphere_s_radius_is_positive_and_within_1e30() {
    let radius = |r: Value| {
        only_object(json!({ "sphere": { "center": [0, 0, 0], "radius": r }, "material": "red" }))
    };
    check_render(vec![
        (
            "a radius of 0",
            radius(json!(0)),
            false,
            Invalid("/objects/0/sphere/radius"),
        ),
        (
            "a radius over 1e30",
            radius(json!(2e30)),
            false,
            Invalid("/objects/0/sphere/radius"),
        ),
    ]);
}

#[test]
fn a_normal_is_given_for_each_position() {
    assert_written(
        "/components/schemas/Vertices/description",
        "/vertices/normals",
    );
    assert_written(
        "/components/schemas/Mesh/properties/normals/description",
        "/objects/{i}/mesh/normals",
    );
    check_shade(vec![
        (
            "fewer normals than positions",
            json!({ "vertices": { "positions": [[0, 0, 0], [1, 0, 0]], "normals": [[0, 0, 1]] } }),
            true,
            Invalid("/vertices/normals"),
        ),
        (
            "no normal for one position",
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } }),
            true,
            Invalid("/vertices/normals"),
        ),
    ]);
    check_render(vec![
        (
            "fewer mesh normals than positions",
            only_mesh(json!({ "positions": triangle(), "indices": [0, 1, 2],
                              "normals": [[0, 0, 1]] })),
            true,
            Invalid("/objects/0/mesh/normals"),
        ),
        (
            "no mesh normals",
            nothing_but_mesh(json!({ "positions": triangle(), "indices": [0, 1, 2],
                                     "normals": [] })),
            true,
            Invalid("/objects/0/mesh/normals"),
        ),
    ]);
}

/// A normal is normalised by default, whatever its length; used as given
/// (`normalize_normals: false`) it must stay within `MAX_RAW_NORMAL`, so
/// that its products stay finite.
#[test]
fn a_long_normal_is_refused_only_when_used_as_given() {
    assert_written(
        "/components/schemas/Vertices/properties/normals/description",
        "/vertices/normals/{k}",
    );
    assert_written(
        "/components/schemas/Mesh/properties/normals/description",
        "/objects/{i}/mesh/normals/{k}",
    );
    check_shade(vec![
        (
            "a long normal, normalised",
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1e300]] } }),
            true,
            Accepted,
        ),
        (
            "a long normal used as given",
            json!({ "light_model": { "normalize_normals": false },
                    "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 2e6]] } }),
            true,
            Invalid("/vertices/normals/0"),
        ),
        (
            "a long normal along -y used as given",
            json!({ "light_model": { "normalize_normals": false },
                    "vertices": { "positions": [[0, 0, 0]], "normals": [[0, -2e6, 0]] } }),
            true,
            Invalid("/vertices/normals/0"),
        ),
    ]);
    let raw = |normalize: bool, normals: Value, scene: fn(Value) -> Value| {
        let mut body =
            scene(json!({ "positions": triangle(), "indices": [0, 1, 2], "normals": normals }));
        body["light_model"] = json!({ "normalize_normals": normalize });
        body
    };
    let first_long = json!([[0, 0, 2e6], [0, 0, 1], [0, 0, 1]]);
    let last_long = json!([[0, 0, 1], [0, 0, 1], [0, 0, 2e6]]);
    check_render(vec![
        (
            "a long mesh normal, normalised",
            raw(true, first_long.clone(), only_mesh),
            true,
            Accepted,
        ),
        (
            "a long mesh normal used as given",
            raw(false, first_long, only_mesh),
            true,
            Invalid("/objects/0/mesh/normals/0"),
        ),
        (
            "the last mesh normal long, used as given",
            raw(false, last_long, nothing_but_mesh),
            true,
            Invalid("/objects/0/mesh/normals/2"),
        ),
    ]);
}

/// A zero normal lights nothing but emission and ambient; it is not an
/// error.
#[test]
fn a_zero_normal_is_accepted() {
    check_shade(vec![(
        "a zero normal",
        json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 0]] } }),
        true,
        Accepted,
    )]);
}

#[test]
fn an_object_has_exactly_one_shape() {
    assert_written(
        "/components/schemas/SceneObject/description",
        "/objects/{i}",
    );
    check_render(vec![
        (
            "no shape",
            only_object(json!({ "material": "red" })),
            true,
            Invalid("/objects/0"),
        ),
        (
            "no shape in an empty scene",
            nothing_but(json!({ "material": "red" })),
            true,
            Invalid("/objects/0"),
        ),
        (
            "two shapes",
            only_object(json!({ "sphere": { "center": [0, 0, 0], "radius": 1 },
                                "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] },
                                "material": "red" })),
            true,
            Invalid("/objects/0"),
        ),
    ]);
}

#[test]
fn a_plane_has_a_normal() {
    assert_written(
        "/components/schemas/Plane/properties/normal/description",
        "/objects/{i}/plane/normal",
    );
    let flat = json!({ "plane": { "point": [0, 0, 0], "normal": [0, 0, 0] }, "material": "red" });
    check_render(vec![
        (
            "a plane without a normal",
            only_object(flat.clone()),
            true,
            Invalid("/objects/0/plane/normal"),
        ),
        (
            "a plane without a normal in an empty scene",
            nothing_but(flat),
            true,
            Invalid("/objects/0/plane/normal"),
        ),
    ]);
}

#[test]
fn mesh_indices_come_in_threes() {
    assert_written(
        "/components/schemas/Mesh/properties/indices/description",
        "/objects/{i}/mesh/indices",
    );
    let two = json!({ "positions": triangle(), "indices": [0, 1] });
    check_render(vec![
        (
            "indices not in threes",
            only_mesh(two.clone()),
            true,
            Invalid("/objects/0/mesh/indices"),
        ),
        (
            "indices not in threes in an empty scene",
            nothing_but_mesh(two),
            true,
            Invalid("/objects/0/mesh/indices"),
        ),
    ]);
}

#[test]
fn a_mesh_index_names_one_of_its_positions() {
    assert_written(
        "/components/schemas/Mesh/properties/indices/description",
        "/objects/{i}/mesh/indices/{k}",
    );
    let past = json!({ "positions": triangle(), "indices": [0, 1, 3] });
    check_render(vec![
        (
            "an index out of range",
            only_mesh(past.clone()),
            true,
            Invalid("/objects/0/mesh/indices/2"),
        ),
        (
            "an index out of range in an empty scene",
            nothing_but_mesh(past),
            true,
            Invalid("/objects/0/mesh/indices/2"),
        ),
    ]);
}

/// The mesh vertices of all objects together count against the vertex
/// limit, at the mesh that passes it.
#[test]
fn the_vertices_of_all_meshes_count_against_the_vertex_limit() {
    let five = |limits: &mut Limits| limits.max_vertices = 5;
    let two_meshes = one_sphere_with(
        "objects",
        json!([
            { "mesh": { "positions": triangle(), "indices": [0, 1, 2] }, "material": "red" },
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "mesh": { "positions": triangle(), "indices": [0, 1, 2] }, "material": "red" },
        ]),
    );
    let name = "two triangles past a limit of 5 vertices";
    check_render_past(five, name, two_meshes, "/objects/2/mesh/positions");
}

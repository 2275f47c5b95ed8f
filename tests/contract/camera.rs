//! Where a scene is seen from and what picture is made: a shade's view and
//! a render's camera (an eye apart from its target, an up vector off the
//! view, a field of view inside (0, 180)), the image's size and the
//! server's pixel limit, the region, the probes and the samples per pixel,
//! the contract's own bounds 422 and a server's lower limits 413.

use glint::scene::{Limits, MAX_PROBES};
use serde_json::json;

use super::support::{
    Verdict::{Accepted, Invalid, OverLimit},
    assert_written, check_render, check_render_past, check_shade, nothing_8x6, one_sphere_camera,
    one_sphere_with, one_vertex_with,
};

/// The view direction is `target - eye`: the same point gives none.
#[test]
fn the_eye_is_not_the_target() {
    assert_written(
        "/components/schemas/View/properties/target/description",
        "/view/target",
    );
    assert_written(
        "/components/schemas/Camera/properties/target/description",
        "/camera/target",
    );
    check_shade(vec![
        (
            "the eye at the target",
            one_vertex_with(json!({ "view": { "eye": [1, 2, 3], "target": [1, 2, 3] } })),
            true,
            Invalid("/view/target"),
        ),
        (
            "the eye at the target (0, 0, 1)",
            one_vertex_with(json!({ "view": { "eye": [0, 0, 1], "target": [0, 0, 1] } })),
            true,
            Invalid("/view/target"),
        ),
    ]);
    check_render(vec![
        (
            "the eye at the target",
            one_sphere_camera("target", json!([0, 0, 5])),
            true,
            Invalid("/camera/target"),
        ),
        (
            "the eye at the target of an empty scene",
            nothing_8x6(&|b| b["camera"]["target"] = json!([0, 0, 5])),
            true,
            Invalid("/camera/target"),
        ),
    ]);
}

/// The image's vertical is the up vector made orthogonal to the view: a
/// zero vector, or one along the view, gives none.
#[test]
fn the_up_vector_is_neither_zero_nor_along_the_view() {
    assert_written(
        "/components/schemas/Camera/properties/up/description",
        "/camera/up",
    );
    let up = |v: [i32; 3]| nothing_8x6(&|b| b["camera"]["up"] = json!(v));
    check_render(vec![
        (
            "a zero up",
            one_sphere_camera("up", json!([0, 0, 0])),
            true,
            Invalid("/camera/up"),
        ),
        (
            "an up along the view direction",
            one_sphere_camera("up", json!([0, 0, -2])),
            true,
            Invalid("/camera/up"),
        ),
        (
            "a zero up in an empty scene",
            up([0, 0, 0]),
            true,
            Invalid("/camera/up"),
        ),
        (
            "an up along the view, backwards",
            up([0, 0, 3]),
            true,
            Invalid("/camera/up"),
        ),
    ]);
}

#[test]
fn a_field_of_view_lies_strictly_between_0_and_180() {
    let fov_y = |degrees: i32| one_sphere_camera("fov_y", json!(degrees));
    let at = "/camera/fov_y";
    check_render(vec![
        ("a fov_y of 0", fov_y(0), false, Invalid(at)),
        ("a fov_y of 180", fov_y(180), false, Invalid(at)),
        ("a fov_y of 179", fov_y(179), true, Accepted),
    ]);
}

#[test]
fn an_image_is_at_least_one_pixel_wide_and_high() {
    check_render(vec![
        (
            "a width of 0",
            one_sphere_camera("width", json!(0)),
            false,
            Invalid("/camera/width"),
        ),
        (
            "a height of 0",
            one_sphere_camera("height", json!(0)),
            false,
            Invalid("/camera/height"),
        ),
    ]);
}

/// The pixel count is a limit of the server (`--max-pixels`), 413 past it.
#[test]
fn pixels_past_the_server_s_limit_are_413_at_camera() {
    let size = |width: u32, height: u32| {
        let mut body = one_sphere_camera("width", json!(width));
        body["camera"]["height"] = json!(height);
        body
    };
    check_render(vec![
        ("3840×2160 pixels", size(3840, 2160), true, Accepted),
        (
            "more pixels than the limit",
            size(4000, 4000),
            true,
            OverLimit("/camera"),
        ),
    ]);
}

#[test]
fn a_region_lies_inside_the_image() {
    assert_written("/components/schemas/Region/description", "/region");
    check_render(vec![
        (
            "a region inside the image",
            one_sphere_with(
                "region",
                json!({ "x": 60, "y": 40, "width": 4, "height": 8 }),
            ),
            true,
            Accepted,
        ),
        (
            "a region past the image",
            one_sphere_with(
                "region",
                json!({ "x": 60, "y": 40, "width": 5, "height": 8 }),
            ),
            true,
            Invalid("/region"),
        ),
        (
            "a region past an image 8 wide",
            nothing_8x6(&|b| b["region"] = json!({ "x": 4, "y": 0, "width": 5, "height": 1 })),
            true,
            Invalid("/region"),
        ),
    ]);
}

#[test]
fn a_region_of_width_0_is_422_at_its_width() {
    check_render(vec![(
        "a region of width 0",
        one_sphere_with("region", json!({ "x": 0, "y": 0, "width": 0, "height": 8 })),
        false,
        Invalid("/region/width"),
    )]);
}

/// A probe is a pixel of the image, inside the region or not.
#[test]
fn a_probe_lies_inside_the_image() {
    assert_written(
        "/components/schemas/RenderRequest/properties/probes/description",
        "/probes/{k}",
    );
    let mut outside_the_region = one_sphere_with("probes", json!([[63, 47]]));
    outside_the_region["region"] = json!({ "x": 0, "y": 0, "width": 8, "height": 8 });
    check_render(vec![
        (
            "a probe in the image, out of the region",
            outside_the_region,
            true,
            Accepted,
        ),
        (
            "a probe outside the image",
            one_sphere_with("probes", json!([[0, 0], [64, 0]])),
            true,
            Invalid("/probes/1"),
        ),
        (
            "a probe below an image 6 high",
            nothing_8x6(&|b| b["probes"] = json!([[0, 0], [0, 6]])),
            true,
            Invalid("/probes/1"),
        ),
    ]);
}

/// The contract's bound of probes (`MAX_PROBES`): past it is 422.
#[test]
fn probes_past_4096_are_422_at_probes() {
    let probes = |n: usize| one_sphere_with("probes", json!(vec![json!([0, 0]); n]));
    check_render(vec![
        ("4096 probes", probes(MAX_PROBES), true, Accepted),
        (
            "4097 probes, past the contract's bound",
            probes(MAX_PROBES + 1),
            false,
            Invalid("/probes"),
        ),
    ]);
}

/// The contract takes 1 to 64 samples per pixel: a value outside the
/// contract's own range is 422, not 413.
#[test]
fn samples_outside_1_to_64_are_422_at_samples() {
    let samples = |n: i32| one_sphere_with("samples", json!(n));
    check_render(vec![
        ("1 sample", samples(1), true, Accepted),
        ("64 samples", samples(64), true, Accepted),
        ("0 samples", samples(0), false, Invalid("/samples")),
        (
            "65 samples, past the contract's bound",
            samples(65),
            false,
            Invalid("/samples"),
        ),
    ]);
}

/// A server's own limit below the contract's bound is 413: a value the
/// schema takes, past this server's setting.
#[test]
fn samples_past_a_server_s_limit_are_413_at_samples() {
    let seventeen = one_sphere_with("samples", json!(17));
    let sixteen = |limits: &mut Limits| limits.max_samples = 16;
    let name = "17 samples, past a limit of 16";
    check_render_past(sixteen, name, seventeen, "/samples");
}

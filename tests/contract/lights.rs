//! The rules of lights (OpenGL 2.1, section 2.14.1, and the contract's
//! descriptions): where a light is, its attenuation, its spot cone, and how
//! many lights a request may have. Each test holds bodies against the
//! schema and the code, and a rule the schema leaves to a description
//! against that description too.

use glint::scene::Limits;
use serde_json::{Value, json};

use super::support::{
    Verdict::{Accepted, Invalid},
    assert_written, check_render, check_render_past, check_shade, one_sphere_with,
    one_vertex_lit_by, one_vertex_with,
};

/// `w = 0` is a direction towards the light: the zero vector is none.
#[test]
fn a_directional_light_needs_a_direction() {
    assert_written(
        "/components/schemas/LightPosition/description",
        "/lights/{i}/position",
    );
    check_shade(vec![
        (
            "a positional light at the origin",
            one_vertex_lit_by(json!({ "position": [0, 0, 0, 1] })),
            true,
            Accepted,
        ),
        (
            "a directional light without a direction",
            one_vertex_lit_by(json!({ "position": [0, 0, 0, 0] })),
            true,
            Invalid("/lights/0/position"),
        ),
    ]);
}

/// A positional light is at (x, y, z) / w, which must stay within the
/// bound of coordinates.
#[test]
fn a_light_far_away_after_division_by_w_is_422() {
    assert_written(
        "/components/schemas/LightPosition/description",
        "/lights/{i}/position",
    );
    check_shade(vec![(
        "a light position far away after division by w",
        one_vertex_lit_by(json!({ "position": [1e30, 0, 0, 1e-10] })),
        true,
        Invalid("/lights/0/position"),
    )]);
}

/// The attenuation factor 1 / (k0 + k1·d + k2·d²) needs some k non-zero,
/// whether or not the light is positional.
#[test]
fn all_zero_attenuation_is_422() {
    assert_written(
        "/components/schemas/Light/properties/attenuation/description",
        "/lights/{i}/attenuation",
    );
    check_shade(vec![
        (
            "all-zero attenuation",
            one_vertex_lit_by(json!({ "position": [0, 0, 1, 1], "attenuation": [0, 0, 0] })),
            true,
            Invalid("/lights/0/attenuation"),
        ),
        (
            "all-zero attenuation of a directional light",
            one_vertex_lit_by(json!({ "attenuation": [0, 0, 0] })),
            true,
            Invalid("/lights/0/attenuation"),
        ),
    ]);
}

#[test]
fn a_negative_attenuation_is_422() {
    check_shade(vec![(
        "a negative attenuation",
        one_vertex_lit_by(json!({ "attenuation": [1, -0.5, 0] })),
        false,
        Invalid("/lights/0/attenuation/1"),
    )]);
}

/// GL takes a cutoff of 180 (no cone) or one in [0, 90]; the range is in
/// the schema, the gap between 90 and 180 in its description.
#[test]
fn a_spot_cutoff_is_180_or_within_0_to_90() {
    assert_written(
        "/components/schemas/Spot/properties/cutoff/description",
        "/lights/{i}/spot/cutoff",
    );
    let cutoff = |degrees: Value| one_vertex_lit_by(json!({ "spot": { "cutoff": degrees } }));
    let at = "/lights/0/spot/cutoff";
    check_shade(vec![
        ("a cutoff of 180", cutoff(json!(180)), true, Accepted),
        ("a cutoff of 90", cutoff(json!(90)), true, Accepted),
        ("a cutoff of 0", cutoff(json!(0)), true, Accepted),
        ("a cutoff of 181", cutoff(json!(181)), false, Invalid(at)),
        ("a cutoff of -1", cutoff(json!(-1)), false, Invalid(at)),
        ("a cutoff of 120", cutoff(json!(120)), true, Invalid(at)),
        ("a cutoff of 90.5", cutoff(json!(90.5)), true, Invalid(at)),
    ]);
    check_render(vec![(
        "a cutoff of 120",
        one_sphere_with("lights", json!([{ "spot": { "cutoff": 120 } }])),
        true,
        Invalid(at),
    )]);
}

#[test]
fn a_negative_spot_exponent_is_422() {
    check_shade(vec![(
        "a negative exponent",
        one_vertex_lit_by(json!({ "spot": { "exponent": -1 } })),
        false,
        Invalid("/lights/0/spot/exponent"),
    )]);
}

/// A cone needs an axis; a light that is no spotlight (cutoff 180) never
/// uses its direction.
#[test]
fn a_zero_spot_direction_is_refused_only_with_a_cone() {
    assert_written(
        "/components/schemas/Spot/properties/direction/description",
        "/lights/{i}/spot/direction",
    );
    check_shade(vec![
        (
            "a zero spot direction without a cone",
            one_vertex_lit_by(json!({ "spot": { "direction": [0, 0, 0] } })),
            true,
            Accepted,
        ),
        (
            "a zero spot direction with a cone of 45",
            one_vertex_lit_by(json!({ "spot": { "direction": [0, 0, 0], "cutoff": 45 } })),
            true,
            Invalid("/lights/0/spot/direction"),
        ),
        (
            "a zero spot direction with a cone of 30",
            one_vertex_lit_by(json!({ "spot": { "direction": [0, 0, 0], "cutoff": 30 } })),
            true,
            Invalid("/lights/0/spot/direction"),
        ),
    ]);
}

/// The contract's bound is 64 lights (`Lights.maxItems`, the code's
/// `MAX_LIGHTS`): a value outside the contract's own range is 422, not 413.
#[test]
fn sixty_five_lights_are_422_at_lights() {
    let lights = |n: usize| one_vertex_with(json!({ "lights": vec![json!({}); n] }));
    check_shade(vec![
        ("64 lights", lights(64), true, Accepted),
        (
            "65 lights, past the contract's bound",
            lights(65),
            false,
            Invalid("/lights"),
        ),
    ]);
}

/// A server's own limit below the contract's bound is 413: a value the
/// schema takes, past this server's setting.
#[test]
fn lights_past_a_server_s_limit_are_413_at_lights() {
    let three = one_sphere_with("lights", json!([{}, {}, {}]));
    let two = |limits: &mut Limits| limits.max_lights = 2;
    check_render_past(two, "3 lights, past a limit of 2", three, "/lights");
}

//! The defaults and bounds the document writes are the code's: GL's
//! initial values (OpenGL 2.1, section 2.14.1, as `glint_lighting` holds
//! them) for the light model, the material and GL_LIGHT0, the
//! precision tiers' bounds, the numeric bounds of colours, coordinates and
//! normals, the counts of lists, and the render defaults a request that
//! gives none gets.

use glint::scene::{self, Limits, MAX_PROBES, TermsDetail, wire};
use glint_lighting::{self as lighting, LightPosition, Precision};
use glint_trace::MAX_SAMPLES;
use serde_json::{Value, json};

use super::support::schema;

/// The default the document writes for the property `field` of `schema`.
fn default(schema_name: &str, field: &str) -> Value {
    schema(schema_name)["properties"][field]["default"].clone()
}

/// A colour as the document writes it: four numbers.
fn rgba(c: glam::DVec4) -> Value {
    json!(c.to_array())
}

#[test]
fn the_light_model_defaults_are_gl_s() {
    let m = lighting::LightModel::default();
    assert_eq!(default("LightModel", "ambient"), rgba(m.ambient));
    assert_eq!(default("LightModel", "local_viewer"), json!(m.local_viewer));
    assert_eq!(default("LightModel", "two_side"), json!(m.two_side));
    assert_eq!(
        default("LightModel", "attenuation_clamp"),
        json!(m.attenuation_clamp)
    );
    assert_eq!(
        default("LightModel", "normalize_normals"),
        json!(m.normalize_normals)
    );
    let control = match m.color_control {
        lighting::ColorControl::Single => "single",
        lighting::ColorControl::SeparateSpecular => "separate_specular",
    };
    assert_eq!(default("LightModel", "color_control"), json!(control));
    let specular = match m.specular_model {
        lighting::SpecularModel::BlinnPhong => "blinn_phong",
        lighting::SpecularModel::Phong => "phong",
    };
    assert_eq!(default("LightModel", "specular_model"), json!(specular));
}

#[test]
fn the_material_defaults_are_gl_s() {
    let mat = lighting::Material::default();
    assert_eq!(default("Material", "ambient"), rgba(mat.ambient));
    assert_eq!(default("Material", "diffuse"), rgba(mat.diffuse));
    assert_eq!(default("Material", "specular"), rgba(mat.specular));
    assert_eq!(default("Material", "emission"), rgba(mat.emission));
    assert_eq!(default("Material", "shininess"), json!(mat.shininess));
}

#[test]
fn the_light_defaults_are_gl_light0_s() {
    let light = lighting::Light::default();
    let LightPosition::Directional(towards) = light.position else {
        panic!("GL_LIGHT0 is directional");
    };
    assert_eq!(default("Light", "position"), rgba(towards.extend(0.0)));
    assert_eq!(default("Light", "ambient"), rgba(light.ambient));
    assert_eq!(default("Light", "diffuse"), rgba(light.diffuse));
    assert_eq!(default("Light", "specular"), rgba(light.specular));
    assert_eq!(default("Light", "attenuation"), json!(light.attenuation));
    assert_eq!(
        default("Spot", "direction"),
        json!(light.spot.direction.to_array())
    );
    assert_eq!(default("Spot", "exponent"), json!(light.spot.exponent));
    assert_eq!(default("Spot", "cutoff"), json!(light.spot.cutoff));
}

#[test]
fn the_precision_and_terms_defaults_are_the_code_s() {
    assert_eq!(
        schema("Precision")["default"],
        json!(wire::Precision::from(Precision::default()))
    );
    assert_eq!(
        schema("TermsDetail")["default"],
        json!(TermsDetail::default())
    );
}

/// The three bounds, each written in the description (a number enum is
/// beyond client generators), and the least and the greatest as the
/// schema's range. Real responses carry their mode's bound exactly
/// (`responses::a_shade_answer_states_its_mode_and_bound`).
#[test]
fn the_precision_bounds_are_written_and_are_the_schema_s_range() {
    let bounds: Vec<f64> = [Precision::Reference, Precision::Accurate, Precision::Fast]
        .map(Precision::max_abs_error)
        .to_vec();
    let max_abs_error = &schema("PrecisionInfo")["properties"]["max_abs_error"];
    let written: Vec<f64> = max_abs_error["description"]
        .as_str()
        .unwrap()
        .split(|c: char| c.is_whitespace() || "(),;".contains(c))
        .filter_map(|word| word.parse().ok())
        .collect();
    for bound in &bounds {
        assert!(
            written.contains(bound),
            "the bound {bound} is not written in {written:?}"
        );
    }
    assert_eq!(max_abs_error["minimum"].as_f64(), Some(bounds[0]));
    assert_eq!(max_abs_error["maximum"].as_f64(), Some(bounds[2]));
}

#[test]
fn a_colour_is_bounded_by_max_color() {
    let item = &schema("Color")["items"];
    assert_eq!(item["maximum"].as_f64(), Some(lighting::MAX_COLOR));
    assert_eq!(item["minimum"].as_f64(), Some(-lighting::MAX_COLOR));
}

#[test]
fn a_coordinate_is_bounded_by_max_coordinate() {
    let item = &schema("Point3")["items"];
    assert_eq!(item["maximum"].as_f64(), Some(lighting::MAX_COORDINATE));
    assert_eq!(item["minimum"].as_f64(), Some(-lighting::MAX_COORDINATE));
    assert_eq!(
        schema("Sphere")["properties"]["radius"]["maximum"].as_f64(),
        Some(lighting::MAX_COORDINATE)
    );
}

/// The bound of normals used as given depends on the light model: it is
/// written where the normals and the switch are described (and the code
/// enforces it: `geometry::a_long_normal_is_refused_only_when_used_as_given`).
#[test]
fn the_bound_of_raw_normals_is_written_beside_the_normals() {
    let raw_bound = format!("±{:e}", lighting::MAX_RAW_NORMAL);
    for (schema_name, field) in [
        ("Vertices", "normals"),
        ("Mesh", "normals"),
        ("LightModel", "normalize_normals"),
    ] {
        let description = schema(schema_name)["properties"][field]["description"]
            .as_str()
            .unwrap()
            .to_owned();
        assert!(
            description.contains(&raw_bound),
            "{schema_name}.{field} does not write {raw_bound}: {description}"
        );
    }
}

#[test]
fn the_bound_of_lights_is_max_lights() {
    assert_eq!(
        schema("Lights")["maxItems"].as_u64(),
        Some(lighting::MAX_LIGHTS as u64)
    );
}

/// The contract's bound of samples is the renderer's, and the server's
/// default limit is that bound.
#[test]
fn the_bound_of_samples_is_max_samples() {
    let samples = &schema("RenderRequest")["properties"]["samples"];
    assert_eq!(
        samples["maximum"].as_u64(),
        Some(u64::from(Limits::default().max_samples))
    );
    assert_eq!(samples["maximum"].as_u64(), Some(u64::from(MAX_SAMPLES)));
}

#[test]
fn the_bound_of_probes_is_max_probes() {
    assert_eq!(
        schema("RenderRequest")["properties"]["probes"]["maxItems"].as_u64(),
        Some(MAX_PROBES as u64)
    );
}

#[test]
fn the_bound_of_objects_is_max_objects() {
    assert_eq!(
        schema("RenderRequest")["properties"]["objects"]["maxItems"].as_u64(),
        Some(wire::MAX_OBJECTS as u64)
    );
}

#[test]
fn the_bound_of_materials_is_max_materials() {
    assert_eq!(
        schema("RenderRequest")["properties"]["materials"]["maxProperties"].as_u64(),
        Some(wire::MAX_MATERIALS as u64)
    );
}

/// The render defaults: those of a request that gives none.
#[test]
fn the_render_defaults_are_those_of_a_request_that_gives_none() {
    let render = schema("RenderRequest");
    let minimal = json!({
        "materials": { "red": {} },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 4, "height": 3 },
        "objects": [],
    });
    let r = scene::parse_render(&serde_json::to_vec(&minimal).unwrap(), &Limits::default())
        .expect("a minimal render");
    let property = |field: &str| render["properties"][field]["default"].clone();
    assert_eq!(property("samples"), json!(r.samples.max()));
    assert_eq!(property("shadows"), json!(r.shadows));
    assert_eq!(property("background"), rgba(r.background));
    assert_eq!(property("probes"), json!(r.probes));
    assert_eq!(
        schema("Precision")["default"],
        json!(wire::Precision::from(r.precision))
    );
    let shading = match r.shading {
        glint_trace::ShadingMode::PerPixel => "per_pixel",
        glint_trace::ShadingMode::PerVertex => "per_vertex",
    };
    assert_eq!(schema("ShadingMode")["default"], json!(shading));
    let encoding = match r.encoding {
        glint_trace::Encoding::Linear => "linear",
        glint_trace::Encoding::Srgb => "srgb",
    };
    assert_eq!(schema("Encoding")["default"], json!(encoding));
    assert_eq!(
        r.region,
        glint_trace::Region {
            x: 0,
            y: 0,
            width: 4,
            height: 3
        },
        "no region is the whole image"
    );
}

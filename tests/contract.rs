//! `api/openapi.yaml`, the written contract, checked against itself and
//! against the code:
//!
//! - it is OpenAPI 3.1, every `$ref` resolves inside it, and every request
//!   and response body is a named schema under `components/schemas`;
//! - every named schema compiles as JSON Schema 2020-12 and its `examples`
//!   validate;
//! - the schemas accept and refuse what the parser and the validation of
//!   `glint::scene` accept and refuse;
//! - the GL defaults and bounds written in it are the ones of
//!   `glint::lighting`, and the precision bounds those of `glint::scene`;
//! - real responses of the code (shade bodies, problems, the HTTP service's
//!   own answers) validate against the schemas the document names for them.

use glint::lighting::{self, LightPosition};
use glint::scene::{self, Limits, Precision, RequestErrorKind, TermsDetail, wire};
use reqwest::{Method, StatusCode};
use serde_json::{Value, json};

const DOCUMENT: &str = include_str!("../api/openapi.yaml");

/// The document as JSON.
fn document() -> Value {
    serde_norway::from_str(DOCUMENT).expect("api/openapi.yaml is YAML")
}

/// A validator for `#/components/schemas/{name}` of `doc`: the schema is
/// compiled inside a root that holds the components, so that every
/// `#/components/schemas/...` reference resolves.
fn validator_in(doc: &Value, name: &str) -> jsonschema::Validator {
    assert!(
        doc["components"]["schemas"].get(name).is_some(),
        "no schema {name}"
    );
    let root = json!({
        "$ref": format!("#/components/schemas/{name}"),
        "components": { "schemas": doc["components"]["schemas"] },
    });
    jsonschema::options()
        .with_draft(jsonschema::Draft::Draft202012)
        .build(&root)
        .unwrap_or_else(|e| panic!("schema {name} does not compile: {e}"))
}

fn validator(name: &str) -> jsonschema::Validator {
    validator_in(&document(), name)
}

/// Panics with every error when `instance` is not valid.
fn assert_valid(validator: &jsonschema::Validator, name: &str, instance: &Value) {
    let errors: Vec<String> = validator
        .iter_errors(instance)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect();
    assert!(
        errors.is_empty(),
        "{instance} is not a valid {name}:\n{}",
        errors.join("\n")
    );
}

/// Every value under the key `key`, anywhere in `value`, with its location.
fn find_all<'a>(value: &'a Value, key: &str, at: String, out: &mut Vec<(String, &'a Value)>) {
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                let here = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
                if k == key {
                    out.push((here.clone(), v));
                }
                find_all(v, key, here, out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                find_all(v, key, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
}

/// Follows a local `$ref` (only one level: enough for `components/responses`).
fn deref<'a>(doc: &'a Value, value: &'a Value) -> &'a Value {
    match value.get("$ref").and_then(Value::as_str) {
        Some(r) => doc
            .pointer(r.strip_prefix('#').expect("a local reference"))
            .expect("the reference resolves"),
        None => value,
    }
}

#[test]
fn the_document_is_openapi_3_1() {
    let doc = document();
    let version = doc["openapi"].as_str().expect("`openapi` is a string");
    assert!(version.starts_with("3.1"), "openapi: {version}");
    assert!(doc["info"]["title"].is_string());
    assert!(doc["info"]["version"].is_string());
}

#[test]
fn every_ref_resolves_inside_the_document() {
    let doc = document();
    let mut refs = Vec::new();
    find_all(&doc, "$ref", String::new(), &mut refs);
    assert!(refs.len() > 50, "only {} references", refs.len());
    for (at, reference) in refs {
        let reference = reference
            .as_str()
            .unwrap_or_else(|| panic!("{at}: $ref is not a string"));
        let pointer = reference
            .strip_prefix('#')
            .unwrap_or_else(|| panic!("{at}: {reference} is not a local reference"));
        assert!(
            doc.pointer(pointer).is_some(),
            "{at}: {reference} does not resolve"
        );
    }
}

#[test]
fn the_paths_are_those_of_the_service() {
    let doc = document();
    let mut paths: Vec<&str> = doc["paths"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    paths.sort_unstable();
    assert_eq!(
        paths,
        [
            "/healthz",
            "/metrics",
            "/openapi.yaml",
            "/readyz",
            "/v1/render",
            "/v1/shade"
        ]
    );
}

/// Every request and response body is a `$ref` to a named schema, so tests
/// can validate real bodies by name; every response documents x-request-id.
#[test]
fn every_body_is_a_named_schema() {
    let doc = document();
    let mut bodies = 0;
    for (path, item) in doc["paths"].as_object().unwrap() {
        for (method, operation) in item.as_object().unwrap() {
            if method == "parameters" {
                continue;
            }
            let at = format!("{method} {path}");
            let mut contents = Vec::new();
            if let Some(body) = operation.get("requestBody") {
                contents.push((format!("{at} request"), &body["content"]));
            }
            for (status, response) in operation["responses"].as_object().unwrap() {
                let response = deref(&doc, response);
                assert!(
                    response["headers"].get("x-request-id").is_some(),
                    "{at} {status}: no x-request-id header"
                );
                if status == "429" || (status == "503" && path.starts_with("/v1/")) {
                    assert!(
                        response["headers"].get("Retry-After").is_some(),
                        "{at} {status}: no Retry-After header"
                    );
                }
                contents.push((format!("{at} {status}"), &response["content"]));
            }
            for (at, content) in contents {
                let content = content
                    .as_object()
                    .unwrap_or_else(|| panic!("{at}: no content"));
                for (media, media_type) in content {
                    let reference = media_type["schema"]["$ref"].as_str();
                    assert!(
                        reference.is_some_and(|r| r.starts_with("#/components/schemas/")),
                        "{at} {media}: the body is not a named schema"
                    );
                    bodies += 1;
                }
            }
        }
    }
    assert!(bodies >= 20, "only {bodies} bodies");
}

#[test]
fn every_schema_compiles_and_its_examples_validate() {
    let doc = document();
    let schemas = doc["components"]["schemas"].as_object().unwrap();
    for name in [
        "ShadeRequest",
        "ShadeResponse",
        "RenderRequest",
        "RenderJsonResponse",
        "Problem",
        "LightModel",
        "Material",
        "Light",
        "Spot",
        "Color",
        "Vec3",
        "Breakdown",
        "TermsSummary",
    ] {
        assert!(schemas.contains_key(name), "no schema {name}");
    }
    for (name, schema) in schemas {
        let validator = validator_in(&doc, name);
        let mut examples = Vec::new();
        find_all(schema, "examples", String::new(), &mut examples);
        for (at, list) in examples {
            // Only the examples of the schema itself: nested ones belong to
            // properties and are checked by those schemas where named.
            if at != "/examples" {
                continue;
            }
            for example in list.as_array().expect("examples is an array") {
                assert_valid(&validator, name, example);
            }
        }
    }
}

#[test]
fn hand_written_bodies() {
    let shade = validator("ShadeRequest");
    let minimal = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] } });
    assert_valid(&shade, "ShadeRequest", &minimal);
    let mut unknown = minimal.clone();
    unknown["colour"] = json!([1, 0, 0]);
    assert!(!shade.is_valid(&unknown), "an unknown field is accepted");

    let problem = validator("Problem");
    assert_valid(
        &problem,
        "Problem",
        &json!({
            "type": "urn:glint:problem:invalid",
            "title": "Invalid request",
            "status": 422,
            "detail": "a spot cutoff must be 180 or lie in [0, 90], not 120",
            "pointer": "/lights/2/spot/cutoff",
        }),
    );
    assert_valid(
        &problem,
        "Problem",
        &json!({ "type": "urn:glint:problem:busy", "title": "Busy", "status": 429, "detail": "later" }),
    );
    for wrong in [
        // A type that does not exist.
        json!({ "type": "about:blank", "title": "x", "status": 400, "detail": "x" }),
        // A type with another class's status.
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 400, "detail": "x" }),
        // No detail.
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422 }),
        // A pointer that is not a JSON Pointer.
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422, "detail": "x",
                "pointer": "lights.2" }),
    ] {
        assert!(!problem.is_valid(&wrong), "{wrong} is accepted");
    }
}

/// What the code does with a body: accepted, or refused with this kind.
fn shade_outcome(body: &Value) -> Result<(), RequestErrorKind> {
    let bytes = serde_json::to_vec(body).unwrap();
    scene::parse_shade(&bytes, &Limits::default())
        .map(|_| ())
        .map_err(|e| e.kind)
}

/// Each case: a body, whether the schema accepts it, and what the code does.
/// The schema refuses every body the parser refuses (400), and every 422
/// that JSON Schema can express; the rest are written in descriptions.
#[test]
fn shade_schema_agrees_with_parsing_and_validation() {
    use RequestErrorKind::{Invalid, Malformed, OverLimit};
    let shade = validator("ShadeRequest");
    let v = |extra: Value| {
        let mut body = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] } });
        for (k, value) in extra.as_object().unwrap() {
            body[k] = value.clone();
        }
        body
    };
    let light = |l: Value| v(json!({ "lights": [l] }));
    let many_lights: Vec<Value> = (0..65).map(|_| json!({})).collect();
    let cases: Vec<(&str, Value, bool, Result<(), RequestErrorKind>)> = vec![
        ("minimal", v(json!({})), true, Ok(())),
        (
            "everything",
            v(json!({
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
            Ok(()),
        ),
        (
            "an unknown field",
            v(json!({ "colour": 1 })),
            false,
            Err(Malformed),
        ),
        (
            "an unknown nested field",
            v(json!({ "light_model": { "two_sided": true } })),
            false,
            Err(Malformed),
        ),
        (
            "a colour of 2 numbers",
            v(json!({ "material": { "diffuse": [1, 0] } })),
            false,
            Err(Malformed),
        ),
        (
            "a colour of 5 numbers",
            v(json!({ "material": { "diffuse": [1, 0, 0, 1, 1] } })),
            false,
            Err(Malformed),
        ),
        (
            "an unknown precision",
            v(json!({ "precision": "exact" })),
            false,
            Err(Malformed),
        ),
        (
            "an unknown terms detail",
            v(json!({ "terms": "all" })),
            false,
            Err(Malformed),
        ),
        (
            "a string for a number",
            v(json!({ "material": { "shininess": "10" } })),
            false,
            Err(Malformed),
        ),
        ("no vertices", json!({}), false, Err(Malformed)),
        (
            "a position of 2 numbers",
            json!({ "vertices": { "positions": [[0, 0]], "normals": [[0, 0, 1]] } }),
            false,
            Err(Malformed),
        ),
        (
            "a view without a target",
            v(json!({ "view": { "eye": [0, 0, 1] } })),
            false,
            Err(Malformed),
        ),
        (
            "a cutoff of 180",
            light(json!({ "spot": { "cutoff": 180 } })),
            true,
            Ok(()),
        ),
        (
            "a cutoff of 90",
            light(json!({ "spot": { "cutoff": 90 } })),
            true,
            Ok(()),
        ),
        (
            "a cutoff of 0",
            light(json!({ "spot": { "cutoff": 0 } })),
            true,
            Ok(()),
        ),
        (
            "a cutoff of 120",
            light(json!({ "spot": { "cutoff": 120 } })),
            false,
            Err(Invalid),
        ),
        (
            "a cutoff of -1",
            light(json!({ "spot": { "cutoff": -1 } })),
            false,
            Err(Invalid),
        ),
        (
            "a negative exponent",
            light(json!({ "spot": { "exponent": -1 } })),
            false,
            Err(Invalid),
        ),
        (
            "a zero spot direction with a cone",
            light(json!({ "spot": { "direction": [0, 0, 0], "cutoff": 45 } })),
            false,
            Err(Invalid),
        ),
        (
            "a zero spot direction without a cone",
            light(json!({ "spot": { "direction": [0, 0, 0] } })),
            true,
            Ok(()),
        ),
        (
            "all-zero attenuation",
            light(json!({ "position": [0, 0, 1, 1], "attenuation": [0, 0, 0] })),
            false,
            Err(Invalid),
        ),
        (
            "a negative attenuation",
            light(json!({ "attenuation": [1, -0.5, 0] })),
            false,
            Err(Invalid),
        ),
        (
            "a directional light without a direction",
            light(json!({ "position": [0, 0, 0, 0] })),
            false,
            Err(Invalid),
        ),
        (
            "a positional light at the origin",
            light(json!({ "position": [0, 0, 0, 1] })),
            true,
            Ok(()),
        ),
        (
            "a negative shininess",
            v(json!({ "material": { "shininess": -1 } })),
            false,
            Err(Invalid),
        ),
        (
            "a shininess above GL's 128",
            v(json!({ "material": { "shininess": 1000 } })),
            true,
            Ok(()),
        ),
        (
            "a colour of 1e6",
            v(json!({ "light_model": { "ambient": [1e6, -1e6, 0] } })),
            true,
            Ok(()),
        ),
        (
            "a colour over 1e6",
            v(json!({ "light_model": { "ambient": [2e6, 0, 0] } })),
            false,
            Err(Invalid),
        ),
        (
            "a back material colour over 1e6",
            v(json!({ "back_material": { "emission": [0, 0, -2e6] } })),
            false,
            Err(Invalid),
        ),
        (
            "a coordinate over 1e30",
            json!({ "vertices": { "positions": [[2e30, 0, 0]], "normals": [[0, 0, 1]] } }),
            false,
            Err(Invalid),
        ),
        (
            "an eye over 1e30",
            v(json!({ "view": { "eye": [0, 0, 2e30], "target": [0, 0, 0] } })),
            false,
            Err(Invalid),
        ),
        (
            "a long normal, normalised",
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1e300]] } }),
            true,
            Ok(()),
        ),
        (
            "a long normal used as given",
            json!({ "light_model": { "normalize_normals": false },
                    "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 2e6]] } }),
            false,
            Err(Invalid),
        ),
        (
            "a zero normal",
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 0]] } }),
            true,
            Ok(()),
        ),
        (
            "64 lights",
            v(json!({ "lights": many_lights[..64].to_vec() })),
            true,
            Ok(()),
        ),
        (
            "65 lights",
            v(json!({ "lights": many_lights })),
            false,
            Err(OverLimit),
        ),
        // Rules JSON Schema cannot express: in the descriptions.
        (
            "fewer normals than positions",
            json!({ "vertices": { "positions": [[0, 0, 0], [1, 0, 0]], "normals": [[0, 0, 1]] } }),
            true,
            Err(Invalid),
        ),
        (
            "the eye at the target",
            v(json!({ "view": { "eye": [1, 2, 3], "target": [1, 2, 3] } })),
            true,
            Err(Invalid),
        ),
        (
            "a light position far away after division by w",
            light(json!({ "position": [1e30, 0, 0, 1e-10] })),
            true,
            Err(Invalid),
        ),
    ];
    for (name, body, schema_accepts, outcome) in cases {
        assert_eq!(
            shade.is_valid(&body),
            schema_accepts,
            "{name}: the schema {} {body}",
            if schema_accepts { "refuses" } else { "accepts" }
        );
        assert_eq!(
            shade_outcome(&body),
            outcome,
            "{name}: the code, for {body}"
        );
    }
}

/// Real `/v1/shade` bodies: every combination of sides, terms and precision
/// validates against `ShadeResponse`, and the problems of refused requests
/// against `Problem`.
#[test]
fn real_shade_responses_validate() {
    let doc = document();
    let response = validator_in(&doc, "ShadeResponse");
    let problem = validator_in(&doc, "Problem");
    let lights = json!([
        { "position": [0, 1, 1, 0], "specular": [1, 1, 1] },
        { "position": [0, 2, 3, 1], "attenuation": [1, 0.5, 0.25],
          "spot": { "direction": [0, -1, -1], "cutoff": 60, "exponent": 4 } },
    ]);
    let vertices = json!({
        "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]],
        "normals": [[0, 0, 1], [0, 0, -1], [0, 0, 0], [1, 1, 1]],
    });
    for two_side in [false, true] {
        for terms in ["none", "summary", "per_vertex"] {
            for precision in ["reference", "accurate", "fast"] {
                for empty in [false, true] {
                    let vertices = if empty {
                        json!({ "positions": [], "normals": [] })
                    } else {
                        vertices.clone()
                    };
                    let body = json!({
                        "light_model": { "two_side": two_side, "ambient": [3, 3, 3] },
                        "material": { "specular": [0.5, 0.5, 0.5], "shininess": 10,
                                      "emission": [-0.5, 0, 0] },
                        "lights": lights,
                        "vertices": vertices,
                        "precision": precision,
                        "terms": terms,
                    });
                    let scene =
                        scene::parse_shade(&serde_json::to_vec(&body).unwrap(), &Limits::default())
                            .unwrap_or_else(|e| panic!("{body}: {e}"));
                    let out = serde_json::to_value(glint::shading::shade(&scene)).unwrap();
                    assert_valid(&response, "ShadeResponse", &out);
                    // The optional parts are there exactly when documented.
                    assert_eq!(out.get("back_colors").is_some(), two_side, "{out}");
                    assert_eq!(out.get("terms").is_some(), terms != "none", "{out}");
                    if terms != "none" {
                        let t = &out["terms"];
                        assert_eq!(t.get("summary").is_some(), !empty, "{out}");
                        assert_eq!(
                            t.get("per_vertex").is_some(),
                            terms == "per_vertex",
                            "{out}"
                        );
                        assert_eq!(t.get("back").is_some(), two_side, "{out}");
                    }
                }
            }
        }
    }

    let refused = [
        json!({}),
        json!({ "vertices": { "positions": [], "normals": [] }, "lights": [{ "spot": { "cutoff": 120 } }] }),
        json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } }),
        json!({ "vertices": { "positions": [], "normals": [] }, "lights": (0..65).map(|_| json!({})).collect::<Vec<_>>() }),
    ];
    for body in refused {
        let e = scene::parse_shade(&serde_json::to_vec(&body).unwrap(), &Limits::default())
            .expect_err("refused");
        let out = serde_json::to_value(glint::problem::Problem::from(&e)).unwrap();
        assert_valid(&problem, "Problem", &out);
        // The pointer names a place in the body, or the whole body.
        let pointer = out["pointer"]
            .as_str()
            .expect("request errors carry a pointer");
        let parent = pointer.rsplit_once('/').map_or("", |(p, _)| p);
        assert!(body.pointer(parent).is_some(), "{pointer} is not in {body}");
    }
    assert_valid(
        &problem,
        "Problem",
        &serde_json::to_value(glint::problem::Problem::busy()).unwrap(),
    );
    assert_valid(
        &problem,
        "Problem",
        &serde_json::to_value(glint::problem::Problem::internal()).unwrap(),
    );
}

/// The defaults and bounds the document writes are the code's.
#[test]
fn defaults_and_bounds_are_the_codes() {
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    let default =
        |schema: &str, field: &str| schemas[schema]["properties"][field]["default"].clone();
    let rgba = |c: glam::DVec4| json!(c.to_array());

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

    let mat = lighting::Material::default();
    assert_eq!(default("Material", "ambient"), rgba(mat.ambient));
    assert_eq!(default("Material", "diffuse"), rgba(mat.diffuse));
    assert_eq!(default("Material", "specular"), rgba(mat.specular));
    assert_eq!(default("Material", "emission"), rgba(mat.emission));
    assert_eq!(default("Material", "shininess"), json!(mat.shininess));

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

    assert_eq!(schemas["Precision"]["default"], json!(Precision::default()));
    assert_eq!(
        schemas["TermsDetail"]["default"],
        json!(TermsDetail::default())
    );
    let bounds: Vec<f64> = [Precision::Reference, Precision::Accurate, Precision::Fast]
        .map(Precision::max_abs_error)
        .to_vec();
    let written: Vec<f64> = schemas["PrecisionInfo"]["properties"]["max_abs_error"]["enum"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().expect("a number"))
        .collect();
    assert_eq!(written, bounds);

    let item = |schema: &str| &schemas[schema]["items"];
    assert_eq!(item("Color")["maximum"].as_f64(), Some(lighting::MAX_COLOR));
    assert_eq!(
        item("Color")["minimum"].as_f64(),
        Some(-lighting::MAX_COLOR)
    );
    assert_eq!(
        item("Point3")["maximum"].as_f64(),
        Some(lighting::MAX_COORDINATE)
    );
    assert_eq!(
        item("Point3")["minimum"].as_f64(),
        Some(-lighting::MAX_COORDINATE)
    );
    let raw = &schemas["ShadeRequest"]["then"]["properties"]["vertices"]["properties"]["normals"]["items"]
        ["items"];
    assert_eq!(raw["maximum"].as_f64(), Some(lighting::MAX_RAW_NORMAL));
    assert_eq!(raw["minimum"].as_f64(), Some(-lighting::MAX_RAW_NORMAL));
    assert_eq!(
        schemas["Lights"]["maxItems"].as_u64(),
        Some(lighting::MAX_LIGHTS as u64)
    );
    assert_eq!(
        schemas["RenderRequest"]["properties"]["samples"]["maximum"].as_u64(),
        Some(u64::from(Limits::default().max_samples))
    );
}

/// The render request schema against the wire types (the renderer itself is
/// not built yet: only parsing is checked).
#[test]
fn render_schema_agrees_with_the_wire_types() {
    let render = validator("RenderRequest");
    let base = json!({
        "materials": { "red": { "diffuse": [1, 0, 0] } },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 64, "height": 48 },
        "objects": [{ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" }],
    });
    let with = |k: &str, value: Value| {
        let mut body = base.clone();
        body[k] = value;
        body
    };
    let parses = |body: &Value| {
        scene::parse_json::<wire::RenderRequest>(&serde_json::to_vec(body).unwrap()).is_ok()
    };
    let full = {
        let mut body = base.clone();
        body["light_model"] = json!({ "two_side": true });
        body["lights"] = json!([{ "position": [1, 1, 1, 0] }]);
        body["objects"] = json!([
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "red" },
            { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                        "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]], "indices": [0, 1, 2] },
              "material": "red" },
            { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2] },
              "material": "red" },
        ]);
        body["background"] = json!([0, 0, 0]);
        body["shading"] = json!("per_vertex");
        body["samples"] = json!(16);
        body["shadows"] = json!(true);
        body["precision"] = json!("reference");
        body["region"] = json!({ "x": 0, "y": 0, "width": 32, "height": 24 });
        body["probes"] = json!([[1, 2], [30, 20]]);
        body["encoding"] = json!("srgb");
        body
    };
    for body in [&base, &full] {
        assert_valid(&render, "RenderRequest", body);
        assert!(parses(body), "{body} does not parse");
    }
    // Refused by the parser and by the schema alike.
    for body in [
        with("material", json!({})),
        with("back_material", json!({ "shininess": "high" })),
        with("shading", json!("flat")),
        with("encoding", json!("gamma")),
        with("probes", json!([[1, 2, 3]])),
        with("region", json!({ "x": 0, "y": 0, "width": 1 })),
        with(
            "objects",
            json!([{ "sphere": { "center": [0, 0, 0] }, "material": "red" }]),
        ),
        with("objects", json!([{ "cube": {}, "material": "red" }])),
        with(
            "camera",
            json!({ "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0] }),
        ),
    ] {
        assert!(!render.is_valid(&body), "the schema accepts {body}");
        assert!(!parses(&body), "the parser accepts {body}");
    }
    // Parsed, then refused by validation (422): not exactly one shape.
    for objects in [
        json!([{ "material": "red" }]),
        json!([{ "sphere": { "center": [0, 0, 0], "radius": 1 },
                 "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] }, "material": "red" }]),
    ] {
        let body = with("objects", objects);
        assert!(!render.is_valid(&body), "the schema accepts {body}");
        assert!(parses(&body), "{body} does not parse");
    }
    for samples in [0, 65] {
        assert!(!render.is_valid(&with("samples", json!(samples))));
    }
}

/// The HTTP service's own answers, over a loopback socket.
#[tokio::test]
async fn http_responses_validate() {
    let doc = document();
    let state = glint::http::AppState::new(&glint::config::ServeConfig::default()).unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    let server =
        tokio::spawn(axum::serve(listener, glint::http::app(state.clone(), &[])).into_future());
    let client = reqwest::Client::new();
    let call = |method: Method, uri: &str, content_type: Option<&str>, body: Value| {
        let mut request = client.request(method, format!("{base}{uri}"));
        if let Some(content_type) = content_type {
            request = request.header("content-type", content_type);
        }
        if !body.is_null() {
            request = request.body(serde_json::to_vec(&body).unwrap());
        }
        async move {
            let response = request.send().await.unwrap();
            let status = response.status();
            let headers = response.headers().clone();
            let bytes = response.bytes().await.unwrap();
            (status, headers, bytes)
        }
    };
    let json = |bytes: &[u8]| -> Value { serde_json::from_slice(bytes).unwrap() };
    let problem = validator_in(&doc, "Problem");
    let content_type =
        |headers: &reqwest::header::HeaderMap| headers["content-type"].to_str().unwrap().to_owned();

    // The documented answers of each operation.
    let shade_body = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] },
                             "lights": [{}], "terms": "per_vertex" });
    let (status, headers, bytes) = call(
        Method::POST,
        "/v1/shade",
        Some("application/json"),
        shade_body.clone(),
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    assert!(headers.contains_key("x-request-id"));
    assert_valid(
        &validator_in(&doc, "ShadeResponse"),
        "ShadeResponse",
        &json(&bytes),
    );

    let (status, headers, bytes) = call(Method::GET, "/healthz", None, Value::Null).await;
    assert_eq!(status, StatusCode::OK);
    assert!(content_type(&headers).starts_with("text/plain"));
    assert_valid(
        &validator_in(&doc, "HealthzBody"),
        "HealthzBody",
        &json!(std::str::from_utf8(&bytes).unwrap()),
    );
    let (status, _, bytes) = call(Method::GET, "/readyz", None, Value::Null).await;
    assert_eq!(status, StatusCode::OK);
    assert_valid(
        &validator_in(&doc, "ReadyzBody"),
        "ReadyzBody",
        &json!(std::str::from_utf8(&bytes).unwrap()),
    );
    let (status, headers, bytes) = call(Method::GET, "/openapi.yaml", None, Value::Null).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(content_type(&headers), "application/yaml");
    assert_eq!(&bytes[..], DOCUMENT.as_bytes());

    // Each error: the status and type the document gives it.
    let shade_errors = [
        (
            Some("application/json"),
            json!({ "vertices": {} }),
            400,
            "malformed",
        ),
        (
            Some("text/plain"),
            shade_body.clone(),
            415,
            "unsupported-media-type",
        ),
        (None, shade_body.clone(), 415, "unsupported-media-type"),
        (
            Some("application/json"),
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } }),
            422,
            "invalid",
        ),
    ];
    for (content, body, expected, slug) in shade_errors {
        let (status, headers, bytes) = call(Method::POST, "/v1/shade", content, body).await;
        assert_eq!(status.as_u16(), expected);
        assert_eq!(content_type(&headers), "application/problem+json");
        assert!(headers.contains_key("x-request-id"));
        let body = json(&bytes);
        assert_valid(&problem, "Problem", &body);
        assert_eq!(body["type"], format!("urn:glint:problem:{slug}"));
        assert!(
            doc["paths"]["/v1/shade"]["post"]["responses"]
                .get(expected.to_string())
                .is_some(),
            "{expected} is not documented for /v1/shade"
        );
    }
    let others = [
        (Method::POST, "/v1/render", 501, "not-implemented"),
        (Method::GET, "/nowhere", 404, "not-found"),
        (Method::DELETE, "/v1/shade", 405, "method-not-allowed"),
    ];
    for (method, uri, expected, slug) in others {
        let (status, headers, bytes) =
            call(method, uri, Some("application/json"), shade_body.clone()).await;
        assert_eq!(status.as_u16(), expected, "{uri}");
        assert_eq!(content_type(&headers), "application/problem+json");
        let body = json(&bytes);
        assert_valid(&problem, "Problem", &body);
        assert_eq!(body["type"], format!("urn:glint:problem:{slug}"));
    }

    // The metrics the document lists are the ones served.
    let (status, headers, bytes) = call(Method::GET, "/metrics", None, Value::Null).await;
    assert_eq!(status, StatusCode::OK);
    assert!(content_type(&headers).starts_with("application/openmetrics-text; version=1.0.0"));
    let text = std::str::from_utf8(&bytes).unwrap();
    let listed = doc["paths"]["/metrics"]["get"]["description"]
        .as_str()
        .unwrap();
    for name in [
        "glint_requests_total{route,status}",
        "glint_request_duration_seconds{route}",
        "glint_vertices_shaded_total",
        "glint_pixels_shaded_total",
        "glint_jobs_queued",
        "glint_jobs_running",
        "glint_rejections_total{reason}",
    ] {
        assert!(listed.contains(name), "the document does not list {name}");
        let family = name.split('{').next().unwrap();
        let family = family.strip_suffix("_total").unwrap_or(family);
        assert!(
            text.contains(&format!("# TYPE {family} ")),
            "/metrics has no {family}:\n{text}"
        );
    }

    // Shutting down: /readyz answers 503 with a documented problem.
    state
        .shutting_down
        .store(true, std::sync::atomic::Ordering::Relaxed);
    let (status, headers, bytes) = call(Method::GET, "/readyz", None, Value::Null).await;
    assert_eq!(status, StatusCode::SERVICE_UNAVAILABLE);
    assert_eq!(content_type(&headers), "application/problem+json");
    assert_valid(&problem, "Problem", &json(&bytes));
    server.abort();
}

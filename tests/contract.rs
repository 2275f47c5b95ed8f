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
//!   `glint_lighting`, and the precision bounds those of `glint_lighting`;
//! - real responses of the code (shade and render bodies, problems, the HTTP
//!   service's own answers, the PNG included) validate against the schemas
//!   the document names for them.

use base64::Engine;
use glint::scene::{self, Limits, MAX_PROBES, RequestErrorKind, TermsDetail, wire};
use glint_lighting::{self as lighting, LightPosition, Precision};
use glint_trace::MAX_SAMPLES;
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

/// The status each problem `type` fixes, from the table of errors in the
/// document's description (`| 429 / 503 | `urn:glint:problem:busy` | ...`).
fn problem_statuses(doc: &Value) -> Vec<(String, Vec<u64>)> {
    let description = doc["info"]["description"].as_str().unwrap();
    let rows: Vec<(String, Vec<u64>)> = description
        .lines()
        .filter_map(|line| {
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            let kind = cells.get(2)?.strip_prefix('`')?.strip_suffix('`')?;
            let kind = kind.strip_prefix("urn:glint:problem:")?;
            let statuses = cells[1]
                .split('/')
                .map(|s| s.trim().parse().ok())
                .collect::<Option<Vec<u64>>>()?;
            Some((kind.to_owned(), statuses))
        })
        .collect();
    assert!(rows.len() >= 10, "the table of errors: {rows:?}");
    rows
}

/// Whether a problem's `status` is one its `type` fixes: a rule the schema
/// `Problem` states in its description.
fn status_fits_type(doc: &Value, problem: &Value) -> Result<(), String> {
    let kind = problem["type"].as_str().unwrap_or_default();
    let status = problem["status"].as_u64().unwrap_or_default();
    let statuses = problem_statuses(doc)
        .into_iter()
        .filter(|(k, _)| format!("urn:glint:problem:{k}") == kind)
        .flat_map(|(_, s)| s)
        .collect::<Vec<_>>();
    if statuses.contains(&status) {
        Ok(())
    } else {
        Err(format!("{problem}: a {kind} is {statuses:?}"))
    }
}

/// A problem is of the schema `Problem`, and its status fits its type.
fn assert_problem(doc: &Value, validator: &jsonschema::Validator, problem: &Value) {
    assert_valid(validator, "Problem", problem);
    if let Err(e) = status_fits_type(doc, problem) {
        panic!("{e}");
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
            "/",
            "/healthz",
            "/metrics",
            "/openapi.yaml",
            "/playground/{file}",
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

    let doc = document();
    let problem = validator_in(&doc, "Problem");
    assert_problem(
        &doc,
        &problem,
        &json!({
            "type": "urn:glint:problem:invalid",
            "title": "Invalid request",
            "status": 422,
            "detail": "a spot cutoff must be 180 or lie in [0, 90], not 120",
            "pointer": "/lights/2/spot/cutoff",
        }),
    );
    assert_problem(
        &doc,
        &problem,
        &json!({ "type": "urn:glint:problem:busy", "title": "Busy", "status": 429, "detail": "later" }),
    );
    for wrong in [
        // A type that does not exist.
        json!({ "type": "about:blank", "title": "x", "status": 400, "detail": "x" }),
        // No detail.
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422 }),
        // A pointer that is not a JSON Pointer.
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422, "detail": "x",
                "pointer": "lights.2" }),
    ] {
        assert!(!problem.is_valid(&wrong), "{wrong} is accepted");
    }

    // The status a type fixes is written in the description of `Problem`,
    // as in the table of errors, and checked on every real problem below
    // (`assert_problem`); a type with another class's status breaks it.
    let written = doc["components"]["schemas"]["Problem"]["description"]
        .as_str()
        .unwrap();
    for (kind, statuses) in problem_statuses(&doc) {
        let statuses = statuses
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(" or ");
        assert!(
            written.contains(&format!("`{kind}` {statuses}")),
            "the description of Problem does not say that {kind} is {statuses}"
        );
    }
    let right =
        json!({ "type": "urn:glint:problem:busy", "title": "x", "status": 429, "detail": "x" });
    assert_problem(&doc, &problem, &right);
    let wrong =
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 400, "detail": "x" });
    assert!(status_fits_type(&doc, &wrong).is_err(), "{wrong} passes");
}

/// What the code does with a body: accepted, or refused with this kind.
fn shade_outcome(body: &Value) -> Result<(), RequestErrorKind> {
    let bytes = serde_json::to_vec(body).unwrap();
    scene::parse_shade(&bytes, &Limits::default())
        .map(|_| ())
        .map_err(|e| e.kind)
}

/// A shade body of one vertex at the origin facing +z, with the members of
/// `extra` beside it.
fn one_vertex_with(extra: Value) -> Value {
    let mut body = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] } });
    for (k, value) in extra.as_object().unwrap() {
        body[k] = value.clone();
    }
    body
}

/// Each case: a body, whether the schema accepts it, and what the code does.
/// The schema refuses every body the parser refuses (400), and every 422
/// that the JSON Schema client generators read can express (bounds); the
/// rest are written in descriptions.
#[test]
fn shade_schema_agrees_with_parsing_and_validation() {
    use RequestErrorKind::{Invalid, Malformed};
    let shade = validator("ShadeRequest");
    let v = one_vertex_with;
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
            "a cutoff of 181",
            light(json!({ "spot": { "cutoff": 181 } })),
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
            "a zero spot direction without a cone",
            light(json!({ "spot": { "direction": [0, 0, 0] } })),
            true,
            Ok(()),
        ),
        (
            "a negative attenuation",
            light(json!({ "attenuation": [1, -0.5, 0] })),
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
            "65 lights, past the contract's bound",
            v(json!({ "lights": many_lights })),
            false,
            Err(Invalid),
        ),
        (
            "a null for a field left out",
            v(json!({ "terms": null })),
            false,
            Err(Malformed),
        ),
        (
            "a null light model",
            v(json!({ "light_model": null })),
            false,
            Err(Malformed),
        ),
        // Rules written in descriptions, not in the schema: one value
        // forbidden, or one field tied to another.
        (
            "a cutoff of 120",
            light(json!({ "spot": { "cutoff": 120 } })),
            true,
            Err(Invalid),
        ),
        (
            "a zero spot direction with a cone",
            light(json!({ "spot": { "direction": [0, 0, 0], "cutoff": 45 } })),
            true,
            Err(Invalid),
        ),
        (
            "all-zero attenuation",
            light(json!({ "position": [0, 0, 1, 1], "attenuation": [0, 0, 0] })),
            true,
            Err(Invalid),
        ),
        (
            "all-zero attenuation of a directional light",
            light(json!({ "attenuation": [0, 0, 0] })),
            true,
            Err(Invalid),
        ),
        (
            "a directional light without a direction",
            light(json!({ "position": [0, 0, 0, 0] })),
            true,
            Err(Invalid),
        ),
        (
            "a long normal used as given",
            json!({ "light_model": { "normalize_normals": false },
                    "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 2e6]] } }),
            true,
            Err(Invalid),
        ),
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
                    let out = serde_json::to_value(glint::shade::shade(&scene)).unwrap();
                    assert_valid(&response, "ShadeResponse", &out);
                    // The bound is the one its mode documents.
                    assert_eq!(out["precision"]["mode"], precision);
                    assert_eq!(
                        out["precision"]["max_abs_error"].as_f64(),
                        Some(scene.precision.max_abs_error()),
                        "{out}"
                    );
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
        assert_problem(&doc, &problem, &out);
        // The pointer names a place in the body, or the whole body.
        let pointer = out["pointer"]
            .as_str()
            .expect("request errors carry a pointer");
        let parent = pointer.rsplit_once('/').map_or("", |(p, _)| p);
        assert!(body.pointer(parent).is_some(), "{pointer} is not in {body}");
    }
    assert_problem(
        &doc,
        &problem,
        &serde_json::to_value(glint::problem::Problem::busy()).unwrap(),
    );
    assert_problem(
        &doc,
        &problem,
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

    assert_eq!(
        schemas["Precision"]["default"],
        json!(wire::Precision::from(Precision::default()))
    );
    assert_eq!(
        schemas["TermsDetail"]["default"],
        json!(TermsDetail::default())
    );
    // The three bounds, each written in the description (a number enum is
    // beyond client generators), and the least and the greatest as the
    // schema's range. Real responses carry their mode's bound exactly
    // (`real_shade_responses_validate`).
    let bounds: Vec<f64> = [Precision::Reference, Precision::Accurate, Precision::Fast]
        .map(Precision::max_abs_error)
        .to_vec();
    let max_abs_error = &schemas["PrecisionInfo"]["properties"]["max_abs_error"];
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
    // The bound of normals used as given depends on the light model: it is
    // written where the normals and the switch are described (and the code
    // enforces it: `a long normal used as given` in the cases above).
    let raw_bound = format!("±{:e}", lighting::MAX_RAW_NORMAL);
    for (schema, field) in [
        ("Vertices", "normals"),
        ("Mesh", "normals"),
        ("LightModel", "normalize_normals"),
    ] {
        let description = schemas[schema]["properties"][field]["description"]
            .as_str()
            .unwrap();
        assert!(
            description.contains(&raw_bound),
            "{schema}.{field} does not write {raw_bound}: {description}"
        );
    }
    assert_eq!(
        schemas["Lights"]["maxItems"].as_u64(),
        Some(lighting::MAX_LIGHTS as u64)
    );
    let render = &schemas["RenderRequest"];
    assert_eq!(
        render["properties"]["samples"]["maximum"].as_u64(),
        Some(u64::from(Limits::default().max_samples))
    );
    assert_eq!(
        render["properties"]["samples"]["maximum"].as_u64(),
        Some(u64::from(MAX_SAMPLES))
    );
    assert_eq!(
        render["properties"]["probes"]["maxItems"].as_u64(),
        Some(MAX_PROBES as u64)
    );
    assert_eq!(
        render["properties"]["objects"]["maxItems"].as_u64(),
        Some(wire::MAX_OBJECTS as u64)
    );
    assert_eq!(
        render["properties"]["materials"]["maxProperties"].as_u64(),
        Some(wire::MAX_MATERIALS as u64)
    );
    assert_eq!(
        schemas["Sphere"]["properties"]["radius"]["maximum"].as_f64(),
        Some(lighting::MAX_COORDINATE)
    );

    // The render defaults: those of a request that gives none.
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
        schemas["Precision"]["default"],
        json!(wire::Precision::from(r.precision))
    );
    let shading = match r.shading {
        glint_trace::ShadingMode::PerPixel => "per_pixel",
        glint_trace::ShadingMode::PerVertex => "per_vertex",
    };
    assert_eq!(schemas["ShadingMode"]["default"], json!(shading));
    let encoding = match r.encoding {
        glint_trace::Encoding::Linear => "linear",
        glint_trace::Encoding::Srgb => "srgb",
    };
    assert_eq!(schemas["Encoding"]["default"], json!(encoding));
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

/// What the code does with a render body: accepted, or refused with this
/// kind at this pointer.
fn render_outcome(body: &Value, limits: &Limits) -> Result<(), (RequestErrorKind, String)> {
    let bytes = serde_json::to_vec(body).unwrap();
    scene::parse_render(&bytes, limits)
        .map(|_| ())
        .map_err(|e| (e.kind, e.pointer))
}

/// A small render: 32×24, a red sphere on a grey floor, a directional light
/// and a positional spotlight; probes on the sphere and on the background
/// (above the horizon).
fn render_body() -> Value {
    json!({
        "materials": {
            "red": { "diffuse": [1, 0, 0], "specular": [1, 1, 1], "shininess": 20 },
            "floor": { "diffuse": [0.5, 0.5, 0.5] },
        },
        "lights": [
            { "position": [1, 1, 1, 0] },
            { "position": [0, 3, 3, 1], "attenuation": [1, 0.1, 0],
              "spot": { "direction": [0, -1, -1], "cutoff": 60, "exponent": 2 } },
        ],
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 32, "height": 24 },
        "objects": [
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "floor" },
        ],
        "background": [0, 0, 0.25],
        "probes": [[16, 12], [0, 0]],
    })
}

/// A quad of two triangles (with normals, one of them zero) beside a
/// sphere: per-vertex shading lights the quad at its vertices and the
/// sphere per pixel.
fn per_vertex_body() -> Value {
    let mut body = render_body();
    body["objects"] = json!([
        { "mesh": { "positions": [[-2, -1, 0], [0, -1, 0], [0, 1, 0], [-2, 1, 0]],
                    "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 0]],
                    "indices": [0, 1, 2, 0, 2, 3] },
          "material": "floor" },
        { "sphere": { "center": [1, 0, 0], "radius": 0.75 }, "material": "red" },
    ]);
    body["shading"] = json!("per_vertex");
    body["probes"] = json!([[10, 12], [24, 12], [0, 0]]);
    body
}

/// The render request schema against the parser and the validation of
/// `glint::scene`: what the schema refuses the code refuses, and the rules
/// the schema cannot express (written in descriptions) the code enforces at
/// the documented pointers.
#[test]
fn render_schema_agrees_with_the_wire_types() {
    use RequestErrorKind::{Invalid, Malformed, OverLimit};
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
    // Parsing, and the JSON form's own fields (a request with a model may
    // leave out its camera, materials and objects).
    let parses = |body: &Value| {
        scene::parse_json::<wire::RenderRequest>(&serde_json::to_vec(body).unwrap())
            .is_ok_and(|request| request.json_form().is_ok())
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
    for body in [&base, &full, &render_body(), &per_vertex_body()] {
        assert_valid(&render, "RenderRequest", body);
        assert!(parses(body), "{body} does not parse");
        assert_eq!(render_outcome(body, &Limits::default()), Ok(()), "{body}");
    }
    // Refused by the parser and by the schema alike.
    for body in [
        with("material", json!({})),
        with("back_material", json!({ "shininess": "high" })),
        with("shading", json!("flat")),
        with("encoding", json!("gamma")),
        with("probes", json!([[1, 2, 3]])),
        with("probes", json!([[-1, 2]])),
        with("samples", json!(-1)),
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
        assert!(
            matches!(
                render_outcome(&body, &Limits::default()),
                Err((Malformed, _))
            ),
            "{body}"
        );
    }

    // Parsed, then accepted or refused by validation.
    let camera = |k: &str, value: Value| {
        let mut body = base.clone();
        body["camera"][k] = value;
        body
    };
    let object = |o: Value| with("objects", json!([o]));
    let mesh = |m: Value| object(json!({ "mesh": m, "material": "red" }));
    let triangle = json!([[0, 0, 0], [1, 0, 0], [0, 1, 0]]);
    let raw = |normalize: bool| {
        let mut body = mesh(json!({ "positions": triangle, "indices": [0, 1, 2],
                                    "normals": [[0, 0, 2e6], [0, 0, 1], [0, 0, 1]] }));
        body["light_model"] = json!({ "normalize_normals": normalize });
        body
    };
    let probes = |n: usize| with("probes", json!(vec![json!([0, 0]); n]));
    /// What the code must answer: accepted, or refused with this kind at this pointer.
    type Verdict<'a> = Result<(), (RequestErrorKind, &'a str)>;
    let cases: Vec<(&str, Value, bool, Verdict)> = vec![
        (
            "no shape",
            object(json!({ "material": "red" })),
            true,
            Err((Invalid, "/objects/0")),
        ),
        (
            "two shapes",
            object(json!({ "sphere": { "center": [0, 0, 0], "radius": 1 },
                           "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] },
                           "material": "red" })),
            true,
            Err((Invalid, "/objects/0")),
        ),
        ("1 sample", with("samples", json!(1)), true, Ok(())),
        ("64 samples", with("samples", json!(64)), true, Ok(())),
        (
            "0 samples",
            with("samples", json!(0)),
            false,
            Err((Invalid, "/samples")),
        ),
        (
            "65 samples, past the contract's bound",
            with("samples", json!(65)),
            false,
            Err((Invalid, "/samples")),
        ),
        (
            "a fov_y of 0",
            camera("fov_y", json!(0)),
            false,
            Err((Invalid, "/camera/fov_y")),
        ),
        (
            "a fov_y of 180",
            camera("fov_y", json!(180)),
            false,
            Err((Invalid, "/camera/fov_y")),
        ),
        ("a fov_y of 179", camera("fov_y", json!(179)), true, Ok(())),
        (
            "a zero up",
            camera("up", json!([0, 0, 0])),
            true,
            Err((Invalid, "/camera/up")),
        ),
        (
            "an up along the view direction",
            camera("up", json!([0, 0, -2])),
            true,
            Err((Invalid, "/camera/up")),
        ),
        (
            "the eye at the target",
            camera("target", json!([0, 0, 5])),
            true,
            Err((Invalid, "/camera/target")),
        ),
        (
            "a width of 0",
            camera("width", json!(0)),
            false,
            Err((Invalid, "/camera/width")),
        ),
        (
            "a height of 0",
            camera("height", json!(0)),
            false,
            Err((Invalid, "/camera/height")),
        ),
        (
            "3840×2160 pixels",
            {
                let mut body = camera("width", json!(3840));
                body["camera"]["height"] = json!(2160);
                body
            },
            true,
            Ok(()),
        ),
        (
            "more pixels than the limit",
            {
                let mut body = camera("width", json!(4000));
                body["camera"]["height"] = json!(4000);
                body
            },
            true,
            Err((OverLimit, "/camera")),
        ),
        (
            "an eye over 1e30",
            camera("eye", json!([0, 0, 2e30])),
            false,
            Err((Invalid, "/camera/eye")),
        ),
        (
            "a radius of 0",
            object(json!({ "sphere": { "center": [0, 0, 0], "radius": 0 }, "material": "red" })),
            false,
            Err((Invalid, "/objects/0/sphere/radius")),
        ),
        (
            "a radius over 1e30",
            object(json!({ "sphere": { "center": [0, 0, 0], "radius": 2e30 }, "material": "red" })),
            false,
            Err((Invalid, "/objects/0/sphere/radius")),
        ),
        (
            "a plane without a normal",
            object(
                json!({ "plane": { "point": [0, 0, 0], "normal": [0, 0, 0] }, "material": "red" }),
            ),
            true,
            Err((Invalid, "/objects/0/plane/normal")),
        ),
        (
            "an unknown material",
            object(json!({ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "blue" })),
            true,
            Err((Invalid, "/objects/0/material")),
        ),
        (
            "a material colour over 1e6",
            with("materials", json!({ "red": { "diffuse": [2e6, 0, 0] } })),
            false,
            Err((Invalid, "/materials/red/diffuse/0")),
        ),
        (
            "a material name to escape",
            {
                let mut body = with("materials", json!({ "a/b": { "shininess": -1 } }));
                body["objects"][0]["material"] = json!("a/b");
                body
            },
            false,
            Err((Invalid, "/materials/a~1b/shininess")),
        ),
        (
            "a cutoff of 120",
            with("lights", json!([{ "spot": { "cutoff": 120 } }])),
            true,
            Err((Invalid, "/lights/0/spot/cutoff")),
        ),
        (
            "a background over 1e6",
            with("background", json!([0, 0, 2e6])),
            false,
            Err((Invalid, "/background/2")),
        ),
        (
            "a background over 1, clamped",
            with("background", json!([2, 0, 0])),
            true,
            Ok(()),
        ),
        (
            "indices not in threes",
            mesh(json!({ "positions": triangle, "indices": [0, 1] })),
            true,
            Err((Invalid, "/objects/0/mesh/indices")),
        ),
        (
            "an index out of range",
            mesh(json!({ "positions": triangle, "indices": [0, 1, 3] })),
            true,
            Err((Invalid, "/objects/0/mesh/indices/2")),
        ),
        (
            "fewer normals than positions",
            mesh(json!({ "positions": triangle, "indices": [0, 1, 2], "normals": [[0, 0, 1]] })),
            true,
            Err((Invalid, "/objects/0/mesh/normals")),
        ),
        ("a long mesh normal, normalised", raw(true), true, Ok(())),
        (
            "a long mesh normal used as given",
            raw(false),
            true,
            Err((Invalid, "/objects/0/mesh/normals/0")),
        ),
        (
            "a region inside the image",
            with(
                "region",
                json!({ "x": 60, "y": 40, "width": 4, "height": 8 }),
            ),
            true,
            Ok(()),
        ),
        (
            "a region past the image",
            with(
                "region",
                json!({ "x": 60, "y": 40, "width": 5, "height": 8 }),
            ),
            true,
            Err((Invalid, "/region")),
        ),
        (
            "a region of width 0",
            with("region", json!({ "x": 0, "y": 0, "width": 0, "height": 8 })),
            false,
            Err((Invalid, "/region/width")),
        ),
        (
            "a probe in the image, out of the region",
            {
                let mut body = with("probes", json!([[63, 47]]));
                body["region"] = json!({ "x": 0, "y": 0, "width": 8, "height": 8 });
                body
            },
            true,
            Ok(()),
        ),
        (
            "a probe outside the image",
            with("probes", json!([[0, 0], [64, 0]])),
            true,
            Err((Invalid, "/probes/1")),
        ),
        ("4096 probes", probes(MAX_PROBES), true, Ok(())),
        (
            "4097 probes, past the contract's bound",
            probes(MAX_PROBES + 1),
            false,
            Err((Invalid, "/probes")),
        ),
    ];
    for (name, body, schema_accepts, outcome) in cases {
        assert!(parses(&body), "{name}: {body} does not parse");
        assert_eq!(
            render.is_valid(&body),
            schema_accepts,
            "{name}: the schema {} {body}",
            if schema_accepts { "refuses" } else { "accepts" }
        );
        assert_eq!(
            render_outcome(&body, &Limits::default()),
            outcome.map_err(|(kind, pointer)| (kind, pointer.to_owned())),
            "{name}: the code, for {body}"
        );
    }

    // The mesh vertices of all objects together count against the vertex
    // limit, at the mesh that passes it.
    let limits = Limits {
        max_vertices: 5,
        ..Limits::default()
    };
    let two_meshes = with(
        "objects",
        json!([
            { "mesh": { "positions": triangle, "indices": [0, 1, 2] }, "material": "red" },
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "mesh": { "positions": triangle, "indices": [0, 1, 2] }, "material": "red" },
        ]),
    );
    assert_valid(&render, "RenderRequest", &two_meshes);
    assert_eq!(
        render_outcome(&two_meshes, &limits),
        Err((OverLimit, "/objects/2/mesh/positions".to_owned()))
    );

    // A server's own limits below the contract's bounds are 413: a value
    // the schema takes, past this server's setting.
    let few = Limits {
        max_samples: 16,
        max_lights: 2,
        ..Limits::default()
    };
    let samples = with("samples", json!(17));
    assert_valid(&render, "RenderRequest", &samples);
    assert_eq!(
        render_outcome(&samples, &few),
        Err((OverLimit, "/samples".to_owned()))
    );
    let lights = with("lights", json!([{}, {}, {}]));
    assert_valid(&render, "RenderRequest", &lights);
    assert_eq!(
        render_outcome(&lights, &few),
        Err((OverLimit, "/lights".to_owned()))
    );
}

/// The schemas keep to the JSON Schema that client generators and test
/// tools read: openapi-python-client refused the document for a `not`,
/// schemathesis could generate no request past an `if`/`then`, and a number
/// `enum` or a union of `const`s became generated code that refuses real
/// answers. So: no `if`, `then`, `else`, `not`, `oneOf` or `allOf`; every
/// `anyOf` is "null or a named schema"; every `enum` and `const` is a
/// string. The rules those forms held are written in descriptions
/// (`rules_written_in_descriptions_are_stated_and_enforced`).
#[test]
fn the_schemas_keep_to_what_client_generators_read() {
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    // A key that is a keyword, not the name of a property.
    let keywords = |key: &str| {
        let mut found = Vec::new();
        find_all(schemas, key, String::new(), &mut found);
        found.retain(|(at, _)| !at.ends_with(&format!("/properties/{key}")));
        found
    };
    for key in ["if", "then", "else", "not", "oneOf", "allOf"] {
        let found: Vec<String> = keywords(key).into_iter().map(|(at, _)| at).collect();
        assert!(found.is_empty(), "`{key}` at {found:?}");
    }
    // A union of named schemas (a generated client's union of its types),
    // or `null` or one named schema.
    for (at, branches) in keywords("anyOf") {
        let branches = branches.as_array().unwrap();
        let null = branches.iter().filter(|b| b["type"] == "null").count();
        let named = branches.iter().filter(|b| b.get("$ref").is_some()).count();
        assert!(
            branches.len() == 2 && null + named == 2 && null <= 1,
            "{at}: anyOf is not `null` or a named schema, nor two named schemas"
        );
    }
    for (at, values) in keywords("enum") {
        assert!(
            values.as_array().unwrap().iter().all(Value::is_string),
            "{at}: an enum of non-strings"
        );
    }
    for (at, value) in keywords("const") {
        assert!(value.is_string(), "{at}: a const that is not a string");
    }
}

/// Each rule that the schemas leave to a description (a value forbidden, or
/// a field tied to another): its description states it with the pointer of
/// its 422, the document's list of such rules names that pointer, the
/// schema accepts a body that breaks it, and the code refuses that body
/// with 422 at that pointer. (Those 422s of schema-valid requests are what
/// `tests/clients/schemathesis.toml` declares to schemathesis.)
#[test]
fn rules_written_in_descriptions_are_stated_and_enforced() {
    use RequestErrorKind::Invalid;
    let doc = document();
    let listed = doc["info"]["description"].as_str().unwrap();
    let shade = validator_in(&doc, "ShadeRequest");
    let render = validator_in(&doc, "RenderRequest");
    let vertex = one_vertex_with;
    let light = |l: Value| vertex(json!({ "lights": [l] }));
    let base = json!({
        "materials": { "red": {} },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 8, "height": 6 },
        "objects": [],
    });
    let scene = |change: &dyn Fn(&mut Value)| {
        let mut body = base.clone();
        change(&mut body);
        body
    };
    let object = |o: Value| scene(&|b| b["objects"] = json!([o]));
    let triangle = json!([[0, 0, 0], [1, 0, 0], [0, 1, 0]]);
    let mesh = |m: Value| object(json!({ "mesh": m, "material": "red" }));
    // (where the rule is written, the pointer it writes, the body, whether
    // it is a render, the pointer of the code's 422)
    let cases: Vec<(&str, &str, Value, bool, &str)> = vec![
        (
            "/components/schemas/LightPosition/description",
            "/lights/{i}/position",
            light(json!({ "position": [0, 0, 0, 0] })),
            false,
            "/lights/0/position",
        ),
        (
            "/components/schemas/LightPosition/description",
            "/lights/{i}/position",
            light(json!({ "position": [1e30, 0, 0, 1e-10] })),
            false,
            "/lights/0/position",
        ),
        (
            "/components/schemas/Light/properties/attenuation/description",
            "/lights/{i}/attenuation",
            light(json!({ "attenuation": [0, 0, 0] })),
            false,
            "/lights/0/attenuation",
        ),
        (
            "/components/schemas/Spot/properties/cutoff/description",
            "/lights/{i}/spot/cutoff",
            light(json!({ "spot": { "cutoff": 90.5 } })),
            false,
            "/lights/0/spot/cutoff",
        ),
        (
            "/components/schemas/Spot/properties/direction/description",
            "/lights/{i}/spot/direction",
            light(json!({ "spot": { "direction": [0, 0, 0], "cutoff": 30 } })),
            false,
            "/lights/0/spot/direction",
        ),
        (
            "/components/schemas/Vertices/properties/normals/description",
            "/vertices/normals/{k}",
            json!({ "light_model": { "normalize_normals": false },
                    "vertices": { "positions": [[0, 0, 0]], "normals": [[0, -2e6, 0]] } }),
            false,
            "/vertices/normals/0",
        ),
        (
            "/components/schemas/Vertices/description",
            "/vertices/normals",
            json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } }),
            false,
            "/vertices/normals",
        ),
        (
            "/components/schemas/View/properties/target/description",
            "/view/target",
            vertex(json!({ "view": { "eye": [0, 0, 1], "target": [0, 0, 1] } })),
            false,
            "/view/target",
        ),
        (
            "/components/schemas/Camera/properties/target/description",
            "/camera/target",
            scene(&|b| b["camera"]["target"] = json!([0, 0, 5])),
            true,
            "/camera/target",
        ),
        (
            "/components/schemas/Camera/properties/up/description",
            "/camera/up",
            scene(&|b| b["camera"]["up"] = json!([0, 0, 0])),
            true,
            "/camera/up",
        ),
        (
            "/components/schemas/Camera/properties/up/description",
            "/camera/up",
            scene(&|b| b["camera"]["up"] = json!([0, 0, 3])),
            true,
            "/camera/up",
        ),
        (
            "/components/schemas/Plane/properties/normal/description",
            "/objects/{i}/plane/normal",
            object(
                json!({ "plane": { "point": [0, 0, 0], "normal": [0, 0, 0] }, "material": "red" }),
            ),
            true,
            "/objects/0/plane/normal",
        ),
        (
            "/components/schemas/SceneObject/description",
            "/objects/{i}",
            object(json!({ "material": "red" })),
            true,
            "/objects/0",
        ),
        (
            "/components/schemas/SceneObject/properties/material/description",
            "/objects/{i}/material",
            object(json!({ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "blue" })),
            true,
            "/objects/0/material",
        ),
        (
            "/components/schemas/Mesh/properties/normals/description",
            "/objects/{i}/mesh/normals/{k}",
            {
                let mut body = mesh(json!({ "positions": triangle, "indices": [0, 1, 2],
                                            "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 2e6]] }));
                body["light_model"] = json!({ "normalize_normals": false });
                body
            },
            true,
            "/objects/0/mesh/normals/2",
        ),
        (
            "/components/schemas/Mesh/properties/normals/description",
            "/objects/{i}/mesh/normals",
            mesh(json!({ "positions": triangle, "indices": [0, 1, 2], "normals": [] })),
            true,
            "/objects/0/mesh/normals",
        ),
        (
            "/components/schemas/Mesh/properties/indices/description",
            "/objects/{i}/mesh/indices",
            mesh(json!({ "positions": triangle, "indices": [0, 1] })),
            true,
            "/objects/0/mesh/indices",
        ),
        (
            "/components/schemas/Mesh/properties/indices/description",
            "/objects/{i}/mesh/indices/{k}",
            mesh(json!({ "positions": triangle, "indices": [0, 1, 3] })),
            true,
            "/objects/0/mesh/indices/2",
        ),
        (
            "/components/schemas/Region/description",
            "/region",
            scene(&|b| b["region"] = json!({ "x": 4, "y": 0, "width": 5, "height": 1 })),
            true,
            "/region",
        ),
        (
            "/components/schemas/RenderRequest/properties/probes/description",
            "/probes/{k}",
            scene(&|b| b["probes"] = json!([[0, 0], [0, 6]])),
            true,
            "/probes/1",
        ),
    ];
    for (written_at, pointer, body, is_render, at) in cases {
        let written = doc
            .pointer(written_at)
            .and_then(Value::as_str)
            .unwrap_or_else(|| panic!("no description at {written_at}"));
        let pointer = format!("`{pointer}`");
        assert!(
            written.contains(&pointer),
            "{written_at} does not name {pointer}: {written}"
        );
        assert!(
            listed.contains(&pointer),
            "the document's list of such rules does not name {pointer}"
        );
        let (schema_accepts, outcome) = if is_render {
            (
                render.is_valid(&body),
                render_outcome(&body, &Limits::default()),
            )
        } else {
            let bytes = serde_json::to_vec(&body).unwrap();
            (
                shade.is_valid(&body),
                scene::parse_shade(&bytes, &Limits::default())
                    .map(|_| ())
                    .map_err(|e| (e.kind, e.pointer)),
            )
        };
        assert!(schema_accepts, "{pointer}: the schema refuses {body}");
        assert_eq!(
            outcome,
            Err((Invalid, at.to_owned())),
            "{pointer}: the code, for {body}"
        );
    }
}

/// Regression: `null` for a field that may be left out was read as if the
/// field were absent (a request the schema refuses was answered 200), though
/// no schema takes `null`. Now each such field refuses `null` as a wrong
/// type (400) at its own pointer, as its schema does.
#[test]
fn regression_null_is_not_an_absent_field() {
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

/// Regression: an integer written with a zero fraction (`64.0`), which
/// JSON Schema, and so the contract, counts as the integer 64, was refused
/// as malformed (400) by the render parser. Every integer of a request now
/// takes it; a fraction, a negative number or one past u32 stay malformed.
#[test]
fn regression_integers_written_with_a_zero_fraction_are_integers() {
    let render = validator("RenderRequest");
    let body = |width: Value| {
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
    };
    let whole = body(json!(8.0));
    assert!(whole.to_string().contains("\"width\":8.0"), "{whole}");
    assert_valid(&render, "RenderRequest", &whole);
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

    for width in [json!(8.5), json!(-8.0), json!(4294967296.0), json!(1e300)] {
        let wrong = body(width.clone());
        assert!(
            !render.is_valid(&wrong),
            "the schema takes a width of {width}"
        );
        assert_eq!(
            render_outcome(&wrong, &Limits::default()),
            Err((RequestErrorKind::Malformed, "/camera/width".to_owned())),
            "a width of {width}"
        );
    }
}

/// Regression: the schema of `GET /openapi.yaml` said a string, but a YAML
/// body is read as the data it holds, as tools read it: the document, an
/// object, failed its own schema.
#[test]
fn regression_the_served_document_is_an_openapi_document() {
    let doc = document();
    let served = &doc["paths"]["/openapi.yaml"]["get"]["responses"]["200"]["content"];
    assert_eq!(
        served["application/yaml"]["schema"]["$ref"],
        "#/components/schemas/OpenApiDocument"
    );
    assert_valid(
        &validator_in(&doc, "OpenApiDocument"),
        "OpenApiDocument",
        &doc,
    );
}

/// Real `/v1/render` JSON bodies from `glint::rendering`, in every shading
/// mode and precision, with and without samples, shadows, two sides, a
/// region and anything hit, validate against `RenderJsonResponse`, and say
/// no more than it documents; the problems of refused renders validate
/// against `Problem`.
#[test]
fn real_render_responses_validate() {
    let doc = document();
    let response = validator_in(&doc, "RenderJsonResponse");
    let problem = validator_in(&doc, "Problem");
    let schemas = &doc["components"]["schemas"];
    // Every key of `value` is a property of `schema`.
    let documented = |schema: &str, value: &Value| {
        for key in value.as_object().expect("an object").keys() {
            assert!(
                schemas[schema]["properties"].get(key).is_some(),
                "{schema} does not document `{key}`: {value}"
            );
        }
    };
    for shading in ["per_pixel", "per_vertex"] {
        for precision in ["reference", "accurate", "fast"] {
            for variant in 0..3 {
                let mut body = if shading == "per_vertex" {
                    per_vertex_body()
                } else {
                    render_body()
                };
                body["shading"] = json!(shading);
                body["precision"] = json!(precision);
                if variant == 1 {
                    body["samples"] = json!(4);
                    body["shadows"] = json!(true);
                    body["light_model"] = json!({ "two_side": true });
                    body["back_material"] = json!({ "diffuse": [0, 1, 0] });
                    body["region"] = json!({ "x": 8, "y": 4, "width": 17, "height": 9 });
                    body["encoding"] = json!("srgb");
                }
                let empty = variant == 2;
                if empty {
                    // Nothing to hit: no summary, every probe a miss.
                    body["objects"] = json!([]);
                }
                let scene =
                    scene::parse_render(&serde_json::to_vec(&body).unwrap(), &Limits::default())
                        .unwrap_or_else(|e| panic!("{body}: {e}"));
                let out = glint::render::render_json(&scene, &|| false).expect("not cancelled");
                let out = serde_json::to_value(out).unwrap();
                assert_valid(&response, "RenderJsonResponse", &out);
                documented("RenderJsonResponse", &out);
                documented("RenderStats", &out["stats"]);
                documented("RenderTerms", &out["terms"]);

                let (width, height) = if variant == 1 { (17, 9) } else { (32, 24) };
                assert_eq!(
                    (out["width"].as_u64(), out["height"].as_u64()),
                    (Some(width), Some(height))
                );
                let stats = &out["stats"];
                assert_eq!(
                    (
                        stats["width"].as_u64(),
                        stats["height"].as_u64(),
                        stats["pixels"].as_u64()
                    ),
                    (Some(width), Some(height), Some(width * height))
                );
                let png = base64::engine::general_purpose::STANDARD
                    .decode(out["png_base64"].as_str().unwrap())
                    .expect("png_base64 is base64");
                assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");

                let terms = &out["terms"];
                assert_eq!(terms.get("summary").is_some(), !empty, "{out}");
                let probes = terms["probes"].as_array().unwrap();
                assert_eq!(probes.len(), body["probes"].as_array().unwrap().len());
                for (probe, pixel) in probes.iter().zip(body["probes"].as_array().unwrap()) {
                    documented("Probe", probe);
                    assert_eq!(&probe["pixel"], pixel);
                    // As `Probe` says: a miss has neither, a hit has both.
                    assert_eq!(
                        probe["hit"].is_null(),
                        probe["breakdown"].is_null(),
                        "{probe}"
                    );
                    if !probe["hit"].is_null() {
                        documented("ProbeHit", &probe["hit"]);
                    }
                }
                // The last probe is on the background.
                let miss = probes.last().unwrap();
                assert!(
                    miss["hit"].is_null() && miss["breakdown"].is_null(),
                    "{miss}"
                );
                if !empty {
                    let hit = &probes[0]["hit"];
                    assert_eq!(hit["side"], "front", "{out}");
                    assert!(probes[0]["breakdown"].is_object(), "{out}");
                }

                let codes: Vec<&str> = out["warnings"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|w| w["code"].as_str().unwrap())
                    .collect();
                let expected: &[&str] = match (shading, empty) {
                    ("per_vertex", false) => &["per_pixel_fallback", "zero_normals"],
                    _ => &[],
                };
                assert_eq!(codes, expected, "{out}");
            }
        }
    }

    let refused = [
        json!({}),
        with_lights(json!([{ "spot": { "cutoff": 120 } }])),
        {
            let mut body = render_body();
            body["samples"] = json!(0);
            body
        },
        {
            let mut body = render_body();
            body["camera"]["width"] = json!(4000);
            body["camera"]["height"] = json!(4000);
            body
        },
        {
            let mut body = render_body();
            body["probes"] = json!([[32, 0]]);
            body
        },
    ];
    for body in refused {
        let e = scene::parse_render(&serde_json::to_vec(&body).unwrap(), &Limits::default())
            .expect_err("refused");
        let out = serde_json::to_value(glint::problem::Problem::from(&e)).unwrap();
        assert_problem(&doc, &problem, &out);
        let pointer = out["pointer"]
            .as_str()
            .expect("request errors carry a pointer");
        let parent = pointer.rsplit_once('/').map_or("", |(p, _)| p);
        assert!(body.pointer(parent).is_some(), "{pointer} is not in {body}");
    }
}

/// [`render_body`] with other lights.
fn with_lights(lights: Value) -> Value {
    let mut body = render_body();
    body["lights"] = lights;
    body
}

/// The HTTP service's own answers, over a loopback socket.
#[tokio::test]
async fn http_responses_validate() {
    let doc = document();
    let state = glint::http::AppState::new(&glint::config::ServeConfig::default()).unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    let app = axum::ServiceExt::<axum::extract::Request>::into_make_service(glint::http::app(
        state.clone(),
        &[],
    ));
    let server = tokio::spawn(axum::serve(listener, app).into_future());
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
    let served: Value = serde_norway::from_slice(&bytes).expect("YAML");
    assert_valid(
        &validator_in(&doc, "OpenApiDocument"),
        "OpenApiDocument",
        &served,
    );

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
        assert_problem(&doc, &problem, &body);
        assert_eq!(body["type"], format!("urn:glint:problem:{slug}"));
        assert!(
            doc["paths"]["/v1/shade"]["post"]["responses"]
                .get(expected.to_string())
                .is_some(),
            "{expected} is not documented for /v1/shade"
        );
    }
    // Renders: the PNG by default and whenever `Accept` does not prefer
    // JSON, the JSON form when it does; both vary on `Accept`.
    let render = |accept: Option<&'static str>, body: Value| {
        let mut request = client
            .post(format!("{base}/v1/render"))
            .header("content-type", "application/json")
            .body(serde_json::to_vec(&body).unwrap());
        if let Some(accept) = accept {
            request = request.header("accept", accept);
        }
        async move {
            let response = request.send().await.unwrap();
            let status = response.status();
            let headers = response.headers().clone();
            let bytes = response.bytes().await.unwrap();
            (status, headers, bytes)
        }
    };
    let ok = &doc["paths"]["/v1/render"]["post"]["responses"]["200"];
    assert!(
        ok["headers"].get("Vary").is_some(),
        "Vary is not documented"
    );
    let varies = |headers: &reqwest::header::HeaderMap| {
        headers
            .get_all("vary")
            .iter()
            .any(|v| v.to_str().unwrap().to_ascii_lowercase().contains("accept"))
    };
    for accept in [
        None,
        Some("image/png"),
        Some("*/*"),
        Some("image/png, application/json"),
    ] {
        let (status, headers, bytes) = render(accept, render_body()).await;
        assert_eq!(status, StatusCode::OK, "{accept:?}");
        assert!(ok["content"].get("image/png").is_some());
        assert_eq!(content_type(&headers), "image/png", "{accept:?}");
        assert!(headers.contains_key("x-request-id"));
        assert!(varies(&headers), "{accept:?}: no Vary: accept");
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{accept:?}: not a PNG"
        );
    }
    let render_json = validator_in(&doc, "RenderJsonResponse");
    for (accept, body, per_vertex) in [
        ("application/json", render_body(), false),
        ("application/json, */*", per_vertex_body(), true),
    ] {
        let (status, headers, bytes) = render(Some(accept), body).await;
        assert_eq!(status, StatusCode::OK, "{accept}");
        assert_eq!(content_type(&headers), "application/json", "{accept}");
        assert!(headers.contains_key("x-request-id"));
        assert!(varies(&headers), "{accept}: no Vary: accept");
        let out = json(&bytes);
        assert_valid(&render_json, "RenderJsonResponse", &out);
        assert_eq!(
            (out["width"].as_u64(), out["height"].as_u64()),
            (Some(32), Some(24))
        );
        let probes = out["terms"]["probes"].as_array().unwrap();
        assert_eq!(probes[0]["hit"]["object"], 0, "{out}");
        assert!(probes.last().unwrap()["hit"].is_null(), "{out}");
        let fallback = out["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "per_pixel_fallback");
        assert_eq!(fallback, per_vertex, "{out}");
    }
    let render_errors = [
        (
            with_lights(json!([{ "spot": { "cutoff": 120 } }])),
            422,
            "invalid",
            "/lights/0/spot/cutoff",
        ),
        (
            {
                let mut body = render_body();
                body["samples"] = json!(0);
                body
            },
            422,
            "invalid",
            "/samples",
        ),
        (
            {
                let mut body = render_body();
                body["camera"]["width"] = json!(4000);
                body["camera"]["height"] = json!(4000);
                body
            },
            413,
            "over-limit",
            "/camera",
        ),
        (
            {
                let mut body = render_body();
                body["colour"] = json!(1);
                body
            },
            400,
            "malformed",
            "/colour",
        ),
    ];
    for (body, expected, slug, pointer) in render_errors {
        for accept in [None, Some("application/json")] {
            let (status, headers, bytes) = render(accept, body.clone()).await;
            assert_eq!(status.as_u16(), expected, "{body}");
            assert_eq!(content_type(&headers), "application/problem+json");
            assert!(headers.contains_key("x-request-id"));
            let problem_body = json(&bytes);
            assert_problem(&doc, &problem, &problem_body);
            assert_eq!(problem_body["type"], format!("urn:glint:problem:{slug}"));
            assert_eq!(problem_body["pointer"], pointer, "{problem_body}");
            assert!(
                doc["paths"]["/v1/render"]["post"]["responses"]
                    .get(expected.to_string())
                    .is_some(),
                "{expected} is not documented for /v1/render"
            );
        }
    }

    let others = [
        (Method::GET, "/nowhere", 404, "not-found"),
        (Method::DELETE, "/v1/shade", 405, "method-not-allowed"),
    ];
    for (method, uri, expected, slug) in others {
        let (status, headers, bytes) =
            call(method, uri, Some("application/json"), shade_body.clone()).await;
        assert_eq!(status.as_u16(), expected, "{uri}");
        assert_eq!(content_type(&headers), "application/problem+json");
        let body = json(&bytes);
        assert_problem(&doc, &problem, &body);
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
    assert_problem(&doc, &problem, &json(&bytes));
    server.abort();
}

/// The JSON answers of `/v1/shade` with a model are `ShadeResponse`s with
/// `primitives`; the baked model's `extras.glint` holds what the contract
/// says, its `stats` a `ShadeStats`; the requests of the glTF tests are
/// `ModelShadeRequest`s, and the schema's fields are those the wire type
/// reads.
#[test]
fn real_model_responses_validate() {
    use glint::bake::{self, Form};
    let doc = document();
    let response = validator_in(&doc, "ShadeResponse");
    let stats = validator_in(&doc, "ShadeStats");
    let warning = validator_in(&doc, "Warning");
    let request_schema = validator_in(&doc, "ModelShadeRequest");
    let (model, _) = crate::gltf::bake::hierarchy();
    let glb = model.glb();
    for two_side in [false, true] {
        for terms in ["none", "summary", "per_vertex"] {
            let mut request = crate::gltf::bake::request();
            request["light_model"]["two_side"] = json!(two_side);
            request["terms"] = json!(terms);
            assert_valid(&request_schema, "ModelShadeRequest", &request);
            let body = serde_json::to_vec(&request).unwrap();
            for form in [Form::Json, Form::Glb] {
                let scene = scene::parse_bake(Some(&body), &glb, &Limits::default()).unwrap();
                let out = bake::bake(scene, form).body.to_vec(&glb);
                match form {
                    Form::Json => {
                        let out: Value = serde_json::from_slice(&out).unwrap();
                        assert_valid(&response, "ShadeResponse", &out);
                        assert!(out["primitives"].as_array().is_some_and(|p| !p.is_empty()));
                    }
                    Form::Glb => {
                        let glint = &crate::gltf::support::read_glb(&out).json["extras"]["glint"];
                        assert_valid(&stats, "ShadeStats", &glint["stats"]);
                        for w in glint["warnings"].as_array().unwrap() {
                            assert_valid(&warning, "Warning", w);
                        }
                        assert!(glint["modeled"].is_array() && glint["precision"].is_object());
                        assert_eq!(glint.get("summary").is_some(), terms != "none");
                    }
                }
            }
        }
    }
    // Every property of the schema is a field of the wire type: an object
    // of all of them parses.
    let properties = doc["components"]["schemas"]["ModelShadeRequest"]["properties"]
        .as_object()
        .unwrap();
    let mut all = crate::gltf::bake::request();
    all["back_material"] = json!({});
    all["precision"] = json!("fast");
    all["terms"] = json!("summary");
    all["color_space"] = json!("linear");
    all["color_format"] = json!("unorm8");
    let keys: Vec<&String> = all.as_object().unwrap().keys().collect();
    let mut names: Vec<&String> = properties.keys().collect();
    names.sort();
    let mut sorted = keys.clone();
    sorted.sort();
    assert_eq!(sorted, names);
    let body = serde_json::to_vec(&all).unwrap();
    scene::parse_bake(Some(&body), &glb, &Limits::default()).unwrap();
}

//! What the contract's tests share: the document (`api/openapi.yaml`) as
//! JSON and its schemas as validators, the table of problem types and their
//! statuses read from its own description, the requests the rules are tried
//! on, and one way to hold a body against both the schema and the code.

use glint::scene::{self, Limits, RequestError, RequestErrorKind, wire};
use serde_json::{Value, json};

/// The contract, as the repository holds it and the server serves it.
pub const DOCUMENT: &str = include_str!("../../api/openapi.yaml");

/// The document as JSON.
pub fn document() -> Value {
    serde_norway::from_str(DOCUMENT).expect("api/openapi.yaml is YAML")
}

/// The schema `name` of the document (`#/components/schemas/{name}`).
pub fn schema(name: &str) -> Value {
    document()["components"]["schemas"][name].clone()
}

/// A validator for `#/components/schemas/{name}` of `doc`: the schema is
/// compiled inside a root that holds the components, so that every
/// `#/components/schemas/...` reference resolves.
pub fn validator_in(doc: &Value, name: &str) -> jsonschema::Validator {
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

/// A validator for the schema `name` of the document.
pub fn validator(name: &str) -> jsonschema::Validator {
    validator_in(&document(), name)
}

/// Panics with every error when `instance` is not valid.
#[track_caller]
pub fn assert_valid(validator: &jsonschema::Validator, name: &str, instance: &Value) {
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

/// Each of `instances` is a valid `name` (a schema of the document).
#[track_caller]
pub fn assert_each_valid<'a>(name: &str, instances: impl IntoIterator<Item = &'a Value>) {
    let validator = validator(name);
    for instance in instances {
        assert_valid(&validator, name, instance);
    }
}

/// Every value under the key `key`, anywhere in `value`, with its location.
pub fn find_all<'a>(value: &'a Value, key: &str, at: String, out: &mut Vec<(String, &'a Value)>) {
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
pub fn deref<'a>(doc: &'a Value, value: &'a Value) -> &'a Value {
    match value.get("$ref").and_then(Value::as_str) {
        Some(r) => doc
            .pointer(r.strip_prefix('#').expect("a local reference"))
            .expect("the reference resolves"),
        None => value,
    }
}

/// Every operation of the document: its path, its method and itself.
pub fn operations(doc: &Value) -> Vec<(&str, &str, &Value)> {
    let mut all = Vec::new();
    for (path, item) in doc["paths"].as_object().unwrap() {
        for (method, operation) in item.as_object().unwrap() {
            if method != "parameters" {
                all.push((path.as_str(), method.as_str(), operation));
            }
        }
    }
    all
}

/// Every response of every operation: its path, `METHOD path status` for
/// messages, and the response (a shared one followed).
pub fn responses(doc: &Value) -> Vec<(&str, String, &Value)> {
    let mut all = Vec::new();
    for (path, method, operation) in operations(doc) {
        for (status, response) in operation["responses"].as_object().unwrap() {
            all.push((
                path,
                format!("{method} {path} {status}"),
                deref(doc, response),
            ));
        }
    }
    all
}

/// The status each problem `type` fixes, from the table of errors in the
/// document's description (`| 429 / 503 | `urn:glint:problem:busy` | ...`).
pub fn problem_statuses(doc: &Value) -> Vec<(String, Vec<u64>)> {
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
pub fn status_fits_type(doc: &Value, problem: &Value) -> Result<(), String> {
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
#[track_caller]
pub fn assert_problem(doc: &Value, validator: &jsonschema::Validator, problem: &Value) {
    assert_valid(validator, "Problem", problem);
    if let Err(e) = status_fits_type(doc, problem) {
        panic!("{e}");
    }
}

/// A problem of a refused request: a `Problem` whose status fits its type,
/// with a pointer that names a place in the body (or the whole body).
#[track_caller]
pub fn assert_problem_points_into(doc: &Value, error: &RequestError, body: &Value) {
    let problem = serde_json::to_value(glint::problem::Problem::from(error)).unwrap();
    assert_problem(doc, &validator_in(doc, "Problem"), &problem);
    let pointer = problem["pointer"]
        .as_str()
        .expect("request errors carry a pointer");
    let parent = pointer.rsplit_once('/').map_or("", |(p, _)| p);
    assert!(body.pointer(parent).is_some(), "{pointer} is not in {body}");
}

/// What the code must answer a body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Read and validated.
    Accepted,
    /// Refused as not of the schema (400), wherever the problem points.
    Malformed,
    /// Refused as invalid (422), the problem pointing here.
    Invalid(&'static str),
    /// Refused as past this server's configured limit (413), the problem
    /// pointing here.
    OverLimit(&'static str),
}

/// One body tried against a rule: a name for messages, the body, whether
/// the schema accepts it, and what the code must answer.
pub type Case = (&'static str, Value, bool, Verdict);

/// The code's `outcome` is the `verdict`.
#[track_caller]
fn assert_verdict(name: &str, body: &Value, verdict: Verdict, outcome: Result<(), RequestError>) {
    let outcome = outcome.map_err(|e| (e.kind, e.pointer));
    match verdict {
        Verdict::Accepted => assert_eq!(outcome, Ok(()), "{name}: the code, for {body}"),
        Verdict::Malformed => assert!(
            matches!(outcome, Err((RequestErrorKind::Malformed, _))),
            "{name}: the code, for {body}: {outcome:?}"
        ),
        Verdict::Invalid(at) => assert_eq!(
            outcome,
            Err((RequestErrorKind::Invalid, at.to_owned())),
            "{name}: the code, for {body}"
        ),
        Verdict::OverLimit(at) => assert_eq!(
            outcome,
            Err((RequestErrorKind::OverLimit, at.to_owned())),
            "{name}: the code, for {body}"
        ),
    }
}

/// The schema takes `body` exactly when `accepts`.
#[track_caller]
fn assert_schema(schema: &jsonschema::Validator, name: &str, body: &Value, accepts: bool) {
    assert_eq!(
        schema.is_valid(body),
        accepts,
        "{name}: the schema {} {body}",
        if accepts { "refuses" } else { "accepts" }
    );
}

/// What the code does with a shade body under `limits`.
fn shade_outcome(body: &Value, limits: &Limits) -> Result<(), RequestError> {
    scene::parse_shade(&serde_json::to_vec(body).unwrap(), limits).map(|_| ())
}

/// What the code does with a render body under `limits`.
pub fn render_outcome(body: &Value, limits: &Limits) -> Result<(), RequestError> {
    scene::parse_render(&serde_json::to_vec(body).unwrap(), limits).map(|_| ())
}

/// Whether a render body is read: parsed, and its JSON form's own fields
/// there (a request with a model may leave out its camera, materials and
/// objects).
fn render_parses(body: &Value) -> bool {
    scene::parse_json::<wire::RenderRequest>(&serde_json::to_vec(body).unwrap())
        .is_ok_and(|request| request.json_form().is_ok())
}

/// Each shade case: the schema `ShadeRequest` and the code (with the
/// default limits) answer as it says.
#[track_caller]
pub fn check_shade(cases: Vec<Case>) {
    let schema = validator("ShadeRequest");
    for (name, body, schema_accepts, verdict) in cases {
        assert_schema(&schema, name, &body, schema_accepts);
        assert_verdict(
            name,
            &body,
            verdict,
            shade_outcome(&body, &Limits::default()),
        );
    }
}

/// Each render case: the schema `RenderRequest` and the code answer as it
/// says under `limits`; the parser reads every body but a malformed one.
#[track_caller]
pub fn check_render_within(limits: &Limits, cases: Vec<Case>) {
    let schema = validator("RenderRequest");
    for (name, body, schema_accepts, verdict) in cases {
        assert_eq!(
            render_parses(&body),
            verdict != Verdict::Malformed,
            "{name}: the parser, for {body}"
        );
        assert_schema(&schema, name, &body, schema_accepts);
        assert_verdict(name, &body, verdict, render_outcome(&body, limits));
    }
}

/// A render the schema takes, past a limit this server sets lower (the
/// default limits as `lower` sets them): 413, the problem pointing at `at`.
#[track_caller]
pub fn check_render_past(
    lower: impl FnOnce(&mut Limits),
    name: &'static str,
    body: Value,
    at: &'static str,
) {
    let mut limits = Limits::default();
    lower(&mut limits);
    check_render_within(&limits, vec![(name, body, true, Verdict::OverLimit(at))]);
}

/// [`check_render_within`] the default limits.
#[track_caller]
pub fn check_render(cases: Vec<Case>) {
    check_render_within(&Limits::default(), cases);
}

/// A rule the schemas leave to a description (a value forbidden, or a field
/// tied to another): the description at `written_at` (a pointer into the
/// document) names the pointer of its 422, `pointer`, and so does the
/// document's own list of such rules. (Those 422s of schema-valid requests
/// are what `tests/clients/schemathesis.toml` declares to schemathesis.)
/// The rule's test holds a body that breaks it, which the schema takes and
/// the code refuses there.
#[track_caller]
pub fn assert_written(written_at: &str, pointer: &str) {
    let doc = document();
    let written = doc
        .pointer(written_at)
        .and_then(Value::as_str)
        .unwrap_or_else(|| panic!("no description at {written_at}"));
    let pointer = format!("`{pointer}`");
    assert!(
        written.contains(&pointer),
        "{written_at} does not name {pointer}: {written}"
    );
    let listed = doc["info"]["description"].as_str().unwrap();
    assert!(
        listed.contains(&pointer),
        "the document's list of such rules does not name {pointer}"
    );
}

/// A shade body of one vertex at the origin facing +z, with the members of
/// `extra` beside it.
pub fn one_vertex_with(extra: Value) -> Value {
    let mut body = json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] } });
    for (k, value) in extra.as_object().unwrap() {
        body[k] = value.clone();
    }
    body
}

/// [`one_vertex_with`] one light.
pub fn one_vertex_lit_by(light: Value) -> Value {
    one_vertex_with(json!({ "lights": [light] }))
}

/// The three corners of a triangle in the plane z = 0.
pub fn triangle() -> Value {
    json!([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
}

/// A render of one red sphere of radius 1 at the origin, 64×48 pixels,
/// seen from (0, 0, 5): the body the render rules are tried on.
pub fn one_sphere() -> Value {
    json!({
        "materials": { "red": { "diffuse": [1, 0, 0] } },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 64, "height": 48 },
        "objects": [{ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" }],
    })
}

/// [`one_sphere`] with its member `key` set to `value`.
pub fn one_sphere_with(key: &str, value: Value) -> Value {
    let mut body = one_sphere();
    body[key] = value;
    body
}

/// [`one_sphere`] with the camera's member `key` set to `value`.
pub fn one_sphere_camera(key: &str, value: Value) -> Value {
    let mut body = one_sphere();
    body["camera"][key] = value;
    body
}

/// [`one_sphere`]'s camera and material with `object` as the only object.
pub fn only_object(object: Value) -> Value {
    one_sphere_with("objects", json!([object]))
}

/// [`one_sphere`]'s camera and material with a red mesh as the only object.
pub fn only_mesh(mesh: Value) -> Value {
    only_object(json!({ "mesh": mesh, "material": "red" }))
}

/// A render of nothing, 8×6 pixels, seen from (0, 0, 5), with a material
/// `red` of GL's defaults, changed by `change`.
pub fn nothing_8x6(change: &dyn Fn(&mut Value)) -> Value {
    let mut body = json!({
        "materials": { "red": {} },
        "camera": { "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 8, "height": 6 },
        "objects": [],
    });
    change(&mut body);
    body
}

/// A small render: 32×24, a red sphere on a grey floor, a directional light
/// and a positional spotlight; probes on the sphere and on the background
/// (above the horizon).
pub fn sphere_on_a_floor() -> Value {
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

/// [`sphere_on_a_floor`] with `change` made to it.
pub fn sphere_on_a_floor_but(change: &dyn Fn(&mut Value)) -> Value {
    let mut body = sphere_on_a_floor();
    change(&mut body);
    body
}

/// A quad of two triangles (with normals, one of them zero) beside a
/// sphere: per-vertex shading lights the quad at its vertices and the
/// sphere per pixel.
pub fn quad_beside_a_sphere() -> Value {
    sphere_on_a_floor_but(&|body| {
        body["objects"] = json!([
            { "mesh": { "positions": [[-2, -1, 0], [0, -1, 0], [0, 1, 0], [-2, 1, 0]],
                        "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 0]],
                        "indices": [0, 1, 2, 0, 2, 3] },
              "material": "floor" },
            { "sphere": { "center": [1, 0, 0], "radius": 0.75 }, "material": "red" },
        ]);
        body["shading"] = json!("per_vertex");
        body["probes"] = json!([[10, 12], [24, 12], [0, 0]]);
    })
}

//! The document as a document: OpenAPI 3.1, every `$ref` resolving inside
//! it, the paths of the service, every request and response body a named
//! schema (so that tests and tools can validate real bodies by name), the
//! headers every answer documents, every named schema compiling as JSON
//! Schema 2020-12 with its examples valid, and the document itself valid
//! against the schema it names for `GET /openapi.yaml`.

use serde_json::Value;

use super::support::{
    assert_valid, deref, document, find_all, operations, responses, validator_in,
};

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
            "/v1/compare",
            "/v1/render",
            "/v1/shade"
        ]
    );
}

/// Every request and response body is a `$ref` to a named schema, so tests
/// can validate real bodies by name.
#[test]
fn every_body_is_a_named_schema() {
    let doc = document();
    let mut bodies = 0;
    for (path, method, operation) in operations(&doc) {
        let at = format!("{method} {path}");
        let mut contents = Vec::new();
        if let Some(body) = operation.get("requestBody") {
            contents.push((format!("{at} request"), &body["content"]));
        }
        for (status, response) in operation["responses"].as_object().unwrap() {
            contents.push((format!("{at} {status}"), &deref(&doc, response)["content"]));
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
    assert!(bodies >= 20, "only {bodies} bodies");
}

/// Each of `responses` (`(where, response)`) documents the header `header`.
#[track_caller]
fn assert_each_documents<'a>(
    header: &str,
    responses: impl IntoIterator<Item = (String, &'a Value)>,
) {
    for (at, response) in responses {
        assert!(
            response["headers"].get(header).is_some(),
            "{at}: no {header} header"
        );
    }
}

/// Every answer carries the request's id (`x-request-id`), and the document
/// says so of every response.
#[test]
fn every_response_documents_x_request_id() {
    let doc = document();
    let all = responses(&doc).into_iter().map(|(_, at, r)| (at, r));
    assert_each_documents("x-request-id", all);
}

/// A saturated server (429, or 503 from an operation of `/v1/`) says when
/// to try again: the document gives those responses `Retry-After`.
#[test]
fn every_busy_answer_documents_retry_after() {
    let doc = document();
    let busy: Vec<(String, &Value)> = responses(&doc)
        .into_iter()
        .filter(|(path, at, _)| {
            at.ends_with(" 429") || (at.ends_with(" 503") && path.starts_with("/v1/"))
        })
        .map(|(_, at, response)| (at, response))
        .collect();
    assert!(!busy.is_empty(), "no busy answer is documented");
    assert_each_documents("Retry-After", busy);
}

/// The schemas the tests validate real bodies against, by name.
#[test]
fn the_schemas_named_by_the_tests_exist() {
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
}

#[test]
fn every_schema_compiles_as_json_schema_2020_12() {
    let doc = document();
    for name in doc["components"]["schemas"].as_object().unwrap().keys() {
        validator_in(&doc, name);
    }
}

#[test]
fn every_schema_s_examples_validate() {
    let doc = document();
    for (name, schema) in doc["components"]["schemas"].as_object().unwrap() {
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

/// Regression: the schema of `GET /openapi.yaml` said a string, but a YAML
/// body is read as the data it holds, as tools read it: the document, an
/// object, failed its own schema.
#[test]
fn the_served_document_is_an_openapi_document() {
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

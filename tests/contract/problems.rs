//! The schema `Problem` (RFC 9457 problem details): what it takes and
//! refuses, and the status each problem `type` fixes, written in the table
//! of errors of the document's description and in the schema's own
//! description, and held by every problem the code makes.

use serde_json::{Value, json};

use super::support::{
    assert_problem, document, problem_statuses, schema, status_fits_type, validator_in,
};

/// `problem` is a `Problem` whose status fits its type.
#[track_caller]
fn assert_is_problem(problem: Value) {
    let doc = document();
    assert_problem(&doc, &validator_in(&doc, "Problem"), &problem);
}

#[test]
fn an_invalid_request_s_problem_with_its_pointer_is_a_problem() {
    assert_is_problem(json!({
        "type": "urn:glint:problem:invalid",
        "title": "Invalid request",
        "status": 422,
        "detail": "a spot cutoff must be 180 or lie in [0, 90], not 120",
        "pointer": "/lights/2/spot/cutoff",
    }));
}

#[test]
fn a_problem_without_a_pointer_is_a_problem() {
    assert_is_problem(
        json!({ "type": "urn:glint:problem:busy", "title": "Busy", "status": 429, "detail": "later" }),
    );
}

#[test]
fn a_problem_s_type_is_one_of_glint_s() {
    let problem = validator_in(&document(), "Problem");
    let wrong = json!({ "type": "about:blank", "title": "x", "status": 400, "detail": "x" });
    assert!(!problem.is_valid(&wrong), "{wrong} is accepted");
}

#[test]
fn a_problem_has_a_detail() {
    let problem = validator_in(&document(), "Problem");
    let wrong = json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422 });
    assert!(!problem.is_valid(&wrong), "{wrong} is accepted");
}

#[test]
fn a_problem_s_pointer_is_a_json_pointer() {
    let problem = validator_in(&document(), "Problem");
    let wrong = json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 422,
                        "detail": "x", "pointer": "lights.2" });
    assert!(!problem.is_valid(&wrong), "{wrong} is accepted");
}

/// The status a type fixes is written in the description of `Problem`, as
/// in the table of errors.
#[test]
fn the_problem_schema_writes_the_status_of_each_type() {
    let problem = schema("Problem");
    let written = problem["description"].as_str().unwrap();
    for (kind, statuses) in problem_statuses(&document()) {
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
}

/// The check every real problem meets (`assert_problem`): a type with
/// another class's status breaks it.
#[test]
fn a_problem_s_status_is_the_one_its_type_fixes() {
    let doc = document();
    assert_is_problem(
        json!({ "type": "urn:glint:problem:busy", "title": "x", "status": 429, "detail": "x" }),
    );
    let wrong =
        json!({ "type": "urn:glint:problem:invalid", "title": "x", "status": 400, "detail": "x" });
    assert!(status_fits_type(&doc, &wrong).is_err(), "{wrong} passes");
}

/// The problems the service makes of itself, not of a request.
#[test]
fn the_busy_and_internal_problems_are_problems() {
    for made in [
        glint::problem::Problem::busy(),
        glint::problem::Problem::internal(),
    ] {
        assert_is_problem(serde_json::to_value(made).unwrap());
    }
}

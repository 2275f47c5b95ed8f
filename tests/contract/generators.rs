//! The schemas keep to the JSON Schema that client generators and test
//! tools read: openapi-python-client refused the document for a `not`,
//! schemathesis could generate no request past an `if`/`then`, and a number
//! `enum` or a union of `const`s became generated code that refuses real
//! answers. The rules those forms held are written in descriptions instead
//! (each checked with its rule: `assert_written`).

use serde_json::Value;

use super::support::{document, find_all};

/// Where `key` stands in the schemas as a keyword, not as the name of a
/// property.
fn keyword(key: &str) -> Vec<(String, Value)> {
    let doc = document();
    let mut found = Vec::new();
    find_all(
        &doc["components"]["schemas"],
        key,
        String::new(),
        &mut found,
    );
    found
        .into_iter()
        .filter(|(at, _)| !at.ends_with(&format!("/properties/{key}")))
        .map(|(at, value)| (at, value.clone()))
        .collect()
}

#[test]
fn no_schema_uses_if_then_else_not_one_of_or_all_of() {
    for key in ["if", "then", "else", "not", "oneOf", "allOf"] {
        let found: Vec<String> = keyword(key).into_iter().map(|(at, _)| at).collect();
        assert!(found.is_empty(), "`{key}` at {found:?}");
    }
}

#[test]
fn every_any_of_is_null_or_a_named_schema_or_two_named_schemas() {
    // A union of named schemas is a generated client's union of its types.
    for (at, branches) in keyword("anyOf") {
        let branches = branches.as_array().unwrap();
        let null = branches.iter().filter(|b| b["type"] == "null").count();
        let named = branches.iter().filter(|b| b.get("$ref").is_some()).count();
        assert!(
            branches.len() == 2 && null + named == 2 && null <= 1,
            "{at}: anyOf is not `null` or a named schema, nor two named schemas"
        );
    }
}

#[test]
fn every_enum_is_of_strings() {
    for (at, values) in keyword("enum") {
        assert!(
            values.as_array().unwrap().iter().all(Value::is_string),
            "{at}: an enum of non-strings"
        );
    }
}

#[test]
fn every_const_is_a_string() {
    for (at, value) in keyword("const") {
        assert!(value.is_string(), "{at}: a const that is not a string");
    }
}

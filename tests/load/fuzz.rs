//! The fuzz target of CI: the request parsers on arbitrary bytes, on valid
//! requests mutated byte by byte, and on valid requests with any field
//! swapped for a strange value. They never panic; every refusal names its
//! field by a well-formed JSON Pointer, one that exists in the document when
//! the document is JSON; and whatever `parse_shade` accepts is lit to
//! colours in [0, 1].
//!
//! `GLINT_FUZZ_CASES` raises the case count of each property (2000 by
//! default, to keep CI quick) for a longer hunt.

use glint::scene::{Limits, RequestError, parse_render, parse_shade};
use proptest::prelude::*;
use proptest::sample::Index;
use serde_json::{Value, json};

use crate::support::Rng;

fn cases() -> u32 {
    std::env::var("GLINT_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(2000)
}

/// RFC 6901: empty, or `/`-separated tokens in which `~` only escapes `0`
/// or `1`.
fn is_json_pointer(pointer: &str) -> bool {
    if pointer.is_empty() {
        return true;
    }
    pointer.starts_with('/')
        && pointer
            .split('~')
            .skip(1)
            .all(|rest| rest.starts_with('0') || rest.starts_with('1'))
}

/// The checks every refusal passes; `document` is the body as JSON, if it
/// is JSON.
fn check_error(e: &RequestError, document: Option<&Value>) -> Result<(), TestCaseError> {
    prop_assert!(is_json_pointer(&e.pointer), "not a JSON Pointer: {e:?}");
    prop_assert!(!e.detail.is_empty(), "a refusal says why: {e:?}");
    if let Some(document) = document {
        prop_assert!(
            document.pointer(&e.pointer).is_some(),
            "the pointer of {e:?} is not in the document {document}"
        );
    }
    Ok(())
}

/// Both parsers on `body`; whatever `parse_shade` accepts is lit too.
fn check_body(body: &[u8]) -> Result<(), TestCaseError> {
    // A body serde_json reads is a document the pointer must exist in.
    let document: Option<Value> = serde_json::from_slice(body).ok();
    let limits = Limits::default();
    match parse_shade(body, &limits) {
        Err(e) => check_error(&e, document.as_ref())?,
        Ok(scene) => {
            let response = glint::shade::shade(&scene);
            prop_assert_eq!(response.colors.len(), scene.positions.len());
            let all = response
                .colors
                .iter()
                .chain(response.back_colors.iter().flatten());
            for color in all {
                prop_assert!(
                    color.to_array().iter().all(|c| (0.0..=1.0).contains(c)),
                    "a colour out of [0, 1]: {color:?} for {}",
                    String::from_utf8_lossy(body)
                );
            }
        }
    }
    if let Err(e) = parse_render(body, &limits) {
        check_error(&e, document.as_ref())?;
    }
    Ok(())
}

/// A small valid `/v1/shade` request from `seed`.
fn shade_seed(seed: u64) -> Value {
    Rng::new(seed).shade_request(4)
}

/// A small valid `/v1/render` request using every field of the contract.
fn render_seed(seed: u64) -> Value {
    let mut rng = Rng::new(seed);
    json!({
        "light_model": { "two_side": rng.chance(0.5), "local_viewer": rng.chance(0.5) },
        "materials": { "red": { "diffuse": [1, 0, 0] }, "floor": { "specular": [1, 1, 1], "shininess": 8 } },
        "back_material": { "emission": [0.1, 0, 0] },
        "lights": [rng.light(), rng.light()],
        "camera": { "eye": [0, 1, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 8, "height": 6 },
        "objects": [
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "red" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "floor" },
            { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                        "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]],
                        "indices": [0, 1, 2] }, "material": "red" }
        ],
        "background": [0, 0, 0, 1],
        "shading": "per_vertex",
        "samples": 2,
        "shadows": true,
        "precision": "fast",
        "region": { "x": 1, "y": 1, "width": 4, "height": 3 },
        "probes": [[0, 0], [7, 5]],
        "encoding": "srgb"
    })
}

/// Every node of `value`, by pointer.
fn pointers(value: &Value, at: String, out: &mut Vec<String>) {
    match value {
        Value::Object(map) => {
            for (key, child) in map {
                let token = key.replace('~', "~0").replace('/', "~1");
                pointers(child, format!("{at}/{token}"), out);
            }
        }
        Value::Array(items) => {
            for (i, child) in items.iter().enumerate() {
                pointers(child, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
    out.push(at);
}

/// Values a careless or hostile client might put anywhere.
fn strange_value() -> impl Strategy<Value = Value> {
    let fixed: Vec<Value> = vec![
        json!(null),
        json!(true),
        json!(0),
        json!(-0.0),
        json!(-1),
        json!(0.5),
        json!(90),
        json!(120),
        json!(180),
        json!(1e30),
        json!(1e31),
        json!(-1e308),
        json!(5e-324),
        json!(u64::MAX),
        json!(i64::MIN),
        json!(""),
        json!("reference"),
        json!("~1/"),
        json!([]),
        json!([0]),
        json!([0, 0]),
        json!([0, 0, 0]),
        json!([0, 0, 0, 0]),
        json!([1, 1, 1, 1, 1]),
        json!([[0, 0, 0]]),
        json!({}),
        json!({ "unknown": 1 }),
    ];
    prop_oneof![
        3 => proptest::sample::select(fixed),
        1 => any::<f64>()
            .prop_filter("JSON numbers are finite", |x| x.is_finite())
            .prop_map(|x| json!(x)),
        1 => (-1e7f64..1e7).prop_map(|x| json!([x, -x, x / 3.0])),
    ]
}

/// Byte edits: overwrite, insert, or delete at a position.
#[derive(Clone, Debug)]
enum Edit {
    Set(Index, u8),
    Insert(Index, u8),
    Delete(Index),
}

fn json_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        4 => proptest::sample::select(b"{}[]\":,0123456789.eE+- \\nulltrue~/".to_vec()),
        1 => any::<u8>(),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<Index>(), json_byte()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<Index>(), json_byte()).prop_map(|(i, b)| Edit::Insert(i, b)),
        any::<Index>().prop_map(Edit::Delete),
    ]
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        match *e {
            Edit::Set(ref i, b) if !bytes.is_empty() => {
                let i = i.index(bytes.len());
                bytes[i] = b;
            }
            Edit::Insert(ref i, b) => {
                let i = i.index(bytes.len() + 1);
                bytes.insert(i, b);
            }
            Edit::Delete(ref i) if !bytes.is_empty() => {
                let i = i.index(bytes.len());
                bytes.remove(i);
            }
            _ => {}
        }
    }
    bytes
}

/// A node swapped, dropped, or given an unknown sibling.
#[derive(Clone, Debug)]
enum Swap {
    Replace(Index, Value),
    Remove(Index),
    AddUnknown(Index),
}

fn swap() -> impl Strategy<Value = Swap> {
    prop_oneof![
        4 => (any::<Index>(), strange_value()).prop_map(|(i, v)| Swap::Replace(i, v)),
        1 => any::<Index>().prop_map(Swap::Remove),
        1 => any::<Index>().prop_map(Swap::AddUnknown),
    ]
}

fn apply_swaps(mut document: Value, swaps: &[Swap]) -> Value {
    for s in swaps {
        let mut all = Vec::new();
        pointers(&document, String::new(), &mut all);
        let (Swap::Replace(i, _) | Swap::Remove(i) | Swap::AddUnknown(i)) = s;
        let at = all[i.index(all.len())].clone();
        match s {
            Swap::Replace(_, value) => match document.pointer_mut(&at) {
                Some(node) => *node = value.clone(),
                None => unreachable!("{at} was listed"),
            },
            Swap::Remove(_) => {
                let Some((parent, last)) = at.rsplit_once('/') else {
                    continue; // the root stays
                };
                match document.pointer_mut(parent) {
                    Some(Value::Object(map)) => {
                        map.remove(&last.replace("~1", "/").replace("~0", "~"));
                    }
                    Some(Value::Array(items)) => {
                        items.remove(last.parse::<usize>().unwrap());
                    }
                    _ => unreachable!("the parent of {at} is a container"),
                }
            }
            Swap::AddUnknown(_) => {
                if let Some(Value::Object(map)) = document.pointer_mut(&at) {
                    map.insert("colour".into(), json!(1));
                }
            }
        }
    }
    document
}

#[test]
fn the_seeds_are_valid_requests() {
    for seed in 0..50 {
        let body = shade_seed(seed).to_string();
        parse_shade(body.as_bytes(), &Limits::default()).unwrap();
        let body = render_seed(seed).to_string();
        parse_render(body.as_bytes(), &Limits::default()).unwrap();
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn fuzz_request_parsers_on_arbitrary_bytes(body in proptest::collection::vec(any::<u8>(), 0..512)) {
        check_body(&body)?;
    }

    #[test]
    fn fuzz_request_parsers_on_byte_edits_of_valid_requests(
        seed in any::<u64>(),
        render in any::<bool>(),
        edits in proptest::collection::vec(edit(), 1..8),
    ) {
        let document = if render { render_seed(seed) } else { shade_seed(seed) };
        check_body(&apply(document.to_string().into_bytes(), &edits))?;
    }

    #[test]
    fn fuzz_request_parsers_on_valid_requests_with_strange_fields(
        seed in any::<u64>(),
        render in any::<bool>(),
        swaps in proptest::collection::vec(swap(), 1..4),
    ) {
        let document = if render { render_seed(seed) } else { shade_seed(seed) };
        check_body(apply_swaps(document, &swaps).to_string().as_bytes())?;
    }
}

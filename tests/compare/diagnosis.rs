//! The diagnosis over HTTP: each deviation's candidate is explained by that
//! deviation first; GL's colours by none, within the bound; noise by none.

use serde_json::{Value, json};

use super::{DEVIATIONS, every_term, scene_for};
use crate::http::TestServer;
use crate::support::Rng;

/// The answer of `/v1/compare` to `body`, which must be a `200`.
async fn compared(server: &TestServer, body: &Value) -> Value {
    let response = server.post_json("/v1/compare", body).await;
    assert_eq!(response.status(), 200);
    response.json().await.unwrap()
}

/// The names of an explanation's deviations.
pub(super) fn names(explanation: &Value) -> Vec<&str> {
    explanation["deviations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap())
        .collect()
}

#[tokio::test]
async fn each_deviation_s_candidate_is_explained_by_it_first() {
    let server = TestServer::start().await;
    let mut failures = Vec::new();
    for deviation in DEVIATIONS {
        let body = scene_for(deviation).compare(&[deviation], "reference");
        let answer = compared(&server, &body).await;
        let diagnosis = answer["diagnosis"].as_array().unwrap();
        let first = diagnosis.first();
        let ok = !answer["error"]["within_bound"].as_bool().unwrap()
            && first.is_some_and(|e| names(e) == [deviation] && e["explains"] == true);
        if !ok {
            failures.push(format!(
                "{deviation}: error {}, first {}",
                answer["error"],
                first.map_or("none".to_owned(), Value::to_string)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[tokio::test]
async fn a_pair_of_deviations_is_explained_by_the_pair() {
    let server = TestServer::start().await;
    let pair = ["attenuation_ignored", "emission_missing"];
    let answer = compared(&server, &every_term().compare(&pair, "reference")).await;
    let first = &answer["diagnosis"][0];
    let mut found = names(first);
    found.sort_unstable();
    assert_eq!(found, pair, "{answer}");
    assert_eq!(first["explains"], true, "{answer}");
    // No single deviation explains it.
    let singles = answer["diagnosis"].as_array().unwrap();
    assert!(
        singles
            .iter()
            .filter(|e| names(e).len() == 1)
            .all(|e| e["explains"] == false),
        "{answer}"
    );
}

#[tokio::test]
async fn gl_s_own_colours_are_within_the_bound_and_explained_by_nothing() {
    let server = TestServer::start().await;
    for precision in ["reference", "accurate", "fast"] {
        let answer = compared(&server, &every_term().compare(&[], precision)).await;
        assert_eq!(
            answer["error"]["within_bound"], true,
            "{precision}: {answer}"
        );
        let bound = answer["precision"]["max_abs_error"].as_f64().unwrap();
        assert!(answer["error"]["max_abs"].as_f64().unwrap() <= bound);
        let diagnosis = answer["diagnosis"].as_array().unwrap();
        assert!(
            diagnosis.iter().all(|e| e["explains"] == false),
            "{precision}: {answer}"
        );
    }
}

#[tokio::test]
async fn noise_is_explained_by_no_deviation() {
    let server = TestServer::start().await;
    let scene = every_term();
    let mut body = scene.compare(&[], "accurate");
    let mut rng = Rng::new(31);
    let noisy: Vec<[f64; 4]> = scene
        .colors(&[], false)
        .into_iter()
        .map(|[r, g, b, a]| {
            let mut noise = || rng.uniform(-0.02, 0.02);
            [r + noise(), g + noise(), b + noise(), a]
        })
        .collect();
    body["candidate"] = json!({ "colors": noisy });
    let answer = compared(&server, &body).await;
    assert_eq!(answer["error"]["within_bound"], false, "{answer}");
    let max = answer["error"]["max_abs"].as_f64().unwrap();
    assert!(max > 0.01 && max <= 0.02 + 1e-5, "{answer}");
    assert!(
        answer["diagnosis"]
            .as_array()
            .unwrap()
            .iter()
            .all(|e| e["explains"] == false),
        "{answer}"
    );
}

#[tokio::test]
async fn the_worst_vertices_are_the_largest_errors_with_their_terms() {
    let server = TestServer::start().await;
    let scene = every_term();
    let mut body = scene.compare(&[], "reference");
    // Three vertices moved by known amounts.
    let moved = [(17usize, 0.3), (101, 0.2), (5, 0.1)];
    for (k, by) in moved {
        let red = body["candidate"]["colors"][k][0].as_f64().unwrap();
        body["candidate"]["colors"][k][0] = json!(red - by);
    }
    body["worst"] = json!(3);
    let answer = compared(&server, &body).await;
    let worst = answer["worst"].as_array().unwrap();
    assert_eq!(worst.len(), 3, "{answer}");
    for (entry, (k, by)) in worst.iter().zip(moved) {
        assert_eq!(entry["vertex"], k, "{answer}");
        let error = entry["error"].as_f64().unwrap();
        assert!((error - by).abs() < 1e-6, "{entry}");
        let expected = scene.color(&[], k, false);
        let gl = entry["expected"][0].as_f64().unwrap();
        assert!((gl - expected[0]).abs() < 1e-6, "{entry}");
        // The breakdown's unclamped sum is GL's colour (nothing clamps here).
        let sum = entry["breakdown"]["unclamped"][0].as_f64().unwrap();
        assert!((sum - expected[0]).abs() < 1e-6, "{entry}");
        assert_eq!(entry["breakdown"]["lights"].as_array().unwrap().len(), 3);
    }
    let max = answer["error"]["max_abs"].as_f64().unwrap();
    assert!((max - 0.3).abs() < 1e-6, "{answer}");
}

//! Precision asked for as an error budget, `{"max_abs_error": E}`: the
//! cheapest tier whose documented bound is at most `E` evaluates the
//! request, and the answer says which; a budget no tier meets is 422 with
//! its pointer. The bounds are the contract's: 1/512 for `fast`, 1e-5 for
//! `accurate`, 2^-24 (the f32 rounding of the output) for `reference`.

use serde_json::{Value, json};

use super::{TestServer, client, expect_problem, one_vertex};

const FAST: f64 = 1.0 / 512.0;
const ACCURATE: f64 = 1e-5;
const REFERENCE: f64 = 5.960_464_477_539_063e-8;

/// `body` with its precision set to the budget `e`.
fn budgeted(mut body: Value, e: f64) -> Value {
    body["precision"] = json!({ "max_abs_error": e });
    body
}

fn render_body() -> Value {
    json!({
        "materials": { "m": {} },
        "lights": [{}],
        "camera": { "eye": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": 8, "height": 6 },
        "objects": [{ "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "m" }],
    })
}

#[tokio::test]
async fn a_budget_picks_the_cheapest_tier_within_it() {
    let server = TestServer::start().await;
    let cases = [
        (0.1, "fast", FAST),
        (FAST, "fast", FAST),
        (FAST * 0.999, "accurate", ACCURATE),
        (ACCURATE, "accurate", ACCURATE),
        (ACCURATE * 0.999, "reference", REFERENCE),
        (REFERENCE, "reference", REFERENCE),
    ];
    for (e, mode, bound) in cases {
        for (path, body) in [("/v1/shade", one_vertex()), ("/v1/render", render_body())] {
            let response = client()
                .post(server.url(path))
                .header("accept", "application/json")
                .json(&budgeted(body, e))
                .send()
                .await
                .unwrap();
            assert_eq!(response.status(), 200, "{path}, budget {e}");
            let answer: Value = response.json().await.unwrap();
            assert_eq!(answer["precision"]["mode"], mode, "{path}, budget {e}");
            assert_eq!(
                answer["precision"]["max_abs_error"].as_f64(),
                Some(bound),
                "{path}, budget {e}"
            );
        }
    }
}

#[tokio::test]
async fn a_budget_no_tier_meets_is_422_at_its_pointer() {
    let server = TestServer::start().await;
    for e in [REFERENCE * 0.5, 1e-300, 0.0, -1.0] {
        let response = server
            .post_json("/v1/shade", &budgeted(one_vertex(), e))
            .await;
        expect_problem(response, 422, "invalid", Some("/precision/max_abs_error")).await;
    }
    for bad in [
        json!({ "max_abs_error": "small" }),
        json!({ "max_error": 0.01 }),
        json!({}),
    ] {
        let mut body = one_vertex();
        body["precision"] = bad;
        let response = server.post_json("/v1/shade", &body).await;
        expect_problem(response, 400, "malformed", None).await;
    }
}

#[test]
fn the_command_line_takes_a_budget_in_place_of_the_requests_precision() {
    let dir = crate::support::Scratch::new("budget-cli");
    let file = dir.path().join("request.json");
    let mut request = one_vertex();
    request["precision"] = json!("reference");
    std::fs::write(&file, request.to_string()).unwrap();
    let glint = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .args(args)
            .output()
            .unwrap()
    };
    let file = file.to_str().unwrap();
    let output = glint(&["shade", file, "--max-abs-error", "0.001"]);
    assert!(output.status.success(), "{output:?}");
    let answer: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(answer["precision"]["mode"], "accurate");
    let output = glint(&["shade", file, "--max-abs-error", "1e-12"]);
    assert_eq!(output.status.code(), Some(1));
    let problem: Value = serde_json::from_slice(&output.stderr).unwrap();
    assert_eq!(problem["pointer"], "/precision/max_abs_error", "{problem}");
}

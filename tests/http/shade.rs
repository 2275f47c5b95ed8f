//! `POST /v1/shade` answers: colours, breakdowns and the response's fields.

use serde_json::{Value, json};

use super::{TestServer, one_vertex};

#[tokio::test]
async fn lights_a_vertex_as_the_spec_says() {
    let server = TestServer::start().await;
    let response = server.post_json("/v1/shade", &one_vertex()).await;
    assert_eq!(response.status(), 200);
    assert_eq!(response.headers()["content-type"], "application/json");
    let body: Value = response.json().await.unwrap();
    // a_cm·a_cs + (n·VP) d_cm·d_cli = 0.2·0.2 + 1·0.8·1 = 0.84; specular 0.
    for (channel, value) in body["colors"][0].as_array().unwrap().iter().enumerate() {
        let expected = if channel == 3 { 1.0 } else { 0.84 };
        assert!((value.as_f64().unwrap() - expected).abs() < 1e-6, "{body}");
    }
    assert_eq!(body["precision"]["mode"], "accurate");
    assert_eq!(body["precision"]["max_abs_error"], 1e-5);
    assert_eq!(body["stats"]["vertices"], 1);
    assert_eq!(body["stats"]["lights"], 1);
    assert!(body.get("back_colors").is_none() && body.get("terms").is_none());
    assert_eq!(
        body["modeled"],
        json!(["global_ambient", "lights[0].diffuse"])
    );
    assert_eq!(body["warnings"], json!([]));
}

#[tokio::test]
async fn answers_as_the_offline_engine_does_in_every_precision() {
    let server = TestServer::start().await;
    let scene: Value = serde_json::from_str(include_str!("../../examples/triangle.json")).unwrap();
    for precision in ["reference", "accurate", "fast"] {
        let mut request = scene.clone();
        request["precision"] = json!(precision);
        request["terms"] = json!("per_vertex");
        let response = server.post_json("/v1/shade", &request).await;
        assert_eq!(response.status(), 200);
        let body: Value = response.json().await.unwrap();

        let offline = glint::scene::parse_shade(
            request.to_string().as_bytes(),
            &glint::scene::Limits::default(),
        )
        .unwrap();
        let text = serde_json::to_vec(&glint::shade::shade(&offline)).unwrap();
        let mut expected: Value = serde_json::from_slice(&text).unwrap();
        // Timing is the one field that differs between two runs.
        expected["stats"]["compute_ms"] = body["stats"]["compute_ms"].clone();
        assert_eq!(body, expected, "{precision}");
    }
}

#[tokio::test]
async fn two_sided_lighting_returns_back_colours_and_back_terms() {
    let server = TestServer::start().await;
    let mut request = one_vertex();
    request["light_model"] = json!({ "two_side": true });
    request["back_material"] = json!({ "emission": [0.5, 0.0, 0.0] });
    request["terms"] = json!("summary");
    let body: Value = server
        .post_json("/v1/shade", &request)
        .await
        .json()
        .await
        .unwrap();
    // The back side's normal is -z, away from the light: emission 0.5 plus
    // the back material's default ambient 0.2·0.2.
    let back = &body["back_colors"][0];
    assert!((back[0].as_f64().unwrap() - 0.54).abs() < 1e-6, "{body}");
    assert!((back[1].as_f64().unwrap() - 0.04).abs() < 1e-6, "{body}");
    assert_eq!(body["terms"]["back"]["summary"]["vertices"], 1);
    assert_eq!(
        body["terms"]["summary"]["lights"][0]["diffuse"]["max"][0],
        0.8
    );
}

#[tokio::test]
async fn a_zero_normal_is_lit_by_ambient_only_and_warned_about() {
    let server = TestServer::start().await;
    let request = json!({
        "lights": [{}],
        "vertices": { "positions": [[0, 0, 0], [1, 0, 0]], "normals": [[0, 0, 0], [0, 0, 1]] }
    });
    let body: Value = server
        .post_json("/v1/shade", &request)
        .await
        .json()
        .await
        .unwrap();
    assert!((body["colors"][0][0].as_f64().unwrap() - 0.04).abs() < 1e-6);
    assert_eq!(body["warnings"][0]["code"], "zero_normals");
    assert_eq!(body["warnings"][0]["count"], 1);
}

#[tokio::test]
async fn a_view_puts_the_infinite_viewer_from_target_to_eye() {
    let server = TestServer::start().await;
    // Light and viewer both along +x in world space, normal +x: the halfway
    // vector is the normal, so n·ĥ = 1 and the specular term is s_cm·s_cli.
    let request = json!({
        "material": { "diffuse": [0, 0, 0], "ambient": [0, 0, 0], "specular": [0.5, 0.5, 0.5], "shininess": 10 },
        "lights": [{ "position": [1, 0, 0, 0] }],
        "view": { "eye": [10, 0, 0], "target": [0, 0, 0] },
        "vertices": { "positions": [[0, 0, 0]], "normals": [[1, 0, 0]] }
    });
    let body: Value = server
        .post_json("/v1/shade", &request)
        .await
        .json()
        .await
        .unwrap();
    assert!(
        (body["colors"][0][0].as_f64().unwrap() - 0.5).abs() < 1e-6,
        "{body}"
    );
}

#[tokio::test]
async fn an_empty_batch_is_answered() {
    let server = TestServer::start().await;
    let request = json!({ "vertices": { "positions": [], "normals": [] }, "terms": "summary" });
    let response = server.post_json("/v1/shade", &request).await;
    assert_eq!(response.status(), 200);
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["colors"], json!([]));
    assert!(body["terms"].get("summary").is_none());
}

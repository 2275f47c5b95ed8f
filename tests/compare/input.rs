//! Bad compares: each a problem+json at its pointer, never a panic.

use serde_json::json;

use super::every_term;
use crate::http::{TestServer, expect_problem};

#[tokio::test]
async fn bad_candidates_are_refused_at_their_pointer() {
    let server = TestServer::start().await;
    let scene = every_term();
    let good = scene.compare(&[], "accurate");
    let vertices = scene.positions.len();
    let mut cases = Vec::new();
    let mut short = good.clone();
    short["candidate"]["colors"].as_array_mut().unwrap().pop();
    cases.push((short, 422, "invalid", "/candidate/colors".to_owned()));
    let mut long = good.clone();
    long["candidate"]["colors"]
        .as_array_mut()
        .unwrap()
        .push(json!([0, 0, 0, 1]));
    cases.push((long, 422, "invalid", "/candidate/colors".to_owned()));
    // JSON has no NaN, and a number past f32's range is refused as it is
    // read.
    let mut huge = good.clone();
    huge["candidate"]["colors"][7][2] = json!(1e300);
    cases.push((huge, 400, "malformed", "/candidate/colors/7/2".to_owned()));
    // Within f32's range but past the contract's [-1e6, 1e6]: the error's
    // sums would leave f32's range (f32::MAX is 3.4e38), so it is refused.
    let mut large = good.clone();
    large["candidate"]["colors"][5][0] = json!(-3.4e38);
    cases.push((large, 422, "invalid", "/candidate/colors/5/0".to_owned()));
    let mut edge = good.clone();
    edge["candidate"]["colors"][6][1] = json!(1_000_001);
    cases.push((edge, 422, "invalid", "/candidate/colors/6/1".to_owned()));
    let mut null = good.clone();
    null["candidate"]["colors"][3][1] = json!(null);
    cases.push((null, 400, "malformed", "/candidate/colors/3/1".to_owned()));
    let mut three = good.clone();
    three["candidate"]["colors"][4] = json!([0.5, 0.5, 0.5]);
    cases.push((three, 400, "malformed", "/candidate/colors/4".to_owned()));
    let mut back = good.clone();
    back["candidate"]["back_colors"] = good["candidate"]["colors"].clone();
    cases.push((back, 422, "invalid", "/candidate/back_colors".to_owned()));
    let mut missing = good.clone();
    missing.as_object_mut().unwrap().remove("candidate");
    cases.push((missing, 400, "malformed", String::new()));
    let mut unknown = good.clone();
    unknown["candidate"]["colours"] = json!([]);
    cases.push((unknown, 400, "malformed", "/candidate/colours".to_owned()));
    let mut worst = good.clone();
    worst["worst"] = json!(1001);
    cases.push((worst, 422, "invalid", "/worst".to_owned()));
    let mut claimed = good.clone();
    claimed["worst"] = json!(u64::MAX);
    cases.push((claimed, 422, "invalid", "/worst".to_owned()));
    let mut tolerance = good.clone();
    tolerance["tolerance"] = json!(0);
    cases.push((tolerance, 422, "invalid", "/tolerance".to_owned()));
    let mut terms = good.clone();
    terms["terms"] = json!("summary");
    cases.push((terms, 400, "malformed", "/terms".to_owned()));
    for (body, status, kind, pointer) in cases {
        let response = server.post_json("/v1/compare", &body).await;
        expect_problem(response, status, kind, Some(&pointer)).await;
    }
    assert!(vertices > 8);
}

#[tokio::test]
async fn a_shade_refuses_the_fields_of_a_compare() {
    let server = TestServer::start().await;
    let mut body = every_term().compare(&[], "accurate");
    body.as_object_mut().unwrap().remove("precision");
    let response = server.post_json("/v1/shade", &body).await;
    expect_problem(response, 400, "malformed", Some("/candidate")).await;
}

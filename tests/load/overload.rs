//! Past its capacity the server sheds load at once with 503 and
//! `Retry-After`, answers the requests it took in full, and recovers.

use std::time::{Duration, Instant};

use serde_json::Value;

use super::{assert_same_answer, offline_answer, poll};
use crate::http::TestServer;
use crate::support::Rng;

const BURST: usize = 50;
const VERTICES: usize = 20_000;
const REQUEST_TIMEOUT_MS: u64 = 20_000;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_burst_past_capacity_is_shed_with_quick_503s_and_the_rest_served_in_full() {
    // One job at a time and two waiting: a burst of fifty cannot all fit.
    let server = TestServer::one_job(2, |c| {
        c.retry_after_secs = 3;
        c.request_timeout_ms = REQUEST_TIMEOUT_MS;
    })
    .await;

    // A few heavy variants (8 lights, every vertex through the reference
    // evaluator), so that answers crossing between requests would show.
    let mut rng = Rng::new(0x0e4_10ad);
    let variants: Vec<(Vec<u8>, Value)> = (0..3)
        .map(|_| {
            let mut request = rng.shade_request(1);
            let lights: Vec<Value> = (0..8).map(|_| rng.light()).collect();
            request["lights"] = lights.into();
            request["vertices"] = rng.vertices(VERTICES);
            request["precision"] = "reference".into();
            request["terms"] = "none".into();
            let body = request.to_string().into_bytes();
            let expected = offline_answer(&body);
            (body, expected)
        })
        .collect();

    let url = server.url("/v1/shade");
    let burst: Vec<_> = (0..BURST)
        .map(|i| {
            let (body, _) = variants[i % variants.len()].clone();
            let url = url.clone();
            tokio::spawn(async move {
                let started = Instant::now();
                let response = crate::support::client()
                    .post(url)
                    .header("content-type", "application/json")
                    .body(body)
                    .send()
                    .await
                    .unwrap_or_else(|e| panic!("request {i}: {e}"));
                let elapsed = started.elapsed();
                let status = response.status().as_u16();
                let headers = response.headers().clone();
                let body = response.bytes().await.unwrap();
                (i, status, headers, body, elapsed)
            })
        })
        .collect();

    let (mut served, mut shed) = (0, 0);
    let deadline = Duration::from_millis(REQUEST_TIMEOUT_MS);
    for request in burst {
        let (i, status, headers, body, elapsed) = request.await.unwrap();
        match status {
            200 => {
                served += 1;
                let got: Value = serde_json::from_slice(&body).expect("a complete JSON body");
                let (_, expected) = &variants[i % variants.len()];
                assert_same_answer(got, expected, &format!("request {i}"));
            }
            503 => {
                shed += 1;
                assert_eq!(headers["retry-after"], "3", "request {i}");
                assert_eq!(headers["content-type"], "application/problem+json");
                let problem: Value = serde_json::from_slice(&body).unwrap();
                assert_eq!(problem["type"], "urn:glint:problem:busy", "{problem}");
                assert!(
                    !problem["detail"].as_str().unwrap().contains("deadline"),
                    "request {i} was refused at the door, not after waiting: {problem}"
                );
                assert!(
                    elapsed < deadline,
                    "request {i}: a 503 came after {elapsed:?}, not before the {deadline:?} deadline"
                );
            }
            other => panic!("request {i}: {other} {}", String::from_utf8_lossy(&body)),
        }
    }
    eprintln!("burst of {BURST}: {served} served, {shed} shed");
    assert!(
        served >= 1,
        "the first request always finds the worker free"
    );
    assert!(shed >= 1, "{BURST} requests for 3 places: some are shed");

    // Nothing is left holding a place, and the server serves again.
    let settled = poll(100, Duration::from_millis(20), || async {
        server.state.pool.running() == 0 && server.state.pool.queued() == 0
    })
    .await;
    assert!(settled, "every place is given back after the burst");
    let response = server
        .post_json("/v1/shade", &crate::http::one_vertex())
        .await;
    assert_eq!(response.status(), 200, "served again after the burst");
}

/// Regression: the pool gave back a job's slot only after its answer had
/// left, so a client sending its next request as soon as it had the last
/// answer could find the slot still taken and, with no queue, get a 503.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_waits_for_each_answer_is_never_refused() {
    let server = TestServer::one_job(0, |_| {}).await;
    let http = crate::support::client();
    let body = crate::http::one_vertex();
    for i in 0..300 {
        let response = http
            .post(server.url("/v1/shade"))
            .json(&body)
            .send()
            .await
            .unwrap();
        assert_eq!(
            response.status(),
            200,
            "request {i} of one sequential client"
        );
        response.bytes().await.unwrap();
    }
}

//! Graceful shutdown: accepted requests finish with their full answer, new
//! connections are refused, readiness goes down first.

use std::sync::atomic::Ordering;
use std::time::Duration;

use serde_json::Value;

use super::{POOLED_VERTICES, TestServer, pooled_request};
use crate::support::client;

#[tokio::test]
async fn an_in_flight_request_finishes_after_shutdown_begins() {
    let mut server = TestServer::with(|c| {
        c.threads = 1;
        c.max_jobs = 1;
        c.shutdown_grace_ms = 20_000;
    })
    .await;
    let release = server.occupy_workers().await;

    // A request that is accepted and waits in the queue.
    let in_flight = tokio::spawn({
        let url = server.url("/v1/shade");
        async move { client().post(url).json(&pooled_request()).send().await }
    });
    while server.state.pool.queued() == 0 {
        tokio::task::yield_now().await;
    }

    server.begin_shutdown();
    while !server.state.shutting_down.load(Ordering::Relaxed) {
        tokio::task::yield_now().await;
    }
    drop(release);

    let response = in_flight
        .await
        .unwrap()
        .expect("the accepted request is answered");
    assert_eq!(response.status(), 200);
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["colors"].as_array().unwrap().len(), POOLED_VERTICES);

    tokio::time::timeout(Duration::from_secs(20), server.stopped())
        .await
        .expect("the server stops within its grace period")
        .unwrap();
    let refused = client().get(server.url("/healthz")).send().await;
    assert!(
        refused.is_err(),
        "new connections are refused after shutdown"
    );
}

#[tokio::test]
async fn readiness_goes_down_when_shutdown_begins() {
    let server = TestServer::start().await;
    server.state.shutting_down.store(true, Ordering::Relaxed);
    let ready = client().get(server.url("/readyz")).send().await.unwrap();
    assert_eq!(ready.status(), 503);
    let health = client().get(server.url("/healthz")).send().await.unwrap();
    assert_eq!(health.status(), 200, "alive while draining");
}

//! The drain a load balancer needs: on SIGTERM, `/readyz` answers 503 while
//! the listener still takes connections for `--drain-ms` (so that active
//! health checks see the replica leave), and a render in flight runs to its
//! end and is answered before the process exits 0.
#![cfg(unix)]

use std::time::Duration;

use super::spheres;
use crate::load::{Glint, metric, poll};
use crate::support::client;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_during_a_long_render_answers_it_while_readyz_is_503() {
    let mut glint = Glint::spawn(&[
        "--threads",
        "1",
        "--drain-ms",
        "1500",
        "--shutdown-grace-ms",
        "120000",
    ])
    .await;
    // Some seconds of work on one thread.
    let request = spheres(400, 300, 16);
    let render = tokio::spawn({
        let (url, request) = (glint.url("/v1/render"), request.clone());
        async move {
            let response = client().post(url).json(&request).send().await?;
            let status = response.status();
            let served_by = response.headers().get("x-served-by").cloned();
            Ok::<_, reqwest::Error>((status, served_by, response.bytes().await?))
        }
    });
    let running = poll(1000, Duration::from_millis(10), || async {
        metric(&glint.metrics().await, "glint_jobs_running") == 1.0
    })
    .await;
    assert!(running, "the render is running");

    glint.terminate();
    // Readiness turns 503 at once, and the replica still answers it: a load
    // balancer's checks see it leave.
    let mut draining = None;
    let mut every = tokio::time::interval(Duration::from_millis(10));
    for _ in 0..200 {
        every.tick().await;
        if let Ok(r) = client().get(glint.url("/readyz")).send().await
            && r.status() == 503
        {
            draining = Some(r.json::<serde_json::Value>().await.unwrap());
            break;
        }
    }
    assert!(
        draining.is_some(),
        "/readyz answers 503 after SIGTERM\n{}",
        glint.logs()
    );
    assert!(
        !render.is_finished(),
        "the render was still running meanwhile"
    );
    let problem = draining.unwrap();
    assert_eq!(
        problem["type"], "urn:glint:problem:shutting-down",
        "{problem}"
    );
    let health = client().get(glint.url("/healthz")).send().await.unwrap();
    assert_eq!(health.status(), 200, "alive while draining");

    // The render is answered in full.
    let (status, served_by, png) = tokio::time::timeout(Duration::from_secs(120), render)
        .await
        .expect("the render is answered within its grace")
        .unwrap()
        .expect("the render is answered");
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&png));
    assert!(served_by.is_some(), "x-served-by on the answer");
    // The same PNG the engine makes of the request, here in the test.
    let expected = tokio::task::spawn_blocking(move || {
        let scene = glint::scene::parse_render(
            &serde_json::to_vec(&request).unwrap(),
            &glint::scene::Limits::default(),
        )
        .unwrap();
        glint::render::render_png(&scene)
    })
    .await
    .unwrap();
    assert!(png == expected, "the PNG is the engine's, byte for byte");

    // And the process exits 0 once it has answered.
    let mut exited = None;
    let mut every = tokio::time::interval(Duration::from_millis(50));
    for _ in 0..600 {
        every.tick().await;
        exited = glint.try_wait();
        if exited.is_some() {
            break;
        }
    }
    let exited = exited.unwrap_or_else(|| panic!("glint exits after its drain\n{}", glint.logs()));
    assert!(exited.success(), "{exited}\n{}", glint.logs());
}

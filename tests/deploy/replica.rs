//! What one replica offers a deployment: `x-served-by` on every response,
//! `glint healthcheck` as a probe, and `glint render --tile`, one tile of an
//! image as an Indexed Job's pod renders it.
#![cfg(unix)]

use std::time::Duration;

use super::{Scratch, png_from, run_to_end, spheres};
use crate::load::Glint;
use crate::support::client;

#[tokio::test]
async fn every_response_names_the_replica_that_answered() {
    let glint = Glint::spawn(&["--instance-id", "replica-a"]).await;
    let client = client();
    let responses = [
        client.get(glint.url("/healthz")).send().await.unwrap(),
        client.get(glint.url("/readyz")).send().await.unwrap(),
        client.get(glint.url("/metrics")).send().await.unwrap(),
        client.get(glint.url("/no-such-path")).send().await.unwrap(),
        client.get(glint.url("/v1/shade")).send().await.unwrap(),
        client
            .post(glint.url("/v1/shade"))
            .header("content-type", "application/json")
            .body("{")
            .send()
            .await
            .unwrap(),
        client
            .post(glint.url("/v1/render"))
            .json(&spheres(8, 8, 1))
            .send()
            .await
            .unwrap(),
    ];
    let statuses: Vec<u16> = responses.iter().map(|r| r.status().as_u16()).collect();
    assert_eq!(statuses, [200, 200, 200, 404, 405, 400, 200]);
    for response in &responses {
        assert_eq!(
            response.headers()["x-served-by"],
            "replica-a",
            "{}",
            response.url()
        );
    }

    // By default, the host name.
    let unnamed = Glint::spawn(&[]).await;
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    let answer = client.get(unnamed.url("/healthz")).send().await.unwrap();
    assert_eq!(answer.headers()["x-served-by"], host.trim());
}

/// `glint healthcheck` with `args`: its exit code.
async fn healthcheck(args: &[&str]) -> Option<i32> {
    let mut all: Vec<&std::ffi::OsStr> = vec!["healthcheck".as_ref()];
    all.extend(args.iter().map(std::ffi::OsStr::new));
    run_to_end(
        env!("CARGO_BIN_EXE_glint"),
        &all,
        |_| {},
        Duration::from_secs(30),
    )
    .await
    .unwrap()
    .status
    .code()
}

#[tokio::test]
async fn healthcheck_exits_0_on_a_ready_replica_and_1_otherwise() {
    let mut glint = Glint::spawn(&["--drain-ms", "60000"]).await;
    let readyz = glint.url("/readyz");
    assert_eq!(healthcheck(&["--url", &readyz]).await, Some(0));
    // Draining: alive, but /readyz answers 503.
    glint.terminate();
    let mut every = tokio::time::interval(Duration::from_millis(10));
    let mut draining = false;
    for _ in 0..300 {
        every.tick().await;
        let answer = client().get(&readyz).send().await;
        if answer.is_ok_and(|r| r.status() == 503) {
            draining = true;
            break;
        }
    }
    assert!(draining, "/readyz turns 503 after SIGTERM");
    assert_eq!(healthcheck(&["--url", &readyz]).await, Some(1));
    assert!(glint.try_wait().is_none(), "still draining");
    // Nothing listening.
    let port = super::free_ports(1)[0];
    let nowhere = format!("http://127.0.0.1:{port}/readyz");
    assert_eq!(healthcheck(&["--url", &nowhere]).await, Some(1));
}

#[tokio::test]
async fn a_tile_rendered_alone_is_its_region_of_the_image() {
    let single = Glint::spawn(&[]).await;
    let scratch = Scratch::new("tile");
    let request = spheres(50, 30, 2);
    let file = scratch.path().join("request.json");
    std::fs::write(&file, serde_json::to_vec(&request).unwrap()).unwrap();
    let out = scratch.path().join("tile.png");
    // 3 × 2 tiles of 50 × 30: columns at 0, 16, 33; rows at 0, 15. Tile 5
    // is the last of the second row.
    let mut region = request.clone();
    region["region"] = serde_json::json!({"x": 33, "y": 15, "width": 17, "height": 15});
    let expected = png_from(&single.url("/v1/render"), &region).await;
    let render = |tile: &'static str| {
        let (file, out) = (file.clone(), out.clone());
        async move {
            run_to_end(
                env!("CARGO_BIN_EXE_glint"),
                &[
                    "render".as_ref(),
                    file.as_ref(),
                    "--tiles".as_ref(),
                    "3x2".as_ref(),
                    "--tile".as_ref(),
                    tile.as_ref(),
                    "-o".as_ref(),
                    out.as_ref(),
                ],
                |_| {},
                Duration::from_secs(60),
            )
            .await
            .unwrap()
        }
    };
    let done = render("5").await;
    assert!(done.status.success(), "{}", super::printed(&done));
    assert_eq!(std::fs::read(&out).unwrap(), expected);
    // There is no tile 6 of 3 × 2.
    let refused = render("6").await;
    assert_eq!(refused.status.code(), Some(1));
    let problem: serde_json::Value = serde_json::from_slice(&refused.stderr).unwrap();
    assert_eq!(problem["status"], 422, "{problem}");
}

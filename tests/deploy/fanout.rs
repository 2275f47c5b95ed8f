//! `glint render REQ.json --via URL`, the tile fan-out client, as a user
//! runs it: through HAProxy (tiles answered by several replicas, one of
//! them killed mid-render), through one replica whose pixel limit is below
//! the image's size, through a replica that is busy, and to nothing at all.
//! Its PNG must be the single request's, byte for byte, as a single glint
//! process answers it in the same test.
#![cfg(unix)]

use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{Cluster, Scratch, png_from, run_to_end, signal, spheres};
use crate::load::{Glint, poll};

/// Runs the client with `args` after `glint render REQUEST`, within a
/// minute and a half.
async fn fanout(request: &Path, args: &[&str]) -> Output {
    let mut all: Vec<&std::ffi::OsStr> = vec!["render".as_ref(), request.as_ref()];
    all.extend(args.iter().map(std::ffi::OsStr::new));
    run_to_end(
        env!("CARGO_BIN_EXE_glint"),
        &all,
        |c| {
            for proxy in ["http_proxy", "HTTP_PROXY", "all_proxy", "ALL_PROXY"] {
                c.env_remove(proxy);
            }
        },
        Duration::from_secs(90),
    )
    .await
    .unwrap_or_else(|e| panic!("glint render --via: {e}"))
}

/// The `--report` the client printed.
fn report(output: &Output) -> Value {
    assert!(
        output.status.success(),
        "the fan-out render fails: {}",
        super::printed(output)
    );
    serde_json::from_slice(&output.stdout)
        .unwrap_or_else(|e| panic!("a JSON report ({e}): {}", super::printed(output)))
}

/// Renders `file` through `via` with `flags` and `--report`, checks that
/// the PNG is `expected`, byte for byte, and returns the report.
pub(super) async fn fanned_out(file: &Path, via: &str, flags: &[&str], expected: &[u8]) -> Value {
    let out = file.with_extension("png");
    let out = out.to_str().unwrap();
    let mut args = vec!["--via", via, "--report", "-o", out];
    args.extend_from_slice(flags);
    let said = report(&fanout(file, &args).await);
    assert!(
        std::fs::read(out).unwrap() == expected,
        "the PNG differs from the single request's\n{said}"
    );
    said
}

/// Writes `request` to a file in `dir`.
fn request_file(dir: &Path, name: &str, request: &Value) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(request).unwrap()).unwrap();
    path
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn through_haproxy_the_tiles_make_the_single_requests_png() {
    let test = "through_haproxy_the_tiles_make_the_single_requests_png";
    let Some(cluster) = Cluster::start(test, 3, &[]).await else {
        return;
    };
    let single = Glint::spawn(&[]).await;
    let scratch = Scratch::new("fanout-haproxy");
    let lb = cluster.lb_url("");

    // Tiles spread over the replicas.
    let request = spheres(96, 64, 2);
    let expected = png_from(&single.url("/v1/render"), &request).await;
    let file = request_file(scratch.path(), "small.json", &request);
    let flags = ["--tiles", "4x4", "--parallel", "4"];
    let said = fanned_out(&file, &lb, &flags, &expected).await;
    let served_by = said["served_by"].as_object().unwrap();
    assert!(
        served_by.len() >= 2 && served_by.keys().all(|k| k.starts_with("replica-")),
        "tiles from at least two replicas: {said}"
    );
    assert_eq!(said["tiles"].as_array().unwrap().len(), 16);

    // A replica killed while the tiles are being rendered.
    let request = spheres(160, 120, 4);
    let expected = png_from(&single.url("/v1/render"), &request).await;
    let file = request_file(scratch.path(), "large.json", &request);
    let client = tokio::spawn({
        let (file, lb) = (file.clone(), lb.clone());
        async move {
            let flags = ["--tiles", "8x8", "--parallel", "3"];
            fanned_out(&file, &lb, &flags, &expected).await
        }
    });
    // HAProxy's count of requests sent to the replicas (its sessions; its
    // health checks are not among them).
    let before = cluster.backend_counter("stot").await;
    let under_way = poll(3000, Duration::from_millis(10), || async {
        cluster.backend_counter("stot").await >= before + 8
    })
    .await;
    assert!(under_way, "the fan-out starts");
    signal(cluster.replica_pid(0).expect("replica-1 runs"), "KILL");
    // The same PNG bytes with a replica killed mid-render.
    client.await.unwrap();
    assert!(cluster.replica_exits(0).contains(&(128 + 9)));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn through_one_replica_the_tiles_pass_its_pixel_limit() {
    let limited = Glint::spawn(&["--max-pixels", "1000"]).await;
    let single = Glint::spawn(&[]).await;
    let scratch = Scratch::new("fanout-limit");
    // 96 × 64 = 6144 pixels: over the limit in one request…
    let request = spheres(96, 64, 2);
    let refused = super::client()
        .post(limited.url("/v1/render"))
        .json(&request)
        .send()
        .await
        .unwrap();
    assert_eq!(refused.status(), 413);
    let expected = png_from(&single.url("/v1/render"), &request).await;

    // …and within it as 4 × 4 tiles of 24 × 16 = 384.
    let file = request_file(scratch.path(), "request.json", &request);
    let out = scratch.path().join("out.png");
    let via = limited.url("");
    let output = fanout(
        &file,
        &["--via", &via, "--tiles", "4x4", "-o", out.to_str().unwrap()],
    )
    .await;
    assert!(output.status.success(), "{}", super::printed(&output));
    // On a pipe, nothing: no progress bar, no report unless asked.
    assert!(output.stdout.is_empty(), "{}", super::printed(&output));
    assert!(output.stderr.is_empty(), "{}", super::printed(&output));
    assert_eq!(std::fs::read(&out).unwrap(), expected, "the same PNG bytes");

    // Tiles still over the limit (48 × 32 = 1536) are refused, and no retry
    // mends that: the client stops at once with the server's problem.
    let started = Instant::now();
    let output = fanout(
        &file,
        &["--via", &via, "--tiles", "2x2", "-o", out.to_str().unwrap()],
    )
    .await;
    assert_eq!(output.status.code(), Some(1), "{}", super::printed(&output));
    let stderr = String::from_utf8_lossy(&output.stderr);
    let problem: Value = serde_json::from_str(stderr.lines().last().unwrap_or_default())
        .unwrap_or_else(|e| panic!("a problem+json on stderr ({e}): {stderr}"));
    assert_eq!(problem["status"], 413, "{problem}");
    assert_eq!(problem["pointer"], "/region", "{problem}");
    assert!(started.elapsed() < Duration::from_secs(30));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_busy_replica_gets_each_tile_again_after_its_retry_after() {
    // One job at a time and no queue: of two tiles sent at once, one is
    // refused with 503 and `Retry-After: 1`.
    let busy = Glint::spawn(&["--max-jobs", "1", "--queue", "0"]).await;
    let single = Glint::spawn(&[]).await;
    let scratch = Scratch::new("fanout-busy");
    let request = spheres(160, 120, 8);
    let expected = png_from(&single.url("/v1/render"), &request).await;
    let file = request_file(scratch.path(), "request.json", &request);
    let flags = ["--tiles", "2x2", "--parallel", "2", "--tries", "20"];
    let said = fanned_out(&file, &busy.url(""), &flags, &expected).await;
    let retries = said["retries"].as_u64().unwrap();
    let refused = crate::load::metric(
        &busy.metrics().await,
        r#"glint_rejections_total{reason="busy"}"#,
    );
    assert_eq!(
        retries as f64, refused,
        "every 503 was tried again, and nothing else was: {said}"
    );
    // A 503 says to wait a second before the next try.
    if retries > 0 {
        assert!(said["elapsed_ms"].as_f64().unwrap() >= 1000.0, "{said}");
    }
}

#[tokio::test]
async fn with_nothing_listening_the_client_gives_up_after_its_tries() {
    // A port the kernel gave and took back: nothing listens there.
    let port = super::free_ports(1)[0];
    let scratch = Scratch::new("fanout-nothing");
    let file = request_file(scratch.path(), "request.json", &spheres(8, 8, 1));
    let out = scratch.path().join("out.png");
    let via = format!("http://127.0.0.1:{port}");
    let output = fanout(
        &file,
        &["--via", &via, "--tries", "3", "-o", out.to_str().unwrap()],
    )
    .await;
    assert_eq!(output.status.code(), Some(1), "{}", super::printed(&output));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("failed 3 tries"), "{stderr}");
    assert!(!out.exists(), "no PNG is written");
}

//! SIGTERM to the real binary: every request it had taken is answered in
//! full, the listener closes at once, and the process exits 0 within its
//! grace period.
#![cfg(unix)]

use std::io::ErrorKind;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use tokio::net::TcpStream;

use super::{Glint, poll};
use crate::support::Rng;

const IN_FLIGHT: usize = 4;
const VERTICES: usize = 20_000;
const GRACE_MS: u64 = 60_000;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_finishes_every_accepted_request_and_exits_0() {
    let grace = GRACE_MS.to_string();
    let mut glint = Glint::spawn(&[
        "--threads",
        "1",
        "--max-jobs",
        "1",
        "--queue",
        "8",
        "--shutdown-grace-ms",
        &grace,
    ])
    .await;

    // Slow-ish work: every vertex through the f64 reference evaluator for
    // eight lights, twice (colours and the term summary), one job at a time.
    let mut rng = Rng::new(0x51_6e);
    let mut request = json!({
        "lights": (0..8).map(|_| rng.light()).collect::<Vec<_>>(),
        "vertices": rng.vertices(VERTICES),
        "precision": "reference",
        "terms": "summary",
    });
    let body = request.to_string();
    let in_flight: Vec<_> = (0..IN_FLIGHT)
        .map(|_| {
            let (url, body) = (glint.url("/v1/shade"), body.clone());
            tokio::spawn(async move {
                crate::support::client()
                    .post(url)
                    .header("content-type", "application/json")
                    .body(body)
                    .send()
                    .await?
                    .error_for_status()?
                    .bytes()
                    .await
            })
        })
        .collect();

    // SIGTERM once the server has taken all of them (its metrics say so):
    // one running, the rest queued, or at most one already answered.
    let taken = poll(400, Duration::from_millis(25), || async {
        let text = glint.metrics().await;
        let held =
            super::metric(&text, "glint_jobs_running") + super::metric(&text, "glint_jobs_queued");
        let done = super::metric(
            &text,
            r#"glint_requests_total{route="/v1/shade",status="200"}"#,
        );
        held + done == IN_FLIGHT as f64 && held >= (IN_FLIGHT - 1) as f64
    })
    .await;
    assert!(taken, "the server takes all {IN_FLIGHT} requests");
    let signalled = Instant::now();
    glint.terminate();

    // The listener closes at once, while the taken requests still run.
    let refused = poll(400, Duration::from_millis(5), || async {
        matches!(
            TcpStream::connect(glint.addr).await,
            Err(e) if e.kind() == ErrorKind::ConnectionRefused
        )
    })
    .await;
    assert!(refused, "new connections are refused after SIGTERM");
    assert!(
        glint.try_wait().is_none(),
        "the listener closed before the process ended: it drains first"
    );

    // Every taken request gets its whole answer, right.
    let expected = {
        // The reference evaluator lights each vertex on its own, so a few
        // vertices checked offline stand for all of them.
        let picks = [0, 1, VERTICES / 2, VERTICES - 1];
        let vertices = &request["vertices"];
        request["vertices"] = json!({
            "positions": picks.map(|i| vertices["positions"][i].clone()),
            "normals": picks.map(|i| vertices["normals"][i].clone()),
        });
        let answer = super::offline_answer(request.to_string().as_bytes());
        (picks, answer)
    };
    for (i, task) in in_flight.into_iter().enumerate() {
        let bytes = task
            .await
            .unwrap()
            .unwrap_or_else(|e| panic!("request {i} was answered in full: {e}"));
        let answer: Value = serde_json::from_slice(&bytes).expect("complete JSON");
        assert_eq!(answer["colors"].as_array().unwrap().len(), VERTICES);
        assert_eq!(answer["terms"]["summary"]["vertices"], VERTICES);
        assert_eq!(answer["stats"]["vertices"], VERTICES);
        let (picks, offline) = &expected;
        for (k, &v) in picks.iter().enumerate() {
            assert_eq!(
                answer["colors"][v], offline["colors"][k],
                "request {i}, vertex {v}"
            );
        }
    }

    // And the process exits 0, within the grace period.
    let grace = Duration::from_millis(GRACE_MS);
    let exited = tokio::time::timeout(grace, async {
        let mut every = tokio::time::interval(Duration::from_millis(20));
        loop {
            every.tick().await;
            if let Some(status) = glint.try_wait() {
                return status;
            }
        }
    })
    .await
    .unwrap_or_else(|_| panic!("glint exits within its grace period\n{}", glint.logs()));
    assert!(
        exited.success(),
        "glint exits 0 after a drain: {exited}\n{}",
        glint.logs()
    );
    assert!(signalled.elapsed() < grace);
    assert!(
        glint.logs().contains("every request finished"),
        "{}",
        glint.logs()
    );
}

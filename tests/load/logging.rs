//! The access log never holds a request up: with its output a pipe that
//! nobody reads, the real binary still answers a burst of requests, and
//! counts the lines it had to drop.

use std::time::Duration;

use super::{Glint, metric};

/// Connections, each sending its requests one after another.
const CONNECTIONS: usize = 8;
const REQUESTS_PER_CONNECTION: usize = 500;
/// The lines this server's log holds. Its 4,000 access lines of about 250
/// bytes (1 MB) are many times what a pipe (64 KiB), these lines and the
/// batch the log thread is stuck writing can hold between them.
const LOG_BUFFER_LINES: &str = "256";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_log_nobody_reads_drops_lines_and_never_holds_up_a_request() {
    let glint = Glint::spawn_unread(&["--log-buffer-lines", LOG_BUFFER_LINES]).await;

    let body = crate::http::one_vertex().to_string();
    let tasks: Vec<_> = (0..CONNECTIONS)
        .map(|connection| {
            let (url, body) = (glint.url("/v1/shade"), body.clone());
            tokio::spawn(async move {
                // One client per task: its own keep-alive connection.
                let http = crate::support::client();
                for i in 0..REQUESTS_PER_CONNECTION {
                    let status = http
                        .post(&url)
                        .header("content-type", "application/json")
                        .body(body.clone())
                        .send()
                        .await
                        .unwrap_or_else(|e| panic!("connection {connection}, request {i}: {e}"))
                        .status();
                    assert_eq!(status, 200, "connection {connection}, request {i}");
                }
            })
        })
        .collect();
    let burst = async {
        for task in tasks {
            task.await.expect("every connection got every answer");
        }
    };
    tokio::time::timeout(Duration::from_secs(120), burst)
        .await
        .expect("every request of the burst is answered within 120 s");

    let text = glint.metrics().await;
    let total = (CONNECTIONS * REQUESTS_PER_CONNECTION) as f64;
    let answered = metric(
        &text,
        r#"glint_requests_total{route="/v1/shade",status="200"}"#,
    );
    assert_eq!(answered, total, "{text}");
    let dropped = metric(&text, "glint_log_lines_dropped_total");
    assert!(
        dropped > 0.0 && dropped <= total,
        "{dropped} lines dropped of {total}\n{text}"
    );
}

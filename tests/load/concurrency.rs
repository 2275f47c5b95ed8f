//! Many clients at once get exactly the answers the offline engine gives:
//! no answer crosses to another request, none is cut short, none is lost.

use std::time::Duration;

use serde_json::Value;

use super::{assert_same_answer, metric, offline_answer, poll};
use crate::http::TestServer;
use crate::support::Rng;

const CLIENTS: usize = 64;
const REQUESTS_PER_CLIENT: usize = 6;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sixty_four_clients_get_the_offline_engines_answers() {
    // Room for every client's one outstanding request, so a 503 here
    // would be a bug, not load shedding: in the pool's hands are at most
    // CLIENTS requests, and a slot held by a job that has already answered
    // still leaves `queue` places for the rest.
    let server = TestServer::with(|c| {
        c.queue = CLIENTS;
        c.request_timeout_ms = 60_000;
    })
    .await;

    // Every request and its expected answer, made before the traffic so
    // that the offline engine does not compete with the server.
    let mut rng = Rng::new(0x5eed_0001);
    let work: Vec<Vec<(Vec<u8>, Value)>> = (0..CLIENTS)
        .map(|_| {
            (0..REQUESTS_PER_CLIENT)
                .map(|_| {
                    let body = rng.shade_request(200).to_string().into_bytes();
                    let expected = offline_answer(&body);
                    (body, expected)
                })
                .collect()
        })
        .collect();

    let url = server.url("/v1/shade");
    let clients: Vec<_> = work
        .into_iter()
        .enumerate()
        .map(|(client, requests)| {
            let url = url.clone();
            tokio::spawn(async move {
                // One client per task: its own keep-alive connection.
                let http = crate::support::client();
                for (i, (body, expected)) in requests.into_iter().enumerate() {
                    let response = http
                        .post(&url)
                        .header("content-type", "application/json")
                        .body(body)
                        .send()
                        .await
                        .unwrap_or_else(|e| panic!("client {client}, request {i}: {e}"));
                    let status = response.status().as_u16();
                    let text = response.text().await.unwrap();
                    assert_eq!(status, 200, "client {client}, request {i}: {text}");
                    let got: Value = serde_json::from_str(&text).unwrap();
                    assert_same_answer(got, &expected, &format!("client {client}, request {i}"));
                }
            })
        })
        .collect();
    for client in clients {
        client.await.expect("every client got every answer right");
    }

    // The accounting agrees, and the pool is idle again.
    let total = (CLIENTS * REQUESTS_PER_CLIENT) as f64;
    let settled = poll(100, Duration::from_millis(20), || async {
        server.state.pool.running() == 0 && server.state.pool.queued() == 0
    })
    .await;
    assert!(settled, "the pool is idle after the traffic");
    let text = crate::support::client()
        .get(server.url("/metrics"))
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert_eq!(
        metric(
            &text,
            r#"glint_requests_total{route="/v1/shade",status="200"}"#
        ),
        total,
        "{text}"
    );
}

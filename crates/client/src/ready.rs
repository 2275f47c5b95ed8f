//! The readiness probe behind `glint healthcheck`: one `GET` of a
//! replica's `/readyz`, for container images that have no shell or curl to
//! run a probe with.

use std::time::Duration;

use crate::describe;

/// `/readyz` on the loopback address at `port`.
pub fn local_url(port: u16) -> String {
    format!("http://127.0.0.1:{port}{}", glint_protocol::READY)
}

/// Whether `url` answers 200 within `timeout`: `Ok`, or why not.
pub async fn check(url: &str, timeout: Duration) -> Result<(), String> {
    let client = reqwest::Client::builder()
        .no_proxy()
        .timeout(timeout)
        .build()
        .map_err(|e| format!("cannot make an HTTP client: {e}"))?;
    let response = client
        .get(url)
        .send()
        .await
        .map_err(|e| format!("{url}: {}", describe(&e)))?;
    match response.status() {
        reqwest::StatusCode::OK => Ok(()),
        status => Err(format!("{url} answered {status}")),
    }
}

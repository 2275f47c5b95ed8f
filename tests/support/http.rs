//! The HTTP client of the tests: every request a test sends goes to a
//! server it started on 127.0.0.1, so the client takes no proxy from the
//! environment, and a server that never answers fails the test within a
//! bound instead of hanging it.

use std::time::Duration;

/// The longest a test waits for one answer: a render through the
/// container topology is the slowest answer the suites wait for.
const ANSWER_WITHIN: Duration = Duration::from_secs(120);

/// A client for loopback, with no proxy and no retry of its own.
pub fn client() -> reqwest::Client {
    reqwest::Client::builder()
        .no_proxy()
        .timeout(ANSWER_WITHIN)
        .build()
        .expect("a reqwest client with no proxy builds")
}

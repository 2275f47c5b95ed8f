//! Clients of a glint service, kept out of the service itself: the tile
//! fan-out behind `glint render --via` ([`fanout`]), which splits one
//! render into `region` tiles sent concurrently through any glint URL and
//! stitches them into the single request's PNG, and the readiness probe
//! behind `glint healthcheck` ([`ready`]).

pub mod fanout;
pub mod ready;

/// An error of the HTTP client with its causes, which hold the useful part
/// ("connection refused").
pub fn describe(e: &reqwest::Error) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(cause) = source {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        source = cause.source();
    }
    text
}

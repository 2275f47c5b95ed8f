//! RFC 9457 problem details: the one shape of every error glint reports, over
//! HTTP and on the command line alike.

use serde::Serialize;

use crate::scene::{RequestError, RequestErrorKind};

/// A problem+json body.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Problem {
    /// A URN naming the class of problem (`urn:glint:problem:invalid`).
    #[serde(rename = "type")]
    pub kind: String,
    pub title: String,
    pub status: u16,
    pub detail: String,
    /// JSON Pointer of the field at fault, when one is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pointer: Option<String>,
}

impl Problem {
    pub fn new(status: u16, slug: &str, title: &str, detail: impl Into<String>) -> Self {
        Self {
            kind: format!("urn:glint:problem:{slug}"),
            title: title.to_owned(),
            status,
            detail: detail.into(),
            pointer: None,
        }
    }

    pub fn at(mut self, pointer: impl Into<String>) -> Self {
        self.pointer = Some(pointer.into());
        self
    }

    /// The service is saturated; the client should retry later.
    pub fn busy() -> Self {
        Self::new(
            503,
            "busy",
            "Service saturated",
            "every worker is busy and the queue is full; retry after the delay in Retry-After",
        )
    }

    /// Something failed inside glint; the details are in the server's log.
    pub fn internal() -> Self {
        Self::new(
            500,
            "internal",
            "Internal error",
            "the request failed inside the server; it has been logged",
        )
    }
}

impl From<&RequestError> for Problem {
    fn from(e: &RequestError) -> Self {
        let (status, slug, title) = match e.kind {
            RequestErrorKind::Malformed => (400, "malformed", "Malformed request"),
            RequestErrorKind::OverLimit => (413, "over-limit", "Over a limit of this server"),
            RequestErrorKind::Invalid => (422, "invalid", "Invalid request"),
        };
        Problem::new(status, slug, title, e.detail.clone()).at(e.pointer.clone())
    }
}

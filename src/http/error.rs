//! The one error type of the HTTP layer and its one mapping to a response:
//! `application/problem+json` (RFC 9457), with `Retry-After` when the client
//! should come back later. The response carries its [`ProblemKind`] in its
//! extensions, where the metrics read why a request was refused.

use std::time::Duration;

use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};

use crate::problem::{Problem, ProblemKind};
use crate::scene::RequestError;

/// A refused or failed request.
#[derive(Debug)]
pub struct ApiError {
    pub problem: Problem,
    /// Seconds for `Retry-After` (busy only).
    pub retry_after: Option<u64>,
}

impl ApiError {
    pub fn new(kind: ProblemKind, detail: impl Into<String>) -> Self {
        Self::from(Problem::new(kind, detail))
    }

    /// The pool is full: retry after `retry_after` seconds.
    pub fn busy(retry_after: u64) -> Self {
        Self {
            problem: Problem::busy(),
            retry_after: Some(retry_after),
        }
    }

    /// The request missed the server's deadline: retry after `retry_after`
    /// seconds.
    pub fn deadline(deadline: Duration, retry_after: u64) -> Self {
        Self {
            problem: Problem::new(
                ProblemKind::Busy,
                format!(
                    "the request did not finish within this server's deadline of {} ms",
                    deadline.as_millis()
                ),
            ),
            retry_after: Some(retry_after),
        }
    }

    pub fn internal() -> Self {
        Self::from(Problem::internal())
    }

    pub fn not_found() -> Self {
        Self::new(
            ProblemKind::NotFound,
            "no such endpoint; GET /openapi.yaml lists them",
        )
    }

    pub fn method_not_allowed() -> Self {
        Self::new(
            ProblemKind::MethodNotAllowed,
            "this endpoint does not take that method; GET /openapi.yaml lists them",
        )
    }
}

impl From<Problem> for ApiError {
    fn from(problem: Problem) -> Self {
        Self {
            problem,
            retry_after: None,
        }
    }
}

impl From<RequestError> for ApiError {
    fn from(e: RequestError) -> Self {
        Self::from(Problem::from(e))
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let kind = self.problem.kind();
        let status =
            StatusCode::from_u16(kind.status()).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
        let body = serde_json::to_vec(&self.problem).expect("a problem always serialises");
        let mut response = (
            status,
            [(
                header::CONTENT_TYPE,
                HeaderValue::from_static("application/problem+json"),
            )],
            body,
        )
            .into_response();
        if let Some(secs) = self.retry_after {
            response
                .headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(secs));
        }
        response.extensions_mut().insert(kind);
        response
    }
}

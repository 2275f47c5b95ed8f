//! The one error type of the HTTP layer and its one mapping to a response:
//! `application/problem+json` (RFC 9457), with `Retry-After` when the client
//! should come back later.

use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};

use crate::problem::Problem;
use crate::scene::RequestError;

/// A refused or failed request.
#[derive(Debug)]
pub struct ApiError {
    pub problem: Problem,
    /// Seconds for `Retry-After` (503 and 429 only).
    pub retry_after: Option<u64>,
}

impl ApiError {
    pub fn new(problem: Problem) -> Self {
        Self {
            problem,
            retry_after: None,
        }
    }

    pub fn busy(retry_after: u64) -> Self {
        Self {
            problem: Problem::busy(),
            retry_after: Some(retry_after),
        }
    }

    pub fn not_found() -> Self {
        Self::new(Problem::new(
            404,
            "not-found",
            "Not found",
            "no such endpoint; GET /openapi.yaml lists them",
        ))
    }

    pub fn method_not_allowed() -> Self {
        Self::new(Problem::new(
            405,
            "method-not-allowed",
            "Method not allowed",
            "this endpoint does not take that method; GET /openapi.yaml lists them",
        ))
    }
}

impl From<RequestError> for ApiError {
    fn from(e: RequestError) -> Self {
        Self::new(Problem::from(&e))
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status =
            StatusCode::from_u16(self.problem.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
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
        response
    }
}

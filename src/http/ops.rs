//! What a deployment needs: liveness, readiness, metrics, the contract.

use std::sync::atomic::Ordering;

use axum::extract::State;
use axum::http::header;
use axum::response::IntoResponse;

use super::AppState;
use super::error::ApiError;
use crate::problem::ProblemKind;

/// The contract, served as written.
pub const OPENAPI_YAML: &str = include_str!("../../api/openapi.yaml");

pub async fn healthz() -> &'static str {
    "ok"
}

/// Ready while not shutting down.
pub async fn readyz(State(state): State<AppState>) -> Result<&'static str, ApiError> {
    if state.shutting_down.load(Ordering::Relaxed) {
        Err(ApiError::new(
            ProblemKind::ShuttingDown,
            "this replica is draining its requests before it stops",
        ))
    } else {
        Ok("ready")
    }
}

pub async fn metrics(State(state): State<AppState>) -> impl IntoResponse {
    (
        [(
            header::CONTENT_TYPE,
            "application/openmetrics-text; version=1.0.0; charset=utf-8",
        )],
        state.metrics.encode(&state.pool),
    )
}

pub async fn openapi() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "application/yaml")], OPENAPI_YAML)
}

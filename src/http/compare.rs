//! `POST /v1/compare`: extract, compare on the pool, map.

use axum::extract::{Request, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use super::media::{self, Content};
use crate::scene;

pub async fn compare(
    State(state): State<AppState>,
    request: Request,
) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Content::Model(_) = media::content(&parts.headers)? {
        return Err(ApiError::new(
            crate::problem::ProblemKind::UnsupportedMediaType,
            "send a compare as application/json, with the candidate in `candidate.colors`",
        ));
    }
    let body = state.read_pooled_body(&parts.headers, body).await?;
    let limits = state.limits;
    let json = Box::pin(state.run(move |_| {
        let scene = scene::parse_compare(&body, &limits)?;
        let response = crate::compare::compare(&scene)?;
        Ok(serde_json::to_vec(&response).expect("a response always serialises"))
    }))
    .await?;
    Ok(([(header::CONTENT_TYPE, "application/json")], json).into_response())
}

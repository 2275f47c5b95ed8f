//! `POST /v1/compare`: extract, compare on the pool, map. A compare with a
//! model (its candidate in `COLOR_0`) is read as a shade's model is
//! ([`super::model::compare`]).

use axum::extract::{Request, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use super::media::{self, Content};
use crate::scene::{self, CompareScene, RequestError};

pub async fn compare(
    State(state): State<AppState>,
    request: Request,
) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Content::Model(kind) = media::content(&parts.headers)? {
        return Box::pin(super::model::compare(state, parts, body, kind)).await;
    }
    let body = state.read_pooled_body(&parts.headers, body).await?;
    let limits = state.limits;
    let json =
        Box::pin(state.run(move |_| respond(&scene::parse_compare(&body, &limits)?))).await?;
    Ok(answer(json))
}

/// The JSON body of the compare of `scene`.
pub(super) fn respond(scene: &CompareScene) -> Result<Vec<u8>, RequestError> {
    let response = crate::compare::compare(scene)?;
    Ok(serde_json::to_vec(&response).expect("a response always serialises"))
}

/// A `200` of the JSON `body`.
pub(super) fn answer(body: Vec<u8>) -> Response {
    ([(header::CONTENT_TYPE, "application/json")], body).into_response()
}

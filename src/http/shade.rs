//! `POST /v1/shade`: extract, hand to the pool, map.

use axum::extract::{Request, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use crate::{scene, shading};

pub async fn shade(State(state): State<AppState>, request: Request) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    let body = state.read_body(&parts.headers, body).await?;
    let limits = state.limits;
    let (json, vertices) = state
        .run(move |_| {
            let scene = scene::parse_shade(&body, &limits)?;
            let response = shading::shade(&scene);
            let json = serde_json::to_vec(&response).expect("a response always serialises");
            Ok((json, scene.positions.len()))
        })
        .await?;
    state.metrics.add_vertices(vertices);
    Ok(([(header::CONTENT_TYPE, "application/json")], json).into_response())
}

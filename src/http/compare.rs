//! `POST /v1/compare`: extract, compare on the pool, map. A JSON body holds
//! per-vertex colours; a form holds a `request` and the candidate: a
//! `model` (its candidate in `COLOR_0`, read as a shade's model is,
//! [`super::model::compare`]) or an `image` (a PNG of the render the
//! `request` asks for, [`compare_image`]).

use axum::body::Bytes;
use axum::extract::{Request, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use super::media::{self, Content, IMAGE_PNG};
use crate::compare::image::ImageCompared;
use crate::problem::{Problem, ProblemKind};
use crate::scene::{self, CompareScene, RequestError};

/// The parts a compare's form may have.
const COMPARE_PARTS: &[&str] = &["request", "model", "image"];

pub async fn compare(
    State(state): State<AppState>,
    request: Request,
) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Content::Model(kind) = media::content(&parts.headers)? {
        let form = state
            .read_parts(&parts.headers, body, kind, COMPARE_PARTS)
            .await?;
        let missing = |pointer: &str, detail: &str| {
            ApiError::from(Problem::new(ProblemKind::Malformed, detail).at(pointer))
        };
        return match (form.model, form.image) {
            (Some(model), None) => {
                Box::pin(super::model::compare(state, form.request, model)).await
            }
            (None, Some(image)) => {
                let request = form.request.ok_or_else(|| {
                    missing(
                        "/request",
                        "no `request` part: an image is compared with the render the `request` \
                         part asks for",
                    )
                })?;
                let png = media::prefers_to_json(&parts.headers, IMAGE_PNG);
                Box::pin(compare_image(state, request, image, png)).await
            }
            (Some(_), Some(_)) => Err(missing(
                "/image",
                "a `model` and an `image` part: a compare's form carries one candidate",
            )),
            (None, None) => Err(missing(
                "/image",
                "no `image` or `model` part: the form carries the candidate's PNG in `image`, \
                 or a GLB whose COLOR_0 holds it in `model`",
            )),
        };
    }
    let body = state.read_pooled_body(&parts.headers, body).await?;
    let limits = state.limits;
    let json =
        Box::pin(state.run(move |_| respond(&scene::parse_compare(&body, &limits)?))).await?;
    Ok(answer(json))
}

/// An image compare: the answer's JSON, or with `png` the heatmap's PNG.
async fn compare_image(
    state: AppState,
    request: Bytes,
    image: Bytes,
    png: bool,
) -> Result<Response, ApiError> {
    let limits = state.limits;
    let compared = state
        .run(move |cancel| {
            let scene = scene::parse_compare_image(&request, &image, &limits)?;
            let pixels = scene.render.region.pixels();
            let compared = crate::compare::image::compare_image(&scene, &|| cancel.is_cancelled());
            Ok(compared.map(|c| (c, pixels)))
        })
        .await?
        // `None`: the client went away, and nobody awaits this answer.
        .ok_or_else(ApiError::internal)?;
    let (
        ImageCompared {
            response,
            heatmap_png,
        },
        pixels,
    ) = compared;
    state.metrics.add_pixels(pixels);
    Ok(if png {
        ([(header::CONTENT_TYPE, "image/png")], heatmap_png).into_response()
    } else {
        answer(serde_json::to_vec(&response).expect("a response always serialises"))
    })
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

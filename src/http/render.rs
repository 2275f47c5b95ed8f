//! `POST /v1/render`: extract, negotiate the form, hand to the pool, map.

use axum::extract::{Request, State};
use axum::http::{HeaderMap, header};
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use super::media::{self, Content};
use crate::render::{self, Form};
use crate::scene;

pub async fn render(State(state): State<AppState>, request: Request) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Content::Model(kind) = media::content(&parts.headers)? {
        return Box::pin(super::model::render(state, parts, body, kind)).await;
    }
    let form = negotiate(&parts.headers);
    let body = state.read_pooled_body(&parts.headers, body).await?;
    let limits = state.limits;
    let rendered = state
        .run(move |cancel| {
            let scene = scene::parse_render(&body, &limits)?;
            Ok(render::render(&scene, form, &|| cancel.is_cancelled()))
        })
        .await?
        // `None` means the render stopped because its client went away, and
        // then nobody awaits this answer.
        .ok_or_else(ApiError::internal)?;
    state.metrics.add_pixels(rendered.pixels);
    Ok(negotiated(rendered.content_type, rendered.body))
}

/// A `200` whose form `Accept` chose: of `content_type`, with `Vary: accept`.
pub(super) fn negotiated(content_type: &'static str, body: impl IntoResponse) -> Response {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::VARY, "accept"),
        ],
        body,
    )
        .into_response()
}

/// The form the client prefers: JSON when its `Accept` ranks
/// `application/json` above `image/png` (see [`media::prefers_json`]); a
/// missing or unsatisfiable `Accept` gets the default, PNG, rather than a
/// 406.
pub(super) fn negotiate(headers: &HeaderMap) -> Form {
    if media::prefers_json(headers, media::IMAGE_PNG) {
        Form::Json
    } else {
        Form::Png
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn form(accept: &str) -> Form {
        let mut headers = HeaderMap::new();
        headers.insert(header::ACCEPT, accept.parse().unwrap());
        negotiate(&headers)
    }

    #[test]
    fn accept_header_chooses_the_form() {
        assert_eq!(negotiate(&HeaderMap::new()), Form::Png);
        assert_eq!(form("application/json"), Form::Json);
        assert_eq!(form("Application/JSON; charset=utf-8"), Form::Json);
        assert_eq!(form("image/png"), Form::Png);
        assert_eq!(form("*/*"), Form::Png);
        assert_eq!(form("application/json, text/plain, */*"), Form::Json);
        // A tie goes to the type the client lists first.
        assert_eq!(form("application/json, image/png"), Form::Json);
        assert_eq!(form("image/png, application/json"), Form::Png);
        assert_eq!(form("image/png;q=0.5, application/json"), Form::Json);
        assert_eq!(form("application/json;q=0.5, image/*"), Form::Png);
        assert_eq!(form("application/json;q=0, */*"), Form::Png);
        assert_eq!(form("text/html"), Form::Png);
    }
}

//! `POST /v1/render`: extract, negotiate the form, hand to the pool, map.

use axum::extract::{Request, State};
use axum::http::{HeaderMap, header};
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;
use crate::render::{self, Form};
use crate::scene;

pub async fn render(State(state): State<AppState>, request: Request) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Some(kind) = super::model::model_body(&parts.headers) {
        return Box::pin(super::model::render(state, parts, body, kind?)).await;
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

/// The form the client prefers: JSON only when its `Accept` ranks
/// `application/json` above `image/png`, by quality and then by naming it
/// explicitly (so `application/json, */*` is JSON, and a tie of two explicit
/// types is the default PNG). A missing or unsatisfiable `Accept` gets the
/// default, PNG, rather than a 406.
pub(super) fn negotiate(headers: &HeaderMap) -> Form {
    if prefers_json(headers, ("image", "png")) {
        Form::Json
    } else {
        Form::Png
    }
}

/// Whether `Accept` ranks `application/json` above `default` (a type and
/// subtype, the answer's default form), as [`negotiate`] ranks it above
/// `image/png`.
pub(super) fn prefers_json(headers: &HeaderMap, (kind, subtype): (&str, &str)) -> bool {
    let mut json = Preference::NONE;
    let mut other = Preference::NONE;
    for value in headers.get_all(header::ACCEPT) {
        let Ok(value) = value.to_str() else { continue };
        for range in value.split(',') {
            let mut params = range.split(';');
            let media = params.next().unwrap_or("").trim().to_ascii_lowercase();
            let q = params
                .filter_map(|p| p.split_once('='))
                .find(|(k, _)| k.trim().eq_ignore_ascii_case("q"))
                .and_then(|(_, v)| v.trim().parse::<f32>().ok())
                .unwrap_or(1.0);
            json.consider(&media, "application", "json", q);
            other.consider(&media, kind, subtype, q);
        }
    }
    json.beats(&other)
}

/// The most specific media range that matches a type, and its quality.
#[derive(Clone, Copy)]
struct Preference {
    /// 0 none, 1 `*/*`, 2 `type/*`, 3 `type/subtype`.
    specificity: u8,
    q: f32,
}

impl Preference {
    const NONE: Self = Self {
        specificity: 0,
        q: 0.0,
    };

    fn consider(&mut self, media: &str, kind: &str, subtype: &str, q: f32) {
        let specificity = match media.split_once('/') {
            Some(("*", "*")) => 1,
            Some((k, "*")) if k == kind => 2,
            Some((k, s)) if k == kind && s == subtype => 3,
            _ => return,
        };
        // RFC 9110 §12.5.1: the most specific range decides the quality.
        if specificity > self.specificity {
            *self = Self { specificity, q };
        }
    }

    fn beats(&self, other: &Self) -> bool {
        self.q > 0.0
            && (self.q > other.q
                || (self.q == other.q && self.specificity == 3 && other.specificity < 3))
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
        assert_eq!(form("application/json, image/png"), Form::Png);
        assert_eq!(form("image/png;q=0.5, application/json"), Form::Json);
        assert_eq!(form("application/json;q=0.5, image/*"), Form::Png);
        assert_eq!(form("application/json;q=0, */*"), Form::Png);
        assert_eq!(form("text/html"), Form::Png);
    }
}

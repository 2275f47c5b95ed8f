//! `POST /v1/shade` and `POST /v1/render` with a glTF model: a
//! `multipart/form-data` body with a `model` part (the GLB) and an optional
//! `request` part (JSON), or a bare `model/gltf-binary` body. The body is
//! read as a JSON body is (within the size limit and the body timeout,
//! refused as busy before it is read while the pool is full); its parts are
//! split, parsed and lit on the pool.

use std::collections::VecDeque;
use std::convert::Infallible;
use std::pin::Pin;
use std::task::{Context, Poll};

use axum::body::{Body, Bytes};
use axum::http::request::Parts;
use axum::http::{HeaderMap, header};
use axum::response::Response;
use glint_model::edit::Written;

use super::AppState;
use super::error::ApiError;
use super::multipart;
use crate::problem::{Problem, ProblemKind};
use crate::scene::{self, RequestError};
use crate::{bake, render};

/// How a request carries its model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ModelBody {
    /// `multipart/form-data` with this boundary.
    Form(String),
    /// `model/gltf-binary`.
    Glb,
}

/// The model body of a request, `None` when its content type is not one;
/// an error for `multipart/form-data` without a usable boundary.
pub fn model_body(headers: &HeaderMap) -> Option<Result<ModelBody, ApiError>> {
    let content_type = headers.get(header::CONTENT_TYPE)?.to_str().ok()?;
    let essence = content_type.split(';').next().unwrap_or("").trim();
    if essence.eq_ignore_ascii_case(glint_model::glb::MEDIA_TYPE) {
        return Some(Ok(ModelBody::Glb));
    }
    multipart::boundary(content_type).map(|boundary| {
        boundary
            .map(ModelBody::Form)
            .map_err(|e| ApiError::from(Problem::new(ProblemKind::Malformed, e.0).at("")))
    })
}

/// The `request` part (if any) and the `model` part of a body.
pub fn split(body: &Bytes, kind: &ModelBody) -> Result<(Option<Bytes>, Bytes), RequestError> {
    let boundary = match kind {
        ModelBody::Glb => return Ok((None, body.clone())),
        ModelBody::Form(boundary) => boundary,
    };
    let parts = multipart::parts(body, boundary)
        .map_err(|e| RequestError::malformed("", format!("not multipart/form-data: {}", e.0)))?;
    let mut request = None;
    let mut model = None;
    for part in parts {
        let slot = match part.name.as_str() {
            "request" => &mut request,
            "model" => &mut model,
            other => {
                return Err(RequestError::malformed(
                    format!("/{}", other.replace('~', "~0").replace('/', "~1")),
                    format!("a part named {other:?}: a form has a `request` and a `model` part"),
                ));
            }
        };
        if slot.replace(part.body).is_some() {
            return Err(RequestError::malformed(
                format!("/{}", part.name),
                format!("two `{}` parts: a form has one of each", part.name),
            ));
        }
    }
    let model = model.ok_or_else(|| {
        RequestError::malformed(
            "/model",
            "no `model` part: the form carries the GLB in `model`",
        )
    })?;
    Ok((request, model))
}

/// A body sent in parts, as they are: the baked model's head, the input's
/// buffer (a slice of the request's body) and the attributes added.
struct Chunks(VecDeque<Bytes>);

impl http_body::Body for Chunks {
    type Data = Bytes;
    type Error = Infallible;

    fn poll_frame(
        mut self: Pin<&mut Self>,
        _: &mut Context<'_>,
    ) -> Poll<Option<Result<http_body::Frame<Bytes>, Infallible>>> {
        Poll::Ready(
            self.0
                .pop_front()
                .map(|part| Ok(http_body::Frame::data(part))),
        )
    }

    fn is_end_stream(&self) -> bool {
        self.0.is_empty()
    }

    fn size_hint(&self) -> http_body::SizeHint {
        http_body::SizeHint::with_exact(self.0.iter().map(|part| part.len() as u64).sum())
    }
}

/// Whether the client prefers JSON to `model/gltf-binary`, which a model's
/// shade answers by default.
fn bake_form(headers: &HeaderMap) -> bake::Form {
    if super::render::prefers_json(headers, ("model", "gltf-binary")) {
        bake::Form::Json
    } else {
        bake::Form::Glb
    }
}

pub async fn shade(
    state: AppState,
    parts: Parts,
    body: Body,
    kind: ModelBody,
) -> Result<Response, ApiError> {
    let form = bake_form(&parts.headers);
    let body = state.read_pooled_model_body(&parts.headers, body).await?;
    let limits = state.limits;
    let (baked, bin) = state
        .run(move |_| {
            let (request, model) = split(&body, &kind)?;
            let scene = scene::parse_bake(request.as_deref(), &model, &limits)?;
            let baked = bake::bake(scene, form);
            // The model's buffer is sent from the request's own bytes.
            let bin = model.slice(baked.body.bin.clone());
            Ok((baked, bin))
        })
        .await?;
    state.metrics.add_vertices(baked.vertices);
    let Written { head, tail, .. } = baked.body;
    let body = Chunks([Bytes::from(head), bin, Bytes::from(tail)].into());
    Ok(super::render::negotiated(
        baked.content_type,
        Body::new(body),
    ))
}

pub async fn render(
    state: AppState,
    parts: Parts,
    body: Body,
    kind: ModelBody,
) -> Result<Response, ApiError> {
    let form = super::render::negotiate(&parts.headers);
    let body = state.read_pooled_model_body(&parts.headers, body).await?;
    let limits = state.limits;
    let rendered = state
        .run(move |cancel| {
            let (request, model) = split(&body, &kind)?;
            let (scene, notes) = scene::parse_model_render(request.as_deref(), &model, &limits)?;
            Ok(render::render_noted(&scene, notes, form, &|| {
                cancel.is_cancelled()
            }))
        })
        .await?
        // `None`: the client went away, and nobody awaits this answer.
        .ok_or_else(ApiError::internal)?;
    state.metrics.add_pixels(rendered.pixels);
    Ok(super::render::negotiated(
        rendered.content_type,
        rendered.body,
    ))
}

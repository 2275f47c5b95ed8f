//! `POST /v1/shade`, `POST /v1/render` and `POST /v1/compare` with a glTF
//! model: a `multipart/form-data` body with a `model` part (the GLB) and an
//! optional `request` part (JSON), or a bare `model/gltf-binary` body. The body is
//! read within the size limit and the body timeout, and refused as busy
//! before it is read while the pool is full, as a JSON body is; a form is
//! split into its parts by `multer` as it arrives. The parts are parsed and
//! lit on the pool. The same reader takes an image compare's form
//! (`request` and `image`, [`super::compare`]).

use std::collections::VecDeque;
use std::convert::Infallible;
use std::pin::Pin;
use std::task::{Context, Poll};

use axum::body::{Body, Bytes};
use axum::http::HeaderMap;
use axum::http::request::Parts;
use axum::response::Response;
use glint_model::edit::Written;

use super::AppState;
use super::error::ApiError;
use super::media::{self, ModelBody};
use crate::problem::{Problem, ProblemKind};
use crate::scene;
use crate::{bake, render};

/// The parts of a model request: its `request` part, if any, and its model.
#[derive(Debug)]
struct ModelParts {
    request: Option<Bytes>,
    model: Bytes,
}

/// The parts of a form, by name, each at most once; a bare GLB is a form of
/// one `model` part.
#[derive(Debug, Default)]
pub(super) struct FormParts {
    pub request: Option<Bytes>,
    pub model: Option<Bytes>,
    pub image: Option<Bytes>,
}

/// The parts a shade's or a render's form may have.
const MODEL_PARTS: &[&str] = &["request", "model"];

impl FormParts {
    /// The parts of a model request: `model` is required.
    fn into_model(self) -> Result<ModelParts, ApiError> {
        let model = self.model.ok_or_else(|| {
            malformed(
                "/model",
                "no `model` part: the form carries the GLB in `model`",
            )
        })?;
        Ok(ModelParts {
            request: self.request,
            model,
        })
    }
}

impl AppState {
    /// Reads a model body bound for the pool, as [`AppState::read_pooled_body`]
    /// reads a JSON one: a bare GLB whole, a form split into its parts by
    /// `multer` as it arrives (the parts named in `names`, no other), within
    /// the size limit and the body timeout.
    pub(super) async fn read_parts(
        &self,
        headers: &HeaderMap,
        body: Body,
        kind: ModelBody,
        names: &'static [&'static str],
    ) -> Result<FormParts, ApiError> {
        let boundary = match kind {
            ModelBody::Glb => {
                let model = self.read_pooled_body(headers, body).await?;
                return Ok(FormParts {
                    model: Some(model),
                    ..FormParts::default()
                });
            }
            ModelBody::Form(boundary) => boundary,
        };
        super::body::check_length(headers, self.max_body_bytes)?;
        if self.pool.is_full() {
            super::body::discard(body, self.max_body_bytes, self.body_timeout);
            return Err(ApiError::busy(self.retry_after_secs));
        }
        let read = read_form(body, boundary, self.max_body_bytes, names);
        match tokio::time::timeout(self.body_timeout, read).await {
            Ok(parts) => parts,
            Err(_) => Err(ApiError::new(
                ProblemKind::Timeout,
                format!(
                    "the body did not arrive within {} ms",
                    self.body_timeout.as_millis()
                ),
            )),
        }
    }

    /// [`Self::read_parts`] of a shade's or a render's model.
    async fn read_model(
        &self,
        headers: &HeaderMap,
        body: Body,
        kind: ModelBody,
    ) -> Result<ModelParts, ApiError> {
        self.read_parts(headers, body, kind, MODEL_PARTS)
            .await?
            .into_model()
    }
}

/// The parts of a form: those named in `names`, each at most once, nothing
/// else.
async fn read_form(
    body: Body,
    boundary: String,
    max_bytes: usize,
    names: &'static [&'static str],
) -> Result<FormParts, ApiError> {
    let constraints = multer::Constraints::new()
        .allowed_fields(names.to_vec())
        .size_limit(multer::SizeLimit::new().whole_stream(max_bytes as u64));
    let mut form =
        multer::Multipart::with_constraints(body.into_data_stream(), boundary, constraints);
    let mut parts = FormParts::default();
    while let Some(field) = form.next_field().await.map_err(|e| form_error(e, names))? {
        let name = field.name().unwrap_or_default().to_owned();
        let bytes = field.bytes().await.map_err(|e| form_error(e, names))?;
        let slot = match name.as_str() {
            "model" => &mut parts.model,
            "image" => &mut parts.image,
            _ => &mut parts.request,
        };
        if slot.replace(bytes).is_some() {
            return Err(malformed(
                format!("/{name}"),
                format!("two `{name}` parts: a form has one of each"),
            ));
        }
    }
    Ok(parts)
}

fn malformed(pointer: impl Into<String>, detail: impl Into<String>) -> ApiError {
    ApiError::from(Problem::new(ProblemKind::Malformed, detail).at(pointer))
}

/// A form `multer` could not read, as the problem that says why; `names`
/// are the parts the form may have.
fn form_error(e: multer::Error, names: &[&str]) -> ApiError {
    match e {
        multer::Error::UnknownField { field_name } => {
            let name = field_name.unwrap_or_default();
            let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
            malformed(
                format!("/{}", name.replace('~', "~0").replace('/', "~1")),
                format!(
                    "a part named {name:?}: the parts of this form are {}",
                    names.join(", ")
                ),
            )
        }
        multer::Error::StreamSizeExceeded { limit } => ApiError::from(
            Problem::new(
                ProblemKind::OverLimit,
                format!("the body is over this server's limit of {limit} bytes"),
            )
            .at(""),
        ),
        e => malformed("", format!("not multipart/form-data: {e}")),
    }
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
    if media::prefers_json(headers, media::MODEL_GLB) {
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
    let ModelParts { request, model } = state.read_model(&parts.headers, body, kind).await?;
    let limits = state.limits;
    let (baked, bin) = state
        .run(move |_| {
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
    let ModelParts { request, model } = state.read_model(&parts.headers, body, kind).await?;
    let limits = state.limits;
    let rendered = state
        .run(move |cancel| {
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

/// A compare with a model: its candidate in the model's `COLOR_0`.
pub(super) async fn compare(
    state: AppState,
    request: Option<Bytes>,
    model: Bytes,
) -> Result<Response, ApiError> {
    let limits = state.limits;
    let json = state
        .run(move |_| {
            let scene = scene::parse_compare_model(request.as_deref(), &model, &limits)?;
            super::compare::respond(&scene)
        })
        .await?;
    Ok(super::compare::answer(json))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A form of `parts` (name, bytes) delimited by `boundary`.
    fn form(boundary: &str, parts: &[(&str, &[u8])]) -> Body {
        let mut body = Vec::new();
        for (name, bytes) in parts {
            body.extend(format!("--{boundary}\r\n").bytes());
            body.extend(format!("Content-Disposition: form-data; name=\"{name}\"\r\n\r\n").bytes());
            body.extend(*bytes);
            body.extend(b"\r\n");
        }
        body.extend(format!("--{boundary}--\r\n").bytes());
        Body::from(body)
    }

    #[tokio::test]
    async fn a_form_is_read_into_its_two_parts() {
        let body = form("b0undary", &[("request", b"{}"), ("model", b"glTF...")]);
        let parts = read_form(body, "b0undary".into(), 1 << 20, MODEL_PARTS)
            .await
            .unwrap();
        assert_eq!(parts.request.as_deref(), Some(&b"{}"[..]));
        assert_eq!(parts.model.as_deref(), Some(&b"glTF..."[..]));
    }

    #[tokio::test]
    async fn a_form_past_the_body_limit_is_over_the_limit() {
        // Its length undeclared (sent in chunks): counted as it is read.
        let body = form("b0undary", &[("model", &[7u8; 4096])]);
        let refused = read_form(body, "b0undary".into(), 1024, MODEL_PARTS)
            .await
            .unwrap_err();
        assert_eq!(refused.problem.kind(), ProblemKind::OverLimit);
    }
}

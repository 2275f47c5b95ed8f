//! Media types: what a request's `Content-Type` says its body is (parsed
//! by the `mediatype` crate), and which form of an answer its `Accept`
//! prefers (negotiated by `headers-accept`, which ranks media ranges as
//! RFC 9110 §12.5.1 does: the most specific range that matches a type gives
//! its quality, and among equal qualities the client's first listed wins).

use std::sync::LazyLock;

use axum::http::{HeaderMap, header};
use headers::HeaderMapExt;
use headers_accept::Accept;
use mediatype::names::{
    APPLICATION, CHARSET, FORM_DATA, GLTF_BINARY, IMAGE, JSON, MODEL, MULTIPART, PNG,
};
use mediatype::values::UTF_8;
use mediatype::{MediaType, Name, Value};

use super::error::ApiError;
use crate::problem::{Problem, ProblemKind};

/// `application/json`, the form every endpoint can answer in.
pub const APPLICATION_JSON: MediaType<'static> = MediaType::new(APPLICATION, JSON);

/// `image/png`, a render's default form.
pub const IMAGE_PNG: MediaType<'static> = MediaType::new(IMAGE, PNG);

/// `model/gltf-binary`, a model's shade's default form.
pub const MODEL_GLB: MediaType<'static> = MediaType::new(MODEL, GLTF_BINARY);

/// What a POST body is, by its content type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Content {
    /// `application/json` or `application/*+json`.
    Json,
    /// A glTF model: a bare GLB, or a form carrying one.
    Model(ModelBody),
}

/// How a request carries its model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ModelBody {
    /// `multipart/form-data` with this boundary.
    Form(String),
    /// `model/gltf-binary`.
    Glb,
}

/// What the content type of a POST says its body is: 415 for a type the
/// endpoints do not take (or none), 400 for a form without a boundary.
pub fn content(headers: &HeaderMap) -> Result<Content, ApiError> {
    let value = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok());
    let Some(media) = value.and_then(|v| MediaType::parse(v).ok()) else {
        return Err(unsupported());
    };
    if media.ty == APPLICATION && (media.subty == JSON || media.suffix == Some(JSON)) {
        return Ok(Content::Json);
    }
    if media.essence() == MODEL_GLB {
        return Ok(Content::Model(ModelBody::Glb));
    }
    if media.ty == MULTIPART && media.subty == FORM_DATA {
        let boundary = multer::parse_boundary(value.unwrap_or_default()).map_err(|_| {
            ApiError::from(
                Problem::new(
                    ProblemKind::Malformed,
                    "multipart/form-data needs a boundary parameter",
                )
                .at(""),
            )
        })?;
        return Ok(Content::Model(ModelBody::Form(boundary)));
    }
    Err(unsupported())
}

fn unsupported() -> ApiError {
    ApiError::new(
        ProblemKind::UnsupportedMediaType,
        "send the body as application/json, or a glTF model as multipart/form-data or \
         model/gltf-binary",
    )
}

/// Whether the client's `Accept` prefers `application/json` to `default`,
/// the answer's default form. A missing `Accept`, one that cannot be read,
/// or one that takes neither gets the default rather than a 406.
pub fn prefers_json(headers: &HeaderMap, default: MediaType<'static>) -> bool {
    prefers(headers, &[default], &json_forms())
}

/// Whether the client's `Accept` prefers `other` to `application/json`,
/// the answer's default form (an image compare's `image/png` heatmap). A
/// missing `Accept`, one that cannot be read, one that takes neither, or
/// one that takes both alike (`*/*`) gets JSON.
pub fn prefers_to_json(headers: &HeaderMap, other: MediaType<'static>) -> bool {
    prefers(headers, &json_forms(), &[other])
}

/// Whether the client's `Accept` chooses one of `others` over the answer's
/// `default` forms, which are offered first and so win equal preferences;
/// `false` without a readable `Accept`, or when it takes none of them.
fn prefers(
    headers: &HeaderMap,
    default: &[MediaType<'static>],
    others: &[MediaType<'static>],
) -> bool {
    let Ok(Some(accept)) = headers.typed_try_get::<Accept>() else {
        return false;
    };
    let available: Vec<MediaType<'static>> = default.iter().chain(others).cloned().collect();
    accept.negotiate(&available).is_some_and(|chosen| {
        others
            .iter()
            .any(|other| other.essence() == chosen.essence())
    })
}

/// `application/json` as a client may name it: bare, or with its UTF-8
/// charset in either case.
fn json_forms() -> [MediaType<'static>; 3] {
    static UTF_8_LOWER: LazyLock<[(Name<'static>, Value<'static>); 1]> =
        LazyLock::new(|| [(CHARSET, Value::new("utf-8").expect("a token"))]);
    [
        APPLICATION_JSON,
        MediaType::from_parts(APPLICATION, JSON, None, &[(CHARSET, UTF_8)]),
        MediaType::from_parts(APPLICATION, JSON, None, &*UTF_8_LOWER),
    ]
}

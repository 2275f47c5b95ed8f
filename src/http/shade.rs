//! `POST /v1/shade`: extract, evaluate (on the pool unless it is tiny), map.

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{HeaderValue, header};
use axum::response::Response;
use glint_lighting::kernel::TASK_VERTICES;

use super::AppState;
use super::error::ApiError;
use super::media::{self, Content};
use crate::scene::{self, ShadeScene, TermsDetail};
use crate::shade;

/// Bodies up to this size are parsed on the async worker that read them
/// (tens of microseconds); larger ones on the pool.
const INLINE_BODY_BYTES: usize = 16 * 1024;

/// Scenes of at most this much [`ShadeScene::work`] that do not ask for
/// every vertex's breakdown (whose JSON grows with vertices × lights) are
/// also lit there, in at most about a millisecond even by the reference
/// evaluator with a term summary. Handing them to the pool would cost more than the
/// work: a thread wake-up and a channel each way. When their length is
/// declared, they are never refused as busy, since they cost no more than
/// the HTTP handling that every request gets anyway. Work of no more than
/// one kernel task (vertices × (lights + 1) × sides, see
/// [`ShadeScene::work`]) is evaluated on the calling thread, as the kernel
/// and the reference evaluator evaluate such a batch, never on rayon's
/// global pool.
const INLINE_WORK: usize = TASK_VERTICES;

pub async fn shade(State(state): State<AppState>, request: Request) -> Result<Response, ApiError> {
    let (parts, body) = request.into_parts();
    if let Content::Model(kind) = media::content(&parts.headers)? {
        return Box::pin(super::model::shade(state, parts, body, kind)).await;
    }
    let declared = super::body::declared_length(&parts.headers);
    let body = if declared.is_some_and(|n| n <= INLINE_BODY_BYTES as u64) {
        state.read_body(&parts.headers, body).await?
    } else {
        state.read_pooled_body(&parts.headers, body).await?
    };
    let limits = state.limits;
    let (json, vertices) = if body.len() <= INLINE_BODY_BYTES {
        let scene = scene::parse_shade(&body, &limits)?;
        if scene.work() <= INLINE_WORK && scene.terms != TermsDetail::PerVertex {
            // The pool turns a panic into a 500; so does this.
            std::panic::catch_unwind(|| respond(&scene)).map_err(|_| ApiError::internal())?
        } else {
            // Boxed, here and below: the hand-off's future holds the scene
            // and would make every request's future, moved several times on
            // its way through the stack, kilobytes larger.
            Box::pin(state.run(move |_| Ok(respond(&scene)))).await?
        }
    } else {
        Box::pin(state.run(move |_| Ok(respond(&scene::parse_shade(&body, &limits)?)))).await?
    };
    state.metrics.add_vertices(vertices);
    let mut response = Response::new(Body::from(json));
    response.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    Ok(response)
}

/// The response body and the number of vertices lit.
fn respond(scene: &ShadeScene) -> (Vec<u8>, usize) {
    let json = shade::shade(scene).to_json();
    (json, scene.positions.len())
}

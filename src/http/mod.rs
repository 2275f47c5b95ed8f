//! The HTTP service: the only module that knows axum. Handlers read the
//! request, hand the work to the [`Pool`], and map the result; parsing,
//! validation, lighting and serialisation of large bodies all happen on the
//! pool, never on the async runtime. This module holds the router and what
//! its handlers share; [`serve`] puts it on a socket.

mod body;
mod compare;
mod error;
mod media;
mod metrics;
mod model;
mod ops;
mod playground;
mod render;
mod serve;
mod shade;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use axum::Router;
use axum::body::{Body, Bytes};
use axum::http::{HeaderMap, HeaderName, HeaderValue, Method, header};
use axum::routing::{get, post};
use tower::ServiceBuilder;
use tower_http::cors::{AllowOrigin, Any, CorsLayer};
use tower_http::request_id::{
    MakeRequestId, PropagateRequestId, PropagateRequestIdLayer, RequestId, SetRequestId,
    SetRequestIdLayer,
};
use tower_http::set_header::{SetResponseHeader, SetResponseHeaderLayer};

pub use error::ApiError;
pub use metrics::{Metrics, Observe, Observed};
pub use ops::OPENAPI_YAML;
pub use serve::{run, serve, serve_on};

use crate::config::ServeConfig;
use crate::pool::{Cancel, JobError, Pool};
use crate::scene::{Limits, RequestError};

/// What every handler shares, behind one reference count: axum clones the
/// state for every request.
#[derive(Clone)]
pub struct AppState(Arc<Shared>);

/// The fields of [`AppState`].
pub struct Shared {
    pub pool: Pool,
    pub limits: Limits,
    pub metrics: Metrics,
    /// Set when shutdown begins: `/readyz` then answers 503.
    pub shutting_down: AtomicBool,
    pub max_body_bytes: usize,
    pub body_timeout: Duration,
    pub request_timeout: Duration,
    pub retry_after_secs: u64,
    /// This replica's name, sent in every response's `x-served-by`.
    pub served_by: HeaderValue,
    /// Whether `/` serves the playground.
    pub playground: bool,
}

impl std::ops::Deref for AppState {
    type Target = Shared;

    fn deref(&self) -> &Shared {
        &self.0
    }
}

impl AppState {
    pub fn new(config: &ServeConfig) -> std::io::Result<Self> {
        let instance = config.instance_id();
        HeaderValue::try_from(instance.as_str()).map_err(|_| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("the instance id {instance:?} cannot be sent in a header"),
            )
        })?;
        // Static, so that each answer's copy of it is a pointer rather than
        // a count that every thread answering requests updates: a few bytes
        // kept for the life of the process, once per server.
        let served_by = HeaderValue::from_static(Box::leak(instance.into_boxed_str()));
        let pool = Pool::new(config.threads, config.max_jobs, config.queue)?;
        Ok(Self(Arc::new(Shared {
            pool,
            limits: config.limits(),
            metrics: Metrics::default(),
            shutting_down: AtomicBool::new(false),
            max_body_bytes: config.max_body_bytes,
            body_timeout: config.body_timeout(),
            request_timeout: config.request_timeout(),
            retry_after_secs: config.retry_after_secs,
            served_by,
            playground: config.playground,
        })))
    }

    /// Reads a body within this server's size and time limits.
    async fn read_body(&self, headers: &HeaderMap, body: Body) -> Result<Bytes, ApiError> {
        body::check_length(headers, self.max_body_bytes)?;
        body::read(body, self.max_body_bytes, self.body_timeout).await
    }

    /// Reads a body bound for the pool: while the pool is full, refused
    /// with 503 before a byte of it is read (after the head's own checks,
    /// whose errors no retry would mend), so that a saturated server neither
    /// waits for nor holds the bodies it will refuse. What the client still
    /// sends is then read and dropped (see [`body::discard`]).
    async fn read_pooled_body(&self, headers: &HeaderMap, body: Body) -> Result<Bytes, ApiError> {
        body::check_length(headers, self.max_body_bytes)?;
        if self.pool.is_full() {
            body::discard(body, self.max_body_bytes, self.body_timeout);
            return Err(ApiError::busy(self.retry_after_secs));
        }
        body::read(body, self.max_body_bytes, self.body_timeout).await
    }

    /// Runs `job` on the pool within the request deadline; a refusal or a
    /// missed deadline is a 503 with Retry-After, never a half answer.
    async fn run<T, F>(&self, job: F) -> Result<T, ApiError>
    where
        T: Send + 'static,
        F: FnOnce(&Cancel<'_, Result<T, RequestError>>) -> Result<T, RequestError> + Send + 'static,
    {
        let outcome = tokio::time::timeout(self.request_timeout, self.pool.run(job)).await;
        match outcome {
            Ok(Ok(result)) => result.map_err(ApiError::from),
            Ok(Err(JobError::Busy)) => Err(ApiError::busy(self.retry_after_secs)),
            Ok(Err(JobError::Panicked)) => Err(ApiError::internal()),
            Err(_) => Err(ApiError::deadline(
                self.request_timeout,
                self.retry_after_secs,
            )),
        }
    }
}

/// The service's routes, also the `route` label of its metrics.
const ROUTES: [&str; 9] = [
    "/v1/shade",
    "/v1/render",
    "/v1/compare",
    "/healthz",
    "/readyz",
    "/metrics",
    "/openapi.yaml",
    "/",
    "/playground/{file}",
];

/// The whole service, as [`app`] builds it.
pub type App =
    SetRequestId<PropagateRequestId<SetResponseHeader<Observed<Router>, HeaderValue>>, RequestIds>;

/// The service, without a socket (tests call it with `oneshot`): its
/// [`routes`] inside [`Observe`], which counts and logs every request, CORS
/// preflights and unknown paths too (around the router rather than a layer
/// of it, which would wrap every route in one more boxed service and
/// future); inside tower-http's layers that name each request
/// (`x-request-id`: the client's, or a new one, echoed in the answer) and
/// name the replica in every answer (`x-served-by`).
pub fn app(state: AppState, cors_origins: &[String]) -> App {
    let request_id = HeaderName::from_static(glint_protocol::REQUEST_ID);
    ServiceBuilder::new()
        .layer(SetRequestIdLayer::new(
            request_id.clone(),
            RequestIds::default(),
        ))
        .layer(PropagateRequestIdLayer::new(request_id))
        .layer(SetResponseHeaderLayer::overriding(
            HeaderName::from_static(glint_protocol::SERVED_BY),
            state.served_by.clone(),
        ))
        .layer(Observe(state.clone()))
        .service(routes(state, cors_origins))
}

/// The service's routes, with CORS when origins are configured.
pub fn routes(state: AppState, cors_origins: &[String]) -> Router {
    let [
        shading,
        rendering,
        comparing,
        health,
        readiness,
        metering,
        contract,
        page,
        files,
    ] = ROUTES;
    let router = Router::new()
        .route(shading, post(shade::shade))
        .route(rendering, post(render::render))
        .route(comparing, post(compare::compare))
        .route(health, get(ops::healthz))
        .route(readiness, get(ops::readyz))
        .route(metering, get(ops::metrics))
        .route(contract, get(ops::openapi))
        .merge(playground::router(state.playground, page, files))
        .fallback(|| async { ApiError::not_found() })
        .method_not_allowed_fallback(|| async { ApiError::method_not_allowed() });
    let router = match cors(cors_origins) {
        Some(cors) => router.layer(cors),
        None => router,
    };
    router.with_state(state)
}

/// CORS for browser tools: none unless origins are configured.
fn cors(origins: &[String]) -> Option<CorsLayer> {
    if origins.is_empty() {
        return None;
    }
    let allow = if origins.iter().any(|o| o == "*") {
        AllowOrigin::from(Any)
    } else {
        AllowOrigin::list(origins.iter().filter_map(|o| HeaderValue::from_str(o).ok()))
    };
    let layer = CorsLayer::new()
        .allow_origin(allow)
        .allow_methods([Method::GET, Method::POST])
        .allow_headers([header::CONTENT_TYPE, header::ACCEPT])
        .expose_headers([
            header::RETRY_AFTER,
            HeaderName::from_static(glint_protocol::REQUEST_ID),
            HeaderName::from_static(glint_protocol::SERVED_BY),
        ]);
    Some(layer)
}

/// Request ids for requests that come without one:
/// `{process}-{thread}-{n}`, a random prefix per process, the thread that
/// made it, and that thread's count, unique across replicas for practical
/// purposes. Each thread counts on its own, so that the threads answering
/// requests share no counter.
#[derive(Clone, Copy)]
pub struct RequestIds {
    /// Eight hex digits.
    prefix: u32,
}

impl Default for RequestIds {
    fn default() -> Self {
        let random = std::collections::hash_map::RandomState::new();
        Self {
            prefix: std::hash::BuildHasher::hash_one(&random, std::process::id()) as u32,
        }
    }
}

impl MakeRequestId for RequestIds {
    fn make_request_id<B>(&mut self, _: &axum::http::Request<B>) -> Option<RequestId> {
        static THREADS: AtomicU64 = AtomicU64::new(1);
        thread_local! {
            /// This thread's number, and its count of ids made.
            static MADE: std::cell::Cell<(u64, u64)> =
                std::cell::Cell::new((THREADS.fetch_add(1, Ordering::Relaxed), 0));
        }
        let (thread, n) = MADE.with(|made| {
            let (thread, n) = made.get();
            made.set((thread, n + 1));
            (thread, n + 1)
        });
        let id = HeaderValue::try_from(format!("{:08x}-{thread}-{n}", self.prefix))
            .expect("hex digits, dashes and digits make a header value");
        Some(RequestId::new(id))
    }
}

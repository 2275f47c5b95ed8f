//! The HTTP service: the only module that knows axum. Handlers read the
//! request, hand the work to the [`Pool`], and map the result; parsing,
//! validation, lighting and serialisation of large bodies all happen on the
//! pool, never on the async runtime.

mod body;
mod error;
mod head_timeout;
mod metrics;
mod model;
mod multipart;
mod ops;
mod playground;
mod render;
mod shade;
mod sharded;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use axum::Router;
use axum::body::{Body, Bytes};
use axum::http::{HeaderMap, HeaderValue, Method, header};
use axum::routing::{get, post};
use tower::Layer;
use tower_http::cors::{AllowOrigin, Any, CorsLayer};

pub use error::ApiError;
pub use metrics::{Metrics, Observe, Observed};
pub use ops::OPENAPI_YAML;

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
    pub request_ids: RequestIds,
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
        // Static, so that each response's copy of it is a pointer rather
        // than a count that every thread answering requests updates: a few
        // bytes kept for the life of the process, once per server.
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
            request_ids: RequestIds::default(),
            served_by,
            playground: config.playground,
        })))
    }

    /// Reads a JSON body within this server's size and time limits.
    async fn read_body(&self, headers: &HeaderMap, body: Body) -> Result<Bytes, ApiError> {
        body::read_json(headers, body, self.max_body_bytes, self.body_timeout).await
    }

    /// Reads a JSON body bound for the pool: while the pool is full, refused
    /// with 503 before a byte of it is read (after the head's own checks,
    /// whose errors no retry would mend), so that a saturated server neither
    /// waits for nor holds the bodies it will refuse. What the client still
    /// sends is then read and dropped (see [`body::discard`]).
    async fn read_pooled_body(&self, headers: &HeaderMap, body: Body) -> Result<Bytes, ApiError> {
        body::check_head(headers, self.max_body_bytes)?;
        if self.pool.is_full() {
            body::discard(body, self.max_body_bytes, self.body_timeout);
            return Err(ApiError::busy(self.retry_after_secs));
        }
        self.read_body(headers, body).await
    }

    /// Reads a model body bound for the pool, as [`Self::read_pooled_body`]
    /// reads a JSON one; its content type is the caller's.
    async fn read_pooled_model_body(
        &self,
        headers: &HeaderMap,
        body: Body,
    ) -> Result<Bytes, ApiError> {
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
const ROUTES: [&str; 8] = [
    "/v1/shade",
    "/v1/render",
    "/healthz",
    "/readyz",
    "/metrics",
    "/openapi.yaml",
    "/",
    "/playground/{file}",
];

/// The header naming the replica that answered, on every response.
pub(crate) const SERVED_BY: header::HeaderName = header::HeaderName::from_static("x-served-by");

/// The service, without a socket (tests call it with `oneshot`): its
/// [`routes`] inside [`Observe`], which names, counts and logs every
/// request, CORS preflights and unknown paths too, and names the replica in
/// every response. Around the router rather than a layer of it, which would
/// wrap every route in one more boxed service and future.
pub fn app(state: AppState, cors_origins: &[String]) -> Observed<Router> {
    Observe(state.clone()).layer(routes(state, cors_origins))
}

/// The service's routes, with CORS when origins are configured.
pub fn routes(state: AppState, cors_origins: &[String]) -> Router {
    let [
        shading,
        rendering,
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
            header::HeaderName::from_static("x-request-id"),
            SERVED_BY,
        ]);
    Some(layer)
}

/// Request ids for requests that come without one: a per-process random
/// prefix and a counter, unique across replicas for practical purposes.
///
/// Each thread takes the counter's values [`IDS_PER_TAKE`] at a time and
/// hands them out itself, so that the threads answering requests do not
/// pass the counter's cache line between them on every request: ids are
/// unique, and increase on each thread, but not in the order the requests
/// came across threads.
pub struct RequestIds {
    /// The prefix in hex, and the dash after it.
    prefix: [u8; PREFIX],
    next: AtomicU64,
    /// Tells the threads' ranges of one `RequestIds` from another's.
    instance: u64,
}

/// The bytes of a request id's prefix: 8 hex digits and a dash.
const PREFIX: usize = 9;

/// How many ids a thread takes from the counter at a time.
const IDS_PER_TAKE: u64 = 1024;

thread_local! {
    /// The range of ids this thread holds: (instance, next, end).
    static TAKEN_IDS: std::cell::Cell<(u64, u64, u64)> = const { std::cell::Cell::new((0, 0, 0)) };
}

impl Default for RequestIds {
    fn default() -> Self {
        static INSTANCES: AtomicU64 = AtomicU64::new(1);
        let random = std::collections::hash_map::RandomState::new();
        let random = std::hash::BuildHasher::hash_one(&random, std::process::id()) as u32;
        let mut prefix = [b'-'; PREFIX];
        for (i, digit) in prefix[..PREFIX - 1].iter_mut().enumerate() {
            *digit = b"0123456789abcdef"[(random >> (28 - 4 * i) & 0xf) as usize];
        }
        Self {
            prefix,
            next: AtomicU64::new(1),
            instance: INSTANCES.fetch_add(1, Ordering::Relaxed),
        }
    }
}

impl RequestIds {
    /// `{prefix:08x}-{n}`, written without `format!`.
    fn next(&self) -> HeaderValue {
        let n = TAKEN_IDS.with(|taken| {
            let (instance, next, end) = taken.get();
            let (next, end) = if instance == self.instance && next < end {
                (next, end)
            } else {
                let first = self.next.fetch_add(IDS_PER_TAKE, Ordering::Relaxed);
                (first, first + IDS_PER_TAKE)
            };
            taken.set((self.instance, next + 1, end));
            next
        });
        let mut digits = [0; 20];
        let digits = crate::response::decimal(n, &mut digits);
        let mut id = [0; PREFIX + 20];
        id[..PREFIX].copy_from_slice(&self.prefix);
        id[PREFIX..PREFIX + digits.len()].copy_from_slice(digits);
        HeaderValue::from_maybe_shared(Bytes::copy_from_slice(&id[..PREFIX + digits.len()]))
            .expect("hex digits, a dash and digits make a header value")
    }
}

/// Serves until SIGTERM or Ctrl-C, then stops taking connections, gives
/// in-flight requests the grace period to finish, and returns.
pub async fn serve(config: &ServeConfig) -> anyhow::Result<()> {
    let listener = tokio::net::TcpListener::bind(config.listen).await?;
    let state = AppState::new(config)?;
    tracing::info!(
        address = %listener.local_addr()?,
        workers = state.pool.threads(),
        instance = ?state.served_by,
        "glint listening"
    );
    serve_on(listener, state, config, shutdown_signal()).await
}

/// Serves on `listener` until `shutdown` completes; the testable core of
/// [`serve`].
///
/// Each connection has `header_timeout` to send its request head (a client
/// that trickles its headers is cut off). On shutdown `/readyz` turns 503;
/// new connections are still served for the drain (`--drain-ms`), so that a
/// load balancer's health checks see the replica leave while it answers;
/// then the listener closes so new connections are refused, idle
/// connections are closed, and requests in flight get the grace period to
/// finish.
pub async fn serve_on(
    listener: tokio::net::TcpListener,
    state: AppState,
    config: &ServeConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> anyhow::Result<()> {
    use head_timeout::{Activity, Watched, WatchedIo};
    use hyper_util::rt::{TokioExecutor, TokioIo};
    use hyper_util::server::graceful::GracefulShutdown;

    let router = app(state.clone(), &config.cors_origins);
    // No hyper timer, so no hyper header timeout: `head_timeout` keeps it.
    let builder = hyper_util::server::conn::auto::Builder::new(TokioExecutor::new());
    let header_timeout = config.header_timeout();
    let connections = GracefulShutdown::new();
    let serve_connection = |stream: tokio::net::TcpStream| {
        let activity = Activity::new();
        let service = Watched {
            inner: OneConnection(std::cell::RefCell::new(router.for_connection())),
            activity: activity.clone(),
        };
        let io = WatchedIo {
            inner: stream,
            activity: activity.clone(),
        };
        let connection = builder
            .serve_connection_with_upgrades(TokioIo::new(io), service)
            .into_owned();
        let connection = connections.watch(connection);
        let connection = async move {
            if let Err(e) = connection.await {
                tracing::debug!(error = %e, "connection ended with an error");
            }
        };
        head_timeout::watch(connection, activity, header_timeout);
    };

    accept_until(&listener, shutdown, serve_connection).await;
    state.shutting_down.store(true, Ordering::Relaxed);
    let drain = config.drain();
    if !drain.is_zero() {
        tracing::info!(
            drain_ms = drain.as_millis() as u64,
            "draining: /readyz answers 503, new connections are still served"
        );
        accept_until(&listener, tokio::time::sleep(drain), serve_connection).await;
    }
    drop(listener);
    let grace = config.shutdown_grace();
    tracing::info!(grace_ms = grace.as_millis() as u64, "shutting down");
    tokio::select! {
        _ = connections.shutdown() => tracing::info!("every request finished"),
        _ = tokio::time::sleep(grace) => {
            tracing::warn!("requests still in flight at the end of the grace period")
        }
    }
    Ok(())
}

/// The service of one connection, called in place.
///
/// `hyper_util`'s `TowerToHyperService` clones the service for every
/// request, to call it as `tower` asks (`&mut`, after `poll_ready`): here a
/// clone of the router and of the state, each a count of references that
/// every connection's requests update, from every thread. The connection
/// owns this one instead and calls it in place: its calls are never nested
/// (each returns a future, polled later), so the cell is never borrowed
/// twice. Every service in the stack is always ready; it is asked all the
/// same, as `tower` wants, so that a layer that is not fails loudly here.
struct OneConnection<S>(std::cell::RefCell<S>);

impl<S, R> hyper::service::Service<R> for OneConnection<S>
where
    S: tower::Service<R, Error = std::convert::Infallible>,
{
    type Response = S::Response;
    type Error = S::Error;
    type Future = S::Future;

    fn call(&self, request: R) -> Self::Future {
        let mut service = self.0.borrow_mut();
        let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
        assert!(
            service.poll_ready(&mut cx).is_ready(),
            "every service of the stack is always ready"
        );
        service.call(request)
    }
}

/// Hands every connection `listener` accepts to `serve` until `until`
/// completes.
async fn accept_until(
    listener: &tokio::net::TcpListener,
    until: impl Future<Output = ()>,
    mut serve: impl FnMut(tokio::net::TcpStream),
) {
    let mut until = std::pin::pin!(until);
    loop {
        tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _peer)) => serve(stream),
                Err(e) => {
                    // Out of file descriptors and the like: pause, not spin.
                    tracing::warn!(error = %e, "accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                }
            },
            _ = &mut until => return,
        }
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}

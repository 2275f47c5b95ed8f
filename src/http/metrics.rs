//! Prometheus metrics, and the middleware that records and logs every request.

use std::convert::Infallible;
use std::pin::Pin;
use std::sync::{Arc, OnceLock};
use std::task::{Context, Poll, ready};
use std::time::Instant;

use axum::http::Request;
use axum::http::{HeaderName, HeaderValue, Method};
use axum::response::Response;
use prometheus_client::collector::Collector;
use prometheus_client::encoding::{
    DescriptorEncoder, EncodeLabelSet, EncodeLabelValue, EncodeMetric, LabelValueEncoder,
};
use prometheus_client::metrics::counter::{ConstCounter, Counter};
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::registry::Registry;

use tower::{Layer, Service};

use super::sharded::{ShardedCounter, ShardedHistogram};
use super::{AppState, ROUTES};
use crate::pool::Pool;
use crate::problem::ProblemKind;

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RequestLabels {
    route: &'static str,
    status: u16,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RouteLabels {
    route: &'static str,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct ReasonLabels {
    reason: Reason,
}

/// Why a request was refused: its problem's kind, named by its slug in the
/// metrics' own spelling (`over-limit` is `over_limit`).
#[derive(Clone, Copy, Debug, Hash, PartialEq, Eq)]
struct Reason(ProblemKind);

impl EncodeLabelValue for Reason {
    fn encode(&self, encoder: &mut LabelValueEncoder) -> Result<(), std::fmt::Error> {
        use std::fmt::Write;
        for (i, word) in self.0.slug().split('-').enumerate() {
            if i > 0 {
                encoder.write_char('_')?;
            }
            encoder.write_str(word)?;
        }
        Ok(())
    }
}

/// The service's metrics.
pub struct Metrics {
    registry: Registry,
    requests: Family<RequestLabels, ShardedCounter>,
    durations: Family<RouteLabels, ShardedHistogram>,
    vertices: ShardedCounter,
    pixels: ShardedCounter,
    rejections: Family<ReasonLabels, Counter>,
    queued: Gauge,
    running: Gauge,
    /// Per route (by its index in `ROUTES`, and one more for unmatched
    /// requests), its count of `200` answers and its latency histogram,
    /// looked up in the families once: the lookup takes a lock and hashes
    /// the labels.
    answered: [OnceLock<(ShardedCounter, ShardedHistogram)>; ROUTES.len() + 1],
}

impl Default for Metrics {
    fn default() -> Self {
        let requests = Family::<RequestLabels, ShardedCounter>::default();
        let durations = Family::<RouteLabels, ShardedHistogram>::default();
        let (vertices, pixels) = (ShardedCounter::default(), ShardedCounter::default());
        let rejections = Family::<ReasonLabels, Counter>::default();
        let (queued, running) = (Gauge::default(), Gauge::default());

        let mut registry = Registry::with_prefix("glint");
        registry.register("requests", "HTTP requests answered", requests.clone());
        registry.register(
            "request_duration_seconds",
            "Time from request to response head",
            durations.clone(),
        );
        registry.register(
            "vertices_shaded",
            "Vertices lit by /v1/shade",
            vertices.clone(),
        );
        registry.register(
            "pixels_shaded",
            "Pixels rendered by /v1/render",
            pixels.clone(),
        );
        registry.register(
            "rejections",
            "Requests refused before any work, by reason",
            rejections.clone(),
        );
        registry.register("jobs_queued", "Jobs waiting for a worker", queued.clone());
        registry.register("jobs_running", "Jobs running now", running.clone());
        registry.register_collector(Box::new(DroppedLogLines));
        Metrics {
            registry,
            requests,
            durations,
            vertices,
            pixels,
            rejections,
            queued,
            running,
            answered: Default::default(),
        }
    }
}

impl Metrics {
    /// Counts a request answered on `route` with `status` after `elapsed`.
    fn count(&self, route: Route, status: u16, elapsed: std::time::Duration) {
        let seconds = elapsed.as_secs_f64();
        let name = route.name();
        if status == 200 {
            let (answered, durations) = self.answered[route.0].get_or_init(|| {
                let labels = RequestLabels {
                    route: name,
                    status,
                };
                let answered = self.requests.get_or_create(&labels).clone();
                let durations = self.durations.get_or_create(&RouteLabels { route: name });
                (answered, durations.clone())
            });
            answered.inc();
            durations.observe(seconds);
        } else {
            let labels = RequestLabels {
                route: name,
                status,
            };
            self.requests.get_or_create(&labels).inc();
            let durations = self.durations.get_or_create(&RouteLabels { route: name });
            durations.observe(seconds);
        }
    }

    pub fn add_vertices(&self, n: usize) {
        self.vertices.inc_by(n as u64);
    }

    pub fn add_pixels(&self, n: u64) {
        self.pixels.inc_by(n);
    }

    /// Counts a refusal, by the kind of its problem. Only refusals of a
    /// request's body or of its timing count: not a missing endpoint or
    /// method, not a draining replica's `/readyz`, not a failure inside the
    /// server.
    fn reject(&self, kind: ProblemKind) {
        use ProblemKind::*;
        match kind {
            Malformed | Timeout | OverLimit | UnsupportedMediaType | Invalid | Busy => {
                self.rejections
                    .get_or_create(&ReasonLabels {
                        reason: Reason(kind),
                    })
                    .inc();
            }
            NotFound | MethodNotAllowed | Internal | ShuttingDown | Unreadable | NoOutput
            | Unwritable => {}
        }
    }

    /// The Prometheus text exposition, with the pool's gauges read now.
    pub fn encode(&self, pool: &Pool) -> String {
        self.queued.set(pool.queued() as i64);
        self.running.set(pool.running() as i64);
        let mut out = String::new();
        prometheus_client::encoding::text::encode(&mut out, &self.registry)
            .expect("writing to a String cannot fail");
        out
    }
}

/// The log lines dropped because the log's reader could not keep up,
/// read from the log writer at each scrape.
#[derive(Debug)]
struct DroppedLogLines;

impl Collector for DroppedLogLines {
    fn encode(&self, mut encoder: DescriptorEncoder) -> Result<(), std::fmt::Error> {
        let dropped = ConstCounter::new(crate::logging::dropped_lines());
        let metric = encoder.encode_descriptor(
            "log_lines_dropped",
            "Log lines dropped because the log's reader could not keep up",
            None,
            dropped.metric_type(),
        )?;
        dropped.encode(metric)
    }
}

/// A route of [`ROUTES`] by its index, or `ROUTES.len()` for a request no
/// route matched.
#[derive(Clone, Copy, Debug)]
struct Route(usize);

impl Route {
    /// The route whose pattern `path` matches, whatever the method, and
    /// whether or not the route is served (the playground's may be off).
    fn of(path: &str) -> Self {
        let index = ROUTES
            .iter()
            .position(|&route| match route.split_once('{') {
                None => path == route,
                // `/playground/{file}`: one segment after the prefix.
                Some((prefix, _)) => path
                    .strip_prefix(prefix)
                    .is_some_and(|rest| !rest.is_empty() && !rest.contains('/')),
            });
        Self(index.unwrap_or(ROUTES.len()))
    }

    fn name(self) -> &'static str {
        ROUTES.get(self.0).copied().unwrap_or("unmatched")
    }
}

/// The header that names a request in the logs of the service and of its
/// clients.
const X_REQUEST_ID: HeaderName = HeaderName::from_static("x-request-id");

/// Names each request (the client's `x-request-id`, or a new one), answers
/// with its name and the replica's (`x-served-by`), records it in the
/// metrics and writes its one log line: id, method, route, status, latency
/// and response size.
///
/// A layer written out rather than a middleware function
/// (`axum::middleware::from_fn`), which boxes the service it wraps and its
/// future at every request: that cost more than all the rest of this did.
#[derive(Clone)]
pub struct Observe(pub AppState);

impl<S> Layer<S> for Observe {
    type Service = Observed<S>;

    fn layer(&self, inner: S) -> Observed<S> {
        Observed {
            inner,
            state: Arc::new(self.0.clone()),
        }
    }
}

/// A route with [`Observe`] around it.
#[derive(Clone)]
pub struct Observed<S> {
    inner: S,
    /// Shared by the requests of the copies of this `Observed`: each
    /// request holds it while it is answered.
    state: Arc<AppState>,
}

impl<S: Clone> Observed<S> {
    /// A copy for one connection's requests, whose holds on the state
    /// count in a count of their own rather than in the one every other
    /// connection's requests update.
    pub fn for_connection(&self) -> Self {
        Self {
            inner: self.inner.clone(),
            state: Arc::new(AppState::clone(&self.state)),
        }
    }
}

impl<S, B> Service<Request<B>> for Observed<S>
where
    S: Service<Request<B>, Response = Response, Error = Infallible>,
    S::Future: Unpin,
{
    type Response = Response;
    type Error = Infallible;
    type Future = Observing<S::Future>;

    fn poll_ready(&mut self, cx: &mut Context<'_>) -> Poll<Result<(), Infallible>> {
        self.inner.poll_ready(cx)
    }

    fn call(&mut self, request: Request<B>) -> Self::Future {
        let started = Instant::now();
        let route = Route::of(request.uri().path());
        let method = request.method().clone();
        let id = match request.headers().get(X_REQUEST_ID) {
            Some(id) => id.clone(),
            None => self.state.request_ids.next(),
        };
        Observing {
            inner: self.inner.call(request),
            state: self.state.clone(),
            started,
            route,
            method,
            id: Some(id),
        }
    }
}

/// A request on its way through [`Observed`].
pub struct Observing<F> {
    inner: F,
    state: Arc<AppState>,
    started: Instant,
    route: Route,
    method: Method,
    id: Option<HeaderValue>,
}

impl<F> Future for Observing<F>
where
    F: Future<Output = Result<Response, Infallible>> + Unpin,
{
    type Output = Result<Response, Infallible>;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        let this = &mut *self;
        let Ok(mut response) = ready!(Pin::new(&mut this.inner).poll(cx));
        let answered = Instant::now();
        let elapsed = answered - this.started;
        let status = response.status().as_u16();
        let metrics = &this.state.metrics;
        if let Some(&kind) = response.extensions().get::<ProblemKind>() {
            metrics.reject(kind);
        }
        metrics.count(this.route, status, elapsed);
        let size = http_body::Body::size_hint(response.body()).exact();
        let id = this.id.take().expect("a request is answered once");
        crate::logging::access(&crate::logging::Access {
            at: answered,
            request_id: id.to_str().unwrap_or("-"),
            method: this.method.as_str(),
            route: this.route.name(),
            status,
            latency_ms: elapsed.as_secs_f64() * 1e3,
            size: size.map_or(-1, |n| n as i64),
        });
        let headers = response.headers_mut();
        headers.insert(X_REQUEST_ID, id);
        headers.insert(super::SERVED_BY, this.state.served_by.clone());
        Poll::Ready(Ok(response))
    }
}

//! Prometheus metrics, and the middleware that records and logs every request.

use std::convert::Infallible;
use std::pin::Pin;
use std::sync::OnceLock;
use std::task::{Context, Poll, ready};
use std::time::Instant;

use axum::http::{Method, Request};
use axum::response::Response;
use prometheus_client::collector::Collector;
use prometheus_client::encoding::{
    DescriptorEncoder, EncodeLabelSet, EncodeLabelValue, EncodeMetric, LabelValueEncoder,
};
use prometheus_client::metrics::counter::{ConstCounter, Counter};
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;
use tower::{Layer, Service};

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

/// The upper bounds of the latency histograms' buckets, besides `+Inf`:
/// 0.1 ms and 19 doublings after it, up to 52 s.
fn latency_buckets() -> impl Iterator<Item = f64> {
    exponential_buckets(0.0001, 2.0, 20)
}

/// The service's metrics.
pub struct Metrics {
    registry: Registry,
    requests: Family<RequestLabels, Counter>,
    durations: Family<RouteLabels, Histogram>,
    vertices: Counter,
    pixels: Counter,
    rejections: Family<ReasonLabels, Counter>,
    queued: Gauge,
    running: Gauge,
    /// Per route of [`ROUTES`], its count of `200` answers and its latency
    /// histogram, looked up in the families once: a lookup takes the
    /// family's lock and hashes the labels.
    answered: [OnceLock<(Counter, Histogram)>; ROUTES.len()],
}

impl Default for Metrics {
    fn default() -> Self {
        let requests = Family::<RequestLabels, Counter>::default();
        let durations = Family::<RouteLabels, Histogram>::new_with_constructor(|| {
            Histogram::new(latency_buckets())
        });
        let (vertices, pixels) = (Counter::default(), Counter::default());
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
    fn count(&self, route: &'static str, status: u16, elapsed: std::time::Duration) {
        let lookup = || {
            let requests = self
                .requests
                .get_or_create(&RequestLabels { route, status });
            let durations = self.durations.get_or_create(&RouteLabels { route });
            (requests.clone(), durations.clone())
        };
        let looked_up;
        let (requests, durations) = match ROUTES.iter().position(|&r| r == route) {
            Some(i) if status == 200 => self.answered[i].get_or_init(lookup),
            _ => {
                looked_up = lookup();
                &looked_up
            }
        };
        requests.inc();
        durations.observe(elapsed.as_secs_f64());
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

/// The route of [`ROUTES`] whose pattern `path` matches, whatever the
/// method and whether or not the route is served (the playground's may be
/// off); `unmatched` for none.
fn route_of(path: &str) -> &'static str {
    ROUTES
        .iter()
        .find(|&&route| match route.split_once('{') {
            None => path == route,
            // `/playground/{file}`: one segment after the prefix.
            Some((prefix, _)) => path
                .strip_prefix(prefix)
                .is_some_and(|rest| !rest.is_empty() && !rest.contains('/')),
        })
        .copied()
        .unwrap_or("unmatched")
}

/// Records every request in the metrics and writes its one log line: id
/// (the `x-request-id` that tower-http's request-id layer set or kept),
/// method, route, status, latency and response size.
///
/// A layer written out rather than a middleware function
/// (`axum::middleware::from_fn`), which boxes the service it wraps and its
/// future at every request.
#[derive(Clone)]
pub struct Observe(pub AppState);

impl<S> Layer<S> for Observe {
    type Service = Observed<S>;

    fn layer(&self, inner: S) -> Observed<S> {
        Observed {
            inner,
            state: self.0.clone(),
        }
    }
}

/// A service with [`Observe`] around it.
#[derive(Clone)]
pub struct Observed<S> {
    inner: S,
    state: AppState,
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
        let request_id = request
            .headers()
            .get(glint_protocol::REQUEST_ID)
            .and_then(|id| id.to_str().ok())
            .unwrap_or("-")
            .to_owned();
        Observing {
            started: Instant::now(),
            route: route_of(request.uri().path()),
            method: request.method().clone(),
            request_id,
            inner: self.inner.call(request),
            state: self.state.clone(),
        }
    }
}

/// A request on its way through [`Observed`].
pub struct Observing<F> {
    inner: F,
    state: AppState,
    started: Instant,
    route: &'static str,
    method: Method,
    request_id: String,
}

impl<F> Future for Observing<F>
where
    F: Future<Output = Result<Response, Infallible>> + Unpin,
{
    type Output = Result<Response, Infallible>;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        let this = &mut *self;
        let Ok(response) = ready!(Pin::new(&mut this.inner).poll(cx));
        let elapsed = this.started.elapsed();
        let status = response.status().as_u16();
        let metrics = &this.state.metrics;
        if let Some(&kind) = response.extensions().get::<ProblemKind>() {
            metrics.reject(kind);
        }
        metrics.count(this.route, status, elapsed);
        let size = http_body::Body::size_hint(response.body()).exact();
        crate::logging::access(&crate::logging::Access {
            request_id: &this.request_id,
            method: this.method.as_str(),
            route: this.route,
            status,
            latency_ms: elapsed.as_secs_f64() * 1e3,
            size: size.map_or(-1, |n| n as i64),
        });
        Poll::Ready(Ok(response))
    }
}

//! Prometheus metrics, and the middleware that records and logs every request.

use std::time::Instant;

use axum::extract::{MatchedPath, Request, State};
use axum::http::HeaderName;
use axum::middleware::Next;
use axum::response::Response;
use prometheus_client::encoding::{EncodeLabelSet, EncodeLabelValue, LabelValueEncoder};
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;

use super::AppState;
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
    requests: Family<RequestLabels, Counter>,
    durations: Family<RouteLabels, Histogram>,
    vertices: Counter,
    pixels: Counter,
    rejections: Family<ReasonLabels, Counter>,
    queued: Gauge,
    running: Gauge,
}

impl Default for Metrics {
    fn default() -> Self {
        let requests = Family::<RequestLabels, Counter>::default();
        let durations = Family::<RouteLabels, Histogram>::new_with_constructor(
            (|| Histogram::new(exponential_buckets(0.0001, 2.0, 20))) as fn() -> Histogram,
        );
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
        Metrics {
            registry,
            requests,
            durations,
            vertices,
            pixels,
            rejections,
            queued,
            running,
        }
    }
}

impl Metrics {
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

/// The header that names a request in the logs of the service and of its
/// clients.
const X_REQUEST_ID: HeaderName = HeaderName::from_static("x-request-id");

/// Names each request (the client's `x-request-id`, or a new one), answers
/// with its name, records it in the metrics and writes its one log line: id,
/// method, route, status, latency and response size.
pub async fn observe(State(state): State<AppState>, request: Request, next: Next) -> Response {
    let started = Instant::now();
    let matched = request.extensions().get::<MatchedPath>();
    let route = super::ROUTES
        .into_iter()
        .find(|r| matched.is_some_and(|m| m.as_str() == *r))
        .unwrap_or("unmatched");
    let method = request.method().clone();
    let id = match request.headers().get(X_REQUEST_ID) {
        Some(id) => id.clone(),
        None => state.request_ids.next(),
    };
    let mut response = next.run(request).await;
    let elapsed = started.elapsed();
    let status = response.status().as_u16();
    let metrics = &state.metrics;
    if let Some(&kind) = response.extensions().get::<ProblemKind>() {
        metrics.reject(kind);
    }
    metrics
        .requests
        .get_or_create(&RequestLabels { route, status })
        .inc();
    metrics
        .durations
        .get_or_create(&RouteLabels { route })
        .observe(elapsed.as_secs_f64());
    let size = http_body::Body::size_hint(response.body()).exact();
    tracing::info!(
        request_id = id.to_str().unwrap_or("-"),
        %method,
        %route,
        status,
        latency_ms = elapsed.as_secs_f64() * 1e3,
        size = size.map_or(-1, |n| n as i64),
        "request"
    );
    response.headers_mut().insert(X_REQUEST_ID, id);
    response
}

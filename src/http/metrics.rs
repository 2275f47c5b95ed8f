//! Prometheus metrics, and the middleware that records and logs every request.

use std::sync::Arc;
use std::time::Instant;

use axum::extract::{MatchedPath, Request, State};
use axum::middleware::Next;
use axum::response::Response;
use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;

use super::AppState;
use crate::pool::Pool;

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RequestLabels {
    route: String,
    status: u16,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RouteLabels {
    route: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct ReasonLabels {
    reason: String,
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

impl Metrics {
    pub fn new() -> Arc<Self> {
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
        Arc::new(Metrics {
            registry,
            requests,
            durations,
            vertices,
            pixels,
            rejections,
            queued,
            running,
        })
    }

    pub fn add_vertices(&self, n: usize) {
        self.vertices.inc_by(n as u64);
    }

    pub fn add_pixels(&self, n: u64) {
        self.pixels.inc_by(n);
    }

    /// Counts a refusal, named after its status.
    fn reject(&self, status: u16) {
        let reason = match status {
            400 => "malformed",
            408 => "timeout",
            413 => "over_limit",
            415 => "unsupported_media_type",
            422 => "invalid",
            429 | 503 => "busy",
            _ => return,
        };
        self.rejections
            .get_or_create(&ReasonLabels {
                reason: reason.to_owned(),
            })
            .inc();
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

/// Records each request in the metrics and writes its one log line: id,
/// method, route, status, latency and response size.
pub async fn observe(State(state): State<AppState>, request: Request, next: Next) -> Response {
    let started = Instant::now();
    let route = request
        .extensions()
        .get::<MatchedPath>()
        .map_or("unmatched", MatchedPath::as_str)
        .to_owned();
    let method = request.method().clone();
    let id = request
        .headers()
        .get("x-request-id")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("-")
        .to_owned();
    let response = next.run(request).await;
    let elapsed = started.elapsed();
    let status = response.status().as_u16();
    let metrics = &state.metrics;
    metrics.reject(status);
    metrics
        .requests
        .get_or_create(&RequestLabels {
            route: route.clone(),
            status,
        })
        .inc();
    metrics
        .durations
        .get_or_create(&RouteLabels {
            route: route.clone(),
        })
        .observe(elapsed.as_secs_f64());
    let size = http_body::Body::size_hint(response.body()).exact();
    tracing::info!(
        request_id = %id,
        %method,
        %route,
        status,
        latency_ms = elapsed.as_secs_f64() * 1e3,
        size = size.map_or(-1, |n| n as i64),
        "request"
    );
    response
}

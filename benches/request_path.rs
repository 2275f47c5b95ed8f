//! The request path in process: the 3-vertex shade of `benches/load.sh`
//! through glint's router (its layers, the body reader, parsing,
//! validation, lighting, the response) against the bare axum router of the
//! load benchmark (`benches/bare/mod.rs`: the same JSON work, no layers),
//! called one request at a time on one thread, with no sockets, no client
//! and no log line (the log is installed only by the binary). The
//! difference is what glint's request path costs beyond its JSON; the load
//! benchmark measures the rest, kernel and client included.
//!
//! `cargo bench --bench request_path`

use std::convert::Infallible;
use std::hint::black_box;

use axum::body::Body;
use axum::http::Request;
use criterion::{Criterion, criterion_group, criterion_main};
use tower::Service;

mod bare;

/// `examples/triangle.json` as a client asks for colours alone, as
/// `benches/load.sh` sends it.
fn body() -> Vec<u8> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/triangle.json");
    let mut request: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("the example exists"))
            .expect("the example is JSON");
    request.as_object_mut().expect("an object").remove("terms");
    serde_json::to_vec(&request).expect("JSON serialises")
}

fn request_path(c: &mut Criterion) {
    let body = body();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("a runtime");
    let state = glint::http::AppState::new(&glint::config::ServeConfig::default())
        .expect("the server's state");
    let bare = bare::router();
    let glint = glint::http::app(state, &[]);
    let mut group = c.benchmark_group("request_path");
    let post = || {
        Request::post("/v1/shade")
            .header("content-type", "application/json")
            .header("content-length", body.len())
            .body(Body::from(body.clone()))
            .expect("a request")
    };
    group.bench_function("bare axum, the same JSON work", |b| {
        b.iter(|| black_box(runtime.block_on(answer(bare.clone(), post()))))
    });
    group.bench_function("glint", |b| {
        b.iter(|| black_box(runtime.block_on(answer(glint.clone(), post()))))
    });
    group.finish();
}

/// The body of `service`'s answer to `request`, which must be a 200.
async fn answer<S>(mut service: S, request: Request<Body>) -> axum::body::Bytes
where
    S: Service<Request<Body>, Response = axum::response::Response, Error = Infallible>,
{
    let response = service.call(request).await.expect("infallible");
    assert_eq!(response.status(), 200);
    axum::body::to_bytes(response.into_body(), usize::MAX)
        .await
        .expect("a body")
}

criterion_group!(benches, request_path);
criterion_main!(benches);

//! glTF against JSON, and against the wire, end to end over loopback:
//! writes `docs/gltf.md`.
//!
//! One server runs glint's router and, beside it on the same stack
//! (hyper-util's connection loop, axum, the same body reading), a no-work
//! endpoint `POST /wire` that reads a body and answers as many bytes as it
//! is asked (`x-answer-bytes`): the ceiling of any endpoint that must read
//! that body and send that answer. A client on the same machine sends each
//! request and reads the whole answer; the requests run in turns, round
//! after round, so that the machine's drift touches each alike, and each
//! figure is the median of its rounds.
//!
//! - Bake: a 1M-vertex GLB (a grid: positions, normals, 32-bit indices) as
//!   `multipart/form-data` to `/v1/shade`, against `/wire` with the same
//!   body and the baked model's size, and against the same vertices and
//!   lighting as a JSON request.
//! - Render: a 100k-triangle GLB at 1920×1080 to `/v1/render`, against the
//!   same scene as JSON; and what reading and placing the model takes, on
//!   its own, beside the whole request.

use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::Request;
use axum::routing::post;
use glint::config::ServeConfig;
use glint::http::AppState;
use glint::scene::{Limits, parse_model_render};
use serde_json::{Value, json};
use tower::Layer;

/// Rounds of each measurement.
const ROUNDS: usize = 5;

/// A grid of `side × side` vertices, wavy, with its normals and two
/// triangles per cell: (positions, normals, indices).
fn grid(side: usize) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let mut positions = Vec::with_capacity(side * side);
    let mut normals = Vec::with_capacity(side * side);
    for j in 0..side {
        for i in 0..side {
            let (u, v) = (i as f32 / side as f32, j as f32 / side as f32);
            positions.push([u * 4.0 - 2.0, 0.2 * (u * 9.0).sin(), v * 4.0 - 2.0]);
            let n = [-(u * 9.0).cos() * 0.45, 1.0, 0.0f32];
            let l = (n[0] * n[0] + n[1] * n[1]).sqrt();
            normals.push([n[0] / l, n[1] / l, 0.0]);
        }
    }
    let mut indices = Vec::with_capacity((side - 1) * (side - 1) * 6);
    for j in 0..side as u32 - 1 {
        for i in 0..side as u32 - 1 {
            let a = j * side as u32 + i;
            let (b, c, d) = (a + 1, a + side as u32, a + side as u32 + 1);
            indices.extend([a, c, b, b, c, d]);
        }
    }
    (positions, normals, indices)
}

/// The grid as a GLB: one mesh, one node.
fn glb(positions: &[[f32; 3]], normals: &[[f32; 3]], indices: &[u32]) -> Vec<u8> {
    let bytes =
        |v: &[[f32; 3]]| -> Vec<u8> { v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect() };
    let (p, n) = (bytes(positions), bytes(normals));
    let i: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
    let (min, max) = positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), q| {
            (
                [lo[0].min(q[0]), lo[1].min(q[1]), lo[2].min(q[2])],
                [hi[0].max(q[0]), hi[1].max(q[1]), hi[2].max(q[2])],
            )
        });
    let json = json!({
        "asset": { "version": "2.0" }, "scene": 0, "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 2 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": min, "max": max },
            { "bufferView": 1, "componentType": 5126, "count": normals.len(), "type": "VEC3" },
            { "bufferView": 2, "componentType": 5125, "count": indices.len(), "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": p.len() },
            { "buffer": 0, "byteOffset": p.len(), "byteLength": n.len() },
            { "buffer": 0, "byteOffset": p.len() + n.len(), "byteLength": i.len() }
        ],
        "buffers": [{ "byteLength": p.len() + n.len() + i.len() }]
    });
    glint_model::glb::write(&serde_json::to_vec(&json).unwrap(), &[&p, &n, &i])
}

const BOUNDARY: &str = "glint-bench-boundary";

/// A `multipart/form-data` body of a `request` part and a `model` part.
fn form(request: &Value, model: &[u8]) -> Vec<u8> {
    let mut body = Vec::with_capacity(model.len() + 1024);
    body.extend(format!("--{BOUNDARY}\r\nContent-Disposition: form-data; name=\"request\"\r\nContent-Type: application/json\r\n\r\n").bytes());
    body.extend(serde_json::to_vec(request).unwrap());
    body.extend(format!("\r\n--{BOUNDARY}\r\nContent-Disposition: form-data; name=\"model\"; filename=\"grid.glb\"\r\nContent-Type: model/gltf-binary\r\n\r\n").bytes());
    body.extend(model);
    body.extend(format!("\r\n--{BOUNDARY}--\r\n").bytes());
    body
}

/// The lighting of every request: one directional light with specular, a
/// material with a highlight.
fn lighting() -> Value {
    json!({
        "lights": [{ "position": [0.3, 1.0, 0.5, 0.0] }],
        "material": { "diffuse": [0.8, 0.5, 0.3], "specular": [0.5, 0.5, 0.5], "shininess": 16 }
    })
}

/// Answers `x-answer-bytes` zero bytes, having read the whole body.
async fn wire(request: Request) -> Vec<u8> {
    let answer: usize = request.headers()["x-answer-bytes"]
        .to_str()
        .unwrap()
        .parse()
        .unwrap();
    let body = axum::body::to_bytes(request.into_body(), usize::MAX)
        .await
        .unwrap();
    std::hint::black_box(body.len());
    vec![0; answer]
}

/// Serves glint's router and `/wire` on a loopback port, on its own
/// runtime; returns the address.
fn serve() -> std::net::SocketAddr {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let runtime = tokio::runtime::Runtime::new().unwrap();
        runtime.block_on(async move {
            let config = ServeConfig {
                max_vertices: 8_000_000,
                max_body_bytes: 1 << 30,
                body_timeout_ms: 600_000,
                request_timeout_ms: 600_000,
                ..ServeConfig::default()
            };
            let state = AppState::new(&config).unwrap();
            let routes = glint::http::routes(state.clone(), &[])
                .merge(axum::Router::new().route("/wire", post(wire)));
            let router = glint::http::Observe(state).layer(routes);
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            tx.send(listener.local_addr().unwrap()).unwrap();
            let builder =
                hyper_util::server::conn::auto::Builder::new(hyper_util::rt::TokioExecutor::new());
            loop {
                let (stream, _) = listener.accept().await.unwrap();
                let service = hyper_util::service::TowerToHyperService::new(router.clone());
                let connection = builder
                    .serve_connection(hyper_util::rt::TokioIo::new(stream), service)
                    .into_owned();
                tokio::spawn(connection);
            }
        });
    });
    rx.recv().unwrap()
}

struct Client {
    runtime: tokio::runtime::Runtime,
    http: reqwest::Client,
    base: String,
}

impl Client {
    /// Posts `body` and reads the whole answer: (time, answer bytes).
    fn post(
        &self,
        path: &str,
        content_type: &str,
        body: &Bytes,
        headers: &[(&str, String)],
    ) -> (Duration, Vec<u8>) {
        self.runtime.block_on(async {
            let started = Instant::now();
            let mut request = self
                .http
                .post(format!("{}{path}", self.base))
                .header("content-type", content_type)
                .body(body.clone());
            for (k, v) in headers {
                request = request.header(*k, v);
            }
            let response = request.send().await.unwrap();
            let status = response.status();
            let answer = response.bytes().await.unwrap().to_vec();
            assert!(
                status.is_success(),
                "{path}: {status} {}",
                String::from_utf8_lossy(&answer[..answer.len().min(300)])
            );
            (started.elapsed(), answer)
        })
    }
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let addr = serve();
    let client = Client {
        runtime: tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap(),
        http: reqwest::Client::builder()
            .no_proxy()
            .timeout(Duration::from_secs(600))
            .build()
            .unwrap(),
        base: format!("http://{addr}"),
    };
    let mut report = String::new();
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_default();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());

    // Bake: 1000 × 1000 vertices.
    let (positions, normals, indices) = grid(1000);
    let model = glb(&positions, &normals, &indices);
    let request = lighting();
    let form_body = Bytes::from(form(&request, &model));
    let multipart = format!("multipart/form-data; boundary={BOUNDARY}");
    let mut json_request = lighting();
    json_request["vertices"] = json!({ "positions": positions, "normals": normals });
    let json_body = Bytes::from(serde_json::to_vec(&json_request).unwrap());
    // The bake alone, in the library: what the request adds to the wire.
    let mut library_t = Vec::new();
    for _ in 0..ROUNDS {
        let started = Instant::now();
        let request_bytes = serde_json::to_vec(&request).unwrap();
        let scene =
            glint::scene::parse_bake(Some(&request_bytes), &model, &Limits::default()).unwrap();
        let placed = started.elapsed();
        let baked = glint::bake::bake(scene, glint::bake::Form::Glb);
        library_t.push((started.elapsed(), placed));
        std::hint::black_box(baked);
    }
    library_t.sort();
    let (library_m, placed_m) = library_t[ROUNDS / 2];
    println!(
        "the bake in the library: {:.1} ms, of which reading and placing {:.1} ms",
        ms(library_m),
        ms(placed_m)
    );
    let (_, baked) = client.post("/v1/shade", &multipart, &form_body, &[]);
    let answer_bytes = baked.len().to_string();
    let (mut wire_t, mut bake_t, mut json_t) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..ROUNDS {
        wire_t.push(
            client
                .post(
                    "/wire",
                    "application/octet-stream",
                    &form_body,
                    &[("x-answer-bytes", answer_bytes.clone())],
                )
                .0,
        );
        bake_t.push(client.post("/v1/shade", &multipart, &form_body, &[]).0);
        json_t.push(
            client
                .post("/v1/shade", "application/json", &json_body, &[])
                .0,
        );
    }
    let (wire_m, bake_m, json_m) = (median(wire_t), median(bake_t), median(json_t));

    // Render: 224 × 224 vertices, 99,458 triangles, 1920×1080.
    let (positions, normals, indices) = grid(224);
    let model = glb(&positions, &normals, &indices);
    let camera = json!({ "eye": [0.0, 2.5, 4.5], "target": [0.0, 0.0, 0.0], "up": [0, 1, 0], "fov_y": 45, "width": 1920, "height": 1080 });
    let mut render_request = lighting();
    let material = render_request["material"].take();
    render_request.as_object_mut().unwrap().remove("material");
    render_request["materials"] = json!({ "#default": material });
    render_request["camera"] = camera.clone();
    let render_form = Bytes::from(form(&render_request, &model));
    let mut json_render = lighting();
    json_render.as_object_mut().unwrap().remove("material");
    json_render["materials"] = json!({ "grid": material });
    json_render["camera"] = camera;
    json_render["objects"] = json!([{ "mesh": { "positions": positions, "normals": normals, "indices": indices }, "material": "grid" }]);
    let json_render_body = Bytes::from(serde_json::to_vec(&json_render).unwrap());
    let (mut glb_r, mut json_r, mut parse_r) = (Vec::new(), Vec::new(), Vec::new());
    let request_bytes = serde_json::to_vec(&render_request).unwrap();
    for _ in 0..ROUNDS {
        glb_r.push(client.post("/v1/render", &multipart, &render_form, &[]).0);
        json_r.push(
            client
                .post("/v1/render", "application/json", &json_render_body, &[])
                .0,
        );
        let started = Instant::now();
        let scene = parse_model_render(Some(&request_bytes), &model, &Limits::default()).unwrap();
        parse_r.push(started.elapsed());
        std::hint::black_box(scene);
    }
    let (glb_m, json_rm, parse_m) = (median(glb_r), median(json_r), median(parse_r));

    report.push_str(&format!(
        "# glTF against JSON and against the wire\n\n\
         Written by `cargo bench --bench gltf` ({cpu}, {cores} cores): one server on loopback, \
         glint's router beside a no-work endpoint on the same stack; each request sent whole and \
         its answer read whole; requests in turns, the median of {ROUNDS} rounds.\n\n\
         ## Bake: 1,000,000 vertices, 1,996,002 triangles\n\n\
         | request | body | answer | median | ratio |\n| --- | --- | --- | --- | --- |\n\
         | `/wire`: read the multipart GLB, answer as many bytes as the baked model | {:.1} MB | {:.1} MB | {:.1} ms | 1 |\n\
         | `/v1/shade`, multipart GLB, baked GLB answered (unorm16) | {:.1} MB | {:.1} MB | {:.1} ms | {:.2}× the wire (target ≤ 2×) |\n\
         | `/v1/shade`, the same vertices as JSON | {:.1} MB | | {:.1} ms | {:.1}× the GLB (target ≥ 25×) |\n\n\
         No GLB request can beat the wire: on this stack the JSON request takes {:.1}× the \
         no-work endpoint's time for the GLB's body and answer, the most any bake of this model \
         could gain over JSON here. The baked model is the input (48 MB with its 32-bit \
         indices) and its colours, so the answer is larger than the model.\n\n\
         The bake alone, in the library (`parse_bake` and `bake`, no HTTP): {:.1} ms, of which \
         reading and placing the model {:.1} ms.\n\n\
         ## Render: 99,458 triangles at 1920×1080, 1 sample, PNG\n\n\
         | request | body | median |\n| --- | --- | --- |\n\
         | `/v1/render`, multipart GLB | {:.1} MB | {:.1} ms |\n\
         | `/v1/render`, the same scene as JSON | {:.1} MB | {:.1} ms ({:.2}× the GLB) |\n\
         | reading and placing the GLB alone (`parse_model_render`) | | {:.1} ms ({:.1}% of the GLB request) |\n",
        form_body.len() as f64 / 1e6,
        baked.len() as f64 / 1e6,
        ms(wire_m),
        form_body.len() as f64 / 1e6,
        baked.len() as f64 / 1e6,
        ms(bake_m),
        bake_m.as_secs_f64() / wire_m.as_secs_f64(),
        json_body.len() as f64 / 1e6,
        ms(json_m),
        json_m.as_secs_f64() / bake_m.as_secs_f64(),
        json_m.as_secs_f64() / wire_m.as_secs_f64(),
        ms(library_m),
        ms(placed_m),
        render_form.len() as f64 / 1e6,
        ms(glb_m),
        json_render_body.len() as f64 / 1e6,
        ms(json_rm),
        json_rm.as_secs_f64() / glb_m.as_secs_f64(),
        ms(parse_m),
        100.0 * parse_m.as_secs_f64() / glb_m.as_secs_f64(),
    ));
    print!("{report}");
    let path = format!("{}/docs/gltf.md", env!("CARGO_MANIFEST_DIR"));
    std::fs::write(&path, report).unwrap();
    println!("wrote docs/gltf.md");
}

//! The bare axum server of the load benchmark's ceiling, as a router: no
//! middleware, none of glint's layers, the JSON work of a shade request
//! without the lighting. `benches/bare_axum.rs` serves it;
//! `benches/request_path.rs` calls it in process.
//!
//! - `POST /v1/shade` parses the body into typed structs of a shade
//!   request's shape (axum's `Json<T>`) and answers as many colour floats as
//!   glint would: one RGBA of `f32` per vertex, `{"colors":[[r,g,b,a],…]}`.
//! - `POST /parse` parses the vertices of the body with serde_json, as plain
//!   arrays of numbers, and answers a small JSON: the rate a large shade
//!   request cannot beat.

use axum::Json;
use axum::body::Body;
use axum::routing::post;
use serde::{Deserialize, Serialize};

/// The vertices of a shade request, and nothing else of it.
#[derive(Deserialize)]
struct Shade {
    vertices: Vertices,
}

#[derive(Deserialize)]
struct Vertices {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
}

/// A shade request as plain data, every field of `examples/triangle.json`.
#[derive(Deserialize)]
#[allow(dead_code)] // read by serde, then only the normals are used
struct ShadeRequest {
    #[serde(default)]
    material: Option<Material>,
    #[serde(default)]
    lights: Vec<Light>,
    vertices: Vertices,
    #[serde(default)]
    terms: Option<String>,
}

#[derive(Deserialize)]
#[allow(dead_code)]
struct Material {
    #[serde(default)]
    ambient: Option<Vec<f64>>,
    #[serde(default)]
    diffuse: Option<Vec<f64>>,
    #[serde(default)]
    specular: Option<Vec<f64>>,
    #[serde(default)]
    shininess: Option<f64>,
}

#[derive(Deserialize)]
#[allow(dead_code)]
struct Light {
    #[serde(default)]
    position: Option<[f64; 4]>,
    #[serde(default)]
    diffuse: Option<Vec<f64>>,
    #[serde(default)]
    attenuation: Option<[f64; 3]>,
}

#[derive(Serialize)]
struct Colors {
    colors: Vec<[f32; 4]>,
}

#[derive(Serialize)]
struct Parsed {
    ok: bool,
    bytes: usize,
}

/// A colour per vertex from its normal: numbers with as many digits as
/// lit colours have, and no lighting.
async fn shade(Json(request): Json<ShadeRequest>) -> Json<Colors> {
    let colors = request
        .vertices
        .normals
        .iter()
        .map(|n| {
            let [r, g, b] = n.map(|x| (0.5 + 0.5 * (x + 0.5).sin()) as f32);
            [r, g, b, 1.0]
        })
        .collect();
    Json(Colors { colors })
}

/// Reads the body whole (a plain `Body`, since the `Bytes` extractor has a
/// limit of 2 MB and lifting it takes a layer), then parses it.
async fn parse(body: Body) -> Json<Parsed> {
    let body = axum::body::to_bytes(body, usize::MAX)
        .await
        .expect("a whole body");
    let shade: Shade = serde_json::from_slice(&body).expect("a shade request");
    Json(Parsed {
        ok: shade.vertices.positions.len() == shade.vertices.normals.len(),
        bytes: body.len(),
    })
}

/// The router, with no layer of any kind.
pub fn router() -> axum::Router {
    axum::Router::new()
        .route("/v1/shade", post(shade))
        .route("/parse", post(parse))
}

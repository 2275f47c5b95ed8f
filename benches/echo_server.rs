//! The ceilings of `benches/load.sh`: an axum server on the same runtime and
//! stack as glint whose endpoints do no lighting. `POST /echo` reads the
//! body (as glint reads a request's) and answers a small typed JSON; what
//! glint loses against it at the same load is the cost of parsing,
//! validating, the hop to the worker pool and lighting. `POST /typed` is
//! the typed JSON echo of axum's own examples: `Json<T>` in, the same
//! `Json<T>` out, with `T` the shape of a shade request, so that it reads
//! and writes about as much JSON as a small shade does and does nothing
//! else. `POST /parse` also
//! parses the body's vertices with serde_json, as plain arrays of numbers:
//! the rate a large shade request cannot beat.
//!
//! `benches/load.sh` starts it with `--listen 127.0.0.1:PORT`; run with no
//! arguments (as `cargo bench` does) it only says what it is and exits.

use axum::Json;
use axum::body::Bytes;
use axum::routing::post;
use serde::{Deserialize, Serialize};

#[derive(Serialize)]
struct Echo {
    ok: bool,
    bytes: usize,
}

/// The vertices of a shade request, and nothing else of it.
#[derive(Deserialize)]
struct Shade {
    vertices: Vertices,
}

#[derive(Deserialize, Serialize)]
struct Vertices {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
}

/// A shade request as plain data: what a typed echo reads and writes back.
#[derive(Deserialize, Serialize)]
struct ShadeEcho {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    material: Option<MaterialEcho>,
    #[serde(default)]
    lights: Vec<LightEcho>,
    vertices: Vertices,
}

#[derive(Deserialize, Serialize)]
struct MaterialEcho {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ambient: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    diffuse: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    specular: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    shininess: Option<f64>,
}

#[derive(Deserialize, Serialize)]
struct LightEcho {
    position: [f64; 4],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    diffuse: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    attenuation: Option<[f64; 3]>,
}

async fn typed(Json(shade): Json<ShadeEcho>) -> Json<ShadeEcho> {
    Json(shade)
}

async fn parse(body: Bytes) -> Json<Echo> {
    let shade: Shade = serde_json::from_slice(&body).expect("a shade request");
    Json(Echo {
        ok: shade.vertices.positions.len() == shade.vertices.normals.len(),
        bytes: body.len(),
    })
}

async fn echo(body: Bytes) -> Json<Echo> {
    Json(Echo {
        ok: true,
        bytes: body.len(),
    })
}

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(at) = args.iter().position(|a| a == "--listen") else {
        println!("echo_server: the no-work ceiling of benches/load.sh, which starts it");
        return Ok(());
    };
    let addr = args.get(at + 1).expect("--listen ADDR:PORT").clone();
    tokio::runtime::Runtime::new()?.block_on(async move {
        let listener = tokio::net::TcpListener::bind(&addr).await?;
        let app = axum::Router::new()
            .route("/echo", post(echo))
            .route("/typed", post(typed))
            .route("/parse", post(parse))
            .layer(axum::extract::DefaultBodyLimit::disable());
        axum::serve(listener, app)
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
    })
}

//! The ceiling of `benches/load.sh`: an axum server on the same runtime and
//! stack as glint whose one endpoint does no work. `POST /echo` reads the
//! body (as glint reads a request's) and answers a small typed JSON; what
//! glint loses against it at the same load is the cost of parsing,
//! validating, the hop to the worker pool and lighting.
//!
//! `benches/load.sh` starts it with `--listen 127.0.0.1:PORT`; run with no
//! arguments (as `cargo bench` does) it only says what it is and exits.

use axum::Json;
use axum::body::Bytes;
use axum::routing::post;
use serde::Serialize;

#[derive(Serialize)]
struct Echo {
    ok: bool,
    bytes: usize,
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
        let app = axum::Router::new().route("/echo", post(echo));
        axum::serve(listener, app)
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
    })
}

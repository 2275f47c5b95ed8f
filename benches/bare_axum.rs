//! The ceiling of `benches/load.sh`: a bare axum server, with no middleware
//! and none of glint's layers, doing the JSON work of a shade request
//! without the lighting (see `benches/bare/mod.rs`). What glint loses
//! against it at the same load is the cost of everything glint adds:
//! request ids, metrics, the access log, CORS, timeouts, the body reader,
//! validation, the lighting and the rest of its response.
//!
//! `benches/load.sh` starts it with `--listen 127.0.0.1:PORT`; run with no
//! arguments (as `cargo bench` does) it only says what it is and exits.

mod bare;

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(at) = args.iter().position(|a| a == "--listen") else {
        println!("bare_axum: the ceiling of benches/load.sh, which starts it");
        return Ok(());
    };
    let addr = args.get(at + 1).expect("--listen ADDR:PORT").clone();
    tokio::runtime::Runtime::new()?.block_on(async move {
        let listener = tokio::net::TcpListener::bind(&addr).await?;
        axum::serve(listener, bare::router())
            .with_graceful_shutdown(async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await
    })
}

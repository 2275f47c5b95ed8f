//! The service on a socket: connections accepted until a signal, each
//! served by hyper-util (HTTP/1.1, or HTTP/2 when the client opens with its
//! preface), and a shutdown that drains, then gives requests in flight a
//! grace period.
//!
//! Each connection has `--header-timeout-ms` to send each request head:
//! hyper's own header-read timeout, which also bounds the wait on an idle
//! keep-alive connection. hyper starts it once it knows the protocol, which
//! it learns from the first bytes, so the wait for a first byte has the
//! same bound here: a client that connects and sends nothing, or trickles
//! its headers, cannot hold a connection for longer.

use std::sync::atomic::Ordering;
use std::time::Duration;

use anyhow::Context;
use hyper_util::rt::{TokioExecutor, TokioIo, TokioTimer};
use hyper_util::server::conn::auto;
use hyper_util::server::graceful::GracefulShutdown;
use hyper_util::service::TowerToHyperService;
use tokio::net::{TcpListener, TcpStream};

use super::AppState;
use crate::config::ServeConfig;

/// `glint serve`: the logs installed, the runtime started, the service
/// served until SIGTERM or Ctrl-C. A failure to start (an address in use,
/// an instance id that no header can carry) is logged before it is
/// returned, so that it is the last line of the log.
pub fn run(config: &ServeConfig) -> anyhow::Result<()> {
    // Written out when dropped, after the server and its last log line.
    let _logs = crate::logging::init(config.logs());
    let served = tokio::runtime::Runtime::new()
        .context("cannot start the async runtime")
        .and_then(|runtime| runtime.block_on(serve(config)));
    if let Err(e) = &served {
        tracing::error!(error = format!("{e:#}"), "glint stopped");
    }
    served
}

/// Serves until SIGTERM or Ctrl-C, then stops taking connections, gives
/// in-flight requests the grace period to finish, and returns.
pub async fn serve(config: &ServeConfig) -> anyhow::Result<()> {
    let listener = TcpListener::bind(config.listen)
        .await
        .with_context(|| format!("cannot listen on {}", config.listen))?;
    let state = AppState::new(config)?;
    tracing::info!(
        address = %listener.local_addr()?,
        workers = state.pool.threads(),
        instance = ?state.served_by,
        "glint listening"
    );
    serve_on(listener, state, config, shutdown_signal()).await
}

/// Serves on `listener` until `shutdown` completes; the testable core of
/// [`serve`].
///
/// On shutdown `/readyz` turns 503; new connections are still served for
/// the drain (`--drain-ms`), so that a load balancer's health checks see
/// the replica leave while it answers; then the listener closes so new
/// connections are refused, idle connections are closed, and requests in
/// flight get the grace period to finish.
pub async fn serve_on(
    listener: TcpListener,
    state: AppState,
    config: &ServeConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> anyhow::Result<()> {
    let app = super::app(state.clone(), &config.cors_origins);
    let header_timeout = config.header_timeout();
    let mut builder = auto::Builder::new(TokioExecutor::new());
    builder
        .http1()
        .timer(TokioTimer::new())
        .header_read_timeout(header_timeout);
    let connections = GracefulShutdown::new();
    let serve_connection = |stream: TcpStream| {
        let (builder, app) = (builder.clone(), app.clone());
        let watcher = connections.watcher();
        tokio::spawn(async move {
            if !sends_within(&stream, header_timeout).await {
                return;
            }
            let service = TowerToHyperService::new(app);
            let connection = builder.serve_connection_with_upgrades(TokioIo::new(stream), service);
            if let Err(e) = watcher.watch(connection.into_owned()).await {
                tracing::debug!(error = %e, "connection ended with an error");
            }
        });
    };

    accept_until(&listener, shutdown, &serve_connection).await;
    state.shutting_down.store(true, Ordering::Relaxed);
    let drain = config.drain();
    if !drain.is_zero() {
        tracing::info!(
            drain_ms = drain.as_millis() as u64,
            "draining: /readyz answers 503, new connections are still served"
        );
        accept_until(&listener, tokio::time::sleep(drain), &serve_connection).await;
    }
    drop(listener);
    let grace = config.shutdown_grace();
    tracing::info!(grace_ms = grace.as_millis() as u64, "shutting down");
    tokio::select! {
        _ = connections.shutdown() => tracing::info!("every request finished"),
        _ = tokio::time::sleep(grace) => {
            tracing::warn!("requests still in flight at the end of the grace period")
        }
    }
    Ok(())
}

/// Whether the client sends a first byte within `timeout` (and has not
/// closed the connection).
async fn sends_within(stream: &TcpStream, timeout: Duration) -> bool {
    let mut first = [0u8; 1];
    matches!(
        tokio::time::timeout(timeout, stream.peek(&mut first)).await,
        Ok(Ok(1))
    )
}

/// Hands every connection `listener` accepts to `serve` until `until`
/// completes.
async fn accept_until(
    listener: &TcpListener,
    until: impl Future<Output = ()>,
    serve: &impl Fn(TcpStream),
) {
    let mut until = std::pin::pin!(until);
    loop {
        tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _peer)) => serve(stream),
                Err(e) => {
                    // Out of file descriptors and the like: pause, not spin.
                    tracing::warn!(error = %e, "accept failed");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                }
            },
            _ = &mut until => return,
        }
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}

//! The HTTP service, driven over real sockets: each endpoint, each error
//! status of the contract with its pointer, limits, saturation, malformed
//! traffic and graceful shutdown.

mod budget;
mod errors;
mod malformed;
mod operations;
mod shade;
mod shutdown;

use std::net::SocketAddr;

use glint::config::ServeConfig;
use glint::http::AppState;
use serde_json::{Value, json};
use tokio::sync::oneshot;
use tokio::task::JoinHandle;

use crate::support::client;

/// A glint server on an ephemeral loopback port, stopped when dropped.
pub struct TestServer {
    pub addr: SocketAddr,
    pub state: AppState,
    shutdown: Option<oneshot::Sender<()>>,
    task: Option<JoinHandle<anyhow::Result<()>>>,
}

impl TestServer {
    pub async fn start() -> Self {
        Self::with(|_| {}).await
    }

    /// Starts a server whose defaults `configure` adjusts.
    pub async fn with(configure: impl FnOnce(&mut ServeConfig)) -> Self {
        let mut config = ServeConfig {
            listen: "127.0.0.1:0".parse().unwrap(),
            ..ServeConfig::default()
        };
        configure(&mut config);
        let listener = tokio::net::TcpListener::bind(config.listen).await.unwrap();
        let addr = listener.local_addr().unwrap();
        let state = AppState::new(&config).unwrap();
        let (tx, rx) = oneshot::channel::<()>();
        let task = tokio::spawn({
            let state = state.clone();
            async move {
                glint::http::serve_on(listener, state, &config, async {
                    let _ = rx.await;
                })
                .await
            }
        });
        Self {
            addr,
            state,
            shutdown: Some(tx),
            task: Some(task),
        }
    }

    /// Starts a server that computes one job at a time on one thread, with
    /// `queue` jobs allowed to wait (the shape of every saturation test),
    /// whose other defaults `configure` adjusts.
    pub async fn one_job(queue: usize, configure: impl FnOnce(&mut ServeConfig)) -> Self {
        Self::with(|c| {
            c.threads = 1;
            c.max_jobs = 1;
            c.queue = queue;
            configure(c);
        })
        .await
    }

    pub fn url(&self, path: &str) -> String {
        format!("http://{}{path}", self.addr)
    }

    /// Begins a graceful shutdown; [`Self::stopped`] waits for its end.
    pub fn begin_shutdown(&mut self) {
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
    }

    pub async fn stopped(&mut self) -> anyhow::Result<()> {
        self.task.take().expect("awaited once").await?
    }

    /// Posts `body` as JSON to `path`.
    pub async fn post_json(&self, path: &str, body: &Value) -> reqwest::Response {
        client()
            .post(self.url(path))
            .json(body)
            .send()
            .await
            .expect("the server answers")
    }

    /// Occupies every job slot of the pool until the returned sender is
    /// dropped or sent to: requests after this wait in the queue.
    pub async fn occupy_workers(&self) -> Vec<std::sync::mpsc::Sender<()>> {
        let mut releases = Vec::new();
        let (started_tx, mut started_rx) = tokio::sync::mpsc::unbounded_channel();
        for _ in 0..self.state.pool.max_jobs() {
            let (tx, rx) = std::sync::mpsc::channel::<()>();
            let pool = self.state.pool.clone();
            let started = started_tx.clone();
            tokio::spawn(async move {
                pool.run(move |_| {
                    let _ = started.send(());
                    let _ = rx.recv();
                })
                .await
            });
            releases.push(tx);
        }
        for _ in 0..releases.len() {
            started_rx.recv().await.unwrap();
        }
        releases
    }
}

impl Drop for TestServer {
    fn drop(&mut self) {
        self.begin_shutdown();
    }
}

/// A small valid shade request: GL's default material, GL_LIGHT0 along +z,
/// one vertex facing it.
pub fn one_vertex() -> Value {
    json!({
        "lights": [{}],
        "vertices": { "positions": [[0, 0, 0]], "normals": [[0, 0, 1]] }
    })
}

/// Vertices in [`pooled_request`]: more work than the server does on its
/// async workers, so the request goes through the pool and its admission.
pub const POOLED_VERTICES: usize = 5000;

/// A shade request that the pool evaluates (a tiny one is answered
/// without it).
pub fn pooled_request() -> Value {
    json!({
        "lights": [{}],
        "vertices": {
            "positions": vec![[0, 0, 0]; POOLED_VERTICES],
            "normals": vec![[0, 0, 1]; POOLED_VERTICES]
        }
    })
}

/// Checks a problem+json response: status, type, pointer; returns its body.
pub async fn expect_problem(
    response: reqwest::Response,
    status: u16,
    kind: &str,
    pointer: Option<&str>,
) -> Value {
    assert_eq!(response.status().as_u16(), status, "status");
    assert_eq!(
        response.headers()["content-type"],
        "application/problem+json"
    );
    let body: Value = response.json().await.unwrap();
    assert_eq!(body["status"], status, "{body}");
    assert_eq!(body["type"], format!("urn:glint:problem:{kind}"), "{body}");
    assert!(
        body["title"].is_string() && body["detail"].is_string(),
        "{body}"
    );
    if let Some(pointer) = pointer {
        assert_eq!(body["pointer"], pointer, "{body}");
    }
    body
}

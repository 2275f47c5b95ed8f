//! The service under load and abuse: many concurrent clients checked against
//! the offline engine, bursts past capacity, hostile connections, memory held
//! flat under refused floods, a log that nobody reads, graceful shutdown of
//! the real binary on SIGTERM, and the fuzz target of the request parsers.
//!
//! Every loop here is bounded in count and time, every wait is a bounded poll
//! (never a sleep standing in for an event), and all traffic goes to
//! 127.0.0.1.

mod concurrency;
mod fuzz;
mod hostile;
mod logging;
mod memory;
mod overload;
mod shutdown;

use std::net::SocketAddr;
use std::process::{ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde_json::{Value, json};
use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader, Lines};
use tokio::net::TcpStream;
use tokio::process::{Child, ChildStderr, ChildStdout, Command};

use crate::support::Rng;

/// The real `glint` binary, serving on a loopback port the kernel chose;
/// killed if still running when dropped.
pub struct Glint {
    child: Child,
    pub addr: SocketAddr,
    /// Every log line after the first, for a failure's message.
    logs: Arc<Mutex<Vec<String>>>,
    /// Its stdout and stderr when nobody reads them (see
    /// [`Glint::spawn_unread`]): held open, never read.
    _unread: Option<(Lines<BufReader<ChildStdout>>, Option<ChildStderr>)>,
}

impl Glint {
    /// Starts `glint serve --listen 127.0.0.1:0` with `flags`, learns its
    /// port from its first log line, and waits until `/readyz` answers.
    ///
    /// The port comes from the server itself rather than from a port the
    /// test picked and freed, so another process cannot take it in between.
    pub async fn spawn(flags: &[&str]) -> Self {
        Self::start(flags, true).await
    }

    /// As [`Glint::spawn`], but its stdout and stderr are pipes that nobody
    /// reads after the first line (which says where it listens), kept open
    /// for as long as it runs: a log collector that has stalled.
    pub async fn spawn_unread(flags: &[&str]) -> Self {
        Self::start(flags, false).await
    }

    async fn start(flags: &[&str], read_logs: bool) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_glint"))
            .args(["serve", "--listen", "127.0.0.1:0", "--log-format", "json"])
            .args(flags)
            .env("RUST_LOG", "info")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(if read_logs {
                Stdio::inherit()
            } else {
                Stdio::piped()
            })
            .kill_on_drop(true)
            .spawn()
            .expect("the glint binary starts");
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let addr = tokio::time::timeout(Duration::from_secs(30), async {
            while let Some(line) = lines.next_line().await.unwrap() {
                let Ok(entry) = serde_json::from_str::<Value>(&line) else {
                    continue;
                };
                if entry["fields"]["message"] == "glint listening" {
                    let addr = entry["fields"]["address"].as_str().unwrap();
                    return addr.parse::<SocketAddr>().unwrap();
                }
            }
            panic!("glint exited before it listened");
        })
        .await
        .expect("glint says where it listens within 30 s");

        let logs = Arc::new(Mutex::new(Vec::new()));
        let mut unread = None;
        if read_logs {
            // Keep reading its logs, or a full pipe would stall the server.
            tokio::spawn({
                let logs = logs.clone();
                async move {
                    while let Ok(Some(line)) = lines.next_line().await {
                        let mut logs = logs.lock().unwrap();
                        if logs.len() < 10_000 {
                            logs.push(line);
                        }
                    }
                }
            });
        } else {
            unread = Some((lines, child.stderr.take()));
        }

        let glint = Self {
            child,
            addr,
            logs,
            _unread: unread,
        };
        let ready = poll(100, Duration::from_millis(50), || async {
            let response = crate::support::client()
                .get(glint.url("/readyz"))
                .send()
                .await;
            response.is_ok_and(|r| r.status() == 200)
        })
        .await;
        assert!(ready, "glint is ready within 100 polls");
        glint
    }

    pub fn url(&self, path: &str) -> String {
        format!("http://{}{path}", self.addr)
    }

    pub fn pid(&self) -> u32 {
        self.child.id().expect("still running")
    }

    /// Resident memory now, in bytes, from `/proc/<pid>/status`.
    #[cfg(target_os = "linux")]
    pub fn resident_bytes(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.pid())).unwrap();
        let line = status
            .lines()
            .find(|l| l.starts_with("VmRSS:"))
            .expect("a VmRSS line");
        let kib: u64 = line
            .split_whitespace()
            .nth(1)
            .and_then(|n| n.parse().ok())
            .expect("VmRSS in kB");
        kib * 1024
    }

    /// Sends SIGTERM, as an orchestrator stopping the replica would.
    pub fn terminate(&self) {
        let status = std::process::Command::new("kill")
            .args(["-TERM", &self.pid().to_string()])
            .status()
            .expect("kill runs");
        assert!(status.success(), "kill -TERM succeeded");
    }

    /// The exit status, if the process has exited.
    pub fn try_wait(&mut self) -> Option<ExitStatus> {
        self.child.try_wait().unwrap()
    }

    /// The logs so far, for an assertion's message.
    pub fn logs(&self) -> String {
        self.logs.lock().unwrap().join("\n")
    }

    /// Its `/metrics` exposition now.
    pub async fn metrics(&self) -> String {
        crate::support::client()
            .get(self.url("/metrics"))
            .send()
            .await
            .unwrap()
            .text()
            .await
            .unwrap()
    }
}

/// The value of the sample `name` (with its labels, if any) in a metrics
/// exposition; 0 when absent.
pub fn metric(text: &str, name: &str) -> f64 {
    text.lines()
        .find_map(|line| {
            let value = line.strip_prefix(name)?.strip_prefix(' ')?;
            value.trim().parse().ok()
        })
        .unwrap_or(0.0)
}

/// Asks `check` up to `attempts` times, `every` apart, until it says yes.
pub async fn poll<F, Fut>(attempts: usize, every: Duration, mut check: F) -> bool
where
    F: FnMut() -> Fut,
    Fut: Future<Output = bool>,
{
    let mut interval = tokio::time::interval(every);
    for _ in 0..attempts {
        interval.tick().await;
        if check().await {
            return true;
        }
    }
    false
}

/// The requests of these tests (and of `deploy`), drawn from the shared
/// seeded [`Rng`]: every option of the contract, valid throughout.
impl Rng {
    /// Uniform in [lo, hi), rounded to 1e-3 so bodies stay short.
    fn rounded(&mut self, lo: f64, hi: f64) -> f64 {
        (self.uniform(lo, hi) * 1e3).round() / 1e3
    }

    fn color(&mut self) -> Value {
        if self.chance(0.5) {
            json!([
                self.rounded(0.0, 1.0),
                self.rounded(0.0, 1.0),
                self.rounded(0.0, 1.0)
            ])
        } else {
            json!([
                self.rounded(0.0, 1.0),
                self.rounded(0.0, 1.0),
                self.rounded(0.0, 1.0),
                self.rounded(0.0, 1.0)
            ])
        }
    }

    /// A vector with at least one component of magnitude >= 0.5.
    fn direction(&mut self) -> [f64; 3] {
        let mut v = [
            self.rounded(-1.0, 1.0),
            self.rounded(-1.0, 1.0),
            self.rounded(-1.0, 1.0),
        ];
        let i = self.below(3);
        v[i] = if self.chance(0.5) { 0.5 } else { -0.5 } + v[i] / 2.0;
        v
    }

    fn material(&mut self) -> Value {
        let mut m = serde_json::Map::new();
        for key in ["ambient", "diffuse", "specular", "emission"] {
            if self.chance(0.6) {
                m.insert(key.into(), self.color());
            }
        }
        if self.chance(0.6) {
            m.insert("shininess".into(), json!(self.rounded(0.0, 128.0)));
        }
        Value::Object(m)
    }

    /// A valid light: directional or positional, maybe a spotlight.
    pub fn light(&mut self) -> Value {
        let mut l = serde_json::Map::new();
        let [x, y, z] = self.direction();
        let positional = self.chance(0.5);
        if positional {
            let scale = self.rounded(1.0, 6.0);
            let w = self.pick(&[1.0, 1.0, 2.0]);
            l.insert(
                "position".into(),
                json!([x * scale, y * scale, z * scale, w]),
            );
            if self.chance(0.6) {
                let k = [
                    self.rounded(0.5, 2.0),
                    self.rounded(0.0, 0.5),
                    self.rounded(0.0, 0.2),
                ];
                l.insert("attenuation".into(), json!(k));
            }
        } else if self.chance(0.8) {
            l.insert("position".into(), json!([x, y, z, 0.0]));
        }
        for key in ["ambient", "diffuse", "specular"] {
            if self.chance(0.5) {
                l.insert(key.into(), self.color());
            }
        }
        if self.chance(0.3) {
            let cutoff = if self.chance(0.2) {
                180.0
            } else {
                self.rounded(0.0, 90.0)
            };
            l.insert(
                "spot".into(),
                json!({
                    "direction": self.direction(),
                    "exponent": self.rounded(0.0, 64.0),
                    "cutoff": cutoff,
                }),
            );
        }
        Value::Object(l)
    }

    /// A valid `/v1/shade` request drawing on every option of the contract,
    /// with 1 to `max_vertices` vertices.
    pub fn shade_request(&mut self, max_vertices: usize) -> Value {
        let mut r = serde_json::Map::new();
        if self.chance(0.7) {
            let mut m = serde_json::Map::new();
            if self.chance(0.5) {
                m.insert("ambient".into(), self.color());
            }
            for key in [
                "local_viewer",
                "two_side",
                "attenuation_clamp",
                "normalize_normals",
            ] {
                if self.chance(0.5) {
                    m.insert(key.into(), json!(self.chance(0.5)));
                }
            }
            if self.chance(0.5) {
                let c = self.pick(&["single", "separate_specular"]);
                m.insert("color_control".into(), json!(c));
            }
            if self.chance(0.5) {
                let s = self.pick(&["blinn_phong", "phong"]);
                m.insert("specular_model".into(), json!(s));
            }
            r.insert("light_model".into(), Value::Object(m));
        }
        if self.chance(0.8) {
            r.insert("material".into(), self.material());
        }
        if self.chance(0.3) {
            r.insert("back_material".into(), self.material());
        }
        let lights: Vec<Value> = (0..self.below(9)).map(|_| self.light()).collect();
        r.insert("lights".into(), json!(lights));
        if self.chance(0.3) {
            let target = [
                self.rounded(-1.0, 1.0),
                self.rounded(-1.0, 1.0),
                self.rounded(-1.0, 1.0),
            ];
            let [dx, dy, dz] = self.direction();
            let eye = [
                target[0] + 4.0 * dx,
                target[1] + 4.0 * dy,
                target[2] + 4.0 * dz,
            ];
            r.insert(
                "view".into(),
                json!({ "eye": eye, "target": target, "up": [0, 1, 0] }),
            );
        }
        let n = 1 + self.below(max_vertices);
        r.insert("vertices".into(), self.vertices(n));
        r.insert(
            "precision".into(),
            json!(self.pick(&["reference", "accurate", "fast"])),
        );
        let terms = if n <= 32 {
            self.pick(&["none", "summary", "per_vertex"])
        } else {
            self.pick(&["none", "summary"])
        };
        r.insert("terms".into(), json!(terms));
        Value::Object(r)
    }

    /// `n` vertices in [-5, 5]³, about one in 50 with a zero normal.
    pub fn vertices(&mut self, n: usize) -> Value {
        let positions: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                [
                    self.rounded(-5.0, 5.0),
                    self.rounded(-5.0, 5.0),
                    self.rounded(-5.0, 5.0),
                ]
            })
            .collect();
        let normals: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                if self.chance(0.02) {
                    [0.0; 3]
                } else {
                    self.direction()
                }
            })
            .collect();
        json!({ "positions": positions, "normals": normals })
    }
}

/// What the offline engine answers to `request`: the body `glint shade`
/// prints, as the server's default limits allow it.
pub fn offline_answer(request: &[u8]) -> Value {
    let scene = glint::scene::parse_shade(request, &glint::scene::Limits::default())
        .expect("a valid request");
    let text = serde_json::to_vec(&glint::shade::shade(&scene)).unwrap();
    serde_json::from_slice(&text).unwrap()
}

/// Asserts that a `200` body is the offline engine's answer: every colour
/// bit for bit, and every other field but the timing.
pub fn assert_same_answer(mut got: Value, expected: &Value, what: &str) {
    let expected_colors = expected["colors"].as_array().unwrap().len();
    assert_eq!(
        got["colors"].as_array().map(Vec::len),
        Some(expected_colors),
        "{what}: every vertex has its colour"
    );
    // The one field that differs between two evaluations.
    got["stats"]["compute_ms"] = expected["stats"]["compute_ms"].clone();
    if got != *expected {
        let first = (0..expected_colors)
            .find(|&i| got["colors"][i] != expected["colors"][i])
            .map_or(String::new(), |i| {
                format!(
                    "vertex {i}: {} against {}",
                    got["colors"][i], expected["colors"][i]
                )
            });
        panic!("{what}: the server's answer differs from the offline engine's {first}");
    }
}

/// A response read off a raw connection.
#[derive(Debug)]
pub struct RawResponse {
    pub status: u16,
    pub head: String,
    pub body: Vec<u8>,
}

impl RawResponse {
    pub fn header(&self, name: &str) -> Option<&str> {
        self.head.lines().skip(1).find_map(|line| {
            let (key, value) = line.split_once(':')?;
            key.trim().eq_ignore_ascii_case(name).then(|| value.trim())
        })
    }
}

/// Splits the bytes a server sent on one connection into its responses
/// (each with a Content-Length, as glint's are); what cannot be parsed
/// as a response is returned as the remainder.
pub fn split_responses(mut bytes: &[u8]) -> (Vec<RawResponse>, Vec<u8>) {
    let mut responses = Vec::new();
    while let Some(end) = bytes.windows(4).position(|w| w == b"\r\n\r\n") {
        let head = String::from_utf8_lossy(&bytes[..end]).into_owned();
        let Some(status) = head
            .strip_prefix("HTTP/1.1 ")
            .and_then(|s| s.get(..3))
            .and_then(|s| s.parse().ok())
        else {
            break;
        };
        let mut response = RawResponse {
            status,
            head,
            body: Vec::new(),
        };
        let length: usize = response
            .header("content-length")
            .and_then(|v| v.parse().ok())
            .unwrap_or(0);
        let start = end + 4;
        if bytes.len() < start + length {
            break;
        }
        response.body = bytes[start..start + length].to_vec();
        bytes = &bytes[start + length..];
        responses.push(response);
    }
    (responses, bytes.to_vec())
}

/// Writes `bytes` on a new connection and reads until the server closes it
/// (at most `within`).
pub async fn exchange(addr: SocketAddr, bytes: &[u8], within: Duration) -> Vec<u8> {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    // The server may answer and close before reading everything.
    let _ = stream.write_all(bytes).await;
    let mut answer = Vec::new();
    tokio::time::timeout(within, async {
        let _ = stream.read_to_end(&mut answer).await;
    })
    .await
    .expect("the server closes the connection in time");
    answer
}

/// The head of a JSON POST to `path` declaring `length` body bytes.
pub fn post_head(path: &str, length: usize, close: bool) -> String {
    let connection = if close { "close" } else { "keep-alive" };
    format!(
        "POST {path} HTTP/1.1\r\nhost: 127.0.0.1\r\ncontent-type: application/json\r\n\
         content-length: {length}\r\nconnection: {connection}\r\n\r\n"
    )
}

/// Asserts a problem+json body of `status`, and returns it.
pub fn problem(status: u16, content_type: Option<&str>, body: &[u8]) -> Value {
    assert_eq!(
        content_type,
        Some("application/problem+json"),
        "a {status} is problem+json"
    );
    let problem: Value = serde_json::from_slice(body).expect("a JSON problem");
    assert_eq!(problem["status"], status, "{problem}");
    assert!(
        problem["type"]
            .as_str()
            .unwrap()
            .starts_with("urn:glint:problem:"),
        "{problem}"
    );
    problem
}

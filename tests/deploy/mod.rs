//! glint as it is deployed: the Kubernetes manifests built and validated
//! offline, the local topology of replicas behind HAProxy (started by the
//! project's own `deploy/local/cluster.sh`) losing no request while a
//! replica is killed or the replicas are restarted in turn, the tile
//! fan-out client, what one replica offers a deployment (`x-served-by`,
//! `glint healthcheck`, one tile alone), the drain on SIGTERM, the
//! container image (built by `docker/build.sh`) and the compose topology
//! of `deploy/compose.yaml`, with faults at the container level.
//!
//! The outside tools (haproxy, kubectl, kubernetes-validate, podman,
//! podman-compose, debootstrap) come from package registries: haproxy,
//! kubectl, podman and debootstrap from Debian's packages, the validator
//! and podman-compose from PyPI at the versions pinned beside this file,
//! installed on first use (kubectl and the Python tools under
//! `target/tools/`, the others with apt-get as root; see `crate::support`). A tool that cannot be
//! had fails its test when `CI` is `true`; elsewhere the test says loudly
//! what is missing and passes.
//!
//! All traffic goes to 127.0.0.1: the containers' ports are published
//! there, and behind them it stays within the bridge network the engine
//! made on this machine for the test. Every loop is bounded in count and
//! time; every process and container a test starts is stopped when its
//! guard drops, panic or not.

mod compose;
mod drain;
mod engine;
mod fanout;
mod image;
mod k8s;
mod replica;
mod topology;

use std::fs;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::Stdio;
use std::time::Duration;

use serde_json::{Value, json};
use tokio::io::{AsyncBufReadExt, BufReader};
use tokio::process::{Child, Command};

pub(crate) use crate::support::{
    InstallLock, PythonTools, Scratch, available, client, debian_program, printed, repo, run,
    run_to_end, tools,
};

/// Sends `signal` (`TERM`, `KILL`) to the process `pid`.
fn signal(pid: u32, signal: &str) {
    let status = std::process::Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -{signal} {pid}");
}

/// Loopback ports the kernel chose, free when this returns. The cluster's
/// replicas must keep their ports across restarts (HAProxy's configuration
/// names them), so they cannot each ask the kernel for one; a port taken in
/// between makes the cluster fail to start, and [`Cluster::start`] tries
/// again with new ones.
fn free_ports(n: usize) -> Vec<u16> {
    let listeners: Vec<_> = (0..n)
        .map(|_| std::net::TcpListener::bind("127.0.0.1:0").expect("a loopback port"))
        .collect();
    listeners
        .iter()
        .map(|l| l.local_addr().unwrap().port())
        .collect()
}

/// HAProxy: on `PATH`, or installed from Debian's package.
async fn haproxy() -> Result<PathBuf, String> {
    debian_program("haproxy", "haproxy").await
}

/// The Python tools of these tests (kubernetes-validate, podman-compose)
/// with the pins of `requirements.txt`.
async fn python_tools() -> Result<PythonTools, String> {
    PythonTools::pinned_by("deploy").await
}

/// Only one cluster at a time: three replicas, HAProxy and a load on two
/// cores are enough for one test.
static ONE_CLUSTER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// `deploy/local/cluster.sh`: glint replicas behind HAProxy, started as a
/// user starts them; the whole process group is stopped when dropped.
struct Cluster {
    child: Child,
    pub lb: SocketAddr,
    pub replicas: Vec<SocketAddr>,
    run_dir: Scratch,
    _one: tokio::sync::MutexGuard<'static, ()>,
}

impl Cluster {
    /// Starts `replicas` replicas with `flags` for `glint serve` behind
    /// HAProxy, and waits until the script says the cluster is ready; `None`
    /// (after a loud skip) when HAProxy cannot be had.
    async fn start(test: &str, replicas: usize, flags: &[&str]) -> Option<Self> {
        available(haproxy().await, test)?;
        let one = ONE_CLUSTER.lock().await;
        let mut last = String::new();
        for _ in 0..3 {
            match Self::try_start(test, replicas, flags).await {
                Ok((child, lb, replicas, run_dir)) => {
                    return Some(Self {
                        child,
                        lb,
                        replicas,
                        run_dir,
                        _one: one,
                    });
                }
                Err(why) => last = why,
            }
        }
        panic!("the cluster did not start in 3 tries; the last:\n{last}");
    }

    async fn try_start(
        test: &str,
        replicas: usize,
        flags: &[&str],
    ) -> Result<(Child, SocketAddr, Vec<SocketAddr>, Scratch), String> {
        let run_dir = Scratch::new(test);
        let ports = free_ports(replicas + 1);
        let replica_ports = ports[1..]
            .iter()
            .map(u16::to_string)
            .collect::<Vec<_>>()
            .join(",");
        let script = repo().join("deploy/local/cluster.sh");
        let mut child = Command::new("bash")
            .arg(&script)
            .args(["--port", &ports[0].to_string()])
            .args(["--replica-ports", &replica_ports])
            .args(["--glint", env!("CARGO_BIN_EXE_glint")])
            .arg("--dir")
            .arg(run_dir.path())
            .arg("--")
            .args(["--log-format", "json"])
            .args(flags)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            // Its own process group, so that the guard stops the script,
            // its replicas and HAProxy together.
            .process_group(0)
            .kill_on_drop(true)
            .spawn()
            .map_err(|e| format!("{} does not start: {e}", script.display()))?;
        let mut stdout = BufReader::new(child.stdout.take().unwrap()).lines();
        let ready = tokio::time::timeout(Duration::from_secs(60), async {
            while let Ok(Some(line)) = stdout.next_line().await {
                if line.starts_with("glint cluster ready") {
                    return true;
                }
            }
            false
        })
        .await;
        let lb: SocketAddr = ([127, 0, 0, 1], ports[0]).into();
        let replicas = ports[1..]
            .iter()
            .map(|&p| SocketAddr::from(([127, 0, 0, 1], p)))
            .collect();
        if ready == Ok(true) {
            // The rest of stdout is drained so the script never blocks on it.
            tokio::spawn(async move { while let Ok(Some(_)) = stdout.next_line().await {} });
            let stderr = child.stderr.take().unwrap();
            tokio::spawn(async move {
                let mut lines = BufReader::new(stderr).lines();
                while let Ok(Some(_)) = lines.next_line().await {}
            });
            return Ok((child, lb, replicas, run_dir));
        }
        stop_group(&mut child).await;
        let mut said = String::new();
        if let Some(mut stderr) = child.stderr.take() {
            use tokio::io::AsyncReadExt;
            let _ = tokio::time::timeout(Duration::from_secs(5), stderr.read_to_string(&mut said))
                .await;
        }
        Err(format!("the cluster script did not get ready:\n{said}"))
    }

    fn lb_url(&self, path: &str) -> String {
        format!("http://{}{path}", self.lb)
    }

    fn replica_url(&self, i: usize, path: &str) -> String {
        format!("http://{}{path}", self.replicas[i])
    }

    /// The process of replica `i` (0-based) now; `None` while its
    /// supervisor is between two of them.
    fn replica_pid(&self, i: usize) -> Option<u32> {
        let file = self.run_dir.path().join(format!("replica-{}.pid", i + 1));
        fs::read_to_string(file).ok()?.trim().parse().ok()
    }

    /// The exit statuses of replica `i`'s processes so far.
    fn replica_exits(&self, i: usize) -> Vec<i32> {
        let file = self.run_dir.path().join(format!("replica-{}.exits", i + 1));
        fs::read_to_string(file)
            .unwrap_or_default()
            .lines()
            .filter_map(|l| l.trim().parse().ok())
            .collect()
    }

    /// HAProxy's `show stat`, from its stats socket.
    async fn haproxy_stats(&self) -> Stats {
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let socket = self.run_dir.path().join("haproxy.sock");
        let mut stream = tokio::net::UnixStream::connect(&socket)
            .await
            .unwrap_or_else(|e| panic!("{}: {e}", socket.display()));
        stream.write_all(b"show stat\n").await.unwrap();
        let mut text = String::new();
        tokio::time::timeout(Duration::from_secs(5), stream.read_to_string(&mut text))
            .await
            .expect("HAProxy answers on its stats socket")
            .unwrap();
        Stats::parse(&text)
    }

    /// A counter of HAProxy's backend of replicas (`wretr`, `wredis`).
    async fn backend_counter(&self, column: &str) -> u64 {
        self.haproxy_stats().await.backend_counter(column)
    }

    /// Whether HAProxy's check has replica `i` up.
    async fn haproxy_sees_up(&self, i: usize) -> bool {
        self.haproxy_stats().await.status(i) == "UP"
    }

    /// What the replicas and HAProxy logged, for a failure's message.
    fn logs(&self) -> String {
        let mut text = String::new();
        let mut files: Vec<_> = fs::read_dir(self.run_dir.path())
            .map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect())
            .unwrap_or_default();
        files.sort();
        for file in files
            .iter()
            .filter(|f| f.extension().is_some_and(|e| e == "log"))
        {
            let log = fs::read_to_string(file).unwrap_or_default();
            let tail: Vec<&str> = log.lines().rev().take(30).collect();
            text.push_str(&format!("--- {} (last lines)\n", file.display()));
            for line in tail.into_iter().rev() {
                text.push_str(line);
                text.push('\n');
            }
        }
        text
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // SIGTERM to the group: the script stops its replicas and HAProxy;
        // what is left after a bounded wait is killed.
        if let Some(pid) = self.child.id() {
            let group = format!("-{pid}");
            let _ = std::process::Command::new("kill")
                .args(["-TERM", "--", &group])
                .status();
            for _ in 0..200 {
                if matches!(self.child.try_wait(), Ok(Some(_))) {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = std::process::Command::new("kill")
                .args(["-KILL", "--", &group])
                .status();
        }
    }
}

/// HAProxy's statistics (`show stat` on its socket, or `/stats;csv` on
/// its stats page): one map of column to value per proxy or server.
struct Stats(Vec<std::collections::HashMap<String, String>>);

impl Stats {
    fn parse(csv: &str) -> Self {
        let mut lines = csv.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap_or_default()
            .trim_start_matches("# ")
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows = lines
            .filter(|l| !l.is_empty())
            .map(|l| {
                header
                    .iter()
                    .cloned()
                    .zip(l.split(',').map(str::to_owned))
                    .collect()
            })
            .collect();
        Self(rows)
    }

    /// The row of server `svname` of the backend of replicas.
    fn row(&self, svname: &str) -> &std::collections::HashMap<String, String> {
        self.0
            .iter()
            .find(|row| row["pxname"] == "replicas" && row["svname"] == svname)
            .unwrap_or_else(|| panic!("no {svname} of the backend in HAProxy's stats"))
    }

    /// A counter of the backend of replicas (`wretr`, `wredis`).
    fn backend_counter(&self, column: &str) -> u64 {
        self.row("BACKEND")[column]
            .parse()
            .unwrap_or_else(|_| panic!("no {column} for the backend in HAProxy's stats"))
    }

    /// What HAProxy's checks say of replica `i` (0-based): `UP`, `DOWN`,
    /// `UP 1/2` while rising, `MAINT (resolution)` while its name resolves
    /// to nothing, …
    fn status(&self, i: usize) -> &str {
        &self.row(&format!("replica-{}", i + 1))["status"]
    }
}

/// Kills the process group of `child` and reaps it.
async fn stop_group(child: &mut Child) {
    if let Some(pid) = child.id() {
        let _ = std::process::Command::new("kill")
            .args(["-KILL", "--", &format!("-{pid}")])
            .status();
    }
    let _ = tokio::time::timeout(Duration::from_secs(10), child.wait()).await;
}

/// A small render of spheres on a plane under two lights, `width × height`
/// at `samples` per pixel: every pixel is some mix of hit, shadow and
/// background, so a misplaced tile would show.
fn spheres(width: u32, height: u32, samples: u32) -> Value {
    json!({
        "materials": {
            "red": {"diffuse": [0.8, 0.1, 0.1], "specular": [0.5, 0.5, 0.5], "shininess": 32},
            "blue": {"diffuse": [0.1, 0.3, 0.9], "specular": [0.9, 0.9, 0.9], "shininess": 64},
            "floor": {}
        },
        "lights": [
            {"position": [2, 3, 4, 1], "attenuation": [1, 0.05, 0]},
            {"position": [-3, 2, 1, 0], "diffuse": [0.3, 0.3, 0.4]}
        ],
        "camera": {"eye": [0, 1.5, 5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 50,
                   "width": width, "height": height},
        "objects": [
            {"sphere": {"center": [-0.8, 0, 0], "radius": 0.9}, "material": "red"},
            {"sphere": {"center": [1.1, -0.3, 0.6], "radius": 0.6}, "material": "blue"},
            {"plane": {"point": [0, -1, 0], "normal": [0, 1, 0]}, "material": "floor"}
        ],
        "samples": samples,
        "shadows": true
    })
}

/// The PNG a glint answers to one render request.
async fn png_from(url: &str, request: &Value) -> Vec<u8> {
    let response = client()
        .post(url)
        .json(request)
        .send()
        .await
        .expect("the single request is answered");
    assert_eq!(response.status(), 200, "{:?}", response.text().await);
    response.bytes().await.unwrap().to_vec()
}

//! The container engine of these tests, podman, and the images it runs:
//! glint's, built by `docker/build.sh` as an operator builds it, and
//! HAProxy's, by `deploy/haproxy/build.sh`, each at most once per test run
//! (and on later runs cargo finds the static binary fresh and podman its
//! layers cached). podman and debootstrap come from Debian's packages,
//! installed as root when missing; podman runs with the settings of
//! `docker/containers.conf`. A container a test starts is removed when its
//! guard drops, panic or not.

use std::ffi::OsStr;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::Output;
use std::time::Duration;

use serde_json::Value;
use tokio::process::Command;
use tokio::sync::OnceCell;

use super::{available, debian_program, printed, repo, run, run_to_end};
use crate::load::poll;
use crate::support::client;

/// The tag `docker/build.sh` gives by default beside `glint:latest`: the
/// crate's version, which the Kubernetes manifests name.
pub const GLINT_IMAGE: &str = concat!("localhost/glint:", env!("CARGO_PKG_VERSION"));
/// The default tag of `deploy/haproxy/build.sh`.
pub const HAPROXY_IMAGE: &str = "localhost/glint-haproxy:latest";
/// The port glint listens on in its image.
pub const GLINT_PORT: u16 = 8080;

/// Points a command (podman, a build script, podman-compose) at podman and
/// at the settings of this repository's `docker/containers.conf`.
pub fn configure(command: &mut Command) {
    command
        .env("CONTAINERS_CONF", repo().join("docker/containers.conf"))
        .env("GLINT_ENGINE", "podman");
}

/// `podman ARGS` within `limit`; an error unless it exits 0.
pub async fn podman(args: &[&str], limit: Duration) -> Result<Output, String> {
    let args: Vec<&OsStr> = args.iter().map(OsStr::new).collect();
    run("podman", &args, configure, limit).await
}

/// `podman ARGS` within `limit`, whatever its exit status.
pub async fn podman_to_end(args: &[&str], limit: Duration) -> Output {
    let args: Vec<&OsStr> = args.iter().map(OsStr::new).collect();
    run_to_end("podman", &args, configure, limit)
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// podman and the runtime `docker/containers.conf` names, installed when
/// missing, and answering.
async fn engine() -> Result<(), String> {
    static ENGINE: OnceCell<Result<(), String>> = OnceCell::const_new();
    ENGINE
        .get_or_init(|| async {
            debian_program("podman", "podman").await?;
            debian_program("runc", "runc").await?;
            podman(&["info"], Duration::from_secs(60)).await.map(|_| ())
        })
        .await
        .clone()
}

/// The target directory of this test's build, where `docker/build.sh`
/// builds the static binary too.
fn target_dir() -> PathBuf {
    super::tools()
        .parent()
        .expect("target/tools is in the target directory")
        .to_owned()
}

/// The static binary `docker/build.sh` copies into the image.
pub fn static_binary() -> PathBuf {
    target_dir().join("x86_64-unknown-linux-gnu/release/glint")
}

/// glint's image, built by `docker/build.sh` once per run; `None` (after a
/// loud skip) when there is no engine. A failed build fails the test.
pub async fn glint_image(test: &str) -> Option<&'static str> {
    available(engine().await, test)?;
    static BUILT: OnceCell<Result<(), String>> = OnceCell::const_new();
    let built = BUILT
        .get_or_init(|| async {
            // The static build goes beside this test's own, in the same
            // target directory.
            let target = target_dir();
            run(
                "bash",
                &[repo().join("docker/build.sh").as_ref()],
                |c| {
                    configure(c);
                    c.env("CARGO_TARGET_DIR", &target);
                },
                Duration::from_secs(1800),
            )
            .await
            .map(|_| ())
        })
        .await;
    if let Err(why) = built {
        panic!("docker/build.sh fails: {why}");
    }
    Some(GLINT_IMAGE)
}

/// HAProxy's image from `deploy/haproxy/build.sh`, built when the engine
/// has none by that tag (it holds no file of this repository: compose
/// mounts the configuration); `None` (after a loud skip) when there is no
/// engine or no debootstrap.
pub async fn haproxy_image(test: &str) -> Option<&'static str> {
    available(engine().await, test)?;
    static BUILT: OnceCell<Result<(), String>> = OnceCell::const_new();
    let built = BUILT
        .get_or_init(|| async {
            let exists = podman(&["image", "exists", HAPROXY_IMAGE], Duration::from_secs(30));
            if exists.await.is_ok() {
                return Ok(());
            }
            debian_program("debootstrap", "debootstrap").await?;
            let script = repo().join("deploy/haproxy/build.sh");
            let built = run(
                "bash",
                &[script.as_ref()],
                configure,
                Duration::from_secs(900),
            )
            .await;
            if let Err(why) = built {
                panic!("deploy/haproxy/build.sh fails: {why}");
            }
            Ok(())
        })
        .await;
    // A failed build panicked: what is left is a missing tool.
    available(built.clone(), test)?;
    Some(HAPROXY_IMAGE)
}

/// `podman image inspect` (or `podman inspect`) of one object, as JSON.
pub async fn inspect(args: &[&str]) -> Value {
    let output = podman(args, Duration::from_secs(30))
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let all: Value = serde_json::from_slice(&output.stdout)
        .unwrap_or_else(|e| panic!("podman inspect prints JSON ({e}): {}", printed(&output)));
    all[0].clone()
}

/// Whether glint at `addr` answers `status` on `/readyz` within 30 s.
pub async fn readyz_answers(addr: SocketAddr, status: u16) -> bool {
    let readyz = format!("http://{addr}/readyz");
    poll(300, Duration::from_millis(100), || async {
        client()
            .get(&readyz)
            .send()
            .await
            .is_ok_and(|r| r.status() == status)
    })
    .await
}

/// A container started with `podman run -d`, removed when dropped.
pub struct Container {
    pub name: String,
}

impl Container {
    /// A name for a container of this test run, and the guard that removes
    /// a container of that name when dropped.
    pub fn named(what: &str) -> Self {
        let name = format!("glint-test-{}-{what}", std::process::id());
        // One left by an earlier run of the same process id.
        let _ = Self::remove(&name);
        Self { name }
    }

    /// `podman run -d --name NAME FLAGS… IMAGE ARGS…`: the container,
    /// started (not necessarily ready).
    pub async fn run(what: &str, flags: &[&str], image: &str, args: &[&str]) -> Self {
        let container = Self::named(what);
        let mut all = vec!["run", "-d", "--name", &container.name];
        all.extend_from_slice(flags);
        all.push(image);
        all.extend_from_slice(args);
        podman(&all, Duration::from_secs(60))
            .await
            .unwrap_or_else(|e| panic!("{e}"));
        container
    }

    /// glint's image run with `flags`, its port published on a loopback
    /// port the engine chose, and ready: the container and that address.
    pub async fn glint(what: &str, image: &str, flags: &[&str]) -> (Self, SocketAddr) {
        let publish = format!("127.0.0.1::{GLINT_PORT}");
        let mut all = vec!["--publish", &publish];
        all.extend_from_slice(flags);
        let container = Self::run(what, &all, image, &[]).await;
        let addr = container.published(GLINT_PORT).await;
        let ready = readyz_answers(addr, 200).await;
        assert!(
            ready,
            "{} is ready within 30 s\n{}",
            container.name,
            container.logs().await
        );
        (container, addr)
    }

    /// The host's address for the container's `port`.
    pub async fn published(&self, port: u16) -> SocketAddr {
        let output = podman(
            &["port", &self.name, &format!("{port}/tcp")],
            Duration::from_secs(30),
        )
        .await
        .unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8_lossy(&output.stdout);
        text.lines()
            .find_map(|l| l.trim().parse().ok())
            .unwrap_or_else(|| panic!("`podman port` says where {port} is published: {text}"))
    }

    /// What the container wrote on stdout and stderr.
    pub async fn logs(&self) -> String {
        let output = podman_to_end(&["logs", &self.name], Duration::from_secs(30)).await;
        printed(&output)
    }

    /// `podman inspect` of the container.
    pub async fn inspect(&self) -> Value {
        inspect(&["inspect", &self.name]).await
    }

    fn remove(name: &str) -> std::io::Result<std::process::Output> {
        std::process::Command::new("podman")
            .args(["rm", "--force", "--time", "0", name])
            .env("CONTAINERS_CONF", repo().join("docker/containers.conf"))
            .stdin(std::process::Stdio::null())
            .output()
    }
}

impl Drop for Container {
    fn drop(&mut self) {
        let _ = Self::remove(&self.name);
    }
}

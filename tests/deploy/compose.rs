//! `deploy/compose.yaml` as an operator runs it, with podman-compose: three
//! glint containers behind HAProxy's container, every request through the
//! balancer's published port, under a bounded load of shade and render
//! requests on several connections. A replica container killed, the
//! replicas replaced one by one (`up --force-recreate`), a replica cut off
//! its network and connected again: no request may fail, and every answer
//! must be the one a single glint process on the host gives. The tile
//! fan-out client through the balancer makes the single request's PNG.
#![cfg(unix)]

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::Output;
use std::sync::Arc;
use std::time::Duration;

use super::engine::{Container, configure, glint_image, haproxy_image, podman, podman_to_end};
use super::topology::{Case, Load, cases};
use super::{
    ONE_CLUSTER, Scratch, Stats, available, free_ports, png_from, python_tools, repo, run_to_end,
    spheres,
};
use crate::load::poll;
use crate::support::client;

const REPLICAS: usize = 3;
/// Requests of the run in which a replica is killed.
const KILL_LOAD: usize = 2000;
/// At most this many requests for the runs that last until the replicas
/// are back and the test stops them: a bound for a test that never does,
/// not a length (twenty thousand ran out during a rolling update of three
/// replicas, and the load then waited for answers that never came).
const LONG_LOAD: usize = 2_000_000;
/// Polls of HAProxy's view, 100 ms apart: its checks are 250 ms apart, a
/// new container starts within a second or two, and a replica cut off its
/// network fails its checks on their 1 s timeout.
const SEEN_WITHIN: usize = 600;

/// One project of `deploy/compose.yaml`: its name, the Python whose
/// environment holds podman-compose, and the variables compose.yaml reads;
/// brought down when dropped.
struct Project {
    name: String,
    python: PathBuf,
    variables: Vec<(&'static str, String)>,
}

impl Project {
    /// `podman-compose ARGS` on this project, within `limit`, whatever its
    /// exit status.
    async fn compose(&self, args: &[&str], limit: Duration) -> Output {
        let head = ["-m", "podman_compose", "--project-name", &self.name];
        let mut all: Vec<&OsStr> = head.iter().map(OsStr::new).collect();
        let file = repo().join("deploy/compose.yaml");
        all.extend([OsStr::new("--file"), file.as_os_str()]);
        all.extend(args.iter().map(OsStr::new));
        run_to_end(
            &self.python,
            &all,
            |c| {
                configure(c);
                c.envs(self.variables.iter().map(|(k, v)| (k, v)));
            },
            limit,
        )
        .await
        .unwrap_or_else(|e| panic!("podman-compose: {e}"))
    }
}

impl Drop for Project {
    fn drop(&mut self) {
        // Synchronously, within two minutes: a guard may drop on a runtime
        // that is going away.
        let _ = std::process::Command::new("timeout")
            .arg("120")
            .arg(&self.python)
            .args([
                "-m",
                "podman_compose",
                "--project-name",
                &self.name,
                "--file",
            ])
            .arg(repo().join("deploy/compose.yaml"))
            .args(["down", "--timeout", "0"])
            .env("CONTAINERS_CONF", repo().join("docker/containers.conf"))
            .envs(self.variables.iter().map(|(k, v)| (k, v)))
            .stdin(std::process::Stdio::null())
            .output();
    }
}

/// The topology up, with HAProxy seeing every replica up.
struct Topology {
    project: Project,
    /// glint's image.
    glint: &'static str,
    lb: SocketAddr,
    stats: SocketAddr,
    _one: tokio::sync::MutexGuard<'static, ()>,
}

impl Topology {
    /// `podman-compose up -d` with glint's and HAProxy's images as built
    /// here and ports the kernel chose, then a wait until HAProxy sees every
    /// replica up; `None` (after a loud skip) when a tool cannot be had.
    async fn up(test: &str) -> Option<Self> {
        let glint = glint_image(test).await?;
        let haproxy = haproxy_image(test).await?;
        let python = available(python_tools().await, test)?.bin("python");
        let one = ONE_CLUSTER.lock().await;
        let mut last = String::new();
        for attempt in 0..3 {
            // The ports must be named in the file's variables; one taken in
            // between fails `up`, and the next attempt takes others.
            let ports = free_ports(2);
            let project = Project {
                name: format!("glint-test-{}-{attempt}", std::process::id()),
                python: python.clone(),
                variables: vec![
                    ("GLINT_IMAGE", glint.to_owned()),
                    ("GLINT_HAPROXY_IMAGE", haproxy.to_owned()),
                    ("GLINT_PORT", ports[0].to_string()),
                    ("GLINT_STATS_PORT", ports[1].to_string()),
                ],
            };
            let output = project
                .compose(&["up", "-d"], Duration::from_secs(180))
                .await;
            if !output.status.success() {
                last = super::printed(&output);
                continue;
            }
            let topology = Self {
                project,
                glint,
                lb: ([127, 0, 0, 1], ports[0]).into(),
                stats: ([127, 0, 0, 1], ports[1]).into(),
                _one: one,
            };
            let up = topology
                .seen(|stats| (0..REPLICAS).all(|i| stats.status(i) == "UP"))
                .await;
            assert!(
                up,
                "HAProxy sees every replica up within a minute\n{}",
                topology.logs().await
            );
            return Some(topology);
        }
        panic!("podman-compose up failed 3 times; the last:\n{last}");
    }

    fn lb_url(&self, path: &str) -> String {
        format!("http://{}{path}", self.lb)
    }

    /// HAProxy's statistics from its stats page; `None` while it does not
    /// answer.
    async fn stats(&self) -> Option<Stats> {
        let response = client()
            .get(format!("http://{}/stats;csv", self.stats))
            .send()
            .await
            .ok()?;
        Some(Stats::parse(&response.text().await.ok()?))
    }

    /// Whether `what` comes true of HAProxy's view within [`SEEN_WITHIN`]
    /// polls.
    async fn seen(&self, what: impl Fn(&Stats) -> bool) -> bool {
        poll(SEEN_WITHIN, Duration::from_millis(100), || async {
            self.stats().await.is_some_and(|stats| what(&stats))
        })
        .await
    }

    /// The name of the container of `service` now.
    async fn container(&self, service: &str) -> String {
        let project = format!("label=io.podman.compose.project={}", self.project.name);
        let service = format!("label=com.docker.compose.service={service}");
        let output = podman(
            &[
                "ps",
                "--filter",
                &project,
                "--filter",
                &service,
                "--format",
                "{{.Names}}",
            ],
            Duration::from_secs(30),
        )
        .await
        .unwrap_or_else(|e| panic!("{e}"));
        let names = String::from_utf8_lossy(&output.stdout);
        let mut names = names.lines().filter(|l| !l.is_empty());
        let name = names
            .next()
            .unwrap_or_else(|| panic!("no running {service}"));
        assert!(names.next().is_none(), "one container of {service}");
        name.to_owned()
    }

    /// The last lines of every container's log, for a failure's message.
    async fn logs(&self) -> String {
        let mut text = String::new();
        let project = format!("label=io.podman.compose.project={}", self.project.name);
        let names = podman_to_end(
            &["ps", "-a", "--filter", &project, "--format", "{{.Names}}"],
            Duration::from_secs(30),
        )
        .await;
        for name in String::from_utf8_lossy(&names.stdout).lines() {
            let log = podman_to_end(&["logs", "--tail", "30", name], Duration::from_secs(30)).await;
            text.push_str(&format!(
                "--- {name} (last lines)\n{}\n",
                super::printed(&log)
            ));
        }
        text
    }

    /// The load of shade and render requests through the balancer, with
    /// the answers of a single container of the same image to check them
    /// against. (A build of other settings, as the tests' own debug build,
    /// may differ in the last bits of the f64 term summaries.)
    async fn load(&self, max: usize) -> Load {
        let (_single, addr) = Container::glint("single", self.glint, &[]).await;
        let cases: Arc<Vec<Case>> = Arc::new(cases(&format!("http://{addr}")).await);
        Load::start(self.lb_url(""), cases, max)
    }

    /// [`Load::finish`], failing with every container's log when a
    /// request failed.
    async fn finish(
        &self,
        load: Load,
        stop: bool,
        limit: Duration,
    ) -> (usize, BTreeMap<String, usize>) {
        match load.finish(stop, limit).await {
            Ok(finished) => finished,
            Err(failed) => panic!("{failed}\n{}", self.logs().await),
        }
    }

    /// Waits until the load has answered `count` requests.
    async fn answered(load: &Load, count: usize) {
        let done = poll(12_000, Duration::from_millis(10), || async {
            load.done() >= count
        })
        .await;
        assert!(done, "{count} requests are answered within two minutes");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replica_container_killed_under_load_loses_no_request() {
    let test = "a_replica_container_killed_under_load_loses_no_request";
    let Some(topology) = Topology::up(test).await else {
        return;
    };
    let load = topology.load(KILL_LOAD).await;
    Topology::answered(&load, KILL_LOAD / 2).await;
    let victim = topology.container("replica-2").await;
    podman(&["kill", &victim], Duration::from_secs(30))
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let (done, served_by) = topology.finish(load, false, Duration::from_secs(180)).await;
    assert_eq!(done, KILL_LOAD);
    assert_eq!(served_by.len(), REPLICAS, "{served_by:?}");
    // What was in flight on the killed replica, and what was sent to it
    // before its checks failed, was retried on another.
    let stats = topology.stats().await.expect("HAProxy's stats");
    let (retries, redispatches) = (
        stats.backend_counter("wretr"),
        stats.backend_counter("wredis"),
    );
    assert!(
        retries + redispatches > 0,
        "HAProxy retried: wretr {retries}, wredis {redispatches}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rolling_update_of_the_replica_containers_loses_no_request() {
    let test = "a_rolling_update_of_the_replica_containers_loses_no_request";
    let Some(topology) = Topology::up(test).await else {
        return;
    };
    let load = topology.load(LONG_LOAD).await;
    Topology::answered(&load, 200).await;
    for i in 0..REPLICAS {
        let service = format!("replica-{}", i + 1);
        let before = topology.container(&service).await;
        let before_id = super::engine::inspect(&["inspect", &before]).await["Id"].clone();
        // The old container drains (SIGTERM: /readyz turns 503, HAProxy
        // takes it out) and is removed; a new one takes its name.
        let replaced = topology
            .project
            .compose(
                &["up", "-d", "--force-recreate", "--no-deps", &service],
                Duration::from_secs(120),
            )
            .await;
        assert!(replaced.status.success(), "{}", super::printed(&replaced));
        let after = topology.container(&service).await;
        let after_id = super::engine::inspect(&["inspect", &after]).await["Id"].clone();
        assert_ne!(before_id, after_id, "{service} is a new container");
        let back = topology.seen(|stats| stats.status(i) == "UP").await;
        assert!(back, "{service} is back up\n{}", topology.logs().await);
    }
    let after = load.done() + 200;
    Topology::answered(&load, after).await;
    let (done, served_by) = topology.finish(load, true, Duration::from_secs(60)).await;
    assert!(done > 400, "{done} requests");
    assert_eq!(served_by.len(), REPLICAS, "{served_by:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replica_cut_off_its_network_is_taken_out_and_back_losing_no_request() {
    let test = "a_replica_cut_off_its_network_is_taken_out_and_back_losing_no_request";
    let Some(topology) = Topology::up(test).await else {
        return;
    };
    let victim = topology.container("replica-2").await;
    let networks =
        super::engine::inspect(&["inspect", &victim]).await["NetworkSettings"]["Networks"]
            .as_object()
            .expect("the replica's networks")
            .keys()
            .cloned()
            .collect::<Vec<_>>();
    assert_eq!(networks.len(), 1, "{networks:?}");
    let network = &networks[0];

    let load = topology.load(LONG_LOAD).await;
    Topology::answered(&load, 200).await;
    podman(
        &["network", "disconnect", network, &victim],
        Duration::from_secs(30),
    )
    .await
    .unwrap_or_else(|e| panic!("{e}"));
    // Its checks fail (DOWN), or its name stops resolving first (MAINT):
    // either way it is out of the rotation.
    let down = topology
        .seen(|stats| {
            let status = stats.status(1);
            status.starts_with("DOWN") || status.starts_with("MAINT")
        })
        .await;
    assert!(
        down,
        "HAProxy takes replica-2 out\n{}",
        topology.logs().await
    );
    let during = load.done() + 100;
    Topology::answered(&load, during).await;
    // Back, under the service's name as compose gave it.
    podman(
        &[
            "network",
            "connect",
            "--alias",
            "replica-2",
            network,
            &victim,
        ],
        Duration::from_secs(30),
    )
    .await
    .unwrap_or_else(|e| panic!("{e}"));
    let up = topology.seen(|stats| stats.status(1) == "UP").await;
    assert!(
        up,
        "HAProxy takes replica-2 back\n{}",
        topology.logs().await
    );
    let after = load.done() + 200;
    Topology::answered(&load, after).await;
    // A request that replica-2 had taken when it was cut off waits for
    // HAProxy's server timeout (60 s) before its retry.
    let (done, served_by) = topology.finish(load, true, Duration::from_secs(120)).await;
    assert!(done > 400, "{done} requests");
    assert_eq!(served_by.len(), REPLICAS, "{served_by:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn glint_render_via_the_compose_balancer_makes_the_single_requests_png() {
    let test = "glint_render_via_the_compose_balancer_makes_the_single_requests_png";
    let Some(topology) = Topology::up(test).await else {
        return;
    };
    // The PNG of one request to one container of the same image.
    let (_single, addr) = Container::glint("single-render", topology.glint, &[]).await;
    let request = spheres(90, 60, 2);
    let expected = png_from(&format!("http://{addr}/v1/render"), &request).await;
    let scratch = Scratch::new("compose-via");
    let file = scratch.path().join("request.json");
    std::fs::write(&file, serde_json::to_vec(&request).unwrap()).unwrap();
    let flags = ["--tiles", "4x3", "--parallel", "4"];
    let said = super::fanout::fanned_out(&file, &topology.lb_url(""), &flags, &expected).await;
    assert_eq!(said["tiles"].as_array().unwrap().len(), 12, "{said}");
    let served_by = said["served_by"].as_object().unwrap();
    assert!(
        served_by.len() >= 2 && served_by.keys().all(|k| k.starts_with("replica-")),
        "the tiles were answered by the containers: {said}"
    );
}

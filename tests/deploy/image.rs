//! glint's image as an operator runs it: built by `docker/build.sh`; small,
//! unprivileged, declaring its port, its probe and its stop signal, as the
//! Kubernetes manifests expect; serving from a read-only root the same
//! bytes as the host's binary; healthy, then unhealthy while it drains;
//! answering a render in flight on `podman stop` and exiting 0; and
//! refusing a bad setting with a line in its log and an exit the engine
//! shows, not a restart loop.
#![cfg(unix)]

use std::ffi::OsStr;
use std::fs;
use std::process::Output;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::engine::{
    Container, GLINT_PORT, glint_image, inspect, podman, podman_to_end, readyz_answers,
    static_binary,
};
use super::{Scratch, png_from, printed, repo, run, run_to_end, spheres};
use crate::load::{assert_same_answer, metric, poll};
use crate::support::Rng;
use crate::support::client;

/// The ceiling of the image's size, in bytes: the static binary and
/// nothing else fits well under it.
const MAX_IMAGE_BYTES: u64 = 30_000_000;
/// `nobody` and `nogroup`, the image's user by number.
const NOBODY: u64 = 65534;

/// A YAML file of the repository, as JSON.
fn yaml(path: &str) -> Value {
    let text = fs::read_to_string(repo().join(path)).unwrap();
    serde_norway::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[tokio::test]
async fn the_image_is_small_unprivileged_and_declares_its_port_probe_and_stop() {
    let test = "the_image_is_small_unprivileged_and_declares_its_port_probe_and_stop";
    let Some(image) = glint_image(test).await else {
        return;
    };
    let inspected = inspect(&["image", "inspect", image]).await;
    let size = inspected["Size"].as_u64().expect("a size");
    assert!(size <= MAX_IMAGE_BYTES, "the image has {size} bytes");
    let config = &inspected["Config"];
    assert_eq!(config["User"], format!("{NOBODY}:{NOBODY}"), "{config}");
    assert!(
        config["ExposedPorts"]
            .get(format!("{GLINT_PORT}/tcp"))
            .is_some(),
        "{config}"
    );
    assert_eq!(config["StopSignal"], "SIGTERM", "{config}");
    // The probe runs the binary itself: the image has no shell to run a
    // command line with.
    let probe = &inspected["Healthcheck"]["Test"];
    assert_eq!(probe[0], "CMD", "{inspected}");
    assert_eq!(probe[1], config["Entrypoint"][0], "{inspected}");
    assert_eq!(probe[2], "healthcheck", "{inspected}");

    // The Kubernetes manifests (the service and the tile Job) run this
    // image, by this tag, as this user.
    for (kustomization, workload) in [
        (
            "deploy/k8s/kustomization.yaml",
            "deploy/k8s/deployment.yaml",
        ),
        (
            "deploy/k8s/tiles/kustomization.yaml",
            "deploy/k8s/tiles/job.yaml",
        ),
    ] {
        let images = &yaml(kustomization)["images"][0];
        let tagged = format!(
            "localhost/{}:{}",
            images["name"].as_str().unwrap(),
            images["newTag"].as_str().unwrap()
        );
        assert_eq!(
            tagged, image,
            "docker/build.sh tags what {kustomization} names"
        );
        let pod = &yaml(workload)["spec"]["template"]["spec"];
        assert_eq!(pod["containers"][0]["image"], images["name"], "{workload}");
        assert_eq!(pod["securityContext"]["runAsUser"], NOBODY, "{workload}");
        assert_eq!(pod["securityContext"]["runAsGroup"], NOBODY, "{workload}");
    }
    let pod = &yaml("deploy/k8s/deployment.yaml")["spec"]["template"]["spec"];
    assert_eq!(
        pod["containers"][0]["ports"][0]["containerPort"],
        GLINT_PORT
    );
}

/// What `server` answers to `body` on `path`: the status and the bytes.
async fn answer(server: &str, path: &str, body: &[u8]) -> (u16, Vec<u8>) {
    let response = client()
        .post(format!("{server}{path}"))
        .header("content-type", "application/json")
        .body(body.to_vec())
        .send()
        .await
        .unwrap_or_else(|e| panic!("{server}{path}: {e}"));
    let status = response.status().as_u16();
    (status, response.bytes().await.unwrap().to_vec())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_read_only_container_answers_as_the_host_binary_does() {
    let test = "a_read_only_container_answers_as_the_host_binary_does";
    let Some(image) = glint_image(test).await else {
        return;
    };
    // No tmpfs either: nothing may be written anywhere.
    let flags = ["--read-only", "--read-only-tmpfs=false"];
    let (container, addr) = Container::glint("read-only", image, &flags).await;
    let state = container.inspect().await;
    assert_eq!(state["HostConfig"]["ReadonlyRootfs"], true);
    // The server runs as nobody.
    let pid = state["State"]["Pid"].as_u64().expect("a running process");
    let status = fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let uid = status.lines().find(|l| l.starts_with("Uid:")).unwrap();
    assert!(
        uid.split_whitespace()
            .skip(1)
            .all(|id| id == NOBODY.to_string()),
        "{uid}"
    );

    // The binary of the image, run on the host, answers the same bodies.
    let in_container = format!("http://{addr}");
    let mut rng = Rng::new(0xc0da1e);
    let mut shades = vec![fs::read(repo().join("examples/triangle.json")).unwrap()];
    shades.extend((0..4).map(|_| serde_json::to_vec(&rng.shade_request(64)).unwrap()));
    for (i, body) in shades.iter().enumerate() {
        let (status, got) = answer(&in_container, "/v1/shade", body).await;
        assert_eq!(status, 200, "{}", String::from_utf8_lossy(&got));
        let expected = on_the_host("shade", body).await;
        assert!(expected.status.success(), "{}", printed(&expected));
        assert_same_answer(
            serde_json::from_slice(&got).unwrap(),
            &serde_json::from_slice(&expected.stdout).unwrap(),
            &format!("shade {i}"),
        );
    }
    for request in [spheres(64, 48, 4), spheres(31, 17, 1)] {
        let got = png_from(&format!("{in_container}/v1/render"), &request).await;
        assert!(
            got == render_on_the_host(&request).await,
            "the container's PNG is the host's"
        );
    }
    // And a request the container refuses, refused as on the host.
    let bad = b"{\"lights\": 3}";
    let (status, problem) = answer(&in_container, "/v1/shade", bad).await;
    assert_eq!(status, 400);
    let refused = on_the_host("shade", bad).await;
    assert!(!refused.status.success());
    let problem: Value = serde_json::from_slice(&problem).unwrap();
    let expected: Value = serde_json::from_slice(&refused.stderr).unwrap();
    assert_eq!(problem, expected);
}

/// `podman healthcheck run`: its exit code and what it printed.
async fn healthcheck(container: &Container) -> (Option<i32>, String) {
    let output = podman_to_end(
        &["healthcheck", "run", &container.name],
        Duration::from_secs(30),
    )
    .await;
    let said = String::from_utf8_lossy(&output.stdout).trim().to_owned();
    (output.status.code(), said)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_healthcheck_is_healthy_and_turns_unhealthy_while_draining() {
    let test = "the_healthcheck_is_healthy_and_turns_unhealthy_while_draining";
    let Some(image) = glint_image(test).await else {
        return;
    };
    // A minute of drain: alive, but unready, for as long as the test looks.
    let flags = ["--env", "GLINT_DRAIN_MS=60000"];
    let (container, addr) = Container::glint("healthcheck", image, &flags).await;
    let (code, said) = healthcheck(&container).await;
    assert_eq!(code, Some(0), "healthy: {said}\n{}", container.logs().await);

    // SIGTERM, as `podman stop` sends it; the drain starts.
    podman(
        &["kill", "--signal", "TERM", &container.name],
        Duration::from_secs(30),
    )
    .await
    .unwrap();
    let draining = readyz_answers(addr, 503).await;
    assert!(draining, "/readyz answers 503 while draining");
    let (code, said) = healthcheck(&container).await;
    assert_eq!(code, Some(1), "unhealthy: {said}");
    assert!(said.contains("unhealthy"), "{said}");
    // Alive all the while.
    let healthz = client()
        .get(format!("http://{addr}/healthz"))
        .send()
        .await
        .unwrap();
    assert_eq!(healthz.status(), 200);
    assert_eq!(container.inspect().await["State"]["Status"], "running");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn podman_stop_during_a_long_render_answers_it_whole_and_exits_0() {
    let test = "podman_stop_during_a_long_render_answers_it_whole_and_exits_0";
    let Some(image) = glint_image(test).await else {
        return;
    };
    let flags = [
        "--env",
        "GLINT_THREADS=1",
        "--env",
        "GLINT_SHUTDOWN_GRACE_MS=60000",
    ];
    let (container, addr) = Container::glint("stop", image, &flags).await;
    // Seconds of work on one thread.
    let request = spheres(LONG_RENDER.0, LONG_RENDER.1, LONG_RENDER.2);
    let render = tokio::spawn({
        let (url, request) = (format!("http://{addr}/v1/render"), request.clone());
        async move {
            let response = client().post(url).json(&request).send().await?;
            let status = response.status();
            Ok::<_, reqwest::Error>((status, response.bytes().await?))
        }
    });
    let metrics = format!("http://{addr}/metrics");
    let running = poll(1000, Duration::from_millis(10), || async {
        let Ok(response) = client().get(&metrics).send().await else {
            return false;
        };
        metric(
            &response.text().await.unwrap_or_default(),
            "glint_jobs_running",
        ) == 1.0
    })
    .await;
    assert!(running, "the render is running");

    assert!(!render.is_finished(), "the render is still in flight");
    let grace = 60;
    let started = Instant::now();
    let stop = podman(
        &["stop", "--time", &grace.to_string(), &container.name],
        Duration::from_secs(grace + 30),
    )
    .await;
    let stopped_after = started.elapsed();
    stop.unwrap_or_else(|e| panic!("{e}"));
    let (status, png) = tokio::time::timeout(Duration::from_secs(30), render)
        .await
        .expect("the render is answered once the container stopped")
        .unwrap()
        .expect("the render is answered");
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&png));
    // The same PNG the image's binary renders of the same request on the
    // host.
    let expected = render_on_the_host(&request).await;
    assert!(png == expected, "the PNG is whole, byte for byte");

    let state = &container.inspect().await["State"];
    assert_eq!(state["Status"], "exited", "{state}");
    assert_eq!(
        state["ExitCode"],
        0,
        "exited 0 within the grace, not killed\n{}",
        container.logs().await
    );
    assert!(
        stopped_after < Duration::from_secs(grace),
        "{stopped_after:?}"
    );
}

/// A render of some seconds on one thread of the release build.
const LONG_RENDER: (u32, u32, u32) = (640, 480, 32);

/// `glint COMMAND FILE` by the static binary of the image, run on the
/// host, with `body` in FILE: what it printed.
async fn on_the_host(command: &str, body: &[u8]) -> Output {
    let scratch = Scratch::new(&format!("host-{command}"));
    let file = scratch.path().join("request.json");
    fs::write(&file, body).unwrap();
    let args: [&OsStr; 2] = [command.as_ref(), file.as_ref()];
    run_to_end(static_binary(), &args, |_| {}, Duration::from_secs(300))
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The PNG the static binary of the image, run on the host, renders of
/// `request`.
async fn render_on_the_host(request: &Value) -> Vec<u8> {
    let scratch = Scratch::new("host-render");
    let (file, out) = (scratch.path().join("r.json"), scratch.path().join("r.png"));
    fs::write(&file, serde_json::to_vec(request).unwrap()).unwrap();
    let args: [&OsStr; 4] = [
        "render".as_ref(),
        file.as_ref(),
        "-o".as_ref(),
        out.as_ref(),
    ];
    run(static_binary(), &args, |_| {}, Duration::from_secs(300))
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    fs::read(&out).unwrap()
}

/// Waits until `container` has exited for good after `restarts` restarts,
/// and returns its state.
async fn exited(container: &Container, restarts: u64) -> Value {
    let done = poll(300, Duration::from_millis(100), || async {
        let state = container.inspect().await;
        state["State"]["Status"] == "exited" && state["RestartCount"] == restarts
    })
    .await;
    let state = container.inspect().await;
    assert!(done, "{} exits within 30 s: {state}", container.name);
    state
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bad_setting_exits_non_zero_with_a_clear_line_in_the_log() {
    let test = "a_bad_setting_exits_non_zero_with_a_clear_line_in_the_log";
    let Some(image) = glint_image(test).await else {
        return;
    };
    // A setting that is no number, with compose's restart policy: three
    // tries, then the container stays down, its reason in its log.
    let flags = ["--env", "GLINT_MAX_JOBS=abc", "--restart", "on-failure:3"];
    let bad = Container::run("bad-setting", &flags, image, &[]).await;
    let state = exited(&bad, 3).await;
    assert_ne!(state["State"]["ExitCode"], 0, "{state}");
    let logs = bad.logs().await;
    assert!(
        logs.contains("invalid value 'abc' for '--max-jobs"),
        "a line names the setting and the value:\n{logs}"
    );

    // The port taken: a second glint in the first one's network namespace.
    let (owner, addr) = Container::glint("port-owner", image, &[]).await;
    let network = format!("container:{}", owner.name);
    let second = Container::run("port-in-use", &["--network", &network], image, &[]).await;
    let state = exited(&second, 0).await;
    assert_ne!(state["State"]["ExitCode"], 0, "{state}");
    let logs = second.logs().await;
    assert!(
        logs.lines()
            .any(|l| l.contains("\"ERROR\"") && l.contains("in use")),
        "an error line says the address is in use:\n{logs}"
    );
    // The first is untouched.
    let readyz = client()
        .get(format!("http://{addr}/readyz"))
        .send()
        .await
        .unwrap();
    assert_eq!(readyz.status(), 200);
}

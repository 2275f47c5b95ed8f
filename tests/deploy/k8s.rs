//! The Kubernetes manifests of `deploy/k8s`, offline: built by the
//! kustomize inside Debian's kubectl, validated by kubernetes-validate
//! `--strict` (unknown fields are errors) against the oldest and the newest
//! Kubernetes the manifests are written for, and read for the properties a
//! schema cannot state. A deliberately broken copy must fail.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Deserialize;
use serde_json::Value;

use super::{
    InstallLock, PythonTools, Scratch, available, python_tools, repo, run, run_to_end, tools,
};

/// The Kubernetes versions validated against: 1.30 is the first whose
/// kubelet runs the preStop `sleep` on by default, the image having no shell.
const VERSIONS: [&str; 2] = ["1.30.0", "1.37.0"];

/// Debian's `kubernetes-client` (kubectl 1.20, with kustomize v2.0.3 built
/// in), unpacked under `target/tools/kubectl` with `apt-get download` and
/// `dpkg-deb -x`: no root needed, and no clash with a kubectl already
/// installed. The kubectl of another distribution would do, but this one
/// every Debian machine can have, so every run builds with the same one.
async fn kubectl() -> Result<PathBuf, String> {
    let dir = tools().join("kubectl");
    let binary = dir.join("root/usr/bin/kubectl");
    let _lock = InstallLock::take()?;
    if binary.is_file() {
        return Ok(binary);
    }
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let minutes = Duration::from_secs(600);
    let download = |dir: &Path| {
        let dir = dir.to_owned();
        async move {
            run(
                "apt-get",
                &["download".as_ref(), "kubernetes-client".as_ref()],
                |c| {
                    c.current_dir(&dir);
                },
                minutes,
            )
            .await
        }
    };
    if download(&dir).await.is_err() {
        // A fresh machine may have no package lists yet.
        run("apt-get", &["update".as_ref()], |_| {}, minutes)
            .await
            .map_err(|e| format!("apt-get update: {e}"))?;
        download(&dir)
            .await
            .map_err(|e| format!("apt-get download kubernetes-client: {e}"))?;
    }
    let deb = fs::read_dir(&dir)
        .map_err(|e| e.to_string())?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|e| e == "deb"))
        .ok_or("apt-get download left no .deb")?;
    run(
        "dpkg-deb",
        &["-x".as_ref(), deb.as_ref(), dir.join("root").as_ref()],
        |_| {},
        minutes,
    )
    .await?;
    if binary.is_file() {
        Ok(binary)
    } else {
        Err(format!("{} has no usr/bin/kubectl", deb.display()))
    }
}

/// The tools both tests need.
struct Tools {
    kubectl: PathBuf,
    validator: PythonTools,
}

impl Tools {
    async fn get(test: &str) -> Option<Self> {
        let kubectl = available(kubectl().await, test)?;
        let validator = available(python_tools().await, test)?;
        Some(Self { kubectl, validator })
    }

    /// `kubectl kustomize DIR`: the manifests as they would be applied.
    async fn build(&self, dir: &Path) -> String {
        let output = run(
            &self.kubectl,
            &["kustomize".as_ref(), dir.as_ref()],
            |_| {},
            Duration::from_secs(60),
        )
        .await
        .unwrap_or_else(|e| panic!("kubectl kustomize {}: {e}", dir.display()));
        String::from_utf8(output.stdout).expect("YAML is text")
    }

    /// kubernetes-validate on `manifests` against `version`; whether it
    /// passed, and what it said.
    async fn validate(&self, manifests: &Path, version: &str, strict: bool) -> (bool, String) {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "-m".as_ref(),
            "kubernetes_validate".as_ref(),
            "--kubernetes-version".as_ref(),
            version.as_ref(),
        ];
        if strict {
            args.push("--strict".as_ref());
        }
        args.push(manifests.as_ref());
        let output = run_to_end(
            self.validator.bin("python"),
            &args,
            |_| {},
            Duration::from_secs(120),
        )
        .await
        .unwrap_or_else(|e| panic!("kubernetes-validate: {e}"));
        let said = format!(
            "{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        (output.status.success(), said)
    }
}

/// Every document of a multi-document YAML stream, by `Kind/name`.
fn documents(yaml: &str) -> HashMap<String, Value> {
    serde_norway::Deserializer::from_str(yaml)
        .map(|doc| Value::deserialize(doc).expect("kustomize writes YAML"))
        .filter(|doc| !doc.is_null())
        .map(|doc| {
            let key = format!(
                "{}/{}",
                doc["kind"].as_str().unwrap(),
                doc["metadata"]["name"].as_str().unwrap()
            );
            (key, doc)
        })
        .collect()
}

/// A duration in seconds from a `GLINT_*_MS` variable of `container`.
fn env_seconds(container: &Value, name: &str) -> f64 {
    let value = container["env"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == name)
        .unwrap_or_else(|| panic!("{name} is set"))["value"]
        .as_str()
        .unwrap();
    value.parse::<f64>().unwrap() / 1e3
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_kubernetes_manifests_build_and_pass_strict_validation() {
    let test = "the_kubernetes_manifests_build_and_pass_strict_validation";
    let Some(tools) = Tools::get(test).await else {
        return;
    };
    let scratch = Scratch::new("k8s");
    for dir in ["deploy/k8s", "deploy/k8s/tiles"] {
        let yaml = tools.build(&repo().join(dir)).await;
        let file = scratch
            .path()
            .join(format!("{}.yaml", dir.replace('/', "-")));
        fs::write(&file, &yaml).unwrap();
        for version in VERSIONS {
            let (passed, said) = tools.validate(&file, version, true).await;
            assert!(passed, "{dir} against Kubernetes {version}:\n{said}");
        }
    }

    // What the schema cannot say.
    let service = documents(&tools.build(&repo().join("deploy/k8s")).await);
    let deployment = &service["Deployment/glint"];
    let spec = &deployment["spec"];
    assert_eq!(spec["strategy"]["rollingUpdate"]["maxUnavailable"], 0);
    let pod = &spec["template"]["spec"];
    let container = &pod["containers"][0];
    assert_eq!(container["readinessProbe"]["httpGet"]["path"], "/readyz");
    assert_eq!(container["livenessProbe"]["httpGet"]["path"], "/healthz");
    assert_eq!(container["startupProbe"]["httpGet"]["path"], "/healthz");
    for probe in ["readinessProbe", "livenessProbe", "startupProbe"] {
        assert_eq!(container[probe]["httpGet"]["port"], "http", "{probe}");
    }
    assert_eq!(container["ports"][0]["name"], "http");
    // Stopping takes the preStop pause, then at most the shutdown grace;
    // the grace outlasts a render (bounded by the request timeout), and the
    // pod's termination grace outlasts both.
    let pause = container["lifecycle"]["preStop"]["sleep"]["seconds"]
        .as_f64()
        .expect("a preStop sleep");
    let shutdown = env_seconds(container, "GLINT_SHUTDOWN_GRACE_MS");
    let longest_render = env_seconds(container, "GLINT_REQUEST_TIMEOUT_MS");
    let termination = pod["terminationGracePeriodSeconds"].as_f64().unwrap();
    assert!(pause > 0.0);
    assert!(
        shutdown > longest_render,
        "{shutdown} s ≤ {longest_render} s"
    );
    assert!(
        termination > pause + shutdown,
        "{termination} s ≤ {pause} s + {shutdown} s"
    );
    for kind in ["requests", "limits"] {
        for resource in ["cpu", "memory"] {
            assert!(
                container["resources"][kind][resource].is_string(),
                "{kind}.{resource}"
            );
        }
    }
    assert_eq!(pod["securityContext"]["runAsNonRoot"], true);
    assert_eq!(container["securityContext"]["readOnlyRootFilesystem"], true);
    assert_eq!(
        container["securityContext"]["allowPrivilegeEscalation"],
        false
    );
    // The Service, the PDB and the autoscaler find the Deployment's pods.
    let labels = &spec["template"]["metadata"]["labels"];
    assert_eq!(&spec["selector"]["matchLabels"], labels);
    assert_eq!(&service["Service/glint"]["spec"]["selector"], labels);
    assert_eq!(
        &service["PodDisruptionBudget/glint"]["spec"]["selector"]["matchLabels"],
        labels
    );
    let hpa = &service["HorizontalPodAutoscaler/glint"];
    assert_eq!(hpa["apiVersion"], "autoscaling/v2");
    assert_eq!(hpa["spec"]["scaleTargetRef"]["name"], "glint");
    assert!(hpa["spec"]["minReplicas"].as_u64().unwrap() >= 2);

    // The Job renders one tile per completion index, of a valid request.
    let tiles = documents(&tools.build(&repo().join("deploy/k8s/tiles")).await);
    let job = &tiles["Job/glint-tiles"]["spec"];
    assert_eq!(job["completionMode"], "Indexed");
    let args: Vec<&str> = job["template"]["spec"]["containers"][0]["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    let after = |flag: &str| args[args.iter().position(|a| *a == flag).unwrap() + 1];
    let grid: glint_client::fanout::Grid = after("--tiles").parse().unwrap();
    assert_eq!(
        job["completions"].as_u64(),
        Some(u64::from(grid.columns * grid.rows)),
        "one completion per tile"
    );
    assert_eq!(after("--tile"), "$(JOB_COMPLETION_INDEX)");
    let request = fs::read(repo().join("deploy/k8s/tiles/request.json")).unwrap();
    let area = glint::offline::render_area(&request).expect("the Job's request is a valid render");
    glint_client::fanout::Plan::new(&request, area, grid).expect("the request is a JSON object");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_broken_copy_of_the_manifests_fails_validation() {
    let test = "a_broken_copy_of_the_manifests_fails_validation";
    let Some(tools) = Tools::get(test).await else {
        return;
    };
    let scratch = Scratch::new("k8s-broken");
    // kustomize builds it without a word: the mistakes are the schema's to see.
    let yaml = tools.build(&repo().join("tests/deploy/k8s-broken")).await;
    let file = scratch.path().join("broken.yaml");
    fs::write(&file, yaml).unwrap();
    for version in VERSIONS {
        let (passed, said) = tools.validate(&file, version, true).await;
        assert!(!passed, "the broken copy passed against {version}:\n{said}");
        assert!(said.contains("'imagePullPolcy' was unexpected"), "{said}");
        assert!(said.contains("spec.minReplicas: 'two'"), "{said}");
    }
    // Without --strict the misspelt field goes through: strict is what
    // catches it.
    let (passed, said) = tools.validate(&file, VERSIONS[1], false).await;
    assert!(!passed, "{said}");
    assert!(!said.contains("imagePullPolcy"), "{said}");
}

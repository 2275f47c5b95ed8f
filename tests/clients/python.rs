//! A Python client generated from the contract by openapi-python-client:
//! `examples/client.py` shades and renders with it against a live glint.

use std::time::Duration;

use super::{PythonTools, Scratch, available, check_example_answer, repo, run};
use crate::load::Glint;

/// The generator's warnings that do not touch the lighting endpoints: it
/// makes no reader for the bodies of `GET /metrics` (OpenMetrics text) and
/// `GET /openapi.yaml` (YAML), and leaves those two answers untyped.
const UNTYPED: [&str; 2] = ["GET /metrics", "GET /openapi.yaml"];

#[tokio::test]
async fn a_generated_python_client_shades_and_renders() {
    let test = "a_generated_python_client_shades_and_renders";
    let Some(python) = available(PythonTools::pinned_by("clients").await, test) else {
        return;
    };
    let work = Scratch::new("python-client");
    let contract = repo().join("api/openapi.yaml");
    // A glTF model's bytes, `model/gltf-binary`, are a file to it.
    let config = repo().join("api/openapi-python-client.yaml");
    let package = work.path().join("glint_client");
    let generated = run(
        python.bin("openapi-python-client"),
        &[
            "generate".as_ref(),
            "--path".as_ref(),
            contract.as_ref(),
            "--config".as_ref(),
            config.as_ref(),
            "--meta".as_ref(),
            "none".as_ref(),
            "--output-path".as_ref(),
            package.as_ref(),
        ],
        |c| {
            c.env("PATH", python.path());
        },
        Duration::from_secs(120),
    )
    .await
    .unwrap_or_else(|e| panic!("the contract does not generate a Python client: {e}"));
    // Every schema became a model, and every warning is about an answer
    // that is not JSON.
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&generated.stdout),
        String::from_utf8_lossy(&generated.stderr)
    );
    assert!(
        !said.contains("Unable to process schema"),
        "the generator dropped a schema:\n{said}"
    );
    for warning in said.lines().filter(|l| l.starts_with("WARNING parsing")) {
        assert!(
            UNTYPED.iter().any(|op| warning.contains(op)),
            "{warning}\n{said}"
        );
    }

    let glint = Glint::spawn(&[]).await;
    let png = work.path().join("sphere.png");
    let example = repo().join("examples/client.py");
    let url = glint.url("");
    let answer = run(
        python.bin("python"),
        &[example.as_ref(), url.as_ref(), png.as_ref()],
        |c| {
            c.env("PYTHONPATH", work.path());
        },
        Duration::from_secs(60),
    )
    .await
    .unwrap_or_else(|e| panic!("examples/client.py: {e}\nglint's log:\n{}", glint.logs()));
    check_example_answer(&answer.stdout, &png);
}

//! schemathesis over every operation of the contract against a live glint:
//! its examples, coverage and fuzzing phases with every check, among them
//! no server error, status code, content type, header and response schema
//! conformance, and the negative-data checks (a request the schema refuses
//! is refused, one it accepts is not, save the declared 413 and 422 of
//! `tests/clients/schemathesis.toml`).

use std::time::Duration;

use super::{PythonTools, Scratch, available, pins, printed, repo, run};
use crate::load::Glint;

/// Test cases per operation and phase: about two thousand requests in all,
/// ten seconds or so.
const EXAMPLES: &str = "100";

#[tokio::test]
async fn schemathesis_finds_nothing_over_every_operation() {
    let test = "schemathesis_finds_nothing_over_every_operation";
    let Some(python) = available(PythonTools::pinned_by("clients").await, test) else {
        return;
    };
    // Small limits keep every render it asks for small (the contract
    // answers 413 past them): 64 × 64 pixels, 20,000 vertices, 1 MiB.
    let glint = Glint::spawn(&[
        "--max-pixels",
        "4096",
        "--max-vertices",
        "20000",
        "--max-body-bytes",
        "1048576",
    ])
    .await;
    let work = Scratch::new("schemathesis");
    let config = pins().join("schemathesis.toml");
    // Bodies of `model/gltf-binary` sent as their bytes (see the file).
    let hooks = pins().join("schemathesis_hooks.py");
    // The document from the repository, which is what the server serves
    // (`contract::http::openapi_yaml_serves_the_document_as_yaml`): read
    // from the server itself, schemathesis would leave out the operation
    // that served it.
    let contract = repo().join("api/openapi.yaml");
    let url = glint.url("");
    let run = run(
        python.bin("st"),
        &[
            "--config-file".as_ref(),
            config.as_ref(),
            "run".as_ref(),
            contract.as_ref(),
            "--url".as_ref(),
            url.as_ref(),
            "--checks".as_ref(),
            "all".as_ref(),
            "--max-examples".as_ref(),
            EXAMPLES.as_ref(),
            "--workers".as_ref(),
            "1".as_ref(),
            "--request-timeout".as_ref(),
            "30".as_ref(),
            "--generation-database".as_ref(),
            "none".as_ref(),
            "--no-color".as_ref(),
        ],
        |c| {
            c.current_dir(work.path()).env("SCHEMATHESIS_HOOKS", &hooks);
        },
        Duration::from_secs(300),
    )
    .await;
    let output =
        run.unwrap_or_else(|e| panic!("schemathesis: {e}\nglint's log:\n{}", glint.logs()));
    let said = String::from_utf8_lossy(&output.stdout);
    // Every operation of the contract was tested, none with a schema it
    // cannot read.
    let operations: usize = crate::contract::support::document()["paths"]
        .as_object()
        .unwrap()
        .values()
        .flat_map(|path| path.as_object().unwrap().keys())
        .filter(|key| ["get", "put", "post", "delete", "patch"].contains(&key.as_str()))
        .count();
    assert!(
        said.contains(&format!("Tested: {operations}")),
        "{operations} operations: {}",
        printed(&output)
    );
    assert!(!said.contains("Schema Error"), "{}", printed(&output));
}

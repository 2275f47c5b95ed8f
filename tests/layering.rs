//! The crate graph is the architecture: the lighting model knows nothing of
//! JSON, HTTP or async, and the ray tracer nothing of JSON or HTTP. Asked of
//! `cargo tree`, so that a dependency added anywhere below either crate
//! shows.

use std::process::Command;

use crate::support::repo;

/// The packages in the normal dependency tree of `package`.
fn dependency_tree(package: &str) -> String {
    let output = Command::new(env!("CARGO"))
        .args([
            "tree",
            "--locked",
            "--offline",
            "-e",
            "normal",
            "--prefix",
            "none",
        ])
        .args(["-p", package])
        .current_dir(repo())
        .output()
        .expect("cargo runs");
    assert!(
        output.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).expect("cargo tree writes UTF-8")
}

/// Whether `tree` lists the crate `name` (any version).
fn lists(tree: &str, name: &str) -> bool {
    tree.lines()
        .any(|line| line.split_whitespace().next() == Some(name))
}

#[test]
fn the_lighting_crate_has_no_serde_http_or_async_below_it() {
    let tree = dependency_tree("glint-lighting");
    assert!(lists(&tree, "glam"), "the tree is read: {tree}");
    for name in [
        "serde",
        "serde_json",
        "axum",
        "hyper",
        "tokio",
        "glint-trace",
    ] {
        assert!(
            !lists(&tree, name),
            "glint-lighting depends on {name}:\n{tree}"
        );
    }
}

#[test]
fn the_trace_crate_has_no_serde_http_or_async_below_it() {
    let tree = dependency_tree("glint-trace");
    assert!(lists(&tree, "glint-lighting"), "the tree is read: {tree}");
    for name in ["serde_json", "axum", "hyper", "tokio"] {
        assert!(
            !lists(&tree, name),
            "glint-trace depends on {name}:\n{tree}"
        );
    }
}

#[test]
fn the_client_is_a_crate_of_its_own_that_the_service_does_not_use() {
    let tree = dependency_tree("glint-client");
    assert!(lists(&tree, "reqwest"), "the tree is read: {tree}");
    for name in ["axum", "glint-model"] {
        assert!(
            !lists(&tree, name),
            "glint-client depends on {name}:\n{tree}"
        );
    }
    // The service is the library; only the command line (main.rs) uses the
    // client crate.
    let src = repo().join("src");
    let mut dirs = vec![src.clone()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).expect("src is readable") {
            let path = entry.expect("an entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") && path != src.join("main.rs") {
                let code = std::fs::read_to_string(&path).expect("a source file");
                for client in ["glint_client", "reqwest", "indicatif"] {
                    assert!(!code.contains(client), "{} uses {client}", path.display());
                }
            }
        }
    }
}

//! TypeScript types generated from the contract by openapi-typescript:
//! `examples/client.ts` type-checks against them (tsc, strict) and, called
//! through openapi-fetch, shades and renders against a live glint.

use std::fs;
use std::time::Duration;

use super::{NodePackages, Scratch, available, check_example_answer, repo, run};
use crate::load::Glint;

/// How the example is compiled: an ES module for Node, every check on.
const TSCONFIG: &str = r#"{
  "compilerOptions": {
    "target": "es2022",
    "module": "esnext",
    "moduleResolution": "bundler",
    "lib": ["es2022", "dom"],
    "types": ["node"],
    "strict": true,
    "noEmitOnError": true,
    "skipLibCheck": true
  },
  "files": ["client.ts"]
}
"#;

#[tokio::test]
async fn generated_typescript_types_shade_and_render() {
    let test = "generated_typescript_types_shade_and_render";
    let Some(node) = available(NodePackages::pinned_by("clients").await, test) else {
        return;
    };
    // Under the tools' directory, so that `openapi-fetch` resolves from
    // their node_modules.
    let work = Scratch::within(node.dir(), "typescript-client");
    let dir = work.path();
    let contract = repo().join("api/openapi.yaml");
    let types = dir.join("glint.d.ts");
    let minute = Duration::from_secs(60);
    run(
        "node",
        &[
            node.script("openapi-typescript", "bin/cli.js").as_ref(),
            contract.as_ref(),
            "--output".as_ref(),
            types.as_ref(),
            // A field with a default is optional in a request; the
            // generator would make it required.
            "--default-non-nullable".as_ref(),
            "false".as_ref(),
        ],
        |_| {},
        minute,
    )
    .await
    .unwrap_or_else(|e| panic!("the contract does not generate TypeScript types: {e}"));

    fs::copy(repo().join("examples/client.ts"), dir.join("client.ts")).unwrap();
    fs::write(dir.join("tsconfig.json"), TSCONFIG).unwrap();
    fs::write(dir.join("package.json"), "{ \"type\": \"module\" }\n").unwrap();
    let tsconfig = dir.join("tsconfig.json");
    run(
        "node",
        &[
            node.script("typescript", "bin/tsc").as_ref(),
            "--project".as_ref(),
            tsconfig.as_ref(),
        ],
        |_| {},
        minute,
    )
    .await
    .unwrap_or_else(|e| panic!("examples/client.ts does not type-check: {e}"));

    let glint = Glint::spawn(&[]).await;
    let png = dir.join("sphere.png");
    let url = glint.url("");
    let answer = run(
        "node",
        &[dir.join("client.js").as_ref(), url.as_ref(), png.as_ref()],
        |_| {},
        minute,
    )
    .await
    .unwrap_or_else(|e| panic!("examples/client.ts: {e}\nglint's log:\n{}", glint.logs()));
    check_example_answer(&answer.stdout, &png);
}

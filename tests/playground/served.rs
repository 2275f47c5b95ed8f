//! The page's files as the server serves them: every file of
//! `src/http/playground/` and every example scene, byte for byte, with its
//! content type and a policy that names no other origin; no file the page
//! refers to is missing; nothing of it is served with `--playground false`.

use std::collections::BTreeSet;

use super::repo;
use crate::http::{TestServer, expect_problem};
use crate::load::Glint;
use crate::support::client;

/// The content type a file is served with, by its extension.
fn content_type(name: &str) -> &'static str {
    match name.rsplit_once('.').map(|(_, ext)| ext) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("json") => "application/json",
        _ => panic!("{name}: a file of a kind the page does not use"),
    }
}

/// Every `…` in `text` that stands between `open` and `close`.
fn between<'a>(text: &'a str, open: &str, close: char) -> Vec<&'a str> {
    text.match_indices(open)
        .filter_map(|(at, _)| {
            let rest = &text[at + open.len()..];
            rest.find(close).map(|end| &rest[..end])
        })
        .collect()
}

/// Checks one answer of the page: status 200, its type, the policy, and its
/// body; returns the body.
async fn fetch(server: &TestServer, path: &str, name: &str) -> String {
    let response = client().get(server.url(path)).send().await.unwrap();
    assert_eq!(response.status(), 200, "{path}");
    let headers = response.headers().clone();
    assert_eq!(headers["content-type"], content_type(name), "{path}");
    assert_eq!(headers["x-content-type-options"], "nosniff", "{path}");
    let policy = headers["content-security-policy"].to_str().unwrap();
    // Every source of every directive is this origin, `none`, or what the
    // page makes itself: nothing may come from elsewhere.
    for directive in policy.split(';') {
        let mut words = directive.split_whitespace();
        let name = words.next().expect("a directive has a name");
        for source in words {
            assert!(
                ["'self'", "'none'", "data:", "blob:"].contains(&source),
                "{path}: `{source}` in {name} of {policy}"
            );
        }
    }
    assert!(policy.contains("default-src 'self'"), "{policy}");
    response.text().await.unwrap()
}

#[tokio::test]
async fn the_page_and_its_files_are_served_as_written() {
    let server = TestServer::start().await;
    let dir = repo().join("src/http/playground");
    let page = fetch(&server, "/", "index.html").await;
    assert_eq!(
        page,
        std::fs::read_to_string(dir.join("index.html")).unwrap()
    );

    // Every file of the page's directory, as it is in the source.
    let mut files = BTreeSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name == "index.html" {
            continue;
        }
        let body = fetch(&server, &format!("/playground/{name}"), &name).await;
        assert_eq!(
            body,
            std::fs::read_to_string(dir.join(&name)).unwrap(),
            "{name}"
        );
        files.insert(name);
    }

    // The example scenes, as examples/ has them.
    let mut examples = BTreeSet::new();
    for name in ["spheres", "mesh", "triangle"] {
        let file = format!("{name}.json");
        let body = fetch(&server, &format!("/playground/{file}"), &file).await;
        assert_eq!(
            body,
            std::fs::read_to_string(repo().join("examples").join(&file)).unwrap()
        );
        examples.insert(name.to_owned());
    }

    // What the page and its modules refer to is among them: the files the
    // page links, the modules they import, the examples they offer.
    let mut linked: BTreeSet<String> = between(&page, "\"/playground/", '"')
        .into_iter()
        .map(str::to_owned)
        .collect();
    for file in files.iter().filter(|f| f.ends_with(".js")) {
        let source = std::fs::read_to_string(dir.join(file)).unwrap();
        linked.extend(
            between(&source, "from './", '\'')
                .into_iter()
                .map(str::to_owned),
        );
        if file == "request.js" {
            let offered: BTreeSet<String> = between(&source, "{ name: '", '\'')
                .into_iter()
                .map(str::to_owned)
                .collect();
            assert_eq!(offered, examples, "the examples the page offers");
        }
    }
    assert!(linked.len() >= 7, "{linked:?}");
    let missing: Vec<_> = linked.difference(&files).collect();
    assert!(
        missing.is_empty(),
        "referred to but not served: {missing:?}"
    );
}

#[tokio::test]
async fn unknown_files_and_other_methods_are_problems() {
    let server = TestServer::start().await;
    for path in ["/playground/nothing.js", "/playground/", "/index.html"] {
        let response = client().get(server.url(path)).send().await.unwrap();
        expect_problem(response, 404, "not-found", None).await;
    }
    let response = client().post(server.url("/")).send().await.unwrap();
    expect_problem(response, 405, "method-not-allowed", None).await;
}

#[tokio::test]
async fn the_page_counts_in_the_metrics_by_its_routes() {
    let glint = Glint::spawn(&[]).await;
    for path in ["/", "/playground/main.js", "/playground/style.css"] {
        let response = client().get(glint.url(path)).send().await.unwrap();
        assert_eq!(response.status(), 200, "{path}");
    }
    let metrics = glint.metrics().await;
    for line in [
        r#"glint_requests_total{route="/",status="200"} 1"#,
        r#"glint_requests_total{route="/playground/{file}",status="200"} 2"#,
    ] {
        assert!(metrics.contains(line), "{line} in\n{metrics}");
    }
}

#[tokio::test]
async fn playground_false_serves_no_page() {
    let glint = Glint::spawn(&["--playground", "false"]).await;
    for path in ["/", "/playground/main.js", "/playground/spheres.json"] {
        let response = client().get(glint.url(path)).send().await.unwrap();
        expect_problem(response, 404, "not-found", None).await;
    }
    // The API is there all the same.
    let response = client().get(glint.url("/healthz")).send().await.unwrap();
    assert_eq!(response.status(), 200);
}

//! The page in headless Chromium against the real binary: `e2e.mjs` loads
//! it, moves its controls, clicks a pixel, sends a bad value, compares two
//! tiers and copies a request as curl, comparing what the page shows with
//! the API's answers. It writes a screenshot to `target/playground/`; an
//! optimised build (`cargo test --release`) also puts it in
//! `docs/playground.png` when the page looks different from the one there
//! (the page shows the server's times, and a build without optimisations
//! would show times, and a trade between tiers, no user sees).

use std::path::Path;
use std::time::Duration;

use super::{Browser, command, loud, repo, target};
use crate::load::Glint;

#[tokio::test]
async fn the_page_in_a_browser() {
    let Some(tools) = Browser::get("playground::browser::the_page_in_a_browser").await else {
        return;
    };
    let glint = Glint::spawn(&[]).await;
    let out = target().join("playground");
    std::fs::create_dir_all(&out).unwrap();
    let shot = out.join("playground.png");
    let _ = std::fs::remove_file(&shot);
    let script = repo().join("tests/playground/e2e.mjs");
    let printed = command(
        "node",
        &[script.to_str().unwrap()],
        Duration::from_secs(240),
        |c| {
            c.env("GLINT_BASE", glint.url(""))
                .env("GLINT_PLAYWRIGHT_DIR", &tools.playwright)
                .env("GLINT_CHROMIUM", &tools.chromium)
                .env("GLINT_EXAMPLES", repo().join("examples"))
                .env("GLINT_SCREENSHOT", &shot);
        },
    )
    .await
    .unwrap_or_else(|e| panic!("{e}\nglint's log:\n{}", glint.logs()));
    eprintln!("{printed}");
    assert!(
        printed.contains("playground: every check passed"),
        "{printed}"
    );

    let new = image::open(&shot)
        .unwrap_or_else(|e| panic!("the test's screenshot {}: {e}", shot.display()))
        .to_rgba8();
    assert_eq!(new.dimensions(), (1280, 800), "the screenshot's size");
    let docs = repo().join("docs/playground.png");
    if !cfg!(debug_assertions) && looks_different(&new, &docs) {
        std::fs::copy(&shot, &docs).unwrap_or_else(|e| panic!("{}: {e}", docs.display()));
        loud(&format!(
            "the page looks different: wrote {}",
            docs.display()
        ));
    }
}

/// Whether `new` looks different from the picture in `old`: another size,
/// or more than 1% of its pixels changed. (The times the page shows change
/// from run to run, a few hundred pixels; a change of its look, far more.)
fn looks_different(new: &image::RgbaImage, old: &Path) -> bool {
    let Ok(old) = image::open(old) else {
        return true;
    };
    let old = old.to_rgba8();
    old.dimensions() != new.dimensions() || {
        let changed = old
            .pixels()
            .zip(new.pixels())
            .filter(|(a, b)| a != b)
            .count();
        changed * 100 > old.pixels().len()
    }
}

//! The playground, `GET /`: the page and its files as the server serves
//! them (their types, a policy that lets nothing load from elsewhere, no file
//! missing, nothing served with `--playground false`), and the page itself
//! in headless Chromium, driven by Playwright (`e2e.mjs`) against the real
//! binary, every number it shows checked against the API's own answer.
//!
//! The browser is Debian's `chromium` package; Playwright's core comes from
//! the npm registry at the version `package-lock.json` pins. Both are
//! installed on first use (Chromium with apt-get, which needs root, as CI
//! has; Playwright with `npm ci` under `target/tools/node-playground`, see
//! `crate::support`), under a file lock, and not again while they are there. Playwright never
//! downloads a browser. A tool that cannot be had fails the test when the
//! environment variable `CI` is `true`; elsewhere the test says loudly what
//! is missing and passes.

mod browser;
mod served;

use std::path::PathBuf;

pub(crate) use crate::support::{
    InstallLock, NodePackages, apt_install, available, debian_program, loud, repo, run, tools,
};

/// `target/`, where the tools are and the test writes what it made.
fn target() -> PathBuf {
    tools()
        .parent()
        .expect("target/tools has a parent")
        .to_path_buf()
}

/// The browser's tools: Chromium's path, and Playwright's core.
struct Browser {
    chromium: PathBuf,
    playwright: NodePackages,
}

impl Browser {
    /// The tools, installed if they are missing; `None` after saying loudly
    /// why the test does not run (in CI, a panic instead).
    async fn get(test: &str) -> Option<Self> {
        available(Self::install().await, test)
    }

    async fn install() -> Result<Self, String> {
        // The page's "Copy as curl" commands are run as a shell would.
        debian_program("curl", "curl").await?;
        let chromium = {
            let _lock = InstallLock::take()?;
            install_chromium().await?
        };
        let playwright = NodePackages::pinned_by("playground").await?;
        Ok(Self {
            chromium,
            playwright,
        })
    }
}

/// Debian's Chromium (or the one `GLINT_CHROMIUM` names), installed with
/// apt-get when it is missing and this is root. The caller holds the
/// [`InstallLock`].
async fn install_chromium() -> Result<PathBuf, String> {
    let chromium = std::env::var_os("GLINT_CHROMIUM")
        .map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    if chromium.exists() {
        return Ok(chromium);
    }
    apt_install("chromium").await?;
    if chromium.exists() {
        Ok(chromium)
    } else {
        Err(format!(
            "apt-get installed chromium, but {} is not there",
            chromium.display()
        ))
    }
}

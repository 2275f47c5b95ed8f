//! The playground, `GET /`: the page and its files as the server serves
//! them (their types, a policy that lets nothing load from elsewhere, no file
//! missing, nothing served with `--playground false`), and the page itself
//! in headless Chromium, driven by Playwright (`e2e.mjs`) against the real
//! binary, every number it shows checked against the API's own answer.
//!
//! The browser is Debian's `chromium` package; Playwright's core comes from
//! the npm registry at the version `package-lock.json` pins. Both are
//! installed on first use (Chromium with apt-get, which needs root, as CI
//! has; Playwright with `npm ci` under `target/tools/playwright`), under a
//! file lock, and not again while they are there. Playwright never
//! downloads a browser. A tool that cannot be had fails the test when the
//! environment variable `CI` is `true`; elsewhere the test says loudly what
//! is missing and passes.

mod browser;
mod served;

use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::Duration;

use tokio::process::Command;

use crate::tools::{InstallLock, apt_install, available, on_path, run, tools};
pub(crate) use crate::tools::{loud, repo};

/// `target/`, where the tools are and the test writes what it made.
fn target() -> PathBuf {
    tools()
        .parent()
        .expect("target/tools has a parent")
        .to_path_buf()
}

/// The browser's tools: Chromium's path, and the directory whose
/// `node_modules` holds Playwright's core.
struct Browser {
    chromium: PathBuf,
    playwright: PathBuf,
}

impl Browser {
    /// The tools, installed if they are missing; `None` after saying loudly
    /// why the test does not run (in CI, a panic instead).
    async fn get(test: &str) -> Option<Self> {
        available(Self::install().await, test)
    }

    async fn install() -> Result<Self, String> {
        let _lock = InstallLock::take()?;
        // The page's "Copy as curl" commands are run as a shell would.
        if on_path("curl").is_none() {
            apt_install("curl").await?;
        }
        let chromium = install_chromium().await?;
        let playwright = install_playwright(&tools().join("playwright")).await?;
        Ok(Self {
            chromium,
            playwright,
        })
    }
}

/// Debian's Chromium (or the one `GLINT_CHROMIUM` names), installed with
/// apt-get when it is missing and this is root.
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

/// Playwright's core, as `package-lock.json` pins it, in `dir`: `npm ci`
/// with no install scripts, so that nothing fetches a browser of its own.
/// A stamp in `dir` records the lock it was installed from.
async fn install_playwright(dir: &Path) -> Result<PathBuf, String> {
    let pins = repo().join("tests/playground");
    let lock = fs::read_to_string(pins.join("package-lock.json")).map_err(|e| e.to_string())?;
    let stamp = dir.join("installed-from");
    if fs::read_to_string(&stamp).is_ok_and(|done| done == lock) {
        return Ok(dir.to_path_buf());
    }
    loud(&format!(
        "installing Playwright's core into {}",
        dir.display()
    ));
    command("node", &["--version"], Duration::from_secs(30), |_| {}).await?;
    let _ = fs::remove_dir_all(dir);
    fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    for file in ["package.json", "package-lock.json"] {
        fs::copy(pins.join(file), dir.join(file)).map_err(|e| format!("{file}: {e}"))?;
    }
    let npm_ci = ["ci", "--ignore-scripts", "--no-audit", "--no-fund"];
    command("npm", &npm_ci, Duration::from_secs(600), |c| {
        c.current_dir(dir)
            .env("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1");
    })
    .await?;
    fs::write(&stamp, lock).map_err(|e| e.to_string())?;
    Ok(dir.to_path_buf())
}

/// Runs `program` with `args` to its end within `limit` and returns what it
/// printed; an error says what failed, with its output.
async fn command(
    program: &str,
    args: &[&str],
    limit: Duration,
    configure: impl FnOnce(&mut Command),
) -> Result<String, String> {
    let args: Vec<&OsStr> = args.iter().map(OsStr::new).collect();
    let output = run(program, &args, configure, limit).await?;
    Ok(String::from_utf8_lossy(&output.stdout).into_owned())
}

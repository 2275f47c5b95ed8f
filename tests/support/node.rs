//! Node packages from the npm registry, as a suite's `package-lock.json`
//! pins them: `node_modules` installed by `npm ci` under
//! `target/tools/node-SUITE` on first use, and not again while the lock is
//! the same. No install scripts run, so nothing fetches a binary of its own
//! (Playwright is told besides not to download a browser).

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::tools::{install_once, repo, run, tools};

/// The packages one suite pins, installed.
pub struct NodePackages {
    dir: PathBuf,
}

impl NodePackages {
    /// The packages of `tests/SUITE/package.json` at the versions of its
    /// `package-lock.json`, installed if they are not there yet.
    pub async fn pinned_by(suite: &str) -> Result<Self, String> {
        let pins = repo().join("tests").join(suite);
        let lock = fs::read_to_string(pins.join("package-lock.json"))
            .map_err(|e| format!("tests/{suite}/package-lock.json: {e}"))?;
        let dir = tools().join(format!("node-{suite}"));
        let what = format!("the Node packages of tests/{suite}");
        install_once(&dir, &lock, &what, || async {
            run(
                "node",
                &["--version".as_ref()],
                |_| {},
                Duration::from_secs(30),
            )
            .await?;
            fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            for file in ["package.json", "package-lock.json"] {
                fs::copy(pins.join(file), dir.join(file)).map_err(|e| format!("{file}: {e}"))?;
            }
            run(
                "npm",
                &[
                    "ci".as_ref(),
                    "--ignore-scripts".as_ref(),
                    "--no-audit".as_ref(),
                    "--no-fund".as_ref(),
                ],
                |c| {
                    c.current_dir(&dir)
                        .env("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1");
                },
                Duration::from_secs(600),
            )
            .await
            .map(|_| ())
        })
        .await?;
        Ok(Self { dir })
    }

    /// The directory whose `node_modules` holds the packages: a script
    /// there, or in a directory below it, resolves them.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A file of an installed package (a script to run with `node`).
    pub fn script(&self, package: &str, path: &str) -> PathBuf {
        self.dir.join("node_modules").join(package).join(path)
    }
}

//! Python packages from PyPI, as a suite's `requirements.txt` pins them:
//! a virtual environment of exactly those pins under
//! `target/tools/python-SUITE`, installed on first use and not again while
//! the pins are the same. Every package a tool needs is pinned in the file,
//! so pip installs without resolving (`--no-deps`): nothing unpinned comes
//! in.

use std::fs;
use std::path::PathBuf;
use std::time::Duration;

use super::tools::{install_once, repo, run, tools};

/// A virtual environment holding the pins of one suite.
pub struct PythonTools {
    venv: PathBuf,
}

impl PythonTools {
    /// The pins of `tests/SUITE/requirements.txt`, installed if they are
    /// not there yet.
    pub async fn pinned_by(suite: &str) -> Result<Self, String> {
        let requirements = repo().join("tests").join(suite).join("requirements.txt");
        let wanted = fs::read_to_string(&requirements)
            .map_err(|e| format!("{}: {e}", requirements.display()))?;
        let env = Self {
            venv: tools().join(format!("python-{suite}")),
        };
        let what = format!("the Python tools of tests/{suite}");
        install_once(&env.venv, &wanted, &what, || async {
            let minutes = Duration::from_secs(600);
            run(
                python()?,
                &["-m".as_ref(), "venv".as_ref(), env.venv.as_ref()],
                |_| {},
                minutes,
            )
            .await?;
            run(
                env.bin("python"),
                &[
                    "-m".as_ref(),
                    "pip".as_ref(),
                    "install".as_ref(),
                    "--disable-pip-version-check".as_ref(),
                    "--no-input".as_ref(),
                    "--no-deps".as_ref(),
                    "--requirement".as_ref(),
                    requirements.as_ref(),
                ],
                |_| {},
                minutes,
            )
            .await
            .map(|_| ())
        })
        .await?;
        Ok(env)
    }

    /// A program of the environment (`python`, or a package's script).
    pub fn bin(&self, name: &str) -> PathBuf {
        self.venv.join("bin").join(name)
    }

    /// `PATH` with the environment's programs first.
    pub fn path(&self) -> std::ffi::OsString {
        let mut dirs = vec![self.venv.join("bin")];
        dirs.extend(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        ));
        std::env::join_paths(dirs).expect("PATH entries without separators")
    }
}

/// The machine's Python, which makes the environments.
fn python() -> Result<&'static str, String> {
    ["python3", "python"]
        .into_iter()
        .find(|p| {
            std::process::Command::new(p)
                .arg("--version")
                .output()
                .is_ok()
        })
        .ok_or_else(|| "no python3 or python on PATH".into())
}

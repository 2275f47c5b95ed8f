//! Scratch directories: one empty directory per test and run, named after
//! the test and the process, and removed when the test ends, panic or not.

use std::fs;
use std::path::{Path, PathBuf};

/// An empty directory for one test of this run, removed when dropped.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Under the system's temporary directory: short, as a Unix socket's
    /// path (HAProxy's stats) must be.
    pub fn new(name: &str) -> Self {
        Self::within(&std::env::temp_dir(), name)
    }

    /// Under `parent`: beside what a tool there resolves (a Node project's
    /// `node_modules`).
    pub fn within(parent: &Path, name: &str) -> Self {
        let dir = parent.join(format!("glint-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        Self(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

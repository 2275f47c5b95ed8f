//! How a test gets and runs an outside program: installed on first use
//! under `target/tools/` (or with apt-get, as root) behind one file lock, so
//! that two tests, or two runs, never install at once, and recorded there by
//! a stamp of the pins it was made from, so that later runs install nothing.
//! A tool that cannot be had fails its test when the environment variable
//! `CI` is `true`; elsewhere the test says loudly what is missing and passes.

use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::Duration;

use tokio::process::Command;

/// The repository.
pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `target/tools/`: beside the build, so that `cargo clean` clears it too.
pub fn tools() -> PathBuf {
    // target/debug/glint (or target/<triple>/debug/glint) → target/...
    Path::new(env!("CARGO_BIN_EXE_glint"))
        .parent()
        .and_then(Path::parent)
        .expect("the binary is in a profile's directory under the target directory")
        .join("tools")
}

/// Whether a missing tool is a failure: in CI it is.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// Says `message` on the process's stderr, where a person running the tests
/// sees it: the test harness keeps what `eprintln!` says to itself when the
/// test passes.
pub fn loud(message: &str) {
    let _ = writeln!(std::io::stderr(), "{message}");
}

/// The tool, or `None` after saying loudly why the test does not run; in CI
/// a missing tool fails the test instead.
pub fn available<T>(tool: Result<T, String>, test: &str) -> Option<T> {
    match tool {
        Ok(tool) => Some(tool),
        Err(why) if in_ci() => panic!("{test} needs a tool CI must have: {why}"),
        Err(why) => {
            loud(&format!(
                "\n!!! SKIPPED {test}: {why}\n!!! (with CI=true this is a failure)\n"
            ));
            None
        }
    }
}

/// Runs `program` to its end within `limit` and returns what it printed;
/// an error says what failed, with its output.
pub async fn run(
    program: impl AsRef<std::ffi::OsStr>,
    args: &[&std::ffi::OsStr],
    configure: impl FnOnce(&mut Command),
    limit: Duration,
) -> Result<Output, String> {
    let shown = shown(program.as_ref(), args);
    let output = run_to_end(program, args, configure, limit).await?;
    if output.status.success() {
        Ok(output)
    } else {
        Err(format!(
            "`{shown}` failed ({}):\n{}",
            output.status,
            printed(&output)
        ))
    }
}

/// Runs `program` to its end within `limit`, whatever its exit status.
pub async fn run_to_end(
    program: impl AsRef<std::ffi::OsStr>,
    args: &[&std::ffi::OsStr],
    configure: impl FnOnce(&mut Command),
    limit: Duration,
) -> Result<Output, String> {
    let program = program.as_ref();
    let shown = shown(program, args);
    let mut command = Command::new(program);
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .kill_on_drop(true);
    configure(&mut command);
    let child = command
        .spawn()
        .map_err(|e| format!("`{shown}` does not start: {e}"))?;
    tokio::time::timeout(limit, child.wait_with_output())
        .await
        .map_err(|_| format!("`{shown}` did not finish within {limit:?}"))?
        .map_err(|e| format!("`{shown}`: {e}"))
}

/// The command line, for messages.
fn shown(program: &std::ffi::OsStr, args: &[&std::ffi::OsStr]) -> String {
    std::iter::once(program)
        .chain(args.iter().copied())
        .map(|a| a.to_string_lossy())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Everything a program printed, for a failure's message.
pub fn printed(output: &Output) -> String {
    format!(
        "--- stdout\n{}\n--- stderr\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// Holds the install lock of `target/tools/` (and of apt-get) while alive.
pub struct InstallLock(File);

impl InstallLock {
    pub fn take() -> Result<Self, String> {
        let dir = tools();
        fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let file = File::create(dir.join("install.lock")).map_err(|e| e.to_string())?;
        file.lock()
            .map_err(|e| format!("locking target/tools: {e}"))?;
        Ok(Self(file))
    }
}

impl Drop for InstallLock {
    fn drop(&mut self) {
        let _ = self.0.unlock();
    }
}

/// Whether the program is on `PATH`.
pub fn on_path(program: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
        .map(|dir| dir.join(program))
        .find(|path| path.is_file())
}

/// `apt-get update` then `apt-get install -y PACKAGE`, as root only. The
/// caller holds the [`InstallLock`].
pub async fn apt_install(package: &str) -> Result<(), String> {
    let root = run("id", &["-u".as_ref()], |_| {}, Duration::from_secs(10))
        .await
        .is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    if !root {
        return Err(format!(
            "{package} is not installed, and only root may install it (apt-get install {package})"
        ));
    }
    loud(&format!("installing {package} with apt-get (once)"));
    let minutes = Duration::from_secs(900);
    let quiet = |c: &mut Command| {
        c.env("DEBIAN_FRONTEND", "noninteractive");
    };
    run("apt-get", &["update".as_ref()], quiet, minutes)
        .await
        .map_err(|e| format!("apt-get update: {e}"))?;
    let install = ["install", "-y", "-o", "DPkg::Lock::Timeout=300", package];
    let install: Vec<&std::ffi::OsStr> = install.iter().map(|a| a.as_ref()).collect();
    run("apt-get", &install, quiet, minutes)
        .await
        .map_err(|e| format!("apt-get install {package}: {e}"))?;
    Ok(())
}

/// `program` on `PATH`, or installed from Debian's `package` (as root) when
/// it is missing.
pub async fn debian_program(program: &str, package: &str) -> Result<PathBuf, String> {
    if let Some(path) = on_path(program) {
        return Ok(path);
    }
    let _lock = InstallLock::take()?;
    if on_path(program).is_none() {
        apt_install(package).await?;
    }
    on_path(program).ok_or_else(|| format!("{program} is not on PATH after installing {package}"))
}

/// Makes `dir` hold an install of `pins` (the text of the pin file it is
/// made from), once: under the [`InstallLock`], `install` fills a fresh
/// `dir` unless the stamp there says it holds those pins already, and the
/// stamp is written when it succeeds. `what` names the install for the
/// person watching.
pub async fn install_once<F, Fut>(
    dir: &Path,
    pins: &str,
    what: &str,
    install: F,
) -> Result<(), String>
where
    F: FnOnce() -> Fut,
    Fut: std::future::Future<Output = Result<(), String>>,
{
    let stamp = dir.join("installed-from");
    let _lock = InstallLock::take()?;
    if fs::read_to_string(&stamp).is_ok_and(|done| done == pins) {
        return Ok(());
    }
    loud(&format!("installing {what} into {}", dir.display()));
    let _ = fs::remove_dir_all(dir);
    install().await?;
    fs::write(&stamp, pins).map_err(|e| format!("{}: {e}", stamp.display()))
}

//! The service's logs, written off the request path.
//!
//! Every line, the one each request writes included, is a `tracing` event
//! formatted by `tracing-subscriber` (readable lines, or one JSON object per
//! line) on the thread that logs it, and handed to `tracing-appender`'s
//! non-blocking writer: a bounded queue of lines that one thread writes to
//! stdout. Writing to stdout blocks whenever its reader is slower than the
//! writer (a terminal, a full pipe, a log collector that has stalled), so no
//! request writes there itself. When the queue is full, a new line is
//! dropped rather than waited for, and counted ([`dropped_lines`], which
//! `/metrics` shows as `glint_log_lines_dropped_total`): a slow reader
//! costs lines, never time. [`LogGuard`] writes what is queued when the
//! server stops.
//!
//! The writer thread takes lines in the order they were queued and gathers
//! them into one write to stdout while more are waiting, so a busy server
//! makes few system calls for its logs.

use std::io::{BufWriter, IsTerminal};
use std::sync::OnceLock;

use clap::ValueEnum;
use tracing_appender::non_blocking::{ErrorCounter, NonBlockingBuilder, WorkerGuard};

/// How log lines are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum LogFormat {
    /// Readable lines for a terminal.
    #[default]
    Human,
    /// One JSON object per line, for log collectors.
    Json,
}

/// How the logs are written.
#[derive(Clone, Copy, Debug)]
pub struct LogConfig {
    pub format: LogFormat,
    /// The most lines waiting for the writer while stdout's reader is slow;
    /// lines past them are dropped and counted.
    pub buffer_lines: usize,
}

/// The bytes the writer gathers before a write to stdout: many lines in one
/// system call, while lines wait.
const GATHER_BYTES: usize = 64 * 1024;

/// The lines dropped so far, once [`init`] has installed the writer.
static DROPPED: OnceLock<ErrorCounter> = OnceLock::new();

/// Installs the global `tracing` subscriber (`RUST_LOG`, default `info`),
/// writing through the non-blocking writer. Keep the guard until the end
/// of `main`: dropping it writes what is left.
pub fn init(config: LogConfig) -> LogGuard {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let ansi = config.format == LogFormat::Human && std::io::stdout().is_terminal();
    let (writer, guard) = NonBlockingBuilder::default()
        .lossy(true)
        .buffered_lines_limit(config.buffer_lines)
        .thread_name("glint-log")
        .finish(BufWriter::with_capacity(GATHER_BYTES, std::io::stdout()));
    let _ = DROPPED.set(writer.error_counter());
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(ansi)
        .with_writer(writer);
    match config.format {
        LogFormat::Human => builder.init(),
        LogFormat::Json => builder.json().init(),
    }
    LogGuard { _writer: guard }
}

/// Log lines dropped so far because the sink could not keep up (0 before
/// [`init`]).
pub fn dropped_lines() -> u64 {
    DROPPED
        .get()
        .map_or(0, |counter| counter.dropped_lines() as u64)
}

/// Writes what is queued when dropped (`tracing-appender` waits a bounded
/// time for a sink that does not take it, whose lines are then lost).
pub struct LogGuard {
    _writer: WorkerGuard,
}

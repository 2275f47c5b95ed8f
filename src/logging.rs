//! The service's logs, written off the request path.
//!
//! Every line is written through `tracing-appender`'s non-blocking writer: a
//! bounded queue of lines that one thread writes to stdout. Writing to
//! stdout blocks whenever its reader is slower than the writer (a terminal,
//! a full pipe, a log collector that has stalled), so no request writes
//! there itself. When the queue is full, a new line is dropped rather than
//! waited for, and counted ([`dropped_lines`], which `/metrics` shows as
//! `glint_log_lines_dropped_total`): a slow reader costs lines, never time.
//! [`LogGuard`] writes what is queued when the server stops. The writer
//! thread writes what has gathered in one call, then rests for [`GATHER`]
//! while the next lines gather: a busy server makes about a hundred writes a
//! second for its logs whatever its rate of requests, and a request that
//! queues a line seldom has to wake the writer.
//!
//! Every line but one is a `tracing` event formatted by `tracing-subscriber`
//! (readable lines, or one JSON object per line; without colours, whose
//! styling cost a sixth of the formatting even when switched off). The one
//! is the line each request writes ([`access`]), which is formatted here,
//! field for field as `tracing-subscriber` writes that event (a test below
//! holds the two equal), and filtered by `RUST_LOG` as that event is:
//! `tracing-subscriber`'s formatting of it cost 12% of the requests/s of the
//! 3-vertex shade at 64 connections, and this formatting about 1%
//! (`docs/performance.md`, "The access line", measured in turns by
//! `benches/load.sh`, which runs a server with `GLINT_ACCESS_LINE=tracing`,
//! the switch that has `tracing-subscriber` format this line too). Its
//! timestamp, integers and floats are written by `humantime`, `itoa` and
//! `zmij` (the float formatter serde_json uses).

use std::cell::RefCell;
use std::io::{BufWriter, Write};
use std::sync::OnceLock;
use std::time::{Duration, SystemTime};

use clap::ValueEnum;
use tracing_appender::non_blocking::{ErrorCounter, NonBlocking, NonBlockingBuilder, WorkerGuard};

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

/// The target of the per-request line, as `RUST_LOG` names it (the module
/// of the layer that writes it, where it has always been).
pub const ACCESS_TARGET: &str = "glint::http::metrics";

/// The bytes the writer gathers before a write to stdout: many lines in one
/// system call, while lines wait.
const GATHER_BYTES: usize = 64 * 1024;

/// How long the writer rests after each write, while lines gather: a bound
/// on the writes per second, and on how late a line reaches stdout.
const GATHER: Duration = Duration::from_millis(10);

/// The process's log, once [`init`] has installed it.
static LOG: OnceLock<Log> = OnceLock::new();

struct Log {
    writer: NonBlocking,
    dropped: ErrorCounter,
    /// The format of the access line written here; `None` when
    /// `tracing-subscriber` writes it (`GLINT_ACCESS_LINE=tracing`).
    by_hand: Option<LogFormat>,
}

/// Installs the global `tracing` subscriber (`RUST_LOG`, default `info`),
/// writing through the non-blocking writer. Keep the guard until the end
/// of `main`: dropping it writes what is left.
pub fn init(config: LogConfig) -> LogGuard {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let (writer, guard) = NonBlockingBuilder::default()
        .lossy(true)
        .buffered_lines_limit(config.buffer_lines)
        .thread_name("glint-log")
        .finish(Gathered(BufWriter::with_capacity(
            GATHER_BYTES,
            std::io::stdout(),
        )));
    let by_tracing = std::env::var("GLINT_ACCESS_LINE").is_ok_and(|by| by == "tracing");
    let _ = LOG.set(Log {
        writer: writer.clone(),
        dropped: writer.error_counter(),
        by_hand: (!by_tracing).then_some(config.format),
    });
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
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
    LOG.get()
        .map_or(0, |log| log.dropped.dropped_lines() as u64)
}

/// Writes what is queued when dropped (`tracing-appender` waits a bounded
/// time for a sink that does not take it, whose lines are then lost).
pub struct LogGuard {
    _writer: WorkerGuard,
}

/// The writer of the writer thread: `tracing-appender` flushes it once it
/// has taken every queued line, and a flush writes them out and then rests
/// for [`GATHER`].
struct Gathered<W: Write>(BufWriter<W>);

impl<W: Write> Write for Gathered<W> {
    fn write(&mut self, line: &[u8]) -> std::io::Result<usize> {
        self.0.write(line)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let written = self.0.flush();
        std::thread::sleep(GATHER);
        written
    }
}

/// The per-request line: id, method, route, status, latency and size.
#[derive(Clone, Copy, Debug)]
pub struct Access<'a> {
    pub request_id: &'a str,
    pub method: &'a str,
    pub route: &'a str,
    pub status: u16,
    pub latency_ms: f64,
    /// The body's size in bytes, when known in advance (-1 when not).
    pub size: i64,
}

thread_local! {
    /// Each thread's line being written, whose memory serves the next, and
    /// its handle on the writer (a clone counts itself in the queue's
    /// shared state, so each thread clones once).
    static LINE: RefCell<(Vec<u8>, Option<NonBlocking>)> = const { RefCell::new((Vec::new(), None)) };
}

/// Logs a request at `info` under [`ACCESS_TARGET`], as
/// `tracing::info!(request_id, %method, %route, status, latency_ms, size,
/// "request")` would, at a fraction of its cost.
pub fn access(line: &Access<'_>) {
    if !tracing::enabled!(target: ACCESS_TARGET, tracing::Level::INFO) {
        return;
    }
    let Some((log, format)) = LOG.get().and_then(|log| Some((log, log.by_hand?))) else {
        return by_tracing(line);
    };
    LINE.with_borrow_mut(|(out, writer)| {
        out.clear();
        write_access(out, format, SystemTime::now(), line);
        // One line, one write: the writer queues it whole, or drops it.
        let writer = writer.get_or_insert_with(|| log.writer.clone());
        let _ = writer.write_all(out);
    });
}

/// The access line as a `tracing` event, for `tracing-subscriber` to format.
fn by_tracing(line: &Access<'_>) {
    tracing::info!(
        target: ACCESS_TARGET,
        request_id = line.request_id,
        method = %line.method,
        route = %line.route,
        status = line.status,
        latency_ms = line.latency_ms,
        size = line.size,
        "request"
    )
}

/// The access line in `format`, as `tracing-subscriber` writes it without
/// colours, newline included.
fn write_access(out: &mut Vec<u8>, format: LogFormat, at: SystemTime, line: &Access<'_>) {
    let mut integers = itoa::Buffer::new();
    match format {
        LogFormat::Human => {
            // `{time}  INFO {target}: request request_id={id:?} method={method} …`
            write_timestamp(out, at);
            out.extend_from_slice(b"  INFO ");
            out.extend_from_slice(ACCESS_TARGET.as_bytes());
            out.extend_from_slice(b": request request_id=\"");
            for &b in line.request_id.as_bytes() {
                // `str`'s Debug, for the characters a header value may hold.
                match b {
                    b'"' => out.extend_from_slice(b"\\\""),
                    b'\\' => out.extend_from_slice(b"\\\\"),
                    b'\t' => out.extend_from_slice(b"\\t"),
                    _ => out.push(b),
                }
            }
            out.extend_from_slice(b"\" method=");
            out.extend_from_slice(line.method.as_bytes());
            out.extend_from_slice(b" route=");
            out.extend_from_slice(line.route.as_bytes());
            out.extend_from_slice(b" status=");
            out.extend_from_slice(integers.format(line.status).as_bytes());
            out.extend_from_slice(b" latency_ms=");
            write_debug_f64(out, line.latency_ms);
            out.extend_from_slice(b" size=");
            out.extend_from_slice(integers.format(line.size).as_bytes());
        }
        LogFormat::Json => {
            out.extend_from_slice(b"{\"timestamp\":\"");
            write_timestamp(out, at);
            out.extend_from_slice(
                b"\",\"level\":\"INFO\",\"fields\":{\"message\":\"request\",\"request_id\":",
            );
            json(out, line.request_id);
            out.extend_from_slice(b",\"method\":");
            json(out, line.method);
            out.extend_from_slice(b",\"route\":");
            json(out, line.route);
            out.extend_from_slice(b",\"status\":");
            out.extend_from_slice(integers.format(line.status).as_bytes());
            out.extend_from_slice(b",\"latency_ms\":");
            json(out, &line.latency_ms);
            out.extend_from_slice(b",\"size\":");
            out.extend_from_slice(integers.format(line.size).as_bytes());
            out.extend_from_slice(b"},\"target\":");
            json(out, ACCESS_TARGET);
            out.push(b'}');
        }
    }
    out.push(b'\n');
}

/// A string or a number as serde_json writes it, as tracing-subscriber's
/// JSON format does.
fn json<T: serde::Serialize + ?Sized>(out: &mut Vec<u8>, value: &T) {
    serde_json::to_writer(out, value).expect("strings and numbers serialise");
}

/// `x` as `{:?}` writes it, as tracing-subscriber records an `f64`. Between
/// 1e-4 and 1e9 (every latency in milliseconds) `{:?}` writes plain
/// decimals whose digits are the shortest that read back as `x`, as `zmij`
/// writes them at a fraction of the cost; elsewhere, where the two may
/// differ, it is `{:?}` itself.
fn write_debug_f64(out: &mut Vec<u8>, x: f64) {
    if x == 0.0 || (x.is_finite() && (1e-4..1e9).contains(&x.abs())) {
        out.extend_from_slice(zmij::Buffer::new().format_finite(x).as_bytes());
    } else {
        let _ = write!(out, "{x:?}");
    }
}

/// `at` in RFC 3339 with microseconds, UTC, as tracing-subscriber's
/// default timer writes it: `2026-11-23T15:10:40.722674Z`.
fn write_timestamp(out: &mut Vec<u8>, at: SystemTime) {
    let _ = write!(out, "{}", humantime::format_rfc3339_micros(at));
}

#[cfg(test)]
mod tests {
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, SystemTime};

    use tracing_subscriber::fmt::MakeWriter;
    use tracing_subscriber::fmt::format::Writer;
    use tracing_subscriber::fmt::time::FormatTime;

    use super::*;

    /// What tracing-subscriber writes, gathered for a comparison.
    #[derive(Clone, Default)]
    struct Captured(Arc<Mutex<Vec<u8>>>);

    impl Write for Captured {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(bytes);
            Ok(bytes.len())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl<'a> MakeWriter<'a> for Captured {
        type Writer = Captured;

        fn make_writer(&'a self) -> Self::Writer {
            self.clone()
        }
    }

    /// A timer that writes the time as [`write_timestamp`] does, so that
    /// lines compare whole; the timestamp itself is compared with
    /// tracing-subscriber's own timer on its own (below).
    struct At(SystemTime);

    impl FormatTime for At {
        fn format_time(&self, w: &mut Writer<'_>) -> std::fmt::Result {
            let mut text = Vec::new();
            write_timestamp(&mut text, self.0);
            w.write_str(std::str::from_utf8(&text).unwrap())
        }
    }

    /// The line tracing-subscriber writes for `line`, in `format`, with
    /// `timer`.
    fn formatted_by_tracing(
        format: LogFormat,
        timer: impl FormatTime + Send + Sync + 'static,
        line: &Access<'_>,
    ) -> String {
        let captured = Captured::default();
        let builder = tracing_subscriber::fmt()
            .with_timer(timer)
            .with_writer(captured.clone());
        let emit = || by_tracing(line);
        match format {
            LogFormat::Human => tracing::subscriber::with_default(builder.finish(), emit),
            LogFormat::Json => tracing::subscriber::with_default(builder.json().finish(), emit),
        }
        String::from_utf8(captured.0.lock().unwrap().clone()).unwrap()
    }

    fn by_hand(format: LogFormat, at: SystemTime, line: &Access<'_>) -> String {
        let mut out = Vec::new();
        write_access(&mut out, format, at, line);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn the_access_line_reads_as_tracing_subscriber_writes_it() {
        let lines = [
            Access {
                request_id: "64fe70ab-1-2",
                method: "POST",
                route: "/v1/shade",
                status: 200,
                latency_ms: 0.094793,
                size: 385,
            },
            Access {
                request_id: "a \"quoted\"\\ id\twith a tab",
                method: "OPTIONS",
                route: "unmatched",
                status: 404,
                latency_ms: 12345.678901234,
                size: -1,
            },
            Access {
                request_id: "",
                method: "GET",
                route: "/metrics",
                status: 503,
                latency_ms: 1e-3,
                size: 0,
            },
        ];
        let times = [
            SystemTime::UNIX_EPOCH + Duration::new(1_795_442_840, 722_674_123),
            SystemTime::UNIX_EPOCH + Duration::new(951_782_400, 5_000),
            SystemTime::UNIX_EPOCH,
        ];
        for format in [LogFormat::Human, LogFormat::Json] {
            for (line, at) in lines.iter().zip(times) {
                assert_eq!(
                    by_hand(format, at, line),
                    formatted_by_tracing(format, At(at), line),
                    "{format:?}"
                );
            }
        }
    }

    #[test]
    fn timestamps_are_written_as_tracing_subscribers_own_timer_writes_them() {
        // Its timer reads the clock itself: the time of each line is read
        // back from it (by humantime's parser) and written again here.
        let line = Access {
            request_id: "",
            method: "GET",
            route: "/",
            status: 200,
            latency_ms: 1.0,
            size: 0,
        };
        for _ in 0..200 {
            let theirs = formatted_by_tracing(
                LogFormat::Human,
                tracing_subscriber::fmt::time::SystemTime,
                &line,
            );
            let stamp = theirs.split_whitespace().next().unwrap();
            let at = humantime::parse_rfc3339(stamp).unwrap();
            let mut ours = Vec::new();
            write_timestamp(&mut ours, at);
            assert_eq!(String::from_utf8(ours).unwrap(), stamp);
        }
    }

    #[test]
    fn latencies_read_as_debug_writes_them() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let special = [
            0.0,
            -0.0,
            1e-4,
            9.99e-5,
            1e16,
            9.999e15,
            1.0,
            0.1,
            1e-30,
            f64::NAN,
        ];
        let random = (0..100_000).map(|_| {
            // Every magnitude from 1e-8 to 1e18, with random digits.
            let exponent = (next() % 27) as i32 - 8;
            (next() >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi(exponent)
        });
        for x in special.into_iter().chain(random) {
            let mut written = Vec::new();
            write_debug_f64(&mut written, x);
            assert_eq!(String::from_utf8(written).unwrap(), format!("{x:?}"));
        }
    }
}

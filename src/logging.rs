//! The service's logs, written off the request path.
//!
//! Writing a line to stdout is a system call, and it blocks whenever the
//! reader is slower than the writer: a terminal, a full pipe, a log
//! collector that has stalled. So no request writes to stdout. Every line,
//! human or JSON as `tracing-subscriber` formats it, goes into a buffer in
//! memory of bounded size ([`LogConfig::buffer_bytes`]), and one thread,
//! `glint-log`, writes what has gathered there to stdout in one write every
//! 10 ms ([`GATHER`]). The per-request line gathers first in a stage of the
//! thread that answered the request, which the writer empties: the threads
//! answering requests then do not pass one buffer and its lock between
//! them at every request. So within one write, the lines of different
//! threads come stage by stage rather than in the order of their
//! timestamps; each thread's own lines keep their order. When the sink
//! cannot keep up and the buffer is full, a new line is dropped rather
//! than waited for, and counted:
//! [`dropped_lines`], which `/metrics` shows as
//! `glint_log_lines_dropped_total`. A slow sink costs lines, never time.
//! [`LogGuard`] writes what is left when the server stops, within a bounded
//! time.
//!
//! The line every request writes (see [`access`]) is formatted here rather
//! than through `tracing`'s machinery, which cost two to three times as
//! much: it reads the same, field for field, as `tracing-subscriber` would
//! write it (a test below holds the two equal), is filtered by `RUST_LOG` as
//! that event would be, and on a terminal, whose colours only
//! `tracing-subscriber` knows, it goes through `tracing` after all.

use std::cell::RefCell;
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock, PoisonError};
use std::time::{Duration, Instant, SystemTime};

use tracing_subscriber::fmt::MakeWriter;

use crate::config::LogFormat;

/// How the logs are written.
#[derive(Clone, Copy, Debug)]
pub struct LogConfig {
    pub format: LogFormat,
    /// The most bytes of log lines held in memory while the sink is busy,
    /// besides a stage of [`STAGE_SHARE`] of it in each thread that logs
    /// requests; lines that do not fit are dropped and counted.
    pub buffer_bytes: usize,
}

/// The target of the per-request line, as `RUST_LOG` names it (the module
/// of the middleware that writes it, where it has always been).
pub const ACCESS_TARGET: &str = "glint::http::metrics";

/// How long the writer gathers lines before it writes them: a bound on the
/// number of writes per second, and on how late a line reaches the sink.
const GATHER: Duration = Duration::from_millis(10);

/// The share of the buffer's capacity each thread's stage of per-request
/// lines holds at most (1/16, so that a few threads' stages never hold more
/// than the buffer); a stage that would hold more is moved into the buffer.
pub const STAGE_SHARE: usize = 16;

/// How long [`LogGuard`] waits, at exit, for what is buffered to be written.
const FLUSH_AT_EXIT: Duration = Duration::from_secs(2);

/// The process's log buffer, once [`init`] has installed it.
static LOG: OnceLock<Log> = OnceLock::new();

struct Log {
    buffer: Arc<Buffer>,
    /// Whether [`access`] formats the line itself (every format but
    /// coloured human lines).
    by_hand: Option<LogFormat>,
}

/// Installs the global `tracing` subscriber (`RUST_LOG`, default `info`),
/// writing through a bounded buffer and the `glint-log` thread. Keep the
/// guard until the end of `main`: dropping it writes what is left.
pub fn init(config: LogConfig) -> LogGuard {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let buffer = Arc::new(Buffer::new(config.buffer_bytes));
    let ansi = config.format == LogFormat::Human && std::io::stdout().is_terminal();
    let writer = thread_for(buffer.clone(), std::io::stdout());
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(ansi)
        .with_writer(BufferWriter(buffer.clone()));
    match config.format {
        LogFormat::Human => builder.init(),
        LogFormat::Json => builder.json().init(),
    }
    let by_hand = (!ansi).then_some(config.format);
    let _ = LOG.set(Log {
        buffer: buffer.clone(),
        by_hand,
    });
    LogGuard {
        buffer,
        writer: Some(writer),
    }
}

/// Log lines dropped so far because the sink could not keep up (0 before
/// [`init`]).
pub fn dropped_lines() -> u64 {
    LOG.get()
        .map_or(0, |log| log.buffer.dropped.load(Ordering::Relaxed))
}

/// Writes what is buffered when dropped, waiting at most a couple of
/// seconds for a sink that does not take it (whose lines are then lost).
pub struct LogGuard {
    buffer: Arc<Buffer>,
    writer: Option<std::thread::JoinHandle<()>>,
}

impl Drop for LogGuard {
    fn drop(&mut self) {
        let mut state = self.buffer.lock();
        state.closing = true;
        self.buffer.wake.notify_all();
        let (state, _) = self
            .buffer
            .wake
            .wait_timeout_while(state, FLUSH_AT_EXIT, |s| !s.finished)
            .unwrap_or_else(PoisonError::into_inner);
        let finished = state.finished;
        drop(state);
        if finished && let Some(writer) = self.writer.take() {
            let _ = writer.join();
        }
    }
}

/// The bytes of log lines not yet written, bounded in size.
struct Buffer {
    state: Mutex<State>,
    /// Wakes the writer (a line after a quiet time, or closing), and the
    /// guard (the writer has finished).
    wake: Condvar,
    capacity: usize,
    dropped: AtomicU64,
    /// The writer waits for a line: the next one wakes it. Set and cleared
    /// by the writer with the state locked; read by every line.
    writer_idle: AtomicBool,
    /// Tells this buffer's stages from another's on a thread.
    id: u64,
    /// Every thread's stage, which the writer empties.
    stages: Mutex<Vec<Arc<Stage>>>,
}

/// A thread's per-request lines not yet in the buffer. Its lock is taken by
/// its own thread, and by the writer once per [`GATHER`]; the writer
/// takes it with the buffer's state locked, and a thread never holds both.
type Stage = Mutex<Vec<u8>>;

#[derive(Default)]
struct State {
    lines: Vec<u8>,
    closing: bool,
    finished: bool,
}

thread_local! {
    /// This thread's stage, and the buffer it belongs to.
    static STAGE: RefCell<Option<(u64, Arc<Stage>)>> = const { RefCell::new(None) };
}

impl Buffer {
    fn new(capacity: usize) -> Self {
        static BUFFERS: AtomicU64 = AtomicU64::new(0);
        Self {
            state: Mutex::new(State::default()),
            wake: Condvar::new(),
            capacity,
            dropped: AtomicU64::new(0),
            writer_idle: AtomicBool::new(false),
            id: BUFFERS.fetch_add(1, Ordering::Relaxed),
            stages: Mutex::new(Vec::new()),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        lock(&self.state)
    }

    /// Adds one or more whole lines, or drops them all if they do not fit.
    /// Never waits for the sink.
    fn push(&self, lines: &[u8]) {
        let mut state = self.lock();
        if state.lines.len() + lines.len() > self.capacity {
            drop(state);
            self.dropped
                .fetch_add(count_lines(lines).max(1), Ordering::Relaxed);
            return;
        }
        state.lines.extend_from_slice(lines);
        // With the state locked, an idle writer is one that waits.
        if self.writer_idle.load(Ordering::SeqCst) {
            self.wake.notify_all();
        }
    }

    /// Writes a line with `write` into this thread's stage. Never waits for
    /// the sink: a stage past its share moves into the buffer, or is
    /// dropped with the lines that do not fit there.
    fn stage(&self, write: impl FnOnce(&mut Vec<u8>)) {
        let full = STAGE.with_borrow_mut(|stage| {
            let (_, lines) = match stage {
                Some((id, _)) if *id == self.id => stage.as_ref().expect("matched"),
                _ => {
                    let lines = Arc::new(Stage::default());
                    lock(&self.stages).push(lines.clone());
                    stage.insert((self.id, lines))
                }
            };
            let mut lines = lock(lines);
            write(&mut lines);
            (lines.len() > self.capacity / STAGE_SHARE).then(|| std::mem::take(&mut *lines))
        });
        if let Some(lines) = full {
            self.push(&lines);
        } else if self.writer_idle.load(Ordering::SeqCst) {
            // The writer may have looked at this stage before the line came:
            // it waits, holding the state until then.
            let _state = self.lock();
            self.wake.notify_all();
        }
    }

    /// Moves the lines of every stage to the end of `batch`, and forgets
    /// the stages of threads that have ended.
    fn take_stages(&self, batch: &mut Vec<u8>) {
        lock(&self.stages).retain(|stage| {
            let mut lines = lock(stage);
            batch.extend_from_slice(&lines);
            lines.clear();
            Arc::strong_count(stage) > 1
        });
    }
}

/// `mutex` locked; a panic while it was held leaves whole lines or none.
fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

fn count_lines(bytes: &[u8]) -> u64 {
    bytes.iter().filter(|&&b| b == b'\n').count() as u64
}

/// Starts the thread that moves lines from `buffer` to `sink`: it takes
/// everything gathered, writes it in one call, then gathers again for a
/// moment, so that a busy server makes about a hundred writes a second
/// whatever its rate of requests, and a quiet one none.
fn thread_for(
    buffer: Arc<Buffer>,
    sink: impl Write + Send + 'static,
) -> std::thread::JoinHandle<()> {
    std::thread::Builder::new()
        .name("glint-log".into())
        .spawn(move || write_out(&buffer, sink))
        .expect("the log thread starts")
}

fn write_out(buffer: &Buffer, mut sink: impl Write) {
    let mut batch = Vec::new();
    loop {
        let mut state = buffer.lock();
        loop {
            batch.extend_from_slice(&state.lines);
            state.lines.clear();
            buffer.take_stages(&mut batch);
            if !batch.is_empty() || state.closing {
                break;
            }
            // Idle from here on: a line staged after the look below finds
            // the flag set, and wakes the writer (see `Buffer::stage`).
            buffer.writer_idle.store(true, Ordering::SeqCst);
            buffer.take_stages(&mut batch);
            if batch.is_empty() {
                state = buffer
                    .wake
                    .wait(state)
                    .unwrap_or_else(PoisonError::into_inner);
            }
            buffer.writer_idle.store(false, Ordering::SeqCst);
        }
        if batch.is_empty() {
            state.finished = true;
            buffer.wake.notify_all();
            return;
        }
        let closing = state.closing;
        drop(state);
        if sink.write_all(&batch).and_then(|()| sink.flush()).is_err() {
            // A closed or broken sink: these lines are lost too.
            buffer
                .dropped
                .fetch_add(count_lines(&batch), Ordering::Relaxed);
        }
        batch.clear();
        if !closing {
            std::thread::sleep(GATHER);
        }
    }
}

/// `tracing-subscriber`'s writer: each event's line, formatted on the
/// thread that logs it, goes into the buffer whole.
struct BufferWriter(Arc<Buffer>);

impl<'a> MakeWriter<'a> for BufferWriter {
    type Writer = LineSink<'a>;

    fn make_writer(&'a self) -> Self::Writer {
        LineSink(&self.0)
    }
}

/// Takes what `tracing-subscriber` writes of one event: the whole line, in
/// one call.
struct LineSink<'a>(&'a Buffer);

impl Write for LineSink<'_> {
    fn write(&mut self, line: &[u8]) -> std::io::Result<usize> {
        self.0.push(line);
        Ok(line.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The per-request line: id, method, route, status, latency and size.
#[derive(Clone, Copy, Debug)]
pub struct Access<'a> {
    /// When the request was answered: the line's timestamp.
    pub at: Instant,
    pub request_id: &'a str,
    pub method: &'a str,
    pub route: &'a str,
    pub status: u16,
    pub latency_ms: f64,
    /// The body's size in bytes, when known in advance (-1 when not).
    pub size: i64,
}

/// Logs a request at `info` under [`ACCESS_TARGET`], as
/// `tracing::info!(request_id, %method, %route, status, latency_ms, size,
/// "request")` would, at a fraction of its cost.
pub fn access(line: &Access<'_>) {
    if !tracing::enabled!(target: ACCESS_TARGET, tracing::Level::INFO) {
        return;
    }
    match LOG.get() {
        Some(Log {
            buffer,
            by_hand: Some(format),
        }) => {
            let at = wall_clock(line.at);
            buffer.stage(|lines| write_access(lines, *format, at, line));
        }
        _ => by_tracing(line),
    }
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

/// How long a thread converts instants to wall-clock times by one reading
/// of both clocks: the wall clock's slewing moves it against the monotonic
/// one by at most a few microseconds in that time.
const WALL_CLOCK_READING: Duration = Duration::from_millis(10);

thread_local! {
    /// This thread's last reading of both clocks.
    static CLOCKS: std::cell::Cell<Option<(Instant, SystemTime)>> = const { std::cell::Cell::new(None) };
}

/// The wall-clock time of `at`, from this thread's last reading of both
/// clocks when it is recent: a line's timestamp without reading the wall
/// clock for every line.
fn wall_clock(at: Instant) -> SystemTime {
    let (instant, time) = match CLOCKS.get() {
        Some((instant, time))
            if at >= instant && at.duration_since(instant) < WALL_CLOCK_READING =>
        {
            (instant, time)
        }
        _ => {
            let reading = (Instant::now(), SystemTime::now());
            CLOCKS.set(Some(reading));
            reading
        }
    };
    match at.checked_duration_since(instant) {
        Some(after) => time + after,
        None => time - instant.duration_since(at),
    }
}

/// The access line in `format`, as `tracing-subscriber` writes it without
/// colours, newline included.
fn write_access(out: &mut Vec<u8>, format: LogFormat, at: SystemTime, line: &Access<'_>) {
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
            write_decimal(out, u64::from(line.status));
            out.extend_from_slice(b" latency_ms=");
            write_debug_f64(out, line.latency_ms);
            out.extend_from_slice(b" size=");
            if line.size < 0 {
                out.push(b'-');
            }
            write_decimal(out, line.size.unsigned_abs());
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
            write_decimal(out, u64::from(line.status));
            out.extend_from_slice(b",\"latency_ms\":");
            json(out, &line.latency_ms);
            out.extend_from_slice(b",\"size\":");
            json(out, &line.size);
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

fn write_decimal(out: &mut Vec<u8>, n: u64) {
    write_padded(out, n, 1);
}

/// `n` in decimal, with zeros before it to at least `width` digits.
fn write_padded(out: &mut Vec<u8>, n: u64, width: usize) {
    let mut digits = [0u8; 20];
    let digits = crate::response::decimal(n, &mut digits);
    out.extend(std::iter::repeat_n(
        b'0',
        width.saturating_sub(digits.len()),
    ));
    out.extend_from_slice(digits);
}

/// `x` as `{:?}` writes it. Between 1e-4 and 1e9 (every latency in
/// milliseconds) `{:?}` writes plain decimals whose digits are the shortest
/// that read back as `x`, as `zmij` writes them at a fraction of the cost;
/// elsewhere, where the two may differ, it is `{:?}` itself.
fn write_debug_f64(out: &mut Vec<u8>, x: f64) {
    if x == 0.0 || (x.is_finite() && (1e-4..1e9).contains(&x.abs())) {
        out.extend_from_slice(zmij::Buffer::new().format_finite(x).as_bytes());
    } else {
        let _ = write!(out, "{x:?}");
    }
}

thread_local! {
    /// Each thread's last timestamp to the second, `2026-11-23T15:10:40`, and
    /// the second it is: requests in the same second share it.
    static SECOND: RefCell<(u64, Vec<u8>)> = const { RefCell::new((u64::MAX, Vec::new())) };
}

/// `at` in RFC 3339 with microseconds, UTC, as tracing-subscriber's
/// default timer writes it: `2026-11-23T15:10:40.722674Z`.
fn write_timestamp(out: &mut Vec<u8>, at: SystemTime) {
    let since = at
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap_or_default();
    let secs = since.as_secs();
    SECOND.with_borrow_mut(|(second, text)| {
        if *second != secs {
            text.clear();
            write_second(text, secs);
            *second = secs;
        }
        out.extend_from_slice(text);
    });
    out.push(b'.');
    write_padded(out, u64::from(since.subsec_micros()), 6);
    out.push(b'Z');
}

/// The second `secs` after the epoch, `2026-11-23T15:10:40`.
fn write_second(out: &mut Vec<u8>, secs: u64) {
    let (year, month, day) = civil_from_days(secs / 86_400);
    let of_day = secs % 86_400;
    if year > 9999 {
        out.push(b'+');
    }
    write_padded(out, year, 4);
    for (separator, n) in [
        (b'-', month),
        (b'-', day),
        (b'T', of_day / 3600),
        (b':', of_day / 60 % 60),
        (b':', of_day % 60),
    ] {
        out.push(separator);
        write_padded(out, n, 2);
    }
}

/// The proleptic Gregorian (year, month, day) of a day counted from
/// 1970-01-01: Howard Hinnant's `civil_from_days`
/// (<https://howardhinnant.github.io/date_algorithms.html#civil_from_days>),
/// for days on or after it.
fn civil_from_days(days: u64) -> (u64, u64, u64) {
    let z = days + 719_468;
    let era = z / 146_097;
    let doe = z % 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + u64::from(month <= 2);
    (year, month, day)
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

    /// tracing-subscriber's own timer, at a fixed time.
    struct At(SystemTime);

    impl FormatTime for At {
        fn format_time(&self, w: &mut Writer<'_>) -> std::fmt::Result {
            let mut text = Vec::new();
            write_timestamp(&mut text, self.0);
            w.write_str(std::str::from_utf8(&text).unwrap())
        }
    }

    /// The line tracing-subscriber writes for `line`, in `format`, at `at`.
    fn formatted_by_tracing(format: LogFormat, at: SystemTime, line: &Access<'_>) -> String {
        let captured = Captured::default();
        let builder = tracing_subscriber::fmt()
            .with_ansi(false)
            .with_timer(At(at))
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
        let at = SystemTime::UNIX_EPOCH + Duration::new(1_795_442_840, 722_674_123);
        let lines = [
            Access {
                at: Instant::now(),
                request_id: "64fe70ab-1",
                method: "POST",
                route: "/v1/shade",
                status: 200,
                latency_ms: 0.094793,
                size: 385,
            },
            Access {
                at: Instant::now(),
                request_id: "a \"quoted\"\\ id\twith a tab, 'ünïcode' is not a header's",
                method: "OPTIONS",
                route: "unmatched",
                status: 404,
                latency_ms: 12345.678901234,
                size: -1,
            },
            Access {
                at: Instant::now(),
                request_id: "",
                method: "GET",
                route: "/metrics",
                status: 503,
                latency_ms: 1e-3,
                size: 0,
            },
        ];
        for format in [LogFormat::Human, LogFormat::Json] {
            for line in &lines {
                assert_eq!(
                    by_hand(format, at, line),
                    formatted_by_tracing(format, at, line),
                    "{format:?}"
                );
            }
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

    #[test]
    fn timestamps_are_rfc_3339_in_utc_with_microseconds() {
        let cases = [
            (0, 0, "1970-01-01T00:00:00.000000Z"),
            (951_782_400, 5_000, "2000-02-29T00:00:00.000005Z"),
            (1_795_442_840, 722_674_999, "2026-11-23T14:07:20.722674Z"),
            (253_402_300_799, 999_999_999, "9999-12-31T23:59:59.999999Z"),
            (253_402_300_800, 0, "+10000-01-01T00:00:00.000000Z"),
        ];
        for (secs, nanos, text) in cases {
            let mut out = Vec::new();
            write_timestamp(
                &mut out,
                SystemTime::UNIX_EPOCH + Duration::new(secs, nanos),
            );
            assert_eq!(String::from_utf8(out).unwrap(), text);
        }
    }

    #[test]
    fn instants_become_the_wall_clock_times_they_were() {
        // Instants before, within and after a thread's reading of both
        // clocks, each against the wall clock read beside it.
        for offset_ms in [0i64, -5, 3, 25, -40, 1, 0] {
            let (now, wall) = (std::time::Instant::now(), SystemTime::now());
            let offset = Duration::from_millis(offset_ms.unsigned_abs());
            let (at, expected) = if offset_ms >= 0 {
                (now + offset, wall + offset)
            } else {
                (now - offset, wall - offset)
            };
            let got = wall_clock(at);
            let error = got
                .duration_since(expected)
                .unwrap_or_else(|e| e.duration());
            assert!(
                error < Duration::from_millis(1),
                "{offset_ms} ms: off by {error:?}"
            );
        }
    }

    /// A sink that takes nothing until it is let go, then counts the lines
    /// it takes.
    struct Stuck(Arc<(Mutex<bool>, Condvar)>, Arc<AtomicU64>);

    impl Write for Stuck {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            let (free, turn) = &*self.0;
            let _free = turn
                .wait_while(free.lock().unwrap(), |free| !*free)
                .unwrap();
            self.1.fetch_add(count_lines(bytes), Ordering::Relaxed);
            Ok(bytes.len())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_stuck_sink_costs_lines_not_time() {
        let buffer = Arc::new(Buffer::new(1000));
        let gate = Arc::new((Mutex::new(false), Condvar::new()));
        let writer = thread_for(buffer.clone(), Stuck(gate.clone(), Arc::default()));
        let line = [b'x'; 99]
            .iter()
            .copied()
            .chain([b'\n'])
            .collect::<Vec<_>>();
        // The writer takes the first lines and is stuck writing them; ten
        // more fill the buffer, and the rest are dropped without waiting.
        for _ in 0..1000 {
            buffer.push(&line);
        }
        // (How many it took before it was stuck depends on when it woke.)
        let dropped = buffer.dropped.load(Ordering::Relaxed);
        assert!((980..=990).contains(&dropped), "{dropped} dropped");
        *gate.0.lock().unwrap() = true;
        gate.1.notify_all();
        let guard = LogGuard {
            buffer: buffer.clone(),
            writer: Some(writer),
        };
        drop(guard);
        assert!(buffer.lock().finished, "the writer wrote what was left");
    }

    /// A line of `len` bytes, newline included.
    fn line_of(len: usize) -> Vec<u8> {
        let mut line = vec![b'x'; len - 1];
        line.push(b'\n');
        line
    }

    #[test]
    fn a_stuck_sink_costs_staged_lines_not_time() {
        // Room for 16 lines of 100 bytes; a stage moves into the buffer
        // past 100 bytes, two lines at a time.
        let buffer = Arc::new(Buffer::new(1600));
        let gate = Arc::new((Mutex::new(false), Condvar::new()));
        let written = Arc::new(AtomicU64::new(0));
        let writer = thread_for(buffer.clone(), Stuck(gate.clone(), written.clone()));
        let line = line_of(100);
        // Staging never waits for the stuck sink: this loop ends.
        for _ in 0..1000 {
            buffer.stage(|lines| lines.extend_from_slice(&line));
        }
        let dropped = buffer.dropped.load(Ordering::Relaxed);
        assert!(dropped >= 900, "{dropped} dropped");
        *gate.0.lock().unwrap() = true;
        gate.1.notify_all();
        drop(LogGuard {
            buffer: buffer.clone(),
            writer: Some(writer),
        });
        // Every line was written or counted as dropped, the staged ones too.
        let written = written.load(Ordering::Relaxed);
        assert_eq!(written + buffer.dropped.load(Ordering::Relaxed), 1000);
    }

    /// A sink that sends what it takes.
    struct Sent(std::sync::mpsc::Sender<Vec<u8>>);

    impl Write for Sent {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            let _ = self.0.send(bytes.to_vec());
            Ok(bytes.len())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_staged_line_reaches_an_idle_writer() {
        // Each line is staged by another thread once the writer has written
        // the one before and says it is idle, while it goes to wait or when
        // it waits: every one of them must wake it.
        let buffer = Arc::new(Buffer::new(1 << 20));
        let (sent, received) = std::sync::mpsc::channel();
        let writer = thread_for(buffer.clone(), Sent(sent));
        for i in 0..100u32 {
            let text = format!("line {i}\n");
            let deadline = std::time::Instant::now() + Duration::from_secs(10);
            while !buffer.writer_idle.load(Ordering::SeqCst) {
                assert!(std::time::Instant::now() < deadline, "the writer idles");
                std::thread::yield_now();
            }
            std::thread::scope(|s| {
                s.spawn(|| buffer.stage(|lines| lines.extend_from_slice(text.as_bytes())));
            });
            let got = received
                .recv_timeout(Duration::from_secs(10))
                .expect("the staged line reaches the sink");
            assert_eq!(String::from_utf8(got).unwrap(), text);
        }
        drop(LogGuard {
            buffer: buffer.clone(),
            writer: Some(writer),
        });
        assert_eq!(buffer.dropped.load(Ordering::Relaxed), 0);
    }
}

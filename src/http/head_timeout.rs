//! The time a connection has to send each request head (`--header-timeout-ms`).
//!
//! A connection that does not send a whole request head within that time of
//! being accepted, or of its last answer being written, is closed: a client
//! that trickles its headers, or keeps an idle connection open, cannot hold
//! a connection for longer.
//!
//! hyper has this timeout built in, but arms a timer for every request head:
//! an allocation, a registration in the runtime's timer wheel under its
//! lock, a removal, and an extra `recv` that finds nothing after each
//! answer. Here each connection has one timer, which wakes once per timeout
//! period at most, however many requests the connection carries; a request
//! costs two readings of a coarse clock and a few uncontended atomic
//! operations.
//!
//! Three parts share a connection's [`Activity`]: [`Watched`] wraps the
//! service and counts the requests being answered, [`WatchedIo`] wraps the
//! socket and notes each write, and [`watch`], a task of its own beside the
//! connection's, aborts the connection's task when the head is late (so the
//! connection's task, woken at every step of every request, polls nothing
//! more than the connection).

use std::io::IoSlice;
use std::pin::Pin;
use std::sync::Arc;
#[cfg(not(target_os = "linux"))]
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::task::{Context, Poll, ready};
use std::time::Duration;
#[cfg(not(target_os = "linux"))]
use std::time::Instant;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::task::AbortHandle;

/// What a connection is doing, as the head timeout sees it.
#[derive(Debug)]
pub struct Activity {
    /// Requests being answered now (more than one only on HTTP/2).
    answering: AtomicUsize,
    /// When the connection began to wait for a request head: its accept,
    /// the end of its last answer, or its last write (on the clock of
    /// [`now`]).
    waiting_since: AtomicU64,
}

impl Activity {
    /// A connection accepted now.
    pub fn new() -> Arc<Self> {
        Arc::new(Self {
            answering: AtomicUsize::new(0),
            waiting_since: AtomicU64::new(now()),
        })
    }

    fn begin(&self) {
        self.answering.fetch_add(1, Ordering::Relaxed);
    }

    fn end(&self) {
        if self.answering.fetch_sub(1, Ordering::Relaxed) == 1 {
            self.waiting_since.store(now(), Ordering::Relaxed);
        }
    }

    fn wrote(&self) {
        self.waiting_since.store(now(), Ordering::Relaxed);
    }
}

/// The clock of [`Activity`], in nanoseconds: on Linux the coarse
/// monotonic clock, which the kernel advances at each tick (every few
/// milliseconds, far finer than a head timeout) and which costs a fraction
/// of the fine one to read, twice per request.
#[cfg(target_os = "linux")]
fn now() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::MonotonicCoarse);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// The clock of [`Activity`], in nanoseconds since its first reading.
#[cfg(not(target_os = "linux"))]
fn now() -> u64 {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64
}

/// Serves a connection on a task of its own, and closes it when it has
/// waited `timeout` for a request head.
pub fn watch(
    connection: impl Future<Output = ()> + Send + 'static,
    activity: Arc<Activity>,
    timeout: Duration,
) {
    let (served_tx, served_rx) = tokio::sync::oneshot::channel::<AbortHandle>();
    let watchdog = tokio::spawn(async move {
        expiry(&activity, timeout).await;
        // The head is late: abort the connection's task, which drops the
        // connection and closes its socket.
        if let Ok(served) = served_rx.await {
            served.abort();
            tracing::debug!("no request head within the header timeout: connection closed");
        }
    });
    let stop_watching = watchdog.abort_handle();
    let served = tokio::spawn(async move {
        connection.await;
        stop_watching.abort();
    });
    let _ = served_tx.send(served.abort_handle());
}

/// Completes when the connection of `activity` has waited `timeout` for a
/// request head; never while it answers one.
async fn expiry(activity: &Activity, timeout: Duration) {
    loop {
        if activity.answering.load(Ordering::Relaxed) > 0 {
            // Looked at again a timeout later: an answer takes its own
            // time, bounded by the request and body timeouts.
            tokio::time::sleep(timeout).await;
            continue;
        }
        let since = activity.waiting_since.load(Ordering::Relaxed);
        let waited = Duration::from_nanos(now().saturating_sub(since));
        if waited >= timeout {
            return;
        }
        tokio::time::sleep(timeout - waited).await;
    }
}

/// A connection's service, counting the requests it answers.
#[derive(Clone, Debug)]
pub struct Watched<S> {
    pub inner: S,
    pub activity: Arc<Activity>,
}

impl<S, R> hyper::service::Service<R> for Watched<S>
where
    S: hyper::service::Service<R>,
    S::Future: Unpin,
{
    type Response = S::Response;
    type Error = S::Error;
    type Future = Answering<S::Future>;

    fn call(&self, request: R) -> Self::Future {
        self.activity.begin();
        Answering {
            inner: self.inner.call(request),
            activity: Some(self.activity.clone()),
        }
    }
}

/// A request being answered: the answer's end, or the request's drop,
/// starts the wait for the next head.
pub struct Answering<F> {
    inner: F,
    activity: Option<Arc<Activity>>,
}

impl<F: Future + Unpin> Future for Answering<F> {
    type Output = F::Output;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<F::Output> {
        let answer = ready!(Pin::new(&mut self.inner).poll(cx));
        if let Some(activity) = self.activity.take() {
            activity.end();
        }
        Poll::Ready(answer)
    }
}

impl<F> Drop for Answering<F> {
    fn drop(&mut self) {
        if let Some(activity) = self.activity.take() {
            activity.end();
        }
    }
}

/// A connection's socket, noting each write: a long answer being written
/// to a client that reads it is activity, not a wait for a head.
#[derive(Debug)]
pub struct WatchedIo<T> {
    pub inner: T,
    pub activity: Arc<Activity>,
}

impl<T: AsyncRead + Unpin> AsyncRead for WatchedIo<T> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.inner).poll_read(cx, buf)
    }
}

impl<T: AsyncWrite + Unpin> WatchedIo<T> {
    fn noted(&self, written: Poll<std::io::Result<usize>>) -> Poll<std::io::Result<usize>> {
        if let Poll::Ready(Ok(n)) = written
            && n > 0
        {
            self.activity.wrote();
        }
        written
    }
}

impl<T: AsyncWrite + Unpin> AsyncWrite for WatchedIo<T> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<std::io::Result<usize>> {
        let written = Pin::new(&mut self.inner).poll_write(cx, buf);
        self.noted(written)
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[IoSlice<'_>],
    ) -> Poll<std::io::Result<usize>> {
        let written = Pin::new(&mut self.inner).poll_write_vectored(cx, bufs);
        self.noted(written)
    }

    fn is_write_vectored(&self) -> bool {
        self.inner.is_write_vectored()
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.inner).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<std::io::Result<()>> {
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }
}

//! The hand-off of CPU work from the async server to a rayon pool, with
//! admission control.
//!
//! At most `max_jobs` jobs run at once; up to `queue` more wait (cheaply, on
//! the async side) for a turn. A job that arrives when both are full is
//! refused at once with [`JobError::Busy`], so a saturated server answers 503
//! immediately instead of timing out slowly. A job whose caller has gone away
//! (the handler's future was dropped) is dropped before it starts, and a
//! running job can ask [`Cancel::is_cancelled`] between chunks of its work.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use tokio::sync::{Semaphore, oneshot};

/// The pool and its admission counters.
#[derive(Clone)]
pub struct Pool {
    inner: Arc<Inner>,
}

struct Inner {
    threads: rayon::ThreadPool,
    running: Arc<Semaphore>,
    max_jobs: usize,
    waiting: AtomicUsize,
    max_waiting: usize,
}

/// Why a job produced no result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobError {
    /// The pool is saturated: every worker is busy and the queue is full.
    Busy,
    /// The job panicked; the panic was logged by the pool.
    Panicked,
}

/// Lets a running job notice that nobody waits for its result any more.
pub struct Cancel<'a, T>(&'a oneshot::Sender<T>);

impl<T> Cancel<'_, T> {
    pub fn is_cancelled(&self) -> bool {
        self.0.is_closed()
    }
}

impl Pool {
    /// A pool of `threads` workers (0: one per core) running at most
    /// `max_jobs` jobs with `queue` more waiting.
    pub fn new(threads: usize, max_jobs: usize, queue: usize) -> std::io::Result<Self> {
        let threads = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("glint-worker-{i}"))
            .panic_handler(|panic| {
                let message = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                tracing::error!(%message, "a job panicked");
            })
            .build()
            .map_err(std::io::Error::other)?;
        let max_jobs = if max_jobs == 0 {
            threads.current_num_threads()
        } else {
            max_jobs
        };
        Ok(Self {
            inner: Arc::new(Inner {
                threads,
                running: Arc::new(Semaphore::new(max_jobs)),
                max_jobs,
                waiting: AtomicUsize::new(0),
                max_waiting: queue,
            }),
        })
    }

    /// Jobs waiting for a turn.
    pub fn queued(&self) -> usize {
        self.inner.waiting.load(Ordering::Relaxed)
    }

    /// Jobs that may run at once.
    pub fn max_jobs(&self) -> usize {
        self.inner.max_jobs
    }

    /// Jobs running now.
    pub fn running(&self) -> usize {
        self.inner.max_jobs - self.inner.running.available_permits()
    }

    /// Worker threads.
    pub fn threads(&self) -> usize {
        self.inner.threads.current_num_threads()
    }

    /// Whether a job offered now would be refused: every slot taken and the
    /// queue full. A hint only (the next moment may differ); [`Pool::run`]
    /// decides.
    pub fn is_full(&self) -> bool {
        let inner = &self.inner;
        inner.running.available_permits() == 0
            && inner.waiting.load(Ordering::Acquire) >= inner.max_waiting
    }

    /// Runs `job` on the pool and waits for its result without blocking the
    /// async runtime. Dropping the returned future cancels the job.
    pub async fn run<T, F>(&self, job: F) -> Result<T, JobError>
    where
        T: Send + 'static,
        F: FnOnce(&Cancel<'_, T>) -> T + Send + 'static,
    {
        let inner = &self.inner;
        let permit = match inner.running.clone().try_acquire_owned() {
            Ok(permit) => permit,
            Err(_) => {
                let _waiting =
                    WaitingTicket::take(&inner.waiting, inner.max_waiting).ok_or(JobError::Busy)?;
                inner
                    .running
                    .clone()
                    .acquire_owned()
                    .await
                    .expect("the semaphore is never closed")
            }
        };
        let (tx, rx) = oneshot::channel();
        inner.threads.spawn(move || {
            if tx.is_closed() {
                return;
            }
            let out = job(&Cancel(&tx));
            // The slot is free before the result leaves: a client that sends
            // its next request as soon as it has this answer must find it so,
            // not get a 503 from a job that is already done.
            drop(permit);
            let _ = tx.send(out);
        });
        rx.await.map_err(|_| JobError::Panicked)
    }
}

/// A place in the queue, given back when dropped (also when the waiting
/// future is dropped because its client went away).
struct WaitingTicket<'a>(&'a AtomicUsize);

impl<'a> WaitingTicket<'a> {
    fn take(waiting: &'a AtomicUsize, max: usize) -> Option<Self> {
        waiting
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < max).then_some(n + 1)
            })
            .ok()
            .map(|_| Self(waiting))
    }
}

impl Drop for WaitingTicket<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

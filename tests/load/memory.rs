//! Floods of refused requests leave the real binary's resident memory flat:
//! a declared length is not an allocation, a body is held only up to the
//! limit, and a request's size in memory stays near its size on the wire.
#![cfg(target_os = "linux")]

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use serde_json::Value;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

use super::{Glint, exchange, post_head, problem, split_responses};

/// Resident memory the server may reach under these floods. It idles at a
/// few MB; a server that took declared lengths at their word, or buffered
/// bodies past the limit, would pass this many times over.
const LIMIT: u64 = 300 * 1024 * 1024;

/// Samples the server's resident memory every few milliseconds until
/// stopped, keeping the peak.
struct Sampler {
    peak: Arc<AtomicU64>,
    stop: Arc<AtomicBool>,
    task: tokio::task::JoinHandle<()>,
}

impl Sampler {
    fn start(pid: u32) -> Self {
        let peak = Arc::new(AtomicU64::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let task = tokio::spawn({
            let (peak, stop) = (peak.clone(), stop.clone());
            async move {
                let mut every = tokio::time::interval(Duration::from_millis(5));
                while !stop.load(Ordering::Relaxed) {
                    every.tick().await;
                    if let Some(rss) = resident_bytes(pid) {
                        peak.fetch_max(rss, Ordering::Relaxed);
                    }
                }
            }
        });
        Self { peak, stop, task }
    }

    async fn peak(self) -> u64 {
        self.stop.store(true, Ordering::Relaxed);
        self.task.await.unwrap();
        self.peak.load(Ordering::Relaxed)
    }
}

fn resident_bytes(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kib * 1024)
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// Runs `count` copies of `one` at most `at_once` at a time.
async fn waves<F, Fut>(count: usize, at_once: usize, one: F)
where
    F: Fn(usize) -> Fut,
    Fut: Future<Output = ()> + Send + 'static,
{
    for wave in (0..count).collect::<Vec<_>>().chunks(at_once) {
        let tasks: Vec<_> = wave.iter().map(|&i| tokio::spawn(one(i))).collect();
        for task in tasks {
            task.await.unwrap();
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn floods_of_refused_bodies_leave_memory_flat() {
    let glint = Glint::spawn(&[
        "--threads",
        "2",
        "--queue",
        "4",
        "--max-body-bytes",
        "1048576",
    ])
    .await;
    let addr = glint.addr;
    let idle = glint.resident_bytes();
    let sampler = Sampler::start(glint.pid());

    // 200 requests each declaring 50 MB: refused on the head alone.
    waves(200, 50, move |_| async move {
        let mut stream = TcpStream::connect(addr).await.unwrap();
        let head = post_head("/v1/shade", 50 * 1024 * 1024, true);
        stream.write_all(head.as_bytes()).await.unwrap();
        let mut answer = Vec::new();
        stream.read_to_end(&mut answer).await.unwrap();
        let (responses, _) = split_responses(&answer);
        let response = responses.first().expect("an answer to a declared 50 MB");
        assert_eq!(response.status, 413);
        problem(413, response.header("content-type"), &response.body);
    })
    .await;

    // 64 bodies of 1 MB, just within the limit, that are not requests:
    // garbage from the first byte, or a long valid prefix gone wrong at
    // the end. Each is read in full and refused by the parser (or shed
    // with 503 when the workers are busy).
    waves(64, 16, move |i| async move {
        let mut body = if i % 2 == 0 {
            b"{\"vertices\": {\"positions\": [".to_vec()
        } else {
            b"\x00\xff garbage ".to_vec()
        };
        while body.len() < 1024 * 1024 - 16 {
            body.extend_from_slice(b"[0.5,0.25,1],");
        }
        body.resize(1024 * 1024, b'#');
        let response = crate::support::client()
            .post(format!("http://{addr}/v1/shade"))
            .header("content-type", "application/json")
            .body(body)
            .send()
            .await
            .unwrap();
        let status = response.status().as_u16();
        assert!(status == 400 || status == 503, "garbage of 1 MB: {status}");
        let content_type = response.headers()["content-type"]
            .to_str()
            .unwrap()
            .to_owned();
        problem(
            status,
            Some(&content_type),
            &response.bytes().await.unwrap(),
        );
    })
    .await;

    // 32 bodies streamed without a length, past the limit: cut off there.
    waves(32, 16, move |_| async move {
        let mut request = b"POST /v1/shade HTTP/1.1\r\nhost: 127.0.0.1\r\n\
            content-type: application/json\r\ntransfer-encoding: chunked\r\n\
            connection: close\r\n\r\n"
            .to_vec();
        let chunk = format!("10000\r\n{}\r\n", " ".repeat(0x10000));
        for _ in 0..17 {
            request.extend_from_slice(chunk.as_bytes());
        }
        let answer = exchange(addr, &request, Duration::from_secs(30)).await;
        let (responses, _) = split_responses(&answer);
        // The server may close with our last chunk unread; then the
        // kernel resets the connection and the answer can be lost, which
        // is the client's loss and no harm to the server.
        if let Some(response) = responses.first() {
            assert_eq!(response.status, 413);
        }
    })
    .await;

    let peak = sampler.peak().await;
    let after = glint.resident_bytes();
    eprintln!(
        "resident memory: idle {:.1} MiB, peak {:.1} MiB, after {:.1} MiB",
        mib(idle),
        mib(peak),
        mib(after)
    );
    assert!(peak < LIMIT, "peak {:.1} MiB under floods", mib(peak));
    assert!(after < LIMIT, "{:.1} MiB after the floods", mib(after));

    let response = crate::support::client()
        .post(glint.url("/v1/shade"))
        .json(&crate::http::one_vertex())
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200, "serving after the floods");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_million_lights_are_refused_quickly_without_building_them() {
    let glint = Glint::spawn(&["--threads", "2", "--request-timeout-ms", "30000"]).await;
    let mut body = String::from("{\"lights\": [");
    body.push_str(&"{},".repeat(999_999));
    body.push_str("{}], \"vertices\": {\"positions\": [[0,0,0]], \"normals\": [[0,0,1]]}}");
    let idle = glint.resident_bytes();
    let sampler = Sampler::start(glint.pid());

    let url = glint.url("/v1/shade");
    let requests: Vec<_> = (0..4)
        .map(|_| {
            let (url, body) = (url.clone(), body.clone());
            tokio::spawn(async move {
                let started = Instant::now();
                let response = crate::support::client()
                    .post(url)
                    .header("content-type", "application/json")
                    .body(body)
                    .send()
                    .await
                    .unwrap();
                let status = response.status().as_u16();
                let content_type = response.headers()["content-type"]
                    .to_str()
                    .unwrap()
                    .to_owned();
                let body = response.bytes().await.unwrap();
                (status, content_type, body, started.elapsed())
            })
        })
        .collect();
    for request in requests {
        let (status, content_type, body, elapsed) = request.await.unwrap();
        assert_eq!(status, 422, "{}", String::from_utf8_lossy(&body));
        let problem: Value = problem(422, Some(&content_type), &body);
        assert_eq!(problem["pointer"], "/lights", "{problem}");
        assert!(
            elapsed < Duration::from_secs(30),
            "refused within the request deadline, not after {elapsed:?}"
        );
        eprintln!(
            "a million lights: {} in {elapsed:?}: {}",
            status, problem["detail"]
        );
    }
    let peak = sampler.peak().await;
    eprintln!(
        "a million lights, four at once: idle {:.1} MiB, peak {:.1} MiB",
        mib(idle),
        mib(peak)
    );
    assert!(peak < LIMIT, "peak {:.1} MiB for 3 MB bodies", mib(peak));
}

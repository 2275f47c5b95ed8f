//! Three replicas behind HAProxy, started by `deploy/local/cluster.sh`,
//! under a bounded load of shade and render requests on several
//! connections: one replica killed with SIGKILL halfway, then every replica
//! stopped with SIGTERM in turn. No request may fail, and every answer must
//! be the one a single glint process gives to the same request.
#![cfg(unix)]

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{Cluster, signal, spheres};
use crate::load::{Glint, poll};
use crate::support::Rng;
use crate::support::client;

const REPLICAS: usize = 3;
/// Distinct requests, each sent many times.
const SHADES: usize = 40;
const RENDERS: usize = 6;
/// Requests in flight at once, each worker on its own connections.
const CONNECTIONS: usize = 8;
/// Requests of the SIGKILL run.
const KILL_LOAD: usize = 2400;
/// At most this many requests, and this long, for the rolling restart.
const RESTART_MAX: usize = 20_000;
const RESTART_TIME: Duration = Duration::from_secs(150);

/// One request of the load and what the single process answered to it.
pub(super) struct Case {
    path: &'static str,
    body: Vec<u8>,
    expected: Expected,
}

enum Expected {
    /// The JSON of `/v1/shade`, but for its timing.
    Shade(Value),
    /// The PNG of `/v1/render`, byte for byte.
    Png(Vec<u8>),
}

/// The requests of the load, each with the answer of the single process
/// at `single` (a base URL).
pub(super) async fn cases(single: &str) -> Vec<Case> {
    let mut rng = Rng::new(0x5ca1e);
    let mut cases = Vec::new();
    for _ in 0..SHADES {
        let body = serde_json::to_vec(&rng.shade_request(16)).unwrap();
        let response = client()
            .post(format!("{single}/v1/shade"))
            .header("content-type", "application/json")
            .body(body.clone())
            .send()
            .await
            .unwrap();
        assert_eq!(response.status(), 200);
        let expected = Expected::Shade(response.json().await.unwrap());
        cases.push(Case {
            path: "/v1/shade",
            body,
            expected,
        });
    }
    for k in 0..RENDERS as u32 {
        let request = spheres(24 + 4 * k, 16 + 2 * k, 1 + k % 2);
        let png = super::png_from(&format!("{single}/v1/render"), &request).await;
        cases.push(Case {
            path: "/v1/render",
            body: serde_json::to_vec(&request).unwrap(),
            expected: Expected::Png(png),
        });
    }
    cases
}

/// Whether `got` is the single process's answer; what differs if not.
fn check(case: &Case, got: &[u8]) -> Result<(), String> {
    match &case.expected {
        Expected::Png(png) if got == png.as_slice() => Ok(()),
        Expected::Png(_) => Err("a render's PNG differs from the single process's".into()),
        Expected::Shade(expected) => {
            let mut got: Value =
                serde_json::from_slice(got).map_err(|e| format!("not JSON: {e}"))?;
            // The one field that differs between two evaluations.
            got["stats"]["compute_ms"] = expected["stats"]["compute_ms"].clone();
            if got == *expected {
                Ok(())
            } else {
                Err(format!("a shade answer differs: {got} against {expected}"))
            }
        }
    }
}

/// A load on the cluster's address: `CONNECTIONS` workers send the cases
/// in turn until `max` requests were sent or `stop` is set.
pub(super) struct Load {
    done: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    failures: Arc<Mutex<Vec<String>>>,
    served_by: Arc<Mutex<BTreeMap<String, usize>>>,
    workers: tokio::task::JoinSet<()>,
}

impl Load {
    pub(super) fn start(base: String, cases: Arc<Vec<Case>>, max: usize) -> Self {
        let done = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let failures = Arc::new(Mutex::new(Vec::new()));
        let served_by = Arc::new(Mutex::new(BTreeMap::new()));
        let next = Arc::new(AtomicUsize::new(0));
        let mut workers = tokio::task::JoinSet::new();
        for _ in 0..CONNECTIONS {
            let (base, cases, next) = (base.clone(), cases.clone(), next.clone());
            let (done, stop) = (done.clone(), stop.clone());
            let (failures, served_by) = (failures.clone(), served_by.clone());
            workers.spawn(async move {
                let client = client();
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= max || stop.load(Ordering::Relaxed) {
                        return;
                    }
                    let case = &cases[i % cases.len()];
                    let outcome = async {
                        let response = client
                            .post(format!("{base}{}", case.path))
                            .header("content-type", "application/json")
                            .body(case.body.clone())
                            .send()
                            .await
                            .map_err(|e| format!("request {i}: {e}"))?;
                        let status = response.status();
                        let by = response
                            .headers()
                            .get("x-served-by")
                            .and_then(|v| v.to_str().ok())
                            .map(str::to_owned)
                            .ok_or_else(|| format!("request {i}: no x-served-by"))?;
                        let body = response
                            .bytes()
                            .await
                            .map_err(|e| format!("request {i}: {e}"))?;
                        if status != 200 {
                            return Err(format!(
                                "request {i}: {status} from {by}: {}",
                                String::from_utf8_lossy(&body)
                            ));
                        }
                        check(case, &body).map_err(|e| format!("request {i} ({by}): {e}"))?;
                        *served_by.lock().unwrap().entry(by).or_insert(0) += 1;
                        Ok(())
                    }
                    .await;
                    if let Err(failure) = outcome {
                        failures.lock().unwrap().push(failure);
                    }
                    done.fetch_add(1, Ordering::Relaxed);
                }
            });
        }
        Self {
            done,
            stop,
            failures,
            served_by,
            workers,
        }
    }

    pub(super) fn done(&self) -> usize {
        self.done.load(Ordering::Relaxed)
    }

    /// Waits for every worker (stopping them first when `stop`), within
    /// `limit`: how many requests were answered, and how many by each
    /// replica; or, when some failed, what failed.
    pub(super) async fn finish(
        mut self,
        stop: bool,
        limit: Duration,
    ) -> Result<(usize, BTreeMap<String, usize>), String> {
        if stop {
            self.stop.store(true, Ordering::Relaxed);
        }
        tokio::time::timeout(limit, async {
            while let Some(joined) = self.workers.join_next().await {
                joined.expect("a load worker does not panic");
            }
        })
        .await
        .expect("the load ends in time");
        let failures = self.failures.lock().unwrap().clone();
        let done = self.done();
        if !failures.is_empty() {
            return Err(format!(
                "{} of {done} requests failed:\n{}",
                failures.len(),
                shown(&failures)
            ));
        }
        let served_by = self.served_by.lock().unwrap().clone();
        Ok((done, served_by))
    }
}

/// The failures, at most 20 of them, for a message.
fn shown(failures: &[String]) -> String {
    let mut text = failures
        .iter()
        .take(20)
        .cloned()
        .collect::<Vec<_>>()
        .join("\n");
    if failures.len() > 20 {
        text.push_str(&format!("\n… and {} more", failures.len() - 20));
    }
    text
}

/// The cluster, and the cases of its load with a single process's answers.
async fn cluster_and_cases(test: &str) -> Option<(Cluster, Arc<Vec<Case>>)> {
    let cluster = Cluster::start(test, REPLICAS, &[]).await?;
    let single = Glint::spawn(&[]).await;
    let cases = Arc::new(cases(&single.url("")).await);
    Some((cluster, cases))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replica_killed_under_load_behind_haproxy_loses_no_request() {
    let test = "a_replica_killed_under_load_behind_haproxy_loses_no_request";
    let Some((cluster, cases)) = cluster_and_cases(test).await else {
        return;
    };

    let load = Load::start(cluster.lb_url(""), cases, KILL_LOAD);
    let halfway = poll(6000, Duration::from_millis(10), || async {
        load.done() >= KILL_LOAD / 2
    })
    .await;
    assert!(halfway, "half the load is answered within a minute");
    signal(cluster.replica_pid(1).expect("replica-2 runs"), "KILL");
    let (done, served_by) = load
        .finish(false, Duration::from_secs(180))
        .await
        .unwrap_or_else(|failed| panic!("{failed}\n{}", cluster.logs()));
    assert_eq!(done, KILL_LOAD);
    assert_eq!(
        served_by.len(),
        REPLICAS,
        "every replica answered: {served_by:?}"
    );
    assert!(
        cluster.replica_exits(1).contains(&(128 + 9)),
        "replica-2 died of SIGKILL: {:?}",
        cluster.replica_exits(1)
    );
    // What was in flight on the killed replica, and what was sent to it
    // before its checks failed, was retried on another.
    let retries = cluster.backend_counter("wretr").await;
    let redispatches = cluster.backend_counter("wredis").await;
    assert!(
        retries + redispatches > 0,
        "HAProxy retried: wretr {retries}, wredis {redispatches}\n{}",
        cluster.logs()
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rolling_restart_under_load_behind_haproxy_loses_no_request() {
    let test = "a_rolling_restart_under_load_behind_haproxy_loses_no_request";
    let Some((cluster, cases)) = cluster_and_cases(test).await else {
        return;
    };

    let started = Instant::now();
    let load = Load::start(cluster.lb_url(""), cases, RESTART_MAX);
    let warm = poll(3000, Duration::from_millis(10), || async {
        load.done() >= 200
    })
    .await;
    assert!(warm, "the load is under way");
    for i in 0..REPLICAS {
        let pid = cluster.replica_pid(i).expect("the replica runs");
        signal(pid, "TERM");
        // It drains and exits…
        let exited = poll(600, Duration::from_millis(50), || async {
            !cluster.replica_exits(i).is_empty()
        })
        .await;
        assert!(exited, "replica-{} exits within 30 s of SIGTERM", i + 1);
        // …its supervisor starts it again, and HAProxy's checks take it back.
        let back = poll(600, Duration::from_millis(50), || async {
            cluster.replica_pid(i).is_some_and(|now| now != pid)
                && client()
                    .get(cluster.replica_url(i, "/readyz"))
                    .send()
                    .await
                    .is_ok_and(|r| r.status() == 200)
                && cluster.haproxy_sees_up(i).await
        })
        .await;
        assert!(back, "replica-{} is back and up within 30 s", i + 1);
    }
    // Some load after the last restart too.
    let after = load.done() + 200;
    let more = poll(3000, Duration::from_millis(10), || async {
        load.done() >= after.min(RESTART_MAX)
    })
    .await;
    assert!(more, "the load goes on after the restarts");
    assert!(started.elapsed() < RESTART_TIME, "{:?}", started.elapsed());
    let (done, served_by) = load
        .finish(true, Duration::from_secs(60))
        .await
        .unwrap_or_else(|failed| panic!("{failed}\n{}", cluster.logs()));
    assert!(done > 400, "{done} requests");
    assert_eq!(served_by.len(), REPLICAS, "{served_by:?}");
    for i in 0..REPLICAS {
        assert_eq!(
            cluster.replica_exits(i),
            vec![0],
            "replica-{} exits 0 after its drain\n{}",
            i + 1,
            cluster.logs()
        );
    }
}

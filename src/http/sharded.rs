//! A counter and a histogram that the threads answering requests update
//! without sharing a cache line.
//!
//! `prometheus-client`'s counter is one atomic, and its histogram a mutex
//! over its buckets: every request's update of them takes the cache line
//! from the core that updated it last, which costs more than the update. In
//! these, each thread adds to a slot of its own (one of [`SLOTS`], given
//! out in the order threads first count), every slot on cache lines of its
//! own, and an encoding sums the slots. They encode as
//! `prometheus-client`'s own counter and histogram do, so `/metrics` reads
//! the same.
//!
//! A scrape during requests may see a request in one field of a histogram
//! (its bucket, say) and not yet in another (its count or sum).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use prometheus_client::encoding::{EncodeMetric, MetricEncoder, NoLabelSet};
use prometheus_client::metrics::{MetricType, TypedMetric};

/// How many slots a metric has; threads past this many share them.
const SLOTS: usize = 16;

/// This thread's slot.
fn slot() -> usize {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    thread_local! {
        static SLOT: usize = NEXT.fetch_add(1, Ordering::Relaxed) % SLOTS;
    }
    SLOT.with(|slot| *slot)
}

/// A value on cache lines of its own (two, for the neighbour prefetch).
#[derive(Debug, Default)]
#[repr(align(128))]
struct Padded<T>(T);

/// A monotonic counter, as `prometheus_client`'s `Counter<u64>`.
#[derive(Clone, Debug, Default)]
pub struct ShardedCounter(Arc<[Padded<AtomicU64>; SLOTS]>);

impl ShardedCounter {
    pub fn inc(&self) {
        self.inc_by(1);
    }

    pub fn inc_by(&self, n: u64) {
        self.0[slot()].0.fetch_add(n, Ordering::Relaxed);
    }

    /// The sum over the slots.
    pub fn get(&self) -> u64 {
        self.0
            .iter()
            .map(|slot| slot.0.load(Ordering::Relaxed))
            .sum()
    }
}

impl TypedMetric for ShardedCounter {
    const TYPE: MetricType = MetricType::Counter;
}

impl EncodeMetric for ShardedCounter {
    fn encode(&self, mut encoder: MetricEncoder) -> Result<(), std::fmt::Error> {
        encoder.encode_counter::<NoLabelSet, _, u64>(&self.get(), None)
    }

    fn metric_type(&self) -> MetricType {
        Self::TYPE
    }
}

/// The upper bounds of a [`ShardedHistogram`]'s buckets, besides the last
/// one (`+Inf`): 0.1 ms and 19 doublings after it, up to 52 s.
const BOUNDS: [f64; 20] = {
    let mut bounds = [0.0001; 20];
    let mut i = 1;
    while i < bounds.len() {
        bounds[i] = bounds[i - 1] * 2.0;
        i += 1;
    }
    bounds
};

/// One slot of a histogram: the sum of its observations (an `f64`'s bits),
/// their count, and how many fell into each bucket (not cumulative).
#[derive(Debug, Default)]
struct HistogramSlot {
    sum: AtomicU64,
    count: AtomicU64,
    buckets: [AtomicU64; BOUNDS.len() + 1],
}

/// A histogram with the buckets [`BOUNDS`] and `+Inf`, as
/// `prometheus_client`'s `Histogram` with those buckets.
#[derive(Clone, Debug, Default)]
pub struct ShardedHistogram(Arc<[Padded<HistogramSlot>; SLOTS]>);

impl ShardedHistogram {
    pub fn observe(&self, v: f64) {
        let slot = &self.0[slot()].0;
        // The first bucket whose bound is at least `v`, as
        // `prometheus_client` counts it.
        let bucket = BOUNDS.partition_point(|&bound| bound < v);
        slot.buckets[bucket].fetch_add(1, Ordering::Relaxed);
        slot.count.fetch_add(1, Ordering::Relaxed);
        // Only this thread (or one sharing its slot) adds to this sum.
        let _ = slot
            .sum
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |bits| {
                Some((f64::from_bits(bits) + v).to_bits())
            });
    }
}

impl TypedMetric for ShardedHistogram {
    const TYPE: MetricType = MetricType::Histogram;
}

impl EncodeMetric for ShardedHistogram {
    fn encode(&self, mut encoder: MetricEncoder) -> Result<(), std::fmt::Error> {
        let (mut sum, mut count) = (0.0, 0);
        let mut buckets: Vec<(f64, u64)> = BOUNDS
            .iter()
            .copied()
            .chain([f64::INFINITY])
            .map(|bound| (bound, 0))
            .collect();
        for Padded(slot) in self.0.iter() {
            sum += f64::from_bits(slot.sum.load(Ordering::Relaxed));
            count += slot.count.load(Ordering::Relaxed);
            for ((_, total), n) in buckets.iter_mut().zip(&slot.buckets) {
                *total += n.load(Ordering::Relaxed);
            }
        }
        encoder.encode_histogram::<NoLabelSet>(sum, count, &buckets, None)
    }

    fn metric_type(&self) -> MetricType {
        Self::TYPE
    }
}

#[cfg(test)]
mod tests {
    use prometheus_client::metrics::counter::Counter;
    use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
    use prometheus_client::registry::Registry;

    use super::*;

    /// The text exposition of `metric` registered as `name`.
    fn exposed(name: &str, metric: impl prometheus_client::registry::Metric) -> String {
        let mut registry = Registry::default();
        registry.register(name, "help", metric);
        let mut out = String::new();
        prometheus_client::encoding::text::encode(&mut out, &registry).unwrap();
        out
    }

    #[test]
    fn they_read_as_prometheus_clients_own_fed_the_same_from_many_threads() {
        let (counter, histogram) = (ShardedCounter::default(), ShardedHistogram::default());
        let (their_counter, their_histogram) = (
            Counter::<u64>::default(),
            Histogram::new(exponential_buckets(0.0001, 2.0, 20)),
        );
        // Values on and around every bound, and past the last.
        let values: Vec<f64> = BOUNDS
            .iter()
            .flat_map(|&b| [b, b * 0.75, b * 1.25])
            .chain([0.0, 1e6])
            .collect();
        std::thread::scope(|s| {
            for t in 0..SLOTS + 3 {
                let (counter, histogram) = (&counter, &histogram);
                let (their_counter, their_histogram) = (&their_counter, &their_histogram);
                let values = &values;
                s.spawn(move || {
                    for &v in values.iter().skip(t % 5) {
                        counter.inc_by(2);
                        their_counter.inc_by(2);
                        histogram.observe(v);
                        their_histogram.observe(v);
                    }
                });
            }
        });
        assert_eq!(exposed("c", counter), exposed("c", their_counter));
        // Line for line, the sums within rounding: the two add the same
        // values in different orders.
        let (ours, theirs) = (exposed("h", histogram), exposed("h", their_histogram));
        assert_eq!(ours.lines().count(), theirs.lines().count());
        for (a, b) in ours.lines().zip(theirs.lines()) {
            match (a.strip_prefix("h_sum "), b.strip_prefix("h_sum ")) {
                (Some(a), Some(b)) => {
                    let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
                    assert!((a - b).abs() <= 1e-12 * b.abs(), "sums {a} and {b}");
                }
                _ => assert_eq!(a, b),
            }
        }
    }
}

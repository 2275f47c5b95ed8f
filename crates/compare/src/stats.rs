//! The arithmetic of an error between two sets of colours: the largest,
//! mean and 99th-percentile absolute difference of the RGB channels, the
//! share of channels whose 8-bit values differ, PSNR, and the entries with
//! the largest error. Shared by the comparison of vertices and of images.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rayon::prelude::*;

use crate::eval::BLOCK;

/// The quantile that [`ErrorStats::p99_abs`] reports.
pub const P99: f64 = 0.99;

/// The error of a candidate's colours against GL's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// The largest `|candidate − GL|` of any RGB channel.
    pub max_abs: f64,
    /// The mean of `|candidate − GL|` over every RGB channel.
    pub mean_abs: f64,
    /// The 99th percentile of `|candidate − GL|` over every RGB channel, by
    /// the nearest-rank method (see [`quantile`]).
    pub p99_abs: f64,
    /// The share of RGB channels whose 8-bit values ([`eight_bit`]) differ.
    pub differing_8bit: f64,
    /// Whether `max_abs` (and `alpha_max_abs`, where alpha is compared) is
    /// at most the bound of the precision tier GL's colours come from.
    pub within_bound: bool,
    /// The number of RGB channels compared.
    pub channels: usize,
    /// The largest `|candidate − GL|` of alpha, where alpha is compared.
    pub alpha_max_abs: Option<f64>,
}

/// A colour channel as an 8-bit framebuffer stores it: `round(255·c)` of
/// `c` clamped to [0, 1] (as GL converts a float to an unsigned normalised
/// 8-bit value, section 2.1.5 of the specification).
#[inline(always)]
pub fn eight_bit(c: f32) -> u8 {
    eight_bit_value(c) as u8
}

/// [`eight_bit`] as an f32, for lanes.
#[inline(always)]
fn eight_bit_value(c: f32) -> f32 {
    (c.clamp(0.0, 1.0) * 255.0).round()
}

/// PSNR in decibels of a mean squared error of colours in [0, 1]: `10 ·
/// log10(1 / mse)`, the peak being 1. Infinite for identical colours; the
/// same figure as the PSNR of 8-bit values with a peak of 255 where the
/// colours are multiples of 1/255.
pub fn psnr_db(mse: f64) -> f64 {
    10.0 * (1.0 / mse).log10()
}

/// The `q`-quantile of `values` (finite, `0 < q ≤ 1`) by the nearest-rank
/// method: the smallest value such that at least `⌈q·n⌉` of the values are
/// at most it. `None` for no values.
///
/// Exact, and linear in time: a sample of the values brackets the rank, one
/// parallel pass counts the values below the bracket and gathers those in
/// it, and a selection among those gives the value. A bracket that misses
/// (never, for a sample of 4096 and a margin of seven standard deviations,
/// unless the values conspire) falls back to a selection among all.
pub fn quantile(values: &[f32], q: f64) -> Option<f32> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let rank = ((q * n as f64).ceil() as usize).clamp(1, n) - 1;
    const SMALL: usize = 1 << 15;
    if n <= SMALL {
        return Some(select(values.to_vec(), rank));
    }
    const SAMPLE: usize = 4096;
    // A fixed pseudo-random sample (a linear congruential sequence): a
    // stride could fall in step with a pattern of the values (every third
    // channel).
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut sample: Vec<f32> = (0..SAMPLE)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            values[((state >> 33) as usize) % n]
        })
        .collect();
    let at = rank as f64 / n as f64 * SAMPLE as f64;
    let margin = 7.0 * (SAMPLE as f64 * q * (1.0 - q)).sqrt() + 8.0;
    let lo_rank = (at - margin).max(0.0) as usize;
    let hi_rank = ((at + margin) as usize).min(SAMPLE - 1);
    sample.sort_unstable_by(f32::total_cmp);
    let (lo, hi) = (sample[lo_rank], sample[hi_rank]);
    let (below, inside) = values
        .par_chunks(1 << 16)
        .map(|chunk| {
            let below = chunk.iter().filter(|&&v| v < lo).count();
            let inside: Vec<f32> = chunk
                .iter()
                .copied()
                .filter(|&v| v >= lo && v <= hi)
                .collect();
            (below, inside)
        })
        .reduce(
            || (0, Vec::new()),
            |(b1, mut i1), (b2, i2)| {
                i1.extend(i2);
                (b1 + b2, i1)
            },
        );
    if rank >= below && rank < below + inside.len() {
        Some(select(inside, rank - below))
    } else {
        Some(select(values.to_vec(), rank))
    }
}

/// The `rank`-th smallest of `values` (from 0).
fn select(mut values: Vec<f32>, rank: usize) -> f32 {
    *values.select_nth_unstable_by(rank, f32::total_cmp).1
}

/// One entry among the worst: a vertex or a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst<I> {
    /// Which entry.
    pub at: I,
    /// Its largest RGB error.
    pub error: f32,
    /// GL's colour and the candidate's, RGBA.
    pub expected: [f32; 4],
    pub candidate: [f32; 4],
}

/// Ordered by error, the larger first among equals the earlier entry: the
/// heap keeps the `n` largest by dropping its least.
#[derive(Clone, Copy, Debug)]
struct Ranked<I> {
    worst: Worst<I>,
    /// The order of arrival, for ties.
    order: u64,
}

impl<I> PartialEq for Ranked<I> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl<I> Eq for Ranked<I> {}

impl<I> PartialOrd for Ranked<I> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl<I> Ord for Ranked<I> {
    /// "Greater" is "worse": a larger error, or an equal one that came first.
    fn cmp(&self, other: &Self) -> Ordering {
        self.worst
            .error
            .total_cmp(&other.worst.error)
            .then(other.order.cmp(&self.order))
    }
}

/// The `n` entries with the largest errors seen so far.
#[derive(Clone, Debug)]
pub(crate) struct WorstOf<I> {
    n: usize,
    /// A min-heap (by [`Ranked`]'s order, reversed) of at most `n`.
    heap: BinaryHeap<std::cmp::Reverse<Ranked<I>>>,
}

impl<I: Copy> WorstOf<I> {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            heap: BinaryHeap::with_capacity(n + 1),
        }
    }

    /// The least error an entry needs to enter.
    #[inline(always)]
    pub fn threshold(&self) -> f32 {
        if self.heap.len() < self.n {
            f32::NEG_INFINITY
        } else {
            self.heap.peek().map_or(f32::INFINITY, |r| r.0.worst.error)
        }
    }

    /// Offers an entry; `order` breaks ties (the earlier is worse).
    pub fn offer(&mut self, worst: Worst<I>, order: u64) {
        if self.n == 0 {
            return;
        }
        self.heap.push(std::cmp::Reverse(Ranked { worst, order }));
        if self.heap.len() > self.n {
            self.heap.pop();
        }
    }

    pub fn merge(mut self, other: Self) -> Self {
        for std::cmp::Reverse(r) in other.heap {
            self.offer(r.worst, r.order);
        }
        self
    }

    /// The entries, worst first.
    pub fn into_sorted(self) -> Vec<Worst<I>> {
        let mut ranked: Vec<Ranked<I>> = self.heap.into_iter().map(|r| r.0).collect();
        ranked.sort_by(|a, b| b.cmp(a));
        ranked.into_iter().map(|r| r.worst).collect()
    }
}

/// Running sums of an error, per task, merged at the end.
#[derive(Clone, Debug)]
pub(crate) struct ErrorSums<I> {
    pub max: f64,
    pub sum: f64,
    pub squares: f64,
    pub differing: u64,
    pub alpha_max: f64,
    pub worst: WorstOf<I>,
    /// Per lane, the sums of the blocks added since the last
    /// [`ErrorSums::flush`]: a block's arithmetic is lane by lane, and the
    /// lanes are summed once per task.
    lanes: ErrorLanes,
}

/// Per-lane sums of [`ErrorSums`].
#[derive(Clone, Debug)]
struct ErrorLanes {
    max: [f32; BLOCK],
    sum: [f32; BLOCK],
    squares: [f32; BLOCK],
    differing: [f32; BLOCK],
    alpha_max: [f32; BLOCK],
}

impl ErrorLanes {
    const ZERO: ErrorLanes = ErrorLanes {
        max: [0.0; BLOCK],
        sum: [0.0; BLOCK],
        squares: [0.0; BLOCK],
        differing: [0.0; BLOCK],
        alpha_max: [0.0; BLOCK],
    };
}

/// A block of colours as lanes: RGBA, one lane per entry.
pub(crate) type ColorLanes = [[f32; BLOCK]; 4];

impl<I: Copy> ErrorSums<I> {
    pub fn new(worst: usize) -> Self {
        Self {
            max: 0.0,
            sum: 0.0,
            squares: 0.0,
            differing: 0,
            alpha_max: 0.0,
            worst: WorstOf::new(worst),
            lanes: ErrorLanes::ZERO,
        }
    }

    /// Adds a block of entries, GL's colours and the candidate's, whose
    /// first `len` lanes hold entries (`mask` is 1 there, 0 past them), and
    /// writes their channel errors into `errors` (three per entry).
    /// `at(lane)` names an entry and gives the order that breaks ties among
    /// the worst.
    #[inline(always)]
    pub fn add_block(
        &mut self,
        expected: &ColorLanes,
        candidate: &ColorLanes,
        mask: &[f32; BLOCK],
        len: usize,
        errors: &mut [f32],
        at: impl Fn(usize) -> (I, u64),
    ) {
        let lanes = &mut self.lanes;
        let mut e = [[0.0f32; BLOCK]; 3];
        let mut largest = [0.0f32; BLOCK];
        for c in 0..3 {
            for i in 0..BLOCK {
                let error = (candidate[c][i] - expected[c][i]).abs() * mask[i];
                e[c][i] = error;
                largest[i] = if error > largest[i] {
                    error
                } else {
                    largest[i]
                };
                lanes.sum[i] += error;
                lanes.squares[i] += error * error;
                let differs = eight_bit_value(candidate[c][i]) != eight_bit_value(expected[c][i]);
                lanes.differing[i] += if differs { mask[i] } else { 0.0 };
            }
        }
        for i in 0..BLOCK {
            lanes.max[i] = if largest[i] > lanes.max[i] {
                largest[i]
            } else {
                lanes.max[i]
            };
            let alpha = (candidate[3][i] - expected[3][i]).abs() * mask[i];
            lanes.alpha_max[i] = if alpha > lanes.alpha_max[i] {
                alpha
            } else {
                lanes.alpha_max[i]
            };
        }
        for i in 0..len {
            for c in 0..3 {
                errors[3 * i + c] = e[c][i];
            }
        }
        let threshold = self.worst.threshold();
        if largest.iter().any(|&l| l > threshold) {
            for i in 0..len {
                if largest[i] > self.worst.threshold() {
                    let color = |lanes: &ColorLanes| std::array::from_fn(|c| lanes[c][i]);
                    let (at, order) = at(i);
                    self.worst.offer(
                        Worst {
                            at,
                            error: largest[i],
                            expected: color(expected),
                            candidate: color(candidate),
                        },
                        order,
                    );
                }
            }
        }
    }

    /// Moves the lanes' sums into the totals.
    pub fn flush(&mut self) {
        let lanes = std::mem::replace(&mut self.lanes, ErrorLanes::ZERO);
        let total = |x: &[f32; BLOCK]| x.iter().map(|&v| f64::from(v)).sum::<f64>();
        let most = |x: &[f32; BLOCK]| x.iter().fold(0.0f64, |m, &v| m.max(f64::from(v)));
        self.max = self.max.max(most(&lanes.max));
        self.sum += total(&lanes.sum);
        self.squares += total(&lanes.squares);
        self.differing += total(&lanes.differing) as u64;
        self.alpha_max = self.alpha_max.max(most(&lanes.alpha_max));
    }

    /// Both tasks' sums; each flushed first.
    pub fn merge(mut self, mut other: Self) -> Self {
        self.flush();
        other.flush();
        Self {
            max: self.max.max(other.max),
            sum: self.sum + other.sum,
            squares: self.squares + other.squares,
            differing: self.differing + other.differing,
            alpha_max: self.alpha_max.max(other.alpha_max),
            worst: self.worst.merge(other.worst),
            lanes: ErrorLanes::ZERO,
        }
    }

    /// The statistics of `errors` (every channel error, as
    /// [`ErrorSums::add_block`] wrote them) against `bound`.
    pub fn stats(&mut self, errors: &[f32], bound: f64, alpha: bool) -> ErrorStats {
        self.flush();
        let channels = errors.len();
        let alpha_max_abs = alpha.then_some(self.alpha_max);
        ErrorStats {
            max_abs: self.max,
            mean_abs: if channels == 0 {
                0.0
            } else {
                self.sum / channels as f64
            },
            p99_abs: quantile(errors, P99).map_or(0.0, f64::from),
            differing_8bit: if channels == 0 {
                0.0
            } else {
                self.differing as f64 / channels as f64
            },
            within_bound: self.max <= bound && alpha_max_abs.is_none_or(|a| a <= bound),
            channels,
            alpha_max_abs,
        }
    }

    /// The mean squared error per channel.
    pub fn mse(&mut self, channels: usize) -> f64 {
        self.flush();
        if channels == 0 {
            0.0
        } else {
            self.squares / channels as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest-rank quantile of 1, 2, …, n is `⌈q·n⌉`, in any order, on
    /// both paths (a selection among all, and the sampled bracket).
    #[test]
    fn quantile_of_a_permutation_is_its_rank() {
        for n in [1usize, 2, 99, 100, 101, 1000, 40_000, 1_000_003] {
            // A permutation of 1..=n: i·p mod n for p prime to n.
            let p = 7_919usize;
            let values: Vec<f32> = (0..n).map(|i| ((i * p) % n + 1) as f32).collect();
            for q in [0.5, 0.9, P99, 1.0] {
                let want = (q * n as f64).ceil().max(1.0) as f32;
                assert_eq!(quantile(&values, q), Some(want), "n {n}, q {q}");
            }
        }
        assert_eq!(quantile(&[], P99), None);
    }

    /// 99 zeros and one 1: the 99th percentile is 0 (rank 99 of 100), with
    /// one more 1 it is 1 (rank 100 of 101 lands on the ones).
    #[test]
    fn quantile_of_a_spike() {
        let mut values = vec![0.0f32; 99];
        values.push(1.0);
        assert_eq!(quantile(&values, P99), Some(0.0));
        values.push(1.0);
        assert_eq!(quantile(&values, P99), Some(1.0));
        // The same shape at a size that takes the sampled path: 2% ones.
        let big: Vec<f32> = (0..100_000)
            .map(|i| if i % 50 == 0 { 1.0 } else { 0.0 })
            .collect();
        assert_eq!(quantile(&big, P99), Some(1.0));
        let few: Vec<f32> = (0..100_000)
            .map(|i| if i % 200 == 0 { 1.0 } else { 0.0 })
            .collect();
        assert_eq!(quantile(&few, P99), Some(0.0));
    }

    /// `round(255·c)`: 0.5/255 rounds up (half away from zero), values
    /// outside [0, 1] saturate.
    #[test]
    fn eight_bit_values_round_to_nearest() {
        assert_eq!(eight_bit(0.0), 0);
        assert_eq!(eight_bit(1.0), 255);
        assert_eq!(eight_bit(-3.0), 0);
        assert_eq!(eight_bit(7.0), 255);
        assert_eq!(eight_bit(0.4 / 255.0), 0);
        assert_eq!(eight_bit(0.6 / 255.0), 1);
        assert_eq!(eight_bit(128.0 / 255.0), 128);
    }

    /// A uniform error `e` on every channel has MSE `e²` and PSNR
    /// `−20·log10(e)`: 1/255 gives 48.13 dB.
    #[test]
    fn psnr_of_a_uniform_error() {
        let e = 1.0 / 255.0;
        assert!((psnr_db(e * e) - 20.0 * 255f64.log10()).abs() < 1e-12);
        assert!((psnr_db(1e-4) - 40.0).abs() < 1e-12);
        assert_eq!(psnr_db(0.0), f64::INFINITY);
    }

    /// Sums over entries whose errors are known: max, mean, the 8-bit
    /// share and the worst entries in order.
    #[test]
    fn sums_of_known_errors() {
        let mut sums = ErrorSums::<usize>::new(2);
        let mut errors = vec![0.0; 9];
        let gl = [0.5, 0.5, 0.5, 1.0];
        // Errors 0.1 (red), 0.001 (green), 0.3 (blue and alpha).
        let candidates = [
            [0.6, 0.5, 0.5, 1.0],
            [0.5, 0.501, 0.5, 1.0],
            [0.5, 0.5, 0.8, 0.7],
        ];
        let lanes = |colors: &[[f32; 4]]| {
            let mut lanes = [[0.0; BLOCK]; 4];
            for (i, color) in colors.iter().enumerate() {
                for c in 0..4 {
                    lanes[c][i] = color[c];
                }
            }
            lanes
        };
        let mut mask = [0.0; BLOCK];
        mask[..3].fill(1.0);
        sums.add_block(
            &lanes(&[gl; 3]),
            &lanes(&candidates),
            &mask,
            3,
            &mut errors,
            |i| (i, i as u64),
        );
        let stats = sums.stats(&errors, 0.2, true);
        assert!((stats.max_abs - 0.3).abs() < 1e-6);
        assert!((stats.mean_abs - (0.1 + 0.001 + 0.3) / 9.0).abs() < 1e-7);
        // 0.5 → 128; 0.6 → 153, 0.501 → 128 (127.755 rounds to 128), 0.8 → 204.
        assert!((stats.differing_8bit - 2.0 / 9.0).abs() < 1e-12);
        assert!(!stats.within_bound);
        assert!((stats.alpha_max_abs.unwrap() - 0.3).abs() < 1e-6);
        let worst = sums.worst.clone().into_sorted();
        assert_eq!(worst.iter().map(|w| w.at).collect::<Vec<_>>(), [2, 0]);
        // Rank 9 of 9 (⌈0.99·9⌉): the largest.
        assert!((stats.p99_abs - 0.3).abs() < 1e-6);
    }
}

//! A seeded, reproducible source of the unit tests' inputs: SplitMix64
//! (Steele, Lea and Flood, *Fast Splittable Pseudorandom Number
//! Generators*, 2014; the constants of Vigna's `splitmix64.c`), as
//! `tests/support/rng.rs` is for the integration tests.

/// SplitMix64's state.
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [−1, 1), from the top 53 bits.
    pub(crate) fn signed(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

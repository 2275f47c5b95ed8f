//! A seeded, reproducible source of the unit tests' inputs: SplitMix64
//! (Steele, Lea and Flood, *Fast Splittable Pseudorandom Number
//! Generators*, 2014), as `glint-lighting`'s `test_rng` is for its unit
//! tests and `tests/support/rng.rs` for the integration tests. Its
//! finaliser is the film's sample patterns' ([`crate::film::mix`]).

/// SplitMix64's state.
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next number: [`crate::film::mix`] adds the step to the state
    /// before it finalises, so it is given the state before the step.
    pub(crate) fn next_u64(&mut self) -> u64 {
        let state = self.0;
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        crate::film::mix(state)
    }

    /// Uniform in [lo, hi).
    pub(crate) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// Uniform in 0..n.
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

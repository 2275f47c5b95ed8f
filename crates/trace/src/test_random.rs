//! A reproducible stream of numbers for the crate's unit tests.

/// SplitMix64: a reproducible stream of uniform numbers.
pub(crate) struct Random(pub(crate) u64);

impl Random {
    /// The finaliser of the film's sample patterns on the state before its
    /// step, which the finaliser itself adds.
    pub(crate) fn next(&mut self) -> u64 {
        let state = self.0;
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        crate::film::mix(state)
    }

    /// Uniform in [lo, hi).
    pub(crate) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }

    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

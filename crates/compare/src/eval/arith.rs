//! The arithmetic of each precision tier, as the block evaluator reads it:
//! f64 with the reference's own `powf` for `reference`, and f32 with the
//! kernels' own `pow`, whole powers and cosines (`glint_lighting::tier_math`)
//! for `accurate` and `fast`, so that a deviated colour is within the same
//! bound of the reference's deviated colour as the tier's shade is of GL's.

use std::fmt::Debug;
use std::marker::PhantomData;

use glint_lighting::tier_math::{
    Accurate, Cosine, Fast, Math, Power, cosine, cosine_of_unit, whole_base,
};
use glint_lighting::{MAX_ATTENUATION, Precision, spec_pow};

use super::BLOCK;

/// f32 or f64, with the conversions the evaluator needs.
pub(crate) trait Real:
    num_traits::Float + Default + Send + Sync + Debug + std::ops::AddAssign + 'static
{
    const ZERO: Self;
    fn of(x: f64) -> Self;
    fn wide(self) -> f64;
    /// The squared distances whose square root and reciprocal lose nothing:
    /// outside, a direction is scaled into range first.
    const SAFE_DISTANCE2: std::ops::Range<Self>;
    /// [`MAX_ATTENUATION`] in this type.
    fn max_attenuation() -> Self {
        Self::of(MAX_ATTENUATION)
    }

    /// The larger of two numbers that are not NaN: a compare and a select,
    /// which vectorise where `max`, which must handle NaN, costs more.
    #[inline(always)]
    fn larger(self, other: Self) -> Self {
        if self > other { self } else { other }
    }

    /// The smaller of two numbers that are not NaN (see [`Real::larger`]).
    #[inline(always)]
    fn smaller(self, other: Self) -> Self {
        if self < other { self } else { other }
    }

    /// Clamped to [0, 1].
    #[inline(always)]
    fn unit_clamped(self) -> Self {
        self.larger(Self::zero()).smaller(Self::one())
    }
}

impl Real for f32 {
    const ZERO: f32 = 0.0;
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        f64::from(self)
    }
    const SAFE_DISTANCE2: std::ops::Range<f32> = 1e-30..1e30;
}

impl Real for f64 {
    const ZERO: f64 = 0.0;
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        self
    }
    const SAFE_DISTANCE2: std::ops::Range<f64> = 1e-280..1e280;
}

/// A tier's powers and cosines.
///
/// A cosine is stored per lane as two numbers (`store_cosine`), and a
/// block's cosines are raised in one pass (`power_pass`) whose plan is
/// chosen once per exponent, as the kernels do.
pub(crate) trait Arith: Copy + Send + Sync + 'static {
    type F: Real;
    /// The precision whose arithmetic this is.
    const PRECISION: Precision;
    /// How `x^s` of a cosine is taken for one exponent `s`.
    type Plan: Copy + Send + Sync + Debug + PartialEq;

    fn plan(s: f64) -> Self::Plan;

    /// The angle between `a` and `b`, stored as the tier's power pass reads
    /// it: a zero vector gives "not positive".
    fn store_cosine(a: [Self::F; 3], b: [Self::F; 3]) -> (Self::F, Self::F);

    /// [`Arith::store_cosine`] where `a` is a unit vector (to rounding, or
    /// zero) and `inverse_b2` is `1/|b|²`: no square root, and no division
    /// where `b` is the same for every lane.
    fn store_cosine_of_unit(
        a: [Self::F; 3],
        b: [Self::F; 3],
        inverse_b2: Self::F,
    ) -> (Self::F, Self::F);

    /// Whether a stored cosine is above 0.
    fn positive(cos: Self::F) -> bool;

    /// `max(cos, 0)^s` of every lane, `0^0 = 1`, capped as
    /// [`glint_lighting::spec_pow`] is.
    fn power_pass(
        plan: Self::Plan,
        sin2: &[Self::F; BLOCK],
        cos: &[Self::F; BLOCK],
        out: &mut [Self::F; BLOCK],
    );

    /// `max(x, 0)^s` for a base that is not a cosine, `0^0 = 1`, capped.
    fn pow(x: Self::F, s: Self::F) -> Self::F;
}

/// The reference tier: f64, the reference's `spec_pow`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reference;

impl Arith for Reference {
    type F = f64;
    const PRECISION: Precision = Precision::Reference;
    type Plan = f64;

    fn plan(s: f64) -> f64 {
        s
    }

    /// The cosine itself (the slot of `sin²` is unused).
    #[inline(always)]
    fn store_cosine(a: [f64; 3], b: [f64; 3]) -> (f64, f64) {
        let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        let b2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
        let lengths = (a2 * b2).sqrt();
        (0.0, if lengths > 0.0 { dot / lengths } else { 0.0 })
    }

    /// The cosine of any two vectors: f64 needs no shortcut.
    #[inline(always)]
    fn store_cosine_of_unit(a: [f64; 3], b: [f64; 3], _: f64) -> (f64, f64) {
        Self::store_cosine(a, b)
    }

    #[inline(always)]
    fn positive(cos: f64) -> bool {
        cos > 0.0
    }

    #[inline(always)]
    fn power_pass(s: f64, _: &[f64; BLOCK], cos: &[f64; BLOCK], out: &mut [f64; BLOCK]) {
        for i in 0..BLOCK {
            out[i] = spec_pow(cos[i], s);
        }
    }

    #[inline(always)]
    fn pow(x: f64, s: f64) -> f64 {
        spec_pow(x, s)
    }
}

/// An f32 tier: the kernels' arithmetic of [`Math`] `M`.
pub(crate) struct Single<M>(PhantomData<M>);

/// The precision of an f32 tier's [`Math`].
pub(crate) trait TierMath: Math + Send + Sync + 'static {
    const PRECISION: Precision;
}

impl TierMath for Accurate {
    const PRECISION: Precision = Precision::Accurate;
}

impl TierMath for Fast {
    const PRECISION: Precision = Precision::Fast;
}

impl<M> Clone for Single<M> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M> Copy for Single<M> {}

pub(crate) type AccurateTier = Single<Accurate>;
pub(crate) type FastTier = Single<Fast>;

impl<M: TierMath> Arith for Single<M> {
    type F = f32;
    const PRECISION: Precision = M::PRECISION;
    type Plan = Power;

    fn plan(s: f64) -> Power {
        Power::new::<M>(s as f32)
    }

    /// `sin²` and `cos²`, `cos²` negative where `cos ≤ 0`, as the kernels
    /// store them.
    #[inline(always)]
    fn store_cosine(a: [f32; 3], b: [f32; 3]) -> (f32, f32) {
        let c = cosine(a, b);
        (c.sin2, if c.positive { c.cos2 } else { -1.0 })
    }

    #[inline(always)]
    fn store_cosine_of_unit(a: [f32; 3], b: [f32; 3], inverse_b2: f32) -> (f32, f32) {
        let c = cosine_of_unit(a, b, inverse_b2);
        (c.sin2, if c.positive { c.cos2 } else { -1.0 })
    }

    #[inline(always)]
    fn positive(cos: f32) -> bool {
        cos >= 0.0
    }

    #[inline(always)]
    fn power_pass(plan: Power, sin2: &[f32; BLOCK], cos2: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        let stored = |i: usize| Cosine {
            positive: cos2[i] >= 0.0,
            sin2: sin2[i],
            cos2: cos2[i].max(0.0),
        };
        match plan {
            Power::One => *out = [1.0; BLOCK],
            // The usual exponents (2 to 128) by squarings, their count a
            // constant of the loop so that it vectorises.
            Power::Whole { n, cutoff } if n.is_power_of_two() && n <= 64 => {
                #[inline(always)]
                fn squared<const K: u32>(
                    cutoff: f32,
                    stored: impl Fn(usize) -> Cosine,
                    out: &mut [f32; BLOCK],
                ) {
                    for i in 0..BLOCK {
                        let mut x = whole_base(stored(i), cutoff);
                        for _ in 0..K {
                            x *= x;
                        }
                        out[i] = x;
                    }
                }
                match n.trailing_zeros() {
                    0 => squared::<0>(cutoff, stored, out),
                    1 => squared::<1>(cutoff, stored, out),
                    2 => squared::<2>(cutoff, stored, out),
                    3 => squared::<3>(cutoff, stored, out),
                    4 => squared::<4>(cutoff, stored, out),
                    5 => squared::<5>(cutoff, stored, out),
                    _ => squared::<6>(cutoff, stored, out),
                }
            }
            Power::Whole { n, .. } => {
                let s = 2.0 * n as f32;
                for i in 0..BLOCK {
                    out[i] = M::pow_cosine(stored(i), s);
                }
            }
            Power::General(s) => {
                for i in 0..BLOCK {
                    out[i] = M::pow_cosine(stored(i), s);
                }
            }
        }
    }

    #[inline(always)]
    fn pow(x: f32, s: f32) -> f32 {
        M::pow(x, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each tier's power of a cosine against `powf` of the exact cosine of
    /// the f32 vectors, over angles from 0 to 180° and the exponents that
    /// pick each plan.
    #[test]
    fn powers_of_cosines_are_within_each_tiers_bound() {
        fn worst<A: Arith<F = f32>>() -> f64 {
            let mut worst: f64 = 0.0;
            for s in [0.0, 1.0, 8.0, 10.0, 32.0, 128.0, 200.0, 7.3] {
                let mut sin2 = [0.0; BLOCK];
                let mut cos = [0.0; BLOCK];
                let mut exact = [0.0; BLOCK];
                for i in 0..BLOCK {
                    let angle = std::f64::consts::PI * i as f64 / (BLOCK - 1) as f64;
                    let a = [0.0f32, 0.0, 1.0];
                    let b = [angle.sin() as f32, 0.0, angle.cos() as f32];
                    (sin2[i], cos[i]) = A::store_cosine(a, b);
                    let bd = b.map(f64::from);
                    exact[i] = spec_pow(bd[2] / (bd[0] * bd[0] + bd[2] * bd[2]).sqrt(), s);
                }
                let mut out = [0.0; BLOCK];
                A::power_pass(A::plan(s), &sin2, &cos, &mut out);
                for i in 0..BLOCK {
                    worst = worst.max((f64::from(out[i]) - exact[i]).abs());
                }
            }
            worst
        }
        assert!(
            worst::<AccurateTier>() < 2e-6,
            "{}",
            worst::<AccurateTier>()
        );
        assert!(worst::<FastTier>() < 1e-4, "{}", worst::<FastTier>());
    }

    #[test]
    fn zero_vectors_are_not_lit() {
        let (sin2, cos) = AccurateTier::store_cosine([0.0; 3], [0.0, 0.0, 1.0]);
        assert!(!AccurateTier::positive(cos));
        let mut out = [0.0; BLOCK];
        AccurateTier::power_pass(
            AccurateTier::plan(8.0),
            &[sin2; BLOCK],
            &[cos; BLOCK],
            &mut out,
        );
        assert_eq!(out, [0.0; BLOCK]);
        let (_, cos) = Reference::store_cosine([0.0; 3], [0.0, 0.0, 1.0]);
        assert!(!Reference::positive(cos));
    }
}

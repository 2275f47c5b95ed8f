//! Branch-free f32 `pow` and `1/sqrt` that the compiler can vectorise (a
//! library `powf` per lane cannot be), at two accuracies: [`Accurate`] for
//! the `accurate` tier, [`Fast`] for the `fast` tier.
//!
//! `pow(x, s) = exp2(s · log2 x)`. `log2` splits `x = m · 2^e` with
//! `m ∈ [√½, √2)` and evaluates `ln m = 2 atanh(u)`, `u = (m − 1)/(m + 1)`,
//! as an odd series in `u` (|u| < 0.172). Its error is relative to `ln m`, so
//! the error of `x^s` stays small for any `s`: near `x = 1`, where a high
//! shininess makes `x^s` sensitive, `log2 x` is small and so is its error.
//! `exp2` rounds `y` to an integer `n` with the 1.5·2^23 trick (no library
//! `round`), evaluates `2^f` on `f ∈ [−½, ½]` by its Taylor polynomial, and
//! builds `2^n` from its bits; results below 2^−126 flush to zero, so high
//! powers of small numbers never produce slow denormals.
//!
//! The polynomials use `mul_add`: one fused instruction where the CPU has
//! FMA, which the kernels are built for at run time (elsewhere it is a
//! slower library call, with the same result).

/// The operations whose accuracy a tier chooses.
pub trait Math {
    /// Terms of the `ln` series.
    const LN_TERMS: usize;
    /// Degree of the `exp2` polynomial.
    const EXP2_DEGREE: usize;
    /// The largest relative error of [`ln_series`] with [`Math::LN_TERMS`]
    /// terms, truncation and rounding (checked by the tests).
    #[cfg(test)]
    const LN_SERIES_ERROR: f64;
    /// The largest relative error of [`exp2`] of degree
    /// [`Math::EXP2_DEGREE`] where its result is normal (checked by the
    /// tests).
    #[cfg(test)]
    const EXP2_ERROR: f64;
    /// The largest `n` for which `(cos²)^n` is taken by multiplication (see
    /// [`Power`]): its relative error grows as `n` times that of `cos²`, a
    /// few 1e-7 (f32 rounding, and a unit vector's length within 4e-7 of 1).
    const MAX_WHOLE: u32;
    /// Use the hardware's estimate of `1/x` alone (1e-4 relative) for the
    /// attenuation, whose error passes linearly into the colour.
    const ESTIMATES: bool;
    /// Take a specular [`Power::Whole`] from `cos²` alone, without the
    /// cross product that gives `sin²`: its error of a few ULP, times `n`,
    /// is within the tier's bound.
    const WHOLE_FROM_COS2: bool;
    /// Test a cone of 30° or more on `cos²` (as every tier tests those past
    /// 45°) and take its power from `cos²` alone, without the cross product
    /// that gives `sin²`: for an exponent up to 128, a few ULP times 64.
    const CONE_FROM_COS2: bool;
    /// Light a block from a light at a point without normalising `VP_pli`,
    /// in a few short passes, where the block and the light allow (see
    /// `kernel::fast_point`).
    const FAST_POINT: bool;

    /// This tier's plan among `powers`.
    fn power(powers: &Powers) -> Power;

    /// `1/√x` for `x > 0`.
    fn rsqrt(x: f32) -> f32;

    /// `x^s` for `x >= 0`, with `0^0 = 1` and the result capped at
    /// [`super::MAX_POWER`].
    #[inline(always)]
    fn pow(x: f32, s: f32) -> f32 {
        let log2_x = log2(x.max(f32::MIN_POSITIVE), Self::LN_TERMS);
        power(x > 0.0, log2_x, s, Self::EXP2_DEGREE)
    }

    /// `max(cos, 0)^s = (cos²)^(s/2)`. Near `cos = 1`, where a high power
    /// is most sensitive, `ln(1 − sin²)` comes from the series in
    /// `u = −sin²/(2 − sin²)`, so the base never goes through an f32 near 1,
    /// whose spacing of 6e-8 times a shininess of 128 would already cost
    /// 1e-5. Farther from 1, `cos²` is split into mantissa and exponent as
    /// in `log2`; both ways share one division and one series.
    #[inline(always)]
    fn pow_cosine(c: Cosine, s: f32) -> f32 {
        let near = c.sin2 < 0.25;
        let (e, m) = split(c.cos2);
        let numerator = if near { -c.sin2 } else { m - 1.0 };
        let denominator = if near { 2.0 - c.sin2 } else { m + 1.0 };
        let e = if near { 0.0 } else { e };
        let log2_cos2 = e + ln_series(numerator / denominator, Self::LN_TERMS) * LOG2_E;
        power(c.positive, 0.5 * log2_cos2, s, Self::EXP2_DEGREE)
    }
}

/// How a tier raises a cosine to a power `s`, chosen once per light and
/// side: `(cos²)^(s/2)`. Where `s/2` is a whole number `n` (the shininess
/// and spot exponents of most scenes: 8, 32, 128) it is `n − 1`
/// multiplications at most, by binary powering, in place of a logarithm, a
/// division and an exponential; the base is `1 − sin²` near 1, so that it is
/// within half an f32 step of the exact `cos²`, and the relative error of
/// the power is about `n` such steps. Bases whose power would be below
/// 2^−125 are flushed to zero first, so that no product is ever denormal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Power {
    /// `s = 0`: 1, even for a cosine of 0 (0^0 = 1).
    One,
    Whole {
        n: u32,
        /// `2^(−125/n)`, rounded up: below it the power is flushed to zero.
        cutoff: f32,
    },
    /// Any other `s`: [`Math::pow_cosine`].
    General(f32),
}

impl Power {
    pub fn new<M: Math>(s: f32) -> Self {
        let half = 0.5 * s;
        if s == 0.0 {
            Self::One
        } else if half.fract() == 0.0 && (1.0..=M::MAX_WHOLE as f32).contains(&half) {
            let n = half as u32;
            let cutoff = (-125.0 / n as f64).exp2() * (1.0 + 1e-6);
            Self::Whole {
                n,
                cutoff: cutoff as f32,
            }
        } else {
            Self::General(s)
        }
    }
}

/// The [`Power`] of one exponent in each tier, planned once per kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Powers {
    accurate: Power,
    fast: Power,
}

impl Powers {
    /// The plans of the exponent 0.
    pub const ONE: Self = Self {
        accurate: Power::One,
        fast: Power::One,
    };

    pub fn new(s: f32) -> Self {
        Self {
            accurate: Power::new::<Accurate>(s),
            fast: Power::new::<Fast>(s),
        }
    }
}

/// The base of a [`Power::Whole`]: `cos²` from whichever of `sin²` and
/// `cos²` holds it without cancellation, zero where `cos ≤ 0` (`positive`
/// false) and where its power would underflow. `(b·…·b)` of it never meets
/// a NaN: a zero vector's NaN `sin²` and `cos²` come with `positive` false.
#[inline(always)]
pub fn whole_base(c: Cosine, cutoff: f32) -> f32 {
    let x = if c.sin2 < 0.25 { 1.0 - c.sin2 } else { c.cos2 };
    if c.positive && x >= cutoff { x } else { 0.0 }
}

/// The angle between two vectors as `sin²` and `cos²`, each without
/// cancellation: `|a×b|² / (|a|²|b|²)` and `(a·b)² / (|a|²|b|²)`, with one
/// division and no square root; and whether `cos > 0`. For a zero vector
/// both are NaN and `positive` is false: "not lit".
#[derive(Clone, Copy, Debug)]
pub struct Cosine {
    pub positive: bool,
    pub sin2: f32,
    pub cos2: f32,
}

#[inline(always)]
pub fn cosine(a: [f32; 3], b: [f32; 3]) -> Cosine {
    let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    let b2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    cosine_over(a, b, 1.0 / (a2 * b2))
}

/// [`cosine`] where `a` is a unit vector (to f32 rounding, or zero) and
/// `inverse_b2` is `1/|b|²`: `1/|a|²`, within about 1e-13 of `2 − |a|²`,
/// costs no division, and none at all where `b` is the same for every
/// vertex.
#[inline(always)]
pub fn cosine_of_unit(a: [f32; 3], b: [f32; 3], inverse_b2: f32) -> Cosine {
    let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    cosine_over(a, b, (2.0 - a2) * inverse_b2)
}

/// [`cosine`]'s `cos²` alone (`sin²` is 1, not computed) where `a` is a unit
/// vector to an ULP or two (as the kernels' normals and `VP_pli` are) and
/// `inverse_b2` is `1/|b|²`: the length of `a` is taken as 1, which leaves
/// `cos²` within about 5.5e-7 relative, and a whole power `n` of it within
/// `n · 5.5e-7`: 5.6e-4 at [`Fast::MAX_WHOLE`] (1024), inside the fast
/// tier's 1/512, for which this is.
#[inline(always)]
pub fn cos2_of_unit(a: [f32; 3], b: [f32; 3], inverse_b2: f32) -> Cosine {
    let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    Cosine {
        positive: dot > 0.0,
        sin2: 1.0,
        cos2: (dot * dot * inverse_b2).min(1.0),
    }
}

/// `sin²` and `cos²` of `a` and `b`, given `1/(|a|²|b|²)`.
#[inline(always)]
fn cosine_over(a: [f32; 3], b: [f32; 3], inverse: f32) -> Cosine {
    let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let cross2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    // Clamped: for a vector so short that `a2·b2` underflows (a half vector
    // of a light almost opposite the viewer) both would be inf or NaN.
    Cosine {
        positive: dot > 0.0,
        sin2: (cross2 * inverse).min(1.0),
        cos2: (dot * dot * inverse).min(1.0),
    }
}

/// About 1e-7 relative error: a few ULP.
pub struct Accurate;

/// About 5e-5 relative error in each polynomial, and 2^-14 in the CPU's
/// reciprocal estimate: far inside the 1/512 bound of the tier.
pub struct Fast;

impl Math for Accurate {
    const LN_TERMS: usize = 5;
    const EXP2_DEGREE: usize = 7;
    #[cfg(test)]
    const LN_SERIES_ERROR: f64 = 3e-7;
    #[cfg(test)]
    const EXP2_ERROR: f64 = 3e-7;
    const MAX_WHOLE: u32 = 32;
    const ESTIMATES: bool = false;
    const WHOLE_FROM_COS2: bool = false;
    const CONE_FROM_COS2: bool = false;
    const FAST_POINT: bool = false;

    fn power(powers: &Powers) -> Power {
        powers.accurate
    }

    #[inline(always)]
    fn rsqrt(x: f32) -> f32 {
        1.0 / x.sqrt()
    }
}

impl Math for Fast {
    const LN_TERMS: usize = 3;
    const EXP2_DEGREE: usize = 4;
    #[cfg(test)]
    const LN_SERIES_ERROR: f64 = 4.1e-6;
    #[cfg(test)]
    const EXP2_ERROR: f64 = 6.2e-5;
    const MAX_WHOLE: u32 = 1024;
    const ESTIMATES: bool = true;
    const WHOLE_FROM_COS2: bool = true;
    const CONE_FROM_COS2: bool = true;
    const FAST_POINT: bool = true;

    fn power(powers: &Powers) -> Power {
        powers.fast
    }

    #[inline(always)]
    fn rsqrt(x: f32) -> f32 {
        rsqrt_fast(x)
    }
}

/// The largest relative error of [`rsqrt_fast`] over the normal f32.
#[cfg(test)]
const RSQRT_FAST_ERROR: f64 = 7.7e-7;

/// `1/√x` for a normal `x` (2^−126 up to the largest f32), within
/// `RSQRT_FAST_ERROR` relative: the fast tier's, in plain arithmetic that
/// every instruction set vectorises (no estimate instruction, no square
/// root, no division: a few multiply-adds on the vector ports).
///
/// Why the bound holds:
///
/// 1. **A guess from the bits.** The bits of a positive f32, read as an
///    integer, are about `2^23 · (log2 x + 127)`: `R − bits/2` is about
///    `−½ log2 x` plus a constant, so `y0` is `1/√x` within a few percent,
///    its relative error a piecewise-smooth function of the mantissa of `x`
///    and of the parity of its exponent.
/// 2. **One period decides all.** `bits(4x) = bits(x) + 2^24`, so
///    `y0(4x) = y0(x)/2` exactly; the products `x·y·y` of both steps are
///    then the same f32 values, and each step's `y` is halved exactly. For
///    every normal `x` the products stay normal (`x·y` is near `√x`, within
///    [2^−64, 2^65]), so the relative error at `x·4^k` is exactly that at
///    `x`: the 2^24 f32 of [1, 4) hold every error this function makes.
/// 3. **A tuned first step.** `y1 = y0·(a − b·x·y0²)` is a Newton step whose
///    coefficients were chosen with `R` to balance its error (the constants
///    of Moroz, Walczyk et al., "Fast calculation of inverse square root
///    with the use of magic constant", 2018): within 6.51e-4.
/// 4. **A plain Newton step.** `y2 = y1·(3/2 − x·y1²/2)` maps a relative
///    error `e` to `−(3/2)e² − (1/2)e³`: from 6.51e-4 to at most 6.36e-7,
///    never above the true value. Its four f32 operations round at most
///    about 2 ULP (1.2e-7) more, either way.
/// 5. **Checked.** `rsqrt_fast_over_every_f32_of_a_period` evaluates all of
///    [1, 4) against f64: the error lies in [−7.69e-7, +1.41e-7].
///
/// Outside the domain: 0 gives a large finite number and subnormals a wrong
/// one; the callers keep their arguments normal.
#[inline(always)]
pub fn rsqrt_fast(x: f32) -> f32 {
    let y = f32::from_bits(0x5f1f_fff9 - (x.to_bits() >> 1));
    let y = y * f32::mul_add(-0.703_952_25, x * y * y, 1.681_913_9);
    y * f32::mul_add(-0.5, x * y * y, 1.5)
}

/// The largest relative error of [`recip_fast`] over its domain.
#[cfg(test)]
const RECIP_FAST_ERROR: f64 = 1.7e-6;

/// The largest argument of [`recip_fast`]: past it the first guess is no
/// longer a normal f32.
pub const RECIP_FAST_MAX: f32 = 4e37;

/// `1/x` for `x` from 2^−126 to [`RECIP_FAST_MAX`], within
/// `RECIP_FAST_ERROR` relative, in plain arithmetic (no division).
///
/// Why the bound holds, as for [`rsqrt_fast`]:
///
/// 1. `y0 = bits⁻¹(R − bits(x))` negates the piecewise-linear logarithm of
///    the bits: `1/x` within about 6%.
/// 2. `bits(2x) = bits(x) + 2^23`, so `y0(2x) = y0(x)/2` exactly, the
///    products `x·y` are the same f32 and every `y` is halved: the 2^23 f32
///    of [1, 2) hold every error the function makes on its domain (where
///    `y0` is normal: `bits(x) ≤ R − 2^23`, about 4.2e37).
/// 3. `y1 = y0·(a − b·x·y0)`, a Newton step with coefficients chosen with
///    `R` (by a search over the period) to balance its error: within
///    1.19e-3.
/// 4. A plain Newton step `y2 = y1·(2 − x·y1)` maps a relative error `e` to
///    exactly `−e²`: at most 1.42e-6, never above the true value; its three
///    f32 operations round about 2 ULP more.
/// 5. `recip_fast_over_every_f32_of_a_period` evaluates all of [1, 2)
///    against f64: the error lies in [−1.66e-6, +1.4e-7].
#[inline(always)]
pub fn recip_fast(x: f32) -> f32 {
    let y = f32::from_bits(0x7ef0_3c00 - x.to_bits());
    let y = y * f32::mul_add(-1.0288, x * y, 2.029_800_2);
    y * f32::mul_add(-x, y, 2.0)
}

const LOG2_E: f32 = std::f32::consts::LOG2_E;

/// log2 of the largest power, [`super::MAX_POWER`] = 1e10.
const LOG2_MAX_POWER: f32 = 33.219_28;

/// `2^(s · log2 x)` where `positive` says `x > 0`; 0^s = 0 and x^0 = 1.
#[inline(always)]
fn power(positive: bool, log2_x: f32, s: f32, exp2_degree: usize) -> f32 {
    let r = exp2((s * log2_x).min(LOG2_MAX_POWER), exp2_degree);
    let r = if positive { r } else { 0.0 };
    if s == 0.0 { 1.0 } else { r }
}

/// log2 of a positive normal `x`.
#[inline(always)]
fn log2(x: f32, ln_terms: usize) -> f32 {
    let (e, m) = split(x);
    e + ln_series((m - 1.0) / (m + 1.0), ln_terms) * LOG2_E
}

/// `x = m · 2^e` with `m ∈ [√½, √2)`, for a positive normal `x` (a
/// non-positive one gives values that the callers discard).
#[inline(always)]
fn split(x: f32) -> (f32, f32) {
    let bits = x.max(f32::MIN_POSITIVE).to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000); // [1, 2)
    let high = m > std::f32::consts::SQRT_2;
    let m = if high { m * 0.5 } else { m };
    let e = if high { e + 1 } else { e };
    (e as f32, m)
}

/// `ln((1 + u)/(1 − u)) = 2 atanh(u) = 2u (1 + u²/3 + u⁴/5 + …)`, `terms`
/// terms, for `|u| ≤ 3 − 2√2 ≈ 0.1716` (the `u` of a mantissa in
/// [√½, √2)), within [`Math::LN_SERIES_ERROR`] relative.
///
/// Why: every term of the series has the sign of `u`, so the omitted ones,
/// `2u Σ_{k ≥ T} u^2k/(2k + 1)`, are at most `u^2T/(2T + 1)/(1 − u²)` of the
/// whole: 3.74e-6 for 3 terms, 2.1e-9 for 5. The Horner sum of positive
/// terms near 1 rounds within about 2 ULP, and the `u` it is given (one
/// subtraction, exact by Sterbenz's lemma, and one division, each rounded
/// once) is within about 1.5 ULP of the exact one. The test
/// `ln_series_over_every_mantissa` takes every f32 mantissa in [√½, √2)
/// through it against f64's `ln`.
#[inline(always)]
fn ln_series(u: f32, terms: usize) -> f32 {
    const ODD_RECIPROCALS: [f32; 5] = [1.0, 1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0];
    let u2 = u * u;
    let mut sum = 0.0;
    for c in ODD_RECIPROCALS[..terms].iter().rev() {
        sum = f32::mul_add(sum, u2, *c);
    }
    2.0 * u * sum
}

/// 2^y, zero below 2^-126.
#[inline(always)]
fn exp2(y: f32, degree: usize) -> f32 {
    const ROUND: f32 = 12_582_912.0; // 1.5 · 2^23
    let y = y.max(-127.0);
    let t = y + ROUND;
    let n = t.to_bits() as i32 - ROUND.to_bits() as i32;
    let f = y - (t - ROUND);
    let scale = f32::from_bits(((n + 127).max(0) as u32) << 23);
    let r = exp2_fraction(f, degree) * scale;
    // From 2^−126 up, `n ≥ −126` and `f ≥ 0` where `n = −126`: a normal
    // result.
    if y < -126.0 { 0.0 } else { r }
}

/// 2^f for `f ∈ [−½, ½]`: the Taylor polynomial of `e^(f ln 2)`, in
/// Horner form with the coefficients `ln(2)^k / k!` (no division at run
/// time), within [`Math::EXP2_ERROR`] relative.
///
/// Why: with `z = f ln 2`, `|z| ≤ 0.3466`, Lagrange's remainder of the
/// degree-`d` polynomial is `z^(d+1)/(d+1)! · e^ξ` for some `ξ` between 0
/// and `z`, so relative to `e^z` it is at most `|z|^(d+1)/(d+1)! · e^|z|`:
/// 5.91e-5 for degree 4, 7.3e-9 for degree 7. The coefficients' rounding
/// and the Horner steps (each a fused multiply-add of a sum near 1) add a
/// few ULP. [`exp2`] scales by `2^n` exactly, so its relative error is this
/// one's wherever the result is normal (and below 2^−126 it is 0). The test
/// `exp2_fraction_densely` takes every 8th f32 of [−½, ½] through it
/// against f64.
#[inline(always)]
fn exp2_fraction(f: f32, degree: usize) -> f32 {
    const COEFFICIENTS: [f32; 8] = [
        1.0,
        std::f32::consts::LN_2,
        0.240_226_5,
        0.055_504_11,
        0.009_618_129,
        0.001_333_355_8,
        0.000_154_035_3,
        0.000_015_252_734,
    ];
    let mut sum = 0.0;
    for c in COEFFICIENTS[..=degree].iter().rev() {
        sum = f32::mul_add(sum, f, *c);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(â·b̂)^s`, the dot product of the unit vectors along `a` and `b`
    /// clamped at zero, with `0^0 = 1`.
    fn pow_cos<M: Math>(a: [f32; 3], b: [f32; 3], s: f32) -> f32 {
        M::pow_cosine(cosine(a, b), s)
    }

    /// Worst relative error of `pow` over a grid of bases and exponents,
    /// against f64.
    fn worst_pow_error<M: Math>() -> f64 {
        let mut worst: f64 = 0.0;
        for i in 1..=2000 {
            let x = i as f32 / 2000.0;
            for s in [0.5_f32, 1.0, 2.0, 7.3, 16.0, 128.0, 1000.0, 10_000.0] {
                let exact = (x as f64).powf(s as f64);
                if exact < 1e-30 {
                    continue;
                }
                let got = M::pow(x, s) as f64;
                worst = worst.max(((got - exact) / exact).abs() / (1.0 + exact.ln().abs()));
            }
        }
        worst
    }

    #[test]
    fn pow_is_accurate_relative_to_the_size_of_its_logarithm() {
        let accurate = worst_pow_error::<Accurate>();
        let fast = worst_pow_error::<Fast>();
        assert!(accurate < 1e-6, "accurate: {accurate:e}");
        assert!(fast < 1e-4, "fast: {fast:e}");
    }

    #[test]
    fn pow_edge_cases() {
        for pow in [<Accurate as Math>::pow, <Fast as Math>::pow] {
            assert_eq!(pow(0.0, 0.0), 1.0, "0^0 = 1");
            assert_eq!(pow(0.0, 3.0), 0.0);
            assert_eq!(pow(0.7, 0.0), 1.0);
            assert_eq!(pow(1.0, 10_000.0), 1.0);
            assert_eq!(pow(0.5, 10_000.0), 0.0, "flushed, not denormal");
            assert_eq!(pow(1e-30, 8.0), 0.0);
            assert!(pow(3.0, 1e4) <= 1e10 && pow(3.0, 1e4) > 9.9e9, "capped");
            assert!((pow(1e-30, 1e-6) - 0.999_931).abs() < 1e-5);
        }
    }

    #[test]
    fn pow_cos_is_accurate_near_one() {
        // Vectors 1e-4 to 1e-1 radians apart, at a shininess of 1e4.
        for i in 1..=1000 {
            let angle = i as f64 * 1e-4;
            let a = [0.0_f32, 0.0, 1.0];
            let b = [angle.sin() as f32, 0.0, angle.cos() as f32];
            // The exact power of the f32 vectors' own angle.
            let bd = b.map(|v| v as f64);
            let cos = bd[2] / (bd[0] * bd[0] + bd[2] * bd[2]).sqrt();
            for s in [128.0_f32, 10_000.0] {
                let exact = cos.powf(s as f64);
                let got = pow_cos::<Accurate>(a, b, s) as f64;
                assert!((got - exact).abs() < 2e-6, "{angle} {s}: {got} {exact}");
                let fast = pow_cos::<Fast>(a, b, s) as f64;
                assert!((fast - exact).abs() < 1e-4, "{angle} {s}: {fast} {exact}");
            }
        }
        assert_eq!(pow_cos::<Accurate>([0.0; 3], [0.0, 0.0, 1.0], 0.0), 1.0);
        assert_eq!(pow_cos::<Accurate>([0.0; 3], [0.0, 0.0, 1.0], 2.0), 0.0);
        assert_eq!(
            pow_cos::<Accurate>([0.0, 0.0, -1.0], [0.0, 0.0, 1.0], 2.0),
            0.0
        );
    }

    #[test]
    fn powers_are_planned_by_tier() {
        let plans = |s: f32| (Power::new::<Accurate>(s), Power::new::<Fast>(s));
        assert_eq!(plans(0.0), (Power::One, Power::One));
        for s in [1.0, 7.0, 0.5, 33.0, 1e-6, 1e4] {
            assert_eq!(plans(s), (Power::General(s), Power::General(s)), "{s}");
        }
        assert!(matches!(plans(64.0).0, Power::Whole { n: 32, .. }));
        assert_eq!(plans(66.0).0, Power::General(66.0));
        assert!(matches!(plans(2048.0).1, Power::Whole { n: 1024, .. }));
        assert_eq!(plans(2050.0).1, Power::General(2050.0));
    }

    /// `x^n` by the binary powering of the kernels, from `whole_base`.
    fn whole_power(c: Cosine, s: f32) -> f32 {
        let Power::Whole { n, cutoff } = Power::new::<Fast>(s) else {
            panic!("{s} is not whole")
        };
        let (mut base, mut result, mut n) = (whole_base(c, cutoff), 1.0f32, n);
        while n > 0 {
            if n & 1 == 1 {
                result *= base;
            }
            base *= base;
            n >>= 1;
        }
        result
    }

    #[test]
    fn whole_powers_are_close_to_the_exact_power_and_never_denormal() {
        let (mut worst_32, mut worst_1024) = (0.0f64, 0.0f64);
        for i in 0..=20_000 {
            // Angles from 0 to 90°, densest near 0.
            let angle = (i as f64 / 20_000.0).powi(3) * std::f64::consts::FRAC_PI_2;
            let a = [0.0_f32, 0.0, 1.0];
            let b = [angle.sin() as f32, 0.0, angle.cos() as f32];
            let bd = b.map(|v| v as f64);
            let cos = bd[2] / (bd[0] * bd[0] + bd[2] * bd[2]).sqrt();
            for (s, worst) in [(64.0_f32, &mut worst_32), (2048.0, &mut worst_1024)] {
                let got = whole_power(cosine(a, b), s);
                assert!(got == 0.0 || got >= f32::MIN_POSITIVE, "{got} is denormal");
                *worst = worst.max((got as f64 - cos.powf(s as f64)).abs());
            }
        }
        assert!(worst_32 < 2e-6, "n = 32: {worst_32:e}");
        assert!(worst_1024 < 5e-4, "n = 1024: {worst_1024:e}");
        // Zero vectors and cosines at or below 0 give 0.
        assert_eq!(whole_power(cosine([0.0; 3], [0.0, 0.0, 1.0]), 8.0), 0.0);
        assert_eq!(
            whole_power(cosine([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]), 8.0),
            0.0
        );
        assert_eq!(
            whole_power(cosine([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), 2.0),
            0.0
        );
    }

    /// The largest relative error below and above the true value of `f`
    /// against `exact` over every f32 from `from` (included) to `to`
    /// (excluded), stepping `step` f32 at a time.
    fn error_range(
        f: impl Fn(f32) -> f32,
        exact: impl Fn(f64) -> f64,
        from: f32,
        to: f32,
        step: usize,
    ) -> (f64, f64) {
        let (mut below, mut above) = (0.0f64, 0.0f64);
        for bits in (from.to_bits()..to.to_bits()).step_by(step) {
            let x = f32::from_bits(bits);
            let want = exact(x as f64);
            let e = (f(x) as f64 - want) / want;
            below = below.min(e);
            above = above.max(e);
        }
        (below, above)
    }

    /// That `f(x·period^k)` is `f(x)·2^−k` exactly, for each `x` of `xs`
    /// and `k` of `ks`: the scaling the proofs of `rsqrt_fast` and
    /// `recip_fast` rest on, at the ends of their domains.
    fn assert_scales(f: fn(f32) -> f32, period: f32, xs: &[f32], ks: &[i32]) {
        for &x in xs {
            for &k in ks {
                let scaled = x * period.powi(k);
                assert_eq!(f(scaled), f(x) * 2f32.powi(-k), "{x}·{period}^{k}");
            }
        }
    }

    /// Every f32 of [1, 4), which holds every error of `rsqrt_fast` (see
    /// its proof), and spot checks of the scaling at the ends of the range.
    #[test]
    fn rsqrt_fast_over_every_f32_of_a_period() {
        let (below, above) = error_range(rsqrt_fast, |x| 1.0 / x.sqrt(), 1.0, 4.0, 1);
        assert!(
            below >= -RSQRT_FAST_ERROR && above <= RSQRT_FAST_ERROR,
            "[{below:e}, {above:e}]"
        );
        // The error is the same at x·4^k: the ends of the normal range.
        assert_scales(
            rsqrt_fast,
            4.0,
            &[1.0, 1.3, 2.9, 3.999_999_8],
            &[-63, -20, 20, 63],
        );
        let smallest = rsqrt_fast(f32::MIN_POSITIVE) as f64 * (f32::MIN_POSITIVE as f64).sqrt();
        let largest = rsqrt_fast(f32::MAX) as f64 * (f32::MAX as f64).sqrt();
        for r in [smallest, largest] {
            assert!((r - 1.0).abs() <= RSQRT_FAST_ERROR, "{r}");
        }
    }

    /// Every f32 of [1, 2), which holds every error of `recip_fast` on its
    /// domain, and the scaling at the ends of the domain.
    #[test]
    fn recip_fast_over_every_f32_of_a_period() {
        let (below, above) = error_range(recip_fast, |x| 1.0 / x, 1.0, 2.0, 1);
        assert!(
            below >= -RECIP_FAST_ERROR && above <= RECIP_FAST_ERROR,
            "[{below:e}, {above:e}]"
        );
        assert_scales(
            recip_fast,
            2.0,
            &[1.0, 1.3, 1.999_999_9],
            &[-126, -60, 60, 124],
        );
        for x in [f32::MIN_POSITIVE, RECIP_FAST_MAX] {
            let r = recip_fast(x) as f64 * x as f64;
            assert!((r - 1.0).abs() <= RECIP_FAST_ERROR, "{x}: {r}");
        }
    }

    /// Every mantissa `m` in [√½, √2) through `ln_series((m − 1)/(m + 1))`,
    /// as `log2` calls it, against f64's `ln m`, for each tier's terms.
    #[test]
    fn ln_series_over_every_mantissa() {
        fn worst<M: Math>() -> f64 {
            let ln = |m: f32| ln_series((m - 1.0) / (m + 1.0), M::LN_TERMS);
            let from = std::f32::consts::FRAC_1_SQRT_2;
            let to = std::f32::consts::SQRT_2;
            let (below, above) = error_range(ln, f64::ln, from, 1.0, 1);
            let (below_1, above_1) = error_range(ln, f64::ln, 1.0f32.next_up(), to, 1);
            assert_eq!(ln(1.0), 0.0);
            below.min(below_1).abs().max(above.max(above_1))
        }
        let (accurate, fast) = (worst::<Accurate>(), worst::<Fast>());
        assert!(
            accurate <= Accurate::LN_SERIES_ERROR,
            "accurate: {accurate:e}"
        );
        assert!(fast <= Fast::LN_SERIES_ERROR, "fast: {fast:e}");
    }

    /// Each tier's `exp2_fraction` against f64's `2^f` on [−½, ½]: every
    /// f32 with `|f|` in [¼, ½], where the truncation error is largest (it
    /// grows as `|f|^(d+1)`), every 64th one down to 2^−24, and 0; `exp2` adds
    /// only an exact scaling.
    #[test]
    fn exp2_fraction_densely() {
        fn worst<M: Math>() -> f64 {
            let f = |x: f32| exp2_fraction(x, M::EXP2_DEGREE);
            let mut worst = (f(0.0) as f64 - 1.0).abs();
            for (from, to, step) in [(0.25, 0.5, 1), (2f32.powi(-24), 0.25, 64)] {
                let (below, above) = error_range(f, f64::exp2, from, to, step);
                let (below_n, above_n) = error_range(|x| f(-x), |x| (-x).exp2(), from, to, step);
                worst = worst.max(below.min(below_n).abs().max(above.max(above_n)));
            }
            worst
        }
        let (accurate, fast) = (worst::<Accurate>(), worst::<Fast>());
        assert!(accurate <= Accurate::EXP2_ERROR, "accurate: {accurate:e}");
        assert!(fast <= Fast::EXP2_ERROR, "fast: {fast:e}");
        for y in [-126.0f32, -100.5, -3.25, 0.0, 0.75, 33.0] {
            let got = exp2(y, Fast::EXP2_DEGREE) as f64;
            let want = (y as f64).exp2();
            assert!(((got - want) / want).abs() <= Fast::EXP2_ERROR, "{y}");
        }
        assert_eq!(exp2(-126.5, Fast::EXP2_DEGREE), 0.0, "flushed below 2^-126");
    }

    #[test]
    fn accurate_rsqrt_is_within_two_ulp() {
        let (below, above) = error_range(Accurate::rsqrt, |x| 1.0 / x.sqrt(), 1.0, 4.0, 1);
        assert!(below >= -2e-7 && above <= 2e-7, "[{below:e}, {above:e}]");
    }
}

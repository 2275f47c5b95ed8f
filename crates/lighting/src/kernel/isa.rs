//! The reciprocals of a block, per instruction set. The light loops need
//! `1/√x` (to normalise `n`, `VP_pli` and `VP_e`) and `1/x` (attenuation,
//! the length of `ĥ`) once per vertex and light; as a square root and a
//! division they occupy the CPU's one divider for about 10 cycles per 16
//! lanes each, which made it the bottleneck of scenes with positional
//! lights. AVX-512 has estimates of both to 2^−14 relative in one pipelined
//! instruction; one Newton step takes them to about 1 ULP, as exact as the
//! square root and the division it replaces (each rounded once), in a few
//! multiply-adds. Elsewhere the plain operations stay: AVX2's estimates have
//! 2^−12, and one step leaves them a few ULP away.
//!
//! The vectoriser cannot produce these instructions from scalar code, so
//! each is a pass over a block array, written with intrinsics.

use super::block::{BLOCK, Block};
use super::point_pass::{ConeOutcome, ConePass, Lanes, PointPass};
use super::variant::{PointLight, Variant};

/// The reciprocals of an instruction set, each on every lane of a block.
pub trait Isa {
    /// `1/√x`, to about 1 ULP, for `x` normal and finite.
    fn rsqrt(x: &[f32; BLOCK], out: &mut [f32; BLOCK]);
    /// Each lane's `n` times [`Isa::rsqrt`] of its squared length, raised
    /// to the smallest normal (zero stays zero).
    fn normalize(n: &mut [[f32; BLOCK]; 3]);
    /// `1/x`, to about 1 ULP, for `x` normal and finite.
    fn recip(x: &[f32; BLOCK], out: &mut [f32; BLOCK]);
    /// `1/x` to 1e-4 relative or better, for `x` normal and finite.
    fn recip_estimate(x: &[f32; BLOCK], out: &mut [f32; BLOCK]);

    /// This instruction set has the fast tier's one pass for a light at a
    /// point ([`super::point_pass`]): [`Isa::cone_pass`] and
    /// [`Isa::point_pass`] may be called.
    const POINT_PASS: bool;
    /// [`super::point_pass`]'s cone pass.
    fn cone_pass(b: &mut Block, p_pli: [f32; 3], cone: &ConePass) -> ConeOutcome;
    /// [`super::point_pass`]'s one pass; `EYE_Z`: the infinite viewer is
    /// GL's eye-space one, `(0, 0, 1)`.
    fn point_pass<V: Variant, P: PointLight, const EYE_Z: bool>(
        b: &mut Block,
        light: &PointPass,
    ) -> Lanes;
}

/// [`Isa::normalize`] in three loops over the block, with `I`'s
/// [`Isa::rsqrt`].
#[inline(always)]
fn normalize_in_loops<I: Isa>(n: &mut [[f32; BLOCK]; 3]) {
    let mut length2 = [0.0; BLOCK];
    for i in 0..BLOCK {
        length2[i] =
            (n[0][i] * n[0][i] + n[1][i] * n[1][i] + n[2][i] * n[2][i]).max(f32::MIN_POSITIVE);
    }
    let mut inverse_length = [0.0; BLOCK];
    I::rsqrt(&length2, &mut inverse_length);
    for axis in n {
        for i in 0..BLOCK {
            axis[i] *= inverse_length[i];
        }
    }
}

/// The square root and division of the language, vectorised by the compiler.
pub struct Plain;

impl Isa for Plain {
    #[inline(always)]
    fn rsqrt(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        for i in 0..BLOCK {
            out[i] = 1.0 / x[i].sqrt();
        }
    }

    #[inline(always)]
    fn normalize(n: &mut [[f32; BLOCK]; 3]) {
        normalize_in_loops::<Self>(n)
    }

    #[inline(always)]
    fn recip(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        for i in 0..BLOCK {
            out[i] = 1.0 / x[i];
        }
    }

    #[inline(always)]
    fn recip_estimate(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        Self::recip(x, out)
    }

    // Its estimates would need Newton steps: the fast tier takes its passes.
    const POINT_PASS: bool = false;

    fn cone_pass(_: &mut Block, _: [f32; 3], _: &ConePass) -> ConeOutcome {
        unreachable!("no one pass without estimates")
    }

    fn point_pass<V: Variant, P: PointLight, const EYE_Z: bool>(
        _: &mut Block,
        _: &PointPass,
    ) -> Lanes {
        unreachable!("no one pass without estimates")
    }
}

/// AVX-512F's `vrsqrt14ps` and `vrcp14ps`, refined by one Newton step. Only
/// for task functions built with AVX-512F, on a CPU that has it: its safe
/// methods rely on that, so it is visible to the kernel module alone, whose
/// `dispatch` names it only for such task functions.
#[cfg(target_arch = "x86_64")]
pub(in crate::kernel) struct Avx512;

#[cfg(target_arch = "x86_64")]
impl Isa for Avx512 {
    #[inline(always)]
    fn rsqrt(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        // SAFETY: `Avx512` is used only by task functions that run where the
        // CPU has AVX-512F (see `dispatch`).
        unsafe { avx512::rsqrt(x, out) }
    }

    #[inline(always)]
    fn normalize(n: &mut [[f32; BLOCK]; 3]) {
        // SAFETY: as in `rsqrt`.
        unsafe { avx512::normalize(n) }
    }

    #[inline(always)]
    fn recip(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        // SAFETY: as in `rsqrt`.
        unsafe { avx512::recip::<true>(x, out) }
    }

    #[inline(always)]
    fn recip_estimate(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        // SAFETY: as in `rsqrt`.
        unsafe { avx512::recip::<false>(x, out) }
    }

    const POINT_PASS: bool = true;

    #[inline(always)]
    fn cone_pass(b: &mut Block, p_pli: [f32; 3], cone: &ConePass) -> ConeOutcome {
        // SAFETY: as in `rsqrt`.
        unsafe { super::point_pass::avx512::cone_pass(b, p_pli, cone) }
    }

    #[inline(always)]
    fn point_pass<V: Variant, P: PointLight, const EYE_Z: bool>(
        b: &mut Block,
        light: &PointPass,
    ) -> Lanes {
        // SAFETY: as in `rsqrt`.
        unsafe { super::point_pass::avx512::point_pass::<V, P, EYE_Z>(b, light) }
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod avx512 {
    use std::arch::x86_64::*;

    use super::BLOCK;

    const LANES: usize = 16;
    // Every load and store below reads whole vectors of a block.
    const _: () = assert!(BLOCK.is_multiple_of(LANES));

    /// `y = rsqrt14(x)`, then `y + y/2 · (1 − x·y·y)`: the residual
    /// `1 − x·y²` comes from a fused multiply-add, so that the step's own
    /// rounding stays below an ULP.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn rsqrt(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        let half = _mm512_set1_ps(0.5);
        let one = _mm512_set1_ps(1.0);
        for i in (0..BLOCK).step_by(LANES) {
            // SAFETY: lanes i..i + 16 are inside both arrays (BLOCK is a
            // multiple of 16); the loads and stores are unaligned ones.
            unsafe {
                let v = _mm512_loadu_ps(x.as_ptr().add(i));
                let y = _mm512_rsqrt14_ps(v);
                let vy = _mm512_mul_ps(v, y);
                let residual = _mm512_fnmadd_ps(vy, y, one);
                let y = _mm512_fmadd_ps(_mm512_mul_ps(y, half), residual, y);
                _mm512_storeu_ps(out.as_mut_ptr().add(i), y);
            }
        }
    }

    /// [`Isa::normalize`] in one pass over the block, the vectors in
    /// registers: the operations of `Plain`'s three loops (the squared
    /// length's products and sums unfused, as the language computes them,
    /// `max` giving the smallest normal for NaN as `f32::max` does), then
    /// [`rsqrt`]'s.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn normalize(n: &mut [[f32; BLOCK]; 3]) {
        let (half, one) = (_mm512_set1_ps(0.5), _mm512_set1_ps(1.0));
        let least = _mm512_set1_ps(f32::MIN_POSITIVE);
        for i in (0..BLOCK).step_by(LANES) {
            // SAFETY: as in `rsqrt`.
            unsafe {
                let v = [0, 1, 2].map(|axis| _mm512_loadu_ps(n[axis].as_ptr().add(i)));
                let length2 = _mm512_add_ps(
                    _mm512_add_ps(_mm512_mul_ps(v[0], v[0]), _mm512_mul_ps(v[1], v[1])),
                    _mm512_mul_ps(v[2], v[2]),
                );
                let x = _mm512_max_ps(length2, least);
                let y = _mm512_rsqrt14_ps(x);
                let residual = _mm512_fnmadd_ps(_mm512_mul_ps(x, y), y, one);
                let y = _mm512_fmadd_ps(_mm512_mul_ps(y, half), residual, y);
                for axis in 0..3 {
                    _mm512_storeu_ps(n[axis].as_mut_ptr().add(i), _mm512_mul_ps(v[axis], y));
                }
            }
        }
    }

    /// `y = rcp14(x)`, then, if `refine`, `y + y·(1 − x·y)`.
    ///
    /// # Safety
    /// The CPU has AVX-512F (the function is inlined into callers built
    /// with it).
    #[inline(always)]
    pub(in crate::kernel) unsafe fn reciprocal(x: __m512, refine: bool) -> __m512 {
        // SAFETY: the caller's CPU has AVX-512F.
        unsafe {
            let y = _mm512_rcp14_ps(x);
            if refine {
                let residual = _mm512_fnmadd_ps(x, y, _mm512_set1_ps(1.0));
                _mm512_fmadd_ps(y, residual, y)
            } else {
                y
            }
        }
    }

    /// [`reciprocal`] of every lane of `x`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn recip<const REFINE: bool>(x: &[f32; BLOCK], out: &mut [f32; BLOCK]) {
        for i in (0..BLOCK).step_by(LANES) {
            // SAFETY: as in `rsqrt`.
            unsafe {
                let v = _mm512_loadu_ps(x.as_ptr().add(i));
                let y = reciprocal(v, REFINE);
                _mm512_storeu_ps(out.as_mut_ptr().add(i), y);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every exponent of the normal f32 range, with mantissas spread over
    /// [1, 2), and the ends: the smallest normal, the largest finite.
    fn normal_inputs() -> Vec<f32> {
        let mut x: Vec<f32> = (-126..=127)
            .flat_map(|e| (0..16).map(move |m| (1.0 + m as f64 / 16.0 + 1e-3) * 2f64.powi(e)))
            .filter(|x| *x < f32::MAX as f64)
            .map(|x| x as f32)
            .collect();
        x.extend([f32::MIN_POSITIVE, f32::MAX, 1.0, 2.0, 0.5]);
        x
    }

    /// The largest error of `f` against `exact` over `inputs`, relative, in
    /// ULP of 1 (2^−23): a correctly rounded result is within 0.5.
    fn worst_ulps(
        f: fn(&[f32; BLOCK], &mut [f32; BLOCK]),
        exact: fn(f64) -> f64,
        inputs: &[f32],
    ) -> f64 {
        let mut worst: f64 = 0.0;
        for chunk in inputs.chunks(BLOCK) {
            let mut x = [1.0f32; BLOCK];
            x[..chunk.len()].copy_from_slice(chunk);
            let mut out = [0.0f32; BLOCK];
            f(&x, &mut out);
            for (x, y) in x.iter().zip(out) {
                let e = exact(*x as f64);
                assert!(y.is_finite() && y > 0.0, "{x} gave {y}");
                worst = worst.max(((y as f64 - e) / e).abs() * 2f64.powi(23));
            }
        }
        worst
    }

    /// The inputs whose reciprocal is normal too.
    fn recip_inputs() -> Vec<f32> {
        let mut x = normal_inputs();
        x.retain(|x| *x <= 2f32.powi(126));
        x
    }

    fn rsqrt_exact(x: f64) -> f64 {
        1.0 / x.sqrt()
    }

    fn recip_exact(x: f64) -> f64 {
        1.0 / x
    }

    #[test]
    fn plain_reciprocals_are_within_an_ulp() {
        let rsqrt = worst_ulps(Plain::rsqrt, rsqrt_exact, &normal_inputs());
        let recip = worst_ulps(Plain::recip, recip_exact, &recip_inputs());
        assert!(rsqrt <= 1.0, "rsqrt: {rsqrt} ULP");
        assert!(recip <= 0.5, "recip: {recip} ULP");
    }

    /// Over the whole normal range, from the smallest normal to the
    /// largest finite (to 2^126 for `1/x`, whose result is subnormal
    /// beyond): the refined estimates within 1.5 ULP, the bare `1/x` within
    /// its 2^−14. Subnormals and 0 are outside their domain: the kernels
    /// raise squared lengths to the smallest normal and clamp the
    /// attenuation's denominator into [1e-10, 1e37] first.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_estimates_are_close_over_the_normal_range() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        let (normal, recip_normal) = (normal_inputs(), recip_inputs());
        let rsqrt = worst_ulps(Avx512::rsqrt, rsqrt_exact, &normal);
        let recip = worst_ulps(Avx512::recip, recip_exact, &recip_normal);
        assert!(rsqrt <= 1.5, "rsqrt: {rsqrt} ULP");
        assert!(recip <= 1.5, "recip: {recip} ULP");
        let estimate = 2f64.powi(23 - 14);
        let recip = worst_ulps(Avx512::recip_estimate, recip_exact, &recip_normal);
        assert!(recip <= estimate, "recip estimate: {recip} ULP");
    }

    /// AVX-512's one pass of [`Isa::normalize`] is its three loops, bit for
    /// bit: normals of every scale from 1e-20 to 1e18, zero, and NaN.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_normalize_is_its_three_loops() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        let mut rng = crate::test_rng::Rng::new(0x5851_f42d_4c95_7f2du64);
        let mut random = || rng.signed() as f32;
        for round in 0..100 {
            let scale = 10f32.powi(round % 39 - 20);
            let mut n = [[0.0f32; BLOCK]; 3];
            for axis in &mut n {
                for x in axis.iter_mut() {
                    *x = random() * scale;
                }
            }
            n[0][3] = 0.0;
            n[1][3] = 0.0;
            n[2][3] = 0.0;
            n[1][5] = f32::NAN;
            let mut by_loops = n;
            normalize_in_loops::<Avx512>(&mut by_loops);
            Avx512::normalize(&mut n);
            for axis in 0..3 {
                for i in 0..BLOCK {
                    assert_eq!(
                        n[axis][i].to_bits(),
                        by_loops[axis][i].to_bits(),
                        "{round} {i}"
                    );
                }
            }
        }
    }
}

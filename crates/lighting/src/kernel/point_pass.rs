//! A light at a point in the fast tier, in one pass over the block where
//! the instruction set has the estimates of `1/x` and `1/√x` that need no
//! Newton step (AVX-512's `vrcp14ps` and `vrsqrt14ps`, 2^−14 relative).
//! Without the Newton chains a vertex's work is short enough that one pass
//! does it all in registers: `d = P_pli − V`, its length, the attenuation,
//! the diffuse term, the halfway vector and the specular power, with the
//! block's colours loaded and stored once per light. A cone takes a first
//! pass of its own (its test, and its power), so that a block outside it
//! costs that pass alone.
//!
//! Two tests per lane are made once per batch and light instead where they
//! can be: a light outside the box of the batch's positions, at a distance
//! well within `UNSCALED_DISTANCE2` of all of it
//! (`Kernel::lights_in_range`), needs no lane's range tested, and an
//! attenuation whose `k` are none negative and whose `k0` is at least the
//! least denominator needs no floor.
//!
//! With GL's eye-space infinite viewer, `VP_e = (0, 0, 1)`, the halfway
//! vector is `u = (d_x, d_y, d_z + |d|)`: its `|u|²` takes the
//! `d_x² + d_y²` that `|d|²` formed and two operations, where the general
//! form takes six, and keeps two of `d`'s three registers free. They are the
//! operations the general form does on the same values (its products with
//! 0 and 1 are exact), so the colours are the same bit for bit
//! (`eye_along_z_is_the_general_pass_bit_for_bit`).
//!
//! Which lights and blocks come here is `fast_point`'s choice (it makes
//! each light's plan, [`PointPass`] and [`ConePass`]): whole powers `2^K`
//! of `cos²` up to `K = 6` (or none), and lanes within
//! `UNSCALED_DISTANCE2` of the light; the lanes outside are left to the
//! general path.
//!
//! # The estimates and the bound
//!
//! The one pass spends its share of the bound of 1/512 on estimates, each
//! with a relative error `ε ≤ 2^−14` (checked over every f32 of a period
//! by `estimates_over_every_f32_of_a_period`):
//!
//! - **`1/|d|`** (`vrsqrt14ps` of `|d|²`) multiplies the diffuse term's
//!   `n·d`: a relative error `ε` of the term.
//! - **`|d|`**, for the attenuation and the halfway vector, is `|d|²/|d|`
//!   with one Newton step on the estimate, `t(1 + (1 − t·r)/2)` for
//!   `t = |d|²·r`: `−(3/2)e² + O(e³)`, about 6e-9, plus a few ULP of
//!   rounding. The halfway vector `u = d + |d|·VP_e` needs it: a relative
//!   error `δ` of `|d|` against `|d|` turns `ĥ` by `δ·tan(α)/2`, `α` half
//!   the angle between `VP_pli` and `VP_e`, which no power could afford
//!   near `α = 90°`.
//! - **The attenuation** is `vrcp14ps` of its denominator: `ε`, plus the
//!   denominator's own few ULP.
//! - **The spot's `cos²`** is `((V − P_pli)·ŝ · r)²`, with `r` the
//!   estimate of `1/|d|` that the light's pass then reads for its diffuse
//!   term and its `|d|`: `2ε` and a few ULP (the direction `ŝ` is taken as
//!   unit: its f32 length is within an ULP of 1); its power `n`
//!   multiplies that by `n`. Up to [`MAX_UNREFINED_SPOT_HALF_EXPONENT`]
//!   (4, a spot exponent of 8) the estimate stands alone: at most
//!   `8ε = 4.9e-4`; above, the `cos²` is `((V − P_pli)·ŝ)²` times the
//!   reciprocal of `|d|²` with a Newton step, to within `ε² +` 2 ULP.
//! - **The specular `cos²`** is `(n·u)² · rcp14(|u|²)`: its power `n`
//!   gives `nε`. Up to [`MAX_UNREFINED_SPECULAR_HALF_EXPONENT`] (16, a
//!   shininess of 32) the estimate stands alone: at most `16ε = 9.8e-4`;
//!   above, a Newton step as for the spot.
//!
//! **How they add up.** A light's terms are products: the ambient term
//! `att·spot·a`, the diffuse `att·spot·cos·d`, the specular
//! `att·spot·gate·cos^s·s`. Their relative errors add: at most
//! `ε + 8ε + 16ε` (attenuation, spot power, specular power) plus a few
//! ULP times the exponents, 1.54e-3, for a specular term, and `ε + 8ε +
//! ε = 6.1e-4` for a diffuse one. Without negative colours (the case the
//! tier's bound is promised for: a request with negative colours is warned
//! that large terms may cancel) every term is at least 0, so where the
//! clamped colour is below 1 the sum of the terms is below 1 and its
//! error at most the largest relative error of a term, 1.54e-3, whatever
//! the number of lights; where the sum is 1 or more, the clamped colour
//! moves only where the computed sum falls below 1, by less than that
//! error again. 1.54e-3 leaves 4.1e-4 of the bound of 1/512 = 1.95e-3 for
//! the f32 rounding of the inputs and of the sums, and for the flushing of
//! powers below 2^−125 to that value (an absolute error below 3e-38).

use super::block::Block;

/// The largest half exponent `n` of a spot whose power takes the square of
/// the estimate of `1/|d|` without a Newton step (see the module docs).
pub(super) const MAX_UNREFINED_SPOT_HALF_EXPONENT: u32 = 4;

/// The largest half exponent `n` of a shininess whose power takes the
/// estimate of `1/|u|²` without a Newton step (see the module docs).
pub(super) const MAX_UNREFINED_SPECULAR_HALF_EXPONENT: u32 = 16;

/// Where the cone's pass finds a lane's cosine within this of the cutoff's,
/// the lane might be on either side, and the exact test decides. The pass
/// tests the cosine whose square it raises to the spot's power,
/// `(V − P_pli)·ŝ` times the estimate of `1/|d|`: the estimate's relative
/// `2^−14` and the product's rounding of a cosine of at most 1 (6.11e-5),
/// and the f32 rounding of `d`, of the dot products and of `ŝ`'s length, a
/// few ULP of the cosine (below 1e-6).
pub(super) const CONE_PASS_BAND: f32 = 1e-4;

const _: () = assert!(CONE_PASS_BAND >= 6.11e-5 + 1e-6);

/// The largest relative error of `avx512::distance` (see there).
#[cfg(test)]
const DISTANCE_ERROR: f64 = 1.8e-7;

/// The largest relative error of `avx512::whole_power` of `2^squarings`
/// (see there): a reciprocal's error `e` (`2^−14` as estimated, `e² +` 2
/// ULP refined) and an ULP of rounding in the product, each squaring
/// doubling the relative error and adding half an ULP.
#[cfg(test)]
fn power_error(squarings: u32, refine: bool) -> f64 {
    let ulp = f64::from(f32::EPSILON);
    let estimate = 2f64.powi(-14);
    let reciprocal = if refine {
        estimate * estimate + 2.0 * ulp
    } else {
        estimate
    };
    let n = 2f64.powi(squarings as i32);
    ((1.0 + reciprocal) * (1.0 + ulp)).powf(n) * (1.0 + ulp / 2.0).powf(n) - 1.0
}

/// A power `(cos²)^(2^K)` of the one pass: `x = max(cos², cutoff)` squared
/// `K` times, where the cutoff (that of [`crate::fastmath::Power::Whole`])
/// keeps every square normal; below it the power is that of the cutoff,
/// about 2^−125, in place of a smaller one. `None`: the exponent is 0,
/// the power 1.
#[derive(Clone, Copy, Debug)]
pub(super) struct Squarings {
    pub squarings: u32,
    pub cutoff: f32,
    /// A Newton step on the reciprocal estimate (see the module docs).
    pub refine: bool,
}

/// What the one pass reads of a light at a point: its plan, made once per
/// task.
#[derive(Clone, Copy, Debug)]
pub(super) struct PointPass {
    pub p_pli: [f32; 3],
    /// k0, k1, k2, and the least denominator (1 with the attenuation
    /// clamp, else that of the largest attenuation).
    pub k: [f32; 3],
    pub least: f32,
    /// The denominator may fall below `least`: the pass raises it.
    pub floor: bool,
    /// Every lane is within `UNSCALED_DISTANCE2`: the pass tests none.
    pub in_range: bool,
    /// The infinite viewer's direction.
    pub eye: [f32; 3],
    /// The light's ambient product, `None` where it is zero.
    pub ambient: Option<[f32; 3]>,
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    /// The specular terms go to the secondary colour.
    pub separate: bool,
    /// The specular power; `None` for an exponent of 0.
    pub power: Option<Squarings>,
}

/// What the cone's pass reads.
#[derive(Clone, Copy, Debug)]
pub(super) struct ConePass {
    /// `ŝ`, negated: `d·(−ŝ) = (V − P_pli)·ŝ`.
    pub away: [f32; 3],
    /// The lanes whose estimated cosine (of the angle at the light between
    /// the axis and the vertex) is above this may be inside the cone: the
    /// cutoff's cosine less [`CONE_PASS_BAND`]; for a cone of 90°, 0, or
    /// −∞ with an exponent of 0 (whose power is 1 even behind the light).
    pub maybe_above: f32,
    /// The lanes whose estimated cosine is at least this are inside for
    /// sure: the cutoff's cosine plus [`CONE_PASS_BAND`], or −∞ for a cone
    /// of 90°. Between the two the exact test decides.
    pub sure_from: f32,
    pub power: Option<Squarings>,
    /// As [`PointPass::in_range`].
    pub in_range: bool,
}

/// What the cone's pass found.
pub(super) struct ConeOutcome {
    /// Some lane's `|d|²` is outside `UNSCALED_DISTANCE2`.
    pub out_of_range: bool,
    /// Some lane may be inside the cone.
    pub any_inside: bool,
    /// Some lane's estimated cosine lies within [`CONE_PASS_BAND`] of the
    /// cutoff's: the exact test decides the block.
    pub near_edge: bool,
}

/// The lanes of a block whose `|d|²` is outside `UNSCALED_DISTANCE2`, a
/// bit per lane: the one pass added nothing to them.
pub(super) type Lanes = u64;

// One bit per lane.
const _: () = assert!(super::block::BLOCK <= Lanes::BITS as usize);

/// The bits of the ends of `UNSCALED_DISTANCE2`: a positive f32 is in the
/// range exactly where its bits minus the first's, unsigned, are below the
/// span (NaN and negative ones are above).
const RANGE_START_BITS: u32 = super::positional::UNSCALED_DISTANCE2.start.to_bits();
const RANGE_SPAN_BITS: u32 = super::positional::UNSCALED_DISTANCE2.end.to_bits() - RANGE_START_BITS;

/// The passes in AVX-512F intrinsics. Each function is unsafe for one
/// reason, that the CPU must have AVX-512F, and is inlined into the task
/// functions built with it (a function with the target feature of its own
/// would be too large to be inlined, and the block's data would go through
/// the stack): their bodies are the intrinsics, without a block each.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_op_in_unsafe_fn)]
pub(super) mod avx512 {
    use std::arch::x86_64::*;

    use super::{
        Block, ConeOutcome, ConePass, Lanes, PointPass, RANGE_SPAN_BITS, RANGE_START_BITS,
        Squarings,
    };
    use crate::kernel::block::BLOCK;
    use crate::kernel::isa::avx512::reciprocal;
    use crate::kernel::variant::{PointLight, Variant};

    const LANES: usize = 16;
    const _: () = assert!(BLOCK.is_multiple_of(LANES));

    /// Lanes `i..i + 16` of `a`.
    ///
    /// # Safety
    /// `i + 16 <= BLOCK`.
    #[inline(always)]
    unsafe fn load(a: &[f32; BLOCK], i: usize) -> __m512 {
        // SAFETY: the caller keeps i + 16 within the array.
        unsafe { _mm512_loadu_ps(a.as_ptr().add(i)) }
    }

    /// Lanes `i..i + 16` of each of `a`.
    ///
    /// # Safety
    /// As [`load`].
    #[inline(always)]
    unsafe fn load3(a: &[[f32; BLOCK]; 3], i: usize) -> [__m512; 3] {
        // SAFETY: as in `load`.
        unsafe { [load(&a[0], i), load(&a[1], i), load(&a[2], i)] }
    }

    /// # Safety
    /// As [`load`].
    #[inline(always)]
    unsafe fn store(a: &mut [f32; BLOCK], i: usize, v: __m512) {
        // SAFETY: as in `load`.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr().add(i), v) }
    }

    #[inline(always)]
    unsafe fn splat3(x: [f32; 3]) -> [__m512; 3] {
        [
            _mm512_set1_ps(x[0]),
            _mm512_set1_ps(x[1]),
            _mm512_set1_ps(x[2]),
        ]
    }

    /// `a·b`, a multiplication and two fused multiply-adds.
    #[inline(always)]
    unsafe fn dot(a: [__m512; 3], b: [__m512; 3]) -> __m512 {
        _mm512_fmadd_ps(
            a[2],
            b[2],
            _mm512_fmadd_ps(a[1], b[1], _mm512_mul_ps(a[0], b[0])),
        )
    }

    /// `a_x² + a_y²` as [`dot`] forms it on the way to `a·a`.
    #[inline(always)]
    unsafe fn squares_across(a: [__m512; 3]) -> __m512 {
        _mm512_fmadd_ps(a[1], a[1], _mm512_mul_ps(a[0], a[0]))
    }

    /// `p − q`.
    #[inline(always)]
    unsafe fn difference(p: [__m512; 3], q: [__m512; 3]) -> [__m512; 3] {
        [
            _mm512_sub_ps(p[0], q[0]),
            _mm512_sub_ps(p[1], q[1]),
            _mm512_sub_ps(p[2], q[2]),
        ]
    }

    /// The lanes of `d2` outside `UNSCALED_DISTANCE2`.
    #[inline(always)]
    unsafe fn out_of_range(d2: __m512) -> __mmask16 {
        let offset = _mm512_sub_epi32(
            _mm512_castps_si512(d2),
            _mm512_set1_epi32(RANGE_START_BITS as i32),
        );
        _mm512_cmpge_epu32_mask(offset, _mm512_set1_epi32(RANGE_SPAN_BITS as i32))
    }

    /// The vectors of a block: each step of the passes below takes all of
    /// them before the next step, so that the CPU has the block's four
    /// independent chains of dependent operations side by side.
    const VECTORS: usize = BLOCK / LANES;

    /// A value of every lane of a block.
    type Lanes4 = [__m512; VECTORS];

    /// `|d|` from `|d|²` and the estimate `r` of `1/|d|`: `t = |d|²·r`,
    /// then one Newton step, `t + (t/2)·(1 − t·r)`, whose residual comes
    /// from a fused multiply-add. A relative error `e` of `r` leaves
    /// `−(3/2)e² − (1/2)e³` (`|e| ≤ 2^−14`: 5.6e-9) and the step's
    /// rounding an ULP or two: within [`super::DISTANCE_ERROR`], which
    /// `distance_over_every_f32_of_a_period` checks. As for `rsqrt_fast`,
    /// `rsqrt14(4x) = rsqrt14(x)/2` exactly, so the f32 of [1, 4) hold every
    /// error of the normal range.
    #[inline(always)]
    pub(super) unsafe fn distance(d2: __m512, r: __m512) -> __m512 {
        let t = _mm512_mul_ps(d2, r);
        let residual = _mm512_fnmadd_ps(t, r, _mm512_set1_ps(1.0));
        _mm512_fmadd_ps(_mm512_mul_ps(t, _mm512_set1_ps(0.5)), residual, t)
    }

    /// The spot's estimated cosine `(V − P_pli)·ŝ/|d|`, from `along =
    /// (V − P_pli)·ŝ` and the estimate `r` of `1/|d|`, and its square, the
    /// `cos²` of the spot's unrefined power: relative errors of `2^−14` and
    /// twice that, and an ULP or two of rounding (see the module docs and
    /// [`super::CONE_PASS_BAND`]; `spot_power_of_the_estimate_densely`
    /// checks the powers).
    #[inline(always)]
    pub(super) unsafe fn spot_cosine(along: __m512, r: __m512) -> (__m512, __m512) {
        let cos = _mm512_mul_ps(along, r);
        (cos, _mm512_mul_ps(cos, cos))
    }

    /// `(numerator / denominator)^(2^K)` of every lane by the plan `power`
    /// (see [`Squarings`]), 0 on the lanes outside `keep`; 1 for `None`.
    /// With `numerator/denominator` a `cos²` in [0, 1] whose power is
    /// normal, the relative error is that of the reciprocal (`2^−14`, or
    /// about 2 ULP refined) and of the product's rounding, each multiplied
    /// by `2^K`: within [`super::power_error`], which `whole_power_densely`
    /// checks.
    #[inline(always)]
    pub(super) unsafe fn whole_power(
        numerator: Lanes4,
        denominator: Lanes4,
        power: Option<Squarings>,
        keep: [__mmask16; VECTORS],
    ) -> Lanes4 {
        let Some(power) = power else {
            return ones(keep);
        };
        let mut cos2 = [_mm512_setzero_ps(); VECTORS];
        for v in 0..VECTORS {
            cos2[v] = _mm512_mul_ps(numerator[v], reciprocal(denominator[v], power.refine));
        }
        raise(cos2, power, keep)
    }

    /// 1 on the lanes of `keep`, 0 on the others: the power of an
    /// exponent of 0.
    #[inline(always)]
    unsafe fn ones(keep: [__mmask16; VECTORS]) -> Lanes4 {
        keep.map(|keep| _mm512_maskz_mov_ps(keep, _mm512_set1_ps(1.0)))
    }

    /// `cos²` raised by the plan `power`, 0 on the lanes outside `keep`:
    /// `max(cos², cutoff)` squared `K` times, the mask taken by the last
    /// operation. `K` is a constant of each of its instances, so that the
    /// squarings are straight code.
    #[inline(always)]
    pub(super) unsafe fn raise(
        cos2: Lanes4,
        power: Squarings,
        keep: [__mmask16; VECTORS],
    ) -> Lanes4 {
        let cutoff = _mm512_set1_ps(power.cutoff);
        match power.squarings {
            0 => raise_by::<0>(cos2, cutoff, keep),
            1 => raise_by::<1>(cos2, cutoff, keep),
            2 => raise_by::<2>(cos2, cutoff, keep),
            3 => raise_by::<3>(cos2, cutoff, keep),
            4 => raise_by::<4>(cos2, cutoff, keep),
            5 => raise_by::<5>(cos2, cutoff, keep),
            _ => raise_by::<6>(cos2, cutoff, keep),
        }
    }

    /// [`raise`] of `K` squarings.
    #[inline(always)]
    unsafe fn raise_by<const K: u32>(
        cos2: Lanes4,
        cutoff: __m512,
        keep: [__mmask16; VECTORS],
    ) -> Lanes4 {
        let mut x = cos2;
        for v in 0..VECTORS {
            x[v] = if K == 0 {
                _mm512_maskz_max_ps(keep[v], x[v], cutoff)
            } else {
                _mm512_max_ps(x[v], cutoff)
            };
        }
        for squaring in 1..=K {
            for v in 0..VECTORS {
                x[v] = if squaring == K {
                    _mm512_maskz_mul_ps(keep[v], x[v], x[v])
                } else {
                    _mm512_mul_ps(x[v], x[v])
                };
            }
        }
        x
    }

    /// The cone's pass: `d` of every lane into `vp_pli`, `|d|²` into
    /// `distance2`, the estimate of `1/|d|` into `inverse_distance`, and the
    /// spot's power into `power`, 0 on the lanes outside the cone for sure.
    /// The test takes the estimated cosine, `(V − P_pli)·ŝ` times the
    /// estimate of `1/|d|` (see [`super::CONE_PASS_BAND`]); a lane near the
    /// edge keeps its power for the exact test to keep or zero.
    #[inline(always)]
    pub(in crate::kernel) unsafe fn cone_pass(
        b: &mut Block,
        p_pli: [f32; 3],
        cone: &ConePass,
    ) -> ConeOutcome {
        let light = splat3(p_pli);
        let away = splat3(cone.away);
        let maybe_above = _mm512_set1_ps(cone.maybe_above);
        let sure_from = _mm512_set1_ps(cone.sure_from);
        // Above the unrefined exponents, the power's `cos²` takes the
        // reciprocal of `|d|²` with a Newton step.
        let refine = cone.power.is_some_and(|power| power.refine);
        let zero = _mm512_setzero_ps();
        let (mut out, mut near, mut inside): (__mmask16, __mmask16, __mmask16) = (0, 0, 0);
        let mut cos2 = [zero; VECTORS];
        let mut maybe: [__mmask16; VECTORS] = [0; VECTORS];
        for v in 0..VECTORS {
            let i = v * LANES;
            // SAFETY: i + 16 <= BLOCK.
            unsafe {
                let d = difference(light, load3(&b.p, i));
                let d2 = dot(d, d);
                if !cone.in_range {
                    out |= out_of_range(d2);
                }
                for axis in 0..3 {
                    store(&mut b.vp_pli[axis], i, d[axis]);
                }
                store(&mut b.distance2, i, d2);
                let r = _mm512_rsqrt14_ps(d2);
                store(&mut b.inverse_distance, i, r);
                let along = dot(d, away);
                let (cos, unrefined) = spot_cosine(along, r);
                maybe[v] = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cos, maybe_above);
                inside |= maybe[v];
                near |= _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(maybe[v], cos, sure_from);
                cos2[v] = if refine {
                    _mm512_mul_ps(_mm512_mul_ps(along, along), reciprocal(d2, true))
                } else {
                    unrefined
                };
            }
        }
        let power = match cone.power {
            Some(power) => raise(cos2, power, maybe),
            None => ones(maybe),
        };
        for v in 0..VECTORS {
            // SAFETY: v·16 + 16 <= BLOCK.
            unsafe { store(&mut b.power, v * LANES, power[v]) };
        }
        ConeOutcome {
            out_of_range: out != 0,
            any_inside: inside != 0,
            near_edge: near != 0,
        }
    }

    /// Adds the terms of the light `c` to every lane of `b` whose `|d|²`
    /// is within `UNSCALED_DISTANCE2`, and returns the others (always none
    /// after a cone's pass, which read `d`, `|d|²`, the estimate of `1/|d|`
    /// and the spot factor from the
    /// block), for a light of the kind `P` in a scene of the variant `V`.
    ///
    /// Inlined where the build optimises. A debug build inlines nothing
    /// else, and the locals of each of its instances (a dozen per task
    /// function) would add up in the task function's one frame, past a
    /// thread's stack: there it keeps a frame of its own.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub(in crate::kernel) unsafe fn point_pass<V: Variant, P: PointLight, const EYE_Z: bool>(
        b: &mut Block,
        c: &PointPass,
    ) -> Lanes {
        let light = splat3(c.p_pli);
        let [k0, k1, k2] = splat3(c.k);
        let least = _mm512_set1_ps(c.least);
        let (zero, one) = (_mm512_setzero_ps(), _mm512_set1_ps(1.0));
        let mut outside: Lanes = 0;
        let mut d = [[zero; 3]; VECTORS];
        // `d_x² + d_y²`, the first two terms of `|d|²`.
        let mut across = [zero; VECTORS];
        let mut n_dot_d = [zero; VECTORS];
        let mut distance = [zero; VECTORS];
        let mut lit = [zero; VECTORS];
        let mut lit_lanes: [__mmask16; VECTORS] = [0; VECTORS];
        let mut factor = [zero; VECTORS];
        for v in 0..VECTORS {
            let i = v * LANES;
            // SAFETY: i + 16 <= BLOCK.
            unsafe {
                let (d2, lanes) = if P::CONE {
                    d[v] = load3(&b.vp_pli, i);
                    if EYE_Z {
                        across[v] = squares_across(d[v]);
                    }
                    (load(&b.distance2, i), !0)
                } else {
                    d[v] = difference(light, load3(&b.p, i));
                    // `dot(d, d)`, by the same operations.
                    across[v] = squares_across(d[v]);
                    let d2 = _mm512_fmadd_ps(d[v][2], d[v][2], across[v]);
                    if c.in_range {
                        (d2, !0)
                    } else {
                        let out = out_of_range(d2);
                        outside |= Lanes::from(out) << i;
                        (d2, !out)
                    }
                };
                n_dot_d[v] = dot(load3(&b.n, i), d[v]);
                let inverse_distance = if P::CONE {
                    // The cone's pass estimated it.
                    load(&b.inverse_distance, i)
                } else {
                    _mm512_rsqrt14_ps(d2)
                };
                if P::ATTENUATED || V::SPEC {
                    distance[v] = self::distance(d2, inverse_distance);
                }
                // `att_i · spot_i`, 0 on the lanes out of range.
                let attenuation = if P::ATTENUATED {
                    let mut denominator =
                        _mm512_fmadd_ps(k2, d2, _mm512_fmadd_ps(k1, distance[v], k0));
                    if c.floor {
                        // `max` gives its second operand where the first is NaN.
                        denominator = _mm512_max_ps(denominator, least);
                    }
                    _mm512_maskz_rcp14_ps(lanes, denominator)
                } else {
                    _mm512_maskz_mov_ps(lanes, one)
                };
                factor[v] = if P::CONE {
                    _mm512_mul_ps(attenuation, load(&b.power, i))
                } else {
                    attenuation
                };
                lit_lanes[v] = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(lanes, n_dot_d[v], zero);
                lit[v] = _mm512_maskz_mul_ps(lit_lanes[v], n_dot_d[v], inverse_distance);
            }
        }
        let mut gate = factor;
        // The block has visibility masks: `visible` is not all ones.
        if b.masks.is_some() {
            for v in 0..VECTORS {
                // SAFETY: v·16 + 16 <= BLOCK.
                let visible = unsafe { load(&b.visible, v * LANES) };
                lit[v] = _mm512_mul_ps(lit[v], visible);
                gate[v] = _mm512_mul_ps(gate[v], visible);
            }
        }
        let diffuse = splat3(c.diffuse);
        let mut primary = [[zero; 3]; VECTORS];
        for v in 0..VECTORS {
            // SAFETY: v·16 + 16 <= BLOCK.
            primary[v] = unsafe { load3(&b.primary, v * LANES) };
            match c.ambient {
                Some(ambient) => {
                    let ambient = splat3(ambient);
                    for axis in 0..3 {
                        let terms = _mm512_fmadd_ps(lit[v], diffuse[axis], ambient[axis]);
                        primary[v][axis] = _mm512_fmadd_ps(factor[v], terms, primary[v][axis]);
                    }
                }
                None => {
                    let weight = _mm512_mul_ps(factor[v], lit[v]);
                    for axis in 0..3 {
                        primary[v][axis] = _mm512_fmadd_ps(weight, diffuse[axis], primary[v][axis]);
                    }
                }
            }
        }
        if V::SPEC {
            let eye = splat3(c.eye);
            let min_positive = _mm512_set1_ps(f32::MIN_POSITIVE);
            let mut n_dot_u2 = [zero; VECTORS];
            let mut u2 = [zero; VECTORS];
            let mut lanes = lit_lanes;
            for v in 0..VECTORS {
                let i = v * LANES;
                // SAFETY: i + 16 <= BLOCK.
                unsafe {
                    // `u = d + |d|·VP_e`, `|d|` times the unnormalised `ĥ`.
                    let u_u = if EYE_Z {
                        // `u = (d_x, d_y, d_z + |d|)`: `dot(u, u)` by the
                        // same operations, those with `d_x` and `d_y` shared
                        // with `|d|²`'s.
                        let u_z = _mm512_add_ps(d[v][2], distance[v]);
                        _mm512_fmadd_ps(u_z, u_z, across[v])
                    } else {
                        let vp_e = if V::LOCAL { load3(&b.vp_e, i) } else { eye };
                        // After a cone's pass `d` is in the block: loaded
                        // again rather than kept in registers (which spills
                        // them to the stack).
                        let d = if P::CONE { load3(&b.vp_pli, i) } else { d[v] };
                        let u = [
                            _mm512_fmadd_ps(vp_e[0], distance[v], d[0]),
                            _mm512_fmadd_ps(vp_e[1], distance[v], d[1]),
                            _mm512_fmadd_ps(vp_e[2], distance[v], d[2]),
                        ];
                        dot(u, u)
                    };
                    u2[v] = _mm512_max_ps(u_u, min_positive);
                    let n_dot_u = _mm512_fmadd_ps(load(&b.n_dot_eye, i), distance[v], n_dot_d[v]);
                    n_dot_u2[v] = _mm512_mul_ps(n_dot_u, n_dot_u);
                    if c.power.is_some() {
                        lanes[v] = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(lanes[v], n_dot_u, zero);
                    }
                }
            }
            let power = whole_power(n_dot_u2, u2, c.power, lanes);
            let specular = splat3(c.specular);
            for v in 0..VECTORS {
                let i = v * LANES;
                let f = _mm512_mul_ps(gate[v], power[v]);
                if c.separate {
                    for axis in 0..3 {
                        // SAFETY: i + 16 <= BLOCK.
                        unsafe {
                            let sum =
                                _mm512_fmadd_ps(f, specular[axis], load(&b.secondary[axis], i));
                            store(&mut b.secondary[axis], i, sum);
                        }
                    }
                } else {
                    for axis in 0..3 {
                        primary[v][axis] = _mm512_fmadd_ps(f, specular[axis], primary[v][axis]);
                    }
                }
            }
        }
        for v in 0..VECTORS {
            for axis in 0..3 {
                // SAFETY: v·16 + 16 <= BLOCK.
                unsafe { store(&mut b.primary[axis], v * LANES, primary[v][axis]) };
            }
        }
        outside
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use std::arch::x86_64::*;

    use super::avx512::{distance, raise, spot_cosine, whole_power};
    use super::*;
    use crate::fastmath::{Fast, Power};
    use crate::kernel::block::BLOCK;

    /// `rsqrt14`, `rcp14` and [`distance`] of the 16 lanes of `x`.
    #[target_feature(enable = "avx512f")]
    fn estimates(x: [f32; 16]) -> [[f32; 16]; 3] {
        let mut out = [[0.0; 16]; 3];
        // SAFETY: the arrays hold 16 lanes; the CPU has AVX-512F.
        unsafe {
            let v = _mm512_loadu_ps(x.as_ptr());
            let r = _mm512_rsqrt14_ps(v);
            _mm512_storeu_ps(out[0].as_mut_ptr(), r);
            _mm512_storeu_ps(out[1].as_mut_ptr(), _mm512_rcp14_ps(v));
            _mm512_storeu_ps(out[2].as_mut_ptr(), distance(v, r));
        }
        out
    }

    /// The relative errors of [`estimates`] on every f32 from `from` to
    /// `to`, 16 at a time.
    fn worst_estimates(from: f32, to: f32) -> [f64; 3] {
        let mut worst = [0.0f64; 3];
        for start in (from.to_bits()..to.to_bits()).step_by(16) {
            let x: [f32; 16] = std::array::from_fn(|k| f32::from_bits(start + k as u32));
            // SAFETY: the caller checked that the CPU has AVX-512F.
            let got = unsafe { estimates(x) };
            for k in 0..16 {
                let x = f64::from(x[k]);
                let exact = [1.0 / x.sqrt(), 1.0 / x, x.sqrt()];
                for e in 0..3 {
                    let error = (f64::from(got[e][k]) - exact[e]).abs() / exact[e];
                    worst[e] = worst[e].max(error);
                }
            }
        }
        worst
    }

    /// Every f32 of [1, 4) (which holds every error of `1/√x` and of the
    /// distance, and two periods of `1/x`), and the exact scaling by 4 that
    /// carries them over the normal range.
    #[test]
    fn estimates_over_every_f32_of_a_period() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        let [rsqrt, recip, distance] = worst_estimates(1.0, 4.0);
        let estimate = 2f64.powi(-14);
        assert!(rsqrt <= estimate, "rsqrt14: {rsqrt:e}");
        assert!(recip <= estimate, "rcp14: {recip:e}");
        assert!(distance <= DISTANCE_ERROR, "distance: {distance:e}");
        for x in [1.0f32, 1.7, 2.9, 3.999_999_8] {
            // SAFETY: checked above.
            let [_, _, at_x] = unsafe { estimates([x; 16]) };
            for k in [-63, -20, 20, 63] {
                let scaled = x * 4f32.powi(k);
                // SAFETY: checked above.
                let [_, _, at_scaled] = unsafe { estimates([scaled; 16]) };
                assert_eq!(at_scaled[0], at_x[0] * 2f32.powi(k), "{x}·4^{k}");
            }
        }
    }

    /// [`whole_power`] of 16 ratios.
    #[target_feature(enable = "avx512f")]
    fn powers(numerator: [f32; 16], denominator: [f32; 16], power: Squarings) -> [f32; 16] {
        let mut out = [0.0; 16];
        // SAFETY: the arrays hold 16 lanes; the CPU has AVX-512F.
        unsafe {
            let n = _mm512_loadu_ps(numerator.as_ptr());
            let d = _mm512_loadu_ps(denominator.as_ptr());
            let [x, ..] = whole_power([n; 4], [d; 4], Some(power), [!0; 4]);
            _mm512_storeu_ps(out.as_mut_ptr(), x);
        }
        out
    }

    /// Every power the one pass takes (`2^K`, `K` up to 6), estimated and
    /// refined: denominators every 512th f32 of [1, 2) (the estimate's
    /// error is a function of the mantissa), ratios from 1 down to the
    /// cutoff, against f64 on the f32 inputs; below the cutoff, the
    /// cutoff's power.
    #[test]
    fn whole_power_densely() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        for squarings in 0..=6u32 {
            let n = 1u32 << squarings;
            let Power::Whole { cutoff, .. } = Power::new::<Fast>(2.0 * n as f32) else {
                panic!("{n} is whole")
            };
            let ratios: Vec<f32> = (0..=64)
                .map(|i| (f64::from(cutoff).ln() * f64::from(i) / 64.0).exp() as f32)
                .filter(|r| *r >= cutoff)
                .collect();
            for refine in [false, true] {
                let power = Squarings {
                    squarings,
                    cutoff,
                    refine,
                };
                let mut worst = 0.0f64;
                for start in (1f32.to_bits()..2f32.to_bits()).step_by(512 * 16) {
                    let d: [f32; 16] =
                        std::array::from_fn(|k| f32::from_bits(start + 512 * k as u32));
                    for &ratio in &ratios {
                        let num = d.map(|d| d * ratio);
                        // SAFETY: checked above.
                        let got = unsafe { powers(num, d, power) };
                        for k in 0..16 {
                            let exact = (f64::from(num[k]) / f64::from(d[k])).powi(n as i32);
                            worst = worst.max((f64::from(got[k]) - exact).abs() / exact);
                        }
                    }
                }
                let bound = power_error(squarings, refine);
                assert!(
                    worst <= bound,
                    "2^{squarings}, {refine}: {worst:e} > {bound:e}"
                );
            }
            // Below the cutoff: about 2^−125, normal, in place of less.
            let below = [cutoff * 0.5; 16];
            // SAFETY: checked above.
            let got = unsafe { powers(below, [1.0; 16], power_of(squarings, cutoff)) };
            assert!(got.iter().all(|x| x.is_normal() && *x <= 2f32.powi(-124)));
        }
    }

    /// The spot's unrefined power of 16 lanes: [`spot_cosine`] of `along`
    /// and the estimate of `1/√d2`, its square raised by `power`.
    #[target_feature(enable = "avx512f")]
    fn spot_powers(along: [f32; 16], d2: [f32; 16], power: Squarings) -> [f32; 16] {
        let mut out = [0.0; 16];
        // SAFETY: the arrays hold 16 lanes; the CPU has AVX-512F.
        unsafe {
            let along = _mm512_loadu_ps(along.as_ptr());
            let (_, cos2) = spot_cosine(along, _mm512_rsqrt14_ps(_mm512_loadu_ps(d2.as_ptr())));
            let [x, ..] = raise([cos2; 4], power, [!0; 4]);
            _mm512_storeu_ps(out.as_mut_ptr(), x);
        }
        out
    }

    /// Every power the cone's pass raises from the square of the estimate
    /// of `1/|d|` (`2^K` up to [`MAX_UNREFINED_SPOT_HALF_EXPONENT`]):
    /// `|d|²` every 512th f32 of [1, 4) (the estimate's error is a function
    /// of the mantissa and of the exponent's parity), `cos²` from 1 down to
    /// the cutoff, against f64 on the f32 inputs. The bound is the
    /// estimate's error doubled by the square, and the rounding of the two
    /// products, each multiplied by `2^K`, with half an ULP per squaring:
    /// at most `8ε` (4.9e-4), as the module docs count it.
    #[test]
    fn spot_power_of_the_estimate_densely() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        let ulp = f64::from(f32::EPSILON);
        let estimate = 2f64.powi(-14);
        for squarings in 0..=MAX_UNREFINED_SPOT_HALF_EXPONENT.trailing_zeros() {
            let n = 1i32 << squarings;
            let Power::Whole { cutoff, .. } = Power::new::<Fast>(2.0 * n as f32) else {
                panic!("{n} is whole")
            };
            let bound = ((1.0 + estimate).powi(2) * (1.0 + ulp).powi(2)).powi(n)
                * (1.0 + ulp / 2.0).powi(n)
                - 1.0;
            assert!(bound <= 4.9e-4, "2^{squarings}: {bound:e}");
            let mut worst = 0.0f64;
            for start in (1f32.to_bits()..4f32.to_bits()).step_by(512 * 16) {
                let d2: [f32; 16] = std::array::from_fn(|k| f32::from_bits(start + 512 * k as u32));
                for i in 0..=64 {
                    let ratio = (f64::from(cutoff).ln() * f64::from(i) / 64.0).exp();
                    let along = d2.map(|d2| (ratio * f64::from(d2)).sqrt() as f32);
                    // SAFETY: checked above.
                    let got = unsafe { spot_powers(along, d2, power_of(squarings, cutoff)) };
                    for k in 0..16 {
                        let cos2 = f64::from(along[k]).powi(2) / f64::from(d2[k]);
                        if cos2 >= f64::from(cutoff) {
                            let exact = cos2.powi(n);
                            worst = worst.max((f64::from(got[k]) - exact).abs() / exact);
                        }
                    }
                }
            }
            assert!(worst <= bound, "2^{squarings}: {worst:e} > {bound:e}");
        }
    }

    /// The one pass of a block lit from a light at a point.
    #[target_feature(enable = "avx512f")]
    fn lit_block<const EYE_Z: bool>(block: &Block, pass: &PointPass) -> Block {
        type V = crate::kernel::variant::Loop<
            Fast,
            crate::kernel::isa::Avx512,
            false,
            true,
            false,
            false,
            true,
        >;
        type P = crate::kernel::variant::PointKind<true, false, false>;
        let mut b = block.clone();
        // SAFETY: the caller checked that the CPU has AVX-512F.
        let outside = unsafe { super::avx512::point_pass::<V, P, EYE_Z>(&mut b, pass) };
        assert_eq!(outside, 0, "every lane in range");
        b
    }

    /// With the eye along `z`, the pass forms `|u|²` from `d_x² + d_y²`
    /// and `d_z + |d|` instead of `u` whole: the same operations on the
    /// same values, so every colour is the same bit for bit, on random
    /// vertices, normals and lights, a light near the vertices among them
    /// and one straight behind them from the eye (`u` near zero).
    #[test]
    fn eye_along_z_is_the_general_pass_bit_for_bit() {
        if !crate::kernel::InstructionSet::Avx512.runs_here_for_test() {
            return;
        }
        let mut rng = crate::test_rng::Rng::new(0x9e37_79b9_7f4a_7c15u64);
        let mut random = || rng.signed() as f32;
        for round in 0..200 {
            let mut block = Block::default();
            for i in 0..BLOCK {
                let n = [random(), random(), random()];
                let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-3);
                for axis in 0..3 {
                    block.p[axis][i] = random() * 4.0;
                    block.n[axis][i] = n[axis] / length;
                    block.primary[axis][i] = random().abs();
                }
                block.n_dot_eye[i] = block.n[2][i];
            }
            let p_pli = match round % 3 {
                0 => [random() * 8.0, random() * 8.0, random() * 8.0],
                // Near the block's vertices.
                1 => [block.p[0][0] + 1e-3, block.p[1][0], block.p[2][0]],
                // Behind the first vertex, seen from the eye: `u` near zero.
                _ => [block.p[0][0], block.p[1][0], block.p[2][0] - 2.0],
            };
            let shininess = [1u32, 4, 16, 64][round % 4];
            let pass = PointPass {
                p_pli,
                k: [1.0, 0.1, 0.02],
                least: 1.0,
                floor: round % 3 != 0,
                in_range: round % 2 == 1,
                eye: [0.0, 0.0, 1.0],
                ambient: (round % 2 == 0).then_some([0.1, 0.2, 0.3]),
                diffuse: [0.7, 0.5, 0.3],
                specular: [0.5, 0.5, 0.5],
                separate: round % 5 == 0,
                power: Some(Squarings {
                    squarings: shininess.trailing_zeros(),
                    cutoff: 1e-30,
                    refine: shininess > MAX_UNREFINED_SPECULAR_HALF_EXPONENT,
                }),
            };
            // SAFETY: checked above.
            let (general, along_z) = unsafe {
                (
                    lit_block::<false>(&block, &pass),
                    lit_block::<true>(&block, &pass),
                )
            };
            for axis in 0..3 {
                for i in 0..BLOCK {
                    for (g, z) in [
                        (general.primary[axis][i], along_z.primary[axis][i]),
                        (general.secondary[axis][i], along_z.secondary[axis][i]),
                    ] {
                        assert_eq!(g.to_bits(), z.to_bits(), "round {round}, lane {i}");
                    }
                }
            }
        }
    }

    fn power_of(squarings: u32, cutoff: f32) -> Squarings {
        Squarings {
            squarings,
            cutoff,
            refine: false,
        }
    }
}

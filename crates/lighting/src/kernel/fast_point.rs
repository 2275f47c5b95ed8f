//! A light at a point in the fast tier. The general path
//! ([`super::positional`]) normalises `VP_pli`, tests the cone on the unit
//! vector, and forms `ĥ` from it, in a dozen passes over the block; this
//! one never forms the unit `VP_pli` at all: with `d = P_pli − V`, the
//! diffuse cosine is `(n·d)/|d|`, the halfway vector is `u = d + |d|·VP_e`
//! (`|d|·ĥ` before its normalisation, whose `n·u` is `n·d + |d|·(n·VP_e)`
//! from the `n·VP_e` the block computed once for all lights), the spot's
//! `cos²` is `((V − P_pli)·ŝ)²/(|d|²|ŝ|²)`, and the attenuation's reciprocal
//! is [`recip_fast`] (1.7e-6 relative, proven in `crate::fastmath`), taken
//! in the pass that forms its denominator. `1/|d|` and `1/|u|²` stay the
//! instruction set's reciprocals ([`Isa`]), to about an ULP: a specular
//! power of up to 64 multiplies the relative error of `cos²`.
//!
//! Its work goes in short passes over the block ([`to_light`],
//! [`distances`], [`halfway`], [`diffuse`], [`add_specular_terms`]) rather
//! than one long one. One pass would chain a hundred cycles of dependent
//! operations per vector (the distance waits for the square root, the
//! attenuation for the distance and the reciprocal), more than the CPU's
//! scheduler holds for the next vectors to overlap.
//!
//! It takes the blocks and lights whose errors stay within the tier's bound
//! ([`plan`]): every vertex of the block at a squared distance from the
//! light within [`UNSCALED_DISTANCE2`] (no scaling into range), Blinn-Phong
//! with normalised normals, specular and spot exponents up to
//! [`MAX_FAST_POINT_EXPONENT`], and cones tested on `cos²` (see
//! [`crate::fastmath::Math::CONE_FROM_COS2`]). Everything else goes the
//! general way.

use glam::Vec3;

use super::Cone;
use super::block::{BLOCK, Block};
use super::isa::Isa;
use super::light::LightColors;
use super::point_pass::{
    CONE_PASS_BAND, ConePass, Lanes, MAX_UNREFINED_SPECULAR_HALF_EXPONENT,
    MAX_UNREFINED_SPOT_HALF_EXPONENT, PointPass, Squarings,
};
use super::positional::{AtPoint, EDGE_BAND, MAX_DENOMINATOR, UNSCALED_DISTANCE2, exact_cone_test};
use super::power::{power_block, store_cos2};
use super::specular::sum_specular;
use super::variant::{PointLight, Variant};
use crate::MAX_ATTENUATION;
use crate::fastmath::{Fast, Math, Power, RECIP_FAST_MAX, recip_fast};

// Every clamped denominator is in `recip_fast`'s domain.
const _: () = assert!(
    MAX_DENOMINATOR <= RECIP_FAST_MAX && (1.0 / MAX_ATTENUATION) as f32 >= f32::MIN_POSITIVE
);

/// The largest exponent (shininess or spot exponent `s`) this path raises.
/// A power `(cos²)^(s/2)` multiplies the relative error of its `cos²` by
/// up to `s/2`, and this path's `cos²` carries a few ULP of f32 rounding
/// (its `n·u` is a sum of two products): GL's largest exponent, 128, keeps
/// that within the tier's bound. Higher ones go the general way, which
/// raises them from `sin²` near the highlight.
pub(super) const MAX_FAST_POINT_EXPONENT: f32 = 128.0;

/// How this path lights a light's blocks: made once per task, by [`plan`].
pub(super) enum FastPlan {
    /// In [`super::point_pass`]'s one pass (and the cone's pass before it).
    OnePass {
        cone: Option<ConePass>,
        pass: PointPass,
        /// The viewer is GL's eye-space infinite one, `VP_e = (0, 0, 1)`
        /// (see [`super::point_pass`]).
        eye_z: bool,
    },
    /// In this module's passes.
    Passes,
}

/// The plan of this path for the light `at` of kind `P` in a scene of the
/// variant `V`, or `None` where it does not take the light: the tier does
/// not ask for it, or the scene's features or exponents are beyond its
/// budget. [`positional`] still declines a block with a lane outside
/// [`UNSCALED_DISTANCE2`].
pub(super) fn plan<V: Variant, P: PointLight>(
    light: &LightColors,
    at: &AtPoint,
) -> Option<FastPlan> {
    if !takes_kind::<V, P>() {
        return None;
    }
    let within = |power: Power| match power {
        Power::One => true,
        Power::Whole { n, .. } => n as f32 * 2.0 <= MAX_FAST_POINT_EXPONENT,
        Power::General(s) => s <= MAX_FAST_POINT_EXPONENT,
    };
    let applies = (!V::SPEC || within(light.power))
        && at
            .cone
            .is_none_or(|cone| within(V::M::power(&cone.exponent)));
    if !applies {
        return None;
    }
    Some(if V::I::POINT_PASS {
        one_pass_plan::<V, P>(light, at).unwrap_or(FastPlan::Passes)
    } else {
        FastPlan::Passes
    })
}

/// Whether this path may take a light of kind `P` in a scene of the
/// variant `V` at all, as the compiler sees it: the tier asks for it,
/// Blinn-Phong with normalised normals, and a cone (if any) tested on
/// `cos²`. Where it may not, the path's code is left out of the variant's
/// loops.
#[inline(always)]
pub(super) const fn takes_kind<V: Variant, P: PointLight>() -> bool {
    V::M::FAST_POINT && !V::PHONG && !V::RAW && (!P::CONE || P::CONE_FROM_COS2)
}

/// What [`positional`] did.
pub(super) enum Outcome {
    /// Added the light's terms to every lane.
    Lit,
    /// Added nothing: some lane is outside [`UNSCALED_DISTANCE2`].
    Declined,
    /// Added the light's terms to every lane but these, outside
    /// [`UNSCALED_DISTANCE2`].
    LitBut(Lanes),
}

/// Adds the terms of the light `at` to the lanes of `b` (see the module
/// docs) by the light's `plan`.
#[inline(always)]
pub(super) fn positional<V: Variant, P: PointLight>(
    b: &mut Block,
    light: &LightColors,
    at: &AtPoint,
    plan: &FastPlan,
) -> Outcome {
    match plan {
        // The plan has a one pass only where the instruction set has it.
        FastPlan::OnePass { cone, pass, eye_z } if V::I::POINT_PASS => {
            one_pass::<V, P>(b, at, cone.as_ref(), pass, *eye_z)
        }
        FastPlan::OnePass { .. } | FastPlan::Passes => {
            if passes::<V, P>(b, light, at) {
                Outcome::Lit
            } else {
                Outcome::Declined
            }
        }
    }
}

/// The plan of the one pass for `power`, whose estimate of `1/cos²`'s
/// denominator stands alone up to the half exponent `max_unrefined`:
/// `Some(None)` for an exponent of 0, `None` where the one pass does not
/// take the power (not `2^K` with `K ≤ 6`).
fn squarings(power: Power, max_unrefined: u32) -> Option<Option<Squarings>> {
    match power {
        Power::One => Some(None),
        Power::Whole { n, cutoff } if n.is_power_of_two() && n <= 64 => Some(Some(Squarings {
            squarings: n.trailing_zeros(),
            cutoff,
            refine: n > max_unrefined,
        })),
        Power::Whole { .. } | Power::General(_) => None,
    }
}

/// The one pass's plan for the light `at`, or `None` where it does not
/// take the light's powers.
fn one_pass_plan<V: Variant, P: PointLight>(light: &LightColors, at: &AtPoint) -> Option<FastPlan> {
    let power = if V::SPEC {
        squarings(light.power, MAX_UNREFINED_SPECULAR_HALF_EXPONENT)?
    } else {
        None
    };
    let cone = match at.cone {
        Some(cone) if P::CONE => {
            let spot = squarings(
                V::M::power(&cone.exponent),
                MAX_UNREFINED_SPOT_HALF_EXPONENT,
            )?;
            let everywhere = cone.cos_cutoff <= 0.0;
            let band = f64::from(CONE_PASS_BAND);
            let (maybe_above, sure_from) = match (everywhere, spot) {
                (true, None) => (f32::NEG_INFINITY, f32::NEG_INFINITY),
                // The power is 0 at a cosine of 0 and behind.
                (true, Some(_)) => (0.0, f32::NEG_INFINITY),
                (false, _) => (
                    (cone.cos_cutoff - band) as f32,
                    (cone.cos_cutoff + band) as f32,
                ),
            };
            Some(ConePass {
                away: (-cone.direction).to_array(),
                maybe_above,
                sure_from,
                power: spot,
                in_range: at.in_range,
            })
        }
        _ => None,
    };
    let least = least_denominator(at);
    let [k0, k1, k2] = at.k;
    let pass = PointPass {
        p_pli: at.p_pli.to_array(),
        k: at.k,
        least,
        // `k0 + k1·|d| + k2·|d|²` is at least `k0` where no `k` is negative.
        floor: !(k0 >= least && k1 >= 0.0 && k2 >= 0.0),
        in_range: at.in_range,
        eye: at.eye.to_array(),
        ambient: (light.ambient != Vec3::ZERO).then_some(light.ambient.to_array()),
        diffuse: light.diffuse.to_array(),
        specular: light.specular.to_array(),
        separate: light.separate,
        power,
    };
    Some(FastPlan::OnePass {
        cone,
        pass,
        eye_z: V::SPEC && !V::LOCAL && at.eye == Vec3::Z,
    })
}

/// [`positional`] in [`super::point_pass`]'s passes by their plans.
#[inline(always)]
fn one_pass<V: Variant, P: PointLight>(
    b: &mut Block,
    at: &AtPoint,
    cone: Option<&ConePass>,
    pass: &PointPass,
    eye_z: bool,
) -> Outcome {
    if P::CONE
        && let (Some(plan), Some(cone)) = (cone, at.cone)
    {
        let found = V::I::cone_pass(b, at.p_pli.to_array(), plan);
        if found.out_of_range {
            return Outcome::Declined;
        }
        if found.near_edge {
            // The pass kept the power of every lane that may be inside.
            exact_cone_test(b, at.p_pli, cone.direction, cone.cos_cutoff);
            for i in 0..BLOCK {
                b.power[i] *= b.scale[i];
            }
            if b.scale.iter().fold(0, |any, s| any | s.to_bits()) == 0 {
                return Outcome::Lit;
            }
        } else if !found.any_inside {
            // The spot factor zeroes every term.
            return Outcome::Lit;
        }
    }
    let outside = if eye_z {
        V::I::point_pass::<V, P, true>(b, pass)
    } else {
        V::I::point_pass::<V, P, false>(b, pass)
    };
    if outside == 0 {
        Outcome::Lit
    } else {
        Outcome::LitBut(outside)
    }
}

/// The least denominator of the attenuation `1/(k0 + k1·d + k2·d²)`: 1
/// with the clamp `att = min(att, 1)`, else that of the largest
/// attenuation.
#[inline(always)]
fn least_denominator(at: &AtPoint) -> f32 {
    if at.clamp {
        1.0
    } else {
        (1.0 / MAX_ATTENUATION) as f32
    }
}

/// [`positional`] in passes; returns false, having added nothing, where
/// some lane is outside [`UNSCALED_DISTANCE2`].
#[inline(always)]
fn passes<V: Variant, P: PointLight>(b: &mut Block, light: &LightColors, at: &AtPoint) -> bool {
    let cone = *at.cone.unwrap_or(&Cone::UNUSED);
    if !to_light::<P>(b, at.p_pli, &cone) {
        return false;
    }
    V::I::rsqrt(&b.distance2, &mut b.inverse_distance);
    if P::CONE {
        if !cone_factors(b, &cone) {
            // The spot factor zeroes every term.
            return true;
        }
        power_block::<V::M>(V::M::power(&cone.exponent), b, true);
    }
    distances::<P>(b, at);
    if V::SPEC {
        halfway::<V>(b, at.eye.to_array());
        V::I::recip(&b.half2, &mut b.inverse_half2);
    }
    diffuse::<V, P>(b, light);
    if V::SPEC {
        add_specular_terms(b, light);
    }
    true
}

/// `a·b`, a multiplication and two fused multiply-adds.
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[2].mul_add(b[2], a[1].mul_add(b[1], a[0] * b[0]))
}

/// `d = P_pli − V` of every lane into `vp_pli` (not normalised), `|d|²`
/// into `distance2` and `n·d` into `n_dot_d`; with a cone, its test into
/// `scale` (1 inside, 0 outside) and `((V − P_pli)·ŝ)²` into `cos2` (−1
/// where the dot product is not positive). The test is on `cos²` scaled by
/// `|d|²|ŝ|²` (no division): where it lies within [`EDGE_BAND`] of the
/// edge's, the block is tested again exactly, as the general path does.
/// Returns false where some lane's `|d|²` is outside [`UNSCALED_DISTANCE2`].
#[inline(always)]
fn to_light<P: PointLight>(b: &mut Block, p_pli: Vec3, cone: &Cone) -> bool {
    let p = p_pli.to_array();
    let s = cone.direction.to_array();
    let s2 = 1.0 / cone.inverse_direction2;
    let edge2 = cone.cos2_cutoff * s2;
    let band = EDGE_BAND * s2;
    let everywhere = cone.cos_cutoff <= 0.0;
    let (mut near, mut out_of_range) = (0u32, 0u32);
    for i in 0..BLOCK {
        let d = [p[0] - b.p[0][i], p[1] - b.p[1][i], p[2] - b.p[2][i]];
        for axis in 0..3 {
            b.vp_pli[axis][i] = d[axis];
        }
        let d2 = dot(d, d);
        out_of_range |= u32::from(!UNSCALED_DISTANCE2.contains(&d2));
        b.distance2[i] = d2;
        b.n_dot_d[i] = dot([b.n[0][i], b.n[1][i], b.n[2][i]], d);
        if P::CONE {
            // `(V − P_pli)·ŝ`: the light's direction to the vertex on the axis.
            let along = -dot(d, s);
            let along2 = along * along;
            let off = along2 - edge2 * d2;
            let inside = everywhere || (along > 0.0 && off >= 0.0);
            near |= u32::from(!everywhere && off.abs() < band * d2);
            b.scale[i] = if inside { 1.0 } else { 0.0 };
            store_cos2(b, i, along > 0.0, along2);
        }
    }
    if P::CONE && near != 0 && out_of_range == 0 {
        exact_cone_test(b, p_pli, cone.direction, cone.cos_cutoff);
    }
    out_of_range == 0
}

/// The spot's `cos²` of every lane from `((V − P_pli)·ŝ)²` in `cos2`;
/// returns whether some lane is inside the cone.
#[inline(always)]
fn cone_factors(b: &mut Block, cone: &Cone) -> bool {
    for i in 0..BLOCK {
        let r = b.inverse_distance[i];
        let along2 = b.cos2[i];
        let cos2 = (along2 * (r * r) * cone.inverse_direction2).min(1.0);
        b.cos2[i] = if along2 >= 0.0 { cos2 } else { -1.0 };
    }
    b.scale.iter().fold(0, |any, s| any | s.to_bits()) != 0
}

/// `|d|` of every lane into `unscale`, and the reciprocal of the
/// attenuation's denominator `k0 + k1·|d| + k2·|d|²`, clamped, into
/// `inverse_denominator`.
#[inline(always)]
fn distances<P: PointLight>(b: &mut Block, at: &AtPoint) {
    let [k0, k1, k2] = at.k;
    let least = least_denominator(at);
    for i in 0..BLOCK {
        let d2 = b.distance2[i];
        let distance = d2 * b.inverse_distance[i];
        b.unscale[i] = distance;
        if P::ATTENUATED {
            let denominator = k2.mul_add(d2, k1.mul_add(distance, k0));
            b.inverse_denominator[i] = recip_fast(denominator.clamp(least, MAX_DENOMINATOR));
        }
    }
}

/// `|u|²` of the halfway vector `u = d + |d|·VP_e` into `half2` and `n·u`
/// into `n_dot_u`.
#[inline(always)]
fn halfway<V: Variant>(b: &mut Block, eye: [f32; 3]) {
    for i in 0..BLOCK {
        let d = [b.vp_pli[0][i], b.vp_pli[1][i], b.vp_pli[2][i]];
        let distance = b.unscale[i];
        let vp_e = if V::LOCAL {
            [b.vp_e[0][i], b.vp_e[1][i], b.vp_e[2][i]]
        } else {
            eye
        };
        let u = [0, 1, 2].map(|axis| vp_e[axis].mul_add(distance, d[axis]));
        b.half2[i] = dot(u, u).max(f32::MIN_POSITIVE);
        b.n_dot_u[i] = b.n_dot_eye[i].mul_add(distance, b.n_dot_d[i]);
    }
}

/// The ambient and diffuse terms of every lane into `primary`, and the
/// gate of the specular term into `gate`.
#[inline(always)]
fn diffuse<V: Variant, P: PointLight>(b: &mut Block, light: &LightColors) {
    for i in 0..BLOCK {
        let n_dot_d = b.n_dot_d[i];
        let spot = if P::CONE {
            b.scale[i] * b.power[i]
        } else {
            1.0
        };
        let factor = if P::ATTENUATED {
            spot * b.inverse_denominator[i]
        } else {
            spot
        };
        let lit = (n_dot_d * b.inverse_distance[i]).max(0.0) * b.visible[i];
        for c in 0..3 {
            b.primary[c][i] = factor.mul_add(
                lit.mul_add(light.diffuse[c], light.ambient[c]),
                b.primary[c][i],
            );
        }
        if V::SPEC {
            b.gate[i] = if n_dot_d > 0.0 {
                b.visible[i] * factor
            } else {
                0.0
            };
        }
    }
}

/// The specular base of lane `i`: `cos²` of `n` and the halfway vector,
/// cut as [`crate::fastmath::whole_base`] cuts it where `least` is the
/// cutoff, else `otherwise`.
#[inline(always)]
fn specular_base(b: &Block, i: usize, least: f32, otherwise: f32) -> f32 {
    let n_dot_u = b.n_dot_u[i];
    let cos2 = (n_dot_u * n_dot_u * b.inverse_half2[i]).min(1.0);
    if n_dot_u > 0.0 && cos2 >= least {
        cos2
    } else {
        otherwise
    }
}

/// `gate · (base)^s · specular` of every lane into its colour, from the
/// bases of [`specular_base`]. A power `s/2 = 2^K` (shininess 2 to 128)
/// is `K` squarings in the same pass as the sum.
#[inline(always)]
fn add_specular_terms(b: &mut Block, light: &LightColors) {
    match light.power {
        Power::Whole { n, .. } if n.is_power_of_two() && n <= 64 => match n.trailing_zeros() {
            0 => raise_and_add::<0>(b, light),
            1 => raise_and_add::<1>(b, light),
            2 => raise_and_add::<2>(b, light),
            3 => raise_and_add::<3>(b, light),
            4 => raise_and_add::<4>(b, light),
            5 => raise_and_add::<5>(b, light),
            _ => raise_and_add::<6>(b, light),
        },
        power => {
            let (least, otherwise) = match power {
                Power::Whole { cutoff, .. } => (cutoff, 0.0),
                Power::One | Power::General(_) => (0.0, -1.0),
            };
            for i in 0..BLOCK {
                b.cos2[i] = specular_base(b, i, least, otherwise);
            }
            power_block::<Fast>(power, b, true);
            sum_specular(b, light, light.specular);
        }
    }
}

/// [`add_specular_terms`] of the power `2^K` of the bases.
#[inline(always)]
fn raise_and_add<const K: u32>(b: &mut Block, light: &LightColors) {
    let Power::Whole { cutoff, .. } = light.power else {
        unreachable!("a whole power")
    };
    for i in 0..BLOCK {
        b.cos2[i] = specular_base(b, i, cutoff, 0.0);
    }
    let (bases, gate) = (&b.cos2, &b.gate);
    let sum = if light.separate {
        &mut b.secondary
    } else {
        &mut b.primary
    };
    for i in 0..BLOCK {
        let mut x = bases[i];
        for _ in 0..K {
            x *= x;
        }
        let f = gate[i] * x;
        for c in 0..3 {
            sum[c][i] = f.mul_add(light.specular[c], sum[c][i]);
        }
    }
}

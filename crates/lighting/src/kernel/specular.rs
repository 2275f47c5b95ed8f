//! The specular term of a lane: its base, `n⊙ĥ` (Blinn-Phong) or `r⊙VP_e`
//! (Phong), stored for [`power_block`], and the sum of `f_i · (base)^s ·
//! s_cm·s_cli` into the block's colour.

use glam::Vec3;

use super::block::{BLOCK, Block};
use super::light::LightColors;
use super::power::{power_block, store_cos2, store_cosine};
use super::range::unit;
use super::variant::Variant;
use crate::fastmath::{Math, cos2_of_unit, cosine, cosine_of_unit};

/// The infinite viewer's `ĥ`, where it is the same for every vertex, and
/// `1/|ĥ|²` (zero for a zero `ĥ`).
#[derive(Clone, Copy)]
pub(super) struct Half {
    pub h: Vec3,
    pub inverse_h2: f32,
}

impl Half {
    pub fn new(h: Vec3) -> Self {
        let h2 = h.length_squared();
        Self {
            h,
            inverse_h2: if h2 > 0.0 { 1.0 / h2 } else { 0.0 },
        }
    }
}

/// What the specular base of one lane reads.
#[derive(Clone, Copy)]
pub(super) struct SpecularLane {
    pub n: [f32; 3],
    pub vp_pli: [f32; 3],
    /// `VP_e`: the lane's for a local viewer, the infinite viewer's else.
    pub vp_e: [f32; 3],
    pub n_dot_vp: f32,
    /// What multiplies the power: visibility, `f_i`, attenuation and spot.
    pub gate: f32,
}

/// The specular base of lane `i` and its `gate`. With unit normals the base
/// is a cosine, stored for [`power_block`], which raises it without losing
/// the digits near 1; raw normals take the plain power of the dot product,
/// here. For an infinite viewer `ĥ` (not necessarily normalised) comes in
/// as `half` with `1/|ĥ|²`: the same for every vertex where `FIXED_HALF` (a
/// light at infinity), else that of the vertex, from an [`super::isa::Isa`]
/// pass; a local viewer's of a light at infinity is a division here.
/// `V::COS2`: the base of a whole power, from `cos²` alone (see
/// [`Math::WHOLE_FROM_COS2`]).
#[inline(always)]
pub(super) fn specular_base<V: Variant, const FIXED_HALF: bool>(
    b: &mut Block,
    i: usize,
    lane: SpecularLane,
    half: Half,
    shininess: f32,
) {
    let SpecularLane {
        n,
        vp_pli: vp,
        vp_e,
        n_dot_vp,
        gate,
    } = lane;
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    b.gate[i] = gate;
    if V::PHONG {
        // `r = 2(n·VP)n − VP`, the reflected light direction.
        let r = [
            2.0 * n_dot_vp * n[0] - vp[0],
            2.0 * n_dot_vp * n[1] - vp[1],
            2.0 * n_dot_vp * n[2] - vp[2],
        ];
        if V::RAW {
            b.power[i] = V::M::pow(dot(r, vp_e), shininess);
        } else {
            store_cosine(b, i, cosine(r, vp_e));
        }
        return;
    }
    let h = if V::LOCAL {
        [vp[0] + vp_e[0], vp[1] + vp_e[1], vp[2] + vp_e[2]]
    } else {
        half.h.to_array()
    };
    if V::RAW {
        b.power[i] = V::M::pow(dot(n, unit::<V::M>(h)), shininess);
        return;
    }
    let inverse_h2 = if V::LOCAL && FIXED_HALF {
        1.0 / dot(h, h)
    } else {
        half.inverse_h2
    };
    if V::COS2 {
        let c = cos2_of_unit(n, h, inverse_h2);
        store_cos2(b, i, c.positive, c.cos2);
    } else {
        store_cosine(b, i, cosine_of_unit(n, h, inverse_h2));
    }
}

/// Adds `gate · power · specular` of every lane to its colour (see
/// [`LightColors::separate`]); raw normals have their power in `power`
/// already. `specular` is the light's, times a constant spot factor.
#[inline(always)]
pub(super) fn add_specular<V: Variant>(b: &mut Block, light: &LightColors, specular: Vec3) {
    if !V::RAW {
        power_block::<V::M>(light.power, b, V::COS2);
    }
    sum_specular(b, light, specular);
}

/// Adds `gate · power · specular` of every lane to its colour.
#[inline(always)]
pub(super) fn sum_specular(b: &mut Block, light: &LightColors, specular: Vec3) {
    let sum = if light.separate {
        &mut b.secondary
    } else {
        &mut b.primary
    };
    for i in 0..BLOCK {
        let f = b.gate[i] * b.power[i];
        for c in 0..3 {
            sum[c][i] = f.mul_add(specular[c], sum[c][i]);
        }
    }
}

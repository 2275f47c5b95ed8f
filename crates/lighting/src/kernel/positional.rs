//! A light at a point: `VP_pli`, the distance, the attenuation and the spot
//! factor per vertex. Its kind ([`PointLight`]) says which of them the
//! scene needs, so that a light with the coefficients (1, 0, 0) and no cone
//! computes neither.

use glam::Vec3;

use super::Cone;
use super::block::{BLOCK, Block};
use super::fast_point::{self, FastPlan, Outcome};
use super::isa::Isa;
use super::light::LightColors;
use super::point_pass::Lanes;
use super::power::{power_block, store_cos2, store_cosine};
use super::range::range_scaled;
use super::specular::{Half, SpecularLane, add_specular, specular_base};
use super::variant::{PointLight, Variant};
use crate::MAX_ATTENUATION;
use crate::fastmath::{Cosine, Math, Powers, cos2_of_unit, cosine_of_unit};

/// A light at a point, recentred, as its loops read it.
pub(super) struct AtPoint<'a> {
    pub p_pli: Vec3,
    /// k0, k1, k2.
    pub k: [f32; 3],
    /// `att = min(att, 1)`.
    pub clamp: bool,
    /// The infinite viewer's direction (unused for a local viewer).
    pub eye: Vec3,
    pub cone: Option<&'a Cone>,
    /// Every lane's `|d|²` is within [`UNSCALED_DISTANCE2`]
    /// ([`super::Kernel::lights_in_range`]).
    pub in_range: bool,
}

/// Squared distances in this range are taken as they are: their square
/// roots and reciprocals are normal f32 and lose nothing. A block with a
/// vertex outside it (a light 1e-15 or 1e15 away) is scaled into range by
/// powers of two, exactly.
pub(super) const UNSCALED_DISTANCE2: std::ops::Range<f32> = 1e-30..1e30;

/// The largest attenuation denominator: its reciprocal is still a normal
/// f32.
pub(super) const MAX_DENOMINATOR: f32 = 1e37;

/// Where the `cos²` of the cone test is within this of the cutoff's, the
/// test might go either way: its f32 error is below 1e-6.
pub(super) const EDGE_BAND: f32 = 4e-6;

/// Adds the terms of the light `at` to every lane of `b`, by the fast
/// tier's path where it has a plan for the light.
#[inline(always)]
pub(super) fn positional<V: Variant, P: PointLight>(
    b: &mut Block,
    light: &LightColors,
    at: &AtPoint,
    fast: Option<&FastPlan>,
) {
    if fast_point::takes_kind::<V, P>()
        && let Some(plan) = fast
    {
        match fast_point::positional::<V, P>(b, light, at, plan) {
            Outcome::Lit => return,
            Outcome::Declined => {}
            Outcome::LitBut(lanes) => {
                return lanes_by_the_general_path::<V, P>(b, light, at, lanes);
            }
        }
    }
    general::<V, P>(b, light, at);
}

/// The terms of the light `at` added to the lanes `lanes` of `b` (a bit
/// each) by [`general`], on a copy of the block whose colours start at 0:
/// the rare block that has some vertex too near the light or too far from
/// it for the fast tier's one pass, which lit the others.
#[cold]
fn lanes_by_the_general_path<V: Variant, P: PointLight>(
    b: &mut Block,
    light: &LightColors,
    at: &AtPoint,
    lanes: Lanes,
) {
    let mut copy = b.clone();
    copy.primary = [[0.0; BLOCK]; 3];
    copy.secondary = [[0.0; BLOCK]; 3];
    general::<V, P>(&mut copy, light, at);
    for i in (0..BLOCK).filter(|i| lanes >> i & 1 == 1) {
        for c in 0..3 {
            b.primary[c][i] += copy.primary[c][i];
            b.secondary[c][i] += copy.secondary[c][i];
        }
    }
}

/// [`positional`] for every tier, every light and every lane.
#[inline(always)]
fn general<V: Variant, P: PointLight>(b: &mut Block, light: &LightColors, at: &AtPoint) {
    // A copy: read through a reference, the cone's fields are not hoisted
    // out of the vertex loops.
    let cone = *at.cone.unwrap_or(&Cone::UNUSED);
    to_light::<V::I>(b, at.p_pli);
    let near_edge = per_lane_factors::<V, P>(b, at, &cone);
    if P::CONE_FROM_COS2 && near_edge {
        exact_cone_test(b, at.p_pli, cone.direction, cone.cos_cutoff);
    }
    // A block wholly outside the cone gets nothing from this light, not even
    // ambient (the spot factor multiplies every term): the rest of the
    // light's work would add zeros. Neighbouring vertices share blocks, so
    // a cone that lights part of a mesh skips the blocks it misses.
    if P::CONE && b.scale.iter().fold(0, |any, s| any | s.to_bits()) == 0 {
        return;
    }
    if P::ATTENUATED {
        if V::M::ESTIMATES {
            V::I::recip_estimate(&b.denominator, &mut b.inverse_denominator);
        } else {
            V::I::recip(&b.denominator, &mut b.inverse_denominator);
        }
        for i in 0..BLOCK {
            b.scale[i] *= b.inverse_denominator[i];
        }
    }
    if P::CONE {
        power_block::<V::M>(V::M::power(&cone.exponent), b, P::CONE_FROM_COS2);
    }
    if V::SPEC && !V::PHONG && !V::RAW {
        half_lengths::<V>(b, at.eye);
    }
    light_lanes::<V, P>(b, light, at.eye);
    if V::SPEC {
        add_specular::<V>(b, light, light.specular);
    }
}

/// `P_pli − V` of every lane into `vp_pli` and its squared length into
/// `distance2`, scaled into range where some lane needs it (`unscale`
/// undoes the scaling), and `1/√distance2` into `inverse_distance`.
#[inline(always)]
fn to_light<I: Isa>(b: &mut Block, p_pli: Vec3) {
    let mut out_of_range = 0u32;
    for i in 0..BLOCK {
        let d = [
            p_pli.x - b.p[0][i],
            p_pli.y - b.p[1][i],
            p_pli.z - b.p[2][i],
        ];
        let distance2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for axis in 0..3 {
            b.vp_pli[axis][i] = d[axis];
        }
        b.distance2[i] = distance2;
        out_of_range |= u32::from(!UNSCALED_DISTANCE2.contains(&distance2));
    }
    if out_of_range == 0 {
        b.unscale = [1.0; BLOCK];
    } else {
        for i in 0..BLOCK {
            let d = [b.vp_pli[0][i], b.vp_pli[1][i], b.vp_pli[2][i]];
            let (w, distance2, unscale) = range_scaled(d);
            for axis in 0..3 {
                b.vp_pli[axis][i] = w[axis];
            }
            b.distance2[i] = distance2;
            b.unscale[i] = unscale;
        }
    }
    // `VP_pli` to full f32 accuracy in every tier: the cone test is a
    // step, and an approximate direction would move its edge.
    I::rsqrt(&b.distance2, &mut b.inverse_distance);
}

/// Per lane: `VP_pli` normalised, the attenuation's denominator (if
/// `P::ATTENUATED`) and the cone test (if `P::CONE`) into `scale`, 1 inside
/// and 0 outside. Returns whether some lane of a cone tested on `cos²` lies
/// so near its edge that the f32 test might be wrong.
#[inline(always)]
fn per_lane_factors<V: Variant, P: PointLight>(b: &mut Block, at: &AtPoint, cone: &Cone) -> bool {
    let [k0, k1, k2] = at.k;
    // `1/(k0 + k1·d + k2·d²)` capped at `MAX_ATTENUATION` (or 1 with the
    // clamp) is the reciprocal of the denominator raised to the cap's
    // reciprocal.
    let least = if at.clamp {
        1.0
    } else {
        (1.0 / MAX_ATTENUATION) as f32
    };
    // Its sign bit clear: some lane's `cos²` is near the cutoff's.
    let mut far = u32::MAX;
    for i in 0..BLOCK {
        let inverse = if b.distance2[i] > f32::MIN_POSITIVE {
            b.inverse_distance[i]
        } else {
            0.0
        };
        let vp = [
            b.vp_pli[0][i] * inverse,
            b.vp_pli[1][i] * inverse,
            b.vp_pli[2][i] * inverse,
        ];
        for axis in 0..3 {
            b.vp_pli[axis][i] = vp[axis];
        }
        if P::ATTENUATED {
            let distance = b.distance2[i] * inverse * b.unscale[i];
            // A coefficient past f32's range is infinite, which keeps the
            // light as dark as the reference makes it at any distance but
            // 0, where `inf · 0` would be NaN: there only `k0` counts.
            let terms = k1 * distance + k2 * distance * distance;
            let terms = if distance > 0.0 { terms } else { 0.0 };
            b.denominator[i] = (k0 + terms).clamp(least, MAX_DENOMINATOR);
        }
        b.scale[i] = if P::CONE {
            let (inside, lane_far) = cone_lane::<P>(b, i, vp, cone);
            far &= lane_far;
            if inside { 1.0 } else { 0.0 }
        } else {
            1.0
        };
    }
    P::CONE_FROM_COS2 && far >> 31 == 0
}

/// The cone test of lane `i`, whose `VP_pli` is `vp`: `P_pli V ⊙ ŝ ≥
/// cos(cutoff)`, tested on `sin²` or `cos²` (see [`Cone`]); the clamp of
/// `⊙` puts every vertex behind the light on the edge of a 90° cone. Stores
/// the cosine for the spot's power, and returns whether the lane is inside
/// and, for a test on `cos²`, bits whose sign is clear where the lane is
/// near the edge. `P::CONE_FROM_COS2` leaves `sin²`, and so the cross
/// product, out.
#[inline(always)]
fn cone_lane<P: PointLight>(b: &mut Block, i: usize, vp: [f32; 3], cone: &Cone) -> (bool, u32) {
    let to_vertex = [-vp[0], -vp[1], -vp[2]];
    let direction = cone.direction.to_array();
    let c: Cosine = if P::CONE_FROM_COS2 {
        cos2_of_unit(to_vertex, direction, cone.inverse_direction2)
    } else {
        cosine_of_unit(to_vertex, direction, cone.inverse_direction2)
    };
    let inside = if !c.positive {
        cone.cos_cutoff <= 0.0
    } else if cone.narrow && !P::CONE_FROM_COS2 {
        c.sin2 <= cone.sin2_cutoff
    } else {
        c.cos2 >= cone.cos2_cutoff
    };
    if P::CONE_FROM_COS2 {
        store_cos2(b, i, c.positive, c.cos2);
        let off = c.cos2 - cone.cos2_cutoff;
        (inside, (-off).mul_add(off, EDGE_BAND * EDGE_BAND).to_bits())
    } else {
        store_cosine(b, i, c);
        (inside, u32::MAX)
    }
}

/// The cone test of every lane of a block in f64, where the f32 one is not
/// sure of a lane: exact for the f32 position of the vertex and of the
/// light, and the f32 direction, so that a cone tested on `cos²` puts its
/// edge where the reference does but for the rounding of those inputs. Sets
/// `scale` to 1 inside, 0 outside.
#[inline(always)]
pub(super) fn exact_cone_test(b: &mut Block, p_pli: Vec3, direction: Vec3, cos_cutoff: f64) {
    let s = direction.as_dvec3();
    for i in 0..BLOCK {
        // `V − P_pli`: each coordinate a difference of two f32, exact in f64,
        // as are the products of the dot product.
        let w = Vec3::new(b.p[0][i], b.p[1][i], b.p[2][i]).as_dvec3() - p_pli.as_dvec3();
        let dot = w.dot(s);
        let inside = cos_cutoff <= 0.0
            || (dot > 0.0
                && dot * dot >= cos_cutoff * cos_cutoff * w.length_squared() * s.length_squared());
        b.scale[i] = if inside { 1.0 } else { 0.0 };
    }
}

/// `1/|ĥ|²` of every lane into `inverse_half2`, for the specular cosine.
#[inline(always)]
fn half_lengths<V: Variant>(b: &mut Block, eye: Vec3) {
    for i in 0..BLOCK {
        let vp_e = if V::LOCAL {
            [b.vp_e[0][i], b.vp_e[1][i], b.vp_e[2][i]]
        } else {
            eye.to_array()
        };
        let h = [
            b.vp_pli[0][i] + vp_e[0],
            b.vp_pli[1][i] + vp_e[1],
            b.vp_pli[2][i] + vp_e[2],
        ];
        b.half2[i] = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).max(f32::MIN_POSITIVE);
    }
    V::I::recip(&b.half2, &mut b.inverse_half2);
}

/// The light's ambient and diffuse terms of every lane, and its specular
/// base: a loop of its own after the factors', as two short loop bodies
/// keep their values in registers where one long one spills them.
#[inline(always)]
fn light_lanes<V: Variant, P: PointLight>(b: &mut Block, light: &LightColors, eye: Vec3) {
    for i in 0..BLOCK {
        let vp = [b.vp_pli[0][i], b.vp_pli[1][i], b.vp_pli[2][i]];
        let scale = if P::CONE {
            b.scale[i] * b.power[i]
        } else {
            b.scale[i]
        };
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp[0] + n[1] * vp[1] + n[2] * vp[2];
        let lit = n_dot_vp.max(0.0) * b.visible[i];
        for c in 0..3 {
            b.primary[c][i] = scale.mul_add(
                lit.mul_add(light.diffuse[c], light.ambient[c]),
                b.primary[c][i],
            );
        }
        if V::SPEC {
            let vp_e = if V::LOCAL {
                [b.vp_e[0][i], b.vp_e[1][i], b.vp_e[2][i]]
            } else {
                eye.to_array()
            };
            // ĥ of the infinite viewer, not normalised.
            let half = Half {
                h: Vec3::new(vp[0] + eye.x, vp[1] + eye.y, vp[2] + eye.z),
                inverse_h2: b.inverse_half2[i],
            };
            let lane = SpecularLane {
                n,
                vp_pli: vp,
                vp_e,
                n_dot_vp,
                // `f_i`: no specular where the light does not reach the front.
                gate: if n_dot_vp > 0.0 {
                    b.visible[i] * scale
                } else {
                    0.0
                },
            };
            specular_base::<V, false>(b, i, lane, half, light.shininess);
        }
    }
}

impl Cone {
    /// A cone no light has, read by no loop: the placeholder of the light
    /// kinds without one.
    pub(super) const UNUSED: Self = Self {
        direction: Vec3::ZERO,
        inverse_direction2: 0.0,
        exponent: Powers::ONE,
        cos_cutoff: 0.0,
        narrow: true,
        sin2_cutoff: 0.0,
        cos2_cutoff: 0.0,
        from_cos2: false,
    };
}

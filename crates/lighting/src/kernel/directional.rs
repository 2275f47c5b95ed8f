//! A light at infinity: `VP_pli`, the infinite viewer's `ĥ` and the spot
//! factor are the same for every vertex, and there is no attenuation.

use glam::Vec3;

use super::block::{BLOCK, Block};
use super::light::LightColors;
use super::specular::{Half, SpecularLane, add_specular, specular_base};
use super::variant::Variant;

/// Adds a light at infinity's terms to every lane of `b`: `vp` is
/// `VP_pli`, `h_infinite` the infinite viewer's `ĥ` and `eye` its
/// direction, `spot` the light's constant spot factor.
#[inline(always)]
pub(super) fn directional<V: Variant>(
    b: &mut Block,
    light: &LightColors,
    vp: Vec3,
    h_infinite: Vec3,
    eye: Vec3,
    spot: f32,
) {
    let ambient = light.ambient * spot;
    let diffuse = light.diffuse * spot;
    let specular = light.specular * spot;
    let half = Half::new(h_infinite);
    for i in 0..BLOCK {
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp.x + n[1] * vp.y + n[2] * vp.z;
        let lit = n_dot_vp.max(0.0) * b.visible[i];
        for c in 0..3 {
            b.primary[c][i] = lit.mul_add(diffuse[c], b.primary[c][i] + ambient[c]);
        }
        if V::SPEC {
            let vp_e = if V::LOCAL {
                [b.vp_e[0][i], b.vp_e[1][i], b.vp_e[2][i]]
            } else {
                eye.to_array()
            };
            let lane = SpecularLane {
                n,
                vp_pli: vp.to_array(),
                vp_e,
                n_dot_vp,
                // `f_i`: no specular where the light does not reach the front.
                gate: if n_dot_vp > 0.0 { b.visible[i] } else { 0.0 },
            };
            specular_base::<V, true>(b, i, lane, half, light.shininess);
        }
    }
    if V::SPEC {
        add_specular::<V>(b, light, specular);
    }
}

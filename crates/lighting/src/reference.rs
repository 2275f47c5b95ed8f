//! The reference evaluator: section 2.14.1 in f64, one vertex at a time, term
//! by term. It is the ground truth the faster paths are measured against, so
//! it is written to be read next to the specification, not to be fast.

use glam::{DVec3, DVec4};

use super::terms::{Breakdown, LightTerms};
use super::{
    Light, LightModel, LightPosition, LightSet, MAX_ATTENUATION, Material, Side, SpecularModel,
    SurfaceMaterial, spec_pow, unit_or_zero,
};

/// The term breakdown of one side of the vertex at `v` with normal `normal`
/// (as given: it is normalised here when the light model asks for it), made
/// of `material` and lit by `lights`.
pub fn evaluate(
    lights: &LightSet,
    material: &SurfaceMaterial,
    side: Side,
    v: DVec3,
    normal: DVec3,
) -> Breakdown {
    let (material, n) = match side {
        Side::Front => (&material.front, normal),
        Side::Back => (&material.back, -normal),
    };
    let n = if lights.model.normalize_normals {
        unit_or_zero(n)
    } else {
        n
    };
    let vp_e = lights.viewer.direction_from(v);
    Breakdown {
        emission: material.emission.truncate(),
        global_ambient: (material.ambient * lights.model.ambient).truncate(),
        lights: lights
            .lights()
            .iter()
            .map(|light| light_terms(&lights.model, material, light, v, n, vp_e))
            .collect(),
    }
}

/// The final colour of one side: the breakdown summed, clamped as GL clamps
/// it, with the diffuse alpha.
pub fn color(
    lights: &LightSet,
    material: &SurfaceMaterial,
    side: Side,
    v: DVec3,
    normal: DVec3,
) -> DVec4 {
    let alpha = material.side(side).diffuse.w;
    evaluate(lights, material, side, v, normal).color(lights.model.color_control, alpha)
}

/// One light's contribution: `att_i · spot_i · [ambient + diffuse + f_i·specular]`.
fn light_terms(
    model: &LightModel,
    material: &Material,
    light: &Light,
    v: DVec3,
    n: DVec3,
    vp_e: DVec3,
) -> LightTerms {
    let (vp_pli, attenuation) = match light.position {
        LightPosition::Directional(towards_light) => (towards_light, 1.0),
        LightPosition::Positional(p_pli) => {
            let to_light = p_pli - v;
            (unit_or_zero(to_light), attenuation(model, light, to_light))
        }
    };
    let spot = light.spot.factor(-vp_pli);
    let scale = attenuation * spot;

    let n_dot_vp = n.dot(vp_pli).max(0.0);
    // f_i: the specular term exists only where the light reaches the front of
    // the surface.
    let f_i = if n_dot_vp > 0.0 { 1.0 } else { 0.0 };
    let specular_base = match model.specular_model {
        SpecularModel::BlinnPhong => {
            let h = unit_or_zero(vp_pli + vp_e);
            n.dot(h)
        }
        SpecularModel::Phong => {
            let r = 2.0 * n.dot(vp_pli) * n - vp_pli;
            r.dot(vp_e)
        }
    };
    let specular_factor = f_i * spec_pow(specular_base, material.shininess);

    LightTerms {
        ambient: scale * (material.ambient * light.ambient).truncate(),
        diffuse: scale * n_dot_vp * (material.diffuse * light.diffuse).truncate(),
        specular: scale * specular_factor * (material.specular * light.specular).truncate(),
        attenuation,
        spot,
    }
}

/// `att_i = 1 / (k0 + k1·d + k2·d²)`, capped (see the module docs) and
/// optionally clamped at 1.
fn attenuation(model: &LightModel, light: &Light, to_light: DVec3) -> f64 {
    let [k0, k1, k2] = light.attenuation;
    let d = to_light.length();
    let att = (1.0 / (k0 + k1 * d + k2 * d * d)).min(MAX_ATTENUATION);
    if model.attenuation_clamp {
        att.min(1.0)
    } else {
        att
    }
}

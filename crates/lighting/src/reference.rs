//! The reference evaluator: section 2.14.1 in f64, one vertex at a time, term
//! by term. It is the ground truth the faster paths are measured against, so
//! it is written to be read next to the specification, not to be fast.
//!
//! It also evaluates the equation as a port with known mistakes would
//! ([`evaluate_port`], [`color_port`]): each [`Deviation`] is a switch at
//! the one place of the equation it changes, and with none of them on the
//! evaluation is GL's, operation for operation.

use glam::{DVec3, DVec4};

use super::deviation::{CLAMPED_EXPONENT, Deviation, Deviations, srgb_encode};
use super::terms::{Breakdown, LightTerms};
use super::{
    ColorControl, Light, LightModel, LightPosition, LightSet, MAX_ATTENUATION, MAX_RAW_NORMAL,
    Material, Side, SpecularModel, SurfaceMaterial, Viewer, spec_pow, unit_or_zero,
};

/// How a port evaluates the equation: GL's, with `deviations`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Port {
    pub deviations: Deviations,
    /// The viewer of the other kind than the light set's, for
    /// [`Deviation::ViewerSwapped`]: the eye point where GL has the infinite
    /// viewer, the infinite direction where GL has the local one (see
    /// [`Port::swapped_viewer`]).
    pub swapped_viewer: Viewer,
}

impl Port {
    /// GL itself.
    pub fn gl(lights: &LightSet) -> Self {
        Self {
            deviations: Deviations::NONE,
            swapped_viewer: lights.viewer,
        }
    }

    /// The viewer GL would use with `GL_LIGHT_MODEL_LOCAL_VIEWER` the other
    /// way: `local_viewer` is the light set's, `eye` the eye point and
    /// `towards_eye` the infinite viewer's unit direction (in eye space the
    /// origin and +z; with a view, its eye and `unit(eye − target)`).
    pub fn swapped_viewer(local_viewer: bool, eye: DVec3, towards_eye: DVec3) -> Viewer {
        if local_viewer {
            Viewer::Infinite(towards_eye)
        } else {
            Viewer::Local(eye)
        }
    }

    fn has(&self, d: Deviation) -> bool {
        self.deviations.contains(d)
    }

    /// `ported` where the port has `d`, else `gl`.
    fn choose<T>(&self, d: Deviation, ported: T, gl: T) -> T {
        if self.has(d) { ported } else { gl }
    }
}

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
    evaluate_port(lights, &Port::gl(lights), material, side, v, normal)
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

/// [`evaluate`] as `port` evaluates it. With [`Deviation::TwoSideIgnored`]
/// the back side is the front side.
pub fn evaluate_port(
    lights: &LightSet,
    port: &Port,
    material: &SurfaceMaterial,
    side: Side,
    v: DVec3,
    normal: DVec3,
) -> Breakdown {
    evaluate_with_alpha(lights, port, material, side, v, normal).0
}

/// [`color`] as `port` evaluates it: its breakdown, summed and written as
/// the port writes it (see the output deviations).
pub fn color_port(
    lights: &LightSet,
    port: &Port,
    material: &SurfaceMaterial,
    side: Side,
    v: DVec3,
    normal: DVec3,
) -> DVec4 {
    let side = lit_side(port, side);
    let (breakdown, summed_alpha) = evaluate_with_alpha(lights, port, material, side, v, normal);
    let diffuse_alpha = material.side(side).diffuse.w;
    let control = port.choose(
        Deviation::SeparateSpecularIgnored,
        ColorControl::Single,
        lights.model.color_control,
    );
    let alpha = port.choose(Deviation::AlphaSummed, summed_alpha, diffuse_alpha);
    let color = port.choose(
        Deviation::UnclampedOutput,
        breakdown.unclamped().extend(alpha),
        breakdown.color(control, alpha),
    );
    port.choose(
        Deviation::SrgbEncoded,
        DVec3::from_array(color.truncate().to_array().map(srgb_encode)).extend(color.w),
        color,
    )
}

/// The side whose material and normal light `side` for `port`.
fn lit_side(port: &Port, side: Side) -> Side {
    port.choose(Deviation::TwoSideIgnored, Side::Front, side)
}

/// The breakdown, and the sum of its terms' alphas (for
/// [`Deviation::AlphaSummed`]).
fn evaluate_with_alpha(
    lights: &LightSet,
    port: &Port,
    material: &SurfaceMaterial,
    side: Side,
    v: DVec3,
    normal: DVec3,
) -> (Breakdown, f64) {
    let (material, n) = match lit_side(port, side) {
        Side::Front => (&material.front, normal),
        Side::Back => (&material.back, -normal),
    };
    let n = if lights.model.normalize_normals {
        port.choose(Deviation::NormalsUnnormalized, as_given(n), unit_or_zero(n))
    } else {
        n
    };
    let viewer = port.choose(Deviation::ViewerSwapped, port.swapped_viewer, lights.viewer);
    let vp_e = viewer.direction_from(v);
    let emission = port.choose(Deviation::EmissionMissing, DVec4::ZERO, material.emission);
    let global_ambient = port.choose(
        Deviation::GlobalAmbientMissing,
        DVec4::ZERO,
        material.ambient * lights.model.ambient,
    );
    let terms: Vec<_> = lights
        .lights()
        .iter()
        .map(|light| light_terms(&lights.model, port, material, light, v, n, vp_e))
        .collect();
    let summed_alpha = terms.iter().fold(emission.w + global_ambient.w, |sum, t| {
        sum + t.ambient.w + t.diffuse.w + t.specular.w
    });
    let breakdown = Breakdown {
        emission: emission.truncate(),
        global_ambient: global_ambient.truncate(),
        lights: terms.iter().map(|t| t.truncate()).collect(),
    };
    (breakdown, summed_alpha)
}

/// A normal used as given by a port that does not normalise, its length
/// capped at [`MAX_RAW_NORMAL`] (the bound GL's own unnormalised normals
/// have), so that the terms stay finite.
fn as_given(n: DVec3) -> DVec3 {
    let length = n.length();
    if length > MAX_RAW_NORMAL {
        unit_or_zero(n) * MAX_RAW_NORMAL
    } else {
        n
    }
}

/// One light's terms with their alphas.
struct Terms4 {
    ambient: DVec4,
    diffuse: DVec4,
    specular: DVec4,
    attenuation: f64,
    spot: f64,
}

impl Terms4 {
    fn truncate(&self) -> LightTerms {
        LightTerms {
            ambient: self.ambient.truncate(),
            diffuse: self.diffuse.truncate(),
            specular: self.specular.truncate(),
            attenuation: self.attenuation,
            spot: self.spot,
        }
    }
}

/// One light's contribution: `att_i · spot_i · [ambient + diffuse + f_i·specular]`.
fn light_terms(
    model: &LightModel,
    port: &Port,
    material: &Material,
    light: &Light,
    v: DVec3,
    n: DVec3,
    vp_e: DVec3,
) -> Terms4 {
    let (vp_pli, attenuation) = match light.position {
        LightPosition::Directional(towards_light) => (towards_light, 1.0),
        LightPosition::Positional(p_pli) => {
            let to_light = p_pli - v;
            let att = port.choose(
                Deviation::AttenuationIgnored,
                1.0,
                attenuation(model, light, to_light),
            );
            (unit_or_zero(to_light), att)
        }
    };
    let spot = spot_factor(port, light, -vp_pli);
    let scale = attenuation * spot;
    let ambient_scale = port.choose(Deviation::AmbientSpotIgnored, attenuation, scale);
    let ambient = port.choose(
        Deviation::LightAmbientMissing,
        DVec4::ZERO,
        ambient_scale * (material.ambient * light.ambient),
    );

    let n_dot_vp_raw = n.dot(vp_pli);
    let n_dot_vp = n_dot_vp_raw.max(0.0);
    // f_i: the specular term exists only where the light reaches the front of
    // the surface.
    let f_i = if n_dot_vp > 0.0 || port.has(Deviation::SpecularUngated) {
        1.0
    } else {
        0.0
    };
    let diffuse_base = port.choose(Deviation::DiffuseUnclamped, n_dot_vp_raw, n_dot_vp);
    let specular_model = port.choose(
        Deviation::PhongSpecular,
        SpecularModel::Phong,
        model.specular_model,
    );
    let specular_base = match specular_model {
        SpecularModel::BlinnPhong => {
            let h = vp_pli + vp_e;
            port.choose(
                Deviation::HalfVectorUnnormalized,
                n.dot(h),
                n.dot(unit_or_zero(h)),
            )
        }
        SpecularModel::Phong => {
            let r = 2.0 * n.dot(vp_pli) * n - vp_pli;
            r.dot(vp_e)
        }
    };
    let specular_factor = f_i * port_pow(port, specular_base, material.shininess);

    Terms4 {
        ambient,
        diffuse: scale * diffuse_base * (material.diffuse * light.diffuse),
        specular: scale * specular_factor * (material.specular * light.specular),
        attenuation,
        spot,
    }
}

/// `spot_i` of `light` as `port` computes it, from `P_pli V` (the unit
/// vector from the light to the vertex).
pub fn spot_factor(port: &Port, light: &Light, p_pli_v: DVec3) -> f64 {
    let directional = matches!(light.position, LightPosition::Directional(_));
    if directional && port.has(Deviation::DirectionalSpotIgnored) {
        return 1.0;
    }
    let spot = &light.spot;
    let cos_cutoff = port.choose(
        Deviation::SpotCutoffRadians,
        spot.cutoff.cos(),
        spot.cos_cutoff(),
    );
    let exponent = port.choose(Deviation::SpotExponentIgnored, 0.0, spot.exponent);
    spot.factor_of(p_pli_v, cos_cutoff, |x| port_pow(port, x, exponent))
}

/// [`spec_pow`] as `port` takes it: the exponent clamped, and `0^0` = 0,
/// where the port does so.
fn port_pow(port: &Port, x: f64, s: f64) -> f64 {
    let s = port.choose(Deviation::ExponentsClamped, s.min(CLAMPED_EXPONENT), s);
    if s == 0.0 && x <= 0.0 && port.has(Deviation::ZeroPowerZero) {
        0.0
    } else {
        spec_pow(x, s)
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

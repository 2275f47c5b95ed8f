//! The OpenGL 2.1 fixed-function lighting model (compatibility specification,
//! section 2.14.1), as pure functions over validated parameters.
//!
//! For a vertex at `V` with normal `n`, one side's colour is
//!
//! ```text
//! c = e_cm + a_cm·a_cs
//!   + Σ_i att_i · spot_i · [a_cm·a_cli + (n⊙VP_pli) d_cm·d_cli + f_i (n⊙ĥ_i)^s_rm s_cm·s_cli]
//! ```
//!
//! where `⊙` is the dot product clamped at zero. The names in this module follow
//! the specification: `VP_pli` is the unit vector from the vertex to light `i`,
//! `VP_e` the unit vector to the eye, `ĥ_i` the normalised halfway vector.
//! Every vector lives in the space of the request: eye space when the request
//! has no view (eye at the origin, infinite viewer along +z), world space
//! otherwise; [`Viewer`] carries the difference.
//!
//! [`reference`] is the ground truth, in f64, written for clarity; [`kernel`]
//! holds the f32 paths that are measured against it.
//!
//! # Decisions where the specification is silent or implementations differ
//!
//! - **0^0 = 1.** Section 2.1.1 defines it so. With shininess 0 every lit vertex
//!   (n·VP > 0) gets the full specular colour even where n·ĥ = 0; the same
//!   holds for a spot exponent of 0 at the edge of a 90° cone. Mesa's llvmpipe
//!   returns pow(0, 0) = 0 on one path; glint follows the specification.
//! - **The spot cone test is `≥ cos(cutoff)`,** as the specification writes it;
//!   Mesa tests with a strict `>`, so a vertex exactly on the cone's edge is lit
//!   here and dark there. A cutoff of exactly 90 uses cos = 0 exactly (not the
//!   6e-17 of a floating-point cosine), so a vertex in the light's plane is on
//!   the edge; and because the specification clamps the dot product (`⊙`)
//!   before the test, so is every vertex behind the light: with exponent 0 it
//!   gets the full light (0^0 = 1), with exponent > 0 none. Mesa, testing the
//!   raw dot product with `>`, leaves both dark. A cutoff of 0 lights only
//!   points exactly on the axis.
//! - **Spotlights that are directional.** The specification defines `P_pli V`
//!   for a light at infinity (w = 0) as the negated light direction, so the
//!   spot factor of a directional light is a constant that depends only on the
//!   angle between its direction and its spot direction. glint follows the
//!   text; Mesa's fixed-function code ignores the spot of a directional light.
//! - **Normalising a zero vector gives the zero vector,** never NaN. So a
//!   zero-length normal gets no diffuse and no specular light (n⊙VP = 0, hence
//!   f_i = 0); a light exactly at the vertex lights it with its ambient term
//!   only; a local viewer exactly at the vertex makes ĥ = VP_pli (and r·v = 0
//!   for the Phong variant).
//! - **Grazing light.** `f_i` is 1 exactly when n·VP_pli > 0: a light in the
//!   tangent plane (n·VP = 0 exactly) contributes no specular, one just above
//!   it contributes its specular term continuously (so with shininess 0 the
//!   specular term jumps from 0 to s_cm·s_cli, as the specification implies).
//! - **Attenuation is capped at [`MAX_ATTENUATION`]** (1e10). `1/(k0 + k1·d + k2·d²)`
//!   is unbounded only when the light (nearly) touches the vertex with k0 = 0
//!   (or tiny); a light exactly at the vertex with k0 = 0 gets the cap. The
//!   cap, with the bounds on colours and raw normals, keeps every term finite
//!   in f32 as well as f64, and is far above anything that changes a clamped
//!   colour.
//! - **Homogeneous light positions** with w ≠ 0 are divided by w, as a position
//!   is in the specification's `VP_pli`.
//! - **Normals are normalised by scaling first** (divide by the largest
//!   component, then normalise), so normals of length 1e-300 or 1e300 keep
//!   their direction when `normalize_normals` is on.

pub mod deviation;
mod fastmath;
pub mod kernel;
pub mod reference;
pub mod terms;
#[cfg(test)]
mod test_rng;

/// The f32 arithmetic of the tiers (`pow` of a cosine, whole powers, their
/// plans), for the evaluators outside this crate that must keep the tiers'
/// bounds: the comparison of a port's colours evaluates its deviations with
/// it.
pub mod tier_math {
    pub use crate::fastmath::{
        Accurate, Cosine, Fast, Math, Power, Powers, cos2_of_unit, cosine, cosine_of_unit,
        whole_base,
    };
}

use glam::{DVec3, DVec4};

/// The largest attenuation factor glint uses; see the module docs.
pub const MAX_ATTENUATION: f64 = 1e10;

/// The largest value of a specular or spot power. Powers above 1 arise only
/// from normals longer than 1 with `normalize_normals` off.
pub const MAX_POWER: f64 = 1e10;

/// The largest magnitude of a colour component. With [`MAX_ATTENUATION`],
/// [`MAX_POWER`] and [`MAX_RAW_NORMAL`] it bounds every term by about 1e32,
/// so that 64 lights' terms sum without overflow even in f32.
pub const MAX_COLOR: f64 = 1e6;

/// The largest magnitude of a normal's component when normals are used as
/// given (`normalize_normals` off).
pub const MAX_RAW_NORMAL: f64 = 1e6;

/// The largest magnitude of a coordinate (of a vertex, a light position after
/// division by w, an eye). f32 holds it with room to spare for differences.
pub const MAX_COORDINATE: f64 = 1e30;

/// A material, one side's `*_cm` parameters (GL's defaults by [`Default`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub ambient: DVec4,
    pub diffuse: DVec4,
    pub specular: DVec4,
    pub emission: DVec4,
    /// `s_rm`, the specular exponent; any finite value >= 0.
    pub shininess: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            ambient: DVec4::new(0.2, 0.2, 0.2, 1.0),
            diffuse: DVec4::new(0.8, 0.8, 0.8, 1.0),
            specular: DVec4::new(0.0, 0.0, 0.0, 1.0),
            emission: DVec4::new(0.0, 0.0, 0.0, 1.0),
            shininess: 0.0,
        }
    }
}

/// A spotlight's cone. A cutoff of 180 degrees means no cone at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// `ŝ_dli`, unit length (validation normalises it).
    pub direction: DVec3,
    /// `s_rli`, >= 0.
    pub exponent: f64,
    /// `c_rli` in degrees: 180, or within [0, 90].
    pub cutoff: f64,
}

impl Spot {
    pub fn is_cone(&self) -> bool {
        self.cutoff != 180.0
    }

    /// cos(c_rli), exact at the cutoffs 0 and 90 where the cone test is most
    /// sensitive to rounding.
    pub fn cos_cutoff(&self) -> f64 {
        match self.cutoff {
            90.0 => 0.0,
            0.0 => 1.0,
            c => c.to_radians().cos(),
        }
    }
}

impl Spot {
    /// `spot_i`, from `P_pli V`, the unit vector from the light to the vertex
    /// (the negated light direction for a light at infinity).
    pub fn factor(&self, p_pli_v: DVec3) -> f64 {
        self.factor_of(p_pli_v, self.cos_cutoff(), |x| spec_pow(x, self.exponent))
    }

    /// [`Spot::factor`] with the cone's cosine and the power given: a port
    /// may compute either its own way (see [`deviation`]).
    pub fn factor_of(&self, p_pli_v: DVec3, cos_cutoff: f64, power: impl Fn(f64) -> f64) -> f64 {
        if !self.is_cone() {
            return 1.0;
        }
        // The specification clamps this dot product (`⊙`) before the cone
        // test, so with a 90° cutoff a vertex behind the light is on the edge.
        let cos_angle = p_pli_v.dot(self.direction).max(0.0);
        if cos_angle >= cos_cutoff {
            power(cos_angle)
        } else {
            0.0
        }
    }
}

impl Default for Spot {
    fn default() -> Self {
        Self {
            direction: DVec3::NEG_Z,
            exponent: 0.0,
            cutoff: 180.0,
        }
    }
}

/// Where a light is: `P_pli` with w = 0 (a direction) or w ≠ 0 (a point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightPosition {
    /// Unit vector towards the light (the normalised xyz of `P_pli`).
    Directional(DVec3),
    /// The point `P_pli / w`.
    Positional(DVec3),
}

/// One light, `*_cli` and friends; [`Default`] is GL_LIGHT0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub position: LightPosition,
    pub ambient: DVec4,
    pub diffuse: DVec4,
    pub specular: DVec4,
    /// k0, k1, k2; all >= 0 and not all zero. Unused for directional lights.
    pub attenuation: [f64; 3],
    pub spot: Spot,
}

impl Default for Light {
    fn default() -> Self {
        Self {
            position: LightPosition::Directional(DVec3::Z),
            ambient: DVec4::new(0.0, 0.0, 0.0, 1.0),
            diffuse: DVec4::ONE,
            specular: DVec4::ONE,
            attenuation: [1.0, 0.0, 0.0],
            spot: Spot::default(),
        }
    }
}

/// GL_LIGHT_MODEL_COLOR_CONTROL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorControl {
    Single,
    /// GL 1.2's SEPARATE_SPECULAR_COLOR: the specular sum is a second colour,
    /// clamped on its own and added after the primary colour is clamped.
    SeparateSpecular,
}

/// Which specular term to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpecularModel {
    /// GL's `(n⊙ĥ)^s`.
    BlinnPhong,
    /// Phong's `(r⊙VP_e)^s`, with `r = 2(n·VP)n − VP` the reflected light
    /// direction.
    Phong,
}

/// The light model state, `GL_LIGHT_MODEL_*` plus the variants glint offers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightModel {
    /// `a_cs`, the global ambient colour.
    pub ambient: DVec4,
    pub local_viewer: bool,
    pub two_side: bool,
    pub color_control: ColorControl,
    pub specular_model: SpecularModel,
    /// `att = min(att, 1)`.
    pub attenuation_clamp: bool,
    /// GL_NORMALIZE: rescale normals to unit length before lighting.
    pub normalize_normals: bool,
}

impl Default for LightModel {
    fn default() -> Self {
        Self {
            ambient: DVec4::new(0.2, 0.2, 0.2, 1.0),
            local_viewer: false,
            two_side: false,
            color_control: ColorControl::Single,
            specular_model: SpecularModel::BlinnPhong,
            attenuation_clamp: false,
            normalize_normals: true,
        }
    }
}

/// The eye as the lighting equation sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Viewer {
    /// A local viewer at this point.
    Local(DVec3),
    /// An infinite viewer in this unit direction (from the scene to the eye).
    Infinite(DVec3),
}

impl Viewer {
    /// `VP_e` at point `p`: the unit vector towards the eye.
    pub fn direction_from(&self, p: DVec3) -> DVec3 {
        match *self {
            Viewer::Local(eye) => unit_or_zero(eye - p),
            Viewer::Infinite(dir) => dir,
        }
    }
}

/// What lights a scene, whatever its surfaces are made of: the light model,
/// the lights and the viewer. A request has one; every material of a render
/// is lit by it.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSet {
    pub model: LightModel,
    /// At most [`MAX_LIGHTS`], so that a [`LightMask`] has a bit for each.
    lights: Vec<Light>,
    pub viewer: Viewer,
}

/// One bit per light of a [`LightSet`], bit `i` for light `i`: which lights
/// reach a point (the renderer's shadow rays).
pub type LightMask = u64;

/// The most lights a [`LightSet`] holds: one per bit of a [`LightMask`].
pub const MAX_LIGHTS: usize = LightMask::BITS as usize;

/// A light set was given more than [`MAX_LIGHTS`] lights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyLights(pub usize);

impl std::fmt::Display for TooManyLights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} lights, more than the {MAX_LIGHTS} a light set holds",
            self.0
        )
    }
}

impl std::error::Error for TooManyLights {}

impl LightSet {
    /// The light set of `lights`, or [`TooManyLights`] past [`MAX_LIGHTS`].
    pub fn new(
        model: LightModel,
        lights: Vec<Light>,
        viewer: Viewer,
    ) -> Result<Self, TooManyLights> {
        if lights.len() > MAX_LIGHTS {
            return Err(TooManyLights(lights.len()));
        }
        Ok(Self {
            model,
            lights,
            viewer,
        })
    }

    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The lights, to change in place: their number stays.
    pub fn lights_mut(&mut self) -> &mut [Light] {
        &mut self.lights
    }

    /// The eye-space viewer GL uses when the request has no view.
    pub fn eye_space_viewer(local_viewer: bool) -> Viewer {
        if local_viewer {
            Viewer::Local(DVec3::ZERO)
        } else {
            Viewer::Infinite(DVec3::Z)
        }
    }

    /// Whether a vertex's colour depends on where it is: a local viewer or
    /// a light at a point. Scenes of directional lights seen from infinity
    /// depend on normals alone.
    pub fn depends_on_position(&self) -> bool {
        matches!(self.viewer, Viewer::Local(_))
            || self
                .lights
                .iter()
                .any(|l| matches!(l.position, LightPosition::Positional(_)))
    }
}

/// What a surface is made of, as GL sees it: a material for each side. The
/// back material lights back faces when the light model is two-sided.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceMaterial {
    pub front: Material,
    pub back: Material,
}

impl SurfaceMaterial {
    /// The same material on both sides.
    pub fn both_sides(material: Material) -> Self {
        Self {
            front: material,
            back: material,
        }
    }

    /// The material of `side`.
    pub fn side(&self, side: Side) -> &Material {
        match side {
            Side::Front => &self.front,
            Side::Back => &self.back,
        }
    }
}

/// Which side of the surface is lit: the back side uses the back material and
/// the negated normal (two-sided lighting).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Front,
    Back,
}

/// The evaluator a request asks for, trading speed for accuracy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// f64, the ground truth: [`reference`].
    Reference,
    /// f32, within 1e-5 of the reference: [`kernel`] with [`Tier::Accurate`](kernel::Tier::Accurate).
    #[default]
    Accurate,
    /// f32 with approximations, within 1/512 of the reference.
    Fast,
}

impl Precision {
    /// The documented bound on the absolute error of any colour channel
    /// against the reference evaluator. The reference's own is the rounding
    /// of its colours to f32 for the response.
    pub fn max_abs_error(self) -> f64 {
        match self {
            Precision::Reference => f32::EPSILON as f64 / 2.0,
            Precision::Accurate => 1e-5,
            Precision::Fast => 1.0 / 512.0,
        }
    }

    /// The f32 tier that evaluates this precision; `None` for the reference.
    pub fn tier(self) -> Option<kernel::Tier> {
        match self {
            Precision::Reference => None,
            Precision::Accurate => Some(kernel::Tier::Accurate),
            Precision::Fast => Some(kernel::Tier::Fast),
        }
    }
}

/// The middle of the bounding box of `points` (zero for none): where the
/// f32 evaluators recentre positions, so that a vertex and a light 1 unit
/// apart near (1e7, 1e7, 1e7) keep their direction.
/// In parallel on the current rayon pool: the minimum and maximum are exact
/// in any order.
pub fn bounding_box_centre(points: &[DVec3]) -> DVec3 {
    use rayon::prelude::*;
    let empty = || (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (lo, hi) = points
        .par_chunks(1 << 14)
        .map(|chunk| {
            chunk
                .iter()
                .fold(empty(), |(lo, hi), &p| (lo.min(p), hi.max(p)))
        })
        .reduce(empty, |(lo1, hi1), (lo2, hi2)| (lo1.min(lo2), hi1.max(hi2)));
    if points.is_empty() {
        DVec3::ZERO
    } else {
        (lo + hi) * 0.5
    }
}

/// Normalises `v`, or returns zero for a zero (or non-finite) vector.
///
/// Scales by the largest component first so that lengths near the ends of the
/// f64 range neither overflow nor underflow.
pub fn unit_or_zero(v: DVec3) -> DVec3 {
    let scale = v.abs().max_element();
    if !(scale > 0.0 && scale.is_finite()) {
        return DVec3::ZERO;
    }
    let scaled = v / scale;
    scaled / scaled.length()
}

/// `x^s` for the specular and spot powers: x is clamped at 0 and 0^0 = 1
/// (section 2.1.1). The result is capped at [`MAX_POWER`].
pub fn spec_pow(x: f64, s: f64) -> f64 {
    if s == 0.0 {
        1.0
    } else {
        x.max(0.0).powf(s).min(MAX_POWER)
    }
}

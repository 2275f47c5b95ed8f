//! Helpers shared by the lighting tests: a closeness assertion that prints
//! both sides and their difference, [`Scene`] (one material under a light
//! set), and constructors for scenes simple enough to light by hand.

use std::fmt::Debug;

use glam::{DVec3, DVec4, Vec3, Vec4};
use glint_lighting::kernel::{Colors, InstructionSet, Kernel, Tier};
use glint_lighting::terms::Breakdown;
use glint_lighting::{
    ColorControl, Light, LightModel, LightPosition, LightSet, Material, Side, SpecularModel,
    SurfaceMaterial, Viewer, reference,
};

/// The default tolerance of [`assert_close!`]: hand arithmetic and the f64
/// reference agree to a few ulps; 1e-12 leaves room for that and nothing more.
pub const TIGHT: f64 = 1e-12;

/// The documented bound of the `accurate` tier (README, api/openapi.yaml):
/// every channel within 1e-5 of the reference.
pub const ACCURATE_TOL: f64 = 1e-5;

/// The documented bound of the `fast` tier: 1/512.
pub const FAST_TOL: f64 = 1.0 / 512.0;

/// Both f32 tiers with their documented bounds.
pub const TIERS: [(Tier, f64); 2] = [(Tier::Accurate, ACCURATE_TOL), (Tier::Fast, FAST_TOL)];

/// `1/√2`, the cosine of 45°.
pub const R2: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Asserts that two scalars or vectors (f64 or f32) agree within a tolerance
/// on every component, printing both sides, their difference and the
/// tolerance when they do not. NaN never agrees with anything.
///
/// ```text
/// assert_close!(actual, expected);                     // tolerance TIGHT
/// assert_close!(actual, expected, tol = 1e-5);
/// assert_close!(actual, expected, tol = 1e-5, "vertex {i}");
/// ```
macro_rules! assert_close {
    ($actual:expr, $expected:expr $(,)?) => {
        assert_close!($actual, $expected, tol = $crate::lighting::support::TIGHT)
    };
    ($actual:expr, $expected:expr, tol = $tol:expr $(,)?) => {
        $crate::lighting::support::check_close(
            &$actual,
            &$expected,
            $tol,
            stringify!($actual),
            stringify!($expected),
            None,
        )
    };
    ($actual:expr, $expected:expr, tol = $tol:expr, $($context:tt)+) => {
        $crate::lighting::support::check_close(
            &$actual,
            &$expected,
            $tol,
            stringify!($actual),
            stringify!($expected),
            Some(format!($($context)+)),
        )
    };
}

/// Anything [`assert_close!`] compares: its components as f64.
pub trait Components: Debug {
    fn components(&self) -> Vec<f64>;
}

impl Components for f64 {
    fn components(&self) -> Vec<f64> {
        vec![*self]
    }
}

impl Components for f32 {
    fn components(&self) -> Vec<f64> {
        vec![f64::from(*self)]
    }
}

impl Components for DVec3 {
    fn components(&self) -> Vec<f64> {
        self.to_array().to_vec()
    }
}

impl Components for DVec4 {
    fn components(&self) -> Vec<f64> {
        self.to_array().to_vec()
    }
}

impl Components for Vec3 {
    fn components(&self) -> Vec<f64> {
        self.as_dvec3().to_array().to_vec()
    }
}

impl Components for Vec4 {
    fn components(&self) -> Vec<f64> {
        self.as_dvec4().to_array().to_vec()
    }
}

/// The function behind [`assert_close!`].
#[track_caller]
pub fn check_close<A: Components + ?Sized, E: Components + ?Sized>(
    actual: &A,
    expected: &E,
    tol: f64,
    actual_expr: &str,
    expected_expr: &str,
    context: Option<String>,
) {
    let a = actual.components();
    let e = expected.components();
    assert_eq!(
        a.len(),
        e.len(),
        "assert_close!: `{actual_expr}` and `{expected_expr}` have different dimensions"
    );
    let diff: Vec<f64> = a.iter().zip(&e).map(|(a, e)| a - e).collect();
    // `!(d <= tol)` so that a NaN on either side fails.
    let ok = diff.iter().all(|d| d.abs() <= tol);
    if !ok {
        let worst = diff.iter().fold(
            0.0f64,
            |m, d| {
                if d.is_nan() { f64::NAN } else { m.max(d.abs()) }
            },
        );
        panic!(
            "assert_close! failed{}\n  actual:     {actual_expr}\n            = {actual:?}\n  expected:   {expected_expr}\n            = {expected:?}\n  difference: {diff:?} (largest {worst:e}, tolerance {tol:e})",
            context.map(|c| format!(" ({c})")).unwrap_or_default(),
        );
    }
}

/// Opaque black: the colour of a term that should vanish.
pub const BLACK: DVec4 = DVec4::new(0.0, 0.0, 0.0, 1.0);

/// An opaque colour.
pub fn rgb(r: f64, g: f64, b: f64) -> DVec4 {
    DVec4::new(r, g, b, 1.0)
}

/// An opaque grey.
pub fn grey(x: f64) -> DVec4 {
    rgb(x, x, x)
}

/// The unit vector along (x, y, z).
pub fn unit(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z).normalize()
}

/// A material that reflects nothing, so that a test turns on only the terms
/// it computes by hand.
pub fn black_material() -> Material {
    Material {
        ambient: BLACK,
        diffuse: BLACK,
        specular: BLACK,
        emission: BLACK,
        shininess: 0.0,
    }
}

/// A light with no colour at `position`: no attenuation (k = 1, 0, 0), no
/// cone.
pub fn black_light(position: LightPosition) -> Light {
    Light {
        position,
        ambient: BLACK,
        diffuse: BLACK,
        specular: BLACK,
        ..Light::default()
    }
}

/// GL's light model without global ambient (a_cs = 0).
pub fn dark_model() -> LightModel {
    LightModel {
        ambient: BLACK,
        ..LightModel::default()
    }
}

/// One material under a light set: what most lighting tests light.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub lights: LightSet,
    pub material: SurfaceMaterial,
}

impl Scene {
    /// The reference colour of `side` at `v` with normal `n`.
    pub fn color(&self, side: Side, v: DVec3, n: DVec3) -> DVec4 {
        reference::color(&self.lights, &self.material, side, v, n)
    }

    /// The reference breakdown of `side` at `v` with normal `n`.
    pub fn evaluate(&self, side: Side, v: DVec3, n: DVec3) -> Breakdown {
        reference::evaluate(&self.lights, &self.material, side, v, n)
    }

    /// Lights a batch with the f32 kernel of `tier`: the light set prepared
    /// for `positions`, then the material (the one place the tests build a
    /// kernel and light with it in a single step).
    pub fn kernel_colors(&self, tier: Tier, positions: &[DVec3], normals: &[DVec3]) -> Colors {
        let kernel = Kernel::new(&self.lights, positions);
        let products = kernel.products(&self.material);
        kernel.light(tier, &products, &kernel.prepare(positions, normals))
    }
}

/// The light set of `lights` under `model` seen by `viewer` (the tests use
/// far fewer than `MAX_LIGHTS`).
pub fn light_set(model: LightModel, lights: Vec<Light>, viewer: Viewer) -> LightSet {
    LightSet::new(model, lights, viewer).expect("a test's light set holds few lights")
}

/// `set` with its lights replaced by `lights`: the same model and viewer.
pub fn with_lights(set: &LightSet, lights: Vec<Light>) -> LightSet {
    light_set(set.model, lights, set.viewer)
}

/// A scene in eye space (GL's viewer for `model.local_viewer`: the eye at
/// the origin or at infinity along +z) with `material` on both sides.
pub fn eye_space(model: LightModel, material: Material, lights: Vec<Light>) -> Scene {
    Scene {
        lights: light_set(
            model,
            lights,
            LightSet::eye_space_viewer(model.local_viewer),
        ),
        material: SurfaceMaterial::both_sides(material),
    }
}

/// The front colour at `v` with normal `n`.
pub fn front(scene: &Scene, v: DVec3, n: DVec3) -> DVec4 {
    scene.color(Side::Front, v, n)
}

/// The front breakdown at `v` with normal `n`.
pub fn front_terms(scene: &Scene, v: DVec3, n: DVec3) -> Breakdown {
    scene.evaluate(Side::Front, v, n)
}

/// Asserts that every number of a breakdown is finite.
#[track_caller]
pub fn assert_finite_breakdown(b: &Breakdown, context: &str) {
    let mut all = vec![b.emission, b.global_ambient];
    for l in &b.lights {
        all.extend([l.ambient, l.diffuse, l.specular]);
        assert!(
            l.attenuation.is_finite() && l.spot.is_finite(),
            "non-finite factor ({context}): {l:?}"
        );
    }
    assert!(
        all.iter().all(|c| c.is_finite()),
        "non-finite term ({context}): {b:?}"
    );
}

/// Asserts that a colour is finite and within [0, 1] on every channel.
#[track_caller]
pub fn assert_unit_color(c: DVec4, context: &str) {
    assert!(
        c.to_array().iter().all(|x| (0.0..=1.0).contains(x)),
        "colour outside [0, 1] or NaN ({context}): {c:?}"
    );
}

/// The sides a kernel of `scene` lights.
pub fn kernel_sides(scene: &Scene) -> &'static [Side] {
    if scene.lights.model.two_side {
        &[Side::Front, Side::Back]
    } else {
        &[Side::Front]
    }
}

/// Compares the f32 kernel with the f64 reference on every channel of every
/// vertex and side: both tiers, in every build of the kernel this CPU runs
/// (not only the widest), within their documented bounds, each multiplied
/// by `scale`.
#[track_caller]
pub fn assert_kernel_matches_reference_scaled(
    scene: &Scene,
    positions: &[DVec3],
    normals: &[DVec3],
    scale: impl Fn(Side, DVec3, DVec3) -> f64,
) {
    let kernel = Kernel::new(&scene.lights, positions);
    let products = kernel.products(&scene.material);
    let vertices = kernel.prepare(positions, normals);
    for (isa, (tier, bound)) in InstructionSet::here().flat_map(|isa| TIERS.map(|t| (isa, t))) {
        let colors = kernel.light_on(isa, tier, &products, &vertices);
        assert_eq!(colors.front.len(), positions.len());
        assert_eq!(colors.back.is_some(), scene.lights.model.two_side);
        for &side in kernel_sides(scene) {
            let lit = match side {
                Side::Front => &colors.front,
                Side::Back => colors.back.as_ref().unwrap(),
            };
            for (i, ((&v, &n), &got)) in positions.iter().zip(normals).zip(lit).enumerate() {
                let want = scene.color(side, v, n);
                let tol = bound * scale(side, v, n);
                assert_close!(
                    got,
                    want,
                    tol = tol,
                    "{isa} build, {tier:?} tier, {side:?} side of vertex {i} at {v:?} with normal {n:?}"
                );
            }
        }
    }
}

/// [`assert_kernel_matches_reference_scaled`] with the documented bounds as
/// they are.
#[track_caller]
pub fn assert_kernel_matches_reference(scene: &Scene, positions: &[DVec3], normals: &[DVec3]) {
    assert_kernel_matches_reference_scaled(scene, positions, normals, |_, _, _| 1.0);
}

/// The light model that random scenes draw: the global ambient, and the
/// flags local viewer, two sides, separate specular, Phong, attenuation
/// clamp, normalisation, in that order.
pub fn model_of(
    ambient: DVec4,
    [local_viewer, two_side, separate, phong, clamp, normalize]: [bool; 6],
) -> LightModel {
    LightModel {
        ambient,
        local_viewer,
        two_side,
        color_control: if separate {
            ColorControl::SeparateSpecular
        } else {
            ColorControl::Single
        },
        specular_model: if phong {
            SpecularModel::Phong
        } else {
            SpecularModel::BlinnPhong
        },
        attenuation_clamp: clamp,
        normalize_normals: normalize,
    }
}

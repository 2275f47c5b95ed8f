//! The evaluator of many ports against the reference evaluator of each
//! port (`reference::color_port`, in f64, one vertex and one port at a
//! time): every model's colour, on both sides, within the documented bound
//! of the tier, on scenes that give every deviation something to change.

use glam::{DVec3, DVec4};
use glint_lighting::deviation::{Deviation, Deviations};
use glint_lighting::reference::{Port, color_port};
use glint_lighting::{
    ColorControl, Light, LightModel, LightPosition, LightSet, Material, Precision, Side,
    SpecularModel, Spot, SurfaceMaterial, Viewer, unit_or_zero,
};

use super::arith::{AccurateTier, Arith, FastTier, Real, Reference};
use super::plan::{Pass, PassScene};
use super::{BLOCK, Block, Points, unnormalized};

/// A scene to test on, with the viewer a swap gives.
pub(crate) struct TestScene {
    pub lights: LightSet,
    pub material: SurfaceMaterial,
    pub swapped_viewer: Viewer,
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
}

fn rgb(r: f64, g: f64, b: f64) -> DVec4 {
    DVec4::new(r, g, b, 1.0)
}

/// Lights of every kind: a directional light, a directional spotlight, a
/// point light with attenuation and a cone, a plain point light.
fn assorted_lights(cutoff: f64, exponent: f64) -> Vec<Light> {
    vec![
        Light {
            position: LightPosition::Directional(unit_or_zero(DVec3::new(0.3, 0.5, 1.0))),
            ambient: rgb(0.05, 0.05, 0.1),
            diffuse: rgb(0.6, 0.5, 0.4),
            specular: rgb(0.7, 0.7, 0.7),
            ..Light::default()
        },
        Light {
            position: LightPosition::Directional(unit_or_zero(DVec3::new(-0.4, 0.2, 1.0))),
            ambient: rgb(0.1, 0.0, 0.05),
            diffuse: rgb(0.3, 0.4, 0.6),
            specular: rgb(0.4, 0.5, 0.3),
            spot: Spot {
                direction: unit_or_zero(DVec3::new(0.4, -0.3, -1.0)),
                exponent,
                cutoff,
            },
            ..Light::default()
        },
        Light {
            position: LightPosition::Positional(DVec3::new(0.5, 1.0, 0.5)),
            ambient: rgb(0.1, 0.1, 0.05),
            diffuse: rgb(0.9, 0.7, 0.5),
            specular: rgb(0.8, 0.8, 0.9),
            attenuation: [0.5, 0.3, 0.1],
            spot: Spot {
                direction: unit_or_zero(DVec3::new(-0.2, -0.4, -1.0)),
                exponent,
                cutoff,
            },
        },
        Light {
            position: LightPosition::Positional(DVec3::new(-1.5, -0.5, 1.0)),
            ambient: rgb(0.05, 0.1, 0.1),
            diffuse: rgb(0.4, 0.6, 0.5),
            specular: rgb(0.5, 0.4, 0.6),
            ..Light::default()
        },
    ]
}

/// Points on a bumpy patch in front of the eye, with normals of varied
/// direction and length (some facing away, one zero).
pub(crate) fn patch(count: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    (0..count)
        .map(|i| {
            let u = (i % 13) as f64 / 12.0;
            let v = (i / 13) as f64 / (count / 13).max(1) as f64;
            let p = DVec3::new(u * 3.0 - 1.5, v * 3.0 - 1.5, -2.0 - 0.3 * (u * 5.0).sin());
            let n = DVec3::new(
                (u * 7.0).sin(),
                (v * 5.0).cos() * 0.8,
                0.9 + 0.5 * (u * v * 9.0).cos(),
            );
            let length = 0.5 + (i % 7) as f64 * 0.25;
            let n = if i == 5 { DVec3::ZERO } else { n * length };
            (p, n)
        })
        .unzip()
}

/// A scene where every deviation has something to change: four lights of
/// every kind, emission, ambient, specular, normals not of unit length, a
/// two-sided model with a back material of its own.
pub(crate) fn rich_scene(
    model: LightModel,
    shininess: f64,
    cutoff: f64,
    exponent: f64,
) -> TestScene {
    let viewer = LightSet::eye_space_viewer(model.local_viewer);
    let swapped_viewer = Port::swapped_viewer(model.local_viewer, DVec3::ZERO, DVec3::Z);
    let front = Material {
        ambient: rgb(0.3, 0.25, 0.2),
        diffuse: DVec4::new(0.7, 0.6, 0.5, 0.8),
        specular: rgb(0.6, 0.6, 0.5),
        emission: rgb(0.05, 0.02, 0.0),
        shininess,
    };
    let back = Material {
        ambient: rgb(0.2, 0.3, 0.2),
        diffuse: DVec4::new(0.3, 0.6, 0.4, 0.6),
        specular: rgb(0.4, 0.5, 0.6),
        emission: rgb(0.0, 0.03, 0.05),
        shininess: shininess * 0.5,
    };
    let (positions, normals) = patch(2 * BLOCK + 23);
    TestScene {
        lights: LightSet::new(model, assorted_lights(cutoff, exponent), viewer).unwrap(),
        material: SurfaceMaterial { front, back },
        swapped_viewer,
        positions,
        normals,
    }
}

/// The light models the scenes are lit with.
pub(crate) fn models() -> Vec<LightModel> {
    let ambient = rgb(0.2, 0.2, 0.25);
    vec![
        LightModel {
            ambient,
            two_side: true,
            ..LightModel::default()
        },
        LightModel {
            ambient,
            local_viewer: true,
            two_side: true,
            color_control: ColorControl::SeparateSpecular,
            ..LightModel::default()
        },
        LightModel {
            ambient,
            local_viewer: true,
            specular_model: SpecularModel::Phong,
            normalize_normals: false,
            attenuation_clamp: true,
            ..LightModel::default()
        },
    ]
}

/// Each model's colour of each point on `side`, by the block evaluator.
fn evaluate<A: Arith>(scene: &TestScene, models: &[Deviations], side: Side) -> Vec<Vec<DVec4>> {
    let pass_scene = PassScene {
        lights: &scene.lights,
        swapped_viewer: scene.swapped_viewer,
        materials: std::slice::from_ref(&scene.material),
        centre: DVec3::new(0.0, 0.0, -2.0),
        unnormalized_normals: unnormalized(&scene.normals),
        alpha: true,
        back: true,
    };
    let pass = Pass::<A>::new(&pass_scene, models);
    let points = Points::new(
        &scene.positions,
        &scene.normals,
        scene.lights.model.normalize_normals,
        Some(pass_scene.centre),
    );
    let mut block = Block::new(&pass);
    let mut out = vec![Vec::new(); models.len()];
    for start in (0..points.len).step_by(BLOCK) {
        let range = start..(start + BLOCK).min(points.len);
        block.load(&pass, &points, range.clone(), Side::Front);
        block.evaluate(&pass, 0, Side::Front);
        if side == Side::Back {
            block.load(&pass, &points, range.clone(), Side::Back);
            block.evaluate(&pass, 0, Side::Back);
        }
        for (m, colors) in out.iter_mut().enumerate() {
            for lane in 0..range.len() {
                colors.push(DVec4::from_array(std::array::from_fn(|c| {
                    block.colors[m][c][lane].wide()
                })));
            }
        }
    }
    out
}

/// Every single deviation and a few pairs, against the reference, in one
/// pass per scene, tier and side.
fn check_tier<A: Arith>(precision: Precision) {
    let bound = precision.max_abs_error();
    let mut sets: Vec<Deviations> = std::iter::once(Deviations::NONE)
        .chain(Deviation::ALL.iter().map(|&d| d.into()))
        .collect();
    sets.extend([
        Deviations::of(&[Deviation::PhongSpecular, Deviation::AttenuationIgnored]),
        Deviations::of(&[Deviation::ViewerSwapped, Deviation::NormalsUnnormalized]),
        Deviations::of(&[Deviation::SpotExponentIgnored, Deviation::SpotCutoffRadians]),
        Deviations::of(&[
            Deviation::AmbientSpotIgnored,
            Deviation::LightAmbientMissing,
        ]),
        Deviations::of(&[Deviation::SrgbEncoded, Deviation::UnclampedOutput]),
        Deviations::of(&[Deviation::TwoSideIgnored, Deviation::DiffuseUnclamped]),
        Deviations::of(&[Deviation::AlphaSummed, Deviation::EmissionMissing]),
        Deviations::of(&[
            Deviation::HalfVectorUnnormalized,
            Deviation::SpecularUngated,
        ]),
    ]);
    let spots = [(40.0, 8.0), (90.0, 0.0), (25.0, 150.0)];
    let shininesses = [20.0, 0.0, 200.0];
    for light_model in models() {
        for ((cutoff, exponent), shininess) in spots.into_iter().zip(shininesses) {
            let scene = rich_scene(light_model, shininess, cutoff, exponent);
            for side in [Side::Front, Side::Back] {
                let colors = evaluate::<A>(&scene, &sets, side);
                for (set, colors) in sets.iter().zip(&colors) {
                    let port = Port {
                        deviations: *set,
                        swapped_viewer: scene.swapped_viewer,
                    };
                    for (i, (&p, &n)) in scene.positions.iter().zip(&scene.normals).enumerate() {
                        let want = color_port(&scene.lights, &port, &scene.material, side, p, n);
                        let got = colors[i];
                        // The bound is of colours in [0, 1]. An unclamped
                        // colour far above 1 has the relative error of the
                        // tier's powers, which grows with the power's
                        // logarithm (see `glint_lighting::tier_math::Math`).
                        let scale = want.abs().max(DVec4::ONE);
                        let error = ((got - want) / scale).abs().max_element();
                        let bound = bound * (1.0 + scale.max_element().ln());
                        assert!(
                            error <= bound,
                            "{precision:?}, {set}, {side:?}, vertex {i}, {light_model:?}, \
                             shininess {shininess}, spot {cutoff}/{exponent}: \
                             {got} against {want} (error {error:e}, bound {bound:e})"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn every_model_is_within_the_reference_tiers_bound() {
    check_tier::<Reference>(Precision::Reference);
}

#[test]
fn every_model_is_within_the_accurate_tiers_bound() {
    check_tier::<AccurateTier>(Precision::Accurate);
}

#[test]
fn every_model_is_within_the_fast_tiers_bound() {
    check_tier::<FastTier>(Precision::Fast);
}

//! The scenes the diagnosis is measured on (`benches/compare.rs`) and
//! tested on (`tests/diagnosis.rs`), defined once so that what the
//! benchmark reports is what the tests hold: a bumpy grid of vertices lit
//! by every kind of light, or by the one directional light of GL's
//! defaults. A candidate is the colours the reference evaluator
//! (`glint_lighting::reference::color_port`, f64, one vertex at a time)
//! draws for a port with some deviations: an implementation apart from the
//! block evaluator that the diagnosis runs.

use glam::{DVec3, DVec4, Vec4};
use glint_compare::{Deviations, Scene};
use glint_lighting::reference::{Port, color_port};
use glint_lighting::{
    Light, LightModel, LightPosition, LightSet, Material, Precision, Side, Spot, SurfaceMaterial,
    Viewer, unit_or_zero,
};
use rayon::prelude::*;

/// What GL lights, owned.
pub struct TestScene {
    pub lights: LightSet,
    pub material: SurfaceMaterial,
    pub swapped_viewer: Viewer,
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
}

impl TestScene {
    pub fn scene(&self, precision: Precision) -> Scene<'_> {
        Scene {
            lights: &self.lights,
            material: &self.material,
            positions: &self.positions,
            normals: &self.normals,
            precision,
            swapped_viewer: self.swapped_viewer,
        }
    }

    /// The front colours of the port with `deviations`, by the reference.
    pub fn port_colors(&self, deviations: Deviations) -> Vec<Vec4> {
        let port = Port {
            deviations,
            swapped_viewer: self.swapped_viewer,
        };
        self.positions
            .par_iter()
            .zip(&self.normals)
            .map(|(&p, &n)| {
                color_port(&self.lights, &port, &self.material, Side::Front, p, n).as_vec4()
            })
            .collect()
    }
}

fn rgb(r: f64, g: f64, b: f64) -> DVec4 {
    DVec4::new(r, g, b, 1.0)
}

/// A bumpy grid of `count` vertices in front of the eye, with normals
/// tilted at most 35° from +z (their z is 1 before normalising, the other
/// components at most 0.5), of lengths from 0.8 to 1.2 where `unit` is
/// false.
pub fn mesh(count: usize, unit: bool) -> (Vec<DVec3>, Vec<DVec3>) {
    let side = (count as f64).sqrt().ceil() as usize;
    (0..count)
        .map(|i| {
            let u = (i % side) as f64 / side as f64;
            let v = (i / side) as f64 / side as f64;
            let p = DVec3::new(u * 4.0 - 2.0, v * 4.0 - 2.0, -3.0 + 0.2 * (u * 9.0).sin());
            let n = DVec3::new((u * 7.0).sin() * 0.5, (v * 5.0).cos() * 0.5, 1.0).normalize();
            let length = if unit {
                1.0
            } else {
                1.0 + 0.2 * (u * 13.0 + v * 3.0).sin()
            };
            (p, n * length)
        })
        .unzip()
}

/// A scene in which every term of the equation is non-zero, so that the
/// catalogue's deviations all have something to change (16 of the 21
/// apply; the others need a two-sided model, a separate specular colour, a
/// shininess of 0 or above 128): a directional light, a directional
/// spotlight, an attenuated point spotlight and an attenuated point light,
/// emission, global and light ambient, specular of shininess 32, normals
/// not of unit length.
pub fn every_term(count: usize) -> TestScene {
    let spot = |direction: DVec3| Spot {
        direction: unit_or_zero(direction),
        exponent: 8.0,
        cutoff: 40.0,
    };
    let lights = vec![
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
            spot: spot(DVec3::new(0.4, -0.3, -1.0)),
            ..Light::default()
        },
        Light {
            position: LightPosition::Positional(DVec3::new(0.5, 1.0, 0.5)),
            ambient: rgb(0.1, 0.1, 0.05),
            diffuse: rgb(0.9, 0.7, 0.5),
            specular: rgb(0.8, 0.8, 0.9),
            attenuation: [1.0, 0.1, 0.02],
            spot: spot(DVec3::new(-0.1, -0.3, -1.0)),
        },
        Light {
            position: LightPosition::Positional(DVec3::new(-1.5, -0.5, 1.0)),
            ambient: rgb(0.05, 0.1, 0.1),
            diffuse: rgb(0.4, 0.6, 0.5),
            specular: rgb(0.5, 0.4, 0.6),
            attenuation: [1.0, 0.05, 0.01],
            ..Light::default()
        },
    ];
    let model = LightModel {
        ambient: rgb(0.2, 0.2, 0.25),
        ..LightModel::default()
    };
    let (positions, normals) = mesh(count, false);
    TestScene {
        lights: LightSet::new(model, lights, LightSet::eye_space_viewer(false)).unwrap(),
        material: SurfaceMaterial::both_sides(Material {
            ambient: rgb(0.3, 0.25, 0.2),
            diffuse: rgb(0.7, 0.6, 0.5),
            specular: rgb(0.6, 0.6, 0.5),
            emission: rgb(0.05, 0.02, 0.0),
            shininess: 32.0,
        }),
        swapped_viewer: Port::swapped_viewer(false, DVec3::ZERO, DVec3::Z),
        positions,
        normals,
    }
}

/// One white directional light towards `direction` (GL's `GL_LIGHT0` for
/// +z), GL's default light model, a diffuse material without specular, on
/// the mesh with normals of unit length.
pub fn one_directional(count: usize, direction: DVec3) -> TestScene {
    let (positions, normals) = mesh(count, true);
    let light = Light {
        position: LightPosition::Directional(unit_or_zero(direction)),
        ..Light::default()
    };
    TestScene {
        lights: LightSet::new(
            LightModel::default(),
            vec![light],
            LightSet::eye_space_viewer(false),
        )
        .unwrap(),
        material: SurfaceMaterial::both_sides(Material {
            diffuse: rgb(0.7, 0.5, 0.3),
            ..Material::default()
        }),
        swapped_viewer: Port::swapped_viewer(false, DVec3::ZERO, DVec3::Z),
        positions,
        normals,
    }
}

//! `/v1/compare` and `glint compare`: candidates made by an implementation
//! of section 2.14.1 written here in f64, independent of glint's evaluators,
//! with each deviation of the catalogue switched on, are diagnosed with that
//! deviation first; GL's own colours are within the bound and explained by
//! no deviation; noise is explained by none; bad candidates are refused at
//! their pointer.

mod cli;
mod diagnosis;
mod images;
mod input;
mod model;

use serde_json::{Value, json};

type Rgba = [f64; 4];
type V3 = [f64; 3];

/// A light as GL's state holds it, every field given.
#[derive(Clone)]
pub struct Light {
    pub position: Rgba,
    pub ambient: Rgba,
    pub diffuse: Rgba,
    pub specular: Rgba,
    pub attenuation: V3,
    /// Direction, exponent, cutoff in degrees.
    pub spot: Option<(V3, f64, f64)>,
}

#[derive(Clone)]
pub struct Material {
    pub ambient: Rgba,
    pub diffuse: Rgba,
    pub specular: Rgba,
    pub emission: Rgba,
    pub shininess: f64,
}

/// A shade request, every value given, in eye space (no view).
#[derive(Clone)]
pub struct Scene {
    pub global_ambient: Rgba,
    pub local_viewer: bool,
    pub two_side: bool,
    pub separate_specular: bool,
    pub normalize_normals: bool,
    pub front: Material,
    pub back: Material,
    pub lights: Vec<Light>,
    pub positions: Vec<V3>,
    pub normals: Vec<V3>,
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: V3, k: f64) -> V3 {
    a.map(|x| x * k)
}

fn unit(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    if l == 0.0 { a } else { scale(a, 1.0 / l) }
}

/// The component-wise product of two colours' RGB.
fn times(a: Rgba, b: Rgba) -> V3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

fn clamp01(x: f64) -> f64 {
    x.clamp(0.0, 1.0)
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value.
fn srgb(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl Scene {
    /// The colour a port with `deviations` (the API's names; none for GL)
    /// draws for vertex `k` on the front or, with `back`, the back side:
    /// equation 2.1 of section 2.14.1, written from the specification.
    pub fn color(&self, deviations: &[&str], k: usize, back: bool) -> Rgba {
        let has = |d: &str| deviations.contains(&d);
        let back = back && !has("two_side_ignored");
        let m = if back { &self.back } else { &self.front };
        let v = self.positions[k];
        let mut n = self.normals[k];
        if self.normalize_normals && !has("normals_unnormalized") {
            n = unit(n);
        }
        if back {
            n = scale(n, -1.0);
        }
        let local = self.local_viewer != has("viewer_swapped");
        let vp_e = if local {
            unit(scale(v, -1.0))
        } else {
            [0.0, 0.0, 1.0]
        };
        let mut primary = [0.0; 3];
        let mut secondary = [0.0; 3];
        if !has("emission_missing") {
            primary = add(primary, [m.emission[0], m.emission[1], m.emission[2]]);
        }
        if !has("global_ambient_missing") {
            primary = add(primary, times(m.ambient, self.global_ambient));
        }
        for light in &self.lights {
            let p = [light.position[0], light.position[1], light.position[2]];
            let directional = light.position[3] == 0.0;
            let (vp, att) = if directional {
                (unit(p), 1.0)
            } else {
                let d = add(p, scale(v, -1.0));
                let dist = dot(d, d).sqrt();
                let [k0, k1, k2] = light.attenuation;
                let att = if has("attenuation_ignored") {
                    1.0
                } else {
                    1.0 / (k0 + k1 * dist + k2 * dist * dist)
                };
                (unit(d), att)
            };
            let spot = match light.spot {
                None => 1.0,
                Some(_) if directional && has("directional_spot_ignored") => 1.0,
                Some((direction, exponent, cutoff)) => {
                    let cos_cutoff = if has("spot_cutoff_radians") {
                        cutoff.cos()
                    } else {
                        cutoff.to_radians().cos()
                    };
                    let x = dot(scale(vp, -1.0), unit(direction));
                    if x < cos_cutoff {
                        0.0
                    } else if has("spot_exponent_ignored") {
                        1.0
                    } else {
                        x.max(0.0).powf(exponent)
                    }
                }
            };
            let ambient_spot = if has("ambient_spot_ignored") {
                1.0
            } else {
                spot
            };
            let ambient = if has("light_ambient_missing") {
                [0.0; 3]
            } else {
                scale(times(m.ambient, light.ambient), att * ambient_spot)
            };
            let n_vp = dot(n, vp);
            let diffuse_base = if has("diffuse_unclamped") {
                n_vp
            } else {
                n_vp.max(0.0)
            };
            let diffuse = scale(times(m.diffuse, light.diffuse), att * spot * diffuse_base);
            let gate = if n_vp > 0.0 || has("specular_ungated") {
                1.0
            } else {
                0.0
            };
            let base = if has("phong_specular") {
                let r = add(scale(n, 2.0 * n_vp), scale(vp, -1.0));
                dot(r, vp_e)
            } else if has("half_vector_unnormalized") {
                dot(n, add(vp, vp_e))
            } else {
                dot(n, unit(add(vp, vp_e)))
            };
            let power = base.max(0.0).powf(m.shininess);
            let specular = scale(times(m.specular, light.specular), att * spot * gate * power);
            primary = add(add(primary, ambient), diffuse);
            if self.separate_specular {
                secondary = add(secondary, specular);
            } else {
                primary = add(primary, specular);
            }
        }
        let rgb: V3 = std::array::from_fn(|c| {
            let (p, s) = (primary[c], secondary[c]);
            let color = if has("unclamped_output") {
                p + s
            } else if self.separate_specular && !has("separate_specular_ignored") {
                clamp01(clamp01(p) + clamp01(s))
            } else {
                clamp01(p + s)
            };
            if has("srgb_encoded") {
                srgb(color)
            } else {
                color
            }
        });
        [rgb[0], rgb[1], rgb[2], clamp01(m.diffuse[3])]
    }

    /// Every vertex's colour of one side, as a port with `deviations`
    /// draws it.
    pub fn colors(&self, deviations: &[&str], back: bool) -> Vec<Rgba> {
        (0..self.positions.len())
            .map(|k| self.color(deviations, k, back))
            .collect()
    }

    /// The `candidate` of a compare: a port's colours, of both sides where
    /// the light model is two-sided.
    pub fn candidate(&self, deviations: &[&str]) -> Value {
        let mut candidate = json!({ "colors": self.colors(deviations, false) });
        if self.two_side {
            candidate["back_colors"] = json!(self.colors(deviations, true));
        }
        candidate
    }

    /// The shade request of this scene at `precision`.
    pub fn request(&self, precision: &str) -> Value {
        let material = |m: &Material| {
            json!({ "ambient": m.ambient, "diffuse": m.diffuse, "specular": m.specular,
                    "emission": m.emission, "shininess": m.shininess })
        };
        let lights: Vec<Value> = self
            .lights
            .iter()
            .map(|l| {
                let mut light = json!({
                    "position": l.position, "ambient": l.ambient, "diffuse": l.diffuse,
                    "specular": l.specular, "attenuation": l.attenuation,
                });
                if let Some((direction, exponent, cutoff)) = l.spot {
                    light["spot"] =
                        json!({ "direction": direction, "exponent": exponent, "cutoff": cutoff });
                }
                light
            })
            .collect();
        json!({
            "light_model": {
                "ambient": self.global_ambient,
                "local_viewer": self.local_viewer,
                "two_side": self.two_side,
                "color_control": if self.separate_specular { "separate_specular" } else { "single" },
                "normalize_normals": self.normalize_normals,
            },
            "material": material(&self.front),
            "back_material": material(&self.back),
            "lights": lights,
            "vertices": { "positions": self.positions, "normals": self.normals },
            "precision": precision,
        })
    }

    /// A compare of the colours of a port with `deviations`.
    pub fn compare(&self, deviations: &[&str], precision: &str) -> Value {
        let mut body = self.request(precision);
        body["candidate"] = self.candidate(deviations);
        body
    }
}

fn rgba(r: f64, g: f64, b: f64) -> Rgba {
    [r, g, b, 1.0]
}

/// A surface in front of the eye, its normals of every direction of the
/// front hemisphere and some turned away from the lights, of lengths from
/// 0.75 to 1.25.
fn surface(count: usize) -> (Vec<V3>, Vec<V3>) {
    (0..count)
        .map(|i| {
            let t = i as f64;
            let (u, v) = (
                (t * 0.618_034).fract() * 2.0 - 1.0,
                (t * 0.414_214).fract() * 2.0 - 1.0,
            );
            let p = [
                1.5 * u,
                1.5 * v,
                -2.5 + 0.4 * (3.0 * u).sin() * (2.0 * v).cos(),
            ];
            let n = unit([
                (2.3 * t).sin(),
                (1.7 * t).cos(),
                0.3 + 0.7 * (0.9 * t).sin(),
            ]);
            let length = 1.0 + 0.25 * (0.37 * t).sin();
            (p, scale(n, length))
        })
        .unzip()
}

/// A scene in which every term of the equation is non-zero: emission,
/// global and per-light ambient, a directional light, an attenuated point
/// spotlight and a directional spotlight, specular of shininess 12, an
/// infinite viewer, normals to normalise.
pub fn every_term() -> Scene {
    let (positions, normals) = surface(240);
    let material = Material {
        ambient: rgba(0.3, 0.2, 0.25),
        diffuse: [0.5, 0.45, 0.35, 0.8],
        specular: rgba(0.4, 0.45, 0.5),
        emission: rgba(0.05, 0.02, 0.03),
        shininess: 12.0,
    };
    Scene {
        global_ambient: rgba(0.15, 0.2, 0.1),
        local_viewer: false,
        two_side: false,
        separate_specular: false,
        normalize_normals: true,
        front: material.clone(),
        back: Material {
            diffuse: [0.2, 0.5, 0.3, 0.6],
            ..material
        },
        lights: vec![
            Light {
                position: [0.3, 0.5, 1.0, 0.0],
                ambient: rgba(0.1, 0.05, 0.1),
                diffuse: rgba(0.4, 0.4, 0.35),
                specular: rgba(0.5, 0.5, 0.5),
                attenuation: [1.0, 0.0, 0.0],
                spot: None,
            },
            Light {
                position: [0.5, 1.5, 0.5, 1.0],
                ambient: rgba(0.1, 0.1, 0.15),
                diffuse: rgba(0.6, 0.4, 0.3),
                specular: rgba(0.4, 0.4, 0.3),
                attenuation: [0.6, 0.2, 0.05],
                spot: Some(([-0.2, -0.6, -1.0], 3.0, 50.0)),
            },
            Light {
                position: [-0.4, 0.2, 1.0, 0.0],
                ambient: rgba(0.05, 0.1, 0.05),
                diffuse: rgba(0.2, 0.3, 0.4),
                specular: rgba(0.3, 0.3, 0.4),
                attenuation: [1.0, 0.0, 0.0],
                spot: Some(([0.3, -0.1, -1.0], 2.0, 60.0)),
            },
        ],
        positions,
        normals,
    }
}

/// Where a deviation needs more than [`every_term`] to show: the scene in
/// which it changes the colours.
pub fn scene_for(deviation: &str) -> Scene {
    let mut scene = every_term();
    match deviation {
        "two_side_ignored" => scene.two_side = true,
        "separate_specular_ignored" => {
            // The two sums clamp apart only where one leaves [0, 1]: a
            // negative emission takes the primary colour below 0.
            scene.separate_specular = true;
            scene.front.emission = rgba(-0.35, -0.3, -0.4);
        }
        "unclamped_output" => {
            for light in &mut scene.lights {
                light.diffuse = light.diffuse.map(|c| c * 3.0);
            }
        }
        _ => {}
    }
    scene
}

/// The catalogue's names that these tests make candidates of.
pub const DEVIATIONS: [&str; 18] = [
    "phong_specular",
    "viewer_swapped",
    "half_vector_unnormalized",
    "specular_ungated",
    "attenuation_ignored",
    "spot_exponent_ignored",
    "spot_cutoff_radians",
    "global_ambient_missing",
    "light_ambient_missing",
    "emission_missing",
    "normals_unnormalized",
    "diffuse_unclamped",
    "two_side_ignored",
    "separate_specular_ignored",
    "srgb_encoded",
    "unclamped_output",
    "ambient_spot_ignored",
    "directional_spot_ignored",
];

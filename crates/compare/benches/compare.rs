//! Comparing 1e6 vertices against the whole catalogue, beside one shade of
//! the same vertices at the same tier: the goal is a compare within 4× the
//! shade.
//!
//! `cargo bench -p glint-compare --bench compare`
//!
//! The shade is what `/v1/shade` does with a validated scene: prepare the
//! light set, convert the batch, light it into fresh buffers. The compare
//! is `glint_compare::compare`: its own conversion, GL and every deviation
//! the scene can show in one pass, the error figures (the exact p99 and the
//! 10 worst vertices included) and the diagnosis.
//!
//! The scenes:
//! - **every term**: what a port's author compares on, a scene in which
//!   every term of the equation is non-zero, so that the catalogue's
//!   deviations all have something to change (16 of the 21 apply; the
//!   others need a two-sided model, a separate specular colour, a shininess
//!   of 0 or above 128): a directional light, a directional spotlight, an
//!   attenuated point spotlight and an attenuated point light, emission,
//!   global and light ambient, specular of shininess 32, normals not of
//!   unit length. The candidate is a port with `phong_specular` (one pass)
//!   and one with `phong_specular` and `attenuation_ignored` (the pairs'
//!   second pass).
//! - **1 directional, no specular**: the scene whose shade is fastest (bound
//!   by memory), the hardest ratio to keep; 7 deviations apply.
//!
//! After criterion's runs, the same work is timed in turns (shade, compare,
//! shade, …), and the medians and their ratio are printed: the figure to
//! quote, since drift of the machine weighs on both alike.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use glam::{DVec3, DVec4, Vec4};
use glint_compare::{Candidate, Deviation, Deviations, Options, Scene, compare};
use glint_lighting::kernel::{Colors, Kernel};
use glint_lighting::reference::{Port, color_port};
use glint_lighting::{
    Light, LightModel, LightPosition, LightSet, Material, Precision, Side, Spot, SurfaceMaterial,
    Viewer, unit_or_zero,
};
use rayon::prelude::*;

const VERTICES: usize = 1_000_000;

/// A scene and its candidates.
struct Bench {
    name: &'static str,
    lights: LightSet,
    material: SurfaceMaterial,
    swapped_viewer: Viewer,
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    /// (name, the port whose colours the candidate holds).
    candidates: Vec<(&'static str, Deviations)>,
}

fn rgb(r: f64, g: f64, b: f64) -> DVec4 {
    DVec4::new(r, g, b, 1.0)
}

/// A bumpy grid of vertices in front of the eye with varied normals, of
/// lengths from 0.8 to 1.2 where `unit` is false.
fn mesh(count: usize, unit: bool) -> (Vec<DVec3>, Vec<DVec3>) {
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

fn every_term() -> Bench {
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
    let (positions, normals) = mesh(VERTICES, false);
    Bench {
        name: "every term",
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
        candidates: vec![
            ("phong_specular", Deviation::PhongSpecular.into()),
            (
                "phong_specular+attenuation_ignored",
                Deviations::of(&[Deviation::PhongSpecular, Deviation::AttenuationIgnored]),
            ),
        ],
    }
}

fn one_directional() -> Bench {
    let (positions, normals) = mesh(VERTICES, true);
    Bench {
        name: "1 directional, no specular",
        lights: LightSet::new(
            LightModel::default(),
            vec![Light::default()],
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
        candidates: vec![("diffuse_unclamped", Deviation::DiffuseUnclamped.into())],
    }
}

impl Bench {
    fn scene(&self, precision: Precision) -> Scene<'_> {
        Scene {
            lights: &self.lights,
            material: &self.material,
            positions: &self.positions,
            normals: &self.normals,
            precision,
            swapped_viewer: self.swapped_viewer,
        }
    }

    /// The colours of the port with `deviations`, by the reference.
    fn candidate(&self, deviations: Deviations) -> Vec<Vec4> {
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

    /// One shade, as `/v1/shade` lights a validated scene.
    fn shade(&self, precision: Precision) -> Colors {
        match precision.tier() {
            Some(tier) => {
                let kernel = Kernel::new(&self.lights, &self.positions);
                let products = kernel.products(&self.material);
                let vertices = kernel.prepare(&self.positions, &self.normals);
                kernel.light(tier, &products, &vertices)
            }
            None => Colors {
                front: self
                    .positions
                    .par_iter()
                    .zip(&self.normals)
                    .map(|(&p, &n)| {
                        glint_lighting::reference::color(
                            &self.lights,
                            &self.material,
                            Side::Front,
                            p,
                            n,
                        )
                        .as_vec4()
                    })
                    .collect(),
                back: None,
            },
        }
    }
}

const TIERS: [(&str, Precision); 3] = [
    ("accurate", Precision::Accurate),
    ("fast", Precision::Fast),
    ("reference", Precision::Reference),
];

fn criterion_runs(c: &mut Criterion, benches: &[(Bench, Vec<Vec<Vec4>>)]) {
    for (bench, candidates) in benches {
        let mut group = c.benchmark_group(bench.name);
        group.throughput(Throughput::Elements(VERTICES as u64));
        group.sample_size(10);
        for (tier, precision) in TIERS {
            group.bench_function(BenchmarkId::new("shade", tier), |b| {
                b.iter(|| black_box(bench.shade(precision)))
            });
            for ((name, _), colors) in bench.candidates.iter().zip(candidates) {
                let candidate = Candidate {
                    front: colors,
                    back: None,
                    alpha: false,
                };
                group.bench_function(BenchmarkId::new(format!("compare {name}"), tier), |b| {
                    b.iter(|| {
                        black_box(compare(
                            &bench.scene(precision),
                            &candidate,
                            &Options::default(),
                        ))
                    })
                });
            }
        }
        group.finish();
    }
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

/// Shade and compare in turns, `rounds` each; prints the medians and the
/// ratio.
fn in_turns(benches: &[(Bench, Vec<Vec<Vec4>>)]) {
    println!("\nIn turns, {VERTICES} vertices, all cores: median of each, and compare ÷ shade");
    for (bench, candidates) in benches {
        for (tier, precision) in TIERS {
            let rounds = if precision == Precision::Reference {
                5
            } else {
                21
            };
            for ((name, deviations), colors) in bench.candidates.iter().zip(candidates) {
                let candidate = Candidate {
                    front: colors,
                    back: None,
                    alpha: false,
                };
                let scene = bench.scene(precision);
                // Whether what is timed finds the port: its deviations
                // first, and explaining the candidate (printed, not assumed).
                let found = compare(&scene, &candidate, &Options::default()).unwrap();
                let best = &found.diagnosis.explanations[0];
                let diagnosed = if best.deviations == *deviations && best.explains {
                    "found".to_owned()
                } else {
                    format!(
                        "NOT found: first {} (explains: {})",
                        best.deviations, best.explains
                    )
                };
                let (mut shades, mut compares) = (Vec::new(), Vec::new());
                for _ in 0..rounds {
                    let start = Instant::now();
                    black_box(bench.shade(precision));
                    shades.push(start.elapsed());
                    let start = Instant::now();
                    black_box(compare(&scene, &candidate, &Options::default()).unwrap());
                    compares.push(start.elapsed());
                }
                let (shade, compared) = (median(shades), median(compares));
                println!(
                    "{:<28} {:<10} candidate {:<36} shade {:>9.2} ms  compare {:>9.2} ms  ratio {:.2} ({} models, {} pairs; {diagnosed})",
                    bench.name,
                    tier,
                    name,
                    shade.as_secs_f64() * 1e3,
                    compared.as_secs_f64() * 1e3,
                    compared.as_secs_f64() / shade.as_secs_f64(),
                    found.diagnosis.explanations.len() + found.diagnosis.unobservable.len(),
                    found.diagnosis.pairs_tried,
                );
            }
        }
    }
}

fn main() {
    let benches: Vec<(Bench, Vec<Vec<Vec4>>)> = [every_term(), one_directional()]
        .into_iter()
        .map(|bench| {
            let candidates = bench
                .candidates
                .iter()
                .map(|(_, d)| bench.candidate(*d))
                .collect();
            (bench, candidates)
        })
        .collect();
    let mut criterion = Criterion::default().configure_from_args();
    criterion_runs(&mut criterion, &benches);
    criterion.final_summary();
    in_turns(&benches);
}

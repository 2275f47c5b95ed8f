//! Vertices per second of each precision tier on the scenes of the speed
//! targets, 1e6 vertices, on one core and on all cores; beside them, a loop
//! written by hand for the simplest scene, the ceiling the specialised
//! kernel should reach.
//!
//! `cargo bench --bench shade`

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, DVec4, Vec4};
use glint::lighting::kernel::{Kernel, Tier};
use glint::lighting::reference::{self, Side};
use glint::lighting::{
    ColorControl, Light, LightModel, LightPosition, Lighting, Material, Spot,
};
use rayon::prelude::*;

const VERTICES: usize = 1_000_000;

/// A bumpy grid of vertices with varied normals, deterministic.
fn mesh(count: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let side = (count as f64).sqrt().ceil() as usize;
    (0..count)
        .map(|i| {
            let (u, v) = (
                (i % side) as f64 / side as f64,
                (i / side) as f64 / side as f64,
            );
            let p = DVec3::new(u * 4.0 - 2.0, v * 4.0 - 2.0, -3.0 + 0.2 * (u * 9.0).sin());
            let n = DVec3::new((u * 7.0).sin() * 0.5, (v * 5.0).cos() * 0.5, 1.0).normalize();
            (p, n)
        })
        .unzip()
}

fn material(specular: f64) -> Material {
    Material {
        diffuse: DVec4::new(0.7, 0.5, 0.3, 1.0),
        specular: DVec4::new(specular, specular, specular, 1.0),
        shininess: 32.0,
        ..Material::default()
    }
}

fn scene(lights: Vec<Light>, model: LightModel, specular: f64) -> Lighting {
    Lighting {
        viewer: Lighting::eye_space_viewer(model.local_viewer),
        model,
        front: material(specular),
        back: material(specular),
        lights,
    }
}

/// The scenes of the targets.
fn scenes() -> Vec<(&'static str, Lighting)> {
    let directional = Light {
        position: LightPosition::Directional(DVec3::new(0.3, 0.4, 1.0).normalize()),
        ..Light::default()
    };
    let positional = |i: usize| Light {
        position: LightPosition::Positional(DVec3::new(i as f64 - 4.0, 1.0, 1.0)),
        attenuation: [1.0, 0.1, 0.02],
        ..Light::default()
    };
    let spot = |i: usize| Light {
        spot: Spot {
            direction: DVec3::new(0.0, -0.2, -1.0).normalize(),
            exponent: 8.0,
            cutoff: 40.0,
        },
        ..positional(i)
    };
    vec![
        (
            "1 directional, no specular",
            scene(vec![directional], LightModel::default(), 0.0),
        ),
        (
            "1 directional",
            scene(vec![directional], LightModel::default(), 0.5),
        ),
        (
            "8 positional",
            scene((0..8).map(positional).collect(), LightModel::default(), 0.5),
        ),
        (
            "8 spots, local viewer, separate specular",
            scene(
                (0..8).map(spot).collect(),
                LightModel {
                    local_viewer: true,
                    color_control: ColorControl::SeparateSpecular,
                    ..LightModel::default()
                },
                0.5,
            ),
        ),
    ]
}

/// The simplest scene written by hand: one directional light, no specular,
/// unit normals, on the same inputs and outputs as the kernel.
fn by_hand(lighting: &Lighting, normals: &[DVec3]) -> Vec<Vec4> {
    let LightPosition::Directional(vp) = lighting.lights[0].position else {
        unreachable!()
    };
    let m = &lighting.front;
    let base = (m.emission + m.ambient * lighting.model.ambient)
        .truncate()
        .as_vec3();
    let diffuse = (m.diffuse * lighting.lights[0].diffuse)
        .truncate()
        .as_vec3();
    let ambient = (m.ambient * lighting.lights[0].ambient)
        .truncate()
        .as_vec3();
    let vp = vp.as_vec3();
    let alpha = m.diffuse.w as f32;
    normals
        .par_iter()
        .with_min_len(4096)
        .map(|n| {
            let n = n.normalize_or_zero().as_vec3();
            let lit = n.dot(vp).max(0.0);
            (base + ambient + lit * diffuse)
                .clamp(glam::Vec3::ZERO, glam::Vec3::ONE)
                .extend(alpha)
        })
        .collect()
}

fn tiers(c: &mut Criterion) {
    let (positions, normals) = mesh(VERTICES);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools = [(1, "1 core"), (cores, "all cores")];
    for (name, lighting) in scenes() {
        let mut group = c.benchmark_group(name);
        group.throughput(Throughput::Elements(VERTICES as u64));
        group.sample_size(10);
        for (threads, label) in pools {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for (tier_name, tier) in [("accurate", Tier::Accurate), ("fast", Tier::Fast)] {
                group.bench_function(BenchmarkId::new(tier_name, label), |b| {
                    b.iter(|| {
                        pool.install(|| {
                            let kernel = Kernel::new(&lighting, &positions);
                            black_box(kernel.shade(tier, &positions, &normals))
                        })
                    })
                });
            }
            group.bench_function(BenchmarkId::new("reference", label), |b| {
                b.iter(|| {
                    pool.install(|| {
                        let colors: Vec<DVec4> = positions
                            .par_iter()
                            .zip(&normals)
                            .map(|(&p, &n)| reference::color(&lighting, Side::Front, p, n))
                            .collect();
                        black_box(colors)
                    })
                })
            });
            if name == "1 directional, no specular" {
                group.bench_function(BenchmarkId::new("by hand", label), |b| {
                    b.iter(|| pool.install(|| black_box(by_hand(&lighting, &normals))))
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, tiers);
criterion_main!(benches);

//! Vertices per second of each precision tier on the scenes of the speed
//! targets, 1e6 vertices, on one core and on all cores; beside them, a loop
//! written by hand for the simplest scene, the ceiling the specialised
//! kernel should reach.
//!
//! `cargo bench --bench shade`

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec4, Vec3, Vec4};
use glint::lighting::kernel::{Colors, Kernel, Tier};
use glint::lighting::reference::{self, Side};
use glint::lighting::{LightPosition, Lighting};
use rayon::prelude::*;

mod common;

const VERTICES: usize = 1_000_000;

/// The simplest scene written by hand: one directional light, no specular,
/// normalised normals, from f32 normals into a reused buffer as the kernel
/// (which reads them as structure of arrays).
fn by_hand(lighting: &Lighting, normals: &[Vec3], out: &mut Vec<Vec4>) {
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
    out.clear();
    normals
        .par_iter()
        .with_min_len(4096)
        .map(|n| {
            let n = n.normalize_or_zero();
            let lit = n.dot(vp).max(0.0);
            (base + ambient + lit * diffuse)
                .clamp(Vec3::ZERO, Vec3::ONE)
                .extend(alpha)
        })
        .collect_into_vec(out);
}

fn tiers(c: &mut Criterion) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools = [(1, "1 core"), (cores, "all cores")];
    for (name, file) in common::SCENES {
        let scene = common::scene(file, VERTICES);
        let (lighting, positions, normals) = (&scene.lighting, &scene.positions, &scene.normals);
        // Inputs prepared once and outputs reused, as in `benches/trade.rs`.
        let kernel = Kernel::new(lighting, positions);
        let vertices = kernel.prepare(positions, normals);
        let normals32: Vec<Vec3> = normals.iter().map(|n| n.as_vec3()).collect();
        let mut out = Colors::default();
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
                    b.iter(|| pool.install(|| kernel.shade_into(tier, &vertices, &mut out)))
                });
            }
            group.bench_function(BenchmarkId::new("reference", label), |b| {
                b.iter(|| {
                    pool.install(|| {
                        let colors: Vec<DVec4> = positions
                            .par_iter()
                            .zip(normals)
                            .map(|(&p, &n)| reference::color(lighting, Side::Front, p, n))
                            .collect();
                        black_box(colors)
                    })
                })
            });
            if name == "1 directional, no specular" {
                group.bench_function(BenchmarkId::new("by hand", label), |b| {
                    b.iter(|| pool.install(|| by_hand(lighting, &normals32, &mut out.front)))
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, tiers);
criterion_main!(benches);

//! Vertices per second of each precision tier on the scenes of the speed
//! targets, 1e6 vertices, on one core and on all cores; beside them, a loop
//! written by hand for the simplest scene, the yardstick the specialised
//! kernel should reach.
//!
//! `cargo bench --bench shade`

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec4, Vec3, Vec4};
use glint::scene::ShadeScene;
use glint_lighting::kernel::{Colors, Kernel, Tier};
use glint_lighting::{LightPosition, Side, reference};
use rayon::prelude::*;

mod common;

const VERTICES: usize = 1_000_000;

/// The simplest scene written by hand: one directional light, no specular,
/// normalised normals. It reads f32 normals as structure of arrays (as the
/// kernel reads them), lights them in one fused loop per 16 vertices, and
/// writes the colours into a reused buffer, in parallel chunks of 4096
/// vertices, built for AVX-512 where the CPU has it, as the kernel is.
fn by_hand(scene: &ShadeScene, normals: &[Vec<f32>; 3], out: &mut Vec<Vec4>) {
    let light = &scene.lights.lights()[0];
    let LightPosition::Directional(vp) = light.position else {
        unreachable!()
    };
    let m = &scene.material.front;
    let rgb = |c: DVec4| c.truncate().as_vec3();
    let global_ambient = scene.lights.model.ambient;
    let scene = HandScene {
        base: rgb(m.emission + m.ambient * global_ambient + m.ambient * light.ambient),
        diffuse: rgb(m.diffuse * light.diffuse),
        vp: vp.as_vec3(),
        alpha: m.diffuse.w as f32,
    };
    let len = normals[0].len();
    // Reused as it is: a buffer cleared each run would be written twice.
    if out.len() != len {
        *out = vec![Vec4::ZERO; len];
    }
    #[cfg(target_arch = "x86_64")]
    let avx512 = is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma");
    out.par_chunks_mut(4096).enumerate().for_each(|(k, out)| {
        let at = k * 4096..k * 4096 + out.len();
        let n = [0, 1, 2].map(|axis| &normals[axis][at.clone()]);
        #[cfg(target_arch = "x86_64")]
        if avx512 {
            // SAFETY: the CPU has AVX-512F and FMA, checked above.
            return unsafe { by_hand_avx512(&scene, n, out) };
        }
        by_hand_chunk(&scene, n, out)
    });
}

struct HandScene {
    base: Vec3,
    diffuse: Vec3,
    vp: Vec3,
    alpha: f32,
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn by_hand_avx512(scene: &HandScene, n: [&[f32]; 3], out: &mut [Vec4]) {
    by_hand_chunk(scene, n, out)
}

#[inline(always)]
fn by_hand_chunk(scene: &HandScene, [xs, ys, zs]: [&[f32]; 3], out: &mut [Vec4]) {
    let (base, diffuse, vp) = (scene.base, scene.diffuse, scene.vp);
    // SAFETY: a `Vec4` is four f32 and nothing else; plain f32 stores are
    // what the vectoriser interleaves.
    let out: &mut [f32] =
        unsafe { std::slice::from_raw_parts_mut(out.as_mut_ptr().cast(), out.len() * 4) };
    let light = |x: f32, y: f32, z: f32, out: &mut [f32]| {
        let len2 = x * x + y * y + z * z;
        let inverse = if len2 > 0.0 { 1.0 / len2.sqrt() } else { 0.0 };
        let lit = ((x * vp.x + y * vp.y + z * vp.z) * inverse).max(0.0);
        for c in 0..3 {
            out[c] = lit.mul_add(diffuse[c], base[c]).clamp(0.0, 1.0);
        }
        out[3] = scene.alpha;
    };
    // Whole groups of 16 have a trip count the vectoriser knows.
    let lanes = xs
        .chunks_exact(16)
        .zip(ys.chunks_exact(16))
        .zip(zs.chunks_exact(16));
    for (((xs, ys), zs), out) in lanes.zip(out.chunks_exact_mut(64)) {
        for i in 0..16 {
            light(xs[i], ys[i], zs[i], &mut out[4 * i..4 * i + 4]);
        }
    }
    for i in xs.len() / 16 * 16..xs.len() {
        light(xs[i], ys[i], zs[i], &mut out[4 * i..4 * i + 4]);
    }
}

fn tiers(c: &mut Criterion) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools = [(1, "1 core"), (cores, "all cores")];
    for (name, file) in common::SCENES {
        let scene = common::scene(file, VERTICES);
        let (lights, material) = (&scene.lights, &scene.material);
        let (positions, normals) = (&scene.positions, &scene.normals);
        // Inputs prepared once and outputs reused, as in `benches/trade.rs`.
        let kernel = Kernel::new(lights, positions);
        let products = kernel.products(material);
        let vertices = kernel.prepare(positions, normals);
        let normals32 =
            [0, 1, 2].map(|axis| normals.iter().map(|n| n[axis] as f32).collect::<Vec<_>>());
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
                    b.iter(|| {
                        pool.install(|| kernel.light_into(tier, &products, &vertices, &mut out))
                    })
                });
            }
            group.bench_function(BenchmarkId::new("reference", label), |b| {
                b.iter(|| {
                    pool.install(|| {
                        let colors: Vec<DVec4> = positions
                            .par_iter()
                            .zip(normals)
                            .map(|(&p, &n)| reference::color(lights, material, Side::Front, p, n))
                            .collect();
                        black_box(colors)
                    })
                })
            });
            if name == "1 directional, no specular" {
                // What is timed is the same lighting: the loop's colours
                // within the accurate tier's bound of the kernel's.
                let mut hand = Vec::new();
                by_hand(&scene, &normals32, &mut hand);
                let lit = kernel.light(Tier::Accurate, &products, &vertices).front;
                let most = hand
                    .iter()
                    .zip(&lit)
                    .map(|(a, b)| (*a - *b).abs().max_element());
                assert!(
                    most.fold(0.0, f32::max) <= 1e-5,
                    "the loop by hand lights otherwise"
                );
                group.bench_function(BenchmarkId::new("by hand", label), |b| {
                    b.iter(|| pool.install(|| by_hand(&scene, &normals32, &mut out.front)))
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, tiers);
criterion_main!(benches);

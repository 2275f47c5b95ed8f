//! The renderer's hot paths at 1920×1080, one sample, per-pixel lighting,
//! on all cores (rayon's global pool):
//!
//! - `spheres_1080p`: 20 spheres on a plane, 4 lights, the whole request
//!   (BVH build, tracing and lighting, PNG encoding);
//! - `mesh_100k_1080p`: a tessellated sphere of ~100k triangles on a plane,
//!   2 lights, the whole request;
//! - `frame_100k_1080p`: that scene's frame once its BVH is built, as a
//!   viewer draws it (tracing and lighting, PNG encoding): the figure to
//!   hold against a ray tracer's frame rate, the build being measured on
//!   its own below;
//! - `traverse_100k_1080p`: the primary rays of that scene through the BVH
//!   in packets of 4×4 pixels, as the renderer traces them, closest hit
//!   only, no lighting;
//! - `traverse_single_100k_1080p`: the same rays one at a time, the path of
//!   shadow rays and probes;
//! - `build_100k`: the geometry and BVH of those 100k triangles.
//!
//! Throughput is in primary rays (one per pixel), triangles for the build.
//! Run: `cargo bench --bench render -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glint::render::{self, Form};
use glint::scene::{self, Limits};
use glint_trace::RenderScene;
use glint_trace::bvh::BvhUse;
use glint_trace::geometry::Geometry;
use glint_trace::packet::Packets;
use glint_trace::{Renderer, film};
use rayon::prelude::*;
use serde_json::{Value, json};

mod common;

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;

fn scene_of(request: &Value) -> RenderScene {
    let limits = Limits {
        max_vertices: usize::MAX,
        ..Limits::default()
    };
    scene::parse_render(&serde_json::to_vec(request).unwrap(), &limits).unwrap()
}

/// 20 spheres in a 5×4 grid on a floor, four lights (two directional, two
/// positional with attenuation).
fn spheres() -> RenderScene {
    let mut objects = vec![json!({
        "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] }, "material": "floor" })];
    for i in 0..20 {
        let (x, z) = ((i % 5) as f64 * 2.0 - 4.0, (i / 5) as f64 * -2.0 + 1.0);
        let r = 0.5 + 0.1 * (i % 3) as f64;
        objects.push(json!({
            "sphere": { "center": [x, r, z], "radius": r },
            "material": if i % 2 == 0 { "red" } else { "blue" },
        }));
    }
    scene_of(&json!({
        "materials": {
            "floor": { "diffuse": [0.6, 0.6, 0.6] },
            "red": { "diffuse": [0.8, 0.2, 0.1], "specular": [0.6, 0.6, 0.6], "shininess": 30 },
            "blue": { "diffuse": [0.1, 0.3, 0.8], "specular": [0.6, 0.6, 0.6], "shininess": 60 },
        },
        "lights": [
            { "position": [-0.4, 1, 0.6, 0] },
            { "position": [0.5, 0.7, -0.2, 0], "diffuse": [0.3, 0.3, 0.4] },
            { "position": [4, 3, 4, 1], "attenuation": [1, 0.05, 0.01] },
            { "position": [-4, 2.5, -2, 1], "attenuation": [1, 0.1, 0.02] },
        ],
        "camera": { "eye": [0, 4, 9], "target": [0, 0.5, -2], "up": [0, 1, 0],
                    "fov_y": 45, "width": WIDTH, "height": HEIGHT },
        "objects": objects,
    }))
}

/// A UV sphere of `2·segments·(rings − 1)` triangles with vertex normals.
fn uv_sphere(segments: u32, rings: u32) -> Value {
    let (positions, indices) = common::uv_sphere(segments, rings);
    json!({ "positions": positions, "normals": positions, "indices": indices })
}

/// ~100k triangles (a 224×224 UV sphere: 99,904) filling most of the
/// image, on a floor, two lights.
fn mesh() -> RenderScene {
    scene_of(&json!({
        "materials": {
            "gold": { "diffuse": [0.75, 0.6, 0.23], "specular": [0.6, 0.55, 0.4], "shininess": 50 },
            "floor": { "diffuse": [0.4, 0.45, 0.5] },
        },
        "lights": [
            { "position": [2, 3, 4, 1], "attenuation": [1, 0.02, 0.005] },
            { "position": [-1, 0.5, 0.3, 0], "diffuse": [0.3, 0.3, 0.45] },
        ],
        "camera": { "eye": [0, 0.8, 3.2], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 45, "width": WIDTH, "height": HEIGHT },
        "objects": [
            { "mesh": uv_sphere(224, 224), "material": "gold" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "floor" },
        ],
    }))
}

fn bench(c: &mut Criterion) {
    let spheres = spheres();
    let mesh = mesh();
    let rays = u64::from(WIDTH * HEIGHT);
    let mut group = c.benchmark_group("render");
    group.sample_size(10);

    group.throughput(Throughput::Elements(rays));
    group.bench_function("spheres_1080p", |b| {
        b.iter(|| render::render(black_box(&spheres), Form::Png, &|| false).unwrap())
    });
    group.bench_function("mesh_100k_1080p", |b| {
        b.iter(|| render::render(black_box(&mesh), Form::Png, &|| false).unwrap())
    });

    let renderer = &Renderer::new(&mesh);
    let geometry = renderer.geometry();
    geometry.build_bvh(BvhUse::PrimaryRays);
    let packets = &Packets::new(geometry, renderer.camera().eye()).expect("a near eye");
    group.bench_function("frame_100k_1080p", |b| {
        b.iter(|| {
            let frame = renderer.render(false, &|| false).unwrap();
            film::encode_png(frame.width, frame.height, &frame.rgba)
        })
    });
    group.bench_function("traverse_100k_1080p", |b| {
        b.iter(|| {
            // Bands of four rows, in blocks of 4×4 pixels.
            (0..HEIGHT / 4)
                .into_par_iter()
                .map(|band| {
                    let rays: Vec<_> = (0..WIDTH / 4)
                        .flat_map(|bx| {
                            (0..16).map(move |k| {
                                renderer
                                    .camera()
                                    .centre_ray(bx * 4 + k % 4, band * 4 + k / 4)
                            })
                        })
                        .collect();
                    let mut hits = vec![None; rays.len()];
                    packets.trace(geometry, &rays, &mut hits);
                    hits.iter().flatten().count()
                })
                .sum::<usize>()
        })
    });
    group.bench_function("traverse_single_100k_1080p", |b| {
        b.iter(|| {
            (0..HEIGHT)
                .into_par_iter()
                .map(|y| {
                    (0..WIDTH)
                        .filter(|&x| {
                            let ray = renderer.camera().centre_ray(x, y);
                            renderer.geometry().closest_hit(&ray).is_some()
                        })
                        .count()
                })
                .sum::<usize>()
        })
    });

    group.throughput(Throughput::Elements(mesh.triangles() as u64));
    group.bench_function("build_100k", |b| {
        b.iter(|| {
            let geometry = Geometry::new(black_box(&mesh.objects));
            geometry.build_bvh(BvhUse::PrimaryRays);
            geometry
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

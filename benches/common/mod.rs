//! The scenes of the speed targets, shared by the benchmarks and the trade
//! table: lighting descriptions in the API's own JSON (`benches/scenes/`,
//! which the NumPy comparison reads too) on a deterministic mesh.

// Each benchmark uses only part of this module.
#![allow(dead_code)]

use glam::DVec3;
use glint::scene::{Limits, ShadeScene, TermsDetail};
use glint_lighting::Precision;

/// (name, file) of each scene, simplest first.
pub const SCENES: [(&str, &str); 4] = [
    ("1 directional, no specular", "one_directional_diffuse"),
    ("1 directional", "one_directional"),
    ("8 positional", "eight_positional"),
    ("8 spots, local viewer, separate specular", "eight_spots"),
];

/// A bumpy grid of `count` vertices with varied unit normals; the NumPy
/// script builds the same one.
pub fn mesh(count: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let side = (count as f64).sqrt().ceil() as usize;
    (0..count)
        .map(|i| {
            let u = (i % side) as f64 / side as f64;
            let v = (i / side) as f64 / side as f64;
            let p = DVec3::new(u * 4.0 - 2.0, v * 4.0 - 2.0, -3.0 + 0.2 * (u * 9.0).sin());
            let n = DVec3::new((u * 7.0).sin() * 0.5, (v * 5.0).cos() * 0.5, 1.0).normalize();
            (p, n)
        })
        .unzip()
}

/// The JSON of scene `file`.
pub fn scene_json(file: &str) -> serde_json::Value {
    let path = format!("{}/benches/scenes/{file}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(&path).expect("the scene file exists"))
        .expect("the scene file is JSON")
}

/// Scene `file` on `count` vertices, validated as `/v1/shade` would.
pub fn scene(file: &str, count: usize) -> ShadeScene {
    let mut request = scene_json(file);
    request["vertices"] = serde_json::json!({ "positions": [], "normals": [] });
    let limits = Limits {
        max_vertices: usize::MAX,
        ..Limits::default()
    };
    let mut scene = glint::scene::parse_shade(request.to_string().as_bytes(), &limits)
        .expect("the scene is valid");
    let (positions, normals) = mesh(count);
    scene.positions = positions;
    scene.normals = normals;
    scene.precision = Precision::Accurate;
    scene.terms = TermsDetail::None;
    scene
}

/// A UV sphere of radius 1 at the origin, `2·segments·(rings − 1)`
/// triangles: its positions (which are also its unit normals) and its
/// vertex indices, three per triangle, counter-clockwise seen from outside.
pub fn uv_sphere(segments: u32, rings: u32) -> (Vec<[f64; 3]>, Vec<u32>) {
    let mut positions = vec![[0.0, 1.0, 0.0]];
    for i in 1..rings {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
        for j in 0..segments {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(segments);
            positions.push([
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ]);
        }
    }
    positions.push([0.0, -1.0, 0.0]);
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let last = positions.len() as u32 - 1;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.extend([0, ring(1, j), ring(1, j + 1)]);
        indices.extend([last, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            indices.extend([a, b, c, a, c, d]);
        }
    }
    (positions, indices)
}

/// The CPU's model name, for the tables' headers.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

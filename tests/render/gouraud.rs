//! Per-vertex (Gouraud) shading against per-pixel shading: equal at the
//! vertices, where both are the lighting equation at the vertex, different
//! between them; spheres and planes fall back to per pixel, with a warning.

use glam::DVec3;
use serde_json::{Value, json};

use super::support::{Cam, Lamp, Mat, assert_close, floats, gl_color, json_of, png_of};

const CAM: Cam = Cam {
    eye: DVec3::new(0.0, 0.0, 0.0),
    target: DVec3::new(0.0, 0.0, -1.0),
    up: DVec3::new(0.0, 1.0, 0.0),
    fov_y: 60.0,
    width: 9,
    height: 9,
};

const SHINY: Mat = Mat {
    ambient: [0.2, 0.2, 0.2, 1.0],
    diffuse: [0.6, 0.4, 0.2, 1.0],
    specular: [0.8, 0.8, 0.8, 1.0],
    emission: [0.0, 0.0, 0.0, 1.0],
    shininess: 30.0,
};

const LAMP: Lamp = Lamp {
    position: [0.5, 0.8, -3.0, 1.0],
    ambient: [0.0, 0.0, 0.0],
    diffuse: [1.0, 1.0, 1.0],
    specular: [1.0, 1.0, 1.0],
    attenuation: [1.0, 0.0, 0.1],
};

/// A 5×5 grid of vertices, vertex (i, j) on the centre ray of pixel
/// (2i, 2j) at a varying depth, with varying normals; two counter-clockwise
/// triangles per cell.
fn grid() -> (Vec<DVec3>, Vec<DVec3>, Vec<u32>) {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for j in 0..5u32 {
        for i in 0..5u32 {
            let depth = 4.0 + 0.3 * (i as f64).sin() + 0.2 * j as f64;
            positions.push(CAM.eye + depth * CAM.centre_dir(2 * i, 2 * j));
            normals.push(DVec3::new(
                0.3 * (i as f64 - 2.0),
                -0.25 * (j as f64 - 2.0),
                1.0,
            ));
        }
    }
    let at = |i: u32, j: u32| j * 5 + i;
    let mut indices = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            indices.extend([at(i, j), at(i, j + 1), at(i + 1, j)]);
            indices.extend([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    (positions, normals, indices)
}

fn request(shading: &str, precision: &str, probes: &[[u32; 2]]) -> Value {
    let (positions, normals, indices) = grid();
    json!({
        "materials": { "shiny": SHINY.json() },
        "lights": [LAMP.json()],
        "camera": CAM.json(),
        "objects": [ {
            "mesh": {
                "positions": positions.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
                "normals": normals.iter().map(|n| n.to_array()).collect::<Vec<_>>(),
                "indices": indices,
            },
            "material": "shiny",
        } ],
        "shading": shading,
        "precision": precision,
        "probes": probes,
    })
}

/// The interior vertices: their pixels' centre rays pass through them.
fn interior() -> Vec<(u32, u32)> {
    (1..4).flat_map(|j| (1..4).map(move |i| (i, j))).collect()
}

#[test]
fn per_vertex_and_per_pixel_agree_at_the_vertices() {
    let (positions, normals, _) = grid();
    let probes: Vec<[u32; 2]> = interior().iter().map(|&(i, j)| [2 * i, 2 * j]).collect();
    // (precision, agreement of the two modes, bound against the f64 formula)
    for (precision, tol, bound) in [("reference", 1e-12, 1e-7), ("accurate", 2e-6, 1e-5)] {
        let vertex = json_of(&request("per_vertex", precision, &probes));
        let pixel = json_of(&request("per_pixel", precision, &probes));
        let vertex_png = png_of(&request("per_vertex", precision, &[]));
        let pixel_png = png_of(&request("per_pixel", precision, &[]));
        for (k, &(i, j)) in interior().iter().enumerate() {
            let v = positions[(j * 5 + i) as usize];
            let n = normals[(j * 5 + i) as usize].normalize();
            // The lighting equation at the vertex, written out.
            let expected = gl_color(&SHINY, [0.2; 3], &[LAMP], v, n, DVec3::Z, &[true]);
            let context = format!("vertex ({i}, {j}), {precision}");
            let c_vertex = floats(&vertex["terms"]["probes"][k]["color"]);
            let c_pixel = floats(&pixel["terms"]["probes"][k]["color"]);
            assert_close(&c_vertex, &expected, bound, &context);
            assert_close(&c_pixel, &expected, bound, &context);
            assert_close(&c_vertex, &c_pixel, tol, &context);
            let (x, y) = (2 * i, 2 * j);
            assert_eq!(
                vertex_png.get_pixel(x, y),
                pixel_png.get_pixel(x, y),
                "{context}: pixel ({x}, {y})"
            );
        }
    }
}

/// Between the vertices Gouraud interpolates colours, which the
/// highlight's non-linearity sets apart from lighting each pixel.
#[test]
fn per_vertex_and_per_pixel_differ_between_the_vertices() {
    let probes: Vec<[u32; 2]> = (0..9).flat_map(|y| (0..9).map(move |x| [x, y])).collect();
    let vertex = json_of(&request("per_vertex", "accurate", &probes));
    let pixel = json_of(&request("per_pixel", "accurate", &probes));
    let largest = (0..probes.len())
        .map(|k| {
            let a = floats(&vertex["terms"]["probes"][k]["color"]);
            let b = floats(&pixel["terms"]["probes"][k]["color"]);
            a.iter()
                .zip(&b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(largest > 0.01, "the largest difference is only {largest}");
    assert_eq!(vertex["warnings"], json!([]));
}

/// An f32 precision that cannot promise its bound says so in a render as
/// in a shade response, counting the objects whose material is concerned.
#[test]
fn renders_warn_where_an_f32_bound_cannot_hold() {
    let request = |precision: &str| {
        json!({
            "materials": {
                "shiny": SHINY.json(),
                "negative": { "diffuse": [1.5, -0.5, 0.2] },
            },
            "lights": [LAMP.json()],
            "camera": CAM.json(),
            "objects": [
                { "sphere": { "center": [0.0, 0.0, -4.0], "radius": 1.0 }, "material": "negative" },
                { "sphere": { "center": [2.0, 0.0, -4.0], "radius": 1.0 }, "material": "negative" },
                { "plane": { "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0] }, "material": "shiny" },
            ],
            "precision": precision,
        })
    };
    for precision in ["accurate", "fast"] {
        let body = json_of(&request(precision));
        let warnings = body["warnings"].as_array().unwrap();
        assert_eq!(warnings.len(), 1, "{precision}: {warnings:?}");
        assert_eq!(warnings[0]["code"], "precision_bound");
        assert_eq!(
            warnings[0]["count"], 2,
            "the two objects of the negative material"
        );
    }
    assert_eq!(json_of(&request("reference"))["warnings"], json!([]));
}

#[test]
fn per_vertex_spheres_and_planes_fall_back_to_per_pixel_with_a_warning() {
    let request = |shading: &str| {
        json!({
            "materials": { "shiny": SHINY.json() },
            "lights": [LAMP.json()],
            "camera": CAM.json(),
            "objects": [
                { "sphere": { "center": [0.0, 0.0, -4.0], "radius": 1.0 }, "material": "shiny" },
                { "plane": { "point": [0.0, -1.0, 0.0], "normal": [0.0, 1.0, 0.0] }, "material": "shiny" },
            ],
            "shading": shading,
        })
    };
    let body = json_of(&request("per_vertex"));
    let warnings = body["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0]["code"], "per_pixel_fallback");
    assert_eq!(warnings[0]["count"], 2);
    assert_eq!(json_of(&request("per_pixel"))["warnings"], json!([]));
    assert_eq!(
        png_of(&request("per_vertex")),
        png_of(&request("per_pixel"))
    );
}

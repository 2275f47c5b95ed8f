//! The film: regions are crops of the whole image, samples are reproducible
//! and averaged, and the PNG holds what the encoding says.

use glam::DVec3;
use serde_json::{Value, json};

use super::support::{Cam, byte, decode_png, json_of, png_of, srgb};

const CAM: Cam = Cam {
    eye: DVec3::new(1.0, 2.0, 7.0),
    target: DVec3::new(0.0, 0.0, 0.0),
    up: DVec3::new(0.0, 1.0, 0.0),
    fov_y: 45.0,
    width: 48,
    height: 36,
};

/// Spheres, a floor, a two-triangle mesh without normals and a mesh with
/// them, in a mix of features: samples, shadows, two lights.
fn busy_scene(extra: Value) -> Value {
    let mut r = json!({
        "light_model": { "two_side": true, "local_viewer": true },
        "materials": {
            "a": { "diffuse": [0.9, 0.3, 0.2], "specular": [0.6, 0.6, 0.6], "shininess": 25 },
            "b": { "diffuse": [0.2, 0.5, 0.9, 0.8], "emission": [0.05, 0.05, 0.0] },
            "floor": { "diffuse": [0.6, 0.6, 0.6], "ambient": [0.3, 0.3, 0.3] }
        },
        "lights": [
            { "position": [2, 5, 3, 1], "attenuation": [1, 0.02, 0.005] },
            { "position": [-1, 1, 0.5, 0], "diffuse": [0.3, 0.3, 0.6], "specular": [0.2, 0.2, 0.2] }
        ],
        "camera": CAM.json(),
        "objects": [
            { "sphere": { "center": [0, 0, 0], "radius": 1 }, "material": "a" },
            { "sphere": { "center": [1.8, -0.4, 0.8], "radius": 0.6 }, "material": "b" },
            { "plane": { "point": [0, -1, 0], "normal": [0, 1, 0] }, "material": "floor" },
            { "mesh": {
                "positions": [[-3, -1, -2], [-1, -1, -2], [-1, 1.5, -2.5], [-3, 1.2, -2.5]],
                "indices": [0, 1, 2, 0, 2, 3] }, "material": "b" },
            { "mesh": {
                "positions": [[1, 0.5, -1], [2.5, 0.2, -1.5], [1.8, 1.8, -1.2]],
                "normals": [[0, 0, 1], [0.5, 0, 1], [0, 0.5, 1]],
                "indices": [0, 1, 2] }, "material": "a" }
        ],
        "background": [0.05, 0.1, 0.2, 1],
        "samples": 5,
        "shadows": true,
    });
    for (k, v) in extra.as_object().unwrap() {
        r[k] = v.clone();
    }
    r
}

#[test]
fn a_region_equals_the_same_crop_of_the_whole_image() {
    for extra in [
        json!({}),
        json!({ "shading": "per_vertex", "precision": "reference" }),
        json!({ "samples": 1, "encoding": "srgb" }),
    ] {
        let whole = png_of(&busy_scene(extra.clone()));
        assert_eq!(whole.dimensions(), (CAM.width, CAM.height));
        let distinct: std::collections::HashSet<_> = whole.pixels().collect();
        assert!(
            distinct.len() > 50,
            "a busy image: {} colours",
            distinct.len()
        );
        for (x, y, w, h) in [
            (13, 7, 20, 15),
            (0, 0, 1, 1),
            (47, 35, 1, 1),
            (5, 30, 43, 6),
        ] {
            let mut request = busy_scene(extra.clone());
            request["region"] = json!({ "x": x, "y": y, "width": w, "height": h });
            let tile = png_of(&request);
            assert_eq!(tile.dimensions(), (w, h), "the PNG is the region's size");
            for ty in 0..h {
                for tx in 0..w {
                    assert_eq!(
                        tile.get_pixel(tx, ty),
                        whole.get_pixel(x + tx, y + ty),
                        "region ({x}, {y}, {w}, {h}) pixel ({tx}, {ty}) with {extra}"
                    );
                }
            }
        }
    }
}

#[test]
fn renders_are_reproducible() {
    let a = png_of(&busy_scene(json!({ "samples": 7 })));
    let b = png_of(&busy_scene(json!({ "samples": 7 })));
    assert_eq!(a, b);
}

/// A pixel half on a black object and half on a white background: its
/// samples average to a grey whose level is the share of samples on each.
#[test]
fn samples_are_box_filtered() {
    let cam = json!({ "eye": [0, 0, 0], "target": [0, 0, -1], "up": [0, 1, 0],
                      "fov_y": 90, "width": 1, "height": 1 });
    // The plane y = 0 seen from above covers the lower half of the single
    // pixel exactly (its horizon passes through the pixel's centre).
    let request = |samples: u32| {
        json!({
            "materials": { "white": { "ambient": [0,0,0], "diffuse": [0,0,0], "emission": [1, 1, 1] } },
            "camera": cam,
            "objects": [ { "plane": { "point": [0, -1e-9, 0], "normal": [0, 1, 0] }, "material": "white" } ],
            "background": [0, 0, 0, 1],
            "samples": samples,
        })
    };
    // 1 sample: the centre ray is horizontal and misses; 4 samples on a 2×2
    // grid: two in the lower half hit.
    assert_eq!(png_of(&request(1)).get_pixel(0, 0).0, [0, 0, 0, 255]);
    assert_eq!(png_of(&request(4)).get_pixel(0, 0).0, [128, 128, 128, 255]);
    // 16 samples on a 4×4 grid: 8 below the horizon.
    assert_eq!(png_of(&request(16)).get_pixel(0, 0).0, [128, 128, 128, 255]);
    // 2 samples: one cell in each row (the second row right to left).
    assert_eq!(png_of(&request(2)).get_pixel(0, 0).0, [128, 128, 128, 255]);
}

/// A uniform image: an emissive plane filling the view, and the
/// background elsewhere.
fn flat(encoding: &str) -> Value {
    json!({
        "materials": { "glow": {
            "ambient": [0, 0, 0], "diffuse": [0, 0, 0, 0.6], "emission": [0.21, 0.52, 0.71] } },
        "camera": { "eye": [0, 0, 1], "target": [0, 0, 0], "up": [0, 1, 0],
                    "fov_y": 30, "width": 12, "height": 8 },
        "objects": [ { "plane": { "point": [0, 0, 0], "normal": [0, 0, 1] }, "material": "glow" } ],
        "encoding": encoding,
        "region": { "x": 2, "y": 1, "width": 7, "height": 5 },
    })
}

#[test]
fn png_is_linear_by_default_and_srgb_on_request() {
    let linear = png_of(&flat("linear"));
    assert_eq!(linear.dimensions(), (7, 5));
    // round(255·c), alpha from the diffuse alpha 0.6.
    let want_linear = [byte(0.21), byte(0.52), byte(0.71), byte(0.6)];
    assert_eq!(want_linear, [54, 133, 181, 153]);
    assert!(linear.pixels().all(|p| p.0 == want_linear));

    let srgb_img = png_of(&flat("srgb"));
    // The transfer curve on colour, not on alpha.
    let want_srgb = [
        byte(srgb(0.21)),
        byte(srgb(0.52)),
        byte(srgb(0.71)),
        byte(0.6),
    ];
    assert_eq!(want_srgb, [126, 191, 219, 153]);
    assert!(
        srgb_img.pixels().all(|p| p.0 == want_srgb),
        "{:?}",
        srgb_img.get_pixel(0, 0)
    );

    let mut default = flat("linear");
    default.as_object_mut().unwrap().remove("encoding");
    assert_eq!(png_of(&default), linear);
}

#[test]
fn the_json_form_carries_the_same_png() {
    let body = json_of(&flat("srgb"));
    assert_eq!(body["width"], 7);
    assert_eq!(body["height"], 5);
    use base64::Engine;
    let png = base64::engine::general_purpose::STANDARD
        .decode(body["png_base64"].as_str().unwrap())
        .unwrap();
    assert_eq!(decode_png(&png), png_of(&flat("srgb")));
    let stats = &body["stats"];
    assert_eq!(stats["width"], 7);
    assert_eq!(stats["pixels"], 35);
    assert_eq!(stats["samples"], 1);
    // One primary ray per pixel and nothing else (no lights, no probes).
    assert_eq!(stats["rays"], 35);
    for key in ["bvh_build_ms", "render_ms", "encode_ms", "compute_ms"] {
        assert!(stats[key].as_f64().unwrap() >= 0.0, "{key}");
    }
    // Every pixel hit the plane: 35 centre breakdowns, none clamped.
    assert_eq!(body["terms"]["summary"]["vertices"], 35);
    assert_eq!(body["terms"]["summary"]["clamped_share"], 0.0);
    assert_eq!(body["modeled"], json!(["emission"]));
    assert_eq!(body["terms"]["probes"], json!([]));
}

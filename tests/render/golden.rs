//! Golden pixels: each primitive's pixels against the analytic ray tracer
//! of `support` (camera, intersection and the lighting equation written
//! out), through both the PNG and the probes of the JSON form.

use glam::DVec3;
use serde_json::{Value, json};

use super::support::{
    BLACK4, Cam, Lamp, Mat, assert_close, assert_pixel, barycentric, byte, floats, gl_color,
    json_of, png_of, ray_plane, ray_sphere,
};

const CAM: Cam = Cam {
    eye: DVec3::new(0.0, 1.0, 6.0),
    target: DVec3::new(0.0, 0.0, 0.0),
    up: DVec3::new(0.0, 1.0, 0.0),
    fov_y: 40.0,
    width: 65,
    height: 49,
};

const SPHERE_C: DVec3 = DVec3::ZERO;
const SPHERE_R: f64 = 1.0;
const FLOOR_P: DVec3 = DVec3::new(0.0, -1.0, 0.0);
const FLOOR_N: DVec3 = DVec3::new(0.0, 1.0, 0.0);
const GLOBAL_AMBIENT: [f64; 3] = [0.2, 0.2, 0.2];
const BACKGROUND: [f64; 4] = [0.1, 0.2, 0.3, 0.5];

const RED: Mat = Mat {
    ambient: [0.3, 0.1, 0.1, 1.0],
    diffuse: [0.8, 0.2, 0.1, 1.0],
    specular: [0.5, 0.5, 0.5, 1.0],
    emission: [0.05, 0.0, 0.0, 1.0],
    shininess: 20.0,
};

const FLOOR: Mat = Mat {
    ambient: [0.2, 0.2, 0.2, 1.0],
    diffuse: [0.5, 0.6, 0.5, 1.0],
    specular: [0.0, 0.0, 0.0, 1.0],
    emission: [0.0, 0.0, 0.0, 1.0],
    shininess: 0.0,
};

fn lamps() -> [Lamp; 2] {
    [
        Lamp {
            position: [1.0, 2.0, 1.5, 0.0],
            ambient: [0.1, 0.1, 0.1],
            diffuse: [0.9, 0.9, 0.8],
            specular: [1.0, 1.0, 1.0],
            attenuation: [1.0, 0.0, 0.0],
        },
        Lamp {
            position: [-3.0, 4.0, 2.0, 1.0],
            ambient: [0.0, 0.0, 0.0],
            diffuse: [0.3, 0.3, 0.5],
            specular: [0.5, 0.5, 0.5],
            attenuation: [1.0, 0.05, 0.01],
        },
    ]
}

/// A red sphere on a grey floor, two lights.
fn request(extra: Value) -> Value {
    let mut r = json!({
        "materials": { "red": RED.json(), "floor": FLOOR.json() },
        "lights": lamps().iter().map(Lamp::json).collect::<Vec<_>>(),
        "camera": CAM.json(),
        "objects": [
            { "sphere": { "center": SPHERE_C.to_array(), "radius": SPHERE_R }, "material": "red" },
            { "plane": { "point": FLOOR_P.to_array(), "normal": FLOOR_N.to_array() }, "material": "floor" }
        ],
        "background": BACKGROUND,
    });
    for (k, v) in extra.as_object().unwrap() {
        r[k] = v.clone();
    }
    r
}

/// What the analytic tracer sees through the image point: the hit's
/// object, point and colour.
fn analytic(px: f64, py: f64, shadows: bool) -> Option<(usize, DVec3, [f64; 4])> {
    let d = CAM.dir(px, py);
    let o = CAM.eye;
    let sphere = ray_sphere(o, d, SPHERE_C, SPHERE_R);
    let floor = ray_plane(o, d, FLOOR_P, FLOOR_N);
    let (object, t) = match (sphere, floor) {
        (Some(s), Some(f)) if f < s => (1, f),
        (Some(s), _) => (0, s),
        (None, Some(f)) => (1, f),
        (None, None) => return None,
    };
    let v = o + t * d;
    let (m, n) = if object == 0 {
        (&RED, (v - SPHERE_C) / SPHERE_R)
    } else {
        (&FLOOR, FLOOR_N)
    };
    let lamps = lamps();
    // Only the sphere can shadow (both lights are above the floor).
    let lit: Vec<bool> = lamps
        .iter()
        .map(|l| {
            if !shadows || object == 0 {
                return true;
            }
            let (towards, dist) = l.towards(v);
            ray_sphere(v, towards, SPHERE_C, SPHERE_R).is_none_or(|t| t >= dist)
        })
        .collect();
    let c = gl_color(
        m,
        GLOBAL_AMBIENT,
        &lamps,
        v,
        n.normalize(),
        CAM.infinite_viewer(),
        &lit,
    );
    Some((object, v, c))
}

fn pixel(img: &image::RgbaImage, x: u32, y: u32) -> [u8; 4] {
    img.get_pixel(x, y).0
}

/// The centre pixel of a 65×49 image looks straight at the sphere's centre.
#[test]
fn sphere_centre_pixel_matches_the_analytic_colour() {
    let (x, y) = (32, 24);
    let (object, point, expected) = analytic(32.5, 24.5, false).unwrap();
    assert_eq!(object, 0, "the centre ray hits the sphere");

    let img = png_of(&request(json!({})));
    assert_pixel(pixel(&img, x, y), expected, "centre pixel (accurate)");

    for (precision, tol) in [
        ("accurate", 1e-5),
        ("fast", 1.0 / 512.0),
        ("reference", 1e-7),
    ] {
        let body = json_of(&request(
            json!({ "precision": precision, "probes": [[x, y]] }),
        ));
        let probe = &body["terms"]["probes"][0];
        assert_eq!(probe["pixel"], json!([x, y]));
        assert_eq!(probe["hit"]["object"], 0);
        assert_eq!(probe["hit"]["side"], "front");
        assert_close(
            &floats(&probe["hit"]["point"]),
            &point.to_array(),
            1e-12,
            "hit point",
        );
        let normal = (point - SPHERE_C) / SPHERE_R;
        assert_close(
            &floats(&probe["hit"]["normal"]),
            &normal.to_array(),
            1e-12,
            "normal",
        );
        assert_close(&floats(&probe["color"]), &expected, tol, precision);
        // The breakdown sums to the colour before clamping.
        let clamped: Vec<f64> = floats(&probe["breakdown"]["unclamped"])
            .iter()
            .map(|c| c.clamp(0.0, 1.0))
            .collect();
        assert_close(&clamped, &expected[..3], 1e-12, "breakdown sum");
        assert_eq!(body["precision"]["mode"], precision);
    }
}

/// Off-centre pixels of the sphere: its specular highlight and its edge.
#[test]
fn sphere_pixels_match_the_analytic_colour() {
    let img = png_of(&request(json!({})));
    for (x, y) in [(36, 20), (28, 27), (40, 24), (32, 17), (25, 22)] {
        let (object, _, expected) = analytic(x as f64 + 0.5, y as f64 + 0.5, false).unwrap();
        assert_eq!(object, 0, "pixel ({x}, {y}) is on the sphere");
        assert_pixel(pixel(&img, x, y), expected, &format!("pixel ({x}, {y})"));
    }
}

#[test]
fn plane_pixel_matches_the_analytic_colour() {
    let (x, y) = (8, 44);
    let (object, point, expected) = analytic(x as f64 + 0.5, y as f64 + 0.5, false).unwrap();
    assert_eq!(object, 1, "pixel ({x}, {y}) is on the floor");
    let img = png_of(&request(json!({})));
    assert_pixel(pixel(&img, x, y), expected, "floor pixel");

    let body = json_of(&request(
        json!({ "precision": "reference", "probes": [[x, y]] }),
    ));
    let probe = &body["terms"]["probes"][0];
    assert_eq!(probe["hit"]["object"], 1);
    assert_close(
        &floats(&probe["hit"]["point"]),
        &point.to_array(),
        1e-12,
        "hit point",
    );
    assert_close(
        &floats(&probe["hit"]["normal"]),
        &FLOOR_N.to_array(),
        0.0,
        "normal",
    );
    assert_close(&floats(&probe["color"]), &expected, 1e-7, "floor colour");
}

#[test]
fn a_pixel_that_misses_is_the_background() {
    let (x, y) = (0, 0);
    assert!(analytic(0.5, 0.5, false).is_none(), "the corner ray misses");
    let img = png_of(&request(json!({})));
    assert_eq!(pixel(&img, x, y), BACKGROUND.map(byte));
    assert_eq!(pixel(&img, x, y), [26, 51, 77, 128]);

    let body = json_of(&request(json!({ "probes": [[x, y]] })));
    let probe = &body["terms"]["probes"][0];
    assert_eq!(probe["hit"], Value::Null);
    assert_eq!(probe["breakdown"], Value::Null);
    assert_close(&floats(&probe["color"]), &BACKGROUND, 1e-7, "background");
}

/// Every pixel of the image against the analytic tracer, without and with
/// shadows (the sphere's shadow on the floor keeps only the ambient terms).
#[test]
fn whole_image_matches_the_analytic_tracer() {
    for shadows in [false, true] {
        let img = png_of(&request(json!({ "shadows": shadows })));
        assert_eq!(img.dimensions(), (CAM.width, CAM.height));
        let mut shadowed = 0;
        for y in 0..CAM.height {
            for x in 0..CAM.width {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let expected = match analytic(px, py, shadows) {
                    None => BACKGROUND,
                    Some((_, _, c)) => c,
                };
                if shadows && analytic(px, py, false).map(|h| h.2) != Some(expected) {
                    shadowed += 1;
                }
                assert_pixel(
                    pixel(&img, x, y),
                    expected,
                    &format!("pixel ({x}, {y}), shadows {shadows}"),
                );
            }
        }
        if shadows {
            assert!(shadowed > 20, "the shadow covers {shadowed} pixels");
        }
    }
}

/// A shadowed light keeps its ambient term in the breakdown and loses its
/// diffuse one.
#[test]
fn a_shadowed_light_adds_only_its_ambient_term() {
    // A floor pixel in the sphere's shadow from light 0.
    let (x, y) = (22..43)
        .flat_map(|x| (25..49).map(move |y| (x, y)))
        .find(|&(x, y)| {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            matches!(analytic(px, py, false), Some((1, _, _)))
                && analytic(px, py, true).unwrap().2 != analytic(px, py, false).unwrap().2
        })
        .expect("some floor pixel is in the shadow");
    let body = json_of(&request(json!({ "shadows": true, "probes": [[x, y]] })));
    let light0 = &body["terms"]["probes"][0]["breakdown"]["lights"][0];
    assert_eq!(floats(&light0["diffuse"]), [0.0; 3]);
    // a_cm · a_cl0 = 0.2 · 0.1
    assert_close(
        &floats(&light0["ambient"]),
        &[0.02; 3],
        1e-15,
        "ambient of light 0",
    );
    assert!(body["stats"]["rays"].as_u64().unwrap() > u64::from(CAM.width * CAM.height));
}

/// One triangle with vertex normals: the normal at a pixel is the
/// barycentric mix of the three, normalised (GL_NORMALIZE is on by default).
#[test]
fn mesh_triangle_pixel_matches_the_analytic_colour() {
    let cam = Cam {
        eye: DVec3::new(0.2, 0.1, 4.0),
        target: DVec3::new(0.0, 0.0, 0.0),
        up: DVec3::new(0.0, 1.0, 0.0),
        fov_y: 50.0,
        width: 40,
        height: 30,
    };
    let p = [
        DVec3::new(-1.5, -1.0, 0.0),
        DVec3::new(1.5, -1.2, 0.5),
        DVec3::new(0.1, 1.5, -0.5),
    ];
    let n = [
        DVec3::new(-0.3, -0.2, 1.0),
        DVec3::new(0.5, -0.1, 1.0),
        DVec3::new(0.0, 0.6, 0.8),
    ];
    let lamp = Lamp {
        position: [0.5, 1.0, 2.0, 1.0],
        ambient: [0.05, 0.05, 0.05],
        diffuse: [1.0, 0.9, 0.8],
        specular: [1.0, 1.0, 1.0],
        attenuation: [1.0, 0.1, 0.0],
    };
    let m = Mat {
        ambient: [0.2, 0.3, 0.2, 1.0],
        diffuse: [0.2, 0.7, 0.3, 0.75],
        specular: [0.6, 0.6, 0.6, 1.0],
        emission: [0.0, 0.0, 0.1, 1.0],
        shininess: 12.0,
    };
    let mesh = |normals: bool| {
        let mut mesh = json!({
            "positions": p.map(|v| v.to_array()),
            "indices": [0, 1, 2],
        });
        if normals {
            mesh["normals"] = json!(n.map(|v| v.to_array()));
        }
        json!({
            "materials": { "green": m.json() },
            "lights": [lamp.json()],
            "camera": cam.json(),
            "objects": [ { "mesh": mesh, "material": "green" } ],
        })
    };
    let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    // Where the centre ray of a pixel meets the triangle's plane, and its
    // barycentric weights there.
    let on_triangle = |x: u32, y: u32| {
        let d = cam.centre_dir(x, y);
        let v = cam.eye + ray_plane(cam.eye, d, p[0], face).unwrap() * d;
        (v, barycentric(v, p[0], p[1], p[2]))
    };
    // Pixels well inside the triangle: the first, the middle and the last.
    let inside: Vec<(u32, u32)> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .filter(|&(x, y)| on_triangle(x, y).1.iter().all(|&w| w > 0.05))
        .collect();
    assert!(
        inside.len() > 100,
        "the triangle covers {} pixels",
        inside.len()
    );
    let pixels = [
        inside[0],
        inside[inside.len() / 2],
        inside[inside.len() - 1],
    ];
    for normals in [true, false] {
        let mut req = mesh(normals);
        req["probes"] = json!(pixels.map(|(x, y)| [x, y]));
        let img = png_of(&req);
        let body = json_of(&req);
        for (k, (x, y)) in pixels.into_iter().enumerate() {
            let (v, w) = on_triangle(x, y);
            let normal = if normals {
                w[0] * n[0] + w[1] * n[1] + w[2] * n[2]
            } else {
                face
            };
            let expected = gl_color(
                &m,
                [0.2; 3],
                &[lamp],
                v,
                normal.normalize(),
                cam.infinite_viewer(),
                &[true],
            );
            let context = format!("pixel ({x}, {y}), normals {normals}");
            assert_pixel(img.get_pixel(x, y).0, expected, &context);
            let probe = &body["terms"]["probes"][k];
            assert_eq!(probe["hit"]["object"], 0);
            assert_close(
                &floats(&probe["hit"]["point"]),
                &v.to_array(),
                1e-12,
                &context,
            );
            assert_close(
                &floats(&probe["hit"]["normal"]),
                &normal.to_array(),
                1e-12,
                &context,
            );
            assert_close(&floats(&probe["color"]), &expected, 1e-5, &context);
        }
        // Alpha is the material's diffuse alpha: round(255 · 0.75).
        assert_eq!(img.get_pixel(pixels[1].0, pixels[1].1).0[3], 191);
        assert_eq!(
            img.get_pixel(0, 0).0,
            BLACK4.map(byte),
            "the default background"
        );
    }
}

/// Seen from below, the floor shows its back. With two-sided lighting the
/// back side is lit with the negated normal by a light below, with the
/// request's `back_material` or else the floor's own; without it GL lights
/// the front colour with the normal as is, so that light adds only its
/// ambient term.
#[test]
fn back_faces_follow_gl_two_sided_lighting() {
    let cam = Cam {
        eye: DVec3::new(0.0, -3.0, 4.0),
        target: DVec3::new(0.0, -1.0, 0.0),
        up: DVec3::new(0.0, 1.0, 0.0),
        fov_y: 60.0,
        width: 21,
        height: 15,
    };
    let lamp = Lamp {
        position: [0.3, -1.0, 0.2, 0.0],
        ambient: [0.1, 0.1, 0.1],
        diffuse: [1.0, 1.0, 1.0],
        specular: [0.0, 0.0, 0.0],
        attenuation: [1.0, 0.0, 0.0],
    };
    let blue = Mat {
        ambient: [0.0, 0.0, 0.3, 1.0],
        diffuse: [0.1, 0.2, 0.9, 0.5],
        ..FLOOR
    };
    for (two_side, back) in [
        (true, None),
        (true, Some(blue)),
        (false, None),
        (false, Some(blue)),
    ] {
        let mut req = json!({
            "light_model": { "two_side": two_side },
            "materials": { "floor": FLOOR.json() },
            "lights": [lamp.json()],
            "camera": cam.json(),
            "objects": [ { "plane": { "point": FLOOR_P.to_array(), "normal": FLOOR_N.to_array() }, "material": "floor" } ],
            "probes": [[10, 3]],
        });
        if let Some(back) = back {
            req["back_material"] = back.json();
        }
        let body = json_of(&req);
        let probe = &body["terms"]["probes"][0];
        assert_eq!(
            probe["hit"]["side"], "back",
            "the camera is below the floor"
        );
        let d = cam.centre_dir(10, 3);
        let v = cam.eye + ray_plane(cam.eye, d, FLOOR_P, FLOOR_N).unwrap() * d;
        let (m, n) = match (two_side, back) {
            (true, Some(back)) => (back, -FLOOR_N),
            (true, None) => (FLOOR, -FLOOR_N),
            (false, _) => (FLOOR, FLOOR_N),
        };
        let expected = gl_color(&m, [0.2; 3], &[lamp], v, n, cam.infinite_viewer(), &[true]);
        let context = format!("two_side {two_side}, back material {}", back.is_some());
        assert_close(&floats(&probe["color"]), &expected, 1e-5, &context);
        let diffuse = floats(&probe["breakdown"]["lights"][0]["diffuse"]);
        assert_eq!(diffuse.iter().any(|&c| c > 0.0), two_side, "{context}");
        let img = png_of(&req);
        assert_pixel(img.get_pixel(10, 3).0, expected, &context);
    }
}

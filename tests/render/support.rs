//! Helpers of the render tests: requests from JSON, the PNG decoded, and an
//! independent analytic ray tracer for spheres, planes and single triangles
//! with the lighting equation written out, to compute expected pixels.
//!
//! Nothing here calls glint's renderer: the camera, the intersections and
//! the lighting formula are written again from the contract (API.md) and
//! section 2.14.1 of the GL 2.1 specification, plainly.

use glam::DVec3;
use glint::render;
use glint::scene::{self, Limits, RequestError};
use glint_trace::RenderScene;
use image::RgbaImage;
use serde_json::Value;

/// Validates a render request given as JSON.
pub fn scene_of(request: &Value) -> RenderScene {
    try_scene(request).unwrap_or_else(|e| panic!("the request is refused: {e}"))
}

pub fn try_scene(request: &Value) -> Result<RenderScene, RequestError> {
    scene::parse_render(&serde_json::to_vec(request).unwrap(), &Limits::default())
}

/// Renders `request` to a PNG and decodes it.
pub fn png_of(request: &Value) -> RgbaImage {
    decode_png(&render::render_png(&scene_of(request)))
}

pub fn decode_png(bytes: &[u8]) -> RgbaImage {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG signature");
    image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .expect("the PNG decodes")
        .into_rgba8()
}

/// The JSON form of the response to `request`.
pub fn json_of(request: &Value) -> Value {
    let response = render::render_json(&scene_of(request), &|| false).unwrap();
    serde_json::to_value(&response).unwrap()
}

/// round(255·c) of a colour in [0, 1], as GL writes an 8-bit framebuffer.
pub fn byte(c: f64) -> u8 {
    (255.0 * c.clamp(0.0, 1.0)).round() as u8
}

/// The sRGB transfer curve of IEC 61966-2-1.
pub fn srgb(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Asserts that an 8-bit pixel is within one step of the expected colour
/// on every channel (the expected value is rounded from an f64 computation,
/// the renderer's from its own; a value on a rounding boundary may go
/// either way).
#[track_caller]
pub fn assert_pixel(actual: [u8; 4], expected: [f64; 4], context: &str) {
    let want = expected.map(byte);
    let off = actual
        .iter()
        .zip(&want)
        .any(|(a, w)| (i32::from(*a) - i32::from(*w)).abs() > 1);
    assert!(
        !off,
        "{context}: pixel {actual:?}, expected {want:?} (= 255·{expected:?})"
    );
}

/// Asserts two float arrays agree within `tol` per component.
#[track_caller]
pub fn assert_close(actual: &[f64], expected: &[f64], tol: f64, context: &str) {
    assert_eq!(actual.len(), expected.len(), "{context}: lengths differ");
    let diff = actual
        .iter()
        .zip(expected)
        .map(|(a, e)| (a - e).abs())
        .fold(0.0, f64::max);
    assert!(
        diff <= tol,
        "{context}: {actual:?} vs expected {expected:?}, difference {diff:e} > {tol:e}"
    );
}

/// A JSON array of numbers as f64s.
pub fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

// ---------------------------------------------------------------------------
// The analytic model
// ---------------------------------------------------------------------------

/// The pinhole camera of the contract.
#[derive(Clone, Copy, Debug)]
pub struct Cam {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    pub fov_y: f64,
    pub width: u32,
    pub height: u32,
}

impl Cam {
    pub fn json(&self) -> Value {
        serde_json::json!({
            "eye": self.eye.to_array(),
            "target": self.target.to_array(),
            "up": self.up.to_array(),
            "fov_y": self.fov_y,
            "width": self.width,
            "height": self.height,
        })
    }

    /// The unit direction of the ray through the image point (px, py):
    /// the image plane at distance 1 along the view direction, tan(fov/2)
    /// high above and below its centre and width/height times that across,
    /// y growing downwards.
    pub fn dir(&self, px: f64, py: f64) -> DVec3 {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let true_up = right.cross(forward);
        let half_h = (self.fov_y.to_radians() / 2.0).tan();
        let half_w = half_h * self.width as f64 / self.height as f64;
        let sx = px / self.width as f64 * 2.0 - 1.0;
        let sy = 1.0 - py / self.height as f64 * 2.0;
        (forward + sx * half_w * right + sy * half_h * true_up).normalize()
    }

    /// The ray through the centre of pixel (x, y).
    pub fn centre_dir(&self, x: u32, y: u32) -> DVec3 {
        self.dir(x as f64 + 0.5, y as f64 + 0.5)
    }

    /// GL's infinite viewer: the unit direction from the target to the eye.
    pub fn infinite_viewer(&self) -> DVec3 {
        (self.eye - self.target).normalize()
    }
}

/// The nearest t > 0 of |o + t·d − c|² = r² (d of unit length), by the
/// quadratic formula.
pub fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.dot(oc) - r * r);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [-b - s, -b + s].into_iter().find(|&t| t > 0.0)
}

/// The t > 0 where o + t·d meets the plane through p with normal n.
pub fn ray_plane(o: DVec3, d: DVec3, p: DVec3, n: DVec3) -> Option<f64> {
    let denom = n.dot(d);
    if denom == 0.0 {
        return None;
    }
    let t = (p - o).dot(n) / denom;
    (t > 0.0).then_some(t)
}

/// The barycentric weights (w0, w1, w2) of q in the triangle (a, b, c), by
/// ratios of signed areas along the triangle's normal.
pub fn barycentric(q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let n = (b - a).cross(c - a);
    let area = n.dot(n);
    let w0 = (c - b).cross(q - b).dot(n) / area;
    let w1 = (a - c).cross(q - c).dot(n) / area;
    [w0, w1, 1.0 - w0 - w1]
}

/// One side's material.
#[derive(Clone, Copy, Debug)]
pub struct Mat {
    pub ambient: [f64; 4],
    pub diffuse: [f64; 4],
    pub specular: [f64; 4],
    pub emission: [f64; 4],
    pub shininess: f64,
}

impl Mat {
    pub fn json(&self) -> Value {
        serde_json::json!({
            "ambient": self.ambient,
            "diffuse": self.diffuse,
            "specular": self.specular,
            "emission": self.emission,
            "shininess": self.shininess,
        })
    }
}

/// A light, directional (`w = 0`) or positional.
#[derive(Clone, Copy, Debug)]
pub struct Lamp {
    pub position: [f64; 4],
    pub ambient: [f64; 3],
    pub diffuse: [f64; 3],
    pub specular: [f64; 3],
    pub attenuation: [f64; 3],
}

impl Lamp {
    pub fn json(&self) -> Value {
        serde_json::json!({
            "position": self.position,
            "ambient": self.ambient,
            "diffuse": self.diffuse,
            "specular": self.specular,
            "attenuation": self.attenuation,
        })
    }

    /// The unit vector from `v` to the light, and the distance (infinite
    /// for a directional light).
    pub fn towards(&self, v: DVec3) -> (DVec3, f64) {
        let [x, y, z, w] = self.position;
        if w == 0.0 {
            (DVec3::new(x, y, z).normalize(), f64::INFINITY)
        } else {
            let to = DVec3::new(x, y, z) / w - v;
            (to.normalize(), to.length())
        }
    }
}

/// Section 2.14.1 with a single colour, Blinn-Phong, no spotlights:
///
/// ```text
/// c = e_cm + a_cm·a_cs
///   + Σ_i att_i · [a_cm·a_cli + (n⊙VP_pli) d_cm·d_cli + f_i (n⊙ĥ_i)^s_rm s_cm·s_cli]
/// ```
///
/// with `n` already of unit length, `vp_e` the unit vector to the eye, and
/// light i's diffuse and specular terms only where `lit[i]` (shadows).
pub fn gl_color(
    m: &Mat,
    global_ambient: [f64; 3],
    lamps: &[Lamp],
    v: DVec3,
    n: DVec3,
    vp_e: DVec3,
    lit: &[bool],
) -> [f64; 4] {
    let rgb = |c: [f64; 4]| DVec3::new(c[0], c[1], c[2]);
    let mut c = rgb(m.emission) + rgb(m.ambient) * DVec3::from_array(global_ambient);
    for (lamp, &lit) in lamps.iter().zip(lit) {
        let (vp, d) = lamp.towards(v);
        let att = if d.is_finite() {
            let [k0, k1, k2] = lamp.attenuation;
            1.0 / (k0 + k1 * d + k2 * d * d)
        } else {
            1.0
        };
        let n_dot_vp = n.dot(vp).max(0.0);
        let h = (vp + vp_e).normalize();
        let f = if n_dot_vp > 0.0 { 1.0 } else { 0.0 };
        let spec = if m.shininess == 0.0 {
            1.0
        } else {
            n.dot(h).max(0.0).powf(m.shininess)
        };
        let mut term = rgb(m.ambient) * DVec3::from_array(lamp.ambient);
        if lit {
            term += n_dot_vp * rgb(m.diffuse) * DVec3::from_array(lamp.diffuse)
                + f * spec * rgb(m.specular) * DVec3::from_array(lamp.specular);
        }
        c += att * term;
    }
    let c = c.clamp(DVec3::ZERO, DVec3::ONE);
    [c.x, c.y, c.z, m.diffuse[3].clamp(0.0, 1.0)]
}

pub const BLACK4: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

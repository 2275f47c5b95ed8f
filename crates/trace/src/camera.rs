//! The pinhole camera: from a point of the image plane to a primary ray.
//!
//! The camera frame is right-handed: `w` the unit view direction
//! `target - eye`, `u = normalize(w × up)` to the right of the image, and
//! `v = u × w` its true up. The image plane lies at distance 1 along `w`,
//! `2·tan(fov_y / 2)` high and `aspect` times as wide, `aspect = width /
//! height`. Pixel (0, 0) is the top-left one, x grows to the right and y
//! downwards, so the image point `(fx, fy)` (in pixels, `(x + 0.5, y + 0.5)`
//! being the centre of pixel (x, y)) maps to
//!
//! ```text
//! dir = w + (2·fx/width − 1)·aspect·tan(fov_y/2)·u + (1 − 2·fy/height)·tan(fov_y/2)·v
//! ```
//!
//! and the ray from the eye along it, normalised.

use glam::DVec3;

use super::geometry::Ray;
use crate::scene::Camera;

/// A camera prepared for generating rays.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    eye: DVec3,
    w: DVec3,
    /// `u` and `v` already scaled by the half-extents of the image plane.
    u: DVec3,
    v: DVec3,
    inv_width: f64,
    inv_height: f64,
}

impl PinholeCamera {
    pub fn new(camera: &Camera) -> Self {
        let w = (camera.target - camera.eye).normalize();
        let u = w.cross(camera.up).normalize();
        let v = u.cross(w);
        let tan_half = (camera.fov_y.to_radians() * 0.5).tan();
        let aspect = f64::from(camera.width) / f64::from(camera.height);
        Self {
            eye: camera.eye,
            w,
            u: u * (aspect * tan_half),
            v: v * tan_half,
            inv_width: 1.0 / f64::from(camera.width),
            inv_height: 1.0 / f64::from(camera.height),
        }
    }

    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// The unit view direction `w` and the image plane's half-extents `u`
    /// (to the right) and `v` (up): the direction through `(fx, fy)` is
    /// `w + sx·u + sy·v` before it is normalised.
    pub fn frame(&self) -> (DVec3, DVec3, DVec3) {
        (self.w, self.u, self.v)
    }

    /// The primary ray through the image point `(fx, fy)`, in pixels.
    #[inline]
    pub fn ray(&self, fx: f64, fy: f64) -> Ray {
        let sx = 2.0 * fx * self.inv_width - 1.0;
        let sy = 1.0 - 2.0 * fy * self.inv_height;
        Ray::new(self.eye, self.w + sx * self.u + sy * self.v)
    }

    /// The primary ray through the centre of pixel `(x, y)`.
    pub fn centre_ray(&self, x: u32, y: u32) -> Ray {
        self.ray(f64::from(x) + 0.5, f64::from(y) + 0.5)
    }
}

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

    /// The primary rays through the image points `points` (pixels), into
    /// `rays`: [`Self::ray`] of each, eight at a time in vector lanes (the
    /// same operations in the same order, so the same bits).
    pub fn rays_into(&self, points: &[(f64, f64)], rays: &mut Vec<Ray>) {
        rays.clear();
        rays.reserve(points.len());
        (self.rays_fn())(self, points, rays);
    }

    fn rays_fn(&self) -> RaysFn {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx512f") {
                return |c, p, r| {
                    // SAFETY: the CPU has AVX-512F, checked just above.
                    unsafe { rays_avx512(c, p, r) }
                };
            }
        }
        |c, p, r| c.rays_lanes(p, r)
    }

    #[inline(always)]
    fn rays_lanes(&self, points: &[(f64, f64)], rays: &mut Vec<Ray>) {
        const N: usize = 8;
        for group in points.chunks(N) {
            // The points first, then the directions from them in a loop of
            // lane arithmetic alone: with the gathering in the same loop,
            // the rays of a frame took about 1.6 times as long.
            let (mut fx, mut fy) = ([0.0f64; N], [0.0f64; N]);
            for l in 0..N {
                (fx[l], fy[l]) = group[l.min(group.len() - 1)];
            }
            let mut d = [[0.0f64; N]; 3];
            for l in 0..N {
                // As `ray` and `Ray::new`'s `normalize` compute them.
                let sx = 2.0 * fx[l] * self.inv_width - 1.0;
                let sy = 1.0 - 2.0 * fy[l] * self.inv_height;
                let x = self.w.x + sx * self.u.x + sy * self.v.x;
                let y = self.w.y + sx * self.u.y + sy * self.v.y;
                let z = self.w.z + sx * self.u.z + sy * self.v.z;
                let inv = 1.0 / (x * x + y * y + z * z).sqrt();
                d[0][l] = x * inv;
                d[1][l] = y * inv;
                d[2][l] = z * inv;
            }
            rays.extend((0..group.len()).map(|l| Ray {
                origin: self.eye,
                direction: DVec3::new(d[0][l], d[1][l], d[2][l]),
                t_min: 0.0,
                t_max: f64::INFINITY,
            }));
        }
    }

    /// The primary ray through the centre of pixel `(x, y)`.
    pub fn centre_ray(&self, x: u32, y: u32) -> Ray {
        self.ray(f64::from(x) + 0.5, f64::from(y) + 0.5)
    }
}

type RaysFn = fn(&PinholeCamera, &[(f64, f64)], &mut Vec<Ray>);

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn rays_avx512(camera: &PinholeCamera, points: &[(f64, f64)], rays: &mut Vec<Ray>) {
    camera.rays_lanes(points, rays)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rays made eight at a time are, bit for bit, those made one by
    /// one.
    #[test]
    fn rays_in_lanes_are_the_rays_one_by_one() {
        let camera = PinholeCamera::new(&Camera {
            eye: DVec3::new(0.3, -1.7, 2.9),
            target: DVec3::new(-0.4, 0.2, 0.1),
            up: DVec3::new(0.1, 1.0, 0.0),
            fov_y: 47.0,
            width: 1919,
            height: 1079,
        });
        // Not a multiple of eight: the last group is partial.
        let points: Vec<(f64, f64)> = (0..1003)
            .map(|i| {
                let i = f64::from(i);
                ((i * 7.37) % 1919.0, (i * 3.11) % 1079.0)
            })
            .collect();
        let mut rays = Vec::new();
        camera.rays_into(&points, &mut rays);
        assert_eq!(rays.len(), points.len());
        for (ray, &(x, y)) in rays.iter().zip(&points) {
            assert_eq!(*ray, camera.ray(x, y), "at ({x}, {y})");
        }
    }
}

//! Rays and the shapes they hit, in f64 world space.
//!
//! Every intersection is computed in f64 from the validated scene, whatever
//! the precision of the lighting: the f32 [`Bvh`] only decides which
//! primitives a ray needs to be tested against, never where it hits them. So
//! the point lit for a pixel is the same in all precisions, and the f32
//! tiers differ from the reference only by their documented lighting error.
//!
//! Spheres and triangles live in the BVH; infinite planes have no bounds and
//! are tested against every ray (before the BVH, so that a floor that is hit
//! first shortens the ray for the traversal).

use glam::DVec3;

use super::bvh::{Aabb64, Bvh};
use crate::scene::{Object, Shape};

/// A ray `origin + t·direction`, `direction` of unit length (so `t` is a
/// distance), valid for `t` in (`t_min`, `t_max`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
    pub t_min: f64,
    pub t_max: f64,
}

impl Ray {
    /// A ray from `origin` along `direction` (normalised here) to infinity.
    pub fn new(origin: DVec3, direction: DVec3) -> Self {
        Self {
            origin,
            direction: direction.normalize(),
            t_min: 0.0,
            t_max: f64::INFINITY,
        }
    }

    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.direction
    }
}

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    /// Index into the scene's objects.
    pub object: u32,
    /// The triangle within a mesh (0 for spheres and planes).
    pub triangle: u32,
    /// Barycentric coordinates of the hit in the triangle `(p0, p1, p2)`:
    /// the point is `(1 - u - v)·p0 + u·p1 + v·p2` (0 for spheres and planes).
    pub u: f64,
    pub v: f64,
}

/// A primitive with bounds, in the order of the BVH's leaves.
#[derive(Clone, Copy, Debug)]
enum Prim {
    Sphere {
        object: u32,
        center: DVec3,
        radius: f64,
    },
    /// Precomputed for Möller–Trumbore: the first vertex and two edges.
    Triangle {
        object: u32,
        triangle: u32,
        p0: DVec3,
        e1: DVec3,
        e2: DVec3,
    },
}

impl Prim {
    fn bounds(&self) -> Aabb64 {
        match *self {
            Prim::Sphere { center, radius, .. } => Aabb64 {
                min: center - radius,
                max: center + radius,
            },
            Prim::Triangle { p0, e1, e2, .. } => {
                let (p1, p2) = (p0 + e1, p0 + e2);
                Aabb64 {
                    min: p0.min(p1).min(p2),
                    max: p0.max(p1).max(p2),
                }
            }
        }
    }

    /// The hit of `ray` within (`t_min`, `t_max`), if any.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        match *self {
            Prim::Sphere {
                object,
                center,
                radius,
            } => intersect_sphere(ray, center, radius, t_max).map(|t| Hit {
                t,
                object,
                triangle: 0,
                u: 0.0,
                v: 0.0,
            }),
            Prim::Triangle {
                object,
                triangle,
                p0,
                e1,
                e2,
            } => intersect_triangle(ray, p0, e1, e2, t_max).map(|(t, u, v)| Hit {
                t,
                object,
                triangle,
                u,
                v,
            }),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct PlanePrim {
    object: u32,
    point: DVec3,
    normal: DVec3,
}

/// The scene's shapes, ready for ray queries from many threads at once.
pub struct Geometry {
    /// In the BVH's leaf order.
    prims: Vec<Prim>,
    planes: Vec<PlanePrim>,
    bvh: Option<Bvh>,
    triangles: usize,
    /// The box around the bounded shapes and the planes' points.
    bounds: Aabb64,
}

impl Geometry {
    /// Collects the shapes of `objects` and builds the BVH over those with
    /// bounds.
    pub fn new(objects: &[Object]) -> Self {
        let mut prims = Vec::new();
        let mut planes = Vec::new();
        let mut triangles = 0;
        for (i, o) in objects.iter().enumerate() {
            let object = i as u32;
            match &o.shape {
                Shape::Sphere(s) => prims.push(Prim::Sphere {
                    object,
                    center: s.center,
                    radius: s.radius,
                }),
                Shape::Plane(p) => planes.push(PlanePrim {
                    object,
                    point: p.point,
                    normal: p.normal,
                }),
                Shape::Mesh(m) => {
                    triangles += m.indices.len();
                    prims.extend(m.indices.iter().enumerate().map(|(t, &[a, b, c])| {
                        let p0 = m.positions[a as usize];
                        Prim::Triangle {
                            object,
                            triangle: t as u32,
                            p0,
                            e1: m.positions[b as usize] - p0,
                            e2: m.positions[c as usize] - p0,
                        }
                    }))
                }
            }
        }
        let bounds: Vec<Aabb64> = prims.iter().map(Prim::bounds).collect();
        let whole = bounds
            .iter()
            .copied()
            .chain(planes.iter().map(|p| Aabb64 {
                min: p.point,
                max: p.point,
            }))
            .fold(Aabb64::EMPTY, |a, b| a.union(&b));
        let bvh = (!prims.is_empty()).then(|| Bvh::build(&bounds));
        if let Some(bvh) = &bvh {
            // Leaf order: the traversal then reads primitives in sequence.
            let order = bvh.primitive_order();
            prims = order.iter().map(|&i| prims[i as usize]).collect();
        }
        Self {
            prims,
            planes,
            bvh,
            triangles,
            bounds: whole,
        }
    }

    /// Triangles over all meshes.
    pub fn triangles(&self) -> usize {
        self.triangles
    }

    /// The box around the spheres, the triangles and the planes' points
    /// ([`Aabb64::EMPTY`] for an empty scene).
    pub fn bounds(&self) -> Aabb64 {
        self.bounds
    }

    /// The closest hit of `ray` within (`t_min`, `t_max`).
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best = self.closest_plane(ray);
        let t_max = best.map_or(ray.t_max, |h| h.t);
        if let Some(bvh) = &self.bvh {
            let traversed = bvh.closest(ray, t_max, |prim, t_max| {
                let hit = self.prims[prim].intersect(ray, t_max)?;
                best = Some(hit);
                Some(hit.t)
            });
            if traversed.is_err() {
                return self.closest_hit_brute_force(ray);
            }
        }
        best
    }

    /// The closest plane `ray` meets within (`t_min`, `t_max`). Planes are
    /// unbounded, so they stay out of the BVH.
    fn closest_plane(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for plane in &self.planes {
            let t_max = best.map_or(ray.t_max, |h| h.t);
            if let Some(t) = intersect_plane(ray, plane.point, plane.normal, t_max) {
                best = Some(Hit {
                    t,
                    object: plane.object,
                    triangle: 0,
                    u: 0.0,
                    v: 0.0,
                });
            }
        }
        best
    }

    /// Whether anything lies on `ray` within (`t_min`, `t_max`): the shadow
    /// query.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.planes
            .iter()
            .any(|p| intersect_plane(ray, p.point, p.normal, ray.t_max).is_some())
            || self.bvh.as_ref().is_some_and(|bvh| {
                let hits = |prim: &Prim| prim.intersect(ray, ray.t_max).is_some();
                bvh.any(ray, |i| hits(&self.prims[i]))
                    .unwrap_or_else(|_| self.prims.iter().any(hits))
            })
    }

    /// [`Self::closest_hit`] by testing every primitive: the ground truth
    /// the BVH is checked against.
    pub fn closest_hit_brute_force(&self, ray: &Ray) -> Option<Hit> {
        let mut best = self.closest_plane(ray);
        let mut t_max = best.map_or(ray.t_max, |h| h.t);
        for prim in &self.prims {
            if let Some(hit) = prim.intersect(ray, t_max) {
                t_max = hit.t;
                best = Some(hit);
            }
        }
        best
    }
}

/// The nearest `t` in (`ray.t_min`, `t_max`) where `ray` meets the sphere.
///
/// The roots of `t² - 2bt + c = 0` with `b = -(o - centre)·d` and
/// `c = |o - centre|² - r²`; the discriminant is taken as
/// `r² - |f - (f·d)d|²` (f = o − centre), which keeps its precision for
/// rays that pass far from the centre (Haines et al., *Precision Improvements
/// for Ray/Sphere Intersection*, Ray Tracing Gems, ch. 7), and the smaller
/// root as `c / q` to avoid cancellation.
#[inline]
pub fn intersect_sphere(ray: &Ray, center: DVec3, radius: f64, t_max: f64) -> Option<f64> {
    let f = ray.origin - center;
    let b = -f.dot(ray.direction);
    let l = f + b * ray.direction;
    let disc = radius * radius - l.length_squared();
    if disc < 0.0 {
        return None;
    }
    let c = f.length_squared() - radius * radius;
    let q = b + b.signum() * disc.sqrt();
    let (t0, t1) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        let (a, b) = (c / q, q);
        (a.min(b), a.max(b))
    };
    [t0, t1].into_iter().find(|&t| t > ray.t_min && t < t_max)
}

/// The `t` in (`ray.t_min`, `t_max`) where `ray` meets the plane, if it is
/// not parallel to it.
#[inline]
pub fn intersect_plane(ray: &Ray, point: DVec3, normal: DVec3, t_max: f64) -> Option<f64> {
    let denom = normal.dot(ray.direction);
    if denom == 0.0 {
        return None;
    }
    let t = normal.dot(point - ray.origin) / denom;
    (t > ray.t_min && t < t_max).then_some(t)
}

/// Möller–Trumbore (*Fast, Minimum Storage Ray/Triangle Intersection*,
/// 1997) for the triangle `(p0, p0 + e1, p0 + e2)`, both sides, edges
/// included: `(t, u, v)` with `t` in (`ray.t_min`, `t_max`).
#[inline]
pub fn intersect_triangle(
    ray: &Ray,
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    t_max: f64,
) -> Option<(f64, f64, f64)> {
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - p0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > ray.t_min && t < t_max).then_some((t, u, v))
}

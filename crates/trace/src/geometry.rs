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
//!
//! Whatever the path (brute force, the BVH one ray at a time, packets of
//! primary rays, the rasterized visibility of [`super::raster`]), a ray
//! finds the same hit: the same f64 tests decide, and exact ties go to the
//! earlier primitive in the scene's order (`Closest`): its object first, then
//! its triangle. The order is the request's, so the tie does not depend on
//! which structure found the candidates.
//!
//! The BVH is built on first use ([`Geometry::build_bvh`]): a frame whose
//! primary rays are rasterized and that has no shadow rays never needs it.
//!
//! A scene of a few spheres ([`SPHERES_TESTED_ALL`] at most, nothing else
//! bounded) answers shadow rays without it where the CPU has AVX-512: every
//! sphere is tested, eight at a time in vector lanes ([`SphereLanes`]). That
//! costs a ray about the same whether it passes near a sphere or not, where
//! a traversal costs most for the rays that graze boxes: those of a
//! shadow's edge, which adaptive sampling refines.

use std::sync::OnceLock;

use glam::DVec3;

use super::bvh::{Aabb64, Bvh, BvhUse};
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

impl Hit {
    /// The hit at distance `t` on plane `object` (planes have no triangle
    /// and no barycentrics).
    pub fn on_plane(t: f64, object: u32) -> Self {
        Self {
            t,
            object,
            triangle: 0,
            u: 0.0,
            v: 0.0,
        }
    }
}

/// A primitive with bounds, in the order of the BVH's leaves.
#[derive(Clone, Copy, Debug)]
pub(super) enum Prim {
    Sphere {
        object: u32,
        center: DVec3,
        radius: f64,
    },
    /// The vertices as given: a shared edge is the same two points in
    /// both of its triangles, which keeps [`intersect_triangle`] watertight.
    Triangle {
        object: u32,
        triangle: u32,
        p0: DVec3,
        p1: DVec3,
        p2: DVec3,
    },
}

impl Prim {
    fn bounds(&self) -> Aabb64 {
        match *self {
            Prim::Sphere { center, radius, .. } => Aabb64 {
                min: center - radius,
                max: center + radius,
            },
            Prim::Triangle { p0, p1, p2, .. } => Aabb64 {
                min: p0.min(p1).min(p2),
                max: p0.max(p1).max(p2),
            },
        }
    }

    /// The hit of `ray` within (`t_min`, `t_max`), if any.
    #[inline]
    pub(super) fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
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
                p1,
                p2,
            } => intersect_triangle(ray, [p0, p1, p2], t_max).map(|(t, u, v)| Hit {
                t,
                object,
                triangle,
                u,
                v,
            }),
        }
    }
}

/// A plane as seen from one point: a ray from there along `d` meets it at
/// `t = offset / (normal · d)`, exactly as [`intersect_plane`] computes it.
#[derive(Clone, Copy, Debug)]
pub(super) struct PlaneSeen {
    pub object: u32,
    pub normal: DVec3,
    pub offset: f64,
}

#[derive(Clone, Copy, Debug)]
struct PlanePrim {
    object: u32,
    point: DVec3,
    normal: DVec3,
}

/// The most spheres a scene of spheres alone (and planes) may have for its
/// shadow rays to test each sphere rather than traverse the BVH: one bit
/// each in a [`SphereLanes`] mask (docs/design.md says what it saves).
pub const SPHERES_TESTED_ALL: usize = 64;

/// The spheres of a scene of few spheres, as arrays for vector lanes: each
/// shadow ray is tested against all of them (see the module docs).
struct SphereLanes {
    /// The spheres in the scene's order, [`SPHERE_LANES`] at a time, the
    /// last group padded with spheres that no ray meets.
    groups: Vec<SphereGroup>,
}

/// The spheres tested together: the f64 lanes of an AVX-512 vector.
const SPHERE_LANES: usize = 8;

#[derive(Clone, Copy)]
struct SphereGroup {
    /// Per axis, the centres.
    center: [[f64; SPHERE_LANES]; 3],
    /// `radius · radius`, as [`intersect_sphere`] computes it; −∞ for the
    /// padding.
    radius_squared: [f64; SPHERE_LANES],
}

impl SphereLanes {
    /// The lanes of `prims`, if they are at most [`SPHERES_TESTED_ALL`]
    /// spheres and nothing else, and the CPU has AVX-512.
    fn of(prims: &[Prim]) -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        let vectors = std::is_x86_feature_detected!("avx512f");
        #[cfg(not(target_arch = "x86_64"))]
        let vectors = false;
        if !vectors || prims.is_empty() || prims.len() > SPHERES_TESTED_ALL {
            return None;
        }
        let padding = SphereGroup {
            center: [[0.0; SPHERE_LANES]; 3],
            radius_squared: [f64::NEG_INFINITY; SPHERE_LANES],
        };
        let mut groups = vec![padding; prims.len().div_ceil(SPHERE_LANES)];
        for (i, prim) in prims.iter().enumerate() {
            let Prim::Sphere { center, radius, .. } = *prim else {
                return None;
            };
            let (group, lane) = (&mut groups[i / SPHERE_LANES], i % SPHERE_LANES);
            for (axis, c) in group.center.iter_mut().zip(center.to_array()) {
                axis[lane] = c;
            }
            group.radius_squared[lane] = radius * radius;
        }
        Some(Self { groups })
    }

    /// Whether `ray` meets a sphere within (`t_min`, `t_max`).
    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Self::of` makes lanes only where the CPU has AVX-512F.
        return unsafe { self.hits_avx512(ray, true) } != 0;
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("lanes are made only where the CPU has AVX-512F")
    }

    /// Bit `i` set: `ray` meets sphere `i` within (`t_min`, `t_max`), where
    /// [`intersect_sphere`] returns a hit: its operations in its order,
    /// none fused, so the same bits. A lane whose `disc` is negative or NaN
    /// goes on to a NaN root and no hit, as in the scalar test after its
    /// early return; a vector whose lanes all miss the circle skips the
    /// root. With `first`, it stops at the first group with a hit.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn hits_avx512(&self, ray: &Ray, first: bool) -> u64 {
        use std::arch::x86_64::*;
        let (o, d) = (ray.origin, ray.direction);
        let [ox, oy, oz] = o.to_array().map(|c| _mm512_set1_pd(c));
        let [dx, dy, dz] = d.to_array().map(|c| _mm512_set1_pd(c));
        let (t_min, t_max) = (_mm512_set1_pd(ray.t_min), _mm512_set1_pd(ray.t_max));
        let (zero, one) = (_mm512_setzero_pd(), _mm512_set1_pd(1.0));
        let sign = _mm512_set1_epi64(i64::MIN);
        // SAFETY: each array is SPHERE_LANES f64s, one vector.
        let load = |lanes: &[f64; SPHERE_LANES]| unsafe { _mm512_loadu_pd(lanes.as_ptr()) };
        let dot = |(ax, ay, az), (bx, by, bz)| {
            _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(ax, bx), _mm512_mul_pd(ay, by)),
                _mm512_mul_pd(az, bz),
            )
        };
        let within = |t| {
            _mm512_cmp_pd_mask::<_CMP_GT_OQ>(t, t_min) & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(t, t_max)
        };
        let mut hits = 0u64;
        for (k, group) in self.groups.iter().enumerate() {
            let [cx, cy, cz] = group.center.each_ref().map(load);
            let r2 = load(&group.radius_squared);
            let f = (
                _mm512_sub_pd(ox, cx),
                _mm512_sub_pd(oy, cy),
                _mm512_sub_pd(oz, cz),
            );
            // −(f·d), exactly: the sign bit flipped.
            let b = _mm512_castsi512_pd(_mm512_xor_si512(
                _mm512_castpd_si512(dot(f, (dx, dy, dz))),
                sign,
            ));
            let l = (
                _mm512_add_pd(f.0, _mm512_mul_pd(b, dx)),
                _mm512_add_pd(f.1, _mm512_mul_pd(b, dy)),
                _mm512_add_pd(f.2, _mm512_mul_pd(b, dz)),
            );
            let disc = _mm512_sub_pd(r2, dot(l, l));
            if _mm512_cmp_pd_mask::<_CMP_GE_OQ>(disc, zero) == 0 {
                continue;
            }
            let c = _mm512_sub_pd(dot(f, f), r2);
            // `b.signum()`: 1 with `b`'s sign bit (a NaN `b` leaves `disc`
            // NaN, and the root with it).
            let signum = _mm512_castsi512_pd(_mm512_or_si512(
                _mm512_castpd_si512(one),
                _mm512_and_si512(_mm512_castpd_si512(b), sign),
            ));
            let q = _mm512_add_pd(b, _mm512_mul_pd(signum, _mm512_sqrt_pd(disc)));
            // The roots `c/q` and `q`, or 0 twice where `q` is 0 (a −0
            // compares as 0).
            let q_zero = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(q, zero);
            let near_root = _mm512_mask_mov_pd(_mm512_div_pd(c, q), q_zero, zero);
            let group_hits = within(near_root) | within(q);
            hits |= u64::from(group_hits) << (k * SPHERE_LANES);
            if first && group_hits != 0 {
                break;
            }
        }
        hits
    }
}

/// The scene's shapes, ready for ray queries from many threads at once.
pub struct Geometry {
    /// In the scene's order: objects in order, a mesh's triangles in order.
    prims: Vec<Prim>,
    /// The spheres of a scene of few spheres, for its shadow rays.
    sphere_lanes: Option<SphereLanes>,
    planes: Vec<PlanePrim>,
    /// The BVH over `prims`, built on first use.
    accel: OnceLock<Option<Accel>>,
    triangles: usize,
    /// The box around the bounded shapes and the planes' points.
    bounds: Aabb64,
}

/// The BVH and the primitives in its leaf order, so that a traversal reads
/// them in sequence.
pub(super) struct Accel {
    pub bvh: Bvh,
    pub prims: Vec<Prim>,
    /// Per leaf primitive: its tie key, its index in the scene's order plus
    /// one (see [`Closest`]).
    pub keys: Vec<u32>,
}

impl Geometry {
    /// Collects the shapes of `objects`; the BVH over those with bounds is
    /// built when first needed. The primitives are the objects' in order: a
    /// sphere's one, each of a mesh's triangles in its order, none for a
    /// plane (`Raster::new` sets them up in the same order from the
    /// objects).
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
                    use rayon::prelude::*;
                    triangles += m.indices.len();
                    prims.par_extend(m.indices.par_iter().enumerate().map(|(t, &[a, b, c])| {
                        let [p0, p1, p2] = [a, b, c].map(|i| m.positions[i as usize]);
                        Prim::Triangle {
                            object,
                            triangle: t as u32,
                            p0,
                            p1,
                            p2,
                        }
                    }))
                }
            }
        }
        let whole = {
            use rayon::prelude::*;
            prims
                .par_iter()
                .map(Prim::bounds)
                .reduce(|| Aabb64::EMPTY, |a, b| a.union(&b))
        };
        let whole = planes
            .iter()
            .map(|p| Aabb64 {
                min: p.point,
                max: p.point,
            })
            .fold(whole, |a, b| a.union(&b));
        Self {
            sphere_lanes: SphereLanes::of(&prims),
            prims,
            planes,
            accel: OnceLock::new(),
            triangles,
            bounds: whole,
        }
    }

    /// Builds the BVH now for `usage`, if it is not built yet. Call it
    /// before queries from inside rayon tasks: a first query there would
    /// build it within the task, and the build itself runs on the pool.
    pub fn build_bvh(&self, usage: BvhUse) {
        self.accel_for(usage);
    }

    /// The BVH and the primitives in its leaf order; `None` for a scene
    /// without bounded shapes. Built, if it is not yet, for primary rays.
    pub(super) fn accel(&self) -> Option<&Accel> {
        self.accel_for(BvhUse::PrimaryRays)
    }

    fn accel_for(&self, usage: BvhUse) -> Option<&Accel> {
        self.accel
            .get_or_init(|| {
                use rayon::prelude::*;
                if self.prims.is_empty() {
                    return None;
                }
                let bounds: Vec<Aabb64> = self.prims.par_iter().map(Prim::bounds).collect();
                let bvh = Bvh::build(&bounds, usage);
                let order = bvh.primitive_order();
                let prims = order.par_iter().map(|&i| self.prims[i as usize]).collect();
                let keys = order.par_iter().map(|&i| i + 1).collect();
                Some(Accel { bvh, prims, keys })
            })
            .as_ref()
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

    /// The primitives with bounds, in the scene's order: the tie key of
    /// `prims()[i]` is `i + 1`.
    pub(super) fn prims(&self) -> &[Prim] {
        &self.prims
    }

    /// The closest hit of `ray` within (`t_min`, `t_max`).
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best = self.closest_plane(ray);
        let t_max = best.map_or(ray.t_max, |h| h.t);
        if let Some(accel) = self.accel() {
            // The BVH offers primitives in another order than brute force;
            // `Closest` breaks exact ties as brute force does.
            let mut closest = Closest::new(best);
            let traversed = accel.bvh.closest(ray, t_max, |prim, _| {
                closest.offer(accel.keys[prim], &accel.prims[prim], ray);
                closest.best.map(|h| h.t)
            });
            if traversed.is_err() {
                return self.closest_hit_brute_force(ray);
            }
            best = closest.best;
        }
        best
    }

    /// The closest plane `ray` meets within (`t_min`, `t_max`). Planes are
    /// unbounded, so they stay out of the BVH.
    pub(super) fn closest_plane(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for plane in &self.planes {
            let t_max = best.map_or(ray.t_max, |h| h.t);
            if let Some(t) = intersect_plane(ray, plane.point, plane.normal, t_max) {
                best = Some(Hit::on_plane(t, plane.object));
            }
        }
        best
    }

    /// The planes as rays from `origin` meet them: the numerator of
    /// [`intersect_plane`], `normal · (point − origin)`, is the same for all.
    pub(super) fn planes_seen_from(&self, origin: DVec3) -> Vec<PlaneSeen> {
        self.planes
            .iter()
            .map(|p| PlaneSeen {
                object: p.object,
                normal: p.normal,
                offset: p.normal.dot(p.point - origin),
            })
            .collect()
    }

    /// Whether anything lies on `ray` within (`t_min`, `t_max`): the shadow
    /// query.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self
            .planes
            .iter()
            .any(|p| intersect_plane(ray, p.point, p.normal, ray.t_max).is_some())
        {
            return true;
        }
        if let Some(spheres) = &self.sphere_lanes {
            return spheres.any_hit(ray);
        }
        let hits = |prim: &Prim| prim.intersect(ray, ray.t_max).is_some();
        self.accel().is_some_and(|accel| {
            accel
                .bvh
                .any(ray, |i| hits(&accel.prims[i]))
                .unwrap_or_else(|_| self.prims.iter().any(hits))
        })
    }

    /// [`Self::closest_hit`] by testing every primitive in the scene's
    /// order: the ground truth the other paths are checked against.
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

/// The closest hit among primitives offered in any order, equal to the one
/// [`Geometry::closest_hit_brute_force`] finds by testing them in the
/// scene's order: at equal distances the earlier primitive in that order
/// wins, and a plane (tested before every primitive) wins over all of them.
#[derive(Clone, Copy, Debug)]
pub(super) struct Closest {
    pub best: Option<Hit>,
    /// The tie key of the best primitive: its index in the scene's order
    /// plus one; 0 for a plane or none.
    key: u32,
}

impl Closest {
    pub fn new(plane: Option<Hit>) -> Self {
        Self {
            best: plane,
            key: 0,
        }
    }

    /// Tests `prim`, whose tie key is `key` (its index in the scene's order
    /// plus one), against `ray`, keeping its hit if it is the closer.
    #[inline]
    pub fn offer(&mut self, key: u32, prim: &Prim, ray: &Ray) {
        // Up to and including the best distance, for the tie rule.
        let t_max = match self.best {
            Some(best) if best.t < f64::INFINITY => best.t.next_up(),
            Some(best) => best.t,
            None => ray.t_max,
        };
        if let Some(hit) = prim.intersect(ray, t_max) {
            self.take(key, hit);
        }
    }

    /// Keeps `hit` (of the primitive whose tie key is `key`, within the
    /// ray's interval) if it is the closer.
    #[inline]
    pub fn take(&mut self, key: u32, hit: Hit) {
        let closer = match self.best {
            None => true,
            Some(best) => hit.t < best.t || (hit.t == best.t && self.key != 0 && key < self.key),
        };
        if closer {
            self.best = Some(hit);
            self.key = key;
        }
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

/// The watertight test of Woop, Benthin and Wald (*Watertight Ray/Triangle
/// Intersection*, JCGT 2013) for the triangle `(p0, p1, p2)`, both sides,
/// edges included: `(t, u, v)` with `t` in (`ray.t_min`, `t_max`).
///
/// The vertices are moved to the ray's origin and sheared so that the ray
/// runs along its dominant axis; the signs of the three 2-D edge functions
/// then say whether it passes inside. An edge's function is computed from
/// its two vertices alone, and negated exactly when the neighbouring
/// triangle walks it the other way, so a ray through a shared edge or
/// vertex cannot slip between the triangles (Möller–Trumbore, which
/// computes each triangle's barycentrics from its own edges, can).
#[inline]
pub fn intersect_triangle(
    ray: &Ray,
    [p0, p1, p2]: [DVec3; 3],
    t_max: f64,
) -> Option<(f64, f64, f64)> {
    let d = ray.direction;
    // The dominant axis z; x and y swapped when it points backwards, to
    // keep the winding.
    let kz = d.abs().max_position();
    let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if d[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let [a, b, c] = [p0, p1, p2].map(|p| p - ray.origin);
    let shear = |p: DVec3| (p[kx] - sx * p[kz], p[ky] - sy * p[kz]);
    let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
    // Twice the signed areas seen along the ray: the weights of p0, p1, p2.
    let w0 = cx * by - cy * bx;
    let w1 = ax * cy - ay * cx;
    let w2 = bx * ay - by * ax;
    if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) && (w0 > 0.0 || w1 > 0.0 || w2 > 0.0) {
        return None;
    }
    let det = w0 + w1 + w2;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t = (w0 * a[kz] + w1 * b[kz] + w2 * c[kz]) * sz / det;
    (t > ray.t_min && t < t_max).then_some((t, w1 / det, w2 / det))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// The spheres' lanes find the hits [`intersect_sphere`] finds, sphere
    /// by sphere: rays through, beside and touching random spheres, from
    /// inside and outside, with a reach that starts and ends inside them,
    /// and with NaN and infinite directions.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sphere_lanes_hit_what_the_scalar_test_hits() {
        let mut rng = Rng::new(7);
        let mut uniform = |lo, hi| rng.uniform(lo, hi);
        // Random spheres, and a last one apart whose roots are exact.
        let mut spheres: Vec<(DVec3, f64)> = (0..SPHERES_TESTED_ALL - 4)
            .map(|_| {
                let center = DVec3::new(uniform(-1.0, 1.0), uniform(-1.0, 1.0), uniform(-1.0, 1.0));
                (center, uniform(0.01, 0.4))
            })
            .collect();
        spheres.push((DVec3::splat(4.0), 0.25));
        let prims: Vec<Prim> = (spheres.iter().enumerate())
            .map(|(i, &(center, radius))| Prim::Sphere {
                object: i as u32,
                center,
                radius,
            })
            .collect();
        if !std::is_x86_feature_detected!("avx512f") {
            assert!(
                SphereLanes::of(&prims).is_none(),
                "no lanes without AVX-512"
            );
            return;
        }
        let lanes = SphereLanes::of(&prims).expect("few spheres take lanes");
        let (mut hit, mut rays) = (0, 0);
        for k in 0..6000 {
            let origin = DVec3::new(uniform(-1.5, 1.5), uniform(-1.5, 1.5), uniform(-1.5, 1.5));
            let (center, radius) = spheres[k % spheres.len()];
            let ray = match k % 6 {
                0 => Ray::new(origin, origin - DVec3::ZERO),
                1 => Ray::new(origin, center - origin),
                // Along x, touching the sphere's lowest point when the
                // arithmetic is exact, and just beside it when it is not.
                2 => Ray::new(center - DVec3::new(1.5, radius, 0.0), DVec3::X),
                3 => Ray {
                    t_min: uniform(0.0, 0.5),
                    t_max: uniform(0.2, 2.0),
                    ..Ray::new(origin, center - origin)
                },
                4 => Ray {
                    direction: DVec3::new(f64::NAN, 0.0, 1.0),
                    ..Ray::new(origin, DVec3::X)
                },
                _ => Ray {
                    direction: DVec3::new(f64::INFINITY, 0.0, 0.0),
                    ..Ray::new(origin, DVec3::X)
                },
            };
            let one_by_one: u64 = (spheres.iter().enumerate())
                .map(|(i, &(c, r))| {
                    u64::from(intersect_sphere(&ray, c, r, ray.t_max).is_some()) << i
                })
                .sum();
            // SAFETY: the CPU has AVX-512F: the lanes exist.
            let in_lanes = unsafe { lanes.hits_avx512(&ray, false) };
            assert_eq!(in_lanes, one_by_one, "ray {k} {ray:?}");
            assert_eq!(lanes.any_hit(&ray), one_by_one != 0, "ray {k} {ray:?}");
            hit += one_by_one.count_ones();
            rays += usize::from(one_by_one != 0);
        }
        assert!(hit > 3000 && rays < 5000, "{hit} hits on {rays} rays");

        // From (2.5, 4, 4) along x the last sphere's roots are exactly 1.25
        // and 1.75: `f = (−1.5, 0, 0)`, `disc = 1/16`, `c = 35/16`,
        // `q = 7/4`. The reach excludes both ends.
        let exact = Ray::new(DVec3::new(2.5, 4.0, 4.0), DVec3::X);
        for (t_min, t_max, expected) in [
            (1.25, 1.75, false),
            (1.25, 1.75f64.next_up(), true),
            (1.25f64.next_down(), 1.75, true),
            (1.0, 1.25, false),
            (1.75, 2.0, false),
        ] {
            let ray = Ray {
                t_min,
                t_max,
                ..exact
            };
            let scalar = intersect_sphere(&ray, DVec3::splat(4.0), 0.25, t_max).is_some();
            assert_eq!(
                scalar, expected,
                "the scalar test within ({t_min}, {t_max})"
            );
            assert_eq!(lanes.any_hit(&ray), expected, "within ({t_min}, {t_max})");
        }
    }
}

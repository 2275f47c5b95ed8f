//! Primary rays in packets: sixteen rays from the eye traverse the BVH
//! together, every box and every primitive tested for all of them at once
//! in f32 lanes (16 per instruction with AVX-512, 8 with AVX2, chosen at run
//! time), so that the cost of reading a node is shared by neighbouring
//! pixels, which nearly always visit the same nodes.
//!
//! The answer is exactly the one of [`Geometry::closest_hit_brute_force`]:
//! the f32 tests only decide which (ray, primitive) pairs need the f64 test
//! of [`super::geometry`], and they are conservative, never discarding a
//! pair that the f64 test would accept.
//!
//! - **Boxes** are the CWBVH's, decoded ([`super::bvh::WideNode`]), with
//!   their padding: the slab test runs in BVH space from the eye, which is
//!   at most [`MAX_EYE`] units from the scene's centre, so its f32 error
//!   (a few 1e-4 units) stays far below [`PAD`].
//! - **Triangles** are seen from the eye as a cone: a ray passes through
//!   the triangle when it lies on the inner side of the three planes
//!   through the eye and an edge. A ray that passes within [`NEAR`] of the
//!   triangle, somewhere at least `r` from the eye, makes an angle of at
//!   most `NEAR / (r − NEAR)` with each plane; that, the f32 error of the
//!   dot products and the f64 error of the planes' normals make the margin
//!   of the test. [`NEAR`] is [`PAD`], four times the f64 rounding that
//!   [`super::bvh::Bvh::resolves`] admits.
//! - **Spheres**: a ray passes within [`NEAR`] of the sphere when its
//!   distance to the centre, `|c × d|`, is at most `r + NEAR`, enlarged for
//!   the f32 error of the cross product.
//!
//! A triangle or sphere within a few [`NEAR`] of the eye, or seen edge-on
//! from it, is tested in f64 for every ray of the packet. Ties (two
//! primitives at exactly the same distance, as at a shared edge) are broken
//! as brute force breaks them (see `geometry::Closest`), so the image does not
//! depend on how the rays were grouped.
//!
//! Packets serve only rays from the eye over (0, ∞), and only when the eye
//! is near enough to the scene; other rays, the shadow rays and every ray of
//! a far-off eye take [`Geometry::closest_hit`].

// The lane loops index several arrays by lane on purpose: that is the
// structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::{PAD, WideNode};
use super::geometry::{Closest, Geometry, Hit, PlaneSeen, Prim, Ray};

/// Rays per packet.
pub const LANES: usize = 16;

/// Every lane of a packet.
const LANE_MASK: u32 = (1 << LANES) - 1;

/// How near, in BVH units, a ray must pass to a primitive for its f64 test
/// to run.
const NEAR: f64 = PAD as f64;

/// The farthest eye, in BVH units from the scene's centre (four times the
/// scene's extent), that packets serve.
const MAX_EYE: f64 = 4096.0;

/// The smallest direction component, in magnitude, of the slab test: it
/// keeps `1/d` finite (a zero component gives ±1e20, whose products with
/// the box planes stay finite and keep their signs).
const MIN_COMPONENT: f32 = 1e-20;

/// The packet tracer of one eye: the f32 filters of every primitive as
/// seen from it.
pub struct Packets {
    /// World space: the origin of every ray a packet takes.
    eye: DVec3,
    /// The eye in BVH space.
    origin: [f32; 3],
    /// BVH units per world unit.
    scale: f64,
    /// Per primitive, in leaf order.
    filters: Vec<Filter>,
    /// The planes, which are not in the BVH, as seen from the eye.
    planes: Vec<PlaneSeen>,
    trace: TraceFn,
}

type TraceFn = fn(&Packets, &Geometry, &[Ray], &mut [Option<Hit>], &mut Vec<Entry>);

/// The f32 test of a primitive against a packet's directions.
#[derive(Clone, Copy, Debug)]
enum Filter {
    /// A triangle: the unit normals of the planes through the eye and each
    /// edge, towards the triangle; a direction passes if `d·n ≥ −margin`
    /// for all three.
    Cone {
        normals: [[f32; 3]; 3],
        margin: f32,
        /// A lower bound on the BVH distance of any hit.
        near: f32,
    },
    /// A sphere: its centre from the eye; a direction passes if
    /// `|c × d|² ≤ reach²`.
    Ball {
        center: [f32; 3],
        reach2: f32,
        near: f32,
    },
    /// Every ray is tested in f64.
    Always,
}

impl Filter {
    /// The filter of `prim` seen from `origin`, all in BVH space.
    fn new(prim: &Prim, to_bvh: impl Fn(DVec3) -> DVec3, scale: f64, origin: DVec3) -> Self {
        match *prim {
            Prim::Triangle { p0, p1, p2, .. } => {
                let [a, b, c] = [p0, p1, p2].map(|p| to_bvh(p) - origin);
                let near = box_distance(a.min(b).min(c), a.max(b).max(c));
                if near.is_nan() || near <= 2.0 * NEAR {
                    return Self::Always;
                }
                // A ray within NEAR of the triangle, at least `near` from the
                // eye, makes at most NEAR / (near − NEAR) with each plane;
                // the f32 rounding of d, of n and of d·n adds under 2^-20.
                let angle = NEAR / (near - NEAR) + 1.0 / 1048576.0;
                let mut margin = angle;
                let mut normals = [[0.0; 3]; 3];
                for (k, (p, q, opposite)) in
                    [(b, c, a), (c, a, b), (a, b, c)].into_iter().enumerate()
                {
                    let n = p.cross(q);
                    let (length, side) = (n.length(), n.dot(opposite));
                    let size = p.length() * q.length();
                    // The f64 error of `n` is a few ulps of `|p|·|q|`; the
                    // side of the opposite vertex must be certain.
                    if !(length > 0.0 && side.abs() > size * opposite.length() / 1099511627776.0) {
                        return Self::Always;
                    }
                    let unit = n / length * side.signum();
                    normals[k] = unit.as_vec3().to_array();
                    // And the f64 error of the unit normal: a few ulps
                    // (2^-48) of |p|·|q| / |p × q|.
                    margin = margin.max(angle + size / length / 281474976710656.0);
                }
                if margin.is_nan() || margin >= 1.0 {
                    return Self::Always;
                }
                Self::Cone {
                    normals,
                    margin: (margin as f32).next_up(),
                    near: ((near - 2.0 * NEAR) as f32).next_down(),
                }
            }
            Prim::Sphere { center, radius, .. } => {
                let c = to_bvh(center) - origin;
                let r = radius * scale;
                let distance = c.length();
                let gap = distance - r;
                if !gap.is_finite() || gap <= 2.0 * NEAR {
                    return Self::Always;
                }
                // |c × d| in f32 is off by a few ulps of |c|, and by |c|
                // times the rounding of d.
                let reach = (r + NEAR + c.abs().element_sum() / 524288.0) * (1.0 + 1.0 / 1048576.0);
                Self::Ball {
                    center: c.as_vec3().to_array(),
                    reach2: ((reach * reach) as f32).next_up(),
                    near: ((distance - r - 2.0 * NEAR) as f32).next_down(),
                }
            }
        }
    }
}

/// The distance from the origin to the box `[lo, hi]`.
fn box_distance(lo: DVec3, hi: DVec3) -> f64 {
    DVec3::ZERO.max(lo).max(-hi).length()
}

/// A node or a leaf to visit, with the lanes whose rays enter its box and
/// the nearest distance at which one of them does.
#[derive(Clone, Copy, Debug)]
pub struct Entry {
    index: u32,
    /// Primitives of a leaf; 0 for a node.
    count: u32,
    mask: u32,
    near: f32,
}

/// The f32 state of a packet's rays, lane by lane, in BVH space.
struct Lanes {
    d: [[f32; LANES]; 3],
    inv: [[f32; LANES]; 3],
    /// A distance beyond every hit still possible: the best hit so far,
    /// enlarged for rounding.
    t_max: [f32; LANES],
}

impl Packets {
    /// The packet tracer for rays from `eye` through `geometry`; `None` when
    /// the scene has no BVH or the eye is too far from it.
    pub fn new(geometry: &Geometry, eye: DVec3) -> Option<Self> {
        let accel = geometry.accel()?;
        let bvh = &accel.bvh;
        if bvh.wide_nodes().is_empty() {
            // Built for shadow rays only.
            return None;
        }
        let (center, scale) = (bvh.center(), bvh.scale());
        let origin = (eye - center) * scale;
        let reach = origin.abs().max_element();
        if !bvh.resolves(eye) || reach.is_nan() || reach > MAX_EYE {
            return None;
        }
        let to_bvh = |p: DVec3| (p - center) * scale;
        let filters = accel
            .prims
            .par_iter()
            .map(|prim| Filter::new(prim, to_bvh, scale, origin))
            .collect();
        Some(Self {
            eye,
            origin: origin.as_vec3().to_array(),
            scale,
            filters,
            planes: geometry.planes_seen_from(eye),
            trace: dispatch(),
        })
    }

    /// The closest hit of each of `rays` into `hits`, sixteen rays at a
    /// time: exactly [`Geometry::closest_hit`] of each. Rays not from the
    /// eye, or limited in `t`, are traced alone.
    pub fn trace(&self, geometry: &Geometry, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "a hit per ray");
        let mut stack = Vec::with_capacity(64);
        for (rays, hits) in rays.chunks(LANES).zip(hits.chunks_mut(LANES)) {
            (self.trace)(self, geometry, rays, hits, &mut stack);
        }
    }

    /// A world distance from the eye as a BVH one, enlarged by a relative
    /// 2^-20 and by [`PAD`] to cover the rounding of the f32 rays.
    #[inline(always)]
    fn to_bvh_t(&self, t: f64) -> f32 {
        ((t * self.scale) * (1.0 + 1.0 / 1048576.0)) as f32 + PAD
    }

    /// One packet of up to [`LANES`] rays.
    #[inline(always)]
    fn trace_packet<M: LaneMask>(
        &self,
        geometry: &Geometry,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        stack: &mut Vec<Entry>,
    ) {
        let accel = geometry.accel().expect("packets need a BVH");
        let nodes = accel.bvh.wide_nodes();
        let (prims, keys) = (&accel.prims, &accel.keys);
        let mut best = [Closest::new(None); LANES];
        let mut lanes = Lanes {
            d: [[0.0; LANES]; 3],
            inv: [[1.0; LANES]; 3],
            t_max: [f32::NEG_INFINITY; LANES],
        };
        // The rays from the eye over (0, ∞) take the packet, the others are
        // traced alone.
        let mut active = 0u32;
        let mut direction = [[0.0f64; LANES]; 3];
        for (l, ray) in rays.iter().enumerate() {
            if ray.origin != self.eye || ray.t_min != 0.0 || ray.t_max != f64::INFINITY {
                hits[l] = geometry.closest_hit(ray);
                continue;
            }
            active |= 1 << l;
            for axis in 0..3 {
                direction[axis][l] = ray.direction[axis];
            }
        }
        let Some(first) = bits(active).next() else {
            return;
        };
        // Lanes without a ray copy the first ray's direction (their t_max
        // keeps them out of every box), so that the octant test below sees
        // only the rays traced.
        for l in bits(!active & LANE_MASK) {
            for axis in 0..3 {
                direction[axis][l] = direction[axis][first];
            }
        }
        // The closest plane of every lane at once, by the operations of
        // `Geometry::closest_plane` in the same order, so the same hits.
        let mut plane_t = [f64::INFINITY; LANES];
        let mut plane_object = [0u32; LANES];
        for plane in &self.planes {
            let n = plane.normal;
            for l in 0..LANES {
                let denom = n.x * direction[0][l] + n.y * direction[1][l] + n.z * direction[2][l];
                let t = plane.offset / denom;
                let hit = denom != 0.0 && t > 0.0 && t < plane_t[l];
                plane_t[l] = if hit { t } else { plane_t[l] };
                plane_object[l] = if hit { plane.object } else { plane_object[l] };
            }
        }
        // The f32 lanes: directions, their reciprocals (one vector division
        // per axis) and the distance to beat, the plane's or none.
        for axis in 0..3 {
            for l in 0..LANES {
                let d = direction[axis][l] as f32;
                lanes.d[axis][l] = d;
                let safe = if d.abs() < MIN_COMPONENT {
                    MIN_COMPONENT.copysign(d)
                } else {
                    d
                };
                lanes.inv[axis][l] = 1.0 / safe;
            }
        }
        for l in 0..LANES {
            lanes.t_max[l] = if active & (1 << l) != 0 {
                self.to_bvh_t(plane_t[l])
            } else {
                f32::NEG_INFINITY
            };
        }
        for l in bits(active) {
            let plane = plane_t[l] < f64::INFINITY;
            best[l] = Closest::new(plane.then(|| Hit::on_plane(plane_t[l], plane_object[l])));
        }
        // When every ray goes the same way along each axis, which of a
        // box's planes is the near one is known for the whole packet.
        let octant = [0, 1, 2].map(|axis| {
            let positive = lanes.inv[axis].iter().all(|&i| i > 0.0);
            let negative = lanes.inv[axis].iter().all(|&i| i < 0.0);
            (positive || negative).then_some(negative)
        });
        let octant = match octant {
            [Some(x), Some(y), Some(z)] => Some([x, y, z]),
            _ => None,
        };
        stack.clear();
        stack.push(Entry {
            index: 0,
            count: 0,
            mask: active,
            near: 0.0,
        });
        while let Some(entry) = stack.pop() {
            let live = entry.mask & reaching::<M>(&lanes.t_max, entry.near);
            if live == 0 {
                continue;
            }
            if entry.count > 0 {
                for i in entry.index..entry.index + entry.count {
                    let i = i as usize;
                    let candidates = live & self.candidates::<M>(&self.filters[i], &lanes);
                    for l in bits(candidates) {
                        let before = best[l].best;
                        best[l].offer(keys[i], &prims[i], &rays[l]);
                        if best[l].best != before {
                            let t = best[l].best.expect("a hit was kept").t;
                            lanes.t_max[l] = self.to_bvh_t(t);
                        }
                    }
                }
                continue;
            }
            let node = &nodes[entry.index as usize];
            let mut found = [(0usize, 0u32, 0f32); 8];
            let mut n = 0;
            for c in bits(u32::from(node.occupied)) {
                let (mask, entries) = match octant {
                    Some(flip) => self.enter_octant::<M>(node, c, &lanes, flip),
                    None => self.enter::<M>(node, c, &lanes),
                };
                let mask = mask & live;
                // Most children are missed by the whole packet: the nearest
                // entry, a reduction across the lanes, only for the others.
                if mask != 0 {
                    found[n] = (c, mask, nearest(&entries));
                    n += 1;
                }
            }
            // Farthest first on the stack: the nearest is visited next.
            let found = &mut found[..n];
            found.sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
            for &(c, mask, near) in found.iter() {
                stack.push(Entry {
                    index: node.index[c],
                    count: u32::from(node.count[c]),
                    mask,
                    near,
                });
            }
        }
        for l in bits(active) {
            hits[l] = best[l].best;
        }
    }

    /// The slab test of child `c` of `node` for every lane: the lanes that
    /// enter it before their `t_max`, and the entry distance of each of
    /// them (see [`nearest`]).
    #[inline(always)]
    fn enter<M: LaneMask>(&self, node: &WideNode, c: usize, lanes: &Lanes) -> (u32, [u32; LANES]) {
        let o = self.origin;
        let lo = [0, 1, 2].map(|axis| node.min[axis][c] - o[axis]);
        let hi = [0, 1, 2].map(|axis| node.max[axis][c] - o[axis]);
        // Lane by lane into arrays: loops the vectoriser takes.
        let mut enters = [0; LANES];
        let mut key = [u32::MAX; LANES];
        for l in 0..LANES {
            let x0 = lo[0] * lanes.inv[0][l];
            let x1 = hi[0] * lanes.inv[0][l];
            let y0 = lo[1] * lanes.inv[1][l];
            let y1 = hi[1] * lanes.inv[1][l];
            let z0 = lo[2] * lanes.inv[2][l];
            let z1 = hi[2] * lanes.inv[2][l];
            let near = max(max(min(x0, x1), min(y0, y1)), max(min(z0, z1), 0.0));
            let far = min(
                min(max(x0, x1), max(y0, y1)),
                min(max(z0, z1), lanes.t_max[l]),
            );
            (enters[l], key[l]) = entered(near, far);
        }
        (M::mask(&enters), key)
    }

    /// [`Self::enter`] for a packet whose rays all go the same way along
    /// each axis (`flip[axis]`: towards negative values): the same
    /// answer, the near and far planes chosen once for all lanes.
    #[inline(always)]
    fn enter_octant<M: LaneMask>(
        &self,
        node: &WideNode,
        c: usize,
        lanes: &Lanes,
        flip: [bool; 3],
    ) -> (u32, [u32; LANES]) {
        let o = self.origin;
        let lo = [0, 1, 2].map(|axis| node.min[axis][c] - o[axis]);
        let hi = [0, 1, 2].map(|axis| node.max[axis][c] - o[axis]);
        let near_plane = [0, 1, 2].map(|axis| if flip[axis] { hi[axis] } else { lo[axis] });
        let far_plane = [0, 1, 2].map(|axis| if flip[axis] { lo[axis] } else { hi[axis] });
        let mut enters = [0; LANES];
        let mut key = [u32::MAX; LANES];
        for l in 0..LANES {
            let x0 = near_plane[0] * lanes.inv[0][l];
            let x1 = far_plane[0] * lanes.inv[0][l];
            let y0 = near_plane[1] * lanes.inv[1][l];
            let y1 = far_plane[1] * lanes.inv[1][l];
            let z0 = near_plane[2] * lanes.inv[2][l];
            let z1 = far_plane[2] * lanes.inv[2][l];
            let near = max(max(x0, y0), max(z0, 0.0));
            let far = min(min(x1, y1), min(z1, lanes.t_max[l]));
            (enters[l], key[l]) = entered(near, far);
        }
        (M::mask(&enters), key)
    }

    /// The lanes whose rays may hit the primitive of `filter`.
    #[inline(always)]
    fn candidates<M: LaneMask>(&self, filter: &Filter, lanes: &Lanes) -> u32 {
        let mut pass = [0; LANES];
        match *filter {
            Filter::Cone {
                normals: [a, b, c],
                margin,
                near,
            } => {
                for l in 0..LANES {
                    let d = [lanes.d[0][l], lanes.d[1][l], lanes.d[2][l]];
                    let da = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
                    let db = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
                    let dc = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
                    let inside = min(min(da, db), dc) >= -margin;
                    let reaches = lanes.t_max[l] >= near;
                    pass[l] = flag(inside & reaches);
                }
            }
            Filter::Ball {
                center: c,
                reach2,
                near,
            } => {
                for l in 0..LANES {
                    let d = [lanes.d[0][l], lanes.d[1][l], lanes.d[2][l]];
                    let wx = c[1] * d[2] - c[2] * d[1];
                    let wy = c[2] * d[0] - c[0] * d[2];
                    let wz = c[0] * d[1] - c[1] * d[0];
                    let inside = wx * wx + wy * wy + wz * wz <= reach2;
                    let reaches = lanes.t_max[l] >= near;
                    pass[l] = flag(inside & reaches);
                }
            }
            Filter::Always => return u32::MAX,
        }
        M::mask(&pass)
    }
}

/// A lane's slab test from its `near` and `far` distances: its [`flag`]
/// (whether it enters the box) and its entry key for [`nearest`].
#[inline(always)]
fn entered(near: f32, far: f32) -> (i32, u32) {
    let enters = near <= far;
    (flag(enters), if enters { near.to_bits() } else { u32::MAX })
}

/// The nearest of the entry distances `keys` (their bits: distances are at
/// least 0, so their bits order as they do; `u32::MAX` for a lane that
/// misses).
#[inline(always)]
fn nearest(keys: &[u32; LANES]) -> f32 {
    f32::from_bits(keys.iter().fold(u32::MAX, |a, &b| a.min(b)))
}

/// The lanes whose `t_max` reaches `near`.
#[inline(always)]
fn reaching<M: LaneMask>(t_max: &[f32; LANES], near: f32) -> u32 {
    M::mask(&t_max.map(|t| flag(t >= near)))
}

/// A lane's flag: all bits set for true, none for false, as a vector
/// comparison leaves it.
#[inline(always)]
fn flag(b: bool) -> i32 {
    -i32::from(b)
}

/// The lane mask of per-lane [`flag`]s, per instruction set. The compiler
/// joins these to the comparisons that made the flags, so that a mask is
/// the comparison's own (one `kmovw` with AVX-512); an OR of shifted bits
/// would be reduced across the vector in a dozen steps.
trait LaneMask {
    fn mask(flags: &[i32; LANES]) -> u32;
}

/// Any CPU: bit by bit.
struct Portable;

impl LaneMask for Portable {
    #[inline(always)]
    fn mask(flags: &[i32; LANES]) -> u32 {
        (0..LANES).fold(0, |m, l| m | (u32::from(flags[l] != 0) << l))
    }
}

/// AVX-512DQ's `vpmovd2m`. Only for [`trace_avx512`], which runs where the
/// CPU has it.
#[cfg(target_arch = "x86_64")]
struct Avx512;

#[cfg(target_arch = "x86_64")]
impl LaneMask for Avx512 {
    #[inline(always)]
    fn mask(flags: &[i32; LANES]) -> u32 {
        use std::arch::x86_64::{__m512i, _mm512_loadu_si512, _mm512_movepi32_mask};
        // SAFETY: `Avx512` is named only by `trace_avx512`, which `dispatch`
        // calls where the CPU has AVX-512F and DQ (and by a test that asks
        // the CPU first); `flags` is 64 bytes, and the load has no
        // alignment demand.
        unsafe {
            u32::from(_mm512_movepi32_mask(_mm512_loadu_si512(
                flags.as_ptr().cast::<__m512i>(),
            )))
        }
    }
}

/// AVX's `vmovmskps`, on each half. Only for [`trace_avx2`], which runs
/// where the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
struct Avx2;

#[cfg(target_arch = "x86_64")]
impl LaneMask for Avx2 {
    #[inline(always)]
    fn mask(flags: &[i32; LANES]) -> u32 {
        use std::arch::x86_64::{
            __m256i, _mm256_castsi256_ps, _mm256_loadu_si256, _mm256_movemask_ps,
        };
        // SAFETY: `Avx2` is named only by `trace_avx2`, which `dispatch`
        // calls where the CPU has AVX2 (and by a test that asks the CPU
        // first); each half of `flags` is 32 bytes, and the loads have no
        // alignment demand.
        let half = |h: &[i32]| unsafe {
            _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_loadu_si256(
                h.as_ptr().cast::<__m256i>(),
            ))) as u32
        };
        half(&flags[..8]) | half(&flags[8..]) << 8
    }
}

/// The indices of the set bits of `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// `min` and `max` as one instruction each (`f32::min` also orders NaNs,
/// which none of these values is).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The widest build of the packet loop the CPU runs.
fn dispatch() -> TraceFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
        {
            return |p, g, r, h, s| {
                // SAFETY: the CPU has AVX-512F and DQ, AVX2 and FMA, checked
                // just above.
                unsafe { trace_avx512(p, g, r, h, s) }
            };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            return |p, g, r, h, s| {
                // SAFETY: the CPU has AVX2 and FMA, checked just above.
                unsafe { trace_avx2(p, g, r, h, s) }
            };
        }
    }
    |p, g, r, h, s| p.trace_packet::<Portable>(g, r, h, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
fn trace_avx512(
    packets: &Packets,
    geometry: &Geometry,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    stack: &mut Vec<Entry>,
) {
    packets.trace_packet::<Avx512>(geometry, rays, hits, stack)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn trace_avx2(
    packets: &Packets,
    geometry: &Geometry,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    stack: &mut Vec<Entry>,
) {
    packets.trace_packet::<Avx2>(geometry, rays, hits, stack)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each instruction set's mask of the same flags is bit `l` for lane
    /// `l`, whichever lanes are set.
    #[test]
    fn lane_masks_are_the_same_on_every_instruction_set() {
        for pattern in [0u32, 1, 0x8000, 0xffff, 0xa5c3, 0x0ff0, 0x1234, 0x7ffe] {
            let flags: [i32; LANES] = std::array::from_fn(|l| flag(pattern >> l & 1 == 1));
            assert_eq!(Portable::mask(&flags), pattern);
            #[cfg(target_arch = "x86_64")]
            {
                if std::is_x86_feature_detected!("avx2") {
                    assert_eq!(Avx2::mask(&flags), pattern, "AVX2, {pattern:#x}");
                }
                if std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx512dq")
                {
                    assert_eq!(Avx512::mask(&flags), pattern, "AVX-512, {pattern:#x}");
                }
            }
        }
    }
}

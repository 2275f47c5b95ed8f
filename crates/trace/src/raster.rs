//! Primary visibility by rasterization: what GL's rasterizer computes,
//! without an acceleration structure, and the tracer's exact hits.
//!
//! A ray from the eye through the image point `(fx, fy)` has the direction
//! `r(fx, fy) = w + sx·u + sy·v` (see [`crate::camera`]), affine in `fx` and
//! `fy`. It meets the triangle `(a, b, c)` (vertices relative to the eye) in
//! front of the eye exactly when `r = α·a + β·b + γ·c` with `α, β, γ ≥ 0`,
//! and with `D = a·(b × c)`, `α·D = r·(b × c)`, `β·D = r·(c × a)`,
//! `γ·D = r·(a × b)`. So the three edge functions
//! `F_i(fx, fy) = sign(D)·(r · e_i)` are affine in the pixel coordinates,
//! the triangle's samples are those where all three are at least 0, and
//! `(F_0 + F_1 + F_2)/|D| = α + β + γ = 1/z`, the inverse of the hit's depth
//! along the view direction: homogeneous rasterization (Olano and Greer,
//! *Triangle Scan Conversion using 2D Homogeneous Coordinates*, 1997), which
//! needs no clipping at the eye's plane.
//!
//! The rasterizer only chooses candidates; the hit of a sample is always
//! the f64 test of [`super::geometry`] on the sample's own ray, so pixels are
//! exactly those of the tracer. Per 16×16-pixel bin (the renderer's tile),
//! each triangle whose screen box meets the bin is evaluated in f32 lanes at
//! the bin's samples, with margins that cover the f32 error of the
//! evaluation and the f64 error of the exact test
//! ([`EDGE_F32`], [`EDGE_F64`]):
//!
//! - a triangle *may* hold the sample when every `F_i ≥ −m_i`, and *surely*
//!   does when every `F_i ≥ m_i` (the exact test then reports a hit);
//! - its `1/z` lies in an interval made from the same margins ([`DEPTH`]).
//!
//! Per sample the rasterizer keeps the sure candidate with the nearest
//! lower bound and the farthest reach of every other candidate. When no
//! other candidate can reach as near as the best, the best is the closest
//! triangle and the exact test runs on it alone; otherwise (a sample within
//! a margin of an edge, surfaces within [`DEPTH`] of each other) every
//! triangle of the bin is tested exactly. The answer does not depend on the
//! order in which the triangles arrive.
//!
//! Triangles the margins cannot vouch for are candidates only, never sure:
//! those seen almost edge-on ([`EDGE_ON`], whose orientation is then
//! uncertain, so both are tested) and those reaching near the eye's plane
//! ([`SAFE_DEPTH`], where the f64 distance loses its relative precision).
//! Spheres and planes are few: every sample tests the planes and the
//! spheres whose screen box meets its bin exactly.

// The lane loops index several arrays by lane on purpose: that is the
// structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

use std::cmp::Ordering;
use std::sync::atomic::{self, AtomicBool, AtomicU32, AtomicUsize};

use glam::DVec3;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
mod setup_avx512;

use crate::camera::PinholeCamera;
use crate::geometry::{Closest, Geometry, Hit, Prim, Ray};
use crate::scene::{Camera, Object, Region, Shape};

/// The side of a bin, in pixels: the renderer's tile.
pub const BIN: u32 = crate::renderer::TILE;

/// Samples evaluated together.
pub const LANES: usize = 16;

/// The mask of every one of [`LANES`].
pub const LANE_MASK: u32 = (1 << LANES) - 1;

/// The f32 part of an edge's margin, relative to the largest value its
/// terms take over the samples it is evaluated at: the coefficients and the
/// sample's coordinates are each rounded once to f32 and the evaluation
/// rounds at most four times, 6·2^-24 in all; 2^-19 is five times that.
pub const EDGE_F32: f64 = 1.0 / 524_288.0;

/// The f64 part of an edge's margin, relative to `|p|·|q|·R` for the edge
/// from `p` to `q` (`R` the longest unnormalised direction of the image):
/// the exact test's edge value, from the f64 direction and vertices, is off
/// by some 100 ulps of that (2^-46); 2^-40 is 64 times that.
pub const EDGE_F64: f64 = 1.0 / 1_099_511_627_776.0;

/// The relative margin of the depth interval: the f32 product of the summed
/// edge functions and `1/|D|` loses up to 3·2^-24, and the f64 distances of
/// two hits on triangles the margins vouch for differ from their exact
/// order by less than 2^-30 (see [`EDGE_ON`]).
pub const DEPTH: f64 = 1.0 / 1_048_576.0;

/// A triangle is seen almost edge-on when the eye lies within 2^-16 of its
/// size from its plane. The f64 distance of a hit then depends on the
/// rounding of its ray's direction up to 2^18 times more than elsewhere:
/// beyond [`DEPTH`]. Such a triangle is a candidate only, in either
/// orientation.
pub const EDGE_ON: f64 = 1.0 / 65_536.0;

/// A triangle reaches near the eye's plane when a vertex's depth is at most
/// 2^-12 of its distance: the f64 distance of a hit, a sum of terms as
/// large as the vertices' distances, then keeps less than 2^-30 of its
/// relative precision. Such a triangle is a candidate only.
pub const SAFE_DEPTH: f64 = 1.0 / 4096.0;

/// The most triangles whose screen box is the whole image (their plane
/// passes through the eye) that a frame rasterizes; with more, it is
/// traced instead.
pub const MAX_UNBOUNDED: usize = 64;

/// No triangle.
const NONE: u32 = u32::MAX;

/// A triangle ready for the bins: its three edge functions in f32,
/// relative to the corner of its screen box, scaled so that their largest
/// term is about 1.
#[derive(Clone, Copy, Debug)]
struct Setup {
    /// `F_i = a[i]·x + b[i]·y + c[i]`, `(x, y)` from `(x0, y0)`.
    a: [f32; 3],
    b: [f32; 3],
    c: [f32; 3],
    /// The margin of each edge.
    m: [f32; 3],
    /// The margin of `F_0 + F_1 + F_2`.
    sum_margin: f32,
    /// `z_ref / |D|` in the scale of the edge functions: `1/z` in units of
    /// `1/z_ref`.
    inv_d: f32,
    /// Of a vouched triangle, at least the `1/z` (in units of `1/z_ref`)
    /// of every point of it, its nearest vertex's; infinite for the others.
    near: f32,
    /// Counter-clockwise as the eye sees it: GL's front face, which a
    /// closed mesh's outward winding turns to the eye where it is nearest.
    ccw: bool,
    /// The screen box, pixels `[x0, x1) × [y0, y1)` of the full image.
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    kind: Kind,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Oriented, its depth interval valid, may be sure.
    Vouched,
    /// Oriented, a candidate only.
    Candidate,
    /// Either orientation, a candidate only.
    EdgeOn,
    /// Not seen (behind the eye, outside the region, or not a triangle):
    /// in no bin.
    Hidden,
}

/// A screen box, pixels `[x0, x1) × [y0, y1)` of the full image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ScreenBox {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// Where a setup goes in the bins: its screen box and its class there,
/// counter-clockwise first (see [`Raster::new`]), or in none.
#[derive(Clone, Copy, Debug)]
struct Placed {
    screen: ScreenBox,
    class: u32,
}

impl Placed {
    /// The class of a setup in no bin.
    const HIDDEN: u32 = u32::MAX;

    fn of(setup: &Setup) -> Self {
        Self {
            screen: setup.screen_box(),
            class: if setup.kind == Kind::Hidden {
                Self::HIDDEN
            } else {
                u32::from(!setup.ccw)
            },
        }
    }
}

/// The box of the whole region, and of the points on its right and bottom
/// borders (the corners of adaptive sampling), which lie in the pixels just
/// past it.
fn whole(region: &Region) -> ScreenBox {
    ScreenBox {
        x0: region.x,
        y0: region.y,
        x1: region.x + region.width + 1,
        y1: region.y + region.height + 1,
    }
}

/// The items of each bin, as offsets into one array.
struct Bins {
    /// Where each class of each bin starts in `items`, bin by bin.
    start: Vec<u32>,
    items: Vec<u32>,
    /// The classes of a bin, listed one after the other.
    classes: usize,
}

impl Bins {
    fn of(&self, bin: usize) -> &[u32] {
        let (first, last) = (bin * self.classes, (bin + 1) * self.classes);
        &self.items[self.start[first] as usize..self.start[last] as usize]
    }
}

/// The frame's triangles set up and binned, its spheres binned.
pub struct Raster {
    view: View,
    /// One per primitive of [`Geometry::prims`], by its index: a setup's
    /// index is its triangle's.
    setups: Vec<Setup>,
    exact_fn: ExactFn,
    triangles: Bins,
    spheres: Bins,
    region: Region,
    bins_x: u32,
    raster_fn: RasterFn,
}

/// Why a frame is traced instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unfit;

/// The camera as the rasterizer needs it: the direction of `(fx, fy)` is
/// `w + sx·u + sy·v` with `sx = 2·fx/width − 1`, `sy = 1 − 2·fy/height`.
#[derive(Clone, Copy, Debug)]
struct View {
    eye: DVec3,
    w: DVec3,
    u: DVec3,
    v: DVec3,
    width: f64,
    height: f64,
    /// The longest direction `|r|` over the image.
    reach: f64,
    /// `u·(width/2)/|u|²` and `v·(height/2)/|v|²`: a point's offsets in
    /// pixels from the image's centre, times its depth.
    to_x: DVec3,
    to_y: DVec3,
    /// `2/width` and `2/height`: the steps of `sx` and `sy` per pixel.
    step_x: f64,
    step_y: f64,
}

/// A point as the setup reads it: computed once per mesh vertex, not once
/// per triangle that shares it (about six in a closed mesh), and the same
/// f64 operations either way, so that every setup is the same.
#[derive(Clone, Copy, Debug)]
struct Seen {
    /// Relative to the eye.
    offset: DVec3,
    /// `|offset|`.
    length: f64,
    /// `offset·w`: its depth along the view direction.
    depth: f64,
    /// Its pixel coordinates ([`View::project`] at its depth), meaningful
    /// only at a positive depth.
    x: f64,
    y: f64,
}

impl View {
    fn new(pinhole: &PinholeCamera, camera: &Camera) -> Self {
        let (w, u, v) = pinhole.frame();
        Self {
            eye: pinhole.eye(),
            w,
            u,
            v,
            width: f64::from(camera.width),
            height: f64::from(camera.height),
            reach: (1.0 + u.length_squared() + v.length_squared()).sqrt() * (1.0 + 1e-12),
            to_x: u * (0.5 * f64::from(camera.width) / u.length_squared()),
            to_y: v * (0.5 * f64::from(camera.height) / v.length_squared()),
            step_x: 2.0 / f64::from(camera.width),
            step_y: 2.0 / f64::from(camera.height),
        }
    }

    /// The unit of `1/z` for a scene in the box from `min` to `max`: the
    /// distance from the eye to the box.
    fn z_ref(&self, min: DVec3, max: DVec3) -> f64 {
        if min.x <= max.x {
            let nearest = self.eye.clamp(min, max);
            let farthest = (self.eye - min).abs().max((self.eye - max).abs()).length();
            (nearest - self.eye).length().max(farthest * 1e-6)
        } else {
            1.0
        }
    }

    /// The point at `offset` from the eye as the setup reads it.
    #[inline(always)]
    fn see(&self, offset: DVec3) -> Seen {
        let depth = offset.dot(self.w);
        let (x, y) = self.project(offset, depth);
        Seen {
            offset,
            length: offset.length(),
            depth,
            x,
            y,
        }
    }

    /// `p` (relative to the eye, at depth `z > 0`) in pixel coordinates.
    /// (The box it serves has a margin of a pixel: a few ulps of rounding
    /// more or less do not matter.)
    #[inline(always)]
    fn project(&self, p: DVec3, z: f64) -> (f64, f64) {
        let inv_z = 1.0 / z;
        (
            0.5 * self.width + p.dot(self.to_x) * inv_z,
            0.5 * self.height - p.dot(self.to_y) * inv_z,
        )
    }

    /// The screen box, within `region`, of the convex hull of `points`
    /// cut at depth `z_cut > 0`; `edges` are its edges, so that the cut's
    /// new corners are found. `None` when none of it is at depth `z_cut` or
    /// more, or its box misses the region. (Inlined: a triangle's three
    /// points and edges, known where it is called, unroll its loops.)
    #[inline(always)]
    fn screen_box(
        &self,
        points: &[Seen],
        edges: &[(usize, usize)],
        z_cut: f64,
        region: &Region,
    ) -> Option<ScreenBox> {
        let (mut x_min, mut x_max) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut y_min, mut y_max) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut add = |(x, y): (f64, f64)| {
            x_min = x_min.min(x);
            x_max = x_max.max(x);
            y_min = y_min.min(y);
            y_max = y_max.max(y);
        };
        for p in points {
            if p.depth >= z_cut {
                add((p.x, p.y));
            }
        }
        for &(i, j) in edges {
            let (p, q) = (&points[i], &points[j]);
            if (p.depth < z_cut) != (q.depth < z_cut) {
                let s = (z_cut - p.depth) / (q.depth - p.depth);
                add(self.project(p.offset + s * (q.offset - p.offset), z_cut));
            }
        }
        if x_min.is_nan() || x_max.is_nan() || y_min.is_nan() || y_max.is_nan() || x_min > x_max {
            return None;
        }
        // A pixel's samples lie in [x, x + 1): a margin of one pixel on each
        // side covers the rounding of the projection many times over. The
        // floor of a value clamped between whole numbers is the clamp of
        // its floor, and of a non-negative value its truncation.
        let clamp = |v: f64, lo: u32, hi: u32| v.max(f64::from(lo)).min(f64::from(hi)) as u32;
        let whole = whole(region);
        let (rx1, ry1) = (whole.x1, whole.y1);
        let b = ScreenBox {
            x0: clamp(x_min - 1.0, region.x, rx1),
            x1: clamp(x_max + 2.0, region.x, rx1),
            y0: clamp(y_min - 1.0, region.y, ry1),
            y1: clamp(y_max + 2.0, region.y, ry1),
        };
        (b.x0 < b.x1 && b.y0 < b.y1).then_some(b)
    }
}

impl Raster {
    /// Sets up and bins the triangles and spheres of `geometry`, the
    /// geometry of `objects`, for the region of `camera`'s image; `Unfit`
    /// when the scene's numbers leave f32 or too many triangles' planes
    /// pass through the eye.
    pub fn new(
        geometry: &Geometry,
        objects: &[Object],
        pinhole: &PinholeCamera,
        camera: &Camera,
        region: &Region,
    ) -> Result<Self, Unfit> {
        let view = View::new(pinhole, camera);
        let bounds = geometry.bounds();
        let z_ref = view.z_ref(bounds.min, bounds.max);
        if !(z_ref.is_finite() && z_ref > 0.0) {
            return Err(Unfit);
        }
        let prims = geometry.prims();
        // One setup per primitive, in the primitives' order (objects in
        // order, a mesh's triangles in order, a sphere's setup hidden):
        // the setup of a triangle seen, else a hidden one, never binned; a
        // setup's index is its primitive's. A mesh's vertices are seen
        // once each, then its triangles set up from them.
        let unfit = AtomicBool::new(false);
        // Edge-on triangles whose box is the whole region (rare: their
        // count is shared, the others never touch it).
        let unbounded = AtomicUsize::new(0);
        let all = whole(region);
        let set_up_lanes = dispatch_setup();
        let set_up = |p: [Seen; 3]| match Setup::new(&view, p, z_ref, region) {
            Ok(Some(setup)) => {
                if setup.kind == Kind::EdgeOn && setup.screen_box() == all {
                    unbounded.fetch_add(1, atomic::Ordering::Relaxed);
                }
                setup
            }
            Ok(None) => Setup::HIDDEN,
            Err(Unfit) => {
                unfit.store(true, atomic::Ordering::Relaxed);
                Setup::HIDDEN
            }
        };
        let mut setups: Vec<Setup> = Vec::with_capacity(prims.len());
        // What the binning reads of each setup, a quarter of its size,
        // written beside it while it is in cache.
        let mut placed: Vec<Placed> = Vec::with_capacity(prims.len());
        for object in objects {
            match &object.shape {
                Shape::Mesh(mesh) => {
                    let seen: Vec<Seen> = mesh
                        .positions
                        .par_iter()
                        .map(|&p| view.see(p - view.eye))
                        .collect();
                    // Eight triangles at a time where the CPU has the
                    // vectors ([`setup_avx512`]), the scalar setup for the
                    // lanes it leaves; every slot is written.
                    let count = mesh.indices.len();
                    setups.reserve(count);
                    placed.reserve(count);
                    let start = setups.len();
                    setups.spare_capacity_mut()[..count]
                        .par_chunks_mut(SETUP_LANES)
                        .zip(placed.spare_capacity_mut()[..count].par_chunks_mut(SETUP_LANES))
                        .zip(mesh.indices.par_chunks(SETUP_LANES))
                        .for_each(|((out, places), triangles)| {
                            let done = set_up_lanes(&view, &seen, triangles, z_ref, region, out);
                            for (l, ((slot, place), triangle)) in
                                out.iter_mut().zip(places).zip(triangles).enumerate()
                            {
                                let setup = if done >> l & 1 == 0 {
                                    slot.write(set_up(triangle.map(|i| seen[i as usize])))
                                } else {
                                    // SAFETY: the vector setup wrote the lanes
                                    // of `done`.
                                    unsafe { slot.assume_init_ref() }
                                };
                                place.write(Placed::of(setup));
                            }
                        });
                    // SAFETY: the loop above wrote the `count` slots after
                    // `start` of both, each setup by the vector setup or the
                    // scalar one.
                    unsafe {
                        setups.set_len(start + count);
                        placed.set_len(start + count);
                    }
                }
                Shape::Sphere(_) => {
                    setups.push(Setup::HIDDEN);
                    placed.push(Placed::of(&Setup::HIDDEN));
                }
                Shape::Plane(_) => {}
            }
        }
        assert_eq!(setups.len(), prims.len(), "a setup per primitive");
        if unfit.into_inner() || unbounded.into_inner() > MAX_UNBOUNDED {
            return Err(Unfit);
        }
        let spheres: Vec<(u32, ScreenBox)> = if geometry.triangles() == prims.len() {
            Vec::new()
        } else {
            prims
                .par_iter()
                .enumerate()
                .filter_map(|(i, p)| match *p {
                    Prim::Sphere { center, radius, .. } => {
                        sphere_box(&view, center, radius, region).map(|b| (i as u32, b))
                    }
                    Prim::Triangle { .. } => None,
                })
                .collect()
        };
        let bins_x = region.width.div_ceil(BIN);
        let bins_y = region.height.div_ceil(BIN);
        // Counter-clockwise triangles first in each bin: those of a closed
        // mesh nearest the eye, behind which the others are skipped.
        let triangles = bin(region, bins_x, bins_y, 2, placed.len(), |i| {
            let p = &placed[i];
            (p.class != Placed::HIDDEN).then_some((p.screen, p.class as usize))
        });
        let mut sphere_bins = bin(region, bins_x, bins_y, 1, spheres.len(), |i| {
            Some((spheres[i].1, 0))
        });
        // Bin items index the list; spheres are named by their primitive.
        for item in &mut sphere_bins.items {
            *item = spheres[*item as usize].0;
        }
        Ok(Self {
            view,
            setups,
            triangles,
            spheres: sphere_bins,
            region: *region,
            bins_x,
            raster_fn: dispatch(),
            exact_fn: dispatch_exact(),
        })
    }

    /// The closest hit of each of `rays` into `hits`, exactly
    /// [`Geometry::closest_hit`] of each: `rays[k]` is the primary ray from
    /// the eye through the image point `points[k]` (pixels of the full
    /// image), and every point lies in the bin whose top-left pixel is
    /// `(x0, y0)`.
    pub fn hits(
        &self,
        geometry: &Geometry,
        (x0, y0): (u32, u32),
        points: &[(f64, f64)],
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        scratch: &mut RasterScratch,
    ) {
        assert_eq!(points.len(), rays.len(), "a point per ray");
        assert_eq!(rays.len(), hits.len(), "a hit per ray");
        let bin = self.rasterize((x0, y0), Samples::Points(points), scratch);
        // The exact tests of the vouched triangles.
        let chunks = &scratch.chunks;
        let vouched = |k: usize| {
            let (state, lane) = (&chunks[k / LANES], k % LANES);
            let best = state.best_id[lane];
            (best != NONE && state.other_hi[lane] < state.best_lo[lane]).then_some(best)
        };
        self.exact_tests(geometry, rays, vouched, &mut scratch.exact);
        let prims = geometry.prims();
        let spheres = self.spheres.of(bin);
        for (k, (ray, hit)) in rays.iter().zip(hits.iter_mut()).enumerate() {
            let (chunk, lane) = (k / LANES, k % LANES);
            let state = &scratch.chunks[chunk];
            let mut closest = Closest::new(geometry.closest_plane(ray));
            for &s in spheres {
                closest.offer(s + 1, &prims[s as usize], ray);
            }
            let lanes = &scratch.exact[k / EXACT_LANES];
            match lanes.triangle_hit(k % EXACT_LANES, prims) {
                Some((prim, hit)) => closest.take(prim + 1, hit),
                None if state.best_id[lane] != NONE || state.other_hi[lane] > f32::NEG_INFINITY => {
                    debug_assert!(
                        lanes.prim[k % EXACT_LANES] == NONE,
                        "a vouched triangle misses its sample"
                    );
                    // (Truncation is the floor of these non-negative
                    // coordinates, as `RasterScratch::load` takes them.)
                    let (x, y) = points[k];
                    self.offer_all(bin, Some((x as u32, y as u32)), prims, ray, &mut closest);
                }
                None => {}
            }
            *hit = closest.best;
        }
    }

    /// The closest hit of each of `rays` into `hits`, exactly
    /// [`Geometry::closest_hit`] of each, in a scene of triangles alone:
    /// `rays[k]` is the primary ray through the centre of a pixel of the
    /// bin whose top-left pixel is `corner`, and `setups[k]` the triangle
    /// the rasterizer decided for it ([`Decisions::triangle`]), which the
    /// exact test alone then decides.
    pub(crate) fn decided_hits(
        &self,
        geometry: &Geometry,
        corner: (u32, u32),
        rays: &[Ray],
        setups: &[u32],
        hits: &mut [Option<Hit>],
        scratch: &mut RasterScratch,
    ) {
        assert_eq!(rays.len(), hits.len(), "a hit per ray");
        // A miss is looked for below, lane by lane.
        self.decided_exact(geometry, rays, setups, scratch);
        let prims = geometry.prims();
        for (k, (ray, hit)) in rays.iter().zip(hits.iter_mut()).enumerate() {
            *hit = match scratch.exact[k / EXACT_LANES].triangle_hit(k % EXACT_LANES, prims) {
                Some((_, hit)) => Some(hit),
                // The margins rule this out; were it to happen, every
                // triangle of the bin would be tested, as `hits` does.
                None => {
                    debug_assert!(false, "a decided triangle misses its sample");
                    let mut closest = Closest::new(None);
                    let bin = self.bin_of(corner);
                    self.offer_all(bin, None, prims, ray, &mut closest);
                    closest.best
                }
            };
        }
    }

    /// The exact tests of `rays` (as [`Self::decided_hits`] takes them),
    /// each on the triangle `setups[k]` alone, into `scratch`, where
    /// [`RasterScratch::decided_lanes`] reads each sample's hit; whether every
    /// sample hit its triangle, as the margins make it (else the caller
    /// takes [`Self::decided_hits`], which searches the bin for a miss).
    pub(crate) fn decided_exact(
        &self,
        geometry: &Geometry,
        rays: &[Ray],
        setups: &[u32],
        scratch: &mut RasterScratch,
    ) -> bool {
        assert_eq!(rays.len(), setups.len(), "a setup per ray");
        self.exact_tests(geometry, rays, |k| Some(setups[k]), &mut scratch.exact);
        scratch.exact.iter().enumerate().all(|(group, lanes)| {
            let count = (rays.len() - group * EXACT_LANES).min(EXACT_LANES);
            lanes.hit[..count].iter().all(|&hit| hit)
        })
    }

    /// Every triangle of `bin` offered to `closest` for `ray`; with
    /// `pixel`, the pixel of the full image the ray's point lies in, only
    /// those whose screen box holds it (the rasterizer's own test: a
    /// triangle outside it is no candidate there).
    fn offer_all(
        &self,
        bin: usize,
        pixel: Option<(u32, u32)>,
        prims: &[Prim],
        ray: &Ray,
        closest: &mut Closest,
    ) {
        for &t in self.triangles.of(bin) {
            if let Some((x, y)) = pixel {
                let s = &self.setups[t as usize];
                if x < s.x0 || x >= s.x1 || y < s.y0 || y >= s.y1 {
                    continue;
                }
            }
            closest.offer(t + 1, &prims[t as usize], ray);
        }
    }

    /// The exact tests of `rays`, [`EXACT_LANES`] at a time, into `exact`:
    /// of `rays[k]` on the triangle `setup(k)`, where there is one.
    fn exact_tests(
        &self,
        geometry: &Geometry,
        rays: &[Ray],
        setup: impl Fn(usize) -> Option<u32>,
        exact: &mut Vec<ExactLanes>,
    ) {
        let prims = geometry.prims();
        // The groups of the last tests kept (a group is a kilobyte, which
        // a fresh default would copy in): each lane's triangle is set or
        // cleared below. Of lanes past the rays, the last group's, only
        // the stale directions are read, to choose the form of the test
        // (`ExactLanes::intersect`), which gives the same bits either way.
        let groups = rays.len().div_ceil(EXACT_LANES);
        exact.truncate(groups);
        exact.resize(groups, ExactLanes::default());
        for ((group, rays), lanes) in rays.chunks(EXACT_LANES).enumerate().zip(exact.iter_mut()) {
            lanes.prim = [NONE; EXACT_LANES];
            for (l, ray) in rays.iter().enumerate() {
                for axis in 0..3 {
                    lanes.d[axis][l] = ray.direction[axis];
                }
                if let Some(prim) = setup(group * EXACT_LANES + l)
                    && let Prim::Triangle { p0, p1, p2, .. } = prims[prim as usize]
                {
                    lanes.prim[l] = prim;
                    for (v, p) in [p0, p1, p2].into_iter().enumerate() {
                        for axis in 0..3 {
                            lanes.p[v][axis][l] = p[axis];
                        }
                    }
                }
            }
            (self.exact_fn)(lanes, geometry_origin(rays));
        }
    }

    /// The index of the bin whose top-left pixel is `(x0, y0)`.
    fn bin_of(&self, (x0, y0): (u32, u32)) -> usize {
        ((y0 - self.region.y) / BIN * self.bins_x + (x0 - self.region.x) / BIN) as usize
    }

    /// Loads `samples` (all in the bin whose top-left pixel is `(x0, y0)`)
    /// and rasterizes the bin's triangles at them; returns the bin's index.
    fn rasterize(
        &self,
        (x0, y0): (u32, u32),
        samples: Samples,
        scratch: &mut RasterScratch,
    ) -> usize {
        let bin = self.bin_of((x0, y0));
        (self.raster_fn)(self, self.triangles.of(bin), (x0, y0), samples, scratch);
        bin
    }

    /// What the rasterizer alone decides at the centres of `pixels` (rows
    /// and columns from the bin's top-left pixel `corner`), [`LANES`] at a
    /// time, in the order given, when the scene's only
    /// shapes are triangles: which samples see nothing, which surely see
    /// one triangle (and its setup); the exact tests must say for the
    /// others. `blocks`: each [`LANES`] of `pixels` are the 4×4 block
    /// whose top-left pixel is their first, row by row, and the chunks are
    /// set up from that pixel alone.
    pub(crate) fn decide_centres<'a>(
        &self,
        corner: (u32, u32),
        pixels: &[(usize, usize)],
        blocks: bool,
        scratch: &'a mut RasterScratch,
    ) -> impl Iterator<Item = Decisions> + 'a {
        let samples = if blocks {
            Samples::Blocks(pixels)
        } else {
            Samples::Centres(pixels)
        };
        self.rasterize(corner, samples, scratch);
        let count = pixels.len();
        scratch.chunks.iter().enumerate().map(move |(i, chunk)| {
            let lanes = (count - i * LANES).min(LANES);
            let valid = (1u32 << lanes) - 1;
            let Decided { triangle, nothing } = chunk.decided;
            Decisions {
                best: chunk.best_id,
                triangle: triangle & valid,
                undecided: valid & !(triangle | nothing),
            }
        })
    }

    /// Whether the triangle of the vouched setup `setup` turns
    /// counter-clockwise as the eye sees it: GL's front faces the eye. (The
    /// sign of `D` is that of the eye's offset from the triangle's plane
    /// along its geometric normal, and a vouched triangle's eye lies off
    /// that plane by far more than the roundings of either; see
    /// [`EDGE_ON`].)
    pub(crate) fn front_faces_eye(&self, setup: u32) -> bool {
        let s = &self.setups[setup as usize];
        debug_assert!(
            s.kind == Kind::Vouched,
            "the orientation of a vouched setup"
        );
        s.ccw
    }

    /// The edge functions of the triangle `p` (world space) in f64 over the
    /// full image's pixel coordinates, oriented so that the samples it
    /// holds have all three at least 0, and the margin of each: the
    /// largest difference between an edge function and that of the exact
    /// test ([`EDGE_F64`]; the f64 evaluation of these coefficients at a
    /// pixel errs by a few ulps of the same terms, far less).
    pub(crate) fn exact_edges(&self, p: [DVec3; 3]) -> ExactEdges {
        let vertices = p.map(|p| p - self.view.eye);
        let terms = EdgeTerms::new(vertices, vertices.map(DVec3::length));
        ExactEdges {
            coefficients: terms.coefficients(&self.view, (0.0, 0.0)),
            margin: terms.margins(&self.view),
        }
    }

    /// Loads `samples` and rasterizes `triangles` (indices
    /// into the setups) at them, in the bin at `(x0, y0)`.
    #[inline(always)]
    fn raster(
        &self,
        triangles: &[u32],
        (x0, y0): (u32, u32),
        samples: Samples,
        scratch: &mut RasterScratch,
    ) {
        // Where the chunks are the bin's blocks row by row, how many make a
        // row: a triangle then visits only the blocks its box meets.
        let grid = match samples {
            Samples::Points(points) => {
                scratch.load(points, (x0, y0));
                None
            }
            Samples::Centres(pixels) => {
                scratch.load_centres(pixels, (x0, y0));
                None
            }
            Samples::Blocks(pixels) => scratch.load_blocks(pixels, (x0, y0)),
        };
        let chunks = &mut scratch.chunks;
        for (i, &t) in triangles.iter().enumerate() {
            if let Some(&ahead) = triangles.get(i + SETUPS_AHEAD) {
                prefetch(&self.setups[ahead as usize]);
            }
            let s = &self.setups[t as usize];
            // The edge functions from the bin's corner: the rebased constant
            // loses at most 2^-24 of the terms the margin already counts.
            let dx = x0 as f32 - s.x0 as f32;
            let dy = y0 as f32 - s.y0 as f32;
            let c = [0, 1, 2].map(|i| s.a[i] * dx + s.b[i] * dy + s.c[i]);
            let Some(columns) = grid else {
                for chunk in chunks.iter_mut() {
                    let pixels = &chunk.pixels;
                    if pixels.x1 > s.x0 && pixels.x0 < s.x1 && pixels.y1 > s.y0 && pixels.y0 < s.y1
                    {
                        chunk.rasterize(s, &c, t);
                    }
                }
                continue;
            };
            // The blocks whose pixels meet the setup's box.
            let rows = chunks.len() / columns;
            for row in blocks_met(s.y0, s.y1, y0, rows) {
                for column in blocks_met(s.x0, s.x1, x0, columns) {
                    chunks[row * columns + column].rasterize(s, &c, t);
                }
            }
        }
        if let Samples::Centres(_) | Samples::Blocks(_) = samples {
            for chunk in chunks.iter_mut() {
                chunk.decide();
            }
        }
    }
}

/// How many triangles of a bin ahead of the one rasterized have their
/// setups fetched into the cache: a bin lists its triangles by index, which
/// jumps through the setups where no hardware prefetcher follows, and each
/// setup is read once per bin (docs/design.md; the distance was chosen on
/// the 10^6-triangle frame, where a triangle's turn is shortest, and the
/// smaller frames took the same time at 8 and 24).
const SETUPS_AHEAD: usize = 24;

/// Asks the CPU to bring `setup` into the cache, every line it spans.
#[inline(always)]
fn prefetch(setup: &Setup) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let first = (setup as *const Setup).cast::<i8>();
        let last = first.wrapping_add(size_of::<Setup>() - 1);
        // SAFETY: a prefetch only hints; it reads nothing and cannot fault.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = setup;
}

impl Setup {
    /// The pixels the triangle may cover.
    fn screen_box(&self) -> ScreenBox {
        ScreenBox {
            x0: self.x0,
            y0: self.y0,
            x1: self.x1,
            y1: self.y1,
        }
    }

    /// The setup of a primitive that is not seen.
    const HIDDEN: Self = Self {
        a: [0.0; 3],
        b: [0.0; 3],
        c: [0.0; 3],
        m: [0.0; 3],
        sum_margin: 0.0,
        inv_d: 0.0,
        near: f32::INFINITY,
        ccw: false,
        x0: 0,
        y0: 0,
        x1: 0,
        y1: 0,
        kind: Kind::Hidden,
    };

    /// The setup of the triangle `p` (its vertices as seen); `None` when it
    /// cannot be seen (behind the eye or outside the region).
    fn new(view: &View, p: [Seen; 3], z_ref: f64, region: &Region) -> Result<Option<Self>, Unfit> {
        let terms = EdgeTerms::new(
            [p[0].offset, p[1].offset, p[2].offset],
            [p[0].length, p[1].length, p[2].length],
        );
        let EdgeTerms {
            vertices: [a, b, c],
            lengths,
            d,
            ..
        } = terms;
        let size = lengths[0].max(lengths[1]).max(lengths[2]);
        let depth = [p[0].depth, p[1].depth, p[2].depth];
        let (z_min, z_max) = (
            depth[0].min(depth[1]).min(depth[2]),
            depth[0].max(depth[1]).max(depth[2]),
        );
        if !size.is_finite() {
            return Err(Unfit);
        }
        // Wholly behind the eye by more than the f64 distance can err.
        if z_max < -SAFE_DEPTH * size {
            return Ok(None);
        }
        let normal = (b - a).cross(c - a).length();
        // (A NaN is edge-on too.)
        let edge_on = d.abs().partial_cmp(&(EDGE_ON * size * normal)) != Some(Ordering::Greater);
        let kind = if edge_on {
            Kind::EdgeOn
        } else if z_min <= SAFE_DEPTH * size {
            Kind::Candidate
        } else {
            Kind::Vouched
        };
        // Every visible point q has |q| ≤ z·reach, and |q| is at least the
        // plane's distance: no visible point lies nearer than that depth.
        let z_cut = if edge_on {
            0.0
        } else {
            d.abs() / normal / view.reach * 0.5
        };
        let screen = if z_cut > 0.0 && z_cut.is_finite() {
            match view.screen_box(&p, &[(0, 1), (1, 2), (2, 0)], z_cut, region) {
                Some(screen) => screen,
                None => return Ok(None),
            }
        } else if z_min > SAFE_DEPTH * size {
            // Edge-on but in front: its box is its projection's.
            match view.screen_box(&p, &[], z_min, region) {
                Some(screen) => screen,
                None => return Ok(None),
            }
        } else {
            whole(region)
        };
        // The edge functions over the full image's pixels from the corner
        // of the screen box, oriented.
        let coefficients = terms.coefficients(view, (f64::from(screen.x0), f64::from(screen.y0)));
        let (reach_x, reach_y) = (
            f64::from(screen.x1 - screen.x0 + BIN),
            f64::from(screen.y1 - screen.y0 + BIN),
        );
        // (Arrays written out: `map` over three items stayed a call each.)
        let reach = |[ca, cb, cc]: [f64; 3]| ca.abs() * reach_x + cb.abs() * reach_y + cc.abs();
        let [e0, e1, e2] = coefficients;
        let largest = [reach(e0), reach(e1), reach(e2)];
        let m64 = terms.margins(view);
        let scale = largest[0].max(largest[1]).max(largest[2]);
        if !scale.is_finite() || m64.iter().any(|m| !m.is_finite()) {
            return Err(Unfit);
        }
        if scale == 0.0 {
            // All three vertices at the eye: nothing to see.
            return Ok(None);
        }
        let k = 1.0 / scale;
        let up = |x: f64| {
            let y = x as f32;
            if f64::from(y) < x { y.next_up() } else { y }
        };
        let margin = |i: usize| (EDGE_F32 * largest[i] + m64[i]) * k;
        let m = [margin(0), margin(1), margin(2)];
        let sum_margin = (m[0] + m[1] + m[2]) + DEPTH * (largest[0] + largest[1] + largest[2]) * k;
        let inv_d = z_ref / (d.abs() * k);
        let kind = if kind == Kind::Vouched && !(inv_d.is_finite() && (inv_d as f32).is_normal()) {
            Kind::Candidate
        } else {
            kind
        };
        // Every point lies at depth z_min or more (its nearest vertex's,
        // positive for a vouched triangle); the margin is the depth
        // interval's, twice over.
        let near = if kind == Kind::Vouched {
            up(z_ref / z_min * (1.0 + 2.0 * DEPTH))
        } else {
            f32::INFINITY
        };
        Ok(Some(Self {
            a: [(e0[0] * k) as f32, (e1[0] * k) as f32, (e2[0] * k) as f32],
            b: [(e0[1] * k) as f32, (e1[1] * k) as f32, (e2[1] * k) as f32],
            c: [(e0[2] * k) as f32, (e1[2] * k) as f32, (e2[2] * k) as f32],
            m: [up(m[0]), up(m[1]), up(m[2])],
            sum_margin: up(sum_margin),
            inv_d: inv_d as f32,
            near,
            // (D = a·(b × c) is negative where a, b, c turn counter-clockwise
            // on the screen.)
            ccw: d < 0.0,
            x0: screen.x0,
            y0: screen.y0,
            x1: screen.x1,
            y1: screen.y1,
            kind,
        }))
    }
}

/// A triangle's vertices relative to the eye and its unnormalised edge
/// normals `e_i` (see the module's first paragraph), in f64.
#[derive(Clone, Copy, Debug)]
struct EdgeTerms {
    vertices: [DVec3; 3],
    lengths: [f64; 3],
    e: [DVec3; 3],
    /// `D = a·(b × c)`: its sign is the triangle's orientation seen from
    /// the eye.
    d: f64,
}

impl EdgeTerms {
    /// The terms of the triangle whose vertices relative to the eye are
    /// `vertices`, of lengths `lengths`.
    fn new(vertices: [DVec3; 3], lengths: [f64; 3]) -> Self {
        let [a, b, c] = vertices;
        let e = [b.cross(c), c.cross(a), a.cross(b)];
        Self {
            vertices,
            lengths,
            e,
            d: a.dot(e[0]),
        }
    }

    /// `F_i = ca·(x − ox) + cb·(y − oy) + cc` over the full image's pixel
    /// coordinates `(x, y)`, as `[ca, cb, cc]` per edge, oriented.
    /// (Written out edge by edge rather than through `map`, which the
    /// compiler left as a call per edge in the setup's hot loop.)
    #[inline(always)]
    fn coefficients(&self, view: &View, (ox, oy): (f64, f64)) -> [[f64; 3]; 3] {
        let orientation = if self.d < 0.0 { -1.0 } else { 1.0 };
        let edge = |e: DVec3| {
            let g = e * orientation;
            let (gu, gv, gw) = (g.dot(view.u), g.dot(view.v), g.dot(view.w));
            let ca = gu * view.step_x;
            let cb = -gv * view.step_y;
            [ca, cb, gw - gu + gv + ca * ox + cb * oy]
        };
        [edge(self.e[0]), edge(self.e[1]), edge(self.e[2])]
    }

    /// The f64 part of each edge's margin ([`EDGE_F64`]).
    #[inline(always)]
    fn margins(&self, view: &View) -> [f64; 3] {
        let [l0, l1, l2] = self.lengths;
        let scale = EDGE_F64 * view.reach;
        [scale * l1 * l2, scale * l2 * l0, scale * l0 * l1]
    }
}

/// What the rasterizer alone decides at [`LANES`] samples (see
/// [`Raster::decide_centres`]), as masks of lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Decisions {
    /// Per lane, the setup (the primitive's index) of the nearest triangle
    /// surely holding it.
    pub best: [u32; LANES],
    /// The lanes whose exact test would find `best` closest, and it alone.
    pub triangle: u32,
    /// The lanes the exact tests must decide. Of the valid lanes, no
    /// triangle can hold those in neither mask.
    pub undecided: u32,
}

/// A triangle's edge functions in f64 over the full image's pixel
/// coordinates (see [`Raster::exact_edges`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ExactEdges {
    /// `F_i = ca·x + cb·y + cc` as `[ca, cb, cc]`.
    pub coefficients: [[f64; 3]; 3],
    /// Each `F_i` lies within this of the exact test's, in the same units.
    pub margin: [f64; 3],
}

/// The screen box of the sphere (centre `center`, world space): that of
/// its bounding box cut at the depth before which none of it can be seen.
fn sphere_box(view: &View, center: DVec3, radius: f64, region: &Region) -> Option<ScreenBox> {
    let c = center - view.eye;
    let gap = c.length() - radius;
    if gap.partial_cmp(&(1e-9 * c.length())) != Some(Ordering::Greater) {
        return Some(whole(region));
    }
    let corners: [Seen; 8] = std::array::from_fn(|i| {
        let s = |bit: usize| if i >> bit & 1 == 1 { radius } else { -radius };
        view.see(c + DVec3::new(s(0), s(1), s(2)))
    });
    let edges: Vec<(usize, usize)> = (0..8)
        .flat_map(|i| {
            [1, 2, 4]
                .into_iter()
                .filter(move |bit| i & bit == 0)
                .map(move |bit| (i, i | bit))
        })
        .collect();
    view.screen_box(&corners, &edges, gap / view.reach * 0.5, region)
}

/// The parts [`bin`] splits its items into per thread of the pool, so
/// that a part whose boxes are larger does not keep the others waiting.
const PARTS_PER_THREAD: usize = 4;

/// The fewest items of a part of [`bin`]: a part counts into a list as
/// long as the bins, which few items would not repay.
const MIN_PART: usize = 4096;

/// Each bin's items: those of the `count` items whose box (`box_of`; none:
/// no bin) meets it, listed by their class (`box_of`'s second value, below
/// `classes`), then in index order.
fn bin(
    region: &Region,
    bins_x: u32,
    bins_y: u32,
    classes: usize,
    count: usize,
    box_of: impl Fn(usize) -> Option<(ScreenBox, usize)> + Sync,
) -> Bins {
    // A list per class of each bin, bin by bin.
    let lists = (bins_x * bins_y) as usize * classes;
    // A box past the region's right or bottom border (for the points on
    // it) is in the last bin.
    let range = |i: usize| {
        let (b, class) = box_of(i)?;
        Some((
            ((b.x0 - region.x) / BIN).min(bins_x - 1)
                ..((b.x1 - 1 - region.x) / BIN + 1).min(bins_x),
            ((b.y0 - region.y) / BIN).min(bins_y - 1)
                ..((b.y1 - 1 - region.y) / BIN + 1).min(bins_y),
            class,
        ))
    };
    let list = |x: u32, y: u32, class: usize| (y * bins_x + x) as usize * classes + class;
    // The items in parts, each counted and placed by one task without
    // atomic counters (two cores adding to the same bin's counter pass its
    // cache line to and fro): every part's place in a list follows the
    // earlier parts', so each list holds its items in index order, whatever
    // the threads' timing, and setups are read in memory order.
    let parts = (rayon::current_num_threads() * PARTS_PER_THREAD)
        .min(count.div_ceil(MIN_PART))
        .max(1);
    let part_size = count.div_ceil(parts).max(1);
    let counts: Vec<Vec<u32>> = (0..parts)
        .into_par_iter()
        .map(|part| {
            let mut counts = vec![0u32; lists];
            for i in part * part_size..((part + 1) * part_size).min(count) {
                let Some((xs, ys, class)) = range(i) else {
                    continue;
                };
                for y in ys {
                    for x in xs.clone() {
                        counts[list(x, y, class)] += 1;
                    }
                }
            }
            counts
        })
        .collect();
    // Each part's first place in each list, and the lists' starts.
    let mut cursors = vec![vec![0u32; lists]; parts];
    let mut start = Vec::with_capacity(lists + 1);
    let mut total = 0u32;
    for l in 0..lists {
        start.push(total);
        for (cursor, counts) in cursors.iter_mut().zip(&counts) {
            cursor[l] = total;
            total += counts[l];
        }
    }
    start.push(total);
    // (Relaxed stores to distinct places: plain stores, shared safely.)
    let items: Vec<AtomicU32> = (0..total).map(|_| AtomicU32::new(0)).collect();
    cursors
        .into_par_iter()
        .enumerate()
        .for_each(|(part, mut cursor)| {
            for i in part * part_size..((part + 1) * part_size).min(count) {
                let Some((xs, ys, class)) = range(i) else {
                    continue;
                };
                for y in ys {
                    for x in xs.clone() {
                        let at = &mut cursor[list(x, y, class)];
                        items[*at as usize].store(i as u32, atomic::Ordering::Relaxed);
                        *at += 1;
                    }
                }
            }
        });
    let items: Vec<u32> = items.into_iter().map(AtomicU32::into_inner).collect();
    Bins {
        start,
        items,
        classes,
    }
}

/// A worker's buffers for [`Raster::hits`].
#[derive(Default)]
pub struct RasterScratch {
    chunks: Vec<Chunk>,
    exact: Vec<ExactLanes>,
}

/// Samples whose exact test runs together.
pub(crate) const EXACT_LANES: usize = 8;

/// A group of exact tests ([`RasterScratch::decided_lanes`]), a value per
/// lane: the triangle tested (its primitive), whether it was hit, the
/// hit's distance and barycentrics, and the ray's direction by axis.
pub(crate) struct DecidedLanes<'a> {
    pub prim: &'a [u32; EXACT_LANES],
    pub hit: &'a [bool; EXACT_LANES],
    pub t: &'a [f64; EXACT_LANES],
    pub u: &'a [f64; EXACT_LANES],
    pub v: &'a [f64; EXACT_LANES],
    pub direction: &'a [[f64; EXACT_LANES]; 3],
}

/// The exact tests of [`EXACT_LANES`] samples, each on the triangle the
/// rasterizer vouched for ([`NONE`]: none).
#[derive(Clone, Copy, Debug)]
struct ExactLanes {
    /// The ray directions, `d[axis][lane]`.
    d: [[f64; EXACT_LANES]; 3],
    /// The vertices, `p[vertex][axis][lane]`.
    p: [[[f64; EXACT_LANES]; 3]; 3],
    prim: [u32; EXACT_LANES],
    t: [f64; EXACT_LANES],
    u: [f64; EXACT_LANES],
    v: [f64; EXACT_LANES],
    hit: [bool; EXACT_LANES],
}

impl Default for ExactLanes {
    fn default() -> Self {
        Self {
            d: [[0.0; EXACT_LANES]; 3],
            p: [[[0.0; EXACT_LANES]; 3]; 3],
            prim: [NONE; EXACT_LANES],
            t: [0.0; EXACT_LANES],
            u: [0.0; EXACT_LANES],
            v: [0.0; EXACT_LANES],
            hit: [false; EXACT_LANES],
        }
    }
}

impl ExactLanes {
    /// Lane `l`'s triangle and its hit, where its exact test found one.
    fn triangle_hit(&self, l: usize, prims: &[Prim]) -> Option<(u32, Hit)> {
        let prim = self.prim[l];
        if prim == NONE || !self.hit[l] {
            return None;
        }
        let Prim::Triangle {
            object, triangle, ..
        } = prims[prim as usize]
        else {
            unreachable!("exact tests are of triangles")
        };
        let hit = Hit {
            t: self.t[l],
            object,
            triangle,
            u: self.u[l],
            v: self.v[l],
        };
        Some((prim, hit))
    }
}

/// The common origin of `rays` (the eye).
fn geometry_origin(rays: &[Ray]) -> DVec3 {
    rays[0].origin
}

impl ExactLanes {
    /// [`crate::geometry::intersect_triangle`] of every lane's ray from
    /// `origin` against its triangle, over (0, ∞): the same operations in
    /// the same order, so the same bits, written lane by lane so that the
    /// compiler runs the lanes as one vector (the dominant axis, chosen per
    /// lane, becomes a selection).
    #[inline(always)]
    fn intersect(&mut self, origin: DVec3) {
        // Neighbouring rays nearly always share their dominant axis and its
        // sign: then the axes are constants of the whole loop.
        let config = |l: usize| {
            let d = [self.d[0][l], self.d[1][l], self.d[2][l]];
            let abs = [d[0].abs(), d[1].abs(), d[2].abs()];
            let kz = if abs[1] > abs[0] {
                if abs[2] > abs[1] { 2 } else { 1 }
            } else if abs[2] > abs[0] {
                2
            } else {
                0
            };
            (kz, d[kz] < 0.0)
        };
        let first = config(0);
        if (1..EXACT_LANES).all(|l| config(l) == first) {
            match first {
                (0, false) => return self.intersect_along::<1, 2, 0>(origin),
                (0, true) => return self.intersect_along::<2, 1, 0>(origin),
                (1, false) => return self.intersect_along::<2, 0, 1>(origin),
                (1, true) => return self.intersect_along::<0, 2, 1>(origin),
                (2, false) => return self.intersect_along::<0, 1, 2>(origin),
                _ => return self.intersect_along::<1, 0, 2>(origin),
            }
        }
        self.intersect_any(origin)
    }

    /// [`Self::intersect`] when every lane's ray has the dominant axis `KZ`
    /// and the sheared axes `KX`, `KY`.
    #[inline(always)]
    fn intersect_along<const KX: usize, const KY: usize, const KZ: usize>(
        &mut self,
        origin: DVec3,
    ) {
        let o = origin.to_array();
        for l in 0..EXACT_LANES {
            let dz = self.d[KZ][l];
            let (sx, sy, sz) = (self.d[KX][l] / dz, self.d[KY][l] / dz, 1.0 / dz);
            let vertex = |v: usize| {
                [
                    self.p[v][0][l] - o[0],
                    self.p[v][1][l] - o[1],
                    self.p[v][2][l] - o[2],
                ]
            };
            let (a, b, c) = (vertex(0), vertex(1), vertex(2));
            let shear = |p: [f64; 3]| (p[KX] - sx * p[KZ], p[KY] - sy * p[KZ]);
            let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
            let w0 = cx * by - cy * bx;
            let w1 = ax * cy - ay * cx;
            let w2 = bx * ay - by * ax;
            let mixed = (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) && (w0 > 0.0 || w1 > 0.0 || w2 > 0.0);
            let det = w0 + w1 + w2;
            let t = (w0 * a[KZ] + w1 * b[KZ] + w2 * c[KZ]) * sz / det;
            self.hit[l] = !mixed && det != 0.0 && det.is_finite() && t > 0.0 && t < f64::INFINITY;
            self.t[l] = t;
            self.u[l] = w1 / det;
            self.v[l] = w2 / det;
        }
    }

    /// [`Self::intersect`] with each lane's axes its own.
    #[inline(always)]
    fn intersect_any(&mut self, origin: DVec3) {
        let o = origin.to_array();
        for l in 0..EXACT_LANES {
            let d = [self.d[0][l], self.d[1][l], self.d[2][l]];
            let abs = [d[0].abs(), d[1].abs(), d[2].abs()];
            // `DVec3::max_position`: the first largest.
            let kz = if abs[1] > abs[0] {
                if abs[2] > abs[1] { 2 } else { 1 }
            } else if abs[2] > abs[0] {
                2
            } else {
                0
            };
            let pick = |v: [f64; 3], k: usize| {
                if k == 0 {
                    v[0]
                } else if k == 1 {
                    v[1]
                } else {
                    v[2]
                }
            };
            let (kx0, ky0) = ((kz + 1) % 3, (kz + 2) % 3);
            let dz = pick(d, kz);
            let (kx, ky) = if dz < 0.0 { (ky0, kx0) } else { (kx0, ky0) };
            let (sx, sy, sz) = (pick(d, kx) / dz, pick(d, ky) / dz, 1.0 / dz);
            let vertex = |v: usize| {
                [
                    self.p[v][0][l] - o[0],
                    self.p[v][1][l] - o[1],
                    self.p[v][2][l] - o[2],
                ]
            };
            let (a, b, c) = (vertex(0), vertex(1), vertex(2));
            let shear = |p: [f64; 3]| {
                let pz = pick(p, kz);
                (pick(p, kx) - sx * pz, pick(p, ky) - sy * pz)
            };
            let ((ax, ay), (bx, by), (cx, cy)) = (shear(a), shear(b), shear(c));
            let w0 = cx * by - cy * bx;
            let w1 = ax * cy - ay * cx;
            let w2 = bx * ay - by * ax;
            let mixed = (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) && (w0 > 0.0 || w1 > 0.0 || w2 > 0.0);
            let det = w0 + w1 + w2;
            let t = (w0 * pick(a, kz) + w1 * pick(b, kz) + w2 * pick(c, kz)) * sz / det;
            self.hit[l] = !mixed && det != 0.0 && det.is_finite() && t > 0.0 && t < f64::INFINITY;
            self.t[l] = t;
            self.u[l] = w1 / det;
            self.v[l] = w2 / det;
        }
    }
}

impl RasterScratch {
    /// The exact tests of [`Raster::decided_exact`], [`EXACT_LANES`]
    /// samples a group, in order: sample `k` is lane `k % EXACT_LANES` of
    /// group `k / EXACT_LANES` (lanes past the samples are stale).
    pub(crate) fn decided_lanes(&self) -> impl Iterator<Item = DecidedLanes<'_>> {
        self.exact.iter().map(|lanes| DecidedLanes {
            prim: &lanes.prim,
            hit: &lanes.hit,
            t: &lanes.t,
            u: &lanes.u,
            v: &lanes.v,
            direction: &lanes.d,
        })
    }

    /// The samples at `points` in chunks of [`LANES`], from the bin's corner
    /// `(x0, y0)`, every lane without a triangle.
    #[inline(always)]
    fn load(&mut self, points: &[(f64, f64)], (x0, y0): (u32, u32)) {
        self.chunks.clear();
        for group in points.chunks(LANES) {
            let (mut fx, mut fy) = ([0.0; LANES], [0.0; LANES]);
            for l in 0..LANES {
                // Lanes past the end repeat the last sample.
                (fx[l], fy[l]) = group[l.min(group.len() - 1)];
            }
            let (mut x, mut y) = ([0.0; LANES], [0.0; LANES]);
            let (mut px, mut py) = ([0u32; LANES], [0u32; LANES]);
            for l in 0..LANES {
                x[l] = (fx[l] - f64::from(x0)) as f32;
                y[l] = (fy[l] - f64::from(y0)) as f32;
                // (Truncation is the floor of these non-negative values,
                // without a call to the library's `floor`.)
                (px[l], py[l]) = (fx[l] as u32, fy[l] as u32);
            }
            // Integers, so that the extremes are found in lanes too.
            let pixels = ScreenBox {
                x0: px.iter().fold(u32::MAX, |a, &b| a.min(b)),
                y0: py.iter().fold(u32::MAX, |a, &b| a.min(b)),
                x1: px.iter().fold(0, |a, &b| a.max(b)) + 1,
                y1: py.iter().fold(0, |a, &b| a.max(b)) + 1,
            };
            self.chunks.push(Chunk::empty(x, y, pixels));
        }
    }

    /// The centres of `pixels` (rows and columns from the bin's corner
    /// `(x0, y0)`) as [`Self::load`] loads points: the same lanes, found
    /// from integers.
    #[inline(always)]
    fn load_centres(&mut self, pixels: &[(usize, usize)], (x0, y0): (u32, u32)) {
        self.chunks.clear();
        for group in pixels.chunks(LANES) {
            let (mut rows, mut columns) = ([0u32; LANES], [0u32; LANES]);
            for l in 0..LANES {
                // Lanes past the end repeat the last sample.
                let (row, column) = group[l.min(group.len() - 1)];
                (rows[l], columns[l]) = (row as u32, column as u32);
            }
            let pixels = ScreenBox {
                x0: x0 + columns.iter().fold(u32::MAX, |a, &b| a.min(b)),
                y0: y0 + rows.iter().fold(u32::MAX, |a, &b| a.min(b)),
                x1: x0 + columns.iter().fold(0, |a, &b| a.max(b)) + 1,
                y1: y0 + rows.iter().fold(0, |a, &b| a.max(b)) + 1,
            };
            self.chunks.push(Chunk::empty(
                columns.map(|c| c as f32 + 0.5),
                rows.map(|r| r as f32 + 0.5),
                pixels,
            ));
        }
    }

    /// [`Self::load_centres`] of pixels in 4×4 blocks, each [`LANES`] of
    /// them one block row by row from its top-left pixel: a chunk's lanes
    /// and box from that pixel alone, the same values as from every lane.
    /// Returns how many blocks make a row where the blocks are the bin's
    /// from its corner, row by row ([`Raster::raster`] then finds a
    /// triangle's blocks from its box); `None` for any other order.
    #[inline(always)]
    fn load_blocks(&mut self, pixels: &[(usize, usize)], (x0, y0): (u32, u32)) -> Option<usize> {
        const SIDE: u32 = crate::renderer::BLOCK;
        const _: () = assert!((SIDE * SIDE) as usize == LANES);
        self.chunks.clear();
        for group in pixels.chunks(LANES) {
            debug_assert!(group.len() == LANES, "whole blocks");
            let (row, column) = (group[0].0 as u32, group[0].1 as u32);
            let pixels = ScreenBox {
                x0: x0 + column,
                y0: y0 + row,
                x1: x0 + column + SIDE,
                y1: y0 + row + SIDE,
            };
            self.chunks.push(Chunk::empty(
                std::array::from_fn(|l| (column + l as u32 % SIDE) as f32 + 0.5),
                std::array::from_fn(|l| (row + l as u32 / SIDE) as f32 + 0.5),
                pixels,
            ));
        }
        // The blocks of the first row, then every block where the grid
        // puts it.
        let columns = (self.chunks.iter())
            .take_while(|chunk| chunk.pixels.y0 == y0)
            .count();
        let grid = columns > 0
            && self.chunks.len().is_multiple_of(columns)
            && self.chunks.iter().enumerate().all(|(k, chunk)| {
                let (row, column) = ((k / columns) as u32, (k % columns) as u32);
                (chunk.pixels.x0, chunk.pixels.y0) == (x0 + column * SIDE, y0 + row * SIDE)
            });
        grid.then_some(columns)
    }
}

/// Along one axis, the blocks of a bin whose corner is at `corner` (each
/// [`crate::renderer::BLOCK`] pixels, `count` of them) that meet the pixels
/// `[lo, hi)`: block `j` holds `[corner + 4j, corner + 4j + 4)`.
#[inline(always)]
fn blocks_met(lo: u32, hi: u32, corner: u32, count: usize) -> std::ops::Range<usize> {
    let side = crate::renderer::BLOCK;
    let first = (lo.saturating_sub(corner) / side) as usize;
    let end = (hi.saturating_sub(corner).div_ceil(side) as usize).min(count);
    first..end
}

/// Sixteen samples and what the rasterizer knows of them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chunk {
    /// From the bin's corner, in pixels.
    x: [f32; LANES],
    y: [f32; LANES],
    /// The sure candidate nearest by its lower bound of `1/z`: that bound,
    /// its upper bound and its setup.
    best_lo: [f32; LANES],
    best_hi: [f32; LANES],
    best_id: [u32; LANES],
    /// The largest upper bound of `1/z` of every other candidate.
    other_hi: [f32; LANES],
    /// The pixels the samples lie in: `[x0, x1) × [y0, y1)`.
    pixels: ScreenBox,
    /// What the rasterizer alone decides of the lanes, once every triangle
    /// is rasterized at the centres of pixels ([`Chunk::decide`]); nothing
    /// (the default) for samples at points.
    decided: Decided,
}

/// The lanes of a chunk whose closest hit the rasterizer decides, as masks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Decided {
    /// The lanes whose exact test would find `best_id` closest, and it
    /// alone.
    triangle: u32,
    /// The lanes no triangle can hold.
    nothing: u32,
}

impl Chunk {
    /// Samples at `x`, `y` (from the bin's corner, in pixels) lying in
    /// `pixels`, with no candidate yet.
    #[inline(always)]
    fn empty(x: [f32; LANES], y: [f32; LANES], pixels: ScreenBox) -> Self {
        Self {
            x,
            y,
            best_lo: [f32::NEG_INFINITY; LANES],
            best_hi: [f32::NEG_INFINITY; LANES],
            other_hi: [f32::NEG_INFINITY; LANES],
            best_id: [NONE; LANES],
            pixels,
            decided: Decided::default(),
        }
    }

    /// Rasterizes triangle `id` (its setup `s`, its edge constants `c`
    /// rebased to the bin) at the sixteen samples, unless it lies wholly
    /// behind every lane's sure triangle: then it is neither nearest nor in
    /// the way of any lane's decision.
    #[inline(always)]
    fn rasterize(&mut self, s: &Setup, c: &[f32; 3], id: u32) {
        if self.behind(s.near) {
            return;
        }
        match s.kind {
            Kind::Vouched => self.update::<true, false>(s, c, id),
            Kind::Candidate => self.update::<false, false>(s, c, id),
            Kind::EdgeOn => self.update::<false, true>(s, c, id),
            Kind::Hidden => unreachable!("hidden setups are in no bin"),
        }
    }

    /// Whether a triangle whose `1/z` is at most `near` everywhere lies
    /// behind every lane's sure triangle: neither nearest nor in the way of
    /// any lane's decision. (Every lane compared, in vector lanes.)
    #[inline(always)]
    fn behind(&self, near: f32) -> bool {
        (0..LANES).fold(true, |all, l| all & (near < self.best_lo[l]))
    }

    /// Sets [`Self::decided`] from the lanes' candidates: each lane's
    /// answers first, then their masks (in vector lanes where the caller
    /// is built for them).
    #[inline(always)]
    fn decide(&mut self) {
        let (mut sure, mut none) = ([false; LANES], [false; LANES]);
        for l in 0..LANES {
            let found = self.best_id[l] != NONE;
            sure[l] = found & (self.other_hi[l] < self.best_lo[l]);
            none[l] = !found & (self.other_hi[l] == f32::NEG_INFINITY);
        }
        let mask =
            |lanes: [bool; LANES]| (0..LANES).fold(0u32, |mask, l| mask | u32::from(lanes[l]) << l);
        self.decided = Decided {
            triangle: mask(sure),
            nothing: mask(none),
        };
    }

    /// Evaluates triangle `id` (its edge constants `c` rebased to the bin)
    /// at the sixteen samples. `SURE`: it may be sure and its depth counts;
    /// `EITHER`: it is tested in both orientations.
    #[inline(always)]
    fn update<const SURE: bool, const EITHER: bool>(&mut self, s: &Setup, c: &[f32; 3], id: u32) {
        for l in 0..LANES {
            let (x, y) = (self.x[l], self.y[l]);
            let f0 = s.a[0] * x + s.b[0] * y + c[0];
            let f1 = s.a[1] * x + s.b[1] * y + c[1];
            let f2 = s.a[2] * x + s.b[2] * y + c[2];
            let inside = (f0 >= -s.m[0]) & (f1 >= -s.m[1]) & (f2 >= -s.m[2]);
            let maybe = if EITHER {
                inside | ((f0 <= s.m[0]) & (f1 <= s.m[1]) & (f2 <= s.m[2]))
            } else {
                inside
            };
            let (lo, hi, take) = if SURE {
                let sum = f0 + f1 + f2;
                let lo = (sum - s.sum_margin) * s.inv_d;
                let hi = (sum + s.sum_margin) * s.inv_d;
                let lo = lo - lo.abs() * DEPTH as f32;
                let hi = hi + hi.abs() * DEPTH as f32;
                let sure = (f0 >= s.m[0]) & (f1 >= s.m[1]) & (f2 >= s.m[2]);
                (lo, hi, sure & (lo > self.best_lo[l]))
            } else {
                (f32::NEG_INFINITY, f32::INFINITY, false)
            };
            // The candidate that is not the best reaches `hi`; a replaced
            // best becomes such a candidate.
            let other = if take {
                self.best_hi[l]
            } else if maybe {
                hi
            } else {
                f32::NEG_INFINITY
            };
            // Every lane written, its old value or its new one chosen by
            // bits: as selects, the compiler stores only the lanes that
            // change, and the next triangle's loads of them stall.
            let keep = if take { 0 } else { u32::MAX };
            let blend = |new: u32, old: u32| (new & !keep) | (old & keep);
            let blend_f32 =
                |new: f32, old: f32| f32::from_bits(blend(new.to_bits(), old.to_bits()));
            self.other_hi[l] = self.other_hi[l].max(other);
            self.best_lo[l] = blend_f32(lo, self.best_lo[l]);
            self.best_hi[l] = blend_f32(hi, self.best_hi[l]);
            self.best_id[l] = blend(id, self.best_id[l]);
        }
    }
}

/// Triangles a call of [`SetupFn`] sets up: as many as an AVX-512 vector
/// has f64 lanes.
const SETUP_LANES: usize = 8;

/// Sets up some of `triangles` (at most [`SETUP_LANES`], vertices indices
/// into the mesh's `seen`) exactly as [`Setup::new`] would, into the same
/// places of `out`; returns the mask of those written, the others left to
/// [`Setup::new`].
type SetupFn =
    fn(&View, &[Seen], &[[u32; 3]], f64, &Region, &mut [std::mem::MaybeUninit<Setup>]) -> u8;

/// The vector setup the CPU runs, if any.
fn dispatch_setup() -> SetupFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx2") {
            return |view, seen, triangles, z_ref, region, out| {
                // SAFETY: the CPU has AVX-512F and AVX2, checked just above.
                unsafe { setup_avx512::set_up(view, seen, triangles, z_ref, region, out) }
            };
        }
    }
    |_, _, _, _, _, _| 0
}

type RasterFn = fn(&Raster, &[u32], (u32, u32), Samples, &mut RasterScratch);

/// The samples of a bin: points of the full image, or the centres of
/// pixels given as rows and columns from the bin's top-left pixel, or such
/// centres in blocks (see [`Raster::decide_centres`]).
#[derive(Clone, Copy, Debug)]
enum Samples<'a> {
    Points(&'a [(f64, f64)]),
    Centres(&'a [(usize, usize)]),
    Blocks(&'a [(usize, usize)]),
}

type ExactFn = fn(&mut ExactLanes, DVec3);

/// The widest build of the exact tests the CPU runs.
fn dispatch_exact() -> ExactFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512dq") {
            return |lanes, origin| {
                // SAFETY: the CPU has AVX-512F and DQ, checked just above.
                unsafe { exact_avx512(lanes, origin) }
            };
        }
        if std::is_x86_feature_detected!("avx2") {
            return |lanes, origin| {
                // SAFETY: the CPU has AVX2, checked just above.
                unsafe { exact_avx2(lanes, origin) }
            };
        }
    }
    |lanes, origin| lanes.intersect(origin)
}

// Without FMA: the exact tests must round as the scalar one does, and Rust
// never fuses a product and a sum unless asked to.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
fn exact_avx512(lanes: &mut ExactLanes, origin: DVec3) {
    lanes.intersect(origin)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn exact_avx2(lanes: &mut ExactLanes, origin: DVec3) {
    lanes.intersect(origin)
}

/// The widest build of the rasterizing loop the CPU runs.
fn dispatch() -> RasterFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
        {
            return |r, t, o, p, s| {
                // SAFETY: the CPU has AVX-512F and DQ, AVX2 and FMA, checked
                // just above.
                unsafe { raster_avx512(r, t, o, p, s) }
            };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            return |r, t, o, p, s| {
                // SAFETY: the CPU has AVX2 and FMA, checked just above.
                unsafe { raster_avx2(r, t, o, p, s) }
            };
        }
    }
    |r, t, o, p, s| r.raster(t, o, p, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
fn raster_avx512(
    raster: &Raster,
    triangles: &[u32],
    origin: (u32, u32),
    samples: Samples,
    s: &mut RasterScratch,
) {
    raster.raster(triangles, origin, samples, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn raster_avx2(
    raster: &Raster,
    triangles: &[u32],
    origin: (u32, u32),
    samples: Samples,
    s: &mut RasterScratch,
) {
    raster.raster(triangles, origin, samples, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mesh;
    use crate::test_rng::Rng;

    /// Every bit of a setup.
    fn bits(s: &Setup) -> Vec<u64> {
        let f = |x: &[f32]| x.iter().map(|x| u64::from(x.to_bits())).collect::<Vec<_>>();
        [
            f(&s.a),
            f(&s.b),
            f(&s.c),
            f(&s.m),
            f(&[s.sum_margin, s.inv_d, s.near]),
            vec![u64::from(s.ccw), s.kind as u64],
            [s.x0, s.y0, s.x1, s.y1].map(u64::from).to_vec(),
        ]
        .concat()
    }

    /// A camera, and a mesh of triangles of every kind the setup branches
    /// on: seen in front, degenerate (a vertex repeated, or three on a
    /// line), slivers, behind the eye, across the eye's plane and near it,
    /// off the image, and (with `wild`) far beyond f32.
    fn scene(rng: &mut Rng, wild: bool) -> (Camera, Mesh) {
        let camera = Camera {
            eye: DVec3::new(0.0, 0.8, 3.2),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y: 45.0,
            width: 320,
            height: 200,
        };
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        let point = |rng: &mut Rng| match rng.below(8) {
            // Around the target, in front of the eye.
            0..=3 => DVec3::new(
                rng.uniform(-1.5, 1.5),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.5, 1.5),
            ),
            // Near the eye, on either side of its plane.
            4 => {
                camera.eye
                    + DVec3::new(
                        rng.uniform(-0.1, 0.1),
                        rng.uniform(-0.1, 0.1),
                        rng.uniform(-0.1, 0.1),
                    )
            }
            // Behind the eye.
            5 => {
                camera.eye
                    + DVec3::new(
                        rng.uniform(-2.0, 2.0),
                        rng.uniform(-2.0, 2.0),
                        rng.uniform(0.5, 3.0),
                    )
            }
            // Far to the side, off the image.
            6 => DVec3::new(rng.uniform(20.0, 40.0), rng.uniform(-1.0, 1.0), 0.0),
            _ if wild => DVec3::splat(rng.uniform(-1.0, 1.0) * 1e200),
            _ => DVec3::new(0.0, 0.0, rng.uniform(-1.0, 1.0)),
        };
        for _ in 0..3000 {
            let base = positions.len() as u32;
            let [a, b, c] = [(); 3].map(|_| point(rng));
            match rng.below(6) {
                // A vertex repeated.
                0 => {
                    positions.extend([a, b]);
                    indices.push([base, base + 1, base + rng.below(2) as u32]);
                }
                // Three on a line, or a sliver off it.
                1 | 2 => {
                    let off = if rng.below(2) == 0 { 0.0 } else { 1e-9 };
                    positions.extend([a, b, a.lerp(b, 0.3) + DVec3::splat(off)]);
                    indices.push([base, base + 1, base + 2]);
                }
                // Shared vertices, as in a mesh.
                3 if base > 0 => {
                    positions.push(a);
                    let (i, j) = (rng.below(base as usize), rng.below(base as usize));
                    indices.push([base, i as u32, j as u32]);
                }
                _ => {
                    positions.extend([a, b, c]);
                    indices.push([base, base + 1, base + 2]);
                }
            }
        }
        (
            camera,
            Mesh {
                positions,
                normals: None,
                indices,
            },
        )
    }

    fn full(camera: &Camera) -> Region {
        Region {
            x: 0,
            y: 0,
            width: camera.width,
            height: camera.height,
        }
    }

    /// The scalar setup, as a frame stores it.
    fn scalar(view: &View, p: [Seen; 3], z_ref: f64, region: &Region) -> Option<Setup> {
        match Setup::new(view, p, z_ref, region) {
            Ok(Some(setup)) => Some(setup),
            Ok(None) => Some(Setup::HIDDEN),
            Err(Unfit) => None,
        }
    }

    /// The pixels of a `width × height` tile (multiples of the block's
    /// side) block by block, each block row by row, as the renderer orders
    /// a tile's.
    fn block_order(width: usize, height: usize) -> Vec<(usize, usize)> {
        const SIDE: usize = crate::renderer::BLOCK as usize;
        let mut pixels = Vec::new();
        for by in (0..height).step_by(SIDE) {
            for bx in (0..width).step_by(SIDE) {
                for row in by..by + SIDE {
                    pixels.extend((bx..bx + SIDE).map(|column| (row, column)));
                }
            }
        }
        pixels
    }

    #[test]
    fn blocks_load_as_their_pixels_do() {
        for (width, height) in [(16, 16), (8, 12), (4, 4)] {
            let pixels = block_order(width, height);
            let (mut blocks, mut centres) = (RasterScratch::default(), RasterScratch::default());
            blocks.load_blocks(&pixels, (32, 48));
            centres.load_centres(&pixels, (32, 48));
            assert_eq!(blocks.chunks, centres.chunks, "{width}×{height}");
        }
    }

    /// A tile's pixels rasterized in blocks, each triangle visiting only the
    /// blocks its box meets, end as they do when every triangle visits every
    /// chunk: over whole images and a region whose last tiles are narrower,
    /// every chunk's candidates and decisions.
    #[test]
    fn blocks_rasterize_as_their_pixels_do() {
        let mut rng = Rng::new(0x0b10_c4ed);
        let tile = crate::renderer::TILE;
        let mut decided = 0;
        for round in 0..4 {
            let (camera, mut mesh) = scene(&mut rng, false);
            // Only the triangles wholly in front of the eye, so that most
            // pixels are decided (a triangle reaching behind it covers the
            // image with a candidate that decides nothing).
            let ahead = camera.target - camera.eye;
            let in_front = |i: &u32| (mesh.positions[*i as usize] - camera.eye).dot(ahead) > 1.0;
            let indices = (mesh.indices.iter())
                .filter(|t| t.iter().all(in_front))
                .copied()
                .collect();
            mesh.indices = indices;
            let region = match round % 2 {
                0 => full(&camera),
                _ => Region {
                    x: 100,
                    y: 40,
                    width: 52,
                    height: 72,
                },
            };
            let objects = [Object {
                shape: Shape::Mesh(bounded(&camera, mesh, &region)),
                material: 0,
            }];
            let geometry = Geometry::new(&objects);
            let pinhole = PinholeCamera::new(&camera);
            let raster =
                Raster::new(&geometry, &objects, &pinhole, &camera, &region).expect("a fit frame");
            for y0 in (region.y..region.y + region.height).step_by(tile as usize) {
                for x0 in (region.x..region.x + region.width).step_by(tile as usize) {
                    let width = (region.x + region.width - x0).min(tile) as usize;
                    let height = (region.y + region.height - y0).min(tile) as usize;
                    let pixels = block_order(width, height);
                    let mut blocks = RasterScratch::default();
                    let mut one_by_one = RasterScratch::default();
                    assert_eq!(
                        blocks.load_blocks(&pixels, (x0, y0)),
                        Some(width / crate::renderer::BLOCK as usize)
                    );
                    let _ = raster.decide_centres((x0, y0), &pixels, true, &mut blocks);
                    let _ = raster.decide_centres((x0, y0), &pixels, false, &mut one_by_one);
                    assert_eq!(blocks.chunks, one_by_one.chunks, "the tile at ({x0}, {y0})");
                    decided += (blocks.chunks.iter())
                        .map(|chunk| chunk.decided.triangle.count_ones())
                        .sum::<u32>();
                }
            }
        }
        assert!(decided > 10_000, "only {decided} pixels decided");
    }

    #[test]
    fn the_vector_setup_is_the_scalar_one_bit_for_bit() {
        let mut rng = Rng::new(0x0005_e709);
        let mut taken = 0;
        let mut total = 0;
        for round in 0..6 {
            let (camera, mesh) = scene(&mut rng, round % 2 == 1);
            let view = View::new(&PinholeCamera::new(&camera), &camera);
            let region = if round < 4 {
                full(&camera)
            } else {
                Region {
                    x: 100,
                    y: 40,
                    width: 50,
                    height: 70,
                }
            };
            let seen: Vec<Seen> = mesh
                .positions
                .iter()
                .map(|&p| view.see(p - view.eye))
                .collect();
            let z_ref = 2.0;
            for group in mesh.indices.chunks(SETUP_LANES) {
                let mut out = [std::mem::MaybeUninit::uninit(); SETUP_LANES];
                let out = &mut out[..group.len()];
                let done = dispatch_setup()(&view, &seen, group, z_ref, &region, out);
                for (l, triangle) in group.iter().enumerate() {
                    total += 1;
                    if done >> l & 1 == 0 {
                        continue;
                    }
                    taken += 1;
                    // SAFETY: the vector setup wrote the lanes of `done`.
                    let vector = unsafe { out[l].assume_init() };
                    let p = triangle.map(|i| seen[i as usize]);
                    let scalar = scalar(&view, p, z_ref, &region).expect("a fit triangle");
                    assert_eq!(bits(&vector), bits(&scalar), "{triangle:?}: {p:?}");
                }
            }
        }
        // Where the CPU has the vectors, they take the common case: the
        // triangles seen whole in front of the eye, about a third here.
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx2") {
            assert!(taken * 5 > total, "{taken} of {total} set up in vectors");
        }
    }

    /// The scalar setups of `mesh`'s triangles as a frame of `camera` and
    /// `region` makes them.
    fn scalar_setups<'a>(
        camera: &Camera,
        mesh: &'a Mesh,
        region: &'a Region,
    ) -> impl Fn(&[u32; 3]) -> Setup + 'a {
        let view = View::new(&PinholeCamera::new(camera), camera);
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let z_ref = view.z_ref(lo, hi);
        move |triangle: &[u32; 3]| {
            let p = triangle.map(|i| view.see(mesh.positions[i as usize] - view.eye));
            scalar(&view, p, z_ref, region).expect("a fit triangle")
        }
    }

    /// `mesh` without the triangles whose plane passes through the eye, of
    /// which a frame rasterizes only a few.
    fn bounded(camera: &Camera, mut mesh: Mesh, region: &Region) -> Mesh {
        let setup = scalar_setups(camera, &mesh, region);
        let unbounded = |s: &Setup| s.kind == Kind::EdgeOn && s.screen_box() == whole(region);
        let indices = (mesh.indices.iter())
            .filter(|t| !unbounded(&setup(t)))
            .copied()
            .collect();
        drop(setup);
        mesh.indices = indices;
        mesh
    }

    #[test]
    fn a_frames_setups_are_the_scalar_ones() {
        let mut rng = Rng::new(0xf4a3e);
        let (camera, mesh) = scene(&mut rng, false);
        let region = full(&camera);
        let pinhole = PinholeCamera::new(&camera);
        let mesh = bounded(&camera, mesh, &region);
        let setup = scalar_setups(&camera, &mesh, &region);
        let objects = [Object {
            shape: Shape::Mesh(mesh.clone()),
            material: 0,
        }];
        let geometry = Geometry::new(&objects);
        let raster =
            Raster::new(&geometry, &objects, &pinhole, &camera, &region).expect("a fit frame");
        assert_eq!(raster.setups.len(), mesh.indices.len());
        let mut vouched = 0;
        for (triangle, got) in mesh.indices.iter().zip(&raster.setups) {
            assert_eq!(bits(got), bits(&setup(triangle)), "{triangle:?}");
            vouched += usize::from(got.kind == Kind::Vouched);
        }
        assert!(vouched * 5 > mesh.indices.len(), "{vouched} vouched");
    }
}

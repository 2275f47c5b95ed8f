//! The acceleration structure of the rays that are not rasterized: an
//! eight-wide compressed BVH (CWBVH, Ylitie et al. 2017) from the `obvhs`
//! crate, built in parallel once per request with its PLOC builder (the
//! quality of the build chosen by what the BVH serves, [`BvhUse`]) and
//! shared read-only by every worker.
//!
//! `obvhs` works in f32, the scene in f64. The BVH is therefore only a
//! conservative filter: it may offer a primitive the ray misses, never hide
//! one the ray hits. Three measures make that hold for any scene that
//! validation admits:
//!
//! - **A normalised space.** Bounds are recentred on the scene and scaled so
//!   that its largest extent is [`EXTENT`], whatever the scene's units or its
//!   distance from the origin, so f32 keeps ~1e-7 of the scene's size.
//! - **Padding.** Every primitive's box is rounded outwards and grown by
//!   [`PAD`] (1.5e-5 of the scene), far above the f32 error of a slab test
//!   in that space (a few 1e-4 units). The CWBVH's 8-bit child boxes are
//!   themselves quantised outwards.
//! - **Rays start at the scene.** A ray is clipped (in f64) to the padded
//!   scene box first: a ray that misses it skips the traversal, and one that
//!   hits it starts there, so an eye 1e30 away costs no f32 precision. The
//!   traversal's hard-coded minimum distance (1e-4 units) is below [`PAD`],
//!   so no box holding a hit can end before it.
//!
//! The primitive tests themselves run in f64 (see [`super::geometry`]); the
//! distance of the best hit so far shortens the f32 ray conservatively.
//!
//! Single rays (shadows, probes, the rays of a far-off eye) take the
//! crate's own traversal. Primary rays take the same tree in packets
//! ([`super::packet`]), its nodes decoded once per request into f32 boxes
//! ([`WideNode`]), rounded outwards from the exact value of each quantised
//! plane so that the decoding loses nothing of the padding.
//!
//! One case is beyond those measures: a ray whose f64 arithmetic is itself
//! coarser than the padding, because its origin is some 1e9 scene sizes
//! away (the hit points of such a ray are rounding noise at the scale of the
//! scene). The BVH then declines the ray ([`Unresolved`]) and the caller
//! tests every primitive, so that the answer is still exactly the brute
//! force one.

use std::time::Duration;

// `UVec2` is named, unqualified, by the expansion of `obvhs::traverse!`.
use glam::{DVec3, UVec2, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::ray::Ray as Ray32;

use super::geometry::Ray;

/// The largest extent of the scene in BVH space.
pub const EXTENT: f64 = 1024.0;

/// The padding of every box in BVH space: 2^-6 units, 1/65536 of
/// [`EXTENT`].
pub const PAD: f32 = 1.0 / 64.0;

/// What a BVH is built for, which sets how much time its build spends on
/// the tree's quality.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BvhUse {
    /// Every primary ray of the frame, in packets: `obvhs`'s fast build
    /// (PLOC with a short search, reinsertion of 2% of the nodes), and the
    /// nodes decoded for the packets.
    #[default]
    PrimaryRays,
    /// Only shadow rays and probes, the primary rays being rasterized: PLOC
    /// with the shortest search and no reinsertion (`obvhs`'s fast build
    /// spends most of its time reinserting nodes, sixteen passes over the
    /// tree), as Embree offers a "low quality" build for frames that trace
    /// few rays per primitive; no packet nodes.
    ShadowRays,
}

/// An axis-aligned box in f64 world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb64 {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb64 {
    pub const EMPTY: Self = Self {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    pub fn union(&self, other: &Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The interval of `t` in which `ray` is inside the box (the slab test,
    /// in f64), if it is not empty.
    fn clip(&self, ray: &Ray) -> Option<(f64, f64)> {
        let inv = ray.direction.recip();
        let t0 = (self.min - ray.origin) * inv;
        let t1 = (self.max - ray.origin) * inv;
        // A zero direction component gives ±inf or NaN (0·inf) for an
        // origin on the slab's plane; `max`/`min` of f64 ignore the NaN.
        let near = t0.min(t1).max_element();
        let far = t0.max(t1).min_element();
        let near = near.max(ray.t_min);
        let far = far.min(ray.t_max);
        (near <= far).then_some((near, far))
    }
}

/// The BVH cannot answer for a ray whose own f64 rounding exceeds its
/// padding; test every primitive instead (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unresolved;

/// A CWBVH over boxes, and the map from world space to its space.
pub struct Bvh {
    cwbvh: CwBvh,
    /// The same tree with its child boxes decoded, for packets of rays.
    wide: Vec<WideNode>,
    /// World point at the origin of BVH space.
    center: DVec3,
    /// BVH units per world unit.
    scale: f64,
    /// The padded scene box, in world space.
    bounds: Aabb64,
    /// The length of its diagonal.
    diagonal: f64,
}

impl Bvh {
    /// Builds the BVH over `boxes` (world space, not empty) for `usage`.
    pub fn build(boxes: &[Aabb64], usage: BvhUse) -> Self {
        assert!(!boxes.is_empty(), "a BVH needs at least one box");
        let whole = boxes.iter().fold(Aabb64::EMPTY, |a, b| a.union(b));
        let center = (whole.min + whole.max) * 0.5;
        let extent = (whole.max - whole.min).max_element();
        let scale = if extent > 0.0 && (EXTENT / extent).is_finite() {
            EXTENT / extent
        } else {
            1.0
        };
        let to_bvh = |p: DVec3| (p - center) * scale;
        let boxes32: Vec<Aabb> = boxes
            .iter()
            .map(|b| Aabb {
                min: round_down(to_bvh(b.min)) - PAD,
                max: round_up(to_bvh(b.max)) + PAD,
            })
            .collect();
        let cwbvh = match usage {
            BvhUse::PrimaryRays => build_cwbvh(
                &boxes32,
                BvhBuildParams::fast_build(),
                &mut Duration::default(),
            ),
            BvhUse::ShadowRays => {
                let params = BvhBuildParams::very_fast_build();
                let bvh2 = PlocBuilder::with_capacity(boxes32.len()).build(
                    PlocSearchDistance::Minimum,
                    &boxes32,
                    (0..boxes32.len() as u32).collect(),
                    SortPrecision::U64,
                    0,
                );
                // Leaves of up to three primitives, as `build_cwbvh` makes.
                bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false)
            }
        };
        // Twice the padding: every primitive's padded box lies a full PAD
        // inside this one, so a ray entering here travels at least PAD before
        // any hit (see the traversal's minimum distance in the module docs).
        let wide = match usage {
            BvhUse::PrimaryRays => cwbvh.nodes.iter().map(WideNode::decode).collect(),
            BvhUse::ShadowRays => Vec::new(),
        };
        let margin = 2.0 * f64::from(PAD) / scale;
        let bounds = Aabb64 {
            min: whole.min - margin,
            max: whole.max + margin,
        };
        Self {
            cwbvh,
            wide,
            center,
            scale,
            diagonal: (bounds.max - bounds.min).length(),
            bounds,
        }
    }

    /// The nodes decoded for packet traversal, the root first; empty for a
    /// BVH built for shadow rays.
    pub fn wide_nodes(&self) -> &[WideNode] {
        &self.wide
    }

    /// The world point at the origin of BVH space.
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// BVH units per world unit.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// `order[i]`: the index in the input boxes of the `i`-th leaf
    /// primitive, the id the traversal reports.
    pub fn primitive_order(&self) -> &[u32] {
        &self.cwbvh.primitive_indices
    }

    /// Whether the f64 rounding, within the scene, of rays from `origin`
    /// stays below a quarter of [`PAD`] (in BVH units).
    pub fn resolves(&self, origin: DVec3) -> bool {
        // A bound on the rounding error, in world units, of a point or a
        // distance along the ray inside the scene box: a few ulps of the
        // largest magnitude involved (2^-50 ≈ 8.9e-16 is four ulps).
        let reach = (origin - self.center).length() + self.diagonal;
        let rounding = (origin.abs().max_element() + reach) / (1u64 << 50) as f64;
        // Written so that a NaN (an infinite origin) is unresolved too.
        rounding * self.scale <= f64::from(PAD) / 4.0
    }

    /// The part of `ray` inside the scene box, `None` when it misses it;
    /// `Unresolved` when the ray's f64 rounding within the scene exceeds a
    /// quarter of [`PAD`].
    fn clip(&self, ray: &Ray) -> Result<Option<(f64, f64)>, Unresolved> {
        if !self.resolves(ray.origin) {
            return Err(Unresolved);
        }
        Ok(self.bounds.clip(ray))
    }

    /// The f32 ray in BVH space for the part of `ray` from `t_start`, and
    /// the map from a world distance to a conservative BVH one.
    fn bvh_ray(&self, ray: &Ray, t_start: f64, t_end: f64) -> (Ray32, impl Fn(f64) -> f32) {
        let origin = (ray.at(t_start) - self.center) * self.scale;
        let scale = self.scale;
        // A world distance t maps to (t - t_start)·scale, enlarged by a
        // relative 2^-20 and by PAD to cover the rounding of the world
        // distances and of the f32 ray.
        let to_bvh_t = move |t: f64| {
            let t = (t - t_start) * scale;
            (t * (1.0 + 1.0 / 1048576.0)) as f32 + PAD
        };
        let ray32 = Ray32::new(
            Vec3A::from(origin.as_vec3()),
            Vec3A::from(ray.direction.as_vec3()),
            0.0,
            to_bvh_t(t_end),
        );
        (ray32, to_bvh_t)
    }

    /// Offers `intersect` every primitive whose box `ray` may cross, nearest
    /// boxes first. `intersect(prim, t_max)` returns the world distance of a
    /// hit closer than `t_max`, which then shortens the ray.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        t_max: f64,
        mut intersect: impl FnMut(usize, f64) -> Option<f64>,
    ) -> Result<(), Unresolved> {
        let Some((t_start, t_end)) = self.clip(&Ray { t_max, ..*ray })? else {
            return Ok(());
        };
        let (mut ray32, to_bvh_t) = self.bvh_ray(ray, t_start, t_end);
        let mut t_max = t_max;
        let bvh = &self.cwbvh;
        let mut state = bvh.new_traversal(ray32.direction);
        let mut node;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_ray(&ray32, state.oct_inv4),
            {
                if let Some(t) = intersect(state.primitive_id as usize, t_max) {
                    t_max = t;
                    ray32.tmax = ray32.tmax.min(to_bvh_t(t));
                }
            }
        );
        Ok(())
    }

    /// Whether `hits(prim)` holds for some primitive whose box `ray` may
    /// cross within (`ray.t_min`, `ray.t_max`); stops at the first.
    #[inline]
    pub fn any(&self, ray: &Ray, mut hits: impl FnMut(usize) -> bool) -> Result<bool, Unresolved> {
        let Some((t_start, t_end)) = self.clip(ray)? else {
            return Ok(false);
        };
        let (ray32, _) = self.bvh_ray(ray, t_start, t_end);
        let bvh = &self.cwbvh;
        let mut state = bvh.new_traversal(ray32.direction);
        let mut node;
        let mut found = false;
        // The macro's primitive block runs inside an inner loop: a labelled
        // block is what stops the whole traversal.
        'traversal: {
            obvhs::traverse!(
                bvh,
                node,
                state,
                node.intersect_ray(&ray32, state.oct_inv4),
                {
                    if hits(state.primitive_id as usize) {
                        found = true;
                        break 'traversal;
                    }
                }
            );
        }
        Ok(found)
    }
}

/// A node of the CWBVH with its eight child boxes decoded to f32 (rounded
/// outwards from the exact f64 value of each quantised plane), as structure
/// of arrays: what a packet of rays tests a child at a time.
#[derive(Clone, Copy, Debug)]
pub struct WideNode {
    /// `min[axis][child]`, in BVH space.
    pub min: [[f32; 8]; 3],
    pub max: [[f32; 8]; 3],
    /// Per child: the index of an inner node, or the first primitive (in
    /// leaf order) of a leaf.
    pub index: [u32; 8],
    /// Per child: the primitives of a leaf; 0 for an inner node.
    pub count: [u8; 8],
    /// Bit `c`: child `c` exists.
    pub occupied: u8,
}

impl WideNode {
    fn decode(node: &obvhs::cwbvh::node::CwBvhNode) -> Self {
        let mut wide = Self {
            min: [[0.0; 8]; 3],
            max: [[0.0; 8]; 3],
            index: [0; 8],
            count: [0; 8],
            occupied: 0,
        };
        let origin = node.p.as_dvec3().to_array();
        let extent = node.compute_extent().as_dvec3().to_array();
        let quantised = [
            (node.child_min_x, node.child_max_x),
            (node.child_min_y, node.child_max_y),
            (node.child_min_z, node.child_max_z),
        ];
        for child in 0..8 {
            if node.is_child_empty(child) {
                continue;
            }
            wide.occupied |= 1 << child;
            for (axis, (lo, hi)) in quantised.iter().enumerate() {
                // Exact in f64: an f32, plus a power of two times a byte.
                let plane = |q: u8| origin[axis] + extent[axis] * f64::from(q);
                wide.min[axis][child] = round_down(DVec3::splat(plane(lo[child]))).x;
                wide.max[axis][child] = round_up(DVec3::splat(plane(hi[child]))).x;
            }
            if node.is_leaf(child) {
                let (first, count) = node.child_primitives(child);
                wide.index[child] = first;
                wide.count[child] = count as u8;
            } else {
                wide.index[child] = node.child_node_index(child);
            }
        }
        wide
    }
}

/// The largest f32 point at or below `p` on every axis.
fn round_down(p: DVec3) -> Vec3A {
    let q = p.as_vec3();
    let below = |q: f32, p: f64| if f64::from(q) > p { q.next_down() } else { q };
    Vec3A::new(below(q.x, p.x), below(q.y, p.y), below(q.z, p.z))
}

/// The smallest f32 point at or above `p` on every axis.
fn round_up(p: DVec3) -> Vec3A {
    let q = p.as_vec3();
    let above = |q: f32, p: f64| if f64::from(q) < p { q.next_up() } else { q };
    Vec3A::new(above(q.x, p.x), above(q.y, p.y), above(q.z, p.z))
}

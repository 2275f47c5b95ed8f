//! Lighting a hit: the surface the ray found, which side of it is lit, the
//! shadow rays, and the lighting equation of the requested precision.
//!
//! **Sides.** A ray hits the back of a surface when it arrives along its
//! front's geometric normal (`n_g · dir > 0`): the outward normal of a
//! sphere, the given normal of a plane, the counter-clockwise winding of a
//! mesh triangle (GL decides a polygon's facing by its winding, not by its
//! vertex normals). With `two_side` on, a back hit is lit as GL's back side:
//! with the back material (the request's `back_material`, else the object's
//! own material) and the negated normal. With `two_side` off GL lights every
//! polygon with its front colour and the normal as is, so a back face
//! usually gets only the ambient and emission terms; glint does the same.
//!
//! **Normals.** A sphere's is `(p − c)/r`, a plane's its given (normalised)
//! normal, a mesh's the barycentric interpolation of its vertex normals, or
//! the triangle's unit geometric normal when the mesh has none. They reach
//! the lighting equation as they are: it normalises them when the light
//! model asks for it (`normalize_normals`), as GL does.
//!
//! **Shadows** (off by default, as GL has none). A light in front of the
//! lit side sends a shadow ray from the point (the reference evaluator asks
//! only for lights that would add diffuse or specular light; the f32 kernels
//! take a mask of every light in front): towards a directional light to
//! infinity, towards a positional one up to the light.
//! The ray starts a small distance off the surface, on the light's side of
//! the geometric normal ([`SHADOW_EPSILON`] relative to the scene's and the
//! point's coordinates), so that a surface never shadows itself at the point
//! it lights. A shadowed light adds only its ambient term: GL's ambient is
//! not occluded.

use glam::{DVec3, DVec4};

use glint_lighting::kernel::{Colors, Vertices};
use glint_lighting::terms::Breakdown;
use glint_lighting::{LightMask, LightPosition, Side, SurfaceMaterial, reference, unit_or_zero};

use crate::Renderer;
use crate::film;
use crate::geometry::{Hit, Prim, Ray};
use crate::raster::{EXACT_LANES, RasterScratch};
use crate::renderer::F32Lighting;
use crate::scene::{Mesh, Shape};

/// How far a shadow ray starts off its surface, relative to the largest
/// coordinate of the scene and of the point: the f64 hit points are good to
/// about 1e-16 of those, so 1e-9 leaves a wide margin while staying far below
/// anything visible.
pub const SHADOW_EPSILON: f64 = 1e-9;

/// Where a ray met the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    pub hit: Hit,
    /// Index into the scene's objects.
    pub object: usize,
    pub point: DVec3,
    /// The front side's shading normal, as given to the lighting equation
    /// (the back side is lit with its negation).
    pub normal: DVec3,
    /// The unit geometric normal of the front side (zero for a degenerate
    /// triangle).
    pub geometric: DVec3,
    /// The side the ray arrived at.
    pub side: Side,
}

/// The unit geometric normal of triangle `triangle` of `mesh` (zero for a
/// degenerate one), by its winding.
pub(crate) fn face_normal(mesh: &Mesh, triangle: usize) -> DVec3 {
    let [p0, p1, p2] = mesh.indices[triangle].map(|i| mesh.positions[i as usize]);
    unit_or_zero((p1 - p0).cross(p2 - p0))
}

/// [`face_normal`] of each triangle of `mesh`: computed once per request
/// when every hit on a triangle and every lit corner of it needs it.
pub(crate) fn face_normals(mesh: &Mesh) -> Vec<DVec3> {
    use rayon::prelude::*;
    (0..mesh.indices.len())
        .into_par_iter()
        .map(|t| face_normal(mesh, t))
        .collect()
}

impl Renderer<'_> {
    /// The surface at `hit` of `ray`. Inlined into its callers, which build
    /// it in place: returned through memory, each of the frame's million
    /// surfaces was read back before its stores had landed.
    #[inline(always)]
    pub(crate) fn surface(&self, ray: &Ray, hit: Hit) -> Surface {
        let object = hit.object as usize;
        let point = ray.at(hit.t);
        let (normal, geometric) = match &self.scene.objects[object].shape {
            Shape::Sphere(s) => {
                let n = (point - s.center) / s.radius;
                (n, unit_or_zero(n))
            }
            Shape::Plane(p) => (p.normal, p.normal),
            Shape::Mesh(_) => {
                let normals = TriangleNormals::of(self, object, hit.triangle as usize);
                (normals.at(hit.u, hit.v), normals.geometric)
            }
        };
        let side = side_seen(geometric, ray.direction);
        Surface {
            hit,
            object,
            point,
            normal,
            geometric,
            side,
        }
    }

    /// The Gouraud colour at `hit` of `ray` on a mesh lit at its vertices:
    /// what [`Self::colors`] gives for its surface, without the rest of the
    /// surface.
    #[inline]
    pub(crate) fn gouraud(&self, vertex_colors: &VertexColors, ray: &Ray, hit: Hit) -> DVec4 {
        let object = hit.object as usize;
        let side = side_seen(
            self.face_normal(object, hit.triangle as usize),
            ray.direction,
        );
        let shape = &self.scene.objects[object].shape;
        vertex_colors.interpolate(hit, self.lit_side(side), shape)
    }

    /// The side whose colour GL uses for a surface seen from `side`.
    pub(crate) fn lit_side(&self, side: Side) -> Side {
        if self.two_side { side } else { Side::Front }
    }

    /// The material of `object`.
    fn material_of(&self, object: usize) -> &SurfaceMaterial {
        &self.scene.materials[self.scene.objects[object].material]
    }

    /// Starts the colours of a set of surfaces, each given to
    /// [`Self::color_into`], then [`Self::finish_colors`].
    pub(crate) fn begin_colors(&self, scratch: &mut LightingScratch) {
        scratch
            .batches
            .resize_with(self.scene.materials.len(), Batch::default);
        scratch.batches.iter_mut().for_each(Batch::clear);
    }

    /// The colour of `s` in the request's shading mode and precision into
    /// `colors[sample]`: an interpolated Gouraud colour or the reference
    /// evaluator's now; with an f32 kernel, once [`Self::finish_colors`]
    /// lights each material's surfaces in one batch. `rays` counts shadow
    /// rays; returns those it traced, for the surface's terms to read.
    #[inline(always)]
    pub(crate) fn color_into(
        &self,
        s: &Surface,
        sample: usize,
        colors: &mut [DVec4],
        rays: &mut u64,
        scratch: &mut LightingScratch,
    ) -> Traced {
        let object = &self.scene.objects[s.object];
        let side = self.lit_side(s.side);
        let mut traced = Traced::default();
        if let Some(vertex_colors) = &self.vertex_colors[s.object] {
            colors[sample] = vertex_colors.interpolate(s.hit, side, &object.shape);
        } else if self.f32_lighting.is_some() {
            let batch = &mut scratch.batches[object.material];
            batch.pairs.push((s.point, s.normal));
            batch.back.push(side == Side::Back);
            batch.samples.push(sample);
            if self.scene.shadows {
                let facing = match side {
                    Side::Front => s.normal,
                    Side::Back => -s.normal,
                };
                let mut shadows = Shadows::new(self, s.point, s.geometric);
                batch
                    .masks
                    .push(self.visibility_of(&mut shadows, Facing::One(facing), rays));
                traced = shadows.traced();
            }
        } else {
            let material = &self.scene.materials[object.material];
            colors[sample] = if self.scene.shadows {
                let b = self.breakdown(s, &mut traced, rays);
                b.color(
                    self.scene.lights.model.color_control,
                    material.side(side).diffuse.w,
                )
            } else {
                reference::color(&self.scene.lights, material, side, s.point, s.normal)
            };
        }
        traced
    }

    /// The colours [`Self::color_into`] left to the f32 kernel: each
    /// material's surfaces lit in one batch, into their samples of
    /// `colors`.
    pub(crate) fn finish_colors(&self, colors: &mut [DVec4], scratch: &mut LightingScratch) {
        let Some(F32Lighting {
            tier,
            kernel,
            materials,
        }) = &self.f32_lighting
        else {
            return;
        };
        let LightingScratch {
            batches,
            vertices,
            lit,
            ..
        } = scratch;
        for (material, batch) in materials.iter().zip(batches.iter_mut()) {
            if batch.samples.is_empty() {
                continue;
            }
            kernel.prepare_into(batch.pairs.iter().copied(), vertices);
            if self.scene.shadows {
                vertices.set_visibility(std::mem::take(&mut batch.masks));
            }
            kernel.light_into(*tier, material, vertices, lit);
            lit_sides(lit, &batch.back);
            for (&sample, color) in batch.samples.iter().zip(&lit.front) {
                colors[sample] = color.as_dvec4();
            }
        }
    }

    /// The colours of the samples of `rays` that the rasterizer decided,
    /// each a hit of the exact test in `exact` ([`Raster::decided_exact`]),
    /// lit per pixel by the f32 kernel in one batch of `material`, encoded
    /// into `rgba[places[j]]` for `rays[j]`: the bytes of
    /// [`Self::color_into`] and [`Self::finish_colors`] without shadows,
    /// each surface made as the kernel reads it, with no hit, surface or
    /// colour kept on the way.
    ///
    /// [`Raster::decided_exact`]: crate::raster::Raster::decided_exact
    pub(crate) fn light_decided(
        &self,
        material: usize,
        rays: &[Ray],
        exact: &RasterScratch,
        places: &[usize],
        rgba: &mut [u32],
        scratch: &mut LightingScratch,
    ) {
        let Some(lighting) = &self.f32_lighting else {
            unreachable!("decided samples are lit by an f32 kernel")
        };
        let kernel = &lighting.kernel;
        let LightingScratch {
            vertices,
            lit,
            decided,
            words,
            normals_met,
            ..
        } = scratch;
        let count = rays.len();
        // Whole groups of lanes, so that each is stored whole.
        decided.reset(count.next_multiple_of(EXACT_LANES));
        let Some(origin) = rays.first().map(|ray| ray.origin) else {
            return;
        };
        // [`Self::surface`]'s point and normal, and the lit side, of each,
        // a group of exact tests at a time: in vector lanes where the group
        // is of one triangle (a block's samples mostly are), whose normals
        // are read once for the samples that share it.
        normals_met.resize(NORMALS_CACHED, None);
        for (group, lanes) in exact.decided_lanes().enumerate() {
            let base = group * EXACT_LANES;
            let used = (count - base).min(EXACT_LANES);
            debug_assert!(
                lanes.hit[..used].iter().all(|&hit| hit),
                "every decided sample hit its triangle"
            );
            let first = lanes.prim[0];
            if lanes.prim[..used].iter().any(|&prim| prim != first) {
                for l in 0..used {
                    let normals = self.triangle_normals(normals_met, lanes.prim[l]);
                    let direction = DVec3::from_array(lanes.direction.map(|axis| axis[l]));
                    let point = origin + lanes.t[l] * direction;
                    let normal = normals.at(lanes.u[l], lanes.v[l]);
                    let seen = side_seen(normals.geometric, direction);
                    for axis in 0..3 {
                        decided.points[axis][base + l] = point[axis];
                        decided.normals[axis][base + l] = normal[axis];
                    }
                    decided.back[base + l] = self.lit_side(seen) == Side::Back;
                }
                continue;
            }
            let normals = self.triangle_normals(normals_met, first);
            let (t, u, v) = (lanes.t, lanes.u, lanes.v);
            let d = lanes.direction;
            let mut point = [[0.0; EXACT_LANES]; 3];
            let mut normal = [[0.0; EXACT_LANES]; 3];
            let mut back = [false; EXACT_LANES];
            // `Ray::at`, `TriangleNormals::at`, `side_seen` and
            // `lit_side` in lanes. (Lanes past the samples compute from
            // stale tests, into places past `count`, which nothing reads.)
            for axis in 0..3 {
                for l in 0..EXACT_LANES {
                    point[axis][l] = origin[axis] + t[l] * d[axis][l];
                }
            }
            match normals.corners {
                Some([a, b, c]) => {
                    for axis in 0..3 {
                        for l in 0..EXACT_LANES {
                            let w = 1.0 - u[l] - v[l];
                            normal[axis][l] = w * a[axis] + u[l] * b[axis] + v[l] * c[axis];
                        }
                    }
                }
                None => normal = normals.geometric.to_array().map(|g| [g; EXACT_LANES]),
            }
            for l in 0..EXACT_LANES {
                let direction = DVec3::new(d[0][l], d[1][l], d[2][l]);
                let seen = side_seen(normals.geometric, direction);
                back[l] = self.lit_side(seen) == Side::Back;
            }
            let group = base..base + EXACT_LANES;
            for axis in 0..3 {
                decided.points[axis][group.clone()].copy_from_slice(&point[axis]);
                decided.normals[axis][group.clone()].copy_from_slice(&normal[axis]);
            }
            decided.back[group].copy_from_slice(&back);
        }
        let points = [0, 1, 2].map(|axis| &decided.points[axis][..count]);
        let normals = [0, 1, 2].map(|axis| &decided.normals[axis][..count]);
        kernel.prepare_lanes(points, normals, vertices);
        let products = &lighting.materials[material];
        kernel.light_into(lighting.tier, products, vertices, lit);
        lit_sides(lit, &decided.back[..count]);
        film::encode_words(&lit.front, self.scene.encoding, words);
        for (&place, &word) in places.iter().zip(words.iter()) {
            rgba[place] = word;
        }
    }

    /// The normals of the triangle of the primitive `prim`, kept in its
    /// slot of `cache` (the index modulo its length) for the samples after
    /// it that share it.
    fn triangle_normals<'c>(
        &self,
        cache: &'c mut [Option<(u32, TriangleNormals)>],
        prim: u32,
    ) -> &'c TriangleNormals {
        let slot = &mut cache[prim as usize % cache.len()];
        if slot.as_ref().is_none_or(|(cached, _)| *cached != prim) {
            let Prim::Triangle {
                object, triangle, ..
            } = self.geometry.prims()[prim as usize]
            else {
                unreachable!("decided samples hit triangles")
            };
            *slot = Some((
                prim,
                TriangleNormals::of(self, object as usize, triangle as usize),
            ));
        }
        &slot.as_ref().expect("filled just above").1
    }

    /// The reference breakdown of the lighting at `s` (per pixel, whatever
    /// the shading mode), with its shadows: those `traced` already holds
    /// read from it, the others traced and added to it.
    pub(crate) fn breakdown(&self, s: &Surface, traced: &mut Traced, rays: &mut u64) -> Breakdown {
        let mut shadows = Shadows::resume(self, s.point, s.geometric, *traced);
        let b = breakdown_at(
            self,
            self.material_of(s.object),
            self.lit_side(s.side),
            s.point,
            s.normal,
            &mut shadows,
            rays,
        );
        *traced = shadows.traced();
        b
    }

    /// Which lights reach `point`, as a mask for the f32 kernels: a shadow
    /// ray for each light in front of the surface (see [`Facing`]); the
    /// others cannot add diffuse or specular light and keep their bit.
    pub(crate) fn visibility(
        &self,
        point: DVec3,
        geometric: DVec3,
        facing: Facing,
        rays: &mut u64,
    ) -> LightMask {
        self.visibility_of(&mut Shadows::new(self, point, geometric), facing, rays)
    }

    /// [`Self::visibility`] of the point of `shadows`, its shadow rays
    /// traced through it.
    fn visibility_of(&self, shadows: &mut Shadows, facing: Facing, rays: &mut u64) -> LightMask {
        let mut mask = LightMask::MAX;
        for (i, light) in self.scene.lights.lights().iter().enumerate() {
            let towards = match light.position {
                LightPosition::Directional(d) => d,
                LightPosition::Positional(q) => q - shadows.point,
            };
            let in_front = match facing {
                Facing::One(n) => n.dot(towards) > 0.0,
                Facing::Both(n) => n.dot(towards) != 0.0,
            };
            if in_front && !shadows.lit(i, rays) {
                mask &= !(1 << i);
            }
        }
        mask
    }
}

/// The normals of a mesh's triangle as its hits read them.
#[derive(Clone, Copy)]
struct TriangleNormals {
    /// Its corners' vertex normals; none where the mesh has none.
    corners: Option<[DVec3; 3]>,
    /// Its unit geometric normal ([`face_normal`]).
    geometric: DVec3,
}

impl TriangleNormals {
    /// Of triangle `triangle` of object `object`, a mesh.
    #[inline(always)]
    fn of(renderer: &Renderer, object: usize, triangle: usize) -> Self {
        let Shape::Mesh(mesh) = &renderer.scene.objects[object].shape else {
            unreachable!("a triangle belongs to a mesh")
        };
        let corners = mesh.indices[triangle].map(|i| i as usize);
        Self {
            corners: (mesh.normals.as_ref()).map(|n| corners.map(|i| n[i])),
            geometric: renderer.face_normal(object, triangle),
        }
    }

    /// The shading normal at the barycentrics `(u, v)` of a hit: the
    /// interpolation of the corners', else the geometric one. (The decided
    /// samples of [`Renderer::light_decided`] take the same steps in vector
    /// lanes.)
    #[inline(always)]
    fn at(&self, u: f64, v: f64) -> DVec3 {
        match self.corners {
            Some([a, b, c]) => (1.0 - u - v) * a + u * b + v * c,
            None => self.geometric,
        }
    }
}

/// The side of a surface of geometric normal `geometric` that a ray along
/// `direction` arrives at.
#[inline(always)]
fn side_seen(geometric: DVec3, direction: DVec3) -> Side {
    if geometric.dot(direction) > 0.0 {
        Side::Back
    } else {
        Side::Front
    }
}

/// Each vertex's colour of the side it is lit from into `lit.front`: the
/// back side's where `back` says so.
fn lit_sides(lit: &mut Colors, back: &[bool]) {
    for (k, _) in back.iter().enumerate().filter(|(_, back)| **back) {
        let back_colors = lit.back.as_ref();
        lit.front[k] = back_colors.expect("a two-sided kernel has back colours")[k];
    }
}

/// The buffers of [`Renderer::color_into`] and
/// [`Renderer::finish_colors`], which a worker keeps from one tile to the
/// next: memory touched for the first time is slow to write.
#[derive(Default)]
pub(crate) struct LightingScratch {
    /// Per material: its surfaces lit by an f32 kernel.
    batches: Vec<Batch>,
    vertices: Vertices,
    lit: Colors,
    /// The surfaces of [`Renderer::light_decided`], and their colours'
    /// bytes.
    decided: DecidedSurfaces,
    words: Vec<u32>,
    /// The normals of the triangles [`Renderer::light_decided`] met last,
    /// [`NORMALS_CACHED`] slots (a tile meets a handful).
    normals_met: Vec<Option<(u32, TriangleNormals)>>,
}

/// The slots of [`LightingScratch::normals_met`].
const NORMALS_CACHED: usize = 64;

/// The surfaces of [`Renderer::light_decided`]: their points and front
/// normals, an array per axis, and whether each is lit on its back side.
#[derive(Default)]
struct DecidedSurfaces {
    points: [Vec<f64>; 3],
    normals: [Vec<f64>; 3],
    back: Vec<bool>,
}

impl DecidedSurfaces {
    /// Room for `count` surfaces, each to be written: the last batch's
    /// values are kept rather than zeroed first, as every one is written
    /// before it is read.
    fn reset(&mut self, count: usize) {
        for axis in self.points.iter_mut().chain(&mut self.normals) {
            axis.resize(count, 0.0);
        }
        self.back.resize(count, false);
    }
}

/// The surfaces of one material waiting for an f32 kernel, in arrays.
#[derive(Default)]
struct Batch {
    /// Each surface's point and front normal.
    pairs: Vec<(DVec3, DVec3)>,
    /// Whether its back side is lit.
    back: Vec<bool>,
    /// The sample it colours.
    samples: Vec<usize>,
    /// With shadows, the lights that reach it.
    masks: Vec<LightMask>,
}

impl Batch {
    fn clear(&mut self) {
        self.pairs.clear();
        self.back.clear();
        self.samples.clear();
        self.masks.clear();
    }
}

/// The side (its normal) whose lights need shadow rays.
#[derive(Clone, Copy)]
pub(crate) enum Facing {
    One(DVec3),
    /// Either side of this normal: a two-sided vertex lit on both.
    Both(DVec3),
}

/// The shadow rays traced from a surface's point: bit `i` of `known` says
/// light `i`'s was traced, bit `i` of `lit` that it reached the light.
/// Lighting a sample traces them, and the terms of the same surface read
/// them rather than trace them again: the same ray from the same point, the
/// same answer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Traced {
    known: LightMask,
    lit: LightMask,
}

/// The shadow rays of one point, each traced at most once: for the
/// reference evaluator lazily (only for lights that would add diffuse or
/// specular light), for the f32 kernels' [`Renderer::visibility`] masks
/// every light in front.
pub(crate) struct Shadows<'a> {
    renderer: &'a Renderer<'a>,
    point: DVec3,
    /// The unit geometric normal at the point (zero: no offset).
    geometric: DVec3,
    traced: Traced,
}

impl<'a> Shadows<'a> {
    pub(crate) fn new(renderer: &'a Renderer<'a>, point: DVec3, geometric: DVec3) -> Self {
        Self::resume(renderer, point, geometric, Traced::default())
    }

    /// The shadows of `point` whose rays `traced` holds, traced from this
    /// point and its `geometric` normal before.
    pub(crate) fn resume(
        renderer: &'a Renderer<'a>,
        point: DVec3,
        geometric: DVec3,
        traced: Traced,
    ) -> Self {
        Self {
            renderer,
            point,
            geometric,
            traced,
        }
    }

    /// The shadow rays traced so far.
    pub(crate) fn traced(&self) -> Traced {
        self.traced
    }

    /// Whether light `i` reaches the point; always when shadows are off.
    pub(crate) fn lit(&mut self, i: usize, rays: &mut u64) -> bool {
        if !self.renderer.scene.shadows {
            return true;
        }
        // A light set holds at most one light per bit.
        let bit: LightMask = 1 << i;
        if self.traced.known & bit != 0 {
            return self.traced.lit & bit != 0;
        }
        *rays += 1;
        let position = self.renderer.scene.lights.lights()[i].position;
        let lit = !self.renderer.occluded(self.point, self.geometric, position);
        self.traced.known |= bit;
        if lit {
            self.traced.lit |= bit;
        }
        lit
    }
}

impl Renderer<'_> {
    /// Whether something lies between `point` and the light at `position`.
    fn occluded(&self, point: DVec3, geometric: DVec3, position: LightPosition) -> bool {
        // Towards the light, unnormalised: only the side of the surface it
        // points to matters here, the sign of its product with the normal.
        let towards = match position {
            LightPosition::Directional(d) => d,
            LightPosition::Positional(q) => q - point,
        };
        let scale = towards.abs().max_element();
        if !(scale > 0.0 && scale.is_finite()) {
            // The light is at the point (or beyond f64's range from it).
            return false;
        }
        let epsilon = SHADOW_EPSILON * (self.scene_scale + point.abs().max_element());
        let offset = if geometric.dot(towards) >= 0.0 {
            epsilon
        } else {
            -epsilon
        };
        let origin = point + offset * geometric;
        let ray = match position {
            LightPosition::Directional(d) => Ray::new(origin, d),
            LightPosition::Positional(q) => {
                // `Ray::new`'s normalisation, its length taken once.
                let to_light = q - origin;
                let distance = to_light.length();
                Ray {
                    origin,
                    direction: to_light * distance.recip(),
                    t_min: 0.0,
                    t_max: distance,
                }
            }
        };
        self.geometry.occluded(&ray)
    }
}

/// Colours lit at a mesh's vertices for Gouraud shading: per vertex when the
/// mesh has normals, else per corner of each triangle (with its geometric
/// normal, so each triangle is flat).
pub(crate) struct VertexColors {
    front: Vec<DVec4>,
    back: Option<Vec<DVec4>>,
    per_corner: bool,
}

impl VertexColors {
    /// Lights the vertices of `mesh` (object `object`) in parallel.
    pub(crate) fn new(renderer: &Renderer, object: usize) -> Option<Self> {
        use rayon::prelude::*;
        let Shape::Mesh(mesh) = &renderer.scene.objects[object].shape else {
            return None;
        };
        let material_index = renderer.scene.objects[object].material;
        let material = &renderer.scene.materials[material_index];
        let lights = &renderer.scene.lights;
        // The position and normal of every vertex, or of every corner.
        let corners: (Vec<DVec3>, Vec<DVec3>);
        let (positions, normals): (&[DVec3], &[DVec3]) = match &mesh.normals {
            Some(normals) => (&mesh.positions, normals),
            None => {
                corners = mesh
                    .indices
                    .par_iter()
                    .enumerate()
                    .flat_map_iter(|(t, &[a, b, c])| {
                        let n = renderer.face_normal(object, t);
                        [a, b, c].map(|i| (mesh.positions[i as usize], n))
                    })
                    .unzip();
                (&corners.0, &corners.1)
            }
        };
        let vertices = || {
            positions
                .par_iter()
                .copied()
                .zip(normals.par_iter().copied())
        };
        let per_corner = mesh.normals.is_none();
        let Some(f32_lighting) = &renderer.f32_lighting else {
            let light = |side: Side| -> Vec<DVec4> {
                vertices()
                    .map(|(p, n)| {
                        let mut rays = 0;
                        let mut shadows = Shadows::new(renderer, p, unit_or_zero(n));
                        let b =
                            breakdown_at(renderer, material, side, p, n, &mut shadows, &mut rays);
                        b.color(lights.model.color_control, material.side(side).diffuse.w)
                    })
                    .collect()
            };
            return Some(Self {
                front: light(Side::Front),
                back: renderer.two_side.then(|| light(Side::Back)),
                per_corner,
            });
        };
        let kernel = &f32_lighting.kernel;
        let mut batch = kernel.prepare(positions, normals);
        if renderer.scene.shadows {
            let facing = |n| match renderer.two_side {
                true => Facing::Both(n),
                false => Facing::One(n),
            };
            let masks = vertices().map(|(p, n)| {
                let mut rays = 0;
                renderer.visibility(p, unit_or_zero(n), facing(n), &mut rays)
            });
            batch.set_visibility(masks.collect());
        }
        let products = &f32_lighting.materials[material_index];
        let lit = kernel.light(f32_lighting.tier, products, &batch);
        let widen = |colors: Vec<glam::Vec4>| colors.par_iter().map(|c| c.as_dvec4()).collect();
        Some(Self {
            front: widen(lit.front),
            back: lit.back.map(widen),
            per_corner,
        })
    }

    /// The colour at `hit` (on one of the mesh's triangles) of `side`.
    fn interpolate(&self, hit: Hit, side: Side, shape: &Shape) -> DVec4 {
        let [a, b, c] = self.corners(hit.triangle, side, shape);
        (1.0 - hit.u - hit.v) * a + hit.u * b + hit.v * c
    }

    /// The colours of `side` at the corners of the mesh's `triangle`.
    pub(crate) fn corners(&self, triangle: u32, side: Side, shape: &Shape) -> [DVec4; 3] {
        let colors = match side {
            Side::Back => self.back.as_ref().unwrap_or(&self.front),
            Side::Front => &self.front,
        };
        let t = triangle as usize;
        let corners = if self.per_corner {
            [3 * t, 3 * t + 1, 3 * t + 2]
        } else {
            let Shape::Mesh(mesh) = shape else {
                unreachable!("vertex colours belong to meshes")
            };
            mesh.indices[t].map(|i| i as usize)
        };
        corners.map(|i| colors[i])
    }
}

/// The reference breakdown at `point` with `normal` on `material`, with
/// shadowed lights' diffuse and specular terms removed.
fn breakdown_at(
    renderer: &Renderer,
    material: &SurfaceMaterial,
    side: Side,
    point: DVec3,
    normal: DVec3,
    shadows: &mut Shadows,
    rays: &mut u64,
) -> Breakdown {
    let mut b = reference::evaluate(&renderer.scene.lights, material, side, point, normal);
    for (i, terms) in b.lights.iter_mut().enumerate() {
        let adds_light = terms.diffuse != DVec3::ZERO || terms.specular != DVec3::ZERO;
        if adds_light && !shadows.lit(i, rays) {
            terms.diffuse = DVec3::ZERO;
            terms.specular = DVec3::ZERO;
        }
    }
    b
}

//! The [`Renderer`]: a scene prepared once per request, and its image
//! rendered in tiles on the rayon pool: uniform or adaptive samples, found
//! by the rasterizer or the tracer, lit in batches.

use std::mem::MaybeUninit;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec3, DVec4};
use rayon::prelude::*;

use glint_lighting::Side;
use glint_lighting::kernel::{Kernel, MaterialProducts, Tier};
use glint_lighting::terms::{Breakdown, ColorStat, FactorStat, LightSummary, Summary};

use crate::bvh::BvhUse;
use crate::camera::PinholeCamera;
use crate::film::{self, Moments, SamplePattern, SetMoments};
use crate::geometry::{Geometry, Hit, Prim, Ray};
use crate::hit_lighting::{self, LightingScratch, Surface, Traced, VertexColors};
use crate::packet::Packets;
use crate::raster::{LANE_MASK, LANES, Raster, RasterScratch};
use crate::raster_gouraud::{self, Corners};
use crate::scene::{Region, RenderScene, Samples, ShadingMode, Shape};

/// The side of a tile, in pixels.
pub const TILE: u32 = 16;

/// The side of the blocks of pixels whose rays are traced together.
pub const BLOCK: u32 = 4;

/// The triangles a worker keeps ready for their Gouraud pixels (see
/// [`Renderer::gouraud_tile`]): a neighbouring tile meets many of the same.
const CORNERS_CACHED: usize = 256;

/// How primary visibility is found: the same hits either way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Visibility {
    /// Rasterized ([`crate::raster`]) where the scene allows it, else
    /// traced.
    #[default]
    Rasterized,
    /// Traced through the BVH, in packets ([`crate::packet`]).
    Traced,
}

/// A scene prepared for rendering: built once per request, shared
/// read-only by the workers.
pub struct Renderer<'s> {
    pub(crate) scene: &'s RenderScene,
    /// The sampling carried out ([`Samples::effective`] of the scene's).
    samples: Samples,
    pub(crate) camera: PinholeCamera,
    pub(crate) geometry: Geometry,
    /// The rasterizer of the primary rays, when the scene allows it.
    pub(crate) raster: Option<Raster>,
    /// One sample's bytes straight from the rasterizer's decisions, when
    /// every pixel is one Gouraud-shaded sample of a mesh, linearly
    /// encoded (see [`raster_gouraud`]).
    gouraud_bytes: Option<raster_gouraud::BytesFn>,
    /// Else, one sample per pixel of a scene of meshes alone: the samples
    /// the rasterizer decides take the exact test on its triangle alone,
    /// without the rest of a traced sample's search (see
    /// [`Self::centres_tile`]).
    decided_centres: bool,
    /// With decided centres lit per pixel by an f32 kernel, without
    /// shadows, every object of one material: that material, in whose one
    /// batch a tile's decided samples are lit straight from their exact
    /// tests ([`Self::light_decided`]).
    lit_decided: Option<usize>,
    /// Else the packet tracer of the primary rays, when the eye allows it.
    pub(crate) packets: Option<Packets>,
    /// The light set prepared for the f32 tier of the request's precision,
    /// with each material's products; `None` for the reference.
    pub(crate) f32_lighting: Option<F32Lighting>,
    /// Per object: the Gouraud colours of a mesh in per-vertex mode.
    pub(crate) vertex_colors: Vec<Option<VertexColors>>,
    /// Per object: a mesh's unit geometric normal of each triangle (see
    /// [`hit_lighting::face_normals`]), empty for other shapes. Built with
    /// the renderer, but not where the frame's pixels are Gouraud bytes,
    /// which read a normal only at the pixels the rasterizer leaves
    /// undecided, nor where its decided samples are lit in one batch
    /// (`lit_decided`), which compute each triangle's normal once for the
    /// samples of a tile that share it: for `render_mesa`'s sphere of 10^6
    /// triangles, half of them behind the other half, the table took 4–5
    /// ms of a 40–45 ms build (see [`Self::face_normal`]). Those frames
    /// build it when they ask for the terms, every pixel of which reads
    /// one.
    face_normals: OnceLock<Vec<Vec<DVec3>>>,
    /// Where uniform samples go.
    pub(crate) pattern: SamplePattern,
    /// Where the full sets of adaptive samples go.
    pub(crate) set_pattern: SamplePattern,
    /// The light model is two-sided: back faces take the back material.
    pub(crate) two_side: bool,
    /// The largest coordinate of the shapes and the eye: the scale of the
    /// scene's rounding errors (see [`hit_lighting::SHADOW_EPSILON`]).
    pub(crate) scene_scale: f64,
    pub(crate) build_time: Duration,
    /// The time to light the Gouraud vertex colours, counted as rendering.
    pub(crate) vertex_time: Duration,
    pub(crate) rays: AtomicU64,
}

/// The request's light set prepared for an f32 tier, and each material's
/// colour products under it.
pub(crate) struct F32Lighting {
    pub tier: Tier,
    pub kernel: Kernel,
    /// In the order of [`RenderScene::materials`].
    pub materials: Vec<MaterialProducts>,
}

/// A rendered image (of the region) and what was learnt on the way.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row by row from the top.
    pub rgba: Vec<u8>,
    /// The term statistics over every pixel whose centre ray hit something,
    /// when asked for.
    pub summary: Option<Summary>,
    pub sampling: SamplingStats,
    pub render_time: Duration,
}

/// What the sampling did over the image (of the region).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingStats {
    /// Samples averaged into a pixel (a corner of adaptive sampling counts
    /// for each of its four pixels): the mean over the pixels and the most.
    pub mean: f64,
    pub max: u32,
    /// The root mean square, over the pixels, of the estimated standard
    /// error of each pixel's colour (its largest channel's); `None` with
    /// one sample per pixel, which gives no estimate.
    pub estimated_error: Option<f64>,
}

/// The sampling of some pixels, added up.
#[derive(Clone, Copy, Debug, Default)]
struct SampleRecord {
    pixels: u64,
    samples: u64,
    max: u32,
    /// The squared errors' sum, over the pixels that have an estimate.
    squared_error: f64,
    estimated: u64,
    /// The rays traced or found by the rasterizer for these pixels (added
    /// to the renderer's count once per frame: a count shared by the
    /// workers, written per tile, would move its cache line between them).
    rays: u64,
}

impl SampleRecord {
    /// One pixel of `samples` samples and its estimated error.
    fn add(&mut self, samples: u32, error: Option<f64>) {
        self.pixels += 1;
        self.samples += u64::from(samples);
        self.max = self.max.max(samples);
        if let Some(error) = error {
            self.squared_error += error * error;
            self.estimated += 1;
        }
    }

    /// `pixels` pixels of one sample each.
    fn add_single(&mut self, pixels: u64) {
        self.pixels += pixels;
        self.samples += pixels;
        self.max = self.max.max(u32::from(pixels > 0));
    }

    fn merge(&mut self, other: &Self) {
        self.pixels += other.pixels;
        self.samples += other.samples;
        self.max = self.max.max(other.max);
        self.squared_error += other.squared_error;
        self.estimated += other.estimated;
        self.rays += other.rays;
    }

    fn stats(&self) -> SamplingStats {
        SamplingStats {
            mean: self.samples as f64 / self.pixels.max(1) as f64,
            max: self.max,
            estimated_error: (self.estimated > 0 && self.estimated == self.pixels)
                .then(|| (self.squared_error / self.estimated as f64).sqrt()),
        }
    }
}

/// The centre ray of one pixel, explained.
#[derive(Clone, Debug)]
pub struct Probe {
    pub pixel: [u32; 2],
    pub surface: Option<Surface>,
    /// The colour of the centre sample (the background for a miss), in the
    /// request's shading mode and precision.
    pub color: DVec4,
    /// The reference breakdown of the lighting at the hit point (per pixel,
    /// whatever the shading mode); `None` for a miss.
    pub breakdown: Option<Breakdown>,
}

impl<'s> Renderer<'s> {
    /// Prepares `scene`: sets up the rasterizer of the primary rays (or,
    /// where it cannot serve, the BVH and packets), the BVH for shadow
    /// rays, the lighting kernels and, for Gouraud shading, the vertex
    /// colours.
    pub fn new(scene: &'s RenderScene) -> Self {
        Self::with_visibility(scene, Visibility::default())
    }

    /// [`Self::new`], finding primary visibility as `visibility` says.
    pub fn with_visibility(scene: &'s RenderScene, visibility: Visibility) -> Self {
        let started = Instant::now();
        let geometry = Geometry::new(&scene.objects);
        let camera = PinholeCamera::new(&scene.camera);
        let eye = scene.camera.eye;
        let bounds = geometry.bounds();
        // The kernels recentre on the scene and the eye, never on the region,
        // so that a region renders exactly the pixels of the whole image.
        let extent = if bounds.min.x <= bounds.max.x {
            vec![bounds.min, bounds.max, eye]
        } else {
            vec![eye]
        };
        let scene_scale = extent
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f64::max);
        // The lights once, then each material's colours under them.
        let f32_lighting = scene.precision.tier().map(|tier| {
            let kernel = Kernel::new(&scene.lights, &extent);
            let materials = scene.materials.iter().map(|m| kernel.products(m)).collect();
            F32Lighting {
                tier,
                kernel,
                materials,
            }
        });
        let raster = match visibility {
            Visibility::Rasterized => Raster::new(
                &geometry,
                &scene.objects,
                &camera,
                &scene.camera,
                &scene.region,
            )
            .ok(),
            Visibility::Traced => None,
        };
        // Rasterized primary rays leave the BVH only shadow rays and probes.
        if scene.shadows || raster.is_none() {
            geometry.build_bvh(bvh_use(&raster));
        }
        let packets = match raster {
            Some(_) => None,
            None => Packets::new(&geometry, eye),
        };
        let samples = scene.samples.effective();
        let only_meshes = scene
            .objects
            .iter()
            .all(|o| matches!(o.shape, Shape::Mesh(_)));
        let gouraud_bytes = (raster.is_some()
            && samples == Samples::Uniform(1)
            && scene.shading == ShadingMode::PerVertex
            && only_meshes
            && raster_gouraud::applies(scene.encoding))
        .then(raster_gouraud::dispatch);
        let decided_centres = raster.is_some() && samples == Samples::Uniform(1) && only_meshes;
        let one_material = (scene.objects.first().map(|o| o.material))
            .filter(|&m| scene.objects.iter().all(|o| o.material == m));
        let lit_decided = one_material.filter(|_| {
            decided_centres
                && f32_lighting.is_some()
                && !scene.shadows
                && scene.shading == ShadingMode::PerPixel
        });
        let face_normals = OnceLock::new();
        if gouraud_bytes.is_none() && lit_decided.is_none() {
            face_normals.get_or_init(|| face_normal_table(scene));
        }
        let mut renderer = Self {
            scene,
            samples,
            camera,
            geometry,
            gouraud_bytes,
            decided_centres,
            lit_decided,
            raster,
            packets,
            f32_lighting,
            vertex_colors: Vec::new(),
            face_normals,
            pattern: SamplePattern::new(match samples {
                Samples::Uniform(n) => n,
                Samples::Adaptive { .. } => 1,
            }),
            set_pattern: SamplePattern::new(film::SET),
            two_side: scene.lights.model.two_side,
            scene_scale,
            build_time: Duration::ZERO,
            vertex_time: Duration::ZERO,
            rays: AtomicU64::new(0),
        };
        renderer.build_time = started.elapsed();
        let lighting_vertices = Instant::now();
        renderer.vertex_colors = (0..scene.objects.len())
            .map(|i| {
                (scene.shading == ShadingMode::PerVertex)
                    .then(|| VertexColors::new(&renderer, i))
                    .flatten()
            })
            .collect();
        renderer.vertex_time = lighting_vertices.elapsed();
        renderer
    }

    /// The time to build the geometry, the BVH, the kernels and the meshes'
    /// face normals.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// [`hit_lighting::face_normal`] of triangle `triangle` of mesh
    /// `object`: from the table when the frame has one.
    #[inline]
    pub(crate) fn face_normal(&self, object: usize, triangle: usize) -> DVec3 {
        match self.face_normals.get() {
            Some(table) => table[object][triangle],
            None => {
                let Shape::Mesh(mesh) = &self.scene.objects[object].shape else {
                    unreachable!("face normals belong to meshes")
                };
                hit_lighting::face_normal(mesh, triangle)
            }
        }
    }

    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// The closest hit of each of `rays` into `hits` when the primary rays
    /// are traced, not rasterized: in packets for rays from the eye (see
    /// [`packet`]), else one by one; the same hits either way. Rays that
    /// are neighbours in `rays` should be neighbours in the image.
    fn primary_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        match &self.packets {
            Some(packets) => packets.trace(&self.geometry, rays, hits),
            None => {
                for (ray, hit) in rays.iter().zip(hits) {
                    *hit = self.geometry.closest_hit(ray);
                }
            }
        }
    }

    /// Every ray traced so far: primary, centre (for the terms), shadow and
    /// probe rays.
    pub fn rays(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Renders the scene's region in tiles on the current rayon pool; with
    /// `with_terms` also the term statistics over the pixels' centre rays.
    /// `None` when `cancelled` turned true before the last tile.
    pub fn render(&self, with_terms: bool, cancelled: &(dyn Fn() -> bool + Sync)) -> Option<Frame> {
        let started = Instant::now();
        if with_terms {
            // Every pixel of a frame with terms reads its normal (see
            // `face_normals`).
            self.face_normals
                .get_or_init(|| face_normal_table(self.scene));
        }
        if with_terms && !self.samples_hold_centres() {
            // The centre rays of the terms are traced one by one, inside
            // the tiles' tasks: the BVH must exist before they start.
            self.geometry.build_bvh(bvh_use(&self.raster));
        }
        let region = self.scene.region;
        let (width, height) = (region.width as usize, region.height as usize);
        let row_bytes = width * 4;
        let len = row_bytes * height;
        // A band of the image: a tile's height of rows. (`max(1)`: a region
        // without width has no rows, but chunks need a size.)
        let band_bytes = (row_bytes * TILE as usize).max(1);
        // The image zeroed in parallel, a band per task: `vec!` would zero
        // the memory it reuses on this thread, before any tile (about a
        // twentieth of a 10,000-triangle frame's samples). Fresh memory is
        // first touched in those bands too, in parallel (a first touch
        // costs about 1 ms per MB, as the operating system maps each page
        // in).
        let mut rgba: Vec<u8> = Vec::with_capacity(len);
        rgba.spare_capacity_mut()[..len]
            .par_chunks_mut(band_bytes)
            .for_each(|band| band.fill(MaybeUninit::new(0)));
        // SAFETY: the bands cover the `len` bytes, each just written.
        unsafe { rgba.set_len(len) };
        // Each tile's rows of the image, which its worker writes in place:
        // no copy afterwards.
        let mut tiles: Vec<(Rect, Vec<&mut [u8]>)> = Vec::new();
        for (band, rows) in rgba.chunks_mut(band_bytes).enumerate() {
            let y0 = region.y + band as u32 * TILE;
            let first = tiles.len();
            tiles.extend(
                (region.x..region.x + region.width)
                    .step_by(TILE as usize)
                    .map(|x0| {
                        let rect = Rect {
                            x0,
                            y0,
                            x1: (x0 + TILE).min(region.x + region.width),
                            y1: (y0 + TILE).min(region.y + region.height),
                        };
                        (rect, Vec::with_capacity(TILE as usize))
                    }),
            );
            for row in rows.chunks_mut(row_bytes) {
                for (k, piece) in row.chunks_mut(TILE as usize * 4).enumerate() {
                    tiles[first + k].1.push(piece);
                }
            }
        }
        let mut record = SampleRecord::default();
        let edges = match self.samples {
            Samples::Adaptive { .. } => {
                let rects: Vec<Rect> = tiles.iter().map(|(rect, _)| *rect).collect();
                Some(self.edge_corners(&rects, &mut record, cancelled)?)
            }
            Samples::Uniform(_) => None,
        };
        // Each tile's result in its place (a cancelled tile's `None`): a
        // collect into `Option` would gather them in pieces, then move
        // them into one vector on this thread.
        let results: Vec<Option<(Option<Summary>, SampleRecord)>> = tiles
            .into_par_iter()
            .map_init(TileScratch::default, |scratch, (rect, mut rows)| {
                (!cancelled())
                    .then(|| self.render_tile(rect, with_terms, edges.as_ref(), scratch, &mut rows))
            })
            .collect();
        // Merged tile by tile in image order.
        let mut summary = None;
        for result in results {
            let (tile_summary, tile_record) = result?;
            record.merge(&tile_record);
            summary = match (summary, tile_summary) {
                (Some(a), Some(b)) => Some(merge(a, b)),
                (a, b) => a.or(b),
            };
        }
        self.rays.fetch_add(record.rays, Ordering::Relaxed);
        Some(Frame {
            width: region.width,
            height: region.height,
            rgba,
            summary,
            sampling: record.stats(),
            render_time: started.elapsed() + self.vertex_time,
        })
    }

    /// Renders one tile into `rows`, the tile's rows of the image (RGBA8),
    /// each pixel the mean of its samples (see [`film`] for where they lie
    /// and, with adaptive sampling, how many there are). Returns the
    /// summary of the terms, when asked for, and what the sampling did.
    fn render_tile(
        &self,
        rect: Rect,
        with_terms: bool,
        edges: Option<&EdgeCorners>,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
    ) -> (Option<Summary>, SampleRecord) {
        let mut rays = 0;
        let mut record = SampleRecord::default();
        match self.samples {
            Samples::Uniform(1) if !with_terms && self.gouraud_bytes.is_some() => {
                self.gouraud_tile(rect, scratch, rows, &mut rays, &mut record)
            }
            Samples::Uniform(1) if self.decided_centres => {
                self.centres_tile(rect, with_terms, scratch, rows, &mut rays, &mut record)
            }
            Samples::Uniform(n) => {
                self.uniform_tile(rect, n, with_terms, scratch, rows, &mut rays, &mut record)
            }
            Samples::Adaptive { max, tolerance } => {
                let edges = edges.expect("adaptive sampling traces the tiles' edges first");
                self.adaptive_tile(
                    rect,
                    max,
                    tolerance,
                    with_terms,
                    edges,
                    scratch,
                    rows,
                    &mut rays,
                    &mut record,
                )
            }
        }
        let mut breakdowns = Vec::new();
        if with_terms {
            // Per pixel (row by row), the surface of its centre ray and the
            // shadow rays its colour traced, when the samples have them.
            let mut centres = if self.samples_hold_centres() {
                std::mem::take(&mut scratch.centres)
            } else {
                Vec::new()
            };
            let width = (rect.x1 - rect.x0) as usize;
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let pixel = (y - rect.y0) as usize * width + (x - rect.x0) as usize;
                    let centre = match centres.get(pixel) {
                        Some(centre) => *centre,
                        None => {
                            rays += 1;
                            let ray = self.camera.centre_ray(x, y);
                            self.geometry
                                .closest_hit(&ray)
                                .map(|hit| (self.surface(&ray, hit), Traced::default()))
                        }
                    };
                    breakdowns.extend(
                        centre.map(|(s, mut traced)| self.breakdown(&s, &mut traced, &mut rays)),
                    );
                }
            }
            // Back for the next tile's, emptied: a tile's terms never read
            // another's centres.
            centres.clear();
            scratch.centres = centres;
        }
        record.rays = rays;
        (Summary::of(&breakdowns), record)
    }

    /// Whether each pixel's samples include its centre (one uniform sample,
    /// or adaptive sampling's first samples): the terms then read the
    /// centre's surface and shadow rays from its sample.
    fn samples_hold_centres(&self) -> bool {
        !matches!(self.samples, Samples::Uniform(n) if n > 1)
    }

    /// `samples` samples in every pixel of the tile. With `centres`, one
    /// sample's surface (the centre ray's) per pixel into `scratch.centres`.
    #[allow(clippy::too_many_arguments)]
    fn uniform_tile(
        &self,
        rect: Rect,
        samples: u32,
        centres: bool,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
        rays: &mut u64,
        record: &mut SampleRecord,
    ) {
        let (width, height) = rect.size();
        let centres = centres && samples == 1;
        self.sample_points(rect, samples, scratch);
        self.trace_samples(rect, centres, scratch, rays);
        if centres {
            scratch.keep_centres(width * height, |scratch, k| {
                let (row, column) = scratch.order[k];
                Some(row * width + column)
            });
        }
        let n = samples as usize;
        if n == 1 {
            record.add_single(scratch.order.len() as u64);
        }
        for (&(row, column), colors) in scratch
            .order
            .iter()
            .zip(scratch.sample_colors.chunks_exact(n))
        {
            let color = match colors {
                // One sample is its own mean (a sum of one, divided by
                // one), with no error estimated (counted above).
                [color] => *color,
                _ => {
                    let moments = Moments::of(colors);
                    record.add(samples, Some(moments.standard_error()));
                    moments.mean()
                }
            };
            rows[row][column * 4..column * 4 + 4]
                .copy_from_slice(&film::encode(color, self.scene.encoding));
        }
    }

    /// The points of `samples` samples in every pixel of the tile into
    /// `scratch.points`: the pixels in blocks of 4×4, so that the samples
    /// evaluated together cover a small square of the image, each pixel's
    /// samples together; `scratch.order[j]`: the pixel of the `j`-th
    /// samples, as its row and column in the tile.
    fn sample_points(&self, rect: Rect, samples: u32, scratch: &mut TileScratch) {
        if samples == 1 {
            self.centre_order(rect, scratch);
            let (x0, y0) = (f64::from(rect.x0) + 0.5, f64::from(rect.y0) + 0.5);
            scratch.points.clear();
            scratch.points.extend(
                scratch
                    .order
                    .iter()
                    .map(|&(row, column)| (x0 + column as f64, y0 + row as f64)),
            );
            return;
        }
        scratch.order_size = None;
        scratch.order.clear();
        scratch.points.clear();
        for by in (rect.y0..rect.y1).step_by(BLOCK as usize) {
            for bx in (rect.x0..rect.x1).step_by(BLOCK as usize) {
                for y in by..(by + BLOCK).min(rect.y1) {
                    for x in bx..(bx + BLOCK).min(rect.x1) {
                        scratch
                            .order
                            .push(((y - rect.y0) as usize, (x - rect.x0) as usize));
                        for k in 0..samples {
                            let (ox, oy) = self.pattern.offset(x, y, k);
                            scratch.points.push((f64::from(x) + ox, f64::from(y) + oy));
                        }
                    }
                }
            }
        }
    }

    /// [`Self::centre_order`] of the tile; whether its chunks are whole
    /// blocks (each [`LANES`] of the order one 4×4 block, row by row).
    fn centre_blocks(&self, rect: Rect, scratch: &mut TileScratch) -> bool {
        self.centre_order(rect, scratch);
        let (width, height) = rect.size();
        width % BLOCK as usize == 0 && height % BLOCK as usize == 0
    }

    /// The pixels of the tile in the order of [`Self::sample_points`] into
    /// `scratch.order`, kept from one tile of the same size to the next.
    fn centre_order(&self, rect: Rect, scratch: &mut TileScratch) {
        let size = rect.size();
        if scratch.order_size == Some(size) {
            return;
        }
        scratch.order_size = Some(size);
        scratch.order.clear();
        for by in (0..size.1).step_by(BLOCK as usize) {
            for bx in (0..size.0).step_by(BLOCK as usize) {
                for row in by..(by + BLOCK as usize).min(size.1) {
                    scratch.order.extend(
                        (bx..(bx + BLOCK as usize).min(size.0)).map(|column| (row, column)),
                    );
                }
            }
        }
    }

    /// One Gouraud-shaded sample in every pixel of the tile, the bytes of
    /// the pixels the rasterizer decides computed from its decision
    /// ([`raster_gouraud`]), the others traced: the bytes of
    /// [`Self::uniform_tile`].
    fn gouraud_tile(
        &self,
        rect: Rect,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
        rays: &mut u64,
        record: &mut SampleRecord,
    ) {
        let (Some(raster), Some(bytes_of)) = (&self.raster, self.gouraud_bytes) else {
            unreachable!("a Gouraud tile is rasterized")
        };
        let blocks = self.centre_blocks(rect, scratch);
        let TileScratch {
            order,
            pending,
            corners,
            tile_rgba,
            raster: raster_scratch,
            ..
        } = scratch;
        // The tile's bytes in the order's places, chunk by chunk, then
        // copied to the rows: the background's where the rasterizer finds
        // nothing, as every place starts.
        let background =
            u32::from_le_bytes(film::encode(self.scene.background, self.scene.encoding));
        pending.clear();
        corners.resize(CORNERS_CACHED, None);
        tile_rgba.clear();
        tile_rgba.resize(order.len().next_multiple_of(LANES), background);
        let mut samples = raster_gouraud::Samples::default();
        let decisions = raster.decide_centres((rect.x0, rect.y0), order, blocks, raster_scratch);
        let (x0, y0) = (f64::from(rect.x0) + 0.5, f64::from(rect.y0) + 0.5);
        for ((chunk, decided), out) in decisions.enumerate().zip(tile_rgba.chunks_exact_mut(LANES))
        {
            let base = chunk * LANES;
            pending.extend(set_lanes(decided.undecided).map(|l| base + l));
            let mut todo = decided.triangle;
            if todo == 0 {
                continue;
            }
            if blocks {
                let (row, column) = order[base];
                let side = BLOCK as usize;
                for l in 0..LANES {
                    samples.x[l] = x0 + (column + l % side) as f64;
                    samples.y[l] = y0 + (row + l / side) as f64;
                }
            } else {
                for l in 0..LANES {
                    // Lanes past the end repeat the last sample.
                    let (row, column) = order[(base + l).min(order.len() - 1)];
                    samples.x[l] = x0 + column as f64;
                    samples.y[l] = y0 + row as f64;
                }
            }
            let out: &mut [u32; LANES] = out.try_into().expect("a chunk's lanes");
            while todo != 0 {
                let (setup, mask) = raster_gouraud::next_triangle(&decided.best, todo);
                todo &= !mask;
                let slot = &mut corners[setup as usize % CORNERS_CACHED];
                let triangle = match slot {
                    Some((cached, triangle)) if *cached == setup => triangle,
                    _ => &slot.insert((setup, self.corners(raster, setup))).1,
                };
                let sure = bytes_of(triangle, &samples, mask, out);
                pending.extend(set_lanes(mask & !sure).map(|l| base + l));
            }
        }
        write_rows(order, tile_rgba, blocks, rows);
        // Every pixel's centre ray counts, found by the rasterizer or traced.
        *rays += (order.len() - pending.len()) as u64;
        record.add_single(order.len() as u64);
        if pending.is_empty() {
            return;
        }
        scratch.points.clear();
        scratch.points.extend(scratch.pending.iter().map(|&k| {
            let (row, column) = scratch.order[k];
            (x0 + column as f64, y0 + row as f64)
        }));
        self.trace_samples(rect, false, scratch, rays);
        for (&k, &color) in scratch.pending.iter().zip(&scratch.sample_colors) {
            let (row, column) = scratch.order[k];
            rows[row][column * 4..column * 4 + 4]
                .copy_from_slice(&film::encode(color, self.scene.encoding));
        }
    }

    /// One sample at the centre of every pixel of the tile in a scene of
    /// meshes: where the rasterizer decides its triangle
    /// ([`Raster::decide_centres`]), the sample's hit is the exact test on
    /// that triangle alone, and the others are traced. The bytes, and with
    /// `centres` the surfaces, of [`Self::uniform_tile`].
    fn centres_tile(
        &self,
        rect: Rect,
        centres: bool,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
        rays: &mut u64,
        record: &mut SampleRecord,
    ) {
        let Some(raster) = &self.raster else {
            unreachable!("decided centres are rasterized")
        };
        let blocks = self.centre_blocks(rect, scratch);
        let TileScratch {
            order,
            pending,
            points,
            primary,
            hits,
            decided_setups,
            traced_samples,
            tile_rgba,
            lighting,
            raster: raster_scratch,
            ..
        } = scratch;
        let corner = (rect.x0, rect.y0);
        // The decided samples (places in `order`) and their triangles,
        // then the undecided ones, which `traced_samples` goes on with.
        traced_samples.clear();
        decided_setups.clear();
        pending.clear();
        for (chunk, decided) in raster
            .decide_centres(corner, order, blocks, raster_scratch)
            .enumerate()
        {
            let base = chunk * LANES;
            if decided.triangle == LANE_MASK {
                // Most chunks: copied whole, not lane by lane.
                traced_samples.extend(base..base + LANES);
                decided_setups.extend_from_slice(&decided.best);
            } else {
                for lane in set_lanes(decided.triangle) {
                    traced_samples.push(base + lane);
                    decided_setups.push(decided.best[lane]);
                }
            }
            pending.extend(set_lanes(decided.undecided).map(|lane| base + lane));
        }
        let decided = traced_samples.len();
        traced_samples.extend_from_slice(pending);
        let (x0, y0) = (f64::from(rect.x0) + 0.5, f64::from(rect.y0) + 0.5);
        points.clear();
        points.extend(traced_samples.iter().map(|&k| {
            let (row, column) = order[k];
            (x0 + column as f64, y0 + row as f64)
        }));
        self.camera.rays_into(points, primary);
        // Every pixel's centre ray counts, decided or traced.
        *rays += order.len() as u64;
        // The background's bytes where no sample is traced, as every place
        // starts.
        let encoding = self.scene.encoding;
        let background = u32::from_le_bytes(film::encode(self.scene.background, encoding));
        tile_rgba.clear();
        tile_rgba.resize(order.len(), background);
        // The decided samples lit in one batch as their exact tests find
        // them, where they can be; else their hits lit with the others'.
        let decided_lit = match self.lit_decided {
            Some(material)
                if !centres
                    && raster.decided_exact(
                        &self.geometry,
                        &primary[..decided],
                        decided_setups,
                        raster_scratch,
                    ) =>
            {
                self.light_decided(
                    material,
                    &primary[..decided],
                    raster_scratch,
                    &traced_samples[..decided],
                    tile_rgba,
                    lighting,
                );
                true
            }
            _ => false,
        };
        // The hits to light, those of the last samples: the traced
        // samples', after the decided samples' unless those are lit
        // already.
        let first = if decided_lit { decided } else { 0 };
        hits.clear();
        hits.resize(primary.len() - first, None);
        let (decided_hits, traced_hits) = hits.split_at_mut(decided - first);
        if !decided_lit {
            raster.decided_hits(
                &self.geometry,
                corner,
                &primary[..decided],
                decided_setups,
                decided_hits,
                raster_scratch,
            );
        }
        if !traced_hits.is_empty() {
            raster.hits(
                &self.geometry,
                corner,
                &points[decided..],
                &primary[decided..],
                traced_hits,
                raster_scratch,
            );
        }
        self.light_hits(centres, scratch, rays);
        let TileScratch {
            order,
            traced_samples,
            sample_colors,
            tile_rgba,
            ..
        } = scratch;
        for (&k, &color) in traced_samples[first..].iter().zip(sample_colors.iter()) {
            tile_rgba[k] = u32::from_le_bytes(film::encode(color, encoding));
        }
        write_rows(order, tile_rgba, blocks, rows);
        record.add_single(order.len() as u64);
        if centres {
            let (width, height) = rect.size();
            scratch.keep_centres(width * height, |scratch, j| {
                let (row, column) = scratch.order[scratch.traced_samples[j]];
                Some(row * width + column)
            });
        }
    }

    /// The triangle of the rasterizer's vouched setup `setup` and the
    /// Gouraud colours of its corners, on the side the eye sees (see
    /// [`Raster::front_faces_eye`]): that of every ray the rasterizer
    /// vouches it for.
    fn corners(&self, raster: &Raster, setup: u32) -> Corners {
        let Prim::Triangle {
            object,
            triangle,
            p0,
            p1,
            p2,
        } = self.geometry.prims()[setup as usize]
        else {
            unreachable!("setups are triangles")
        };
        let object = object as usize;
        let side = if raster.front_faces_eye(setup) {
            Side::Front
        } else {
            Side::Back
        };
        let Some(vertex_colors) = &self.vertex_colors[object] else {
            unreachable!("every object of a Gouraud tile is a mesh with its colours")
        };
        let shape = &self.scene.objects[object].shape;
        Corners::new(
            raster.exact_edges([p0, p1, p2]),
            vertex_colors.corners(triangle, self.lit_side(side), shape),
        )
    }

    /// The colours of the corners on the tiles' edges (see
    /// [`EdgeCorners`]), each traced once, by the tile that owns it.
    fn edge_corners(
        &self,
        tiles: &[Rect],
        record: &mut SampleRecord,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Option<EdgeCorners> {
        let mut edges = EdgeCorners::new(self.scene.region);
        // Per tile, its corners and their colours.
        let traced = tiles
            .par_iter()
            .map_init(TileScratch::default, |scratch, &rect| {
                (!cancelled()).then(|| {
                    let mut rays = 0;
                    scratch.points.clear();
                    edges.owned(rect, &mut scratch.points);
                    self.trace_samples(rect, false, scratch, &mut rays);
                    (scratch.points.clone(), scratch.sample_colors.clone(), rays)
                })
            })
            .collect::<Option<Vec<_>>>()?;
        for (points, colors, rays) in traced {
            record.rays += rays;
            for ((x, y), color) in points.into_iter().zip(colors) {
                *edges.at_mut(x as u32, y as u32) = color;
            }
        }
        Some(edges)
    }

    /// Adaptive sampling of the tile (see [`film`]): each pixel's four
    /// corners (those on the tile's edges from `edges`) and its centre;
    /// where the two estimates they make disagree by more than the
    /// tolerance, sets of stratified samples inside the pixel until its
    /// estimate settles or `max` samples are taken. With `keep_centres`,
    /// the surface of each pixel's centre into `scratch.centres`.
    #[allow(clippy::too_many_arguments)]
    fn adaptive_tile(
        &self,
        rect: Rect,
        max: u32,
        tolerance: f64,
        keep_centres: bool,
        edges: &EdgeCorners,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
        rays: &mut u64,
        record: &mut SampleRecord,
    ) {
        let width = (rect.x1 - rect.x0) as usize;
        let height = (rect.y1 - rect.y0) as usize;
        // The corners inside the tile, then the centres.
        scratch.points.clear();
        for y in rect.y0 + 1..rect.y1 {
            for x in rect.x0 + 1..rect.x1 {
                scratch.points.push((f64::from(x), f64::from(y)));
            }
        }
        let inside = scratch.points.len();
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                scratch
                    .points
                    .push((f64::from(x) + 0.5, f64::from(y) + 0.5));
            }
        }
        self.trace_samples(rect, keep_centres, scratch, rays);
        if keep_centres {
            // The centres follow the corners, row by row.
            scratch.keep_centres(width * height, |_, k| k.checked_sub(inside));
        }
        let first = std::mem::take(&mut scratch.sample_colors);
        let (inner, centres) = first.split_at(inside);
        // Corner `(x, y)` of the full image, on the tile or inside it.
        let corner = |x: u32, y: u32| {
            if x == rect.x0 || x == rect.x1 || y == rect.y0 || y == rect.y1 {
                edges.at(x, y)
            } else {
                inner[(y - rect.y0 - 1) as usize * (width - 1) + (x - rect.x0 - 1) as usize]
            }
        };
        // The pixels still refining, and their samples' moments.
        let mut refining: Vec<(usize, usize, SetMoments)> = Vec::new();
        for row in 0..height {
            for column in 0..width {
                let (x, y) = (rect.x0 + column as u32, rect.y0 + row as u32);
                let four = [
                    corner(x, y),
                    corner(x + 1, y),
                    corner(x, y + 1),
                    corner(x + 1, y + 1),
                ];
                match film::settled(&four, centres[row * width + column], tolerance) {
                    Some((color, error)) => {
                        record.add(film::FIRST, Some(error));
                        rows[row][column * 4..column * 4 + 4]
                            .copy_from_slice(&film::encode(color, self.scene.encoding));
                    }
                    None => refining.push((row, column, SetMoments::default())),
                }
            }
        }
        scratch.sample_colors = first;
        let mut taken = 0;
        let mut set = 0;
        while !refining.is_empty() {
            let size = (max - taken).min(film::SET);
            let pattern = if size == film::SET {
                &self.set_pattern
            } else {
                &SamplePattern::new(size)
            };
            scratch.points.clear();
            for &(row, column, ..) in &refining {
                let (x, y) = (rect.x0 + column as u32, rect.y0 + row as u32);
                for k in 0..size {
                    let (ox, oy) = pattern.offset_in_set(x, y, set, k);
                    scratch.points.push((f64::from(x) + ox, f64::from(y) + oy));
                }
            }
            self.trace_samples(rect, false, scratch, rays);
            taken += size;
            set += 1;
            let colors = &scratch.sample_colors;
            refining = refining
                .into_iter()
                .zip(colors.chunks_exact(size as usize))
                .filter_map(|((row, column, mut moments), colors)| {
                    moments.add_set(pattern, colors);
                    let error = moments.standard_error();
                    if error <= tolerance || taken == max {
                        record.add(taken, Some(error));
                        rows[row][column * 4..column * 4 + 4]
                            .copy_from_slice(&film::encode(moments.mean(), self.scene.encoding));
                        None
                    } else {
                        Some((row, column, moments))
                    }
                })
                .collect();
        }
    }

    /// Traces the samples at `scratch.points` (pixels of the full image,
    /// all in or on the border of the tile `rect`) and lights their hits:
    /// each sample's colour into `scratch.sample_colors`. With
    /// `with_surfaces`, every hit's surface (and the shadow rays its colour
    /// traced) into `scratch.surfaces`, its sample into
    /// `scratch.surface_samples`, in the samples' order.
    fn trace_samples(
        &self,
        rect: Rect,
        with_surfaces: bool,
        scratch: &mut TileScratch,
        rays: &mut u64,
    ) {
        let TileScratch {
            points,
            primary,
            hits,
            raster,
            ..
        } = scratch;
        self.camera.rays_into(points, primary);
        *rays += primary.len() as u64;
        hits.clear();
        hits.resize(primary.len(), None);
        match &self.raster {
            Some(r) => r.hits(
                &self.geometry,
                (rect.x0, rect.y0),
                points,
                primary,
                hits,
                raster,
            ),
            None => self.primary_hits(primary, hits),
        }
        self.light_hits(with_surfaces, scratch, rays);
    }

    /// The colours of the last samples of `scratch.primary`, one for each
    /// of `scratch.hits` (the background where it is none): the hit
    /// `hits[i]` is that of `primary[first + i]`, with `first` the samples
    /// before them, and its colour goes to `scratch.sample_colors[i]`. With
    /// `with_surfaces`, every hit's surface into `scratch.surfaces` and its
    /// sample (`first + i`) into `scratch.surface_samples`, in the samples'
    /// order.
    fn light_hits(&self, with_surfaces: bool, scratch: &mut TileScratch, rays: &mut u64) {
        let TileScratch {
            primary,
            hits,
            surfaces,
            surface_samples,
            sample_colors,
            lighting,
            ..
        } = scratch;
        let first = primary.len() - hits.len();
        // A Gouraud colour is read straight from its hit, unless the
        // surface is wanted; the others are coloured from their surfaces,
        // which are kept only when wanted.
        sample_colors.clear();
        sample_colors.resize(hits.len(), self.scene.background);
        surfaces.clear();
        surface_samples.clear();
        self.begin_colors(lighting);
        for (k, (ray, hit)) in primary[first..].iter().zip(hits.iter()).enumerate() {
            let Some(hit) = *hit else { continue };
            match &self.vertex_colors[hit.object as usize] {
                Some(vertex_colors) if !with_surfaces => {
                    sample_colors[k] = self.gouraud(vertex_colors, ray, hit);
                }
                _ => {
                    let surface = self.surface(ray, hit);
                    let traced = self.color_into(&surface, k, sample_colors, rays, lighting);
                    if with_surfaces {
                        surfaces.push((surface, traced));
                        surface_samples.push(first + k);
                    }
                }
            }
        }
        self.finish_colors(sample_colors, lighting);
    }

    /// Traces the centre ray of pixel `(x, y)` of the full image and
    /// explains it.
    pub fn probe(&self, x: u32, y: u32) -> Probe {
        self.geometry.build_bvh(bvh_use(&self.raster));
        let ray = self.camera.centre_ray(x, y);
        let mut rays = 1;
        let probe = match self.geometry.closest_hit(&ray) {
            None => Probe {
                pixel: [x, y],
                surface: None,
                color: self.scene.background,
                breakdown: None,
            },
            Some(hit) => {
                let surface = self.surface(&ray, hit);
                let mut color = [DVec4::ZERO];
                let mut lighting = LightingScratch::default();
                self.begin_colors(&mut lighting);
                let mut traced = self.color_into(&surface, 0, &mut color, &mut rays, &mut lighting);
                self.finish_colors(&mut color, &mut lighting);
                Probe {
                    pixel: [x, y],
                    surface: Some(surface),
                    color: color[0],
                    breakdown: Some(self.breakdown(&surface, &mut traced, &mut rays)),
                }
            }
        };
        self.rays.fetch_add(rays, Ordering::Relaxed);
        probe
    }
}

impl Surface {
    /// The side's name on the wire.
    pub fn side_name(&self) -> &'static str {
        match self.side {
            Side::Front => "front",
            Side::Back => "back",
        }
    }
}

/// What the BVH, when one is needed, serves: rasterized primary rays leave
/// it only shadow rays and probes.
fn bvh_use(raster: &Option<Raster>) -> BvhUse {
    match raster {
        Some(_) => BvhUse::ShadowRays,
        None => BvhUse::PrimaryRays,
    }
}

/// A tile of the image: pixels `[x0, x1) × [y0, y1)` of the full image.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

impl Rect {
    /// Its width and height.
    fn size(&self) -> (usize, usize) {
        ((self.x1 - self.x0) as usize, (self.y1 - self.y0) as usize)
    }
}

/// The colours of adaptive sampling's corners that lie on the tiles'
/// edges, traced before the tiles: a corner is shared by the pixels that
/// meet there, and on a tile's edge also by the tiles, which would each
/// trace it (an eighth more corners with tiles of 16×16 pixels). Its
/// colour depends only on its point, whichever tile traces it.
struct EdgeCorners {
    region: Region,
    /// Per horizontal edge (`y` a multiple of [`TILE`] from the region's
    /// top, and its bottom), the corners of `x` across the region, its
    /// right included; then per vertical edge (`x` likewise), the corners
    /// of `y` down the region, its bottom included (those on horizontal
    /// edges unused).
    corners: Vec<DVec4>,
}

impl EdgeCorners {
    fn new(region: Region) -> Self {
        let count = Self::rows(region) + Self::edges(region.width) * (region.height as usize + 1);
        Self {
            region,
            corners: vec![DVec4::ZERO; count],
        }
    }

    /// The edges across `length` pixels cut every [`TILE`].
    fn edges(length: u32) -> usize {
        length.div_ceil(TILE) as usize + 1
    }

    /// The corners on the horizontal edges.
    fn rows(region: Region) -> usize {
        Self::edges(region.height) * (region.width as usize + 1)
    }

    /// The index of the edge at `at`, `start + length` the last, in a
    /// region `[start, start + length]` cut every [`TILE`]: `None` off the
    /// edges.
    fn edge(at: u32, start: u32, length: u32) -> Option<usize> {
        let offset = at - start;
        if offset == length {
            Some(length.div_ceil(TILE) as usize)
        } else {
            offset
                .is_multiple_of(TILE)
                .then_some((offset / TILE) as usize)
        }
    }

    /// Where corner `(x, y)`, on an edge, lies in `corners`.
    fn index(&self, x: u32, y: u32) -> usize {
        let r = self.region;
        match Self::edge(y, r.y, r.height) {
            Some(edge) => edge * (r.width as usize + 1) + (x - r.x) as usize,
            None => {
                let edge = Self::edge(x, r.x, r.width).expect("a corner on an edge");
                Self::rows(r) + edge * (r.height as usize + 1) + (y - r.y) as usize
            }
        }
    }

    /// The colour of corner `(x, y)` on an edge.
    fn at(&self, x: u32, y: u32) -> DVec4 {
        self.corners[self.index(x, y)]
    }

    fn at_mut(&mut self, x: u32, y: u32) -> &mut DVec4 {
        let index = self.index(x, y);
        &mut self.corners[index]
    }

    /// The points of the edge corners tile `rect` traces into `points`,
    /// all on its border: its top edge and its left one without either
    /// end below, and at the region's bottom or right its bottom or right
    /// edge too. Every corner on an edge is some tile's, once.
    fn owned(&self, rect: Rect, points: &mut Vec<(f64, f64)>) {
        let r = self.region;
        let (right, bottom) = (rect.x1 == r.x + r.width, rect.y1 == r.y + r.height);
        let across = rect.x0..rect.x1 + u32::from(right);
        let mut push = |x: u32, y: u32| points.push((f64::from(x), f64::from(y)));
        across.clone().for_each(|x| push(x, rect.y0));
        (rect.y0 + 1..rect.y1).for_each(|y| push(rect.x0, y));
        if bottom {
            across.for_each(|x| push(x, rect.y1));
        }
        if right {
            (rect.y0 + 1..rect.y1).for_each(|y| push(rect.x1, y));
        }
    }
}

/// The buffers of [`Renderer::render_tile`], which a worker keeps from one
/// tile to the next: memory touched for the first time is slow to write.
#[derive(Default)]
struct TileScratch {
    order: Vec<(usize, usize)>,
    /// The tile's size when `order` holds one sample per pixel.
    order_size: Option<(usize, usize)>,
    /// Per pixel, the surface of its centre ray and the shadow rays its
    /// colour traced, when the samples have them.
    centres: Vec<Option<(Surface, Traced)>>,
    /// Each primary ray's point of the image, in pixels.
    points: Vec<(f64, f64)>,
    primary: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    /// The surfaces of the samples, when kept, and the shadow rays each
    /// one's colour traced.
    surfaces: Vec<(Surface, Traced)>,
    /// The sample of each surface.
    surface_samples: Vec<usize>,
    sample_colors: Vec<DVec4>,
    lighting: LightingScratch,
    raster: RasterScratch,
    /// The samples left to be traced.
    pending: Vec<usize>,
    /// The triangles the rasterizer decided for samples (see
    /// [`Renderer::centres_tile`]).
    decided_setups: Vec<u32>,
    /// The place in `order` of each sample whose hit a decided tile finds:
    /// those the rasterizer decided, then the others.
    traced_samples: Vec<usize>,
    /// The last triangles of Gouraud tiles ready for their pixels, by
    /// setup modulo [`CORNERS_CACHED`].
    corners: Vec<Option<(u32, Corners)>>,
    /// A Gouraud or decided tile's pixels (RGBA8, R in the lowest byte) in
    /// the order's places, before they are copied to the image's rows.
    tile_rgba: Vec<u32>,
}

impl TileScratch {
    /// The kept surfaces of the centre samples into `centres`, one place
    /// per pixel of a tile of `pixels` (row by row): `pixel_of(k)` is the
    /// pixel of sample `k`, none for a sample off the centres.
    fn keep_centres(&mut self, pixels: usize, pixel_of: impl Fn(&Self, usize) -> Option<usize>) {
        self.centres.clear();
        self.centres.resize(pixels, None);
        for j in 0..self.surfaces.len() {
            if let Some(pixel) = pixel_of(self, self.surface_samples[j]) {
                self.centres[pixel] = Some(self.surfaces[j]);
            }
        }
    }
}

/// The lanes of `mask`, by its set bits.
fn set_lanes(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let lane = (mask != 0).then(|| mask.trailing_zeros() as usize)?;
        mask &= mask - 1;
        Some(lane)
    })
}

/// The pixels of a tile, `tile_rgba` (RGBA8, R in the lowest byte) in the
/// places of `order` (see [`Renderer::centre_order`]), into its `rows`;
/// `blocks`: each [`LANES`] of `order` are a whole 4×4 block.
fn write_rows(order: &[(usize, usize)], tile_rgba: &[u32], blocks: bool, rows: &mut [&mut [u8]]) {
    if blocks {
        let side = BLOCK as usize;
        for (chunk, rgba) in tile_rgba.chunks_exact(LANES).enumerate() {
            let (row, column) = order[chunk * LANES];
            for (r, pixels) in rgba.chunks_exact(side).enumerate() {
                let to = &mut rows[row + r][column * 4..(column + side) * 4];
                let pixels: [u32; BLOCK as usize] = pixels.try_into().expect("a block's row");
                to.copy_from_slice(pixels.map(u32::to_le_bytes).as_flattened());
            }
        }
    } else {
        for (&(row, column), pixel) in order.iter().zip(tile_rgba.iter()) {
            rows[row][column * 4..column * 4 + 4].copy_from_slice(&pixel.to_le_bytes());
        }
    }
}

/// [`hit_lighting::face_normals`] of each mesh of `scene`, none for other
/// shapes.
fn face_normal_table(scene: &RenderScene) -> Vec<Vec<DVec3>> {
    scene
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Mesh(mesh) => hit_lighting::face_normals(mesh),
            _ => Vec::new(),
        })
        .collect()
}

/// The summary of two disjoint batches from their summaries (means weighted
/// by counts).
fn merge(a: Summary, b: Summary) -> Summary {
    let (na, nb) = (a.count as f64, b.count as f64);
    let n = na + nb;
    let color = |x: ColorStat, y: ColorStat| ColorStat {
        mean: (x.mean * na + y.mean * nb) / n,
        max: x.max.max(y.max),
    };
    let factor = |x: FactorStat, y: FactorStat| FactorStat {
        mean: (x.mean * na + y.mean * nb) / n,
        max: x.max.max(y.max),
    };
    Summary {
        count: a.count + b.count,
        emission: color(a.emission, b.emission),
        global_ambient: color(a.global_ambient, b.global_ambient),
        lights: a
            .lights
            .iter()
            .zip(&b.lights)
            .map(|(x, y)| LightSummary {
                ambient: color(x.ambient, y.ambient),
                diffuse: color(x.diffuse, y.diffuse),
                specular: color(x.specular, y.specular),
                attenuation: factor(x.attenuation, y.attenuation),
                spot: factor(x.spot, y.spot),
            })
            .collect(),
        clamped_share: (a.clamped_share * na + b.clamped_share * nb) / n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every corner on an edge of the tiles, as [`Renderer::render`] cuts
    /// a region, is traced by exactly one tile, and each where `at` reads.
    #[test]
    fn every_corner_on_a_tiles_edge_is_one_tiles() {
        for (x, y, width, height) in [
            (0, 0, 40, 33),
            (5, 3, 16, 17),
            (7, 9, 1, 1),
            (0, 0, 32, 16),
            (3, 30, 50, 2),
        ] {
            let region = Region {
                x,
                y,
                width,
                height,
            };
            let mut edges = EdgeCorners::new(region);
            let (right, bottom) = (x + width, y + height);
            let mut points = Vec::new();
            for y0 in (y..bottom).step_by(TILE as usize) {
                for x0 in (x..right).step_by(TILE as usize) {
                    let rect = Rect {
                        x0,
                        y0,
                        x1: (x0 + TILE).min(right),
                        y1: (y0 + TILE).min(bottom),
                    };
                    let before = points.len();
                    edges.owned(rect, &mut points);
                    for &(px, py) in &points[before..] {
                        let on_border = px == f64::from(rect.x0)
                            || px == f64::from(rect.x1)
                            || py == f64::from(rect.y0)
                            || py == f64::from(rect.y1);
                        assert!(on_border, "({px}, {py}) off tile {rect:?}");
                    }
                }
            }
            let mut got: Vec<(u32, u32)> =
                points.iter().map(|&(x, y)| (x as u32, y as u32)).collect();
            got.sort_unstable();
            // The corners on an edge, by brute force: a coordinate a
            // multiple of the tile from the region's start, or its end.
            let on_edge =
                |at: u32, start: u32, end: u32| (at - start).is_multiple_of(TILE) || at == end;
            let want: Vec<(u32, u32)> = (x..=right)
                .flat_map(|cx| (y..=bottom).map(move |cy| (cx, cy)))
                .filter(|&(cx, cy)| on_edge(cx, x, right) || on_edge(cy, y, bottom))
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            assert_eq!(got, want, "region {region:?}");
            // Each corner lands in a slot of its own.
            for (k, &(cx, cy)) in want.iter().enumerate() {
                *edges.at_mut(cx, cy) = DVec4::splat(k as f64);
            }
            for (k, &(cx, cy)) in want.iter().enumerate() {
                assert_eq!(edges.at(cx, cy), DVec4::splat(k as f64), "({cx}, {cy})");
            }
        }
    }
}

//! The [`Renderer`]: a scene prepared once per request, and its image
//! traced in tiles on the rayon pool.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec3, DVec4};
use rayon::prelude::*;

use glint_lighting::Side;
use glint_lighting::kernel::{Kernel, MaterialProducts, Tier};
use glint_lighting::terms::{Breakdown, ColorStat, FactorStat, LightSummary, Summary};

use crate::camera::PinholeCamera;
use crate::film::{self, SamplePattern};
use crate::geometry::{Geometry, Hit, Ray};
use crate::hit_lighting::{self, LightingScratch, Surface, VertexColors};
use crate::packet::Packets;
use crate::raster::{Raster, RasterScratch};
use crate::scene::{RenderScene, ShadingMode, Shape};

/// The side of a tile, in pixels.
pub const TILE: u32 = 16;

/// The side of the blocks of pixels whose rays are traced together.
pub const BLOCK: u32 = 4;

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
    pub(crate) camera: PinholeCamera,
    pub(crate) geometry: Geometry,
    /// The rasterizer of the primary rays, when the scene allows it.
    pub(crate) raster: Option<Raster>,
    /// Else the packet tracer of the primary rays, when the eye allows it.
    pub(crate) packets: Option<Packets>,
    /// The light set prepared for the f32 tier of the request's precision,
    /// with each material's products; `None` for the reference.
    pub(crate) f32_lighting: Option<F32Lighting>,
    /// Per object: the Gouraud colours of a mesh in per-vertex mode.
    pub(crate) vertex_colors: Vec<Option<VertexColors>>,
    /// Per object: a mesh's unit geometric normal of each triangle (see
    /// [`hit_lighting::face_normals`]), empty for other shapes.
    pub(crate) face_normals: Vec<Vec<DVec3>>,
    pub(crate) pattern: SamplePattern,
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
    pub render_time: Duration,
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
            Visibility::Rasterized => {
                Raster::new(&geometry, &camera, &scene.camera, &scene.region).ok()
            }
            Visibility::Traced => None,
        };
        if scene.shadows || raster.is_none() {
            geometry.build_bvh();
        }
        let packets = match raster {
            Some(_) => None,
            None => Packets::new(&geometry, eye),
        };
        let face_normals = scene
            .objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh(mesh) => hit_lighting::face_normals(mesh),
                _ => Vec::new(),
            })
            .collect();
        let mut renderer = Self {
            scene,
            camera,
            geometry,
            raster,
            packets,
            f32_lighting,
            vertex_colors: Vec::new(),
            face_normals,
            pattern: SamplePattern::new(scene.samples),
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
        if with_terms && self.pattern.samples() > 1 {
            // The centre rays of the terms are traced one by one, inside
            // the tiles' tasks: the BVH must exist before they start.
            self.geometry.build_bvh();
        }
        let region = self.scene.region;
        let (width, height) = (region.width as usize, region.height as usize);
        let mut rgba = vec![0u8; width * height * 4];
        // Each tile's rows of the image, which its worker writes in place:
        // no copy afterwards, and the image's fresh memory is first touched
        // by the workers, in parallel (a first touch costs about 1 ms per
        // MB, as the operating system maps each page in).
        let mut tiles: Vec<(Rect, Vec<&mut [u8]>)> = Vec::new();
        let row_bytes = width * 4;
        // (`max(1)`: a region without width has no rows, but chunks need a size.)
        for (band, rows) in rgba
            .chunks_mut((row_bytes * TILE as usize).max(1))
            .enumerate()
        {
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
        let summaries: Vec<Option<Summary>> = tiles
            .into_par_iter()
            .map_init(TileScratch::default, |scratch, (rect, mut rows)| {
                (!cancelled()).then(|| self.render_tile(rect, with_terms, scratch, &mut rows))
            })
            .collect::<Option<_>>()?;
        // Merged tile by tile in image order.
        let summary = summaries
            .into_iter()
            .fold(None, |summary, tile| match (summary, tile) {
                (Some(a), Some(b)) => Some(merge(a, b)),
                (a, b) => a.or(b),
            });
        Some(Frame {
            width: region.width,
            height: region.height,
            rgba,
            summary,
            render_time: started.elapsed() + self.vertex_time,
        })
    }

    /// Traces every sample of the tile, lights all its hits at once (the
    /// f32 kernels take each material's hits as one batch), then averages
    /// each pixel's samples into `rows`, the tile's rows of the image (RGBA8).
    /// Returns the summary of the terms, when asked for.
    fn render_tile(
        &self,
        rect: Rect,
        with_terms: bool,
        scratch: &mut TileScratch,
        rows: &mut [&mut [u8]],
    ) -> Option<Summary> {
        let samples = self.pattern.samples() as usize;
        let width = (rect.x1 - rect.x0) as usize;
        let pixels = width * (rect.y1 - rect.y0) as usize;
        let TileScratch {
            order,
            points,
            primary,
            hits,
            surfaces,
            lighting,
            raster,
        } = scratch;
        // The pixels in blocks of 4×4, so that a packet of rays covers a
        // small square of the image, each pixel's samples together;
        // `order[j]`: the pixel traced `j`-th, as its row and column in the
        // tile.
        order.clear();
        points.clear();
        primary.clear();
        for by in (rect.y0..rect.y1).step_by(BLOCK as usize) {
            for bx in (rect.x0..rect.x1).step_by(BLOCK as usize) {
                for y in by..(by + BLOCK).min(rect.y1) {
                    for x in bx..(bx + BLOCK).min(rect.x1) {
                        order.push(((y - rect.y0) as usize, (x - rect.x0) as usize));
                        for k in 0..samples as u32 {
                            let (ox, oy) = self.pattern.offset(x, y, k);
                            let point = (f64::from(x) + ox, f64::from(y) + oy);
                            points.push(point);
                            primary.push(self.camera.ray(point.0, point.1));
                        }
                    }
                }
            }
        }
        let mut rays = primary.len() as u64;
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
        // A plain loop, so that each surface is built in its slot (through
        // `filter_map` it went through the stack first).
        surfaces.clear();
        for (ray, hit) in primary.iter().zip(hits.iter()) {
            if let Some(hit) = *hit {
                surfaces.push(self.surface(ray, hit));
            }
        }
        let lit = self.colors(surfaces, &mut rays, lighting);
        let mut lit = lit.iter().copied();
        // Per pixel, for the terms: the index in `surfaces` of its first
        // sample's hit.
        let mut first_surface = vec![None; if with_terms { pixels } else { 0 }];
        let mut next_surface = 0;
        for (&(row, column), pixel_hits) in order.iter().zip(hits.chunks_exact(samples)) {
            let pixel = row * width + column;
            if with_terms {
                first_surface[pixel] = pixel_hits[0].map(|_| next_surface);
            }
            let mut sample = |hit: &Option<Hit>| match hit {
                Some(_) => {
                    next_surface += 1;
                    lit.next().expect("a colour per hit")
                }
                None => self.scene.background,
            };
            // One sample is its own mean (a sum of one, divided by one).
            let color = match pixel_hits {
                [hit] => sample(hit),
                _ => pixel_hits.iter().map(sample).sum::<DVec4>() / samples as f64,
            };
            rows[row][column * 4..column * 4 + 4]
                .copy_from_slice(&film::encode(color, self.scene.encoding));
        }
        let mut breakdowns = Vec::new();
        if with_terms {
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let pixel = (y - rect.y0) as usize * width + (x - rect.x0) as usize;
                    // With one sample, its ray is the centre ray.
                    let centre = if samples == 1 {
                        first_surface[pixel].map(|i| surfaces[i])
                    } else {
                        rays += 1;
                        let ray = self.camera.centre_ray(x, y);
                        self.geometry
                            .closest_hit(&ray)
                            .map(|hit| self.surface(&ray, hit))
                    };
                    breakdowns.extend(centre.map(|s| self.breakdown(&s, &mut rays)));
                }
            }
        }
        self.rays.fetch_add(rays, Ordering::Relaxed);
        Summary::of(&breakdowns)
    }

    /// Traces the centre ray of pixel `(x, y)` of the full image and
    /// explains it.
    pub fn probe(&self, x: u32, y: u32) -> Probe {
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
                Probe {
                    pixel: [x, y],
                    surface: Some(surface),
                    color: self.colors(&[surface], &mut rays, &mut LightingScratch::default())[0],
                    breakdown: Some(self.breakdown(&surface, &mut rays)),
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

/// A tile of the image: pixels `[x0, x1) × [y0, y1)` of the full image.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// The buffers of [`Renderer::render_tile`], which a worker keeps from one
/// tile to the next: memory touched for the first time is slow to write.
#[derive(Default)]
struct TileScratch {
    order: Vec<(usize, usize)>,
    /// Each primary ray's point of the image, in pixels.
    points: Vec<(f64, f64)>,
    primary: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    surfaces: Vec<Surface>,
    lighting: LightingScratch,
    raster: RasterScratch,
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

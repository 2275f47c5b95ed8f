//! The validated scene a [`crate::Renderer`] renders: a pinhole camera,
//! spheres, infinite planes and indexed triangle meshes, each with a
//! material, lit by one light set in world space.

use glam::{DVec3, DVec4};
use glint_lighting::{LightSet, Precision, SurfaceMaterial};

/// The most samples per pixel the contract allows, whatever the server's
/// limit.
pub const MAX_SAMPLES: u32 = 64;

/// A validated `/v1/render` request: what to trace, how to light it and
/// what to report.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderScene {
    pub camera: Camera,
    pub objects: Vec<Object>,
    /// The light model, the lights and the viewer (the eye for a local
    /// viewer, else the unit direction from the target to the eye), shared
    /// by every material.
    pub lights: LightSet,
    /// Each material in the order of the names in `material_names`
    /// (sorted): in front the material, behind (used when two-sided) the
    /// request's `back_material` or else the material itself.
    pub materials: Vec<SurfaceMaterial>,
    pub material_names: Vec<String>,
    /// The colour of pixels whose rays hit nothing, clamped to [0, 1] as
    /// GL clamps its clear colour.
    pub background: DVec4,
    pub shading: ShadingMode,
    /// How many samples each pixel takes.
    pub samples: Samples,
    pub shadows: bool,
    pub precision: Precision,
    /// The tile of the image to render; the whole image when the request
    /// has none.
    pub region: Region,
    /// Pixels `[x, y]` of the full image whose centre ray is explained.
    pub probes: Vec<[u32; 2]>,
    pub encoding: Encoding,
    /// How many mesh normals have zero length (they get no diffuse or
    /// specular light).
    pub zero_normals: usize,
}

impl RenderScene {
    /// The number of triangles over all meshes.
    pub fn triangles(&self) -> usize {
        self.objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum()
    }
}

/// How many samples each pixel takes (see [`crate::film`] for where).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Samples {
    /// That many in every pixel, 1 to [`MAX_SAMPLES`].
    Uniform(u32),
    /// A pixel's four corners, then sets of samples inside it while the
    /// standard error of its colour exceeds `tolerance` (colour units, in
    /// (0, [`MAX_TOLERANCE`]]), up to `max` (1 to [`MAX_SAMPLES`]).
    Adaptive { max: u32, tolerance: f64 },
}

impl Samples {
    /// The sampling a renderer carries out: adaptive sampling begins with
    /// [`film::FIRST`](crate::film::FIRST) samples a pixel, so with a `max`
    /// below that every pixel takes `max` uniform samples, and no pixel
    /// takes more than `max`.
    pub fn effective(self) -> Samples {
        match self {
            Samples::Adaptive { max, .. } if max < crate::film::FIRST => Samples::Uniform(max),
            samples => samples,
        }
    }

    /// The most samples a pixel takes.
    pub fn max(&self) -> u32 {
        match *self {
            Samples::Uniform(n) => n,
            Samples::Adaptive { max, .. } => max,
        }
    }
}

/// The largest tolerance of adaptive sampling the contract allows.
pub const MAX_TOLERANCE: f64 = 0.1;

/// A pinhole camera; it defines world space and the image.
///
/// Pixel (0, 0) is the top-left one, x to the right, y down. The primary ray
/// of pixel (x, y) at one sample passes through its centre (x + 0.5,
/// y + 0.5) of the image plane; `fov_y` is the full vertical angle and the
/// aspect ratio is `width / height`; the view direction is `target - eye`
/// and `up` (not parallel to it) fixes the roll.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Degrees, in (0, 180).
    pub fov_y: f64,
    pub width: u32,
    pub height: u32,
}

/// One object of the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    /// Index into [`RenderScene::materials`].
    pub material: usize,
}

/// The closed set of shapes.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Sphere(Sphere),
    Plane(Plane),
    Mesh(Mesh),
}

/// A sphere; its outside is its front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: DVec3,
    /// > 0.
    pub radius: f64,
}

/// An infinite plane; the side its normal points to is its front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub point: DVec3,
    /// Unit length.
    pub normal: DVec3,
}

/// An indexed triangle mesh. A triangle's front is the side from which its
/// vertices run counter-clockwise (GL's default `glFrontFace(GL_CCW)`): the
/// side its geometric normal `(p1 - p0) × (p2 - p0)` points to.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    /// One per position, as given (the light model normalises them when it
    /// is asked to); without them each triangle uses its geometric normal.
    pub normals: Option<Vec<DVec3>>,
    /// Three vertex indices per triangle, each a valid index of `positions`.
    pub indices: Vec<[u32; 3]>,
}

/// Where the lighting equation is evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadingMode {
    /// At every hit point.
    #[default]
    PerPixel,
    /// Gouraud, as GL's fixed pipeline: at a mesh's vertices, the colours
    /// interpolated across each triangle. Spheres and planes have no
    /// vertices and are lit per pixel.
    PerVertex,
}

/// How colours in [0, 1] become 8-bit PNG channels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// round(255·c), as GL writes an 8-bit framebuffer.
    #[default]
    Linear,
    /// The sRGB transfer curve, then round(255·c). Alpha stays linear.
    Srgb,
}

/// A tile of the image in pixels of the full image; inside it and not empty.
/// Only the tile is traced and returned, and its pixels are exactly those of
/// the same crop of the whole image: samples are placed in full-image
/// coordinates and nothing per request depends on the region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Region {
    /// Its number of pixels.
    pub fn pixels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

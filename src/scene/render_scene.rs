//! The validated `/v1/render` request: a pinhole camera, spheres, infinite
//! planes and indexed triangle meshes, each with a named material, lit by one
//! shared set of lights in world space.
//!
//! Validation decides everything that does not depend on a pixel: the
//! lighting description of every material (built once here, never per
//! pixel), the viewer (the eye for a local viewer, else the unit direction
//! from the target to the eye, the same for every pixel), the region (the
//! whole image when none is given) and the default of every optional field.

use std::collections::BTreeMap;

use glam::{DVec3, DVec4};

use super::validate::{self, point, vector};
use super::{At, Limits, Precision, RequestError, parse_json, wire};
use crate::lighting::{self, Lighting, MAX_RAW_NORMAL, Material, Viewer};

type Result<T> = std::result::Result<T, RequestError>;

/// The most samples per pixel the contract allows, whatever the server's
/// limit.
pub const MAX_SAMPLES: u32 = 64;

/// The most probes one request may ask for (413 above): each returns a full
/// breakdown, so the response grows with them.
pub const MAX_PROBES: usize = 4096;

/// A validated `/v1/render` request.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderScene {
    pub camera: Camera,
    pub objects: Vec<Object>,
    /// One lighting description per material, in the order of the names in
    /// `material_names` (sorted): the shared light model, lights and viewer,
    /// the material in front and, behind (used when two-sided), the
    /// request's `back_material` or else the material itself.
    pub materials: Vec<Lighting>,
    pub material_names: Vec<String>,
    /// The number of lights (the same for every material).
    pub lights: usize,
    /// The colour of pixels whose rays hit nothing, clamped to [0, 1] as
    /// GL clamps its clear colour.
    pub background: DVec4,
    pub shading: ShadingMode,
    /// Samples per pixel, 1 to [`MAX_SAMPLES`].
    pub samples: u32,
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

/// Parses and validates a `/v1/render` body.
pub fn parse_render(body: &[u8], limits: &Limits) -> Result<RenderScene> {
    let request: wire::RenderRequest = parse_json(body)?;
    render_scene(&request, limits)
}

/// Validates a `/v1/render` request.
pub fn render_scene(request: &wire::RenderRequest, limits: &Limits) -> Result<RenderScene> {
    let camera = camera(&request.camera, limits)?;
    for (pointer, count, limit) in [
        ("/objects", request.objects.count(), wire::MAX_OBJECTS),
        ("/materials", request.materials.count(), wire::MAX_MATERIALS),
    ] {
        if count > limit {
            return Err(RequestError::over_limit(
                pointer,
                format!("{count} entries, over this server's limit of {limit}"),
            ));
        }
    }

    // The lights and the light model once; each material then only swaps
    // its own colours in.
    let view_dir = lighting::unit_or_zero(camera.target - camera.eye);
    let base = validate::lighting(
        request.light_model.as_ref(),
        None,
        &At::pointer("/material"),
        None,
        request.lights.as_ref(),
        Some(Viewer::Infinite(-view_dir)),
        limits,
    )?;
    let viewer = if base.model.local_viewer {
        Viewer::Local(camera.eye)
    } else {
        Viewer::Infinite(-view_dir)
    };
    let back = request
        .back_material
        .as_ref()
        .map(|m| validate::material(m, &At::pointer("/back_material")))
        .transpose()?;
    let (material_names, materials) = materials(&request.materials, back, &base, viewer)?;

    let mut vertices = 0usize;
    let mut zero_normals = 0usize;
    let raw_limit = (!base.model.normalize_normals).then_some(MAX_RAW_NORMAL);
    let objects_at = At::pointer("/objects");
    let objects = request
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let at = objects_at.index(i);
            let object = object(o, &at, &material_names, raw_limit)?;
            if let Shape::Mesh(mesh) = &object.shape {
                vertices += mesh.positions.len();
                if vertices > limits.max_vertices {
                    return Err(RequestError::over_limit(
                        at.field("mesh").field("positions"),
                        format!(
                            "{vertices} mesh vertices so far, over this server's limit of {}",
                            limits.max_vertices
                        ),
                    ));
                }
                zero_normals += mesh
                    .normals
                    .iter()
                    .flatten()
                    .filter(|n| **n == DVec3::ZERO)
                    .count();
            }
            Ok(object)
        })
        .collect::<Result<Vec<_>>>()?;

    let background = match request.background {
        None => DVec4::new(0.0, 0.0, 0.0, 1.0),
        Some(c) => validate::color(Some(c), DVec4::ZERO, &At::pointer("/background"))?,
    }
    .clamp(DVec4::ZERO, DVec4::ONE);

    Ok(RenderScene {
        region: region(request.region.as_ref(), &camera)?,
        probes: probes(request.probes.as_deref().unwrap_or_default(), &camera)?,
        samples: samples(request.samples, limits)?,
        camera,
        objects,
        lights: base.lights.len(),
        materials,
        material_names,
        background,
        shading: match request.shading {
            None | Some(wire::ShadingMode::PerPixel) => ShadingMode::PerPixel,
            Some(wire::ShadingMode::PerVertex) => ShadingMode::PerVertex,
        },
        shadows: request.shadows.unwrap_or(false),
        precision: request.precision.unwrap_or_default(),
        encoding: match request.encoding {
            None | Some(wire::Encoding::Linear) => Encoding::Linear,
            Some(wire::Encoding::Srgb) => Encoding::Srgb,
        },
        zero_normals,
    })
}

fn camera(c: &wire::Camera, limits: &Limits) -> Result<Camera> {
    let eye = point(&c.eye, &At::pointer("/camera/eye"))?;
    let target = point(&c.target, &At::pointer("/camera/target"))?;
    let up = vector(&c.up, &At::pointer("/camera/up"))?;
    if eye == target {
        return Err(RequestError::invalid(
            "/camera/target",
            "the target is the eye: the camera has no view direction",
        ));
    }
    let view = lighting::unit_or_zero(target - eye);
    let up_unit = lighting::unit_or_zero(up);
    if up_unit == DVec3::ZERO {
        return Err(RequestError::invalid("/camera/up", "the up vector is zero"));
    }
    // The sine of the angle between them: below 1e-9 the image's roll is
    // decided by rounding.
    if view.cross(up_unit).length() < 1e-9 {
        return Err(RequestError::invalid(
            "/camera/up",
            "the up vector is parallel to the view direction (target - eye)",
        ));
    }
    if !(c.fov_y.is_finite() && c.fov_y > 0.0 && c.fov_y < 180.0) {
        return Err(RequestError::invalid(
            "/camera/fov_y",
            format!(
                "fov_y is the full vertical angle in degrees and must lie in (0, 180), not {}",
                c.fov_y
            ),
        ));
    }
    for (name, value) in [("width", c.width), ("height", c.height)] {
        if value == 0 {
            return Err(RequestError::invalid(
                format!("/camera/{name}"),
                format!("the image {name} must be at least 1 pixel"),
            ));
        }
    }
    let pixels = u64::from(c.width) * u64::from(c.height);
    if pixels > limits.max_pixels {
        return Err(RequestError::over_limit(
            "/camera",
            format!(
                "{} × {} = {pixels} pixels, over this server's limit of {}",
                c.width, c.height, limits.max_pixels
            ),
        ));
    }
    Ok(Camera {
        eye,
        target,
        up,
        fov_y: c.fov_y,
        width: c.width,
        height: c.height,
    })
}

/// Every named material as a complete lighting description, sorted by name:
/// the material in front, and behind either `back` (the request's
/// `back_material`) or the material itself.
fn materials(
    named: &BTreeMap<String, wire::Material>,
    back: Option<Material>,
    base: &Lighting,
    viewer: Viewer,
) -> Result<(Vec<String>, Vec<Lighting>)> {
    let mut names = Vec::with_capacity(named.len());
    let mut lightings = Vec::with_capacity(named.len());
    for (name, m) in named {
        let at = format!("/materials/{}", pointer_token(name));
        let material = validate::material(m, &At::pointer(&at))?;
        names.push(name.clone());
        lightings.push(Lighting {
            front: material,
            back: back.unwrap_or(material),
            viewer,
            ..base.clone()
        });
    }
    Ok((names, lightings))
}

/// A name as one reference token of a JSON Pointer (RFC 6901).
fn pointer_token(name: &str) -> String {
    name.replace('~', "~0").replace('/', "~1")
}

fn object(
    o: &wire::Object,
    at: &At,
    material_names: &[String],
    raw_limit: Option<f64>,
) -> Result<Object> {
    let material = material_names.binary_search(&o.material).map_err(|_| {
        RequestError::invalid(
            at.field("material"),
            format!("no material named {:?} in /materials", o.material),
        )
    })?;
    let shape = match (&o.sphere, &o.plane, &o.mesh) {
        (Some(s), None, None) => Shape::Sphere(sphere(s, &at.field("sphere"))?),
        (None, Some(p), None) => Shape::Plane(plane(p, &at.field("plane"))?),
        (None, None, Some(m)) => Shape::Mesh(mesh(m, &at.field("mesh"), raw_limit)?),
        _ => {
            return Err(RequestError::invalid(
                at,
                "an object has exactly one of sphere, plane or mesh",
            ));
        }
    };
    Ok(Object { shape, material })
}

fn sphere(s: &wire::Sphere, at: &At) -> Result<Sphere> {
    let center = point(&s.center, &at.field("center"))?;
    if !(s.radius.is_finite() && s.radius > 0.0 && s.radius <= lighting::MAX_COORDINATE) {
        return Err(RequestError::invalid(
            at.field("radius"),
            format!(
                "a radius must be > 0 and at most {:e}, not {}",
                lighting::MAX_COORDINATE,
                s.radius
            ),
        ));
    }
    Ok(Sphere {
        center,
        radius: s.radius,
    })
}

fn plane(p: &wire::Plane, at: &At) -> Result<Plane> {
    let point = point(&p.point, &at.field("point"))?;
    let normal = lighting::unit_or_zero(vector(&p.normal, &at.field("normal"))?);
    if normal == DVec3::ZERO {
        return Err(RequestError::invalid(
            at.field("normal"),
            "a plane needs a non-zero normal",
        ));
    }
    Ok(Plane { point, normal })
}

fn mesh(m: &wire::Mesh, at: &At, raw_limit: Option<f64>) -> Result<Mesh> {
    let positions = validate::points(&m.positions, &at.field("positions"))?;
    let normals = m
        .normals
        .as_ref()
        .map(|n| validate::normals(n, positions.len(), raw_limit, &at.field("normals")))
        .transpose()?;
    if !m.indices.len().is_multiple_of(3) {
        return Err(RequestError::invalid(
            at.field("indices"),
            format!(
                "{} indices: a mesh has three per triangle, so a multiple of 3",
                m.indices.len()
            ),
        ));
    }
    if let Some(k) = m
        .indices
        .iter()
        .position(|&i| i as usize >= positions.len())
    {
        return Err(RequestError::invalid(
            at.field("indices").index(k),
            format!(
                "index {} is out of range: the mesh has {} positions",
                m.indices[k],
                positions.len()
            ),
        ));
    }
    let indices = m
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    Ok(Mesh {
        positions,
        normals,
        indices,
    })
}

fn samples(samples: Option<u32>, limits: &Limits) -> Result<u32> {
    let samples = samples.unwrap_or(1);
    if samples < 1 {
        return Err(RequestError::invalid(
            "/samples",
            "samples per pixel must be at least 1",
        ));
    }
    if samples > limits.max_samples {
        return Err(RequestError::over_limit(
            "/samples",
            format!(
                "{samples} samples per pixel, over this server's limit of {}",
                limits.max_samples
            ),
        ));
    }
    if samples > MAX_SAMPLES {
        return Err(RequestError::invalid(
            "/samples",
            format!("samples per pixel must lie in 1..={MAX_SAMPLES}, not {samples}"),
        ));
    }
    Ok(samples)
}

fn region(r: Option<&wire::Region>, camera: &Camera) -> Result<Region> {
    let Some(r) = r else {
        return Ok(Region {
            x: 0,
            y: 0,
            width: camera.width,
            height: camera.height,
        });
    };
    for (name, value) in [("width", r.width), ("height", r.height)] {
        if value == 0 {
            return Err(RequestError::invalid(
                format!("/region/{name}"),
                format!("a region's {name} must be at least 1 pixel"),
            ));
        }
    }
    let inside =
        |start: u32, len: u32, size: u32| u64::from(start) + u64::from(len) <= u64::from(size);
    if !(inside(r.x, r.width, camera.width) && inside(r.y, r.height, camera.height)) {
        return Err(RequestError::invalid(
            "/region",
            format!(
                "the region {}×{} at ({}, {}) does not lie inside the {}×{} image",
                r.width, r.height, r.x, r.y, camera.width, camera.height
            ),
        ));
    }
    Ok(Region {
        x: r.x,
        y: r.y,
        width: r.width,
        height: r.height,
    })
}

fn probes(probes: &[[u32; 2]], camera: &Camera) -> Result<Vec<[u32; 2]>> {
    if probes.len() > MAX_PROBES {
        return Err(RequestError::over_limit(
            "/probes",
            format!(
                "{} probes, over this server's limit of {MAX_PROBES}",
                probes.len()
            ),
        ));
    }
    if let Some(k) = probes
        .iter()
        .position(|&[x, y]| x >= camera.width || y >= camera.height)
    {
        let [x, y] = probes[k];
        return Err(RequestError::invalid(
            format!("/probes/{k}"),
            format!(
                "pixel ({x}, {y}) is outside the {}×{} image",
                camera.width, camera.height
            ),
        ));
    }
    Ok(probes.to_vec())
}

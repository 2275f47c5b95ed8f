//! Validating a `/v1/render` request into a [`RenderScene`]: a pinhole
//! camera, spheres, infinite planes and indexed triangle meshes, each with a
//! named material, lit by one light set in world space.
//!
//! Validation decides everything that does not depend on a pixel: the
//! light set and every material (built once here, never per pixel), the
//! viewer (the eye for a local viewer, else the unit direction
//! from the target to the eye, the same for every pixel), the region (the
//! whole image when none is given) and the default of every optional field.

use std::collections::BTreeMap;

use glam::{DVec3, DVec4};

use glint_lighting::{self as lighting, MAX_RAW_NORMAL, Material, SurfaceMaterial, Viewer};
use glint_trace::{
    Camera, Encoding, MAX_SAMPLES, MAX_TOLERANCE, Mesh, Object, Plane, Region, RenderScene,
    Samples, ShadingMode, Shape, Sphere,
};

use super::validate::{self, count_within, point, vector};
use super::{At, Limits, RequestError, parse_json, wire};

type Result<T> = std::result::Result<T, RequestError>;

/// The most probes one request may ask for (422 above, a bound of the
/// contract): each returns a full breakdown, so the response grows with
/// them.
pub const MAX_PROBES: usize = 4096;

/// Parses and validates a `/v1/render` body.
pub fn parse_render(body: &[u8], limits: &Limits) -> Result<RenderScene> {
    let request: wire::RenderRequest = parse_json(body)?;
    let camera = request.json_form()?;
    render_scene(&request, camera, limits)
}

/// Validates a `/v1/render` request seen by `camera` (the request's own,
/// or with a model the one resolved from it).
pub fn render_scene(
    request: &wire::RenderRequest,
    camera: &wire::Camera,
    limits: &Limits,
) -> Result<RenderScene> {
    let camera = self::camera(camera)?;
    let region = region(request.region.as_ref(), &camera)?;
    let objects = request.objects.as_ref().map_or(&[][..], |o| &o[..]);
    let object_count = request.objects.as_ref().map_or(0, |o| o.count());
    let named = request.materials.as_deref();
    let material_count = request.materials.as_ref().map_or(0, |m| m.count());
    // The fixed bounds of the contract, which no server setting lowers.
    count_within(
        "/objects",
        "objects",
        object_count,
        wire::MAX_OBJECTS,
        wire::MAX_OBJECTS,
    )?;
    count_within(
        "/materials",
        "materials",
        material_count,
        wire::MAX_MATERIALS,
        wire::MAX_MATERIALS,
    )?;

    // The lights and the light model once, for every material.
    let view_dir = lighting::unit_or_zero(camera.target - camera.eye);
    let viewer = if validate::request_local_viewer(&request.light_model) {
        Viewer::Local(camera.eye)
    } else {
        Viewer::Infinite(-view_dir)
    };
    let lights = validate::light_set(
        request.light_model.as_ref(),
        request.lights.as_ref(),
        Some(viewer),
        limits,
    )?;
    let back = request
        .back_material
        .as_ref()
        .map(|m| validate::material(m, &At::pointer("/back_material")))
        .transpose()?;
    let no_materials = BTreeMap::new();
    let (material_names, materials) = materials(named.unwrap_or(&no_materials), back)?;

    let mut vertices = 0usize;
    let mut zero_normals = 0usize;
    let raw_limit = (!lights.model.normalize_normals).then_some(MAX_RAW_NORMAL);
    let objects_at = At::pointer("/objects");
    let objects = objects
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
    let probes = probes(request.probes.as_deref().unwrap_or_default(), &camera)?;
    let samples = samples(request.samples, limits)?;
    let precision = validate::precision(request.precision, "")?;
    // The image's size against this server's limit last: a request the
    // contract refuses is 422 (or 400) whatever its size, and 413 says only
    // that this server will not draw so many pixels.
    pixels_within(&region, request.region.is_some(), limits)?;

    Ok(RenderScene {
        region,
        probes,
        samples,
        camera,
        objects,
        lights,
        materials,
        material_names,
        background,
        shading: match request.shading {
            None | Some(wire::ShadingMode::PerPixel) => ShadingMode::PerPixel,
            Some(wire::ShadingMode::PerVertex) => ShadingMode::PerVertex,
        },
        shadows: request.shadows.unwrap_or(false),
        precision,
        encoding: match request.encoding {
            None | Some(wire::Encoding::Linear) => Encoding::Linear,
            Some(wire::Encoding::Srgb) => Encoding::Srgb,
        },
        zero_normals,
    })
}

fn camera(c: &wire::Camera) -> Result<Camera> {
    let (eye, target, up, fov_y, width, height) = c.complete()?;
    let eye = point(&eye, &At::pointer("/camera/eye"))?;
    let target = point(&target, &At::pointer("/camera/target"))?;
    let up = vector(&up, &At::pointer("/camera/up"))?;
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
    if !(fov_y.is_finite() && fov_y > 0.0 && fov_y < 180.0) {
        return Err(RequestError::invalid(
            "/camera/fov_y",
            format!(
                "fov_y is the full vertical angle in degrees and must lie in (0, 180), not {fov_y}"
            ),
        ));
    }
    for (name, value) in [("width", width), ("height", height)] {
        if value == 0 {
            return Err(RequestError::invalid(
                format!("/camera/{name}"),
                format!("the image {name} must be at least 1 pixel"),
            ));
        }
    }
    Ok(Camera {
        eye,
        target,
        up,
        fov_y,
        width,
        height,
    })
}

/// Every named material, sorted by name: the material in front, and behind
/// either `back` (the request's `back_material`) or the material itself.
fn materials(
    named: &BTreeMap<String, wire::Material>,
    back: Option<Material>,
) -> Result<(Vec<String>, Vec<SurfaceMaterial>)> {
    let mut names = Vec::with_capacity(named.len());
    let mut materials = Vec::with_capacity(named.len());
    for (name, m) in named {
        let at = format!("/materials/{}", pointer_token(name));
        let front = validate::material(m, &At::pointer(&at))?;
        names.push(name.clone());
        materials.push(SurfaceMaterial {
            front,
            back: back.unwrap_or(front),
        });
    }
    Ok((names, materials))
}

/// A name as one reference token of a JSON Pointer (RFC 6901).
pub(super) fn pointer_token(name: &str) -> String {
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

/// A count of samples (`/samples`), or adaptive sampling's object.
fn samples(samples: Option<wire::Samples>, limits: &Limits) -> Result<Samples> {
    match samples {
        None => Ok(Samples::Uniform(1)),
        Some(wire::Samples::Count(n)) => sample_count(n, "/samples", limits).map(Samples::Uniform),
        Some(wire::Samples::Adaptive(adaptive)) => {
            let max = sample_count(adaptive.max, "/samples/max", limits)?;
            let tolerance = adaptive.tolerance;
            if !(tolerance > 0.0 && tolerance <= MAX_TOLERANCE) {
                return Err(RequestError::invalid(
                    "/samples/tolerance",
                    format!(
                        "the tolerance of adaptive sampling must lie in (0, {MAX_TOLERANCE}], \
                         not {tolerance}"
                    ),
                ));
            }
            Ok(Samples::Adaptive { max, tolerance })
        }
    }
}

/// A number of samples per pixel at `pointer`, within the contract and the
/// server's limit.
fn sample_count(samples: u32, pointer: &str, limits: &Limits) -> Result<u32> {
    if samples < 1 {
        return Err(RequestError::invalid(
            pointer,
            "samples per pixel must be at least 1",
        ));
    }
    count_within(
        pointer,
        "samples per pixel",
        samples as usize,
        MAX_SAMPLES as usize,
        limits.max_samples as usize,
    )?;
    Ok(samples)
}

/// The pixel limit bounds the pixels a request computes: the region's when
/// it names one, so that an image larger than one server allows is rendered
/// as tiles (the fan-out client does that), each within the limit.
fn pixels_within(region: &Region, named: bool, limits: &Limits) -> Result<()> {
    let pixels = region.pixels();
    if pixels <= limits.max_pixels {
        return Ok(());
    }
    let (pointer, what) = if named {
        ("/region", "region")
    } else {
        ("/camera", "image")
    };
    Err(RequestError::over_limit(
        pointer,
        format!(
            "the {what} is {} × {} = {pixels} pixels, over this server's limit of {}",
            region.width, region.height, limits.max_pixels
        ),
    ))
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
    count_within("/probes", "probes", probes.len(), MAX_PROBES, MAX_PROBES)?;
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

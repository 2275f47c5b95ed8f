//! The glTF → GL mapping: what a request with a model leaves out, taken
//! from the model, every lossy step of it a warning. The mapping (also in
//! `api/openapi.yaml`):
//!
//! - **Lights** (`KHR_lights_punctual`, each where its node puts it): GL's
//!   diffuse and specular colours are `color × intensity`, the ambient
//!   black; a directional light shines along its node's −z; a point or spot
//!   light is at its node's origin with attenuation (0, 0, 1), the inverse
//!   square law glTF's lights follow; a spot's cutoff is its
//!   `outerConeAngle`, and its exponent `e` makes `cos^e` one half where
//!   glTF's falloff, `t²` with `t` linear in the cosine from the outer cone
//!   (0) to the inner (1), is one half: `e = ln ½ / ln(cos_o + (cos_i −
//!   cos_o)/√2)`, at most 128. `range` has no GL counterpart.
//! - **Materials** (`pbrMetallicRoughness`, factors only): diffuse = ambient
//!   = `baseColorFactor`; specular = `mix(0.04, baseColor, metallic) · (1 −
//!   roughness)`; shininess = `2/roughness⁴ − 2` (Blinn-Phong's exponent of
//!   a Beckmann lobe of slope `roughness²`), at most 128; emission =
//!   `emissiveFactor` × `KHR_materials_emissive_strength`. An unlit
//!   material (`KHR_materials_unlit`) is all emission: `baseColorFactor`.
//! - **The view**: the scene's first camera, at its node's origin looking
//!   along its −z with its +y up; else eye space is world space.

use std::collections::BTreeMap;

use glam::{DMat4, DVec3, DVec4};

use glint_lighting::{
    self as lighting, Light, LightPosition, LightSet, MAX_COORDINATE, Material, Spot,
    SurfaceMaterial, Viewer,
};
use glint_model::{self as gltf, Instance, Model, Placed, schema};

use super::render_scene::pointer_token;
use super::validate::{self, count_within};
use super::{At, Limits, RequestError, Warning, wire};

type Result<T> = std::result::Result<T, RequestError>;

/// How a model is placed under `limits` and the light model of `lights`;
/// a render keeps its triangles.
pub(super) fn placement(limits: &Limits, lights: &LightSet, keep_triangles: bool) -> gltf::Options {
    gltf::Options {
        max_vertices: limits.max_vertices,
        max_coordinate: MAX_COORDINATE,
        normalize_normals: lights.model.normalize_normals,
        keep_triangles,
    }
}

/// What placing the model skipped or chose.
pub(super) fn placement_warnings(placed: &Placed) -> Vec<Warning> {
    let computed = placed
        .instances
        .iter()
        .filter(|i| i.normals_computed)
        .count();
    let zero_normals: usize = placed
        .instances
        .iter()
        .map(|i| i.normals.iter().filter(|n| **n == DVec3::ZERO).count())
        .sum();
    let incomplete = placed
        .instances
        .iter()
        .filter(|i| i.incomplete_triangle)
        .count();
    let mut warnings = Vec::new();
    let mut warn = |code, count, detail| warn_if(&mut warnings, code, count, detail);
    warn(
        "incomplete_triangles",
        incomplete,
        format!(
            "{incomplete} primitives end with one or two vertices past their last whole \
             triangle (glTF asks for a multiple of 3): those vertices are lit, and the incomplete \
             triangle is not drawn"
        ),
    );
    warn(
        "no_scene",
        usize::from(!placed.has_scene),
        "the model has no scene: nothing was placed".to_owned(),
    );
    warn(
        "normals_computed",
        computed,
        format!(
            "{computed} primitives have no normals: smooth normals were computed from their \
             triangles, weighted by area (glTF viewers compute flat ones)"
        ),
    );
    warn(
        "not_triangles",
        placed.not_triangles,
        format!(
            "{} primitives are points, lines, strips or fans: they were not shaded",
            placed.not_triangles
        ),
    );
    warn(
        "morph_targets_ignored",
        placed.morph_targets,
        format!(
            "{} primitives have morph targets: their base shape was shaded",
            placed.morph_targets
        ),
    );
    warn(
        "skins_ignored",
        placed.skinned,
        format!(
            "{} primitives are skinned: they were placed by their node's matrix, in bind pose",
            placed.skinned
        ),
    );
    warn(
        "zero_normals",
        zero_normals,
        format!(
            "{zero_normals} normals have zero length (a singular node matrix, a vertex of no \
             triangle); they get no diffuse or specular light"
        ),
    );
    warnings
}

/// Adds the warning `code` about `count` things, when there are any.
pub(super) fn warn_if(
    warnings: &mut Vec<Warning>,
    code: &'static str,
    count: usize,
    detail: String,
) {
    if count > 0 {
        warnings.push(Warning {
            code,
            count,
            detail,
        });
    }
}

/// The scene's first camera, where its node puts it.
pub(super) struct SceneCamera {
    eye: DVec3,
    /// Unit, along the node's −z.
    forward: DVec3,
    up: DVec3,
    camera: schema::Camera,
    index: usize,
}

impl SceneCamera {
    pub(super) fn viewer(&self, local: bool) -> Viewer {
        if local {
            Viewer::Local(self.eye)
        } else {
            Viewer::Infinite(-self.forward)
        }
    }
}

pub(super) fn first_camera(model: &Model, placed: &Placed) -> Result<Option<SceneCamera>> {
    let Some(placed_camera) = placed.cameras.first() else {
        return Ok(None);
    };
    let node_at = format!("/nodes/{}/camera", placed_camera.node);
    let camera: schema::Camera = model.entry("cameras", placed_camera.camera, &node_at)?;
    let world = placed_camera.world;
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = lighting::unit_or_zero(world.transform_vector3(DVec3::NEG_Z));
    let up = world.transform_vector3(DVec3::Y);
    if forward == DVec3::ZERO || forward.cross(lighting::unit_or_zero(up)).length() < 1e-9 {
        return Err(RequestError::invalid(
            format!("/model/nodes/{}", placed_camera.node),
            "the node's matrix leaves its camera no view direction or no up",
        ));
    }
    if eye.abs().max_element() > MAX_COORDINATE {
        return Err(RequestError::invalid(
            format!("/model/nodes/{}", placed_camera.node),
            format!("the node places its camera beyond ±{MAX_COORDINATE:e}"),
        ));
    }
    Ok(Some(SceneCamera {
        eye,
        forward,
        up,
        camera,
        index: placed_camera.camera,
    }))
}

/// The camera of a render: the request's view, or the model's first
/// camera; the request's size, or 480 rows at the camera's aspect ratio
/// (4:3 without one).
pub(super) fn render_camera(
    model: &Model,
    placed: &Placed,
    requested: Option<&wire::Camera>,
) -> Result<wire::Camera> {
    let default = wire::Camera::default();
    let requested = requested.unwrap_or(&default);
    let view = (
        requested.eye,
        requested.target,
        requested.up,
        requested.fov_y,
    );
    let (eye, target, up, fov_y, aspect) = match view {
        (Some(eye), Some(target), Some(up), Some(fov_y)) => (eye, target, up, fov_y, None),
        (None, None, None, None) => {
            let Some(camera) = first_camera(model, placed)? else {
                return Err(RequestError::invalid(
                    "/request/camera",
                    "the model has no camera in its scene: give eye, target, up and fov_y",
                ));
            };
            let at = format!("/model/cameras/{}", camera.index);
            let Some(perspective) = camera
                .camera
                .perspective
                .filter(|_| camera.camera.kind == "perspective")
            else {
                return Err(RequestError::invalid(
                    format!("{at}/type"),
                    "the model's first camera is not a perspective one, and glint renders \
                     through a pinhole: give request.camera",
                ));
            };
            let fov_y = perspective.yfov.to_degrees();
            if !(fov_y > 0.0 && fov_y < 180.0) {
                return Err(RequestError::invalid(
                    format!("{at}/perspective/yfov"),
                    format!("a vertical field of view of {} radians", perspective.yfov),
                ));
            }
            let target = camera.eye + camera.forward;
            (
                camera.eye.to_array(),
                target.to_array(),
                camera.up.to_array(),
                fov_y,
                perspective.aspect_ratio,
            )
        }
        _ => {
            return Err(RequestError::invalid(
                "/request/camera",
                "give eye, target, up and fov_y together, or none of them to use the model's \
                 first camera",
            ));
        }
    };
    const HEIGHT: u32 = 480;
    let aspect = aspect
        .filter(|a| a.is_finite() && *a > 0.0)
        .unwrap_or(4.0 / 3.0);
    let height = requested.height.unwrap_or(HEIGHT);
    let width = requested
        .width
        .unwrap_or_else(|| (f64::from(height) * aspect).round().clamp(1.0, 65_536.0) as u32);
    Ok(wire::Camera {
        eye: Some(eye),
        target: Some(target),
        up: Some(up),
        fov_y: Some(fov_y),
        width: Some(width),
        height: Some(height),
    })
}

/// Where the model's lights are listed.
const LIGHTS_AT: &str = "/extensions/KHR_lights_punctual/lights";

/// The GL lights of the model's `KHR_lights_punctual` lights in the scene.
pub(super) fn model_lights(
    model: &Model,
    placed: &Placed,
    limits: &Limits,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<Light>> {
    let defined = model
        .json()
        .pointer(LIGHTS_AT)
        .and_then(|l| l.as_array())
        .map_or(0, Vec::len);
    let max_lights = limits.max_lights.min(lighting::MAX_LIGHTS);
    if placed.lights.len() > max_lights {
        return Err(RequestError::over_limit(
            format!("/model{LIGHTS_AT}"),
            format!(
                "the scene places {} lights, over this server's limit of {max_lights}",
                placed.lights.len()
            ),
        ));
    }
    let mut used = vec![false; defined];
    let mut ranged = 0;
    let mut spots = 0;
    let mut lights = Vec::with_capacity(placed.lights.len());
    for placed_light in &placed.lights {
        let referrer = format!(
            "/nodes/{}/extensions/KHR_lights_punctual/light",
            placed_light.node
        );
        if placed_light.light >= defined {
            return Err(RequestError::invalid(
                format!("/model{referrer}"),
                format!(
                    "refers to light {}, and the model defines {defined}",
                    placed_light.light
                ),
            ));
        }
        used[placed_light.light] = true;
        let at = format!("{LIGHTS_AT}/{}", placed_light.light);
        let light: schema::Light = model.get(&at)?;
        ranged += usize::from(light.range.is_some());
        spots += usize::from(light.kind == "spot");
        lights.push(gl_light(
            &light,
            &placed_light.world,
            &format!("/model{at}"),
            placed_light.node,
        )?);
    }
    let unused = used.iter().filter(|u| !**u).count();
    let mut warn = |code, count, detail| warn_if(&mut *warnings, code, count, detail);
    warn(
        "no_lights",
        usize::from(lights.is_empty()),
        "neither the request nor the model's scene has lights: only emission and the global \
         ambient light the model"
            .to_owned(),
    );
    warn(
        "lights_not_in_scene",
        unused,
        format!("{unused} lights of the model are on no node of its scene: they light nothing"),
    );
    warn(
        "light_range_ignored",
        ranged,
        format!(
            "{ranged} lights have a range: GL's attenuation has no cut-off, so they reach past it"
        ),
    );
    warn(
        "spot_falloff_fitted",
        spots,
        format!(
            "{spots} spotlights: GL's cone has a hard edge at the outer cone angle and a cos^e \
             falloff, fitted to glTF's smooth falloff where it is one half"
        ),
    );
    Ok(lights)
}

/// One `KHR_lights_punctual` light as GL's (see the module docs).
fn gl_light(light: &schema::Light, world: &DMat4, at: &str, node: usize) -> Result<Light> {
    let color = light.color.unwrap_or([1.0; 3]);
    let intensity = light.intensity.unwrap_or(1.0);
    if let Some(k) = color.iter().position(|c| !(0.0..=1.0).contains(c)) {
        return Err(RequestError::invalid(
            format!("{at}/color/{k}"),
            "a light's colour components lie in [0, 1]",
        ));
    }
    let rgb = DVec3::from_array(color) * intensity;
    if !(intensity >= 0.0 && rgb.max_element() <= lighting::MAX_COLOR) {
        return Err(RequestError::invalid(
            format!("{at}/intensity"),
            format!(
                "an intensity of {intensity}: GL's light colour, colour × intensity, must lie \
                 within [0, {:e}]",
                lighting::MAX_COLOR
            ),
        ));
    }
    let color = rgb.extend(1.0);
    let place_at = format!("/model/nodes/{node}");
    let position = world.transform_point3(DVec3::ZERO);
    let along = lighting::unit_or_zero(world.transform_vector3(DVec3::NEG_Z));
    if along == DVec3::ZERO || position.abs().max_element() > MAX_COORDINATE {
        return Err(RequestError::invalid(
            place_at,
            "the node's matrix leaves its light no direction, or puts it beyond the coordinates \
             glint takes",
        ));
    }
    let positional = |spot| Light {
        position: LightPosition::Positional(position),
        ambient: DVec4::new(0.0, 0.0, 0.0, 1.0),
        diffuse: color,
        specular: color,
        attenuation: [0.0, 0.0, 1.0],
        spot,
    };
    Ok(match light.kind.as_str() {
        "directional" => Light {
            position: LightPosition::Directional(-along),
            diffuse: color,
            specular: color,
            ..Light::default()
        },
        "point" => positional(Spot::default()),
        "spot" => {
            let cone = light.spot.clone().unwrap_or_default();
            let inner = cone.inner_cone_angle.unwrap_or(0.0);
            let outer = cone.outer_cone_angle.unwrap_or(std::f64::consts::FRAC_PI_4);
            if !(0.0 <= inner && inner < outer && outer <= std::f64::consts::FRAC_PI_2) {
                return Err(RequestError::invalid(
                    format!("{at}/spot"),
                    format!(
                        "cone angles {inner} and {outer}: glTF asks for 0 ≤ inner < outer ≤ π/2"
                    ),
                ));
            }
            positional(Spot {
                direction: along,
                exponent: spot_exponent(inner, outer),
                cutoff: outer.to_degrees().min(90.0),
            })
        }
        other => {
            return Err(RequestError::invalid(
                format!("{at}/type"),
                format!(
                    "a light of type {other:?}: KHR_lights_punctual has directional, point and spot"
                ),
            ));
        }
    })
}

/// The largest spot exponent the fit gives: GL's own largest.
const MAX_FITTED_SPOT_EXPONENT: f64 = 128.0;

/// The GL spot exponent whose `cos^e` is one half where glTF's falloff is
/// (see the module docs).
fn spot_exponent(inner: f64, outer: f64) -> f64 {
    let (cos_inner, cos_outer) = (inner.cos(), outer.cos());
    let cos_half = cos_outer + (cos_inner - cos_outer) / std::f64::consts::SQRT_2;
    if cos_half >= 1.0 {
        return MAX_FITTED_SPOT_EXPONENT;
    }
    (0.5f64.ln() / cos_half.ln()).min(MAX_FITTED_SPOT_EXPONENT)
}

/// The GL materials of the placed primitives.
pub(super) struct Resolved {
    /// One per distinct glTF material (and glTF's default material) used.
    pub materials: Vec<SurfaceMaterial>,
    /// Their names in a render's material list: the request's key, else
    /// `#<index>` (`#default` for glTF's default material).
    pub names: Vec<String>,
    pub per_instance: Vec<usize>,
    /// The keys of the request's `materials` that named some material.
    pub keys_used: std::collections::BTreeSet<String>,
    pub double_sided: usize,
    pub warnings: Vec<Warning>,
}

pub(super) fn materials_within_limit(named: &wire::Materials) -> Result<()> {
    count_within(
        "/request/materials",
        "materials",
        named.count(),
        wire::MAX_MATERIALS,
        wire::MAX_MATERIALS,
    )
}

/// Each glTF material the instances use as a GL material: the request's
/// by `#<index>`, else by name, else `default`, else by the mapping of
/// its `pbrMetallicRoughness`; behind, `back` or the same material.
pub(super) fn resolve_materials(
    model: &Model,
    instances: &[Instance],
    named: Option<&wire::Materials>,
    default: Option<Material>,
    back: Option<Material>,
) -> Result<Resolved> {
    let mut resolved = Resolved {
        materials: Vec::new(),
        names: Vec::new(),
        per_instance: Vec::with_capacity(instances.len()),
        keys_used: Default::default(),
        double_sided: 0,
        warnings: Vec::new(),
    };
    let mut slots: BTreeMap<Option<usize>, usize> = BTreeMap::new();
    let mut mapped = 0;
    let mut textured = 0;
    let mut extensions = std::collections::BTreeSet::new();
    // The request's keys that name a material: `#<index>`, then each name.
    let lookup = |index: usize| -> Option<(String, &wire::Material)> {
        let named = named?;
        let by_index = format!("#{index}");
        if let Some(m) = named.get(&by_index) {
            return Some((by_index, m));
        }
        let name = model.material_name(index)?;
        named.get(name).map(|m| (name.to_owned(), m))
    };
    if let Some(named) = named {
        // Every key that names some material of the model counts as used,
        // whether or not a placed primitive uses it.
        for index in 0..model.count("materials") {
            if let Some(name) = model.material_name(index)
                && named.contains_key(name)
            {
                resolved.keys_used.insert(name.to_owned());
            }
            let by_index = format!("#{index}");
            if named.contains_key(&by_index) {
                resolved.keys_used.insert(by_index);
            }
        }
    }
    for instance in instances {
        let slot = instance.material;
        if let Some(&index) = slots.get(&slot) {
            resolved.per_instance.push(index);
            continue;
        }
        let (name, front, gltf_material) = match slot {
            Some(i) => {
                let referrer = format!(
                    "/meshes/{}/primitives/{}/material",
                    instance.mesh, instance.primitive
                );
                let material: schema::Material = model.entry("materials", i, &referrer)?;
                match lookup(i) {
                    Some((key, m)) => {
                        let at = format!("/request/materials/{}", pointer_token(&key));
                        (key, validate::material(m, &At::pointer(&at))?, material)
                    }
                    None => (format!("#{i}"), Material::default(), material),
                }
            }
            None => (
                "#default".to_owned(),
                Material::default(),
                schema::Material::default(),
            ),
        };
        let from_request = match slot {
            Some(i) => lookup(i).is_some(),
            None => false,
        };
        let front = if from_request {
            front
        } else if let Some(default) = default {
            default
        } else {
            mapped += 1;
            let at = match slot {
                Some(i) => format!("/model/materials/{i}"),
                None => "/model".to_owned(),
            };
            let (material, looks) = gl_material(&gltf_material, &at)?;
            textured += usize::from(looks.textured);
            extensions.extend(looks.ignored_extensions);
            material
        };
        resolved.double_sided += usize::from(gltf_material.double_sided);
        let index = resolved.materials.len();
        resolved.materials.push(SurfaceMaterial {
            front,
            back: back.unwrap_or(front),
        });
        resolved.names.push(name);
        slots.insert(slot, index);
        resolved.per_instance.push(index);
    }
    let mut warn = |code, count, detail| warn_if(&mut resolved.warnings, code, count, detail);
    warn(
        "pbr_approximated",
        mapped,
        format!(
            "{mapped} glTF materials were mapped to GL's: diffuse = ambient = baseColorFactor, \
             specular = mix(0.04, baseColorFactor, metallic)·(1 − roughness), shininess = \
             2/roughness⁴ − 2 (at most 128), emission = emissiveFactor; GL's lighting is not \
             physically based"
        ),
    );
    warn(
        "textures_not_sampled",
        textured,
        format!(
            "{textured} materials have textures, and GL materials take their factors only; a \
             baseColorTexture stays in the baked model, where a viewer multiplies it by the \
             baked colours"
        ),
    );
    let ignored: Vec<String> = extensions.into_iter().collect();
    warn(
        "material_extensions_ignored",
        ignored.len(),
        format!(
            "material extensions with no GL counterpart were left out of the mapping: {}",
            ignored.join(", ")
        ),
    );
    Ok(resolved)
}

/// What of a glTF material the mapping could not use.
struct Looks {
    textured: bool,
    ignored_extensions: Vec<String>,
}

/// The extensions of a material that the mapping reads.
const MAPPED_MATERIAL_EXTENSIONS: [&str; 2] =
    ["KHR_materials_unlit", "KHR_materials_emissive_strength"];

/// A glTF material as GL's (see the module docs); `at` is where it is.
fn gl_material(m: &schema::Material, at: &str) -> Result<(Material, Looks)> {
    let pbr = m.pbr_metallic_roughness.clone().unwrap_or_default();
    let pbr_at = format!("{at}/pbrMetallicRoughness");
    let unit = |value: f64, pointer: String| {
        if (0.0..=1.0).contains(&value) {
            Ok(value)
        } else {
            Err(RequestError::invalid(
                pointer,
                format!("{value}: glTF's factors lie in [0, 1]"),
            ))
        }
    };
    let base = pbr.base_color_factor.unwrap_or([1.0; 4]);
    for (k, &c) in base.iter().enumerate() {
        unit(c, format!("{pbr_at}/baseColorFactor/{k}"))?;
    }
    let metallic = unit(
        pbr.metallic_factor.unwrap_or(1.0),
        format!("{pbr_at}/metallicFactor"),
    )?;
    let roughness = unit(
        pbr.roughness_factor.unwrap_or(1.0),
        format!("{pbr_at}/roughnessFactor"),
    )?;
    let emissive = m.emissive_factor.unwrap_or([0.0; 3]);
    for (k, &c) in emissive.iter().enumerate() {
        unit(c, format!("{at}/emissiveFactor/{k}"))?;
    }
    let strength = match m.extensions.get("KHR_materials_emissive_strength") {
        None => 1.0,
        Some(e) => {
            let s = e
                .get("emissiveStrength")
                .and_then(|s| s.as_f64())
                .unwrap_or(1.0);
            if !(0.0..=lighting::MAX_COLOR).contains(&s) {
                return Err(RequestError::invalid(
                    format!("{at}/extensions/KHR_materials_emissive_strength/emissiveStrength"),
                    format!("an emissive strength of {s}"),
                ));
            }
            s
        }
    };
    let looks = Looks {
        textured: pbr.base_color_texture.is_some()
            || pbr.metallic_roughness_texture.is_some()
            || m.emissive_texture.is_some()
            || m.normal_texture.is_some()
            || m.occlusion_texture.is_some(),
        ignored_extensions: m
            .extensions
            .keys()
            .filter(|e| !MAPPED_MATERIAL_EXTENSIONS.contains(&e.as_str()))
            .cloned()
            .collect(),
    };
    let base = DVec4::from_array(base);
    let black = DVec4::new(0.0, 0.0, 0.0, 1.0);
    if m.extensions.contains_key("KHR_materials_unlit") {
        // Unlit: the base colour is all there is, whatever the lights.
        return Ok((
            Material {
                ambient: black.truncate().extend(base.w),
                diffuse: black.truncate().extend(base.w),
                specular: black,
                emission: base.truncate().extend(1.0),
                shininess: 0.0,
            },
            looks,
        ));
    }
    let f0 = DVec3::splat(0.04).lerp(base.truncate(), metallic);
    let shininess = if roughness > 0.0 {
        (2.0 / roughness.powi(4) - 2.0).min(MAX_MAPPED_SHININESS)
    } else {
        MAX_MAPPED_SHININESS
    };
    Ok((
        Material {
            ambient: base,
            diffuse: base,
            specular: (f0 * (1.0 - roughness)).extend(1.0),
            emission: (DVec3::from_array(emissive) * strength).extend(1.0),
            shininess,
        },
        looks,
    ))
}

/// The largest shininess the material mapping gives: GL's own largest.
const MAX_MAPPED_SHININESS: f64 = 128.0;

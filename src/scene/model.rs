//! Requests with a glTF model: the `request` part validated as the JSON
//! requests are, the model read and placed by [`glint_model`], and what the
//! request leaves out taken from the model by the mapping of
//! [`super::gltf`], every lossy step of which is a warning.

use glam::{DVec3, Vec4};
use serde::Deserialize;
use serde::de::DeserializeOwned;

use glint_lighting::{LightSet, Precision, SurfaceMaterial, Viewer};
use glint_model::{self as gltf, Instance, Model};
use glint_trace::{Mesh, Object, RenderScene, Shape};

use super::compare::{CompareScene, candidate_error, options as compare_options};
use super::gltf::{
    first_camera, materials_within_limit, model_lights, placement, placement_warnings,
    render_camera, resolve_materials, warn_if,
};
use super::render_scene::pointer_token;
use super::validate::{self, light_set, view_viewer};
use super::{
    At, Limits, RequestError, RequestErrorKind, ShadeScene, TermsDetail, Warning, parse_json,
    render_scene, wire,
};

type Result<T> = std::result::Result<T, RequestError>;

/// How GL's colours are stored in `COLOR_0`, which glTF defines as linear.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorSpace {
    /// `srgb_to_linear(c)`: GL's colours were what a display showed, so a
    /// glTF viewer, encoding linear colours for the display, shows them.
    #[default]
    Display,
    /// GL's numbers as they are.
    Linear,
}

/// The component type of `COLOR_0`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorFormat {
    #[default]
    Unorm16,
    Unorm8,
    Float,
}

/// A validated `/v1/shade` request with a model.
#[derive(Debug)]
pub struct BakeScene<'a> {
    /// The model, to write back with its colours.
    pub model: Model<'a>,
    pub lights: LightSet,
    /// The viewer of the other kind than the lights' (a compare's
    /// `viewer_swapped`).
    pub swapped_viewer: Viewer,
    /// The default scene's triangle primitives, placed, in scene order.
    pub instances: Vec<Instance>,
    /// Per instance, its material in `materials`.
    pub instance_materials: Vec<usize>,
    pub materials: Vec<SurfaceMaterial>,
    pub precision: Precision,
    pub terms: TermsDetail,
    pub color_space: ColorSpace,
    pub color_format: ColorFormat,
    /// What the model's reading and mapping lost or chose, to report.
    pub warnings: Vec<Warning>,
}

impl BakeScene<'_> {
    /// Vertices over every instance.
    pub fn vertices(&self) -> usize {
        self.instances.iter().map(|i| i.positions.len()).sum()
    }
}

impl From<gltf::Error> for RequestError {
    fn from(e: gltf::Error) -> Self {
        let kind = match e.kind {
            gltf::ErrorKind::Malformed => RequestErrorKind::Malformed,
            gltf::ErrorKind::OverLimit => RequestErrorKind::OverLimit,
            gltf::ErrorKind::Unsupported => RequestErrorKind::Unsupported,
            gltf::ErrorKind::Invalid => RequestErrorKind::Invalid,
        };
        RequestError {
            kind,
            pointer: format!("/model{}", e.pointer),
            detail: e.detail,
        }
    }
}

/// An error of the `request` part, located in it.
pub(super) fn in_request(mut e: RequestError) -> RequestError {
    e.pointer = format!("/request{}", e.pointer);
    e
}

/// The `request` part, or its defaults when there is none.
fn request_part<T: DeserializeOwned + Default>(body: Option<&[u8]>) -> Result<T> {
    body.map_or_else(|| Ok(T::default()), |b| parse_json(b).map_err(in_request))
}

/// Parses and validates a `/v1/shade` request with a model.
pub fn parse_bake<'a>(
    request: Option<&[u8]>,
    model: &'a [u8],
    limits: &Limits,
) -> Result<BakeScene<'a>> {
    let request: wire::ShadeRequest = request_part(request)?;
    request.model_form(false).map_err(in_request)?;
    bake_scene(&request, model, limits)
}

/// Validates the `request` part of a shade (or compare) with a model, and
/// the model.
fn bake_scene<'a>(
    request: &wire::ShadeRequest,
    model: &'a [u8],
    limits: &Limits,
) -> Result<BakeScene<'a>> {
    let model = Model::parse(model)?;
    // The light model first: it says whether placed normals are normalised.
    let model_only =
        light_set(request.light_model.as_ref(), None, None, limits).map_err(in_request)?;
    let placed = model.place(&placement(limits, &model_only, false))?;
    let mut warnings = placement_warnings(&placed);

    let local = model_only.model.local_viewer;
    // GL's viewer, and the other kind, which a port with `viewer_swapped`
    // uses.
    let camera = first_camera(&model, &placed)?;
    let viewer_of = |local: bool| -> Result<Viewer> {
        Ok(match (&request.view, &camera) {
            (Some(view), _) => view_viewer(view, local).map_err(in_request)?,
            (None, Some(camera)) => camera.viewer(local),
            (None, None) => LightSet::eye_space_viewer(local),
        })
    };
    let (viewer, swapped_viewer) = (viewer_of(local)?, viewer_of(!local)?);
    let lights = match &request.lights {
        Some(_) => light_set(
            request.light_model.as_ref(),
            request.lights.as_ref(),
            Some(viewer),
            limits,
        )
        .map_err(in_request)?,
        None => {
            let mapped = model_lights(&model, &placed, limits, &mut warnings)?;
            LightSet::new(model_only.model, mapped, viewer).expect("counted against the limit")
        }
    };

    let named = request.materials.as_ref();
    if let Some(named) = named {
        materials_within_limit(named)?;
    }
    let default = request
        .material
        .as_ref()
        .map(|m| validate::material(m, &At::pointer("/request/material")))
        .transpose()?;
    let back = request
        .back_material
        .as_ref()
        .map(|m| validate::material(m, &At::pointer("/request/back_material")))
        .transpose()?;
    let resolved = resolve_materials(&model, &placed.instances, named, default, back)?;
    if let Some(key) = named.and_then(|n| n.keys().find(|k| !resolved.keys_used.contains(*k))) {
        return Err(RequestError::invalid(
            format!("/request/materials/{}", pointer_token(key)),
            format!("{key:?} names no material of the model (by its name or as #<index>)"),
        ));
    }
    warnings.extend(resolved.warnings);
    // Two-sided lighting gives double-sided materials their back.
    if !lights.model.two_side {
        warn_if(
            &mut warnings,
            "double_sided_one_side",
            resolved.double_sided,
            format!(
                "{} double-sided materials are lit on their front side only: their back faces \
                 show the front colour; light_model.two_side lights the back (_GL_BACK_COLOR)",
                resolved.double_sided
            ),
        );
    }

    Ok(BakeScene {
        model,
        lights,
        swapped_viewer,
        instances: placed.instances,
        instance_materials: resolved.per_instance,
        materials: resolved.materials,
        precision: validate::precision(request.precision, "/request")?,
        terms: request.terms.unwrap_or_default(),
        color_space: request.color_space.unwrap_or_default(),
        color_format: request.color_format.unwrap_or_default(),
        warnings,
    })
}

/// Parses and validates a `/v1/compare` with a model: the `request` part
/// (without `candidate`) and a GLB whose primitives' `COLOR_0` hold the
/// candidate, read as `color_space` says (`display`: GL's colours
/// linearised, as a bake writes them). Every primitive must have one GL
/// material: a compare evaluates one.
pub fn parse_compare_model(
    request: Option<&[u8]>,
    model: &[u8],
    limits: &Limits,
) -> Result<CompareScene> {
    let request: wire::ShadeRequest = request_part(request)?;
    request.model_form(true).map_err(in_request)?;
    let options = compare_options(request.worst, request.tolerance, "/request")?;
    let baked = bake_scene(&request, model, limits)?;
    let Some(&first) = baked.instance_materials.first() else {
        return Err(RequestError::invalid(
            "/model",
            "the model's default scene has no triangle primitive to compare",
        ));
    };
    let material = baked.materials[first];
    if baked
        .instance_materials
        .iter()
        .any(|&m| baked.materials[m] != material)
    {
        return Err(RequestError::invalid(
            "/request/material",
            "the model's primitives have different GL materials: a compare evaluates one; \
             give `material` (and no `materials`)",
        ));
    }
    let mut positions = Vec::with_capacity(baked.vertices());
    let mut normals = Vec::with_capacity(baked.vertices());
    let mut front = Vec::with_capacity(baked.vertices());
    for instance in &baked.instances {
        let colors = baked.model.colors(instance)?.ok_or_else(|| {
            RequestError::invalid(
                format!(
                    "/model/meshes/{}/primitives/{}/attributes",
                    instance.mesh, instance.primitive
                ),
                "no COLOR_0: the model carries the candidate's colours in COLOR_0",
            )
        })?;
        let decode = |c: f32| match baked.color_space {
            ColorSpace::Display => glint_lighting::deviation::srgb_encode(f64::from(c)) as f32,
            ColorSpace::Linear => c,
        };
        front.extend(
            colors
                .iter()
                .map(|c| Vec4::new(decode(c[0]), decode(c[1]), decode(c[2]), c[3])),
        );
        positions.extend_from_slice(&instance.positions);
        normals.extend_from_slice(&instance.normals);
    }
    let zero_normals = normals.iter().filter(|n| **n == DVec3::ZERO).count();
    let scene = CompareScene {
        shade: ShadeScene {
            lights: baked.lights,
            material,
            positions,
            normals,
            precision: baked.precision,
            terms: TermsDetail::None,
            zero_normals,
        },
        swapped_viewer: baked.swapped_viewer,
        front,
        back: None,
        options,
    };
    scene
        .candidate()
        .check(&scene.compare_scene())
        .map_err(candidate_error)?;
    Ok(scene)
}

/// Parses and validates a `/v1/render` request with a model: the model's
/// triangles become meshes beside the request's objects, each with the GL
/// material of its glTF material. The warnings say what the mapping lost.
pub fn parse_model_render(
    request: Option<&[u8]>,
    model: &[u8],
    limits: &Limits,
) -> Result<(RenderScene, Vec<Warning>)> {
    let request: wire::RenderRequest = request_part(request)?;
    request.model_form().map_err(in_request)?;
    let model = Model::parse(model)?;
    let model_only =
        light_set(request.light_model.as_ref(), None, None, limits).map_err(in_request)?;
    let placed = model.place(&placement(limits, &model_only, true))?;
    let mut warnings = placement_warnings(&placed);

    let camera = render_camera(&model, &placed, request.camera.as_ref())?;
    let mut scene = render_scene(&request, &camera, limits).map_err(in_request)?;
    if request.lights.is_none() {
        let mapped = model_lights(&model, &placed, limits, &mut warnings)?;
        scene.lights = LightSet::new(scene.lights.model, mapped, scene.lights.viewer)
            .expect("counted against the limit");
    }

    let back = request
        .back_material
        .as_ref()
        .map(|m| validate::material(m, &At::pointer("/request/back_material")))
        .transpose()?;
    let resolved = resolve_materials(
        &model,
        &placed.instances,
        request.materials.as_ref(),
        None,
        back,
    )?;
    warnings.extend(resolved.warnings);
    let first = scene.materials.len();
    scene.materials.extend(resolved.materials);
    scene.material_names.extend(resolved.names);

    let mut vertices: usize = scene
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Mesh(m) => m.positions.len(),
            _ => 0,
        })
        .sum();
    for (instance, material) in placed.instances.into_iter().zip(resolved.per_instance) {
        vertices += instance.positions.len();
        if vertices > limits.max_vertices {
            return Err(RequestError::over_limit(
                format!(
                    "/model/meshes/{}/primitives/{}/attributes/POSITION",
                    instance.mesh, instance.primitive
                ),
                format!(
                    "{vertices} mesh vertices so far, over this server's limit of {}",
                    limits.max_vertices
                ),
            ));
        }
        scene.zero_normals += instance
            .normals
            .iter()
            .filter(|n| **n == DVec3::ZERO)
            .count();
        scene.objects.push(Object {
            shape: Shape::Mesh(Mesh {
                positions: instance.positions,
                normals: Some(instance.normals),
                indices: instance.triangles,
            }),
            material: first + material,
        });
    }
    Ok((scene, warnings))
}

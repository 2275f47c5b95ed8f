//! Rendering a validated `/v1/render` request into its response: the PNG,
//! or its JSON form with the term statistics, the probes' breakdowns, what
//! was modelled and how long each stage took.
//!
//! The term statistics and the probes come from the reference evaluator,
//! whatever the precision (as in [`crate::shade`]): they explain the
//! ground truth, from which an f32 tier's colours differ by at most its
//! documented bound. They are computed only for the JSON form.

use std::time::Instant;

use base64::Engine;
use serde::Serialize;

use glint_trace::{Frame, Probe, RenderScene, Renderer, ShadingMode, Shape, film};

use crate::response::{self, BreakdownOut, PrecisionOut, SummaryOut, Term, precision_warnings};
use crate::scene::Warning;

/// The two forms of a render response.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// `image/png`, the default.
    Png,
    /// `application/json`: [`RenderResponse`].
    Json,
}

/// A response body ready to send.
#[derive(Clone, Debug)]
pub struct Rendered {
    pub body: Vec<u8>,
    pub content_type: &'static str,
    /// Pixels rendered (of the region).
    pub pixels: u64,
}

/// The `200` JSON body of `/v1/render`.
#[derive(Debug, Serialize)]
pub struct RenderResponse {
    pub png_base64: String,
    /// Of the PNG, i.e. of the region.
    pub width: u32,
    pub height: u32,
    pub terms: RenderTerms,
    pub modeled: Vec<Term>,
    pub precision: PrecisionOut,
    pub stats: RenderStats,
    pub warnings: Vec<Warning>,
}

#[derive(Debug, Serialize)]
pub struct RenderTerms {
    /// Over every pixel whose centre ray hit something (`vertices` counts
    /// those pixels); absent when none did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summary: Option<SummaryOut>,
    /// One per requested probe, in order.
    pub probes: Vec<ProbeOut>,
}

#[derive(Debug, Serialize)]
pub struct ProbeOut {
    pub pixel: [u32; 2],
    /// `null` when the centre ray hit nothing.
    pub hit: Option<HitOut>,
    /// The colour of the centre sample, in the request's shading mode and
    /// precision (the background for a miss).
    pub color: [f32; 4],
    /// The reference terms at the hit, before clamping (per pixel, also in
    /// per-vertex mode); `null` for a miss.
    pub breakdown: Option<BreakdownOut>,
}

impl From<&Probe> for ProbeOut {
    fn from(probe: &Probe) -> Self {
        Self {
            pixel: probe.pixel,
            hit: probe.surface.map(|s| HitOut {
                object: s.object,
                point: s.point.to_array(),
                normal: s.normal.to_array(),
                side: s.side_name(),
            }),
            color: probe.color.as_vec4().to_array(),
            breakdown: probe.breakdown.as_ref().map(BreakdownOut::from),
        }
    }
}

#[derive(Debug, Serialize)]
pub struct HitOut {
    /// Index into the request's `objects`.
    pub object: usize,
    pub point: [f64; 3],
    /// The front side's shading normal as given to the lighting equation
    /// (the back side is lit with its negation).
    pub normal: [f64; 3],
    /// The side the ray arrived at: `front` or `back`.
    pub side: &'static str,
}

#[derive(Debug, Serialize)]
pub struct RenderStats {
    /// Of the output (the region).
    pub width: u32,
    pub height: u32,
    pub pixels: u64,
    /// Per pixel: the count, or adaptive sampling's most.
    pub samples: u32,
    /// Samples averaged into a pixel (with adaptive sampling, a corner
    /// counts for each of its four pixels): the mean and the most.
    pub samples_per_pixel: SamplesPerPixel,
    /// The root mean square over the pixels of each pixel's estimated
    /// error (see `glint_trace::film`); `null` with one sample per pixel.
    pub estimated_error: Option<f64>,
    /// Every ray traced: primary, centre, shadow and probe rays.
    pub rays: u64,
    pub triangles: usize,
    pub lights: usize,
    /// Building the geometry, its BVH and the lighting kernels.
    pub bvh_build_ms: f64,
    /// Tracing and lighting the tiles (with the Gouraud vertex colours).
    pub render_ms: f64,
    /// The PNG and its base64 form.
    pub encode_ms: f64,
    /// All of it, probes included.
    pub compute_ms: f64,
}

#[derive(Debug, Serialize)]
pub struct SamplesPerPixel {
    pub mean: f64,
    pub max: u32,
}

/// Renders `scene` in `form` on the current rayon pool; `None` when
/// `cancelled` turned true first.
pub fn render(
    scene: &RenderScene,
    form: Form,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Option<Rendered> {
    render_noted(scene, Vec::new(), form, cancelled)
}

/// [`render`], with `notes` (what reading the request lost or chose, as a
/// model's mapping does) before the JSON form's own warnings.
pub fn render_noted(
    scene: &RenderScene,
    notes: Vec<Warning>,
    form: Form,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Option<Rendered> {
    let pixels = scene.region.pixels();
    match form {
        Form::Png => {
            let renderer = Renderer::new(scene);
            let frame = renderer.render(false, cancelled)?;
            Some(Rendered {
                body: film::encode_png(frame.width, frame.height, &frame.rgba),
                content_type: "image/png",
                pixels,
            })
        }
        Form::Json => {
            let response = render_json_noted(scene, notes, cancelled)?;
            Some(Rendered {
                body: serde_json::to_vec(&response).expect("a response always serialises"),
                content_type: "application/json",
                pixels,
            })
        }
    }
}

/// The PNG of `scene`.
pub fn render_png(scene: &RenderScene) -> Vec<u8> {
    render(scene, Form::Png, &|| false)
        .expect("never cancelled")
        .body
}

/// The JSON form of the response; `None` when `cancelled` turned true first.
pub fn render_json(
    scene: &RenderScene,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Option<RenderResponse> {
    render_json_noted(scene, Vec::new(), cancelled)
}

/// [`render_json`], with `notes` before its own warnings.
pub fn render_json_noted(
    scene: &RenderScene,
    mut notes: Vec<Warning>,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Option<RenderResponse> {
    let started = Instant::now();
    let renderer = Renderer::new(scene);
    let build = renderer.build_time();
    let frame: Frame = renderer.render(true, cancelled)?;
    let probes = scene
        .probes
        .iter()
        .map(|&[x, y]| ProbeOut::from(&renderer.probe(x, y)))
        .collect();

    let encoding = Instant::now();
    let png = film::encode_png(frame.width, frame.height, &frame.rgba);
    let png_base64 = base64::engine::general_purpose::STANDARD.encode(&png);
    let encode_time = encoding.elapsed();

    Some(RenderResponse {
        png_base64,
        width: frame.width,
        height: frame.height,
        terms: RenderTerms {
            summary: frame.summary.map(SummaryOut::from),
            probes,
        },
        modeled: modeled(scene),
        precision: scene.precision.into(),
        stats: RenderStats {
            width: frame.width,
            height: frame.height,
            pixels: scene.region.pixels(),
            samples: scene.samples.max(),
            samples_per_pixel: SamplesPerPixel {
                mean: frame.sampling.mean,
                max: frame.sampling.max,
            },
            estimated_error: frame.sampling.estimated_error,
            rays: renderer.rays(),
            triangles: scene.triangles(),
            lights: scene.lights.lights().len(),
            bvh_build_ms: build.as_secs_f64() * 1e3,
            render_ms: frame.render_time.as_secs_f64() * 1e3,
            encode_ms: encode_time.as_secs_f64() * 1e3,
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        },
        warnings: {
            notes.extend(warnings(scene));
            notes
        },
    })
}

/// The terms computed for some object: [`response::modeled`] over the
/// materials the objects use, in the equation's order.
pub fn modeled(scene: &RenderScene) -> Vec<Term> {
    let mut used = vec![false; scene.materials.len()];
    for o in &scene.objects {
        used[o.material] = true;
    }
    let mut terms: Vec<Term> = scene
        .materials
        .iter()
        .zip(&used)
        .filter(|(_, used)| **used)
        .flat_map(|(m, _)| response::modeled(&scene.lights, m))
        .collect();
    terms.sort_unstable();
    terms.dedup();
    terms
}

/// What the client should know: never a silent change.
pub(crate) fn warnings(scene: &RenderScene) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if scene.shading == ShadingMode::PerVertex {
        let without_vertices = scene
            .objects
            .iter()
            .filter(|o| !matches!(o.shape, Shape::Mesh(_)))
            .count();
        if without_vertices > 0 {
            warnings.push(Warning {
                code: "per_pixel_fallback",
                count: without_vertices,
                detail: format!(
                    "{without_vertices} spheres and planes have no vertices to light: they are \
                     lit per pixel; per_vertex shading applies to meshes"
                ),
            });
        }
    }
    if scene.zero_normals > 0 {
        warnings.push(Warning {
            code: "zero_normals",
            count: scene.zero_normals,
            detail: format!(
                "{} mesh normals have zero length; they get no diffuse or specular light",
                scene.zero_normals
            ),
        });
    }
    let uses = scene
        .objects
        .iter()
        .map(|object| (&scene.materials[object.material], 1));
    warnings.extend(precision_warnings(scene.precision, &scene.lights, uses));
    warnings
}

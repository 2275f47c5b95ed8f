//! Evaluating a validated image compare into its answer: GL's render of the
//! request against the candidate's PNG (the error figures and PSNR, a
//! heatmap of the per-pixel error, the worst pixels with GL's probe there),
//! and the diagnosis from the shading points of the renderer's own samples
//! ([`glint_trace::RenderShading`], [`glint_compare::image::diagnose_image`]),
//! evaluated only at the pixels that differ and an even sample of the rest.
//!
//! Both images are compared as linear colours, as GL's framebuffer holds
//! them: with `"encoding": "srgb"`, both PNGs are decoded first.

use std::time::Instant;

use base64::Engine;
use glam::Vec4;
use glint_compare::image::{
    DEFAULT_OTHERS, DiagnosisOptions, Image, ImageComparison, PixelSelection, compare_images,
    diagnose_image,
};
use glint_trace::{Encoding, Renderer};
use serde::Serialize;

use super::{ErrorOut, ExplanationOut, diagnosis_out, unobservable};
use crate::render::ProbeOut;
use crate::response::PrecisionOut;
use crate::scene::{ImageCompareScene, Warning, srgb_decoded};

/// The largest slope of sRGB's decoding on [0, 1], at 1: `2.4/1.055 ·
/// ((c + 0.055)/1.055)^1.4` (IEC 61966-2-1). A step of an sRGB-encoded
/// channel is at most this many steps of linear colour.
const SRGB_DECODE_SLOPE: f64 = 2.4 / 1.055;

/// Half a step of GL's 8-bit PNG.
const GL_HALF_STEP: f64 = 0.5 / 255.0;

/// The answer of an image compare: its JSON body, and the heatmap's PNG
/// (the answer to `Accept: image/png`).
#[derive(Debug)]
pub struct ImageCompared {
    pub response: ImageCompareResponse,
    pub heatmap_png: Vec<u8>,
}

/// The `200` JSON body of an image compare.
#[derive(Debug, Serialize)]
pub struct ImageCompareResponse {
    pub error: ErrorOut,
    pub worst: Vec<WorstPixelOut>,
    pub diagnosis: Vec<ExplanationOut>,
    /// The per-pixel error (each pixel's largest RGB error) drawn from
    /// black (0) to pale yellow (`heatmap_scale`), the region's size.
    pub heatmap_png_base64: String,
    pub heatmap_scale: f32,
    pub precision: PrecisionOut,
    pub stats: ImageStats,
    pub warnings: Vec<Warning>,
}

/// One of the worst pixels: GL's colour and the candidate's (linear), and
/// GL's probe of the pixel (its centre ray: the hit, the colour there and
/// the reference breakdown, as `/v1/render`'s probes).
#[derive(Debug, Serialize)]
pub struct WorstPixelOut {
    /// Its largest RGB error.
    pub error: f32,
    pub expected: [f32; 4],
    pub candidate: [f32; 4],
    /// `pixel` (of the full image, as probes are), `hit`, `color`,
    /// `breakdown`.
    #[serde(flatten)]
    pub probe: ProbeOut,
}

#[derive(Debug, Serialize)]
pub struct ImageStats {
    /// Of the images (the region).
    pub width: u32,
    pub height: u32,
    pub pixels: u64,
    /// Pixels whose shading points the diagnosis evaluated.
    pub pixels_diagnosed: usize,
    pub lights: usize,
    /// Pairs of deviations evaluated where no single one explained.
    pub pairs_tried: usize,
    /// Rendering GL's image.
    pub render_ms: f64,
    /// The diagnosis.
    pub diagnosis_ms: f64,
    pub compute_ms: f64,
}

/// The bound an image compare holds the error to: the tier's bound, and
/// half a step of each PNG (GL's 8 bits, the candidate's `half_step`), in
/// linear colour: for an sRGB encoding a step of the encoded channel spans
/// at most [`SRGB_DECODE_SLOPE`] steps of linear colour. Two PNGs rounded
/// from colours within the tier's bound of each other are within this.
pub fn image_bound(tier: f64, encoding: Encoding, half_step: f64) -> f64 {
    let slope = match encoding {
        Encoding::Linear => 1.0,
        Encoding::Srgb => SRGB_DECODE_SLOPE,
    };
    tier + slope * (GL_HALF_STEP + half_step)
}

/// Compares the candidate of `scene` with GL's render, on the current
/// rayon pool; `None` when `cancelled` turned true first.
pub fn compare_image(
    scene: &ImageCompareScene,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Option<ImageCompared> {
    let started = Instant::now();
    let render = &scene.render;
    let renderer = Renderer::new(render);
    let frame = renderer.render(false, cancelled)?;
    let render_time = started.elapsed();
    let expected: Vec<Vec4> = frame
        .rgba
        .chunks_exact(4)
        .map(|p| {
            let c = Vec4::new(p[0].into(), p[1].into(), p[2].into(), p[3].into()) / 255.0;
            match render.encoding {
                Encoding::Linear => c,
                Encoding::Srgb => srgb_decoded(c),
            }
        })
        .collect();
    let image = |pixels| Image {
        width: frame.width,
        height: frame.height,
        pixels,
    };
    let (gl, candidate) = (image(&expected[..]), image(&scene.candidate[..]));
    let tier = render.precision.max_abs_error();
    let bound = image_bound(tier, render.encoding, scene.half_step);
    let comparison = compare_images(&gl, &candidate, bound, scene.alpha, scene.options.worst)
        .expect("the parts were checked: the candidate is the render's size, and finite");

    let diagnosing = Instant::now();
    let source = renderer
        .shading_source()
        .expect("the request was checked: its samples are a count");
    let diagnosed = diagnose_image(
        &renderer.image_scene(),
        &comparison,
        &candidate,
        &source,
        DiagnosisOptions {
            selection: PixelSelection::Differing {
                others: DEFAULT_OTHERS,
            },
            tolerance: Some(scene.options.tolerance.unwrap_or(bound)),
            alpha: scene.alpha,
        },
    );
    let diagnosis_time = diagnosing.elapsed();

    let heatmap = heatmap(&comparison, bound);
    let region = render.region;
    let worst = comparison
        .worst
        .iter()
        .map(|w| {
            let [x, y] = w.at;
            WorstPixelOut {
                error: w.error,
                expected: w.expected,
                candidate: w.candidate,
                probe: ProbeOut::from(&renderer.probe(region.x + x, region.y + y)),
            }
        })
        .collect();
    let mut warnings = crate::render::warnings(render);
    warnings.extend(unobservable(&diagnosed.diagnosis));
    let mut error = ErrorOut::from(&comparison.error);
    error.psnr_db = Some(comparison.psnr_db);
    error.bound = Some(bound);
    let response = ImageCompareResponse {
        error,
        worst,
        diagnosis: diagnosis_out(&diagnosed.diagnosis),
        heatmap_png_base64: base64::engine::general_purpose::STANDARD.encode(&heatmap.0),
        heatmap_scale: heatmap.1,
        precision: render.precision.into(),
        stats: ImageStats {
            width: frame.width,
            height: frame.height,
            pixels: region.pixels(),
            pixels_diagnosed: diagnosed.pixels,
            lights: render.lights.lights().len(),
            pairs_tried: diagnosed.diagnosis.pairs_tried,
            render_ms: render_time.as_secs_f64() * 1e3,
            diagnosis_ms: diagnosis_time.as_secs_f64() * 1e3,
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        },
        warnings,
    };
    Some(ImageCompared {
        response,
        heatmap_png: heatmap.0,
    })
}

/// The heatmap's PNG and its scale: the ramp runs to the largest error, or
/// to `bound` where that is larger, so that an image within the bound
/// shows no bright pixel.
fn heatmap(comparison: &ImageComparison, bound: f64) -> (Vec<u8>, f32) {
    let largest = comparison.per_pixel.iter().fold(0.0f32, |m, &e| m.max(e));
    let scale = largest.max(bound as f32);
    (comparison.heatmap(Some(scale)).png(), scale)
}

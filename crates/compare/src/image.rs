//! An image rendered by a port against GL's image of the same scene: the
//! error of each pixel, the figures of [`crate::stats`] with PSNR, a
//! heatmap, the worst pixels, and the diagnosis.
//!
//! The diagnosis needs the deviations evaluated where the pixels were
//! shaded, not another image per deviation. A renderer describes how it
//! made the colours of the pixels asked for ([`ShadingSource`]): each pixel
//! a weighted sum of the colours of shading points (one per sample for
//! per-pixel shading, the vertices of the hit triangle with their
//! barycentric weights for Gouraud shading) and a constant (the
//! background's share). [`diagnose_image`] evaluates every model at those
//! points in the passes of the vertex comparison, composes each model's
//! pixel colours, and ranks the models by the error they leave. Only the
//! pixels that need it are shaded again: those whose error is above the
//! tolerance, and an even sample of the others ([`PixelSelection`]),
//! which a deviation must leave alone to explain the candidate.

use std::io::Cursor;
use std::ops::Range;

use glam::{DVec3, Vec4};
use glint_lighting::deviation::Deviations;
use glint_lighting::{LightMask, LightSet, Precision, Side, SurfaceMaterial, Viewer};
use image::{ImageDecoder, ImageFormat, ImageReader, Limits};
use rayon::prelude::*;

use crate::diagnosis::{Diagnosis, ModelSums, Thresholds, diagnose};
use crate::eval::arith::{AccurateTier, Arith, FastTier, Real, Reference};
use crate::eval::dispatch::{self, Work};
use crate::eval::plan::{Pass, PassScene};
use crate::eval::{BLOCK, Block, Points, unnormalized};
use crate::stats::{ColorLanes, ErrorStats, ErrorSums, Worst, psnr_db};
use crate::vertices::{catalogue, observable_singles, residual};

/// An image of linear RGBA colours, row by row from the top-left pixel.
#[derive(Clone, Copy, Debug)]
pub struct Image<'a> {
    pub width: u32,
    pub height: u32,
    pub pixels: &'a [Vec4],
}

/// Two images that cannot be compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageError {
    /// The candidate is not the size of GL's image.
    Size {
        expected: (u32, u32),
        found: (u32, u32),
    },
    /// An image whose pixels are not `width × height`.
    Pixels {
        width: u32,
        height: u32,
        pixels: usize,
    },
    /// A channel that is NaN or infinite.
    NotFinite { x: u32, y: u32, channel: usize },
}

impl std::fmt::Display for ImageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ImageError::Size { expected, found } => write!(
                f,
                "the candidate is {}×{}, the render {}×{}: give an image of the render's size",
                found.0, found.1, expected.0, expected.1
            ),
            ImageError::Pixels {
                width,
                height,
                pixels,
            } => write!(f, "{pixels} pixels for an image of {width}×{height}"),
            ImageError::NotFinite { x, y, .. } => {
                write!(f, "pixel ({x}, {y}) has a channel that is not finite")
            }
        }
    }
}

impl std::error::Error for ImageError {}

impl Image<'_> {
    fn check(&self) -> Result<(), ImageError> {
        let (width, height) = (self.width, self.height);
        if self.pixels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(ImageError::Pixels {
                width,
                height,
                pixels: self.pixels.len(),
            });
        }
        for (i, p) in self.pixels.iter().enumerate() {
            if let Some(channel) = p.to_array().iter().position(|c| !c.is_finite()) {
                let (x, y) = (i as u32 % width, i as u32 / width);
                return Err(ImageError::NotFinite { x, y, channel });
            }
        }
        Ok(())
    }
}

/// A candidate image against GL's.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageComparison {
    pub width: u32,
    pub height: u32,
    /// Over the RGB channels of every pixel.
    pub error: ErrorStats,
    /// PSNR of the RGB channels, peak 1 ([`psnr_db`]); infinite for equal
    /// images.
    pub psnr_db: f64,
    /// Per pixel, row by row: its largest RGB error.
    pub per_pixel: Vec<f32>,
    /// The pixels with the largest error, worst first, as `[x, y]`.
    pub worst: Vec<Worst<[u32; 2]>>,
}

/// Compares `candidate` with `expected`, GL's image; `bound` is the
/// documented bound of the precision GL's image was rendered at, `alpha`
/// whether alpha is compared, `worst` how many worst pixels to return.
pub fn compare_images(
    expected: &Image,
    candidate: &Image,
    bound: f64,
    alpha: bool,
    worst: usize,
) -> Result<ImageComparison, ImageError> {
    expected.check()?;
    if (candidate.width, candidate.height) != (expected.width, expected.height) {
        return Err(ImageError::Size {
            expected: (expected.width, expected.height),
            found: (candidate.width, candidate.height),
        });
    }
    candidate.check()?;
    let width = expected.width as usize;
    let mut errors = vec![0.0f32; 3 * expected.pixels.len()];
    let mut per_pixel = vec![0.0f32; expected.pixels.len()];
    const ROWS: usize = 16;
    let chunk = ROWS * width.max(1);
    let mut sums = errors
        .par_chunks_mut(3 * chunk)
        .zip(per_pixel.par_chunks_mut(chunk))
        .enumerate()
        .map(|(k, (errors, per_pixel))| {
            let mut sums = ErrorSums::new(worst);
            for (b, per_pixel) in per_pixel.chunks_mut(BLOCK).enumerate() {
                let first = k * chunk + b * BLOCK;
                let len = per_pixel.len();
                let lanes = |image: &Image| -> ColorLanes {
                    std::array::from_fn(|c| {
                        std::array::from_fn(|i| {
                            if i < len {
                                image.pixels[first + i][c]
                            } else {
                                0.0
                            }
                        })
                    })
                };
                let mask = std::array::from_fn(|i| if i < len { 1.0 } else { 0.0 });
                let errors = &mut errors[3 * b * BLOCK..3 * (b * BLOCK + len)];
                sums.add_block(
                    &lanes(expected),
                    &lanes(candidate),
                    &mask,
                    len,
                    errors,
                    |i| {
                        let at = [((first + i) % width) as u32, ((first + i) / width) as u32];
                        (at, (first + i) as u64)
                    },
                );
                for (i, largest) in per_pixel.iter_mut().enumerate() {
                    *largest = errors[3 * i].max(errors[3 * i + 1]).max(errors[3 * i + 2]);
                }
            }
            sums
        })
        .reduce(|| ErrorSums::new(worst), ErrorSums::merge);
    let error = sums.stats(&errors, bound, alpha);
    Ok(ImageComparison {
        width: expected.width,
        height: expected.height,
        error,
        psnr_db: psnr_db(sums.mse(error.channels)),
        per_pixel,
        worst: sums.worst.into_sorted(),
    })
}

/// A heatmap of the per-pixel error: RGBA8, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Heatmap {
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
    /// The error drawn at the top of the ramp.
    pub scale: f32,
}

/// The ramp of the heatmap, from no error to `scale`: black through
/// purple, red and orange to pale yellow, a ramp whose lightness rises
/// steadily (the stops of matplotlib's "inferno" at 0, ¼, ½, ¾ and 1).
const RAMP: [[f32; 3]; 5] = [
    [0.0, 0.0, 4.0],
    [87.0, 16.0, 110.0],
    [188.0, 55.0, 84.0],
    [249.0, 142.0, 9.0],
    [252.0, 255.0, 164.0],
];

impl ImageComparison {
    /// The heatmap of the per-pixel error, drawn on [`RAMP`] from 0 to
    /// `scale` (`None`: the largest error); errors above it saturate.
    pub fn heatmap(&self, scale: Option<f32>) -> Heatmap {
        let largest = self.per_pixel.iter().fold(0.0f32, |m, &e| m.max(e));
        let scale = scale.unwrap_or(largest);
        let rgba8 = self
            .per_pixel
            .iter()
            .flat_map(|&e| {
                let t = if scale > 0.0 {
                    (e / scale).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let [r, g, b] = ramp(t);
                [r, g, b, 255]
            })
            .collect();
        Heatmap {
            width: self.width,
            height: self.height,
            rgba8,
            scale,
        }
    }
}

/// The colour of the ramp at `t` in [0, 1], linear between its stops.
fn ramp(t: f32) -> [u8; 3] {
    let at = t * (RAMP.len() - 1) as f32;
    let i = (at.floor() as usize).min(RAMP.len() - 2);
    let f = at - i as f32;
    std::array::from_fn(|c| (RAMP[i][c] + (RAMP[i + 1][c] - RAMP[i][c]) * f).round() as u8)
}

impl Heatmap {
    /// The heatmap as a PNG file.
    pub fn png(&self) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        image::RgbaImage::from_raw(self.width, self.height, self.rgba8.clone())
            .expect("the heatmap holds width × height pixels")
            .write_to(&mut out, ImageFormat::Png)
            .expect("writing a PNG into memory does not fail");
        out.into_inner()
    }
}

/// A candidate's PNG as linear colours.
#[derive(Clone, Debug, PartialEq)]
pub struct PngImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec4>,
    /// The PNG has an alpha channel.
    pub alpha: bool,
    /// Bits per channel: 8, or 16.
    pub bits: u8,
}

impl PngImage {
    /// Half a step of the PNG's channels, `0.5 / (2^bits − 1)`: how far
    /// from the colour it stands for a channel rounded to the nearest
    /// step may lie.
    pub fn half_step(&self) -> f64 {
        0.5 / f64::from((1u32 << self.bits) - 1)
    }

    pub fn image(&self) -> Image<'_> {
        Image {
            width: self.width,
            height: self.height,
            pixels: &self.pixels,
        }
    }
}

/// A PNG that cannot be a candidate.
#[derive(Debug)]
pub enum PngError {
    /// Not a PNG, or a broken one.
    Unreadable(String),
    /// Larger than the caller allows, refused before its pixels are
    /// decoded.
    TooLarge { width: u32, height: u32 },
}

impl std::fmt::Display for PngError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PngError::Unreadable(why) => write!(f, "not a readable PNG: {why}"),
            PngError::TooLarge { width, height } => {
                write!(f, "a PNG of {width}×{height}, over the limit")
            }
        }
    }
}

impl std::error::Error for PngError {}

/// Reads a PNG's channels as the linear values GL wrote (`value / 255`, or
/// `/ 65535` for 16 bits; grey is R = G = B; no alpha channel is alpha 1),
/// as glint's own renders encode them with `"encoding": "linear"`. A PNG of
/// more than `max_pixels` pixels is refused from its header, before its
/// pixels are decoded.
pub fn read_png(bytes: &[u8], max_pixels: u64) -> Result<PngImage, PngError> {
    let unreadable = |e: image::ImageError| PngError::Unreadable(e.to_string());
    let mut reader = ImageReader::with_format(Cursor::new(bytes), ImageFormat::Png);
    let mut limits = Limits::default();
    // Room for the decoded pixels at 16 bits per channel, and little more.
    limits.max_alloc = Some(max_pixels.saturating_mul(8).saturating_add(1 << 20));
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(unreadable)?;
    let (width, height) = decoder.dimensions();
    if u64::from(width) * u64::from(height) > max_pixels {
        return Err(PngError::TooLarge { width, height });
    }
    let color_type = decoder.color_type();
    let alpha = color_type.has_alpha();
    // Low bit depths are widened to 8 bits as they are decoded.
    let bits = if color_type.bits_per_pixel() / u16::from(color_type.channel_count()) > 8 {
        16
    } else {
        8
    };
    let decoded = image::DynamicImage::from_decoder(decoder).map_err(unreadable)?;
    let pixels = decoded
        .to_rgba32f()
        .pixels()
        .map(|p| Vec4::from_array(p.0))
        .collect();
    Ok(PngImage {
        width,
        height,
        pixels,
        alpha,
        bits,
    })
}

/// Where a renderer shaded a sample: the inputs of the lighting equation
/// there, as the renderer's own lighting reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    pub position: DVec3,
    /// As given to the lighting (normalised there if the model says so).
    pub normal: DVec3,
    /// An index into [`ImageScene::materials`].
    pub material: u32,
    pub side: Side,
    /// Which lights reach the point (all, without shadows).
    pub visible: LightMask,
}

/// How a renderer made the colours of some pixels: each pixel the sum of
/// `weight × colour` over its terms (the colour of a shading point, clamped
/// as the lighting writes it) and its constant.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelShading {
    pub points: Vec<ShadingPoint>,
    /// Per pixel asked for, in order: its terms, a range of `terms`.
    pub pixels: Vec<Range<u32>>,
    /// `(point, weight)`: an index into `points` and its weight.
    pub terms: Vec<(u32, f32)>,
    /// Per pixel asked for: what comes from no shading point (the
    /// background's share of the samples that missed), RGBA.
    pub constant: Vec<Vec4>,
}

impl PixelShading {
    pub fn clear(&mut self) {
        self.points.clear();
        self.pixels.clear();
        self.terms.clear();
        self.constant.clear();
    }
}

/// A renderer that can say how it shaded any pixel of its image.
pub trait ShadingSource: Sync {
    /// The shading of `pixels` (indices `y·width + x`, in this order) into
    /// `out`, which is empty.
    fn shading(&self, pixels: &[u32], out: &mut PixelShading);
}

/// What lights the image.
#[derive(Clone, Copy, Debug)]
pub struct ImageScene<'a> {
    pub lights: &'a LightSet,
    pub materials: &'a [SurfaceMaterial],
    pub precision: Precision,
    /// See [`crate::Scene::swapped_viewer`].
    pub swapped_viewer: Viewer,
    /// The middle of the scene's bounding box, where the f32 lanes are
    /// recentred (as the renderer's kernel recentres them).
    pub centre: DVec3,
    /// Whether some normal the renderer shades with is not of unit length
    /// (a mesh's normals as given), so that a port that does not
    /// normalise them draws something else.
    pub unnormalized_normals: bool,
}

/// Which pixels a diagnosis shades again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelSelection {
    All,
    /// The pixels whose error is above the tolerance, and at most `others`
    /// of the rest, evenly spaced.
    Differing {
        others: usize,
    },
}

/// How many pixels [`PixelSelection::Differing`] takes of the rest by
/// default: enough that a deviation that changes a tenth of a percent of
/// a 1080p image is seen changing some.
pub const DEFAULT_OTHERS: usize = 1 << 16;

/// A diagnosis of an image, and how many pixels it shaded again.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageDiagnosis {
    pub diagnosis: Diagnosis,
    pub pixels: usize,
}

/// What a diagnosis of an image does beyond the comparison's figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiagnosisOptions {
    pub selection: PixelSelection,
    /// What "explains" means; `None`: the tier's bound.
    pub tolerance: Option<f64>,
    /// Whether alpha is compared.
    pub alpha: bool,
}

/// Diagnoses `candidate` (of `comparison`) from the shading of the
/// pixels `options.selection` chooses, as `source` gives it.
pub fn diagnose_image<S: ShadingSource>(
    scene: &ImageScene,
    comparison: &ImageComparison,
    candidate: &Image,
    source: &S,
    options: DiagnosisOptions,
) -> ImageDiagnosis {
    let job = ImageJob {
        scene,
        comparison,
        candidate,
        source,
        options,
    };
    match scene.precision {
        Precision::Reference => job.diagnose::<Reference>(),
        Precision::Accurate => job.diagnose::<AccurateTier>(),
        Precision::Fast => job.diagnose::<FastTier>(),
    }
}

/// The inputs of [`diagnose_image`].
struct ImageJob<'a, S> {
    scene: &'a ImageScene<'a>,
    comparison: &'a ImageComparison,
    candidate: &'a Image<'a>,
    source: &'a S,
    options: DiagnosisOptions,
}

/// The pixels `selection` chooses.
fn selected(comparison: &ImageComparison, selection: PixelSelection, tolerance: f64) -> Vec<u32> {
    let all = 0..comparison.per_pixel.len() as u32;
    match selection {
        PixelSelection::All => all.collect(),
        PixelSelection::Differing { others } => {
            let differs = |i: &u32| f64::from(comparison.per_pixel[*i as usize]) > tolerance;
            let rest = comparison.per_pixel.len() - all.clone().filter(differs).count();
            let stride = rest.div_ceil(others.max(1)).max(1);
            let mut seen = 0usize;
            all.filter(|i| {
                if differs(i) {
                    return true;
                }
                seen += 1;
                (seen - 1).is_multiple_of(stride)
            })
            .collect()
        }
    }
}

/// Pixels per task of a diagnosis.
const TASK_PIXELS: usize = 1024;

impl<S: ShadingSource> ImageJob<'_, S> {
    fn diagnose<A: Arith>(&self) -> ImageDiagnosis {
        let ImageJob {
            scene,
            comparison,
            candidate,
            source,
            options:
                DiagnosisOptions {
                    selection,
                    tolerance,
                    alpha,
                },
        } = *self;
        let bound = scene.precision.max_abs_error();
        let tolerance = tolerance.unwrap_or(bound);
        let pass_scene = PassScene {
            lights: scene.lights,
            swapped_viewer: scene.swapped_viewer,
            materials: scene.materials,
            centre: scene.centre,
            unnormalized_normals: scene.unnormalized_normals,
            alpha,
            // A back face's pixel is the back colour; a port that ignores
            // two-sided lighting draws the front colour there.
            back: scene.lights.model.two_side,
        };
        let (singles, unobservable) =
            observable_singles::<A>(&pass_scene, &catalogue(alpha, pass_scene.back));
        let pixels = selected(comparison, selection, tolerance);
        let evaluate = |models: &[Deviations]| {
            let pass = Pass::<A>::new(&pass_scene, models);
            pixels
                .par_chunks(TASK_PIXELS)
                .map(|chunk| {
                    let mut shading = PixelShading::default();
                    source.shading(chunk, &mut shading);
                    dispatch::run(PixelTask {
                        pass: &pass,
                        scene: &pass_scene,
                        shading: &shading,
                        pixels: chunk,
                        candidate,
                        alpha,
                    })
                })
                .reduce(
                    || vec![ModelSums::default(); models.len()],
                    |a, b| a.iter().zip(b).map(|(a, b)| a.merge(b)).collect(),
                )
        };
        let models: Vec<Deviations> = std::iter::once(Deviations::NONE)
            .chain(singles.iter().copied())
            .collect();
        let sums = evaluate(&models);
        let channels = pixels.len() * if alpha { 4 } else { 3 };
        let diagnosis = diagnose(
            &singles,
            &sums,
            unobservable,
            channels,
            Thresholds { bound, tolerance },
            evaluate,
        );
        ImageDiagnosis {
            diagnosis,
            pixels: pixels.len(),
        }
    }
}

/// The models' sums over one run of pixels.
struct PixelTask<'a, A: Arith> {
    pass: &'a Pass<A>,
    scene: &'a PassScene<'a>,
    shading: &'a PixelShading,
    pixels: &'a [u32],
    candidate: &'a Image<'a>,
    alpha: bool,
}

impl<A: Arith> Work for PixelTask<'_, A> {
    type Out = Vec<ModelSums>;

    #[inline(always)]
    fn run(self) -> Vec<ModelSums> {
        let PixelTask {
            pass,
            scene,
            shading,
            pixels,
            candidate,
            alpha,
        } = self;
        let models = pass.models.len();
        // Each shading point's colour under each model: [point][model].
        let mut colors = vec![[0.0f32; 4]; shading.points.len() * models];
        let mut block = Block::new(pass);
        let front_for_back = pass.models.iter().any(|m| m.front_for_back);
        for (material, side, indices) in groups(&shading.points) {
            let positions: Vec<DVec3> = indices
                .iter()
                .map(|&i| shading.points[i].position)
                .collect();
            let normals: Vec<DVec3> = indices.iter().map(|&i| shading.points[i].normal).collect();
            let mut points = Points::new(
                &positions,
                &normals,
                pass.normalize,
                pass.positions.then_some(scene.centre),
            );
            points.visible = Some(indices.iter().map(|&i| shading.points[i].visible).collect());
            for start in (0..points.len).step_by(BLOCK) {
                let range = start..(start + BLOCK).min(points.len);
                if side == Side::Back && front_for_back {
                    block.load(pass, &points, range.clone(), Side::Front);
                    block.evaluate(pass, material, Side::Front);
                }
                block.load(pass, &points, range.clone(), side);
                block.evaluate(pass, material, side);
                for (lane, &point) in indices[range].iter().enumerate() {
                    for m in 0..models {
                        colors[point * models + m] =
                            std::array::from_fn(|c| block.colors[m][c][lane].wide() as f32);
                    }
                }
            }
        }
        let mut sums = vec![ModelSums::default(); models];
        let channels = if alpha { 4 } else { 3 };
        for (p, &pixel) in pixels.iter().enumerate() {
            let terms =
                &shading.terms[shading.pixels[p].start as usize..shading.pixels[p].end as usize];
            let constant = shading.constant[p].to_array();
            let composed = |m: usize| -> [f32; 4] {
                let mut c = constant;
                for &(point, weight) in terms {
                    let color = colors[point as usize * models + m];
                    for k in 0..4 {
                        c[k] += weight * color[k];
                    }
                }
                c
            };
            let gl = composed(0);
            let want = candidate.pixels[pixel as usize].to_array();
            for (m, model) in sums.iter_mut().enumerate() {
                let color = composed(m);
                let (mut largest, mut sum, mut moved) = (0.0f32, 0.0f32, 0.0f32);
                for c in 0..channels {
                    let e = residual(want[c], color[c]);
                    largest = largest.max(e);
                    sum += e;
                    moved = moved.max(residual(gl[c], color[c]));
                }
                *model = model.merge(ModelSums {
                    max: f64::from(largest),
                    sum: f64::from(sum),
                    shift: f64::from(moved),
                });
            }
        }
        sums
    }
}

/// The shading points by material and side: the points of one group are
/// evaluated together, against one side of one material.
fn groups(points: &[ShadingPoint]) -> Vec<(usize, Side, Vec<usize>)> {
    let mut groups: Vec<(usize, Side, Vec<usize>)> = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let key = (p.material as usize, p.side);
        match groups.iter_mut().find(|g| (g.0, g.1) == key) {
            Some(g) => g.2.push(i),
            None => groups.push((key.0, key.1, vec![i])),
        }
    }
    groups
}

/// Whether any of `normals` is not of unit length: for
/// [`ImageScene::unnormalized_normals`].
pub fn has_unnormalized(normals: &[DVec3]) -> bool {
    unnormalized(normals)
}

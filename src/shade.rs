//! Evaluating a validated `/v1/shade` request into its response body: the
//! evaluator of the requested precision for the colours, the reference
//! evaluator for the term breakdown when one is asked for.
//!
//! The breakdown always comes from the reference evaluator, whatever the
//! precision: it explains the ground truth, and the colours of an f32 tier
//! differ from its sum by at most that tier's documented bound.

use std::cell::RefCell;
use std::sync::OnceLock;
use std::time::Instant;

use glam::{DVec3, Vec4};
use glint_lighting::kernel::{Colors, Kernel, TASK_VERTICES, Tier, Vertices};
use glint_lighting::terms::Summary;
use glint_lighting::{LightSet, Precision, Side, SurfaceMaterial, reference};
use rayon::prelude::*;
use serde::Serialize;

use crate::response::{BreakdownOut, PrecisionOut, SummaryOut, Term, modeled, precision_warnings};
use crate::scene::{ShadeScene, TermsDetail, Warning, wire};

/// The `200` body of `/v1/shade`. [`ShadeResponse::to_json`] writes it,
/// field for field as serde_json would.
#[derive(Debug, Serialize)]
pub struct ShadeResponse {
    /// RGBA, serialised as arrays of four numbers.
    pub colors: Vec<Vec4>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back_colors: Option<Vec<Vec4>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terms: Option<TermsOut>,
    pub modeled: Vec<Term>,
    pub precision: PrecisionOut,
    pub stats: Stats,
    pub warnings: Vec<Warning>,
}

#[derive(Debug, Serialize)]
pub struct Stats {
    pub vertices: usize,
    pub lights: usize,
    pub compute_ms: f64,
}

/// The breakdown of one side.
#[derive(Debug, Serialize)]
pub struct SideTerms {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summary: Option<SummaryOut>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_vertex: Option<Vec<BreakdownOut>>,
}

/// `terms`: the front side's breakdown, and the back side's when two-sided.
#[derive(Debug, Serialize)]
pub struct TermsOut {
    #[serde(flatten)]
    pub front: SideTerms,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back: Option<SideTerms>,
}

impl ShadeResponse {
    /// The JSON body, as serde_json writes this struct, faster.
    ///
    /// The colours are nearly all of a large body, and writing them is a
    /// number formatted per channel: they are written here, straight into
    /// the body, in parallel on the current rayon pool when they are many
    /// (each chunk of vertices into its own buffer, then joined), and serde
    /// writes the rest after them, into the same buffer. The numbers are
    /// those serde_json would write: the same formatter, `zmij`.
    pub fn to_json(&self) -> Vec<u8> {
        let sides = 1 + usize::from(self.back_colors.is_some());
        let mut out = Vec::with_capacity(REST_BYTES + sides * COLOR_BYTES * self.colors.len());
        out.extend_from_slice(br#"{"colors":"#);
        write_colors(&mut out, &self.colors);
        if let Some(back) = &self.back_colors {
            out.extend_from_slice(br#","back_colors":"#);
            write_colors(&mut out, back);
        }
        if self.terms.is_none() && self.warnings.is_empty() {
            write_plain_tail(&mut out, &self.modeled, &self.precision, &self.stats);
            return out;
        }
        // `{"modeled":…}`, whose opening brace becomes the comma after the
        // colours, and whose closing brace closes the body.
        let rest = AfterColors {
            terms: &self.terms,
            modeled: &self.modeled,
            precision: &self.precision,
            stats: &self.stats,
            warnings: &self.warnings,
        };
        let brace = out.len();
        serde_json::to_writer(&mut out, &rest).expect("a response always serialises");
        out[brace] = b',';
        out
    }
}

/// The fields of a [`ShadeResponse`] after its colours, in its order.
#[derive(Serialize)]
struct AfterColors<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    terms: &'a Option<TermsOut>,
    modeled: &'a [Term],
    precision: &'a PrecisionOut,
    stats: &'a Stats,
    warnings: &'a [Warning],
}

/// The fields after the colours of a body with no breakdown and no
/// warning, as serde_json writes them (the most frequent body, whose
/// numbers are few, so that writing the rest through serde would cost
/// more than its colours): term names need no escapes, and the numbers are
/// written by the same formatter.
fn write_plain_tail(out: &mut Vec<u8>, modeled: &[Term], precision: &PrecisionOut, stats: &Stats) {
    out.extend_from_slice(br#","modeled":["#);
    for (i, term) in modeled.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        out.push(b'"');
        out.extend_from_slice(term.name(&mut [0; 40]).as_bytes());
        out.push(b'"');
    }
    out.extend_from_slice(br#"],"precision":"#);
    out.extend_from_slice(precision_json(precision.mode));
    out.extend_from_slice(br#","stats":{"vertices":"#);
    out.extend_from_slice(crate::response::decimal(
        stats.vertices as u64,
        &mut [0; 20],
    ));
    out.extend_from_slice(br#","lights":"#);
    out.extend_from_slice(crate::response::decimal(stats.lights as u64, &mut [0; 20]));
    out.extend_from_slice(br#","compute_ms":"#);
    write_f64(out, stats.compute_ms);
    out.extend_from_slice(br#"},"warnings":[]}"#);
}

/// The [`PrecisionOut`] of `mode` as serde_json writes it. Its bound is the
/// mode's constant, so each mode's object is written once.
fn precision_json(mode: wire::Precision) -> &'static [u8] {
    use wire::Precision::{Accurate, Fast, Reference};
    const MODES: [wire::Precision; 3] = [Reference, Accurate, Fast];
    static WRITTEN: OnceLock<[Vec<u8>; 3]> = OnceLock::new();
    let written = WRITTEN.get_or_init(|| {
        MODES.map(|mode| {
            let out = PrecisionOut::from(Precision::from(mode));
            serde_json::to_vec(&out).expect("a precision serialises")
        })
    });
    let index = MODES.iter().position(|&m| m == mode);
    &written[index.expect("every mode is in MODES")]
}

/// `x` as serde_json writes an `f64`.
fn write_f64(out: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        out.extend_from_slice(zmij::Buffer::new().format_finite(x).as_bytes());
    } else {
        out.extend_from_slice(b"null");
    }
}

/// About the bytes of a body after its colours, without a breakdown.
const REST_BYTES: usize = 512;

/// About the bytes of one colour in JSON: `[0.7357992,0.3371548,0.4068005,1.0],`.
const COLOR_BYTES: usize = 40;

/// `colors` as a JSON array of arrays of four numbers.
fn write_colors(out: &mut Vec<u8>, colors: &[Vec4]) {
    out.push(b'[');
    if colors.len() <= TASK_VERTICES {
        write_color_list(out, colors);
    } else {
        let chunks: Vec<Vec<u8>> = colors
            .par_chunks(TASK_VERTICES)
            .map(|chunk| {
                let mut text = Vec::with_capacity(COLOR_BYTES * chunk.len());
                write_color_list(&mut text, chunk);
                text
            })
            .collect();
        for (i, chunk) in chunks.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            out.extend_from_slice(chunk);
        }
    }
    out.push(b']');
}

/// `[r,g,b,a],[r,g,b,a],…`: each channel as serde_json writes an `f32`.
fn write_color_list(out: &mut Vec<u8>, colors: &[Vec4]) {
    let mut number = zmij::Buffer::new();
    for (i, color) in colors.iter().enumerate() {
        out.extend_from_slice(if i == 0 { b"[" } else { b",[" });
        for (c, channel) in color.to_array().into_iter().enumerate() {
            if c > 0 {
                out.push(b',');
            }
            if channel.is_finite() {
                out.extend_from_slice(number.format_finite(channel).as_bytes());
            } else {
                out.extend_from_slice(b"null");
            }
        }
        out.push(b']');
    }
}

/// Evaluates `scene` on the current rayon pool.
pub fn shade(scene: &ShadeScene) -> ShadeResponse {
    let started = Instant::now();
    let lights = &scene.lights;
    let colors = match scene.precision.tier() {
        None => reference_colors(lights, &scene.material, &scene.positions, &scene.normals),
        Some(tier) => kernel_colors(scene, tier),
    };
    let terms = match scene.terms {
        TermsDetail::None => None,
        detail => Some(TermsOut {
            front: side_terms(scene, Side::Front, detail),
            back: lights
                .model
                .two_side
                .then(|| side_terms(scene, Side::Back, detail)),
        }),
    };
    ShadeResponse {
        colors: colors.front,
        back_colors: colors.back,
        terms,
        modeled: modeled(lights, &scene.material),
        precision: scene.precision.into(),
        stats: Stats {
            vertices: scene.positions.len(),
            lights: lights.lights().len(),
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        },
        warnings: warnings(scene),
    }
}

/// What a shade's client should know of its scene: zero normals, and an
/// f32 tier's bound that the scene's materials may exceed.
pub fn warnings(scene: &ShadeScene) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if scene.zero_normals > 0 {
        warnings.push(Warning {
            code: "zero_normals",
            count: scene.zero_normals,
            detail: format!(
                "{} normals have zero length; they get no diffuse or specular light",
                scene.zero_normals
            ),
        });
    }
    warnings.extend(precision_warnings(
        scene.precision,
        &scene.lights,
        [(&scene.material, scene.positions.len())],
    ));
    warnings
}

fn kernel_colors(scene: &ShadeScene, tier: Tier) -> Colors {
    let kernel = Kernel::new(&scene.lights, &scene.positions);
    let material = kernel.products(&scene.material);
    let (positions, normals) = (&scene.positions, &scene.normals);
    if positions.len() > TASK_VERTICES {
        return kernel.light(tier, &material, &kernel.prepare(positions, normals));
    }
    SMALL_BATCH.with_borrow_mut(|vertices| {
        let pairs = positions.iter().copied().zip(normals.iter().copied());
        kernel.prepare_into(pairs, vertices);
        kernel.light(tier, &material, vertices)
    })
}

thread_local! {
    /// Each thread's prepared vertices of its last batch of one task at
    /// most, whose six arrays keep their memory for the next: for a small
    /// batch, allocating them anew costs about as much as its lighting.
    static SMALL_BATCH: RefCell<Vertices> = RefCell::new(Vertices::default());
}

/// `f` of every vertex (position, normal), in parallel on the current rayon
/// pool for batches worth it: as in the kernel, a batch of one task's
/// vertices is evaluated on the calling thread.
pub(crate) fn map_vertices<T: Send>(
    positions: &[DVec3],
    normals: &[DVec3],
    f: impl Fn(DVec3, DVec3) -> T + Sync,
) -> Vec<T> {
    if positions.len() <= TASK_VERTICES {
        let pairs = positions.iter().zip(normals);
        pairs.map(|(&p, &n)| f(p, n)).collect()
    } else {
        positions
            .par_iter()
            .zip(normals)
            .map(|(&p, &n)| f(p, n))
            .collect()
    }
}

/// The reference evaluator's colours of every vertex, of both sides when
/// the light model is two-sided.
pub(crate) fn reference_colors(
    lights: &LightSet,
    material: &SurfaceMaterial,
    positions: &[DVec3],
    normals: &[DVec3],
) -> Colors {
    let side = |side: Side| -> Vec<Vec4> {
        map_vertices(positions, normals, |p, n| {
            reference::color(lights, material, side, p, n).as_vec4()
        })
    };
    Colors {
        front: side(Side::Front),
        back: lights.model.two_side.then(|| side(Side::Back)),
    }
}

fn side_terms(scene: &ShadeScene, side: Side, detail: TermsDetail) -> SideTerms {
    let breakdowns = map_vertices(&scene.positions, &scene.normals, |p, n| {
        reference::evaluate(&scene.lights, &scene.material, side, p, n)
    });
    SideTerms {
        summary: Summary::of(&breakdowns).map(SummaryOut::from),
        per_vertex: (detail == TermsDetail::PerVertex)
            .then(|| breakdowns.iter().map(BreakdownOut::from).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn response(colors: Vec<Vec4>, back_colors: Option<Vec<Vec4>>) -> ShadeResponse {
        use crate::response::LightTerm;
        let n = colors.len();
        ShadeResponse {
            colors,
            back_colors,
            terms: None,
            modeled: [
                Term::Emission,
                Term::GlobalAmbient,
                Term::Light(0, LightTerm::Diffuse),
                Term::Light(63, LightTerm::Attenuation),
            ][..n.min(4)]
                .to_vec(),
            precision: PrecisionOut::from(
                [Precision::Accurate, Precision::Fast, Precision::Reference][n % 3],
            ),
            stats: Stats {
                vertices: n,
                lights: n % 65,
                compute_ms: [0.125, 1e-7, 0.015599000000000002, 123456.789][n % 4],
            },
            warnings: Vec::new(),
        }
    }

    #[test]
    fn the_body_is_what_serde_json_writes() {
        let some = |n: usize| -> Vec<Vec4> {
            (0..n)
                .map(|i| {
                    let x = i as f32;
                    Vec4::new((x * 0.618).fract(), 1.0 / (x + 3.0), 0.0, 1.0)
                })
                .collect()
        };
        let cases = [
            (Vec::new(), None),
            (some(1), None),
            (some(3), Some(some(3))),
            (
                some(3 * TASK_VERTICES + 17),
                Some(some(3 * TASK_VERTICES + 17)),
            ),
            (vec![Vec4::new(f32::NAN, f32::INFINITY, -0.0, 1e-30)], None),
        ];
        for (colors, back_colors) in cases {
            let expected =
                serde_json::to_vec(&response(colors.clone(), back_colors.clone())).unwrap();
            let written = response(colors, back_colors).to_json();
            assert!(
                written == expected,
                "{}\nagainst\n{}",
                String::from_utf8_lossy(&written[..written.len().min(300)]),
                String::from_utf8_lossy(&expected[..expected.len().min(300)])
            );
        }
    }
}

//! Baking a validated model request ([`BakeScene`]): every placed
//! primitive lit by one light set, prepared once, with its material's
//! products prepared once per material; the colours written back into the
//! model as `COLOR_0` (and `_GL_BACK_COLOR`, and the per-vertex terms), or
//! answered as the JSON of `/v1/shade` with the runs of each primitive.
//!
//! As in [`crate::shade`], the term breakdown comes from the reference
//! evaluator whatever the precision.

use std::collections::BTreeSet;
use std::time::Instant;

use glam::{DVec3, Vec4};
use glint_lighting::kernel::{Colors, Kernel};
use glint_lighting::terms::{Breakdown, Summary};
use glint_lighting::{Side, SurfaceMaterial, reference};
use glint_model::Instance;
use glint_model::edit::{Edit, Format, Written};
use rayon::prelude::*;
use serde::Serialize;

use crate::response::{BreakdownOut, PrecisionOut, SummaryOut, Term, modeled, precision_warnings};
use crate::scene::{BakeScene, ColorFormat, ColorSpace, TermsDetail, Warning};
use crate::shade::{SideTerms, TermsOut, map_vertices, reference_colors};

/// The two forms of a model shade's response.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// `model/gltf-binary`, the default: the model, baked.
    Glb,
    /// `application/json`: [`BakeResponse`].
    Json,
}

/// A response body ready to send.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The JSON whole (in `head`), or the baked model, whose middle is the
    /// input model's buffer as it was read.
    pub body: Written,
    pub content_type: &'static str,
    /// Vertices lit.
    pub vertices: usize,
}

/// The JSON form: `/v1/shade`'s response, with the run of `colors` that
/// belongs to each primitive as its node places it.
#[derive(Debug, Serialize)]
pub struct BakeResponse {
    pub colors: Vec<Vec4>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back_colors: Option<Vec<Vec4>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terms: Option<TermsOut>,
    pub primitives: Vec<PrimitiveRun>,
    pub modeled: Vec<Term>,
    pub precision: PrecisionOut,
    pub stats: BakeStats,
    pub warnings: Vec<Warning>,
}

/// The colours of one primitive as one node places it.
#[derive(Debug, Serialize)]
pub struct PrimitiveRun {
    pub node: usize,
    pub mesh: usize,
    pub primitive: usize,
    /// Its first vertex in `colors`.
    pub first: usize,
    /// Its vertices: those of its `POSITION` accessor.
    pub count: usize,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct BakeStats {
    pub vertices: usize,
    /// Primitives shaded, a mesh counted once per node that uses it.
    pub primitives: usize,
    pub lights: usize,
    pub compute_ms: f64,
}

/// What a baked model says of itself, in its root's `extras.glint`.
#[derive(Debug, Serialize)]
struct Extras<'a> {
    modeled: &'a [Term],
    precision: PrecisionOut,
    stats: BakeStats,
    warnings: &'a [Warning],
    #[serde(skip_serializing_if = "Option::is_none")]
    summary: Option<SummaryOut>,
    #[serde(skip_serializing_if = "Option::is_none")]
    back_summary: Option<SummaryOut>,
}

/// The lit instances.
struct Lit {
    /// Per instance.
    colors: Vec<Colors>,
    /// Per side (front, back when two-sided), per instance, per vertex.
    breakdowns: Option<[Option<Vec<Vec<Breakdown>>>; 2]>,
}

/// Lights `scene` on the current rayon pool and answers in `form`.
pub fn bake(scene: BakeScene, form: Form) -> Baked {
    let started = Instant::now();
    let lit = light(&scene);
    let modeled = modeled_terms(&scene);
    let precision_notes = precision_notes(&scene);
    let vertices = scene.vertices();
    let two_side = scene.lights.model.two_side;
    let BakeScene {
        model,
        lights,
        instances,
        precision,
        terms,
        color_space,
        color_format,
        mut warnings,
        ..
    } = scene;
    warnings.extend(precision_notes);
    let mut stats = BakeStats {
        vertices,
        primitives: instances.len(),
        lights: lights.lights().len(),
        compute_ms: 0.0,
    };
    let [front_summary, back_summary] = match &lit.breakdowns {
        None => [None, None],
        Some(sides) => sides.each_ref().map(|side| {
            side.as_ref()
                .and_then(|per_instance| Summary::of(&per_instance.concat()))
                .map(SummaryOut::from)
        }),
    };
    match form {
        Form::Json => {
            let mut first = 0;
            let primitives = instances
                .iter()
                .map(|i| {
                    let run = PrimitiveRun {
                        node: i.node,
                        mesh: i.mesh,
                        primitive: i.primitive,
                        first,
                        count: i.positions.len(),
                    };
                    first += run.count;
                    run
                })
                .collect();
            let per_vertex = |side: &Option<Vec<Vec<Breakdown>>>| {
                (terms == TermsDetail::PerVertex).then(|| {
                    side.iter()
                        .flatten()
                        .flatten()
                        .map(BreakdownOut::from)
                        .collect()
                })
            };
            let terms = lit.breakdowns.as_ref().map(|[front, back]| TermsOut {
                front: SideTerms {
                    summary: front_summary,
                    per_vertex: per_vertex(front),
                },
                back: two_side.then(|| SideTerms {
                    summary: back_summary,
                    per_vertex: per_vertex(back),
                }),
            });
            let colors = lit
                .colors
                .iter()
                .flat_map(|c| c.front.iter().copied())
                .collect();
            let back_colors = two_side.then(|| {
                lit.colors
                    .iter()
                    .flat_map(|c| c.back.iter().flatten().copied())
                    .collect()
            });
            stats.compute_ms = started.elapsed().as_secs_f64() * 1e3;
            let response = BakeResponse {
                colors,
                back_colors,
                terms,
                primitives,
                modeled,
                precision: precision.into(),
                stats,
                warnings,
            };
            Baked {
                body: Written {
                    head: serde_json::to_vec(&response).expect("a response always serialises"),
                    bin: 0..0,
                    tail: Vec::new(),
                },
                content_type: "application/json",
                vertices,
            }
        }
        Form::Glb => {
            let mut edit = Edit::new(model);
            write_attributes(
                &mut edit,
                &instances,
                &lit,
                terms == TermsDetail::PerVertex,
                (color_space, color_format),
            );
            let replaced = edit.replaced_colors();
            if replaced > 0 {
                warnings.push(Warning {
                    code: "colors_replaced",
                    count: replaced,
                    detail: format!(
                        "{replaced} primitives had a COLOR_0 of their own: the baked colours \
                         replace it"
                    ),
                });
            }
            stats.compute_ms = started.elapsed().as_secs_f64() * 1e3;
            let extras = Extras {
                modeled: &modeled,
                precision: precision.into(),
                stats,
                warnings: &warnings,
                summary: front_summary,
                back_summary: if two_side { back_summary } else { None },
            };
            let extras = serde_json::to_value(extras).expect("extras always serialise");
            Baked {
                body: edit.finish(extras),
                content_type: glint_model::glb::MEDIA_TYPE,
                vertices,
            }
        }
    }
}

/// The colours of every instance, and the breakdowns when asked for.
fn light(scene: &BakeScene) -> Lit {
    let colors = match scene.precision.tier() {
        None => scene
            .instances
            .iter()
            .zip(&scene.instance_materials)
            .map(|(instance, &m)| {
                reference_colors(
                    &scene.lights,
                    &scene.materials[m],
                    &instance.positions,
                    &instance.normals,
                )
            })
            .collect(),
        Some(tier) => {
            // The kernel recentres on the middle of every vertex's bounding
            // box, which its two corners have too.
            let (lo, hi) = scene
                .instances
                .iter()
                .flat_map(|i| &i.positions)
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                    (lo.min(p), hi.max(p))
                });
            let corners = if lo.cmple(hi).all() {
                vec![lo, hi]
            } else {
                Vec::new()
            };
            let kernel = Kernel::new(&scene.lights, &corners);
            let products: Vec<_> = scene.materials.iter().map(|m| kernel.products(m)).collect();
            scene
                .instances
                .iter()
                .zip(&scene.instance_materials)
                .map(|(instance, &m)| {
                    let vertices = kernel.prepare(&instance.positions, &instance.normals);
                    kernel.light(tier, &products[m], &vertices)
                })
                .collect()
        }
    };
    let breakdowns = (scene.terms != TermsDetail::None).then(|| {
        let side = |side: Side| -> Vec<Vec<Breakdown>> {
            scene
                .instances
                .iter()
                .zip(&scene.instance_materials)
                .map(|(instance, &m)| {
                    map_vertices(&instance.positions, &instance.normals, |p, n| {
                        reference::evaluate(&scene.lights, &scene.materials[m], side, p, n)
                    })
                })
                .collect()
        };
        [
            Some(side(Side::Front)),
            scene.lights.model.two_side.then(|| side(Side::Back)),
        ]
    });
    Lit { colors, breakdowns }
}

/// The materials the instances use.
fn used_materials<'s>(scene: &'s BakeScene) -> impl Iterator<Item = (usize, &'s SurfaceMaterial)> {
    let used: BTreeSet<usize> = scene.instance_materials.iter().copied().collect();
    used.into_iter().map(|m| (m, &scene.materials[m]))
}

/// [`modeled`] over the materials used, in the equation's order.
fn modeled_terms(scene: &BakeScene) -> Vec<Term> {
    let mut terms: Vec<Term> = used_materials(scene)
        .flat_map(|(_, m)| modeled(&scene.lights, m))
        .collect();
    terms.sort_unstable();
    terms.dedup();
    terms
}

/// The precision warnings of the materials used, each counting the
/// vertices it lights.
fn precision_notes(scene: &BakeScene) -> Vec<Warning> {
    let uses = used_materials(scene).map(|(m, material)| {
        let vertices: usize = scene
            .instances
            .iter()
            .zip(&scene.instance_materials)
            .filter(|(_, used)| **used == m)
            .map(|(i, _)| i.positions.len())
            .sum();
        (material, vertices)
    });
    precision_warnings(scene.precision, &scene.lights, uses)
}

/// `c` as `COLOR_0` stores it: `srgb_to_linear` of the colour channels in
/// the display space, alpha as it is.
pub fn stored_color(c: Vec4, space: ColorSpace) -> Vec4 {
    match space {
        ColorSpace::Linear => c,
        ColorSpace::Display => {
            let decode = SrgbDecode::get();
            Vec4::new(decode.at(c.x), decode.at(c.y), decode.at(c.z), c.w)
        }
    }
}

/// sRGB's decoding (IEC 61966-2-1) on [0, 1], where clamped colours lie.
pub(crate) fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Steps of [`SrgbDecode`]'s table.
const SRGB_STEPS: usize = 4096;

/// [`srgb_to_linear`] interpolated linearly in a table of its values: the
/// curve's second derivative is below 3 on [0, 1], so the interpolation
/// is within `3 · (1/4096)² / 8 ≈ 2e-8` of it (and of its kink at 0.04045,
/// where the slopes of its two pieces differ by 0.0013, within 1e-7),
/// far below a 16-bit step. A `powf` per channel would cost more than the
/// lighting.
struct SrgbDecode([f32; SRGB_STEPS + 1]);

impl SrgbDecode {
    fn get() -> &'static Self {
        static TABLE: std::sync::OnceLock<SrgbDecode> = std::sync::OnceLock::new();
        TABLE.get_or_init(|| {
            SrgbDecode(std::array::from_fn(|i| {
                srgb_to_linear(i as f64 / SRGB_STEPS as f64) as f32
            }))
        })
    }

    fn at(&self, c: f32) -> f32 {
        let x = c.clamp(0.0, 1.0) * SRGB_STEPS as f32;
        let i = (x as usize).min(SRGB_STEPS - 1);
        let t = x - i as f32;
        self.0[i] + t * (self.0[i + 1] - self.0[i])
    }
}

/// Colours per rayon task when they are written.
const TASK_COLORS: usize = 16 * 1024;

/// Writes `colors` into `out` in `format`: normalised integers rounded to
/// the nearest (`i = round(c · max)`), or floats.
fn write_colors(out: &mut [u8], colors: &[Vec4], space: ColorSpace, format: ColorFormat) {
    let bytes = color_format(format).bytes();
    out.par_chunks_exact_mut(bytes)
        .zip(colors.par_iter())
        .with_min_len(TASK_COLORS)
        .for_each(|(bytes, &c)| {
            let c = stored_color(c, space).to_array();
            match format {
                ColorFormat::Float => {
                    for (b, x) in bytes.chunks_exact_mut(4).zip(c) {
                        b.copy_from_slice(&x.to_le_bytes());
                    }
                }
                ColorFormat::Unorm16 => {
                    for (b, x) in bytes.chunks_exact_mut(2).zip(c) {
                        // Rounded to the nearest: the value is not negative.
                        let i = (x.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16;
                        b.copy_from_slice(&i.to_le_bytes());
                    }
                }
                ColorFormat::Unorm8 => {
                    for (b, x) in bytes.iter_mut().zip(c) {
                        *b = (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                    }
                }
            }
        });
}

fn color_format(format: ColorFormat) -> Format {
    match format {
        ColorFormat::Unorm16 => Format::Vec4Unorm16,
        ColorFormat::Unorm8 => Format::Vec4Unorm8,
        ColorFormat::Float => Format::Vec4F32,
    }
}

/// The per-vertex terms as attributes: name, and the term of a breakdown.
/// A term's sum of a breakdown.
type TermOf = fn(&Breakdown) -> DVec3;

const TERM_ATTRIBUTES: [(&str, &str, TermOf); 4] = [
    ("_GL_EMISSION", "_GL_BACK_EMISSION", |b| b.emission),
    ("_GL_AMBIENT", "_GL_BACK_AMBIENT", |b| {
        b.lights
            .iter()
            .fold(b.global_ambient, |sum, l| sum + l.ambient)
    }),
    ("_GL_DIFFUSE", "_GL_BACK_DIFFUSE", |b| {
        b.lights.iter().map(|l| l.diffuse).sum()
    }),
    ("_GL_SPECULAR", "_GL_BACK_SPECULAR", |b| {
        b.lights.iter().map(|l| l.specular).sum()
    }),
];

/// Each instance's colours, terms and unlit material into `edit`.
fn write_attributes(
    edit: &mut Edit,
    instances: &[Instance],
    lit: &Lit,
    per_vertex: bool,
    (space, format): (ColorSpace, ColorFormat),
) {
    for (k, (instance, colors)) in instances.iter().zip(&lit.colors).enumerate() {
        let (node, mesh, primitive) = (instance.node, instance.mesh, instance.primitive);
        let n = instance.positions.len();
        let sides = [
            ("COLOR_0", Some(&colors.front)),
            ("_GL_BACK_COLOR", colors.back.as_ref()),
        ];
        for (name, side) in sides {
            if let Some(side) = side {
                let out = edit.attribute(node, mesh, primitive, name, color_format(format), n);
                write_colors(out, side, space, format);
            }
        }
        if let (true, Some(breakdowns)) = (per_vertex, &lit.breakdowns) {
            for (s, side) in breakdowns.iter().enumerate() {
                let Some(side) = side else { continue };
                for (front_name, back_name, term) in TERM_ATTRIBUTES {
                    let name = if s == 0 { front_name } else { back_name };
                    let out = edit.attribute(node, mesh, primitive, name, Format::Vec3F32, n);
                    for (bytes, b) in out.chunks_exact_mut(12).zip(&side[k]) {
                        for (chunk, x) in bytes.chunks_exact_mut(4).zip(term(b).to_array()) {
                            chunk.copy_from_slice(&(x as f32).to_le_bytes());
                        }
                    }
                }
            }
        }
        edit.unlit_material(node, mesh, primitive, instance.material);
    }
}

//! Evaluating a validated `/v1/shade` request into its response body: the
//! evaluator of the requested precision for the colours, the reference
//! evaluator for the term breakdown when one is asked for.
//!
//! The breakdown always comes from the reference evaluator, whatever the
//! precision: it explains the ground truth, and the colours of an f32 tier
//! differ from its sum by at most that tier's documented bound.

use std::time::Instant;

use glam::{DVec3, Vec4};
use glint_lighting::kernel::{Colors, Kernel, TASK_VERTICES, Tier};
use glint_lighting::terms::Summary;
use glint_lighting::{Precision, Side, reference};
use rayon::prelude::*;
use serde::Serialize;

use crate::response::{
    BreakdownOut, PrecisionOut, SummaryOut, Term, Warning, modeled, precision_bound_reasons,
};
use crate::scene::{ShadeScene, TermsDetail};

/// The `200` body of `/v1/shade`.
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

/// Evaluates `scene` on the current rayon pool.
pub fn shade(scene: &ShadeScene) -> ShadeResponse {
    let started = Instant::now();
    let lights = &scene.lights;
    let colors = match scene.precision.tier() {
        None => reference_colors(scene),
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
    warnings.extend(precision_warnings(scene));
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
        warnings,
    }
}

/// [`precision_bound_reasons`] as warnings about every vertex.
fn precision_warnings(scene: &ShadeScene) -> Vec<Warning> {
    if scene.precision == Precision::Reference || scene.positions.is_empty() {
        return Vec::new();
    }
    precision_bound_reasons(&scene.lights, &scene.material)
        .into_iter()
        .map(|detail| Warning {
            code: "precision_bound",
            count: scene.positions.len(),
            detail,
        })
        .collect()
}

fn kernel_colors(scene: &ShadeScene, tier: Tier) -> Colors {
    let kernel = Kernel::new(&scene.lights, &scene.positions);
    let material = kernel.products(&scene.material);
    kernel.light(
        tier,
        &material,
        &kernel.prepare(&scene.positions, &scene.normals),
    )
}

/// `f` of every vertex (position, normal), in parallel on the current rayon
/// pool for batches worth it: as in the kernel, a batch of one task's
/// vertices is evaluated on the calling thread.
fn map_vertices<T: Send>(scene: &ShadeScene, f: impl Fn(DVec3, DVec3) -> T + Sync) -> Vec<T> {
    if scene.positions.len() <= TASK_VERTICES {
        let pairs = scene.positions.iter().zip(&scene.normals);
        pairs.map(|(&p, &n)| f(p, n)).collect()
    } else {
        scene
            .positions
            .par_iter()
            .zip(&scene.normals)
            .map(|(&p, &n)| f(p, n))
            .collect()
    }
}

fn reference_colors(scene: &ShadeScene) -> Colors {
    let side = |side: Side| -> Vec<Vec4> {
        map_vertices(scene, |p, n| {
            reference::color(&scene.lights, &scene.material, side, p, n).as_vec4()
        })
    };
    Colors {
        front: side(Side::Front),
        back: scene.lights.model.two_side.then(|| side(Side::Back)),
    }
}

fn side_terms(scene: &ShadeScene, side: Side, detail: TermsDetail) -> SideTerms {
    let breakdowns = map_vertices(scene, |p, n| {
        reference::evaluate(&scene.lights, &scene.material, side, p, n)
    });
    SideTerms {
        summary: Summary::of(&breakdowns).map(SummaryOut::from),
        per_vertex: (detail == TermsDetail::PerVertex)
            .then(|| breakdowns.iter().map(BreakdownOut::from).collect()),
    }
}

//! Evaluating a validated `/v1/compare` request into its response body: the
//! candidate's error against GL's colours of the requested precision, its
//! worst vertices with the reference's term breakdown, and the deviations
//! of the catalogue that explain it, ranked (see [`glint_compare`]).

use std::time::Instant;

use glint_compare::{Comparison, Diagnosis, ErrorStats, VertexAt, Worst};
use glint_lighting::{Side, reference};
use serde::Serialize;

use crate::response::{BreakdownOut, PrecisionOut};
use crate::scene::{CompareScene, RequestError, Warning, candidate_error};

pub mod image;

/// The `200` body of `/v1/compare`.
#[derive(Debug, Serialize)]
pub struct CompareResponse {
    pub error: ErrorOut,
    pub worst: Vec<WorstOut>,
    pub diagnosis: Vec<ExplanationOut>,
    pub precision: PrecisionOut,
    pub stats: Stats,
    pub warnings: Vec<Warning>,
}

/// `error`: over the RGB channels of every colour compared.
#[derive(Debug, Serialize)]
pub struct ErrorOut {
    pub max_abs: f64,
    pub mean_abs: f64,
    pub p99_abs: f64,
    pub differing_8bit: f64,
    pub within_bound: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_max_abs: Option<f64>,
    /// Images only: PSNR of the RGB channels in dB, peak 1; `null` for
    /// equal images (infinite).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub psnr_db: Option<f64>,
    /// Images only: the bound `within_bound` holds the error to, the
    /// tier's and the rounding of the two PNGs ([`image::image_bound`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bound: Option<f64>,
}

impl From<&ErrorStats> for ErrorOut {
    fn from(e: &ErrorStats) -> Self {
        Self {
            max_abs: e.max_abs,
            mean_abs: e.mean_abs,
            p99_abs: e.p99_abs,
            differing_8bit: e.differing_8bit,
            within_bound: e.within_bound,
            alpha_max_abs: e.alpha_max_abs,
            psnr_db: None,
            bound: None,
        }
    }
}

/// One of the worst vertices: GL's colour, the candidate's, and GL's terms.
#[derive(Debug, Serialize)]
pub struct WorstOut {
    pub vertex: usize,
    /// `back` for a back colour; absent for the front.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub side: Option<&'static str>,
    pub error: f32,
    pub expected: [f32; 4],
    pub candidate: [f32; 4],
    pub breakdown: BreakdownOut,
}

/// One explanation of the diagnosis.
#[derive(Debug, Serialize)]
pub struct ExplanationOut {
    pub deviations: Vec<&'static str>,
    pub max_abs: f64,
    pub mean_abs: f64,
    pub explains: bool,
    pub detail: String,
}

/// The diagnosis as the answer lists it, best explanation first.
fn diagnosis_out(d: &Diagnosis) -> Vec<ExplanationOut> {
    d.explanations
        .iter()
        .map(|e| ExplanationOut {
            deviations: e.deviations.iter().map(|d| d.name()).collect(),
            max_abs: e.max_abs,
            mean_abs: e.mean_abs,
            explains: e.explains,
            detail: e.detail(),
        })
        .collect()
}

#[derive(Debug, Serialize)]
pub struct Stats {
    pub vertices: usize,
    pub lights: usize,
    /// Pairs of deviations evaluated where no single one explained.
    pub pairs_tried: usize,
    pub compute_ms: f64,
}

/// Compares the candidate of `scene` with GL, on the current rayon pool.
pub fn compare(scene: &CompareScene) -> Result<CompareResponse, RequestError> {
    let started = Instant::now();
    let comparison =
        glint_compare::compare(&scene.compare_scene(), &scene.candidate(), &scene.options)
            .map_err(candidate_error)?;
    let shade = &scene.shade;
    let Comparison {
        error,
        worst,
        diagnosis,
        ..
    } = &comparison;
    let mut warnings = crate::shade::warnings(shade);
    warnings.extend(unobservable(diagnosis));
    Ok(CompareResponse {
        error: error.into(),
        worst: worst.iter().map(|w| worst_out(scene, w)).collect(),
        diagnosis: diagnosis_out(diagnosis),
        precision: shade.precision.into(),
        stats: Stats {
            vertices: shade.positions.len(),
            lights: shade.lights.lights().len(),
            pairs_tried: diagnosis.pairs_tried,
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        },
        warnings,
    })
}

/// The warning that some deviations cannot show in this scene, if any.
fn unobservable(diagnosis: &Diagnosis) -> Option<Warning> {
    if diagnosis.unobservable.is_empty() {
        return None;
    }
    let names: Vec<&str> = diagnosis.unobservable.iter().map(|d| d.name()).collect();
    Some(Warning {
        code: "deviations_unobservable",
        count: names.len(),
        detail: format!(
            "this scene draws the same colours with or without these deviations, so none of \
             them can be told apart from GL: {}",
            names.join(", ")
        ),
    })
}

fn worst_out(scene: &CompareScene, w: &Worst<VertexAt>) -> WorstOut {
    let shade = &scene.shade;
    let VertexAt { vertex, side } = w.at;
    let breakdown = reference::evaluate(
        &shade.lights,
        &shade.material,
        side,
        shade.positions[vertex],
        shade.normals[vertex],
    );
    WorstOut {
        vertex,
        side: (side == Side::Back).then_some("back"),
        error: w.error,
        expected: w.expected,
        candidate: w.candidate,
        breakdown: BreakdownOut::from(&breakdown),
    }
}

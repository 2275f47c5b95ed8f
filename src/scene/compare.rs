//! `POST /v1/compare`'s request: a shade request (validated as `/v1/shade`
//! validates it) with the candidate's colours and what to report. The
//! candidate's own faults (a colour count other than the vertex count, a
//! channel that is not finite) are located under `/candidate`.

use glam::{DVec3, Vec4};
use glint_compare::{CandidateError, Options};
use glint_lighting::reference::Port;
use glint_lighting::{Viewer, unit_or_zero};

use super::validate::{count_within, vertex_scene};
use super::{Limits, RequestError, ShadeScene, parse_json, wire};

type Result<T> = std::result::Result<T, RequestError>;

/// The most worst vertices or pixels a compare reports: a bound of the
/// contract (422 past it), so that the list is never sized by a client.
pub const MAX_WORST: usize = 1000;

/// A validated compare of per-vertex colours.
#[derive(Clone, Debug)]
pub struct CompareScene {
    pub shade: ShadeScene,
    /// The viewer of the other kind, for `viewer_swapped`.
    pub swapped_viewer: Viewer,
    pub front: Vec<Vec4>,
    pub back: Option<Vec<Vec4>>,
    pub options: Options,
}

impl CompareScene {
    /// The scene as `glint_compare` takes it.
    pub fn compare_scene(&self) -> glint_compare::Scene<'_> {
        glint_compare::Scene {
            lights: &self.shade.lights,
            material: &self.shade.material,
            positions: &self.shade.positions,
            normals: &self.shade.normals,
            precision: self.shade.precision,
            swapped_viewer: self.swapped_viewer,
        }
    }

    /// The candidate as `glint_compare` takes it: RGBA, alpha compared.
    pub fn candidate(&self) -> glint_compare::Candidate<'_> {
        glint_compare::Candidate {
            front: &self.front,
            back: self.back.as_deref(),
            alpha: true,
        }
    }
}

/// Parses and validates a `/v1/compare` JSON body.
pub fn parse_compare(body: &[u8], limits: &Limits) -> Result<CompareScene> {
    let request: wire::ShadeRequest = parse_json(body)?;
    let (vertices, candidate) = request.compare_form()?;
    let shade = vertex_scene(&request, vertices, limits)?;
    let to_vec4 = |colors: &[[f32; 4]]| colors.iter().map(|&c| Vec4::from(c)).collect();
    let scene = CompareScene {
        swapped_viewer: swapped_viewer(&request),
        front: to_vec4(&candidate.colors),
        back: candidate.back_colors.as_deref().map(to_vec4),
        options: options(request.worst, request.tolerance, "")?,
        shade,
    };
    check_candidate(&scene)?;
    Ok(scene)
}

/// The viewer a port with `viewer_swapped` uses: the eye point and the
/// direction towards it of the request's view, or of eye space.
pub(super) fn swapped_viewer(request: &wire::ShadeRequest) -> Viewer {
    let local = super::validate::request_local_viewer(&request.light_model);
    let (eye, towards_eye) = match &request.view {
        Some(view) => {
            let eye = DVec3::from(view.eye);
            (eye, unit_or_zero(eye - DVec3::from(view.target)))
        }
        None => (DVec3::ZERO, DVec3::Z),
    };
    Port::swapped_viewer(local, eye, towards_eye)
}

/// `worst` and `tolerance`; `at` is where the request is (`""`, or
/// `/request` in a form).
pub(super) fn options(worst: Option<usize>, tolerance: Option<f64>, at: &str) -> Result<Options> {
    let worst = worst.unwrap_or(glint_compare::DEFAULT_WORST);
    count_within(
        &format!("{at}/worst"),
        "worst entries",
        worst,
        MAX_WORST,
        MAX_WORST,
    )?;
    if let Some(tolerance) = tolerance
        && !(tolerance.is_finite() && tolerance > 0.0)
    {
        return Err(RequestError::invalid(
            format!("{at}/tolerance"),
            format!("a tolerance of {tolerance}: it must be a finite error above 0"),
        ));
    }
    Ok(Options { worst, tolerance })
}

/// The candidate's faults, before any evaluation.
fn check_candidate(scene: &CompareScene) -> Result<()> {
    scene
        .candidate()
        .check(&scene.compare_scene())
        .map_err(candidate_error)
}

/// A candidate that does not fit its scene, as a 422 at its pointer.
pub fn candidate_error(e: CandidateError) -> RequestError {
    RequestError::invalid(e.pointer(), e.to_string())
}

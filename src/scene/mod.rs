//! What a client asks for, and its validation.
//!
//! A request body is parsed into the serde types of [`wire`] (which mirror
//! `api/openapi.yaml`), then validated once into the domain types here and in
//! [`glint_lighting`] and [`glint_trace`]. Nothing downstream sees raw JSON or checks it again.
//! Every error carries the JSON Pointer of the field at fault.

mod compare;
mod compare_image;
mod error;
mod gltf;
mod model;
mod render_scene;
mod validate;
pub mod wire;

pub use compare::{CompareScene, MAX_WORST, candidate_error, parse_compare};
pub use compare_image::{ImageCompareScene, parse_compare_image, srgb_decoded};
pub use error::{At, RequestError, RequestErrorKind};
pub use model::{
    BakeScene, ColorFormat, ColorSpace, parse_bake, parse_compare_model, parse_model_render,
};
pub use render_scene::{MAX_PROBES, parse_render, render_scene};
pub use validate::{light_set, shade_scene};

use glam::DVec3;
use glint_lighting::{LightSet, Precision, SurfaceMaterial};
use serde::{Deserialize, Serialize};

/// Something the client should know about its answer, from reading its
/// request or from evaluating it; never a silent change.
#[derive(Debug, Serialize)]
pub struct Warning {
    pub code: &'static str,
    pub count: usize,
    pub detail: String,
}

/// How much of the term breakdown a shade response carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TermsDetail {
    #[default]
    None,
    /// Per-term statistics over the batch.
    Summary,
    /// The statistics and every vertex's breakdown.
    PerVertex,
}

/// The server's limits on one request; each is a flag of `glint serve`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    pub max_vertices: usize,
    pub max_lights: usize,
    pub max_pixels: u64,
    pub max_samples: u32,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_vertices: 4_000_000,
            max_lights: glint_lighting::MAX_LIGHTS,
            max_pixels: 3840 * 2160,
            max_samples: glint_trace::MAX_SAMPLES,
        }
    }
}

/// A validated `/v1/shade` request.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadeScene {
    pub lights: LightSet,
    /// The material of every vertex.
    pub material: SurfaceMaterial,
    pub positions: Vec<DVec3>,
    /// As given; the lighting model normalises them if it is asked to.
    pub normals: Vec<DVec3>,
    pub precision: Precision,
    pub terms: TermsDetail,
    /// How many normals have zero length (they get no diffuse or specular
    /// light).
    pub zero_normals: usize,
}

impl ShadeScene {
    /// The size of the lighting work: vertex-light evaluations over the
    /// sides lit (the global terms count as one light).
    pub fn work(&self) -> usize {
        let sides = if self.lights.model.two_side { 2 } else { 1 };
        self.positions.len() * (self.lights.lights().len() + 1) * sides
    }
}

/// Parses and validates a `/v1/shade` body.
pub fn parse_shade(body: &[u8], limits: &Limits) -> Result<ShadeScene, RequestError> {
    let request: wire::ShadeRequest = parse_json(body)?;
    shade_scene(&request, limits)
}

/// Parses JSON into `T`; a failure names the field where parsing stopped.
/// Parsing tracks the path only on the way to an error: the first pass runs
/// without it, and a body it rejects is parsed again to find the pointer.
pub fn parse_json<T: serde::de::DeserializeOwned>(body: &[u8]) -> Result<T, RequestError> {
    if let Ok(wire::JsonObject(value)) = serde_json::from_slice(body) {
        return Ok(value);
    }
    let mut de = serde_json::Deserializer::from_slice(body);
    let wire::JsonObject(value) =
        serde_path_to_error::deserialize(&mut de).map_err(RequestError::from_serde)?;
    de.end()
        .map_err(|e| RequestError::malformed("", format!("trailing characters: {e}")))?;
    Ok(value)
}

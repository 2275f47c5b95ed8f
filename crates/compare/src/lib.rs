//! A port's colours held against GL's, and the mistake that explains them.
//!
//! People who write GL's fixed-function lighting by hand (a WebGL or Vulkan
//! port, an engine matching an old look) end up with colours that are
//! almost right. This crate measures how far they are from GL's (the
//! largest, mean and 99th-percentile error, the share of 8-bit channels
//! that differ, the worst vertices or pixels) and names the mistake: glint
//! evaluates the scene as a port with each known mistake
//! ([`Deviation`], a switch of glint's own model,
//! `glint_lighting::reference::evaluate_port`) and ranks the mistakes by the
//! error each leaves ([`Diagnosis`]).
//!
//! - [`compare`]: per-vertex colours, the scene of a shade request.
//! - [`image`]: an image against GL's (PSNR, a heatmap, the worst pixels),
//!   and the diagnosis from the shading points of the pixels a renderer
//!   gives ([`image::PixelShading`]).
//! - [`stats`]: the arithmetic of an error (the percentile, 8-bit values,
//!   PSNR).
//!
//! Every deviation and GL itself are evaluated in one pass that shares what
//! they share: the prepared lights, the loads, each light's geometry, and
//! every variant of a factor (see `eval`), in the arithmetic of the scene's
//! precision tier, so that each model is within the tier's bound of the
//! reference's colour for that port.
//!
//! ```
//! use glam::{DVec3, Vec4};
//! use glint_compare::{Candidate, Deviation, Options, Scene, compare};
//! use glint_lighting::reference::{Port, color_port};
//! use glint_lighting::{LightModel, LightSet, Material, Precision, Side, SurfaceMaterial};
//!
//! let lights = LightSet::new(
//!     LightModel::default(),
//!     vec![Default::default()],
//!     LightSet::eye_space_viewer(false),
//! )
//! .unwrap();
//! let material = SurfaceMaterial::both_sides(Material {
//!     specular: [0.5, 0.5, 0.5, 1.0].into(),
//!     shininess: 16.0,
//!     ..Material::default()
//! });
//! let positions: Vec<DVec3> = (0..16).map(|i| DVec3::new(i as f64 * 0.1, 0.0, -2.0)).collect();
//! let normals: Vec<DVec3> =
//!     (0..16).map(|i| DVec3::new((i as f64 * 0.3).sin(), 0.2, 1.0)).collect();
//! let swapped_viewer = Port::swapped_viewer(false, DVec3::ZERO, DVec3::Z);
//! // A port that used Phong's specular: its colours, as glint's reference
//! // evaluates that port.
//! let port = Port { deviations: Deviation::PhongSpecular.into(), swapped_viewer };
//! let colors: Vec<Vec4> = positions
//!     .iter()
//!     .zip(&normals)
//!     .map(|(&p, &n)| color_port(&lights, &port, &material, Side::Front, p, n).as_vec4())
//!     .collect();
//! let scene = Scene {
//!     lights: &lights,
//!     material: &material,
//!     positions: &positions,
//!     normals: &normals,
//!     precision: Precision::Accurate,
//!     swapped_viewer,
//! };
//! let candidate = Candidate { front: &colors, back: None, alpha: false };
//! let comparison = compare(&scene, &candidate, &Options::default()).unwrap();
//! assert!(!comparison.error.within_bound);
//! let best = &comparison.diagnosis.explanations[0];
//! assert_eq!(best.deviations, Deviation::PhongSpecular.into());
//! assert!(best.explains);
//! ```

// The lane loops index several arrays of one block by lane on purpose: that
// is the structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

pub mod diagnosis;
mod eval;
pub mod image;
pub mod stats;
mod vertices;

pub use diagnosis::{Diagnosis, Explanation};
pub use glint_lighting::deviation::{Deviation, Deviations};
pub use stats::{ErrorStats, Worst};
pub use vertices::{
    Candidate, CandidateError, Comparison, DEFAULT_WORST, MAX_CHANNEL, Options, Scene, VertexAt,
    compare,
};

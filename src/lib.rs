//! glint evaluates the OpenGL 2.1 fixed-function lighting model (section
//! 2.14.1 of the compatibility specification) for batches of vertices and
//! ray-traced images, and explains every result term by term.
//!
//! The workspace is cut by domain concept, with dependencies pointing one
//! way (`http → scene, shade, render → glint_trace → glint_lighting`):
//!
//! - [`glint_lighting`] (`crates/lighting`): the lighting equation itself,
//!   pure functions over validated parameters; an f64 reference evaluator
//!   and f32 kernels. No serde, no HTTP.
//! - [`glint_trace`] (`crates/trace`): the ray tracer (camera, geometry,
//!   BVH, packets, film) that lights every visible point with the same
//!   equation.
//! - [`scene`]: the request as it arrives (serde types mirroring
//!   `api/openapi.yaml`) and its validation into the domain types of the
//!   two crates; every error names the offending field by JSON pointer.
//! - [`shade`] and [`render`]: the two use cases, a validated request into
//!   its response; [`response`] holds what their responses share. [`bake`]
//!   is `/v1/shade` with a glTF model ([`glint_model`]): its colours
//!   written back into the model. [`compare`] holds a port's colours
//!   against GL's and names its mistake ([`glint_compare`]).
//! - [`pool`]: the hand-off of CPU work from the async server to rayon.
//! - [`http`]: the axum service, the only module that knows HTTP.
//! - [`offline`]: the same answers for the command line, from files.
//!
//! The clients of the service (the tile fan-out of `glint render --via`,
//! the probe of `glint healthcheck`) are a crate of their own,
//! `glint-client` (`crates/client`), which the server does not use; the
//! names both sides of the contract spell are in `glint-protocol`.
//!
//! ```
//! use glam::DVec3;
//! use glint_lighting::{Light, LightModel, LightSet, Side, SurfaceMaterial, reference};
//!
//! let lights = LightSet::new(
//!     LightModel::default(),
//!     vec![Light::default()], // GL_LIGHT0: white, along +z
//!     LightSet::eye_space_viewer(false),
//! )
//! .unwrap();
//! let material = SurfaceMaterial::default();
//! let c = reference::color(&lights, &material, Side::Front, DVec3::ZERO, DVec3::Z);
//! // global ambient 0.2·0.2 + diffuse 0.8·1
//! assert!((c.x - 0.84).abs() < 1e-12);
//! ```

pub mod bake;
pub mod compare;
pub mod config;
pub mod http;
pub mod logging;
pub mod offline;
pub mod pool;
pub mod problem;
pub mod render;
pub mod response;
pub mod scene;
pub mod shade;

//! glint evaluates the OpenGL 2.1 fixed-function lighting model (section
//! 2.14.1 of the compatibility specification) for batches of vertices and
//! ray-traced images, and explains every result term by term.
//!
//! The crate is cut by domain concept, with dependencies pointing one way:
//!
//! - [`lighting`]: the lighting equation itself, pure functions over
//!   validated parameters; an f64 reference evaluator and f32 kernels.
//! - [`scene`]: the request as it arrives (serde types mirroring
//!   `api/openapi.yaml`) and its validation into the domain types the other
//!   modules use; every error names the offending field by JSON pointer.
//! - [`shading`]: evaluating a validated shade request into its response.
//! - [`render`]: the ray tracer (camera, geometry, BVH, film) that lights
//!   every visible point with the same equation.
//! - [`rendering`]: rendering a validated render request into its response.
//! - [`pool`]: the hand-off of CPU work from the async server to rayon.
//! - [`http`]: the axum service, the only module that knows HTTP.
//!
//! ```
//! use glam::DVec3;
//! use glint::lighting::{Light, Lighting, LightModel, Material, reference};
//!
//! let lighting = Lighting {
//!     model: LightModel::default(),
//!     front: Material::default(),
//!     back: Material::default(),
//!     lights: vec![Light::default()], // GL_LIGHT0: white, along +z
//!     viewer: Lighting::eye_space_viewer(false),
//! };
//! let c = reference::color(&lighting, reference::Side::Front, DVec3::ZERO, DVec3::Z);
//! // global ambient 0.2·0.2 + diffuse 0.8·1
//! assert!((c.x - 0.84).abs() < 1e-12);
//! ```

pub mod config;
pub mod http;
pub mod lighting;
pub mod pool;
pub mod problem;
pub mod render;
pub mod rendering;
pub mod scene;
pub mod shading;

//! The renderer: spheres, infinite planes and triangle meshes seen through
//! a pinhole camera, every visible point lit by the same GL lighting
//! equation as `/v1/shade` ([`glint_lighting`]).
//!
//! A [`Renderer`] prepares a validated [`RenderScene`] once per request: the
//! geometry ([`geometry`]); the rasterizer of the primary rays ([`raster`]),
//! or, for a frame it declines, the BVH and the packet tracer ([`bvh`],
//! [`packet`]); the BVH of the shadow rays when there are shadows; the
//! scene's light set as one f32 kernel and each material's colour products
//! for the `accurate` and `fast` precisions (the reference evaluator needs
//! no preparation); and for Gouraud shading the colours of every mesh
//! vertex. [`Renderer::render`] then renders the image (or its region) in
//! 16×16-pixel tiles on the current rayon pool, all workers sharing that
//! read-only state; nothing is decided per pixel that could be decided per
//! request. Whichever way visibility is found, every hit is the exact f64
//! one, so the pixels do not depend on it. [`hit_lighting`] lights the
//! hits; [`film`] places the samples (uniform or adaptive) and encodes the
//! result.
//!
//! GL has no rays: what the renderer adds to the fixed-function model is
//! visibility (the closest hit along each primary ray, which GL's depth
//! buffer approximates in f32), optional shadows, and per-pixel lighting as
//! an alternative to Gouraud's per-vertex lighting. Everything else is the
//! lighting equation at a point, exactly as `/v1/shade` evaluates it for a
//! vertex.

pub mod bvh;
pub mod camera;
pub mod film;
pub mod geometry;
pub mod hit_lighting;
mod lbvh;
pub mod packet;
pub mod raster;
mod raster_gouraud;
mod renderer;
mod scene;
mod shading_source;
#[cfg(test)]
mod test_rng;

pub use renderer::{BLOCK, Frame, Probe, Renderer, SamplingStats, TILE, Visibility};
pub use scene::{
    Camera, Encoding, MAX_SAMPLES, MAX_TOLERANCE, Mesh, Object, Plane, Region, RenderScene,
    Samples, ShadingMode, Shape, Sphere,
};
pub use shading_source::{AdaptiveSampling, RenderShading};

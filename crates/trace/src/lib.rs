//! The renderer: a ray tracer of spheres, infinite planes and triangle
//! meshes through a pinhole camera, every visible point lit by the same GL
//! lighting equation as `/v1/shade` ([`glint_lighting`]).
//!
//! A [`Renderer`] prepares a validated [`RenderScene`] once per request: the
//! geometry and its BVH ([`geometry`], [`bvh`]), the scene's light set as
//! one f32 kernel and each material's colour products for the `accurate`
//! and `fast` precisions (the reference evaluator needs no preparation), for
//! Gouraud shading the colours of every mesh vertex, and the packet tracer
//! of the primary rays from the eye ([`packet`]). [`Renderer::render`] then
//! traces the image (or its region) in 16×16-pixel tiles on the current
//! rayon pool, each tile's primary rays in packets of 4×4 pixels, all
//! workers sharing that read-only state; nothing is decided per pixel that
//! could be decided per request. [`hit_lighting`] lights the hits; [`film`]
//! places the samples and encodes the result.
//!
//! GL has no rays: what the renderer adds to the fixed-function model is
//! visibility (the closest hit along each primary ray instead of a depth
//! buffer), optional shadows, and per-pixel lighting as an alternative to
//! Gouraud's per-vertex lighting. Everything else is the lighting equation
//! at a point, exactly as `/v1/shade` evaluates it for a vertex.

pub mod bvh;
pub mod camera;
pub mod film;
pub mod geometry;
pub mod hit_lighting;
pub mod packet;
pub mod raster;
mod renderer;
mod scene;

pub use renderer::{BLOCK, Frame, Probe, Renderer, SamplingStats, TILE, Visibility};
pub use scene::{
    Camera, Encoding, MAX_SAMPLES, MAX_TOLERANCE, Mesh, Object, Plane, Region, RenderScene,
    Samples, ShadingMode, Shape, Sphere,
};

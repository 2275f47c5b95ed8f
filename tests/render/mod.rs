//! Tests of the renderer (`glint_trace`, `glint::render` and the
//! validation of `/v1/render` requests): a ray tracer of spheres, planes
//! and meshes lit by the GL lighting equation.
//!
//! - [`golden`]: pixels of each primitive against an analytic tracer (the
//!   camera, the intersections and the lighting equation written out in
//!   `support`), two-sided lighting and shadows.
//! - [`gouraud`]: per-vertex shading equals per-pixel at the vertices.
//! - [`adaptive`]: adaptive sampling spends samples on edges, not on flat
//!   colour, and keeps regions crops of the whole image.
//! - [`film`]: regions are crops, samples are reproducible and averaged,
//!   the PNG's linear and sRGB encodings, the JSON form.
//! - [`validation`]: refused requests and the pointers of their errors.
//! - [`bvh`]: the BVH's hits equal brute force over random rays.
//! - [`raster`]: the rasterized visibility's hits equal brute force, and
//!   its renders the traced renders.
//! - [`http`]: `POST /v1/render` over a socket: content negotiation,
//!   errors, metrics.
//! - [`examples`]: the scenes of `examples/` render, into
//!   `target/render-examples/`.
//!
//! Expected values come from independent computations in the tests, never
//! from the renderer's own output.

mod support;

mod adaptive;
mod bvh;
mod examples;
mod film;
mod golden;
mod gouraud;
mod http;
mod raster;
mod validation;

//! glTF in and out: models built here (node hierarchies with rotation,
//! non-uniform and negative scale; interleaved, sparse and indexed
//! accessors; primitives with and without normals and materials) baked,
//! and the baked colours checked against the f64 reference evaluated on
//! positions and normals that the tests place with their own matrix code.
//!
//! - [`bake`]: colours, the baked model's shape, the JSON form, the
//!   mapping of a model's lights, materials and camera.
//! - [`refused`]: lying and unsupported models, each refused with the
//!   pointer of its fault, over HTTP too, the server serving the next
//!   request.
//! - [`http`]: forms as browsers and curl send them, bare GLB bodies,
//!   the answer's form, renders, lying models and broken forms refused
//!   with the server serving the next request.
//! - [`render`]: a render with a model is the render of the same scene
//!   sent as JSON.
//! - [`incomplete`]: a primitive whose vertex or index count is not a
//!   multiple of 3, baked whole and drawn without its leftovers.
//! - [`fuzz`]: arbitrary bytes and mutations of valid models never panic,
//!   hang or allocate what they claim.
//! The Khronos validator and a Python reader check baked models in
//! `clients::gltf`, beside the other outside tools.

pub(crate) mod support;

pub(crate) mod bake;
mod fuzz;
pub(crate) mod http;
mod incomplete;
mod refused;
mod render;

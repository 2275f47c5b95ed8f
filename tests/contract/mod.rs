//! `api/openapi.yaml`, the written contract, checked against itself and
//! against the code, a test per rule: a failure names the rule that broke.
//!
//! The request rules are grouped by what they constrain (lights, materials,
//! geometry, the camera and the picture, the shape of a body); each holds
//! bodies against the schema the document gives them and against the parser
//! and validation of `glint::scene`, and a rule that the schemas leave to a
//! description against that description as well. The numbers come from the
//! document itself, from OpenGL 2.1's section 2.14.1, or from the bounds the
//! code exports; no test pastes back an answer of the code.

/// What these tests share: the document, its schemas as validators, the
/// request bodies, and one way to hold a body against schema and code.
pub(crate) mod support;

/// The defaults and bounds the document writes are the code's.
mod defaults;
/// The document as a document: OpenAPI 3.1, references, paths, named
/// bodies, documented headers, schemas that compile with valid examples.
mod document;
/// The JSON Schema that client generators read: no conditionals, unions
/// only with null, string enums and consts.
mod generators;
/// The schema `Problem` and the status each problem type fixes.
mod problems;

/// The view and the picture: eye and target, up, field of view, size,
/// region, probes, samples.
mod camera;
/// Geometry: coordinates, normals, objects, spheres, planes, meshes.
mod geometry;
/// Lights: position, attenuation, spot cone, how many.
mod lights;
/// Colours and materials: bounds, shininess, named materials.
mod materials;
/// The shape of a body: what is taken whole, and what is malformed (400).
mod syntax;

/// The HTTP service's answers over a socket against the document.
mod http;
/// Real answers of the code (shade, render, bake, problems) against their
/// schemas and what the document says of their parts.
mod responses;

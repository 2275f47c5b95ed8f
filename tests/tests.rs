//! glint's integration tests, one binary (each module says what it covers).

/// Clients and a fuzzer that outside tools build from `api/openapi.yaml`,
/// against the real binary (the tools are installed under `target/tools/`).
mod clients;
/// `/v1/compare` and `glint compare`: candidates of ports made by an
/// independent implementation, diagnosed; bad candidates refused.
mod compare;
/// `api/openapi.yaml` against itself, the request parser and validation,
/// and real responses: a test per rule of the contract.
mod contract;
/// Deployment: Kubernetes manifests, replicas behind HAProxy, the fan-out
/// client, the drain on SIGTERM, the container image and its compose
/// topology.
mod deploy;
/// glTF models in, baked models out: placement, colours, lying models.
mod gltf;
/// The HTTP service over real sockets.
mod http;
/// The crate graph: the lighting and ray tracing crates know no JSON or HTTP,
/// and the service no HTTP client.
mod layering;
/// The lighting core against the specification: golden cases, edge cases, properties.
mod lighting;
/// Concurrency, overload, hostile traffic and shutdown of the real binary.
mod load;
/// The playground page: its files as served, and the page in headless Chromium.
mod playground;
/// The f32 tiers against the reference, on random scenes and at the extremes.
mod precision;
/// The renderer: golden pixels, Gouraud, film, validation, BVH, HTTP, examples.
mod render;
/// What the suites share (not a suite): outside programs and how they are
/// installed and run, scratch directories, the HTTP client, a seeded rng.
mod support;

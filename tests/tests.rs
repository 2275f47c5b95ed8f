//! glint's integration tests, one binary (each module says what it covers).

/// `api/openapi.yaml` against itself and against real responses.
mod contract;
/// The HTTP service over real sockets.
mod http;

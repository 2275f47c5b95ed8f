//! glint's integration tests, one binary (each module says what it covers).

/// The HTTP service over real sockets.
mod http;

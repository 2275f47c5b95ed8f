//! The names of glint's HTTP contract (`api/openapi.yaml`) that the
//! service and its clients both use: the paths of the endpoints and the
//! headers the service adds to every answer. The service writes them and
//! the clients (`glint-client`) read them, so each is spelt once here.

/// `POST`: per-vertex colours, or a glTF model baked.
pub const SHADE: &str = "/v1/shade";

/// `POST`: a ray-traced image.
pub const RENDER: &str = "/v1/render";

/// `GET`: 200 while the process is alive.
pub const HEALTH: &str = "/healthz";

/// `GET`: 200 while the replica takes work, 503 while it drains.
pub const READY: &str = "/readyz";

/// The header in which a replica names itself, on every answer.
pub const SERVED_BY: &str = "x-served-by";

/// The header that names a request in the logs of the service and of its
/// clients: the client's own, echoed, or one the service makes.
pub const REQUEST_ID: &str = "x-request-id";

//! `POST /v1/render`.

use super::error::ApiError;
use crate::problem::Problem;

/// The renderer is not part of this build yet: say so rather than pretend.
pub async fn render() -> ApiError {
    ApiError::new(Problem::new(
        501,
        "not-implemented",
        "Not implemented",
        "this server does not render images yet; /v1/shade lights vertices",
    ))
}

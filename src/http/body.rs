//! Reading a request body whose content type [`super::media`] has read: the
//! size limited, a slow client cut off. Parsing happens later, on the
//! worker pool.

use std::task::Poll;
use std::time::Duration;

use axum::body::{Body, Bytes};
use axum::http::{HeaderMap, header};
use http_body_util::BodyExt;

use super::error::ApiError;
use crate::problem::{Problem, ProblemKind};

/// The raw bytes of a body whose head has been checked, within
/// `max_bytes` and `timeout`.
pub async fn read(body: Body, max_bytes: usize, timeout: Duration) -> Result<Bytes, ApiError> {
    let mut read = std::pin::pin!(axum::body::to_bytes(body, max_bytes));
    // A body that has arrived whole, as a small one does with its head, is
    // taken without arming a timer; the rest get `timeout` from here.
    let read = match std::future::poll_fn(|cx| Poll::Ready(read.as_mut().poll(cx))).await {
        Poll::Ready(read) => read,
        Poll::Pending => match tokio::time::timeout(timeout, read).await {
            Ok(read) => read,
            Err(_) => {
                return Err(ApiError::new(
                    ProblemKind::Timeout,
                    format!("the body did not arrive within {} ms", timeout.as_millis()),
                ));
            }
        },
    };
    match read {
        Err(e) if is_length_limit(&e) => Err(too_large(max_bytes)),
        Err(e) => Err(ApiError::new(
            ProblemKind::Malformed,
            format!("the body could not be read: {e}"),
        )),
        Ok(bytes) => Ok(bytes),
    }
}

/// Reads and drops the rest of a body refused before it was read, in the
/// background, within `max_bytes` and `timeout`. A server that answers and
/// closes with a body's bytes unread makes the kernel reset the connection,
/// and a client still sending may then lose the answer to the reset; read
/// to its end, the body leaves the connection clean and open for the next
/// request. Nothing of it is kept.
pub fn discard(mut body: Body, max_bytes: usize, timeout: Duration) {
    tokio::spawn(async move {
        let drain = async {
            let mut read = 0;
            while let Some(Ok(frame)) = body.frame().await {
                read += frame.data_ref().map_or(0, |data| data.len());
                if read > max_bytes {
                    break;
                }
            }
        };
        let _ = tokio::time::timeout(timeout, drain).await;
    });
}

/// What the declared length refuses: over `max_bytes` (413).
pub fn check_length(headers: &HeaderMap, max_bytes: usize) -> Result<(), ApiError> {
    if let Some(length) = declared_length(headers)
        && length > max_bytes as u64
    {
        return Err(too_large(max_bytes));
    }
    Ok(())
}

/// The length the client declares for its body, if it does.
pub fn declared_length(headers: &HeaderMap) -> Option<u64> {
    headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok()?.parse().ok())
}

fn too_large(max_bytes: usize) -> ApiError {
    ApiError::from(
        Problem::new(
            ProblemKind::OverLimit,
            format!("the body is over this server's limit of {max_bytes} bytes"),
        )
        .at(""),
    )
}

fn is_length_limit(e: &axum::Error) -> bool {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(err) = source {
        if err.is::<http_body_util::LengthLimitError>() {
            return true;
        }
        source = err.source();
    }
    false
}

//! RFC 9457 problem details: the one shape of every error glint reports, over
//! HTTP and on the command line alike.
//!
//! Every error is of one [`ProblemKind`], which fixes its status, its type URN
//! (`urn:glint:problem:<slug>`) and its title; a [`Problem`] adds what was
//! wrong with this request, and where in its body when that is known.

use serde::ser::{Serialize, SerializeStruct, Serializer};

use crate::scene::{RequestError, RequestErrorKind};

/// Declares [`ProblemKind`] from one table: each kind's status, slug and
/// title are written once, and its type URN is made from its slug.
macro_rules! problem_kinds {
    ($($(#[$doc:meta])* $kind:ident => $status:literal, $slug:literal, $title:literal;)*) => {
        /// The classes of error glint reports.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum ProblemKind {
            $($(#[$doc])* $kind,)*
        }

        impl ProblemKind {
            /// Every kind, in the order of the table.
            pub const ALL: &'static [ProblemKind] = &[$(ProblemKind::$kind,)*];

            /// The HTTP status of this kind of problem.
            pub const fn status(self) -> u16 {
                match self {
                    $(ProblemKind::$kind => $status,)*
                }
            }

            /// The last part of the type URN (`over-limit`).
            pub const fn slug(self) -> &'static str {
                match self {
                    $(ProblemKind::$kind => $slug,)*
                }
            }

            /// The URN naming this kind of problem, the `type` of its body
            /// (`urn:glint:problem:over-limit`).
            pub const fn type_urn(self) -> &'static str {
                match self {
                    $(ProblemKind::$kind => concat!("urn:glint:problem:", $slug),)*
                }
            }

            /// A short summary of this kind of problem, the `title` of its body.
            pub const fn title(self) -> &'static str {
                match self {
                    $(ProblemKind::$kind => $title,)*
                }
            }
        }
    };
}

problem_kinds! {
    /// Not JSON, or not of the schema; or a body that could not be read.
    Malformed => 400, "malformed", "Malformed request";
    /// No such endpoint.
    NotFound => 404, "not-found", "Not found";
    /// The endpoint exists, the method does not.
    MethodNotAllowed => 405, "method-not-allowed", "Method not allowed";
    /// The body did not arrive within the server's body timeout.
    Timeout => 408, "timeout", "Request timeout";
    /// The body, or something in it, is over one of the server's limits.
    OverLimit => 413, "over-limit", "Over a limit of this server";
    /// A content type the endpoint does not take.
    UnsupportedMediaType => 415, "unsupported-media-type", "Unsupported media type";
    /// Well-formed but invalid.
    Invalid => 422, "invalid", "Invalid request";
    /// A failure inside glint; the details are in the server's log.
    Internal => 500, "internal", "Internal error";
    /// Every worker busy and the queue full, or the request deadline passed;
    /// answered with `Retry-After`.
    Busy => 503, "busy", "Service saturated";
    /// `GET /readyz` while the server drains its requests before stopping.
    ShuttingDown => 503, "shutting-down", "Shutting down";
    /// The command line's input file cannot be read (never over HTTP).
    Unreadable => 400, "unreadable", "Cannot read the request";
    /// The command line's render has neither `-o` nor `--json` (never over
    /// HTTP).
    NoOutput => 400, "no-output", "Nowhere to write the image";
    /// The command line's image cannot be written (never over HTTP).
    Unwritable => 500, "unwritable", "Cannot write the image";
}

impl From<RequestErrorKind> for ProblemKind {
    fn from(kind: RequestErrorKind) -> Self {
        match kind {
            RequestErrorKind::Malformed => ProblemKind::Malformed,
            RequestErrorKind::OverLimit => ProblemKind::OverLimit,
            RequestErrorKind::Invalid => ProblemKind::Invalid,
            RequestErrorKind::Unsupported => ProblemKind::UnsupportedMediaType,
        }
    }
}

/// A problem+json body: `{type, title, status, detail, pointer}`, the first
/// three fixed by its [`ProblemKind`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    kind: ProblemKind,
    detail: String,
    /// JSON Pointer of the field at fault, when one is.
    pointer: Option<String>,
}

impl Problem {
    pub fn new(kind: ProblemKind, detail: impl Into<String>) -> Self {
        Self {
            kind,
            detail: detail.into(),
            pointer: None,
        }
    }

    /// The same problem, about the field at `pointer` (`""` for the whole
    /// body).
    pub fn at(mut self, pointer: impl Into<String>) -> Self {
        self.pointer = Some(pointer.into());
        self
    }

    /// The service is saturated; the client should retry later.
    pub fn busy() -> Self {
        Self::new(
            ProblemKind::Busy,
            "every worker is busy and the queue is full; retry after the delay in Retry-After",
        )
    }

    /// Something failed inside glint; the details are in the server's log.
    pub fn internal() -> Self {
        Self::new(
            ProblemKind::Internal,
            "the request failed inside the server; it has been logged",
        )
    }

    pub fn kind(&self) -> ProblemKind {
        self.kind
    }

    /// The HTTP status, its kind's.
    pub fn status(&self) -> u16 {
        self.kind.status()
    }

    pub fn detail(&self) -> &str {
        &self.detail
    }

    pub fn pointer(&self) -> Option<&str> {
        self.pointer.as_deref()
    }
}

impl Serialize for Problem {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let fields = if self.pointer.is_some() { 5 } else { 4 };
        let mut body = serializer.serialize_struct("Problem", fields)?;
        body.serialize_field("type", self.kind.type_urn())?;
        body.serialize_field("title", self.kind.title())?;
        body.serialize_field("status", &self.kind.status())?;
        body.serialize_field("detail", &self.detail)?;
        match &self.pointer {
            Some(pointer) => body.serialize_field("pointer", pointer)?,
            None => body.skip_field("pointer")?,
        }
        body.end()
    }
}

impl From<RequestError> for Problem {
    fn from(e: RequestError) -> Self {
        Problem::new(e.kind.into(), e.detail).at(e.pointer)
    }
}

impl From<&RequestError> for Problem {
    fn from(e: &RequestError) -> Self {
        Problem::from(e.clone())
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;

    #[test]
    fn each_kind_has_its_own_slug_and_a_urn_made_of_it() {
        let mut slugs = HashSet::new();
        for &kind in ProblemKind::ALL {
            assert!(slugs.insert(kind.slug()), "{kind:?}: slug used twice");
            assert_eq!(
                kind.type_urn(),
                format!("urn:glint:problem:{}", kind.slug())
            );
            assert!((400..600).contains(&kind.status()), "{kind:?}");
        }
    }

    #[test]
    fn serialises_in_the_order_of_the_contract() {
        let problem = Problem::new(ProblemKind::Invalid, "a cutoff of 120").at("/lights/0");
        assert_eq!(
            serde_json::to_string(&problem).unwrap(),
            r#"{"type":"urn:glint:problem:invalid","title":"Invalid request","status":422,"detail":"a cutoff of 120","pointer":"/lights/0"}"#
        );
        assert_eq!(
            serde_json::to_string(&Problem::internal()).unwrap(),
            r#"{"type":"urn:glint:problem:internal","title":"Internal error","status":500,"detail":"the request failed inside the server; it has been logged"}"#
        );
    }

    #[test]
    fn request_errors_keep_their_pointer() {
        let cases = [
            (RequestError::malformed("", "x"), ProblemKind::Malformed),
            (
                RequestError::over_limit("/lights", "x"),
                ProblemKind::OverLimit,
            ),
            (RequestError::invalid("/samples", "x"), ProblemKind::Invalid),
        ];
        for (e, kind) in cases {
            let problem = Problem::from(&e);
            assert_eq!(problem.kind(), kind);
            assert_eq!(problem.pointer(), Some(e.pointer.as_str()));
            assert_eq!(problem.detail(), e.detail);
        }
    }
}

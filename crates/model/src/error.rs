//! Why a model was refused, with the JSON Pointer of the part at fault.

use std::fmt;

/// The classes of refusal; the service maps each to one HTTP status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// Not a GLB, or its JSON is not JSON or not of glTF's schema (a count
    /// that is a string): 400.
    Malformed,
    /// Over one of the reader's limits (vertices, primitives, the JSON
    /// chunk): 413.
    OverLimit,
    /// A glTF version or a required extension glint does not read: 415.
    Unsupported,
    /// Well-formed but invalid or lying: an accessor past its buffer view,
    /// an index past the vertices, a non-finite position, a URI: 422.
    Invalid,
}

/// A refused model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    pub kind: ErrorKind,
    /// JSON Pointer (RFC 6901) into the glTF JSON (`/accessors/3/count`);
    /// empty for the container itself.
    pub pointer: String,
    pub detail: String,
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn new(kind: ErrorKind, pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self {
            kind,
            pointer: pointer.into(),
            detail: detail.into(),
        }
    }

    pub fn malformed(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(ErrorKind::Malformed, pointer, detail)
    }

    pub fn invalid(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(ErrorKind::Invalid, pointer, detail)
    }

    pub fn over_limit(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(ErrorKind::OverLimit, pointer, detail)
    }

    pub fn unsupported(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(ErrorKind::Unsupported, pointer, detail)
    }

    /// A serde failure while reading the object at `pointer`, located by the
    /// path within it where reading stopped.
    pub(crate) fn from_serde(
        pointer: &str,
        e: serde_path_to_error::Error<serde_json::Error>,
    ) -> Self {
        use serde_path_to_error::Segment;
        let mut at = pointer.to_owned();
        for segment in e.path().iter() {
            match segment {
                Segment::Seq { index } => at.push_str(&format!("/{index}")),
                Segment::Map { key } | Segment::Enum { variant: key } => {
                    at.push('/');
                    at.push_str(&key.replace('~', "~0").replace('/', "~1"));
                }
                Segment::Unknown => {}
            }
        }
        Self::malformed(at, e.into_inner().to_string())
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.pointer.is_empty() {
            write!(f, "{}", self.detail)
        } else {
            write!(f, "{}: {}", self.pointer, self.detail)
        }
    }
}

impl std::error::Error for Error {}

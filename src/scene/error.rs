//! Why a request was refused, with the JSON Pointer of the field at fault.

use std::fmt;

/// The classes of refusal; each maps to one HTTP status of the contract.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RequestErrorKind {
    /// Not JSON, or not of the schema (wrong type, unknown field): 400.
    Malformed,
    /// Well-formed but over one of the server's limits: 413.
    OverLimit,
    /// Well-formed but invalid (a cutoff of 120, a zero direction): 422.
    Invalid,
    /// A model in a version or with a required extension glint does not
    /// read: 415.
    Unsupported,
}

/// A refused request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RequestError {
    pub kind: RequestErrorKind,
    /// JSON Pointer (RFC 6901) of the offending field; empty for the whole body.
    pub pointer: String,
    pub detail: String,
}

impl RequestError {
    pub fn malformed(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(RequestErrorKind::Malformed, pointer, detail)
    }

    pub fn invalid(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(RequestErrorKind::Invalid, pointer, detail)
    }

    pub fn over_limit(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(RequestErrorKind::OverLimit, pointer, detail)
    }

    fn new(kind: RequestErrorKind, pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self {
            kind,
            pointer: pointer.into(),
            detail: detail.into(),
        }
    }

    /// A serde failure, located by the path where it stopped.
    pub(super) fn from_serde(e: serde_path_to_error::Error<serde_json::Error>) -> Self {
        let pointer = pointer_of(e.path());
        let inner = e.into_inner();
        let detail = match inner.classify() {
            serde_json::error::Category::Eof => format!("the body ends too early: {inner}"),
            serde_json::error::Category::Syntax => format!("not valid JSON: {inner}"),
            _ => inner.to_string(),
        };
        Self::malformed(pointer, detail)
    }
}

impl fmt::Display for RequestError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.pointer.is_empty() {
            write!(f, "{}", self.detail)
        } else {
            write!(f, "{}: {}", self.pointer, self.detail)
        }
    }
}

impl std::error::Error for RequestError {}

/// The JSON Pointer of a serde path (`lights[2].spot` → `/lights/2/spot`).
fn pointer_of(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut pointer = String::new();
    for segment in path.iter() {
        match segment {
            Segment::Seq { index } => pointer.push_str(&format!("/{index}")),
            Segment::Map { key } | Segment::Enum { variant: key } => {
                pointer.push('/');
                pointer.push_str(&key.replace('~', "~0").replace('/', "~1"));
            }
            Segment::Unknown => {}
        }
    }
    pointer
}

/// Where a value sits in a request: a JSON Pointer that is written out only
/// when a value there is at fault, so that checking a valid request formats
/// nothing. `field` names are the contract's own, which need no escaping.
#[derive(Clone, Copy)]
pub struct At<'a> {
    parent: Option<&'a At<'a>>,
    step: Step<'a>,
}

#[derive(Clone, Copy)]
enum Step<'a> {
    /// A pointer written out already: `""`, `/material`, `/materials/red`.
    Pointer(&'a str),
    Field(&'a str),
    Index(usize),
}

impl<'a> At<'a> {
    pub const fn pointer(pointer: &'a str) -> Self {
        Self {
            parent: None,
            step: Step::Pointer(pointer),
        }
    }

    pub fn field(&'a self, name: &'a str) -> Self {
        Self {
            parent: Some(self),
            step: Step::Field(name),
        }
    }

    pub fn index(&'a self, index: usize) -> Self {
        Self {
            parent: Some(self),
            step: Step::Index(index),
        }
    }
}

impl fmt::Display for At<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(parent) = self.parent {
            parent.fmt(f)?;
        }
        match self.step {
            Step::Pointer(pointer) => f.write_str(pointer),
            Step::Field(name) => write!(f, "/{name}"),
            Step::Index(index) => write!(f, "/{index}"),
        }
    }
}

impl From<At<'_>> for String {
    fn from(at: At<'_>) -> String {
        at.to_string()
    }
}

impl From<&At<'_>> for String {
    fn from(at: &At<'_>) -> String {
        at.to_string()
    }
}

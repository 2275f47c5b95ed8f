//! `multipart/form-data` (RFC 7578, on RFC 2046's multipart syntax), as a
//! browser's `FormData` and `curl -F` send it: a body held whole, split
//! into its named parts without copying them.
//!
//! The body is already in memory (read within the server's body limit), so
//! the parts are slices of it: a model of a hundred megabytes is neither
//! copied nor buffered twice. Parts are found by searching for the
//! delimiter `CRLF--boundary`, which a part's content cannot contain
//! (RFC 2046, section 5.1.1: the sender chooses a boundary that does not
//! occur in it).

use axum::body::Bytes;
use memchr::memmem;

/// The most parts a body may have: glint's forms have two, and a body of
/// many empty parts is refused before they are counted out.
const MAX_PARTS: usize = 8;

/// The most bytes of one part's headers.
const MAX_HEADER_BYTES: usize = 8 * 1024;

/// One part of a form.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// The `name` of its `Content-Disposition`.
    pub name: String,
    /// Its `Content-Type`, if it has one.
    pub content_type: Option<String>,
    pub body: Bytes,
}

/// Why a form could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FormError(pub String);

/// The boundary of a `multipart/form-data` content type, `None` for
/// another type; `Err` for multipart without a usable boundary.
pub fn boundary(content_type: &str) -> Option<Result<String, FormError>> {
    let mut params = content_type.split(';');
    let essence = params.next()?.trim();
    if !essence.eq_ignore_ascii_case("multipart/form-data") {
        return None;
    }
    let boundary = params
        .filter_map(|p| p.split_once('='))
        .find(|(k, _)| k.trim().eq_ignore_ascii_case("boundary"))
        .map(|(_, v)| v.trim().trim_matches('"').to_owned());
    Some(match boundary {
        Some(b) if (1..=70).contains(&b.len()) => Ok(b),
        _ => Err(FormError(
            "multipart/form-data needs a boundary parameter of 1 to 70 characters".to_owned(),
        )),
    })
}

/// The parts of `body`, delimited by `boundary`.
pub fn parts(body: &Bytes, boundary: &str) -> Result<Vec<Part>, FormError> {
    let err = |m: &str| Err(FormError(m.to_owned()));
    let dash_boundary = format!("--{boundary}");
    let delimiter = format!("\r\n--{boundary}");
    let finder = memmem::Finder::new(delimiter.as_bytes());
    // The first delimiter may open the body, without the CRLF before it.
    let mut at = if body.starts_with(dash_boundary.as_bytes()) {
        dash_boundary.len()
    } else {
        match finder.find(body) {
            Some(i) => i + delimiter.len(),
            None => return err("the body has no multipart delimiter of its boundary"),
        }
    };
    let mut parts = Vec::new();
    loop {
        let rest = &body[at..];
        if rest.starts_with(b"--") {
            return Ok(parts);
        }
        // Transport padding (spaces and tabs), then the line's end.
        let padding = rest
            .iter()
            .take_while(|b| **b == b' ' || **b == b'\t')
            .count();
        if !rest[padding..].starts_with(b"\r\n") {
            return err("a multipart delimiter is not followed by a line end");
        }
        let headers_start = at + padding + 2;
        let Some(headers_length) = memmem::find(&body[headers_start..], b"\r\n\r\n")
            .or_else(|| body[headers_start..].starts_with(b"\r\n").then_some(0))
        else {
            return err("a part's headers do not end");
        };
        if headers_length > MAX_HEADER_BYTES {
            return err("a part's headers are over 8 KiB");
        }
        let headers = &body[headers_start..headers_start + headers_length];
        let content_start = if headers_length == 0 {
            headers_start + 2
        } else {
            headers_start + headers_length + 4
        };
        let Some(content_length) = finder.find(&body[content_start..]) else {
            return err("the body ends inside a part: no closing delimiter");
        };
        if parts.len() == MAX_PARTS {
            return err("more parts than a form of glint has");
        }
        let (name, content_type) = part_headers(headers)?;
        parts.push(Part {
            name,
            content_type,
            body: body.slice(content_start..content_start + content_length),
        });
        at = content_start + content_length + delimiter.len();
    }
}

/// The name (from `Content-Disposition: form-data; name="…"`) and the
/// content type of a part.
fn part_headers(headers: &[u8]) -> Result<(String, Option<String>), FormError> {
    let headers = std::str::from_utf8(headers)
        .map_err(|_| FormError("a part's headers are not UTF-8".to_owned()))?;
    let mut name = None;
    let mut content_type = None;
    for line in headers.split("\r\n") {
        let Some((field, value)) = line.split_once(':') else {
            return Err(FormError(format!(
                "a part's header line {line:?} has no colon"
            )));
        };
        let value = value.trim();
        if field.trim().eq_ignore_ascii_case("content-disposition") {
            let mut params = value.split(';');
            if !params
                .next()
                .is_some_and(|d| d.trim().eq_ignore_ascii_case("form-data"))
            {
                return Err(FormError(
                    "a part's disposition is not form-data".to_owned(),
                ));
            }
            name = params
                .filter_map(|p| p.split_once('='))
                .find(|(k, _)| k.trim().eq_ignore_ascii_case("name"))
                .map(|(_, v)| unquote(v.trim()));
        } else if field.trim().eq_ignore_ascii_case("content-type") {
            content_type = Some(value.to_owned());
        }
    }
    let name = name.ok_or_else(|| FormError("a part has no name".to_owned()))?;
    Ok((name, content_type))
}

/// A parameter's value without its quotes (and the backslash escapes a
/// quoted string may have).
fn unquote(value: &str) -> String {
    match value.strip_prefix('"').and_then(|v| v.strip_suffix('"')) {
        None => value.to_owned(),
        Some(quoted) => {
            let mut out = String::with_capacity(quoted.len());
            let mut chars = quoted.chars();
            while let Some(c) = chars.next() {
                out.push(if c == '\\' {
                    chars.next().unwrap_or('\\')
                } else {
                    c
                });
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn form(parts: &[(&str, Option<&str>, &[u8])]) -> Bytes {
        let mut body = b"preamble\r\n".to_vec();
        for (name, content_type, content) in parts {
            body.extend(b"--XyZ\r\n");
            body.extend(
                format!("Content-Disposition: form-data; name=\"{name}\"; filename=\"a.glb\"\r\n")
                    .bytes(),
            );
            if let Some(t) = content_type {
                body.extend(format!("Content-Type: {t}\r\n").bytes());
            }
            body.extend(b"\r\n");
            body.extend(*content);
            body.extend(b"\r\n");
        }
        body.extend(b"--XyZ--\r\nepilogue");
        Bytes::from(body)
    }

    #[test]
    fn parts_are_read_as_sent() {
        let body = form(&[
            ("request", Some("application/json"), b"{}"),
            ("model", None, b"glTF\r\n--Xy\r\n-XyZ--XyZ"),
        ]);
        let parts = parts(&body, "XyZ").unwrap();
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].name, "request");
        assert_eq!(parts[0].content_type.as_deref(), Some("application/json"));
        assert_eq!(&parts[0].body[..], b"{}");
        assert_eq!(parts[1].name, "model");
        assert_eq!(&parts[1].body[..], b"glTF\r\n--Xy\r\n-XyZ--XyZ");
    }

    #[test]
    fn the_boundary_comes_from_the_content_type() {
        assert_eq!(boundary("application/json"), None);
        assert_eq!(
            boundary("multipart/form-data; boundary=\"a b\"")
                .unwrap()
                .unwrap(),
            "a b"
        );
        assert!(boundary("Multipart/Form-Data").unwrap().is_err());
    }

    #[test]
    fn broken_forms_are_refused() {
        let whole = form(&[("model", None, b"x")]);
        for cut in 0..whole.len() - b"--\r\nepilogue".len() {
            assert!(parts(&whole.slice(..cut), "XyZ").is_err(), "{cut}");
        }
        let many: Vec<(&str, Option<&str>, &[u8])> = vec![("a", None, b""); MAX_PARTS + 1];
        assert!(parts(&form(&many), "XyZ").is_err());
        let no_name =
            Bytes::from_static(b"--b\r\nContent-Disposition: form-data\r\n\r\nx\r\n--b--");
        assert!(parts(&no_name, "b").is_err());
    }
}

//! The GLB container (glTF 2.0, section 4.4): a 12-byte header, a JSON chunk,
//! an optional BIN chunk, and chunks of other types that readers ignore.
//!
//! Every length the container states is checked against the bytes held
//! before it is used: the reader borrows the chunks from the body and
//! allocates nothing.

use crate::error::{Error, Result};

/// `glTF` in ASCII, little-endian.
const MAGIC: u32 = 0x4654_6C67;
const VERSION: u32 = 2;
const HEADER_BYTES: usize = 12;
const CHUNK_HEADER_BYTES: usize = 8;
/// `JSON` in ASCII, little-endian.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// `BIN\0` in ASCII, little-endian.
const CHUNK_BIN: u32 = 0x004E_4942;

/// The media type of a GLB.
pub const MEDIA_TYPE: &str = "model/gltf-binary";

/// The chunks of a GLB, borrowed from its bytes.
#[derive(Clone, Copy, Debug)]
pub struct Glb<'a> {
    pub json: &'a [u8],
    /// The BIN chunk, the data of the first buffer; `None` when absent.
    pub bin: Option<&'a [u8]>,
    /// Where the BIN chunk's data starts in the GLB's bytes.
    pub bin_offset: usize,
}

fn u32_at(bytes: &[u8], offset: usize) -> Option<u32> {
    let word = bytes.get(offset..offset.checked_add(4)?)?;
    Some(u32::from_le_bytes(word.try_into().ok()?))
}

impl<'a> Glb<'a> {
    /// Splits `bytes` into its chunks; refuses a container whose header or
    /// chunk lengths do not fit the bytes held.
    pub fn parse(bytes: &'a [u8]) -> Result<Self> {
        if bytes.len() < HEADER_BYTES {
            return Err(Error::malformed(
                "",
                format!(
                    "not a GLB: its header is {HEADER_BYTES} bytes and the model has {}",
                    bytes.len()
                ),
            ));
        }
        let word = |offset| u32_at(bytes, offset).expect("within the header, checked above");
        if word(0) != MAGIC {
            return Err(Error::malformed(
                "",
                "not a GLB: it does not begin with the magic `glTF`",
            ));
        }
        let version = word(4);
        if version != VERSION {
            return Err(Error::unsupported(
                "",
                format!("a GLB of glTF version {version}; glint reads version 2"),
            ));
        }
        let length = word(8) as usize;
        if length != bytes.len() {
            return Err(Error::malformed(
                "",
                format!(
                    "the GLB header gives its length as {length} bytes, and the model has {} \
                     (truncated, or followed by other bytes)",
                    bytes.len()
                ),
            ));
        }
        let mut chunks = Chunks {
            bytes,
            offset: HEADER_BYTES,
        };
        let json = match chunks.next()? {
            Some((CHUNK_JSON, data)) => data,
            Some((kind, _)) => {
                return Err(Error::malformed(
                    "",
                    format!("the first chunk of a GLB must be JSON, not of type {kind:#010x}"),
                ));
            }
            None => return Err(Error::malformed("", "the GLB has no JSON chunk")),
        };
        let mut bin = None;
        let mut bin_offset = 0;
        // Chunks of unknown types are skipped (section 4.4.3.1), and so,
        // after the first, are further BIN chunks, which the format does
        // not define; their lengths are checked all the same.
        loop {
            let offset = chunks.offset + CHUNK_HEADER_BYTES;
            let Some((kind, data)) = chunks.next()? else {
                break;
            };
            if kind == CHUNK_BIN && bin.is_none() {
                bin = Some(data);
                bin_offset = offset;
            }
        }
        Ok(Self {
            json,
            bin,
            bin_offset,
        })
    }
}

struct Chunks<'a> {
    bytes: &'a [u8],
    offset: usize,
}

impl<'a> Chunks<'a> {
    /// The next chunk's type and data, `None` at the end.
    fn next(&mut self) -> Result<Option<(u32, &'a [u8])>> {
        let start = self.offset;
        if start == self.bytes.len() {
            return Ok(None);
        }
        let (Some(length), Some(kind)) = (u32_at(self.bytes, start), u32_at(self.bytes, start + 4))
        else {
            return Err(Error::malformed(
                "",
                format!(
                    "a chunk header at byte {start} runs past the end of the GLB ({} bytes)",
                    self.bytes.len()
                ),
            ));
        };
        let data_start = start + CHUNK_HEADER_BYTES;
        let data = data_start
            .checked_add(length as usize)
            .and_then(|end| self.bytes.get(data_start..end))
            .ok_or_else(|| {
                Error::malformed(
                    "",
                    format!(
                        "the chunk at byte {start} claims {length} bytes, past the end of the \
                         GLB ({} bytes)",
                        self.bytes.len()
                    ),
                )
            })?;
        self.offset = data_start + data.len();
        Ok(Some((kind, data)))
    }
}

/// `n` rounded up to a multiple of 4, the alignment of GLB chunks.
pub fn padded(n: usize) -> usize {
    n.div_ceil(4) * 4
}

/// The bytes of a GLB before its BIN chunk's data: the header, the JSON
/// chunk (padded with spaces) and the header of a BIN chunk of `bin_bytes`
/// bytes, a multiple of 4; no BIN chunk when `bin_bytes` is 0.
pub fn head(json: &[u8], bin_bytes: usize) -> Vec<u8> {
    assert!(
        bin_bytes.is_multiple_of(4),
        "a BIN chunk is padded to 4 bytes"
    );
    let mut total = HEADER_BYTES + CHUNK_HEADER_BYTES + padded(json.len());
    if bin_bytes > 0 {
        total += CHUNK_HEADER_BYTES + bin_bytes;
    }
    let length = |n: usize| {
        u32::try_from(n)
            .expect("a GLB is under 4 GiB")
            .to_le_bytes()
    };
    let mut out = Vec::with_capacity(total - bin_bytes);
    out.extend_from_slice(&MAGIC.to_le_bytes());
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&length(total));
    out.extend_from_slice(&length(padded(json.len())));
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(out.len() + padded(json.len()) - json.len(), b' ');
    if bin_bytes > 0 {
        out.extend_from_slice(&length(bin_bytes));
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
    }
    out
}

/// Writes a GLB of `json` and a BIN chunk made of `bin` (the parts one after
/// the other); no BIN chunk when `bin` is empty. The JSON is padded with
/// spaces and the BIN chunk with zeros to multiples of 4 bytes.
pub fn write(json: &[u8], bin: &[&[u8]]) -> Vec<u8> {
    let bin_bytes: usize = bin.iter().map(|part| part.len()).sum();
    let mut out = head(json, padded(bin_bytes));
    out.reserve(padded(bin_bytes));
    for part in bin {
        out.extend_from_slice(part);
    }
    out.resize(out.len() + padded(bin_bytes) - bin_bytes, 0);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorKind;

    #[test]
    fn a_written_glb_reads_back() {
        let glb = write(br#"{"asset":{"version":"2.0"}}"#, &[&[1, 2, 3], &[4, 5]]);
        assert_eq!(glb.len() % 4, 0);
        let read = Glb::parse(&glb).unwrap();
        assert_eq!(
            std::str::from_utf8(read.json).unwrap().trim_end(),
            r#"{"asset":{"version":"2.0"}}"#
        );
        assert_eq!(read.bin.unwrap(), &[1, 2, 3, 4, 5, 0, 0, 0]);
        let no_bin = write(b"{}", &[]);
        assert!(Glb::parse(&no_bin).unwrap().bin.is_none());
    }

    #[test]
    fn every_prefix_of_a_glb_is_refused() {
        let glb = write(b"{}", &[&[7; 8]]);
        for n in 0..glb.len() {
            let e = Glb::parse(&glb[..n]).unwrap_err();
            assert_eq!(e.kind, ErrorKind::Malformed, "{n}: {e}");
        }
    }

    #[test]
    fn a_chunk_length_past_the_body_is_refused() {
        let mut glb = write(b"{}", &[&[7; 8]]);
        // The BIN chunk's length, after the header and the JSON chunk.
        let at = HEADER_BYTES + CHUNK_HEADER_BYTES + 4;
        glb[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = Glb::parse(&glb).unwrap_err();
        assert!(e.detail.contains("past the end"), "{e}");
        let mut glb = write(b"{}", &[]);
        glb[HEADER_BYTES..HEADER_BYTES + 4].copy_from_slice(&0x7fff_fff0u32.to_le_bytes());
        assert!(Glb::parse(&glb).is_err());
    }

    #[test]
    fn a_first_version_glb_is_unsupported() {
        let mut glb = write(b"{}", &[]);
        glb[4] = 1;
        assert_eq!(Glb::parse(&glb).unwrap_err().kind, ErrorKind::Unsupported);
    }
}

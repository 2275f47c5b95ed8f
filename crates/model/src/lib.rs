//! Binary glTF 2.0 (GLB) in and out, for a service that must never trust
//! the numbers a model claims.
//!
//! [`Model::parse`] reads a GLB ([`glb`]) and its JSON, and refuses what
//! glint cannot honour (a required extension it does not read, a buffer
//! that names a URI) at once. [`Model::place`] then reads the default
//! scene's triangle primitives as their nodes place them ([`place`]): every
//! accessor is checked against its buffer view, every buffer view against
//! its buffer, every buffer against the bytes held, every index against the
//! vertices, before anything is allocated from the count it claims; what an
//! accessor without a buffer view claims is bounded by the caller's
//! [`Options`]. [`edit::Edit`] writes a model back with attributes added:
//! the input's JSON edited in place, so that everything glint does not read
//! is kept as it came.
//!
//! Errors ([`Error`]) carry a JSON Pointer into the model's JSON
//! (`/accessors/3/count`, `/meshes/0/primitives/1/attributes/NORMAL`), or
//! the empty pointer for the container.
//!
//! ```
//! use glint_model::{Model, Options, glb};
//!
//! // One triangle: three positions, no normals.
//! let positions: Vec<u8> = [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]]
//!     .iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
//! let json = br#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
//!   "nodes":[{"mesh":0,"translation":[0,0,-5]}],
//!   "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
//!   "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}],
//!   "bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]}"#;
//! let bytes = glb::write(json, &[&positions]);
//! let model = Model::parse(&bytes).unwrap();
//! let placed = model.place(&Options::default()).unwrap();
//! let triangle = &placed.instances[0];
//! assert_eq!(triangle.positions[1].to_array(), [1.0, 0.0, -5.0]);
//! // No normals in the model: computed from the triangle, facing +z.
//! assert_eq!(triangle.normals[0].to_array(), [0.0, 0.0, 1.0]);
//! ```

mod accessor;
pub mod edit;
mod error;
pub mod glb;
pub mod place;
pub mod schema;

pub use error::{Error, ErrorKind, Result};
pub use place::{Instance, Placed, PlacedCamera, PlacedLight};

use serde::de::DeserializeOwned;
use serde_json::Value;

/// The largest JSON chunk glint reads (413 above). A model's JSON is read
/// whole into a tree some ten times its size at worst (`[{},{},…]`); real
/// models' JSON chunks are kilobytes to a few megabytes, their bulk lives in
/// the BIN chunk.
pub const MAX_JSON_BYTES: usize = 16 * 1024 * 1024;

/// The most primitives one model may place (413 above), counting a mesh
/// once per node that uses it: each gets its own attributes, and its own
/// copy of the mesh in a baked model.
pub const MAX_PRIMITIVES: usize = 65_536;

/// The most triangles a model may place per vertex placed (413 above): a
/// closed mesh has about 2. It bounds what index accessors without a
/// buffer view may claim.
pub const TRIANGLES_PER_VERTEX: usize = 4;

/// The extensions that a model may require: those glint reads
/// (`KHR_lights_punctual`, `KHR_materials_unlit`,
/// `KHR_materials_emissive_strength`) and those of textures and material
/// looks that glint passes through untouched and that change no vertex.
/// Any other required extension is refused (415): Draco and meshopt
/// compress the geometry, `KHR_mesh_quantization` changes what a vertex
/// attribute may hold.
pub const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_unlit",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
];

/// How [`Model::place`] places a model, and what it may allocate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Vertices placed, over every primitive and every node that uses it.
    pub max_vertices: usize,
    /// The largest magnitude of a placed coordinate.
    pub max_coordinate: f64,
    /// Whether placed normals are normalised (GL_NORMALIZE): else they are
    /// the model's normals times the inverse transpose of the node's
    /// matrix, as GL computes them without it.
    pub normalize_normals: bool,
    /// Whether [`Instance::triangles`] are kept (a render needs them);
    /// else the indices are only checked, and the triangles are kept only
    /// where they were needed for normals.
    pub keep_triangles: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            max_vertices: 4_000_000,
            max_coordinate: 1e30,
            normalize_normals: true,
            keep_triangles: true,
        }
    }
}

/// A parsed GLB: its JSON, read whole, and its BIN chunk, borrowed.
#[derive(Clone, Debug)]
pub struct Model<'a> {
    json: Value,
    /// The first buffer's bytes: the BIN chunk up to the buffer's
    /// `byteLength`; empty when the model has no buffer.
    bin: &'a [u8],
    /// Where `bin` starts in the GLB's bytes.
    bin_offset: usize,
}

impl<'a> Model<'a> {
    /// Reads a GLB: the container, the JSON, the buffers, and
    /// `extensionsRequired`.
    pub fn parse(bytes: &'a [u8]) -> Result<Self> {
        let glb = glb::Glb::parse(bytes)?;
        if glb.json.len() > MAX_JSON_BYTES {
            return Err(Error::over_limit(
                "",
                format!(
                    "the JSON chunk is {} bytes, over the limit of {MAX_JSON_BYTES}",
                    glb.json.len()
                ),
            ));
        }
        let json: Value = serde_json::from_slice(glb.json)
            .map_err(|e| Error::malformed("", format!("the JSON chunk is not JSON: {e}")))?;
        if !json.is_object() {
            return Err(Error::malformed("", "the JSON chunk is not an object"));
        }
        let mut model = Self {
            json,
            bin: &[],
            bin_offset: glb.bin_offset,
        };
        model.check_version()?;
        model.check_required_extensions()?;
        model.bin = model.first_buffer(glb.bin)?;
        Ok(model)
    }

    fn check_version(&self) -> Result<()> {
        let version = self.json.pointer("/asset/version").and_then(Value::as_str);
        match version {
            Some(v) if v.split('.').next() == Some("2") => Ok(()),
            Some(v) => Err(Error::unsupported(
                "/asset/version",
                format!("glTF version {v}; glint reads version 2"),
            )),
            None => Err(Error::malformed(
                "/asset/version",
                "a glTF model states its version in asset.version",
            )),
        }
    }

    fn check_required_extensions(&self) -> Result<()> {
        let required: Vec<String> = self.get_or_default("/extensionsRequired")?;
        for (i, name) in required.iter().enumerate() {
            if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&name.as_str()) {
                return Err(Error::unsupported(
                    format!("/extensionsRequired/{i}"),
                    format!(
                        "the model requires the extension {name}, which glint does not read \
                         (it reads {})",
                        SUPPORTED_REQUIRED_EXTENSIONS.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The bytes of the first buffer: the BIN chunk, as long as the buffer
    /// says. Buffers are the BIN chunk or nothing: a URI, external or
    /// `data:`, is refused, so a request never makes glint read a file or
    /// the network.
    fn first_buffer(&self, bin: Option<&'a [u8]>) -> Result<&'a [u8]> {
        let count = self.count("buffers");
        let mut first = &[][..];
        for i in 0..count {
            let at = format!("/buffers/{i}");
            let buffer: schema::Buffer = self.get(&at)?;
            if buffer.uri.is_some() {
                return Err(Error::invalid(
                    format!("{at}/uri"),
                    "a buffer with a URI: glint reads the GLB's own BIN chunk only, never a \
                     file, the network or a data URI",
                ));
            }
            if i > 0 {
                return Err(Error::invalid(
                    at,
                    "only the first buffer of a GLB may be its BIN chunk, and other buffers \
                     would need URIs",
                ));
            }
            let held = bin.map_or(0, <[u8]>::len);
            first = usize::try_from(buffer.byte_length)
                .ok()
                .and_then(|n| bin?.get(..n))
                .ok_or_else(|| {
                    Error::invalid(
                        format!("{at}/byteLength"),
                        format!(
                            "the buffer claims {} bytes and the BIN chunk holds {held}",
                            buffer.byte_length
                        ),
                    )
                })?;
        }
        Ok(first)
    }

    /// The model's JSON, as read.
    pub fn json(&self) -> &Value {
        &self.json
    }

    /// The first buffer's bytes (the BIN chunk up to its `byteLength`).
    pub fn bin(&self) -> &'a [u8] {
        self.bin
    }

    /// Where the first buffer's bytes lie in the GLB's bytes.
    pub fn bin_range(&self) -> std::ops::Range<usize> {
        self.bin_offset..self.bin_offset + self.bin.len()
    }

    /// The number of entries of the top-level array `name` (0 when absent
    /// or not an array: reading an entry then says what is wrong).
    pub fn count(&self, name: &str) -> usize {
        self.json
            .get(name)
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    }

    /// The value at `pointer`, read as `T`.
    pub fn get<T: DeserializeOwned>(&self, pointer: &str) -> Result<T> {
        let value = self.json.pointer(pointer).ok_or_else(|| {
            Error::invalid(
                pointer,
                "the model has nothing here (a reference past an array?)",
            )
        })?;
        read(value, pointer)
    }

    /// The value at `pointer` read as `T`, or `T`'s default when absent.
    pub fn get_or_default<T: DeserializeOwned + Default>(&self, pointer: &str) -> Result<T> {
        match self.json.pointer(pointer) {
            None => Ok(T::default()),
            Some(value) => read(value, pointer),
        }
    }

    /// Entry `index` of the top-level array `name`, referred to from
    /// `referrer`: an index past the array is the referrer's fault.
    pub fn entry<T: DeserializeOwned>(
        &self,
        name: &str,
        index: usize,
        referrer: &str,
    ) -> Result<T> {
        if index >= self.count(name) {
            return Err(Error::invalid(
                referrer,
                format!(
                    "refers to {name} {index}, and the model has {}",
                    self.count(name)
                ),
            ));
        }
        self.get(&format!("/{name}/{index}"))
    }

    /// The name of material `index`, if it has one.
    pub fn material_name(&self, index: usize) -> Option<&str> {
        self.json
            .get("materials")?
            .get(index)?
            .get("name")?
            .as_str()
    }

    /// Takes the JSON out, to edit it ([`edit::Edit`]).
    pub fn into_json(self) -> Value {
        self.json
    }
}

fn read<T: DeserializeOwned>(value: &Value, pointer: &str) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| Error::from_serde(pointer, e))
}

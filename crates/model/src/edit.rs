//! Writing a model back with vertex attributes added to its placed
//! primitives: new accessors and buffer views over data appended to the
//! first buffer, the JSON edited in place so that everything else (nodes,
//! materials, textures, other attributes, extensions, extras) stays as it
//! came.
//!
//! A mesh that several nodes use gets its attributes once per node: the
//! first node in scene order keeps the mesh, each further node gets its own
//! copy of it, whose primitives share the original's accessors but for the
//! attributes added.

use std::collections::HashMap;

use serde_json::{Value, json};

use crate::{Model, glb};

/// `target` of a buffer view of vertex attributes.
const ARRAY_BUFFER: u32 = 34962;

/// The layout of an added attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// VEC4 of unsigned bytes, normalised: `c = i / 255`.
    Vec4Unorm8,
    /// VEC4 of unsigned shorts, normalised: `c = i / 65535`.
    Vec4Unorm16,
    /// VEC4 of floats.
    Vec4F32,
    /// VEC3 of floats.
    Vec3F32,
}

impl Format {
    /// Bytes per element, a multiple of 4 as vertex attributes must be.
    pub fn bytes(self) -> usize {
        match self {
            Self::Vec4Unorm8 => 4,
            Self::Vec4Unorm16 => 8,
            Self::Vec4F32 => 16,
            Self::Vec3F32 => 12,
        }
    }

    fn accessor(self, view: usize, count: usize) -> Value {
        let (component, kind, normalized) = match self {
            Self::Vec4Unorm8 => (5121, "VEC4", true),
            Self::Vec4Unorm16 => (5123, "VEC4", true),
            Self::Vec4F32 => (5126, "VEC4", false),
            Self::Vec3F32 => (5126, "VEC3", false),
        };
        let mut accessor = json!({
            "bufferView": view,
            "componentType": component,
            "count": count,
            "type": kind,
        });
        if normalized {
            accessor["normalized"] = Value::Bool(true);
        }
        accessor
    }
}

/// A model being edited.
pub struct Edit<'a> {
    json: Value,
    /// The first buffer as read.
    bin: &'a [u8],
    /// Where it lies in the input's bytes.
    bin_range: std::ops::Range<usize>,
    /// What follows it in the output's first buffer: the zeros that pad it
    /// to a multiple of 4 bytes, then the attributes added.
    appended: Vec<u8>,
    /// Those zeros.
    padding: usize,
    /// For each mesh, the first node that was given attributes on it.
    first_user: HashMap<usize, usize>,
    /// The copy of a mesh that a further node uses: (node, mesh) → copy.
    copies: HashMap<(usize, usize), usize>,
    /// The unlit copy of each material (`None`: glTF's default material).
    unlit: HashMap<Option<usize>, usize>,
    /// The accessors of the input: those below it are the model's own.
    input_accessors: usize,
    replaced_colors: usize,
}

impl<'a> Edit<'a> {
    pub fn new(model: Model<'a>) -> Self {
        let bin = model.bin();
        let bin_range = model.bin_range();
        let padding = glb::padded(bin.len()) - bin.len();
        let input_accessors = model.count("accessors");
        Self {
            json: model.into_json(),
            bin,
            bin_range,
            appended: vec![0; padding],
            padding,
            first_user: HashMap::new(),
            copies: HashMap::new(),
            unlit: HashMap::new(),
            input_accessors,
            replaced_colors: 0,
        }
    }

    /// Reserves room for `bytes` more bytes of attributes.
    pub fn reserve(&mut self, bytes: usize) {
        self.appended.reserve(bytes);
    }

    /// How many primitives had a `COLOR_0` of the input's that an added one
    /// replaced.
    pub fn replaced_colors(&self) -> usize {
        self.replaced_colors
    }

    /// The mesh that `node` shows as `mesh` in the output: the mesh itself
    /// for its first node, a copy for each further one.
    fn output_mesh(&mut self, node: usize, mesh: usize) -> usize {
        let first = *self.first_user.entry(mesh).or_insert(node);
        if first == node {
            return mesh;
        }
        if let Some(&copy) = self.copies.get(&(node, mesh)) {
            return copy;
        }
        let copy_json = self.json["meshes"][mesh].clone();
        let meshes = array(&mut self.json, "meshes");
        meshes.push(copy_json);
        let copy = meshes.len() - 1;
        self.json["nodes"][node]["mesh"] = json!(copy);
        self.copies.insert((node, mesh), copy);
        copy
    }

    /// Adds attribute `name` of `count` elements in `format` to primitive
    /// `primitive` of `mesh` as `node` places it, replacing one of that
    /// name; returns its bytes, zeroed, for the caller to fill.
    pub fn attribute(
        &mut self,
        node: usize,
        mesh: usize,
        primitive: usize,
        name: &str,
        format: Format,
        count: usize,
    ) -> &mut [u8] {
        let mesh = self.output_mesh(node, mesh);
        let start = self.appended.len();
        let length = count * format.bytes();
        let view = json!({
            "buffer": 0,
            "byteOffset": self.bin.len() + start,
            "byteLength": length,
            "target": ARRAY_BUFFER,
        });
        let views = array(&mut self.json, "bufferViews");
        views.push(view);
        let view = views.len() - 1;
        let accessors = array(&mut self.json, "accessors");
        accessors.push(format.accessor(view, count));
        let accessor = accessors.len() - 1;
        let attributes = &mut self.json["meshes"][mesh]["primitives"][primitive]["attributes"];
        let previous = attributes
            .as_object_mut()
            .expect("a placed primitive has attributes")
            .insert(name.to_owned(), json!(accessor));
        // A copy of a mesh has the attributes added to the original.
        let own = previous
            .and_then(|p| p.as_u64())
            .is_some_and(|p| p < self.input_accessors as u64);
        if name == "COLOR_0" && own {
            self.replaced_colors += 1;
        }
        self.appended.resize(start + length, 0);
        &mut self.appended[start..]
    }

    /// Gives primitive `primitive` of `mesh`, as `node` places it, an unlit
    /// copy of its material `original` (`KHR_materials_unlit`) whose base
    /// colour factor is white: a viewer then shows the baked colours as
    /// they are, times the base colour texture if there is one.
    pub fn unlit_material(
        &mut self,
        node: usize,
        mesh: usize,
        primitive: usize,
        original: Option<usize>,
    ) {
        let mesh = self.output_mesh(node, mesh);
        let material = match self.unlit.get(&original) {
            Some(&m) => m,
            None => {
                let mut copy = match original {
                    Some(m) => self.json["materials"][m].clone(),
                    None => json!({}),
                };
                copy["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 1.0]);
                copy["extensions"]["KHR_materials_unlit"] = json!({});
                let materials = array(&mut self.json, "materials");
                materials.push(copy);
                let m = materials.len() - 1;
                self.unlit.insert(original, m);
                m
            }
        };
        self.json["meshes"][mesh]["primitives"][primitive]["material"] = json!(material);
    }

    /// The output GLB, with `glint` in the root's `extras`, in three
    /// parts: the input's first buffer is its middle, unchanged, so that it
    /// can be sent from where it was read.
    pub fn finish(mut self, glint: Value) -> Written {
        if !self.unlit.is_empty() {
            let used = array(&mut self.json, "extensionsUsed");
            if !used.iter().any(|e| e == "KHR_materials_unlit") {
                used.push(json!("KHR_materials_unlit"));
            }
        }
        let added = self.appended.len() > self.padding;
        if added {
            let length = json!(self.bin.len() + self.appended.len());
            match self.json.get_mut("buffers").and_then(Value::as_array_mut) {
                Some(buffers) if !buffers.is_empty() => buffers[0]["byteLength"] = length,
                _ => self.json["buffers"] = json!([{ "byteLength": length }]),
            }
        }
        match self.json.get_mut("extras") {
            Some(Value::Object(extras)) => {
                extras.insert("glint".to_owned(), glint);
            }
            // Extras of another type than an object are kept beside ours.
            Some(other) => {
                let input = other.take();
                *other = json!({ "glint": glint, "input": input });
            }
            None => self.json["extras"] = json!({ "glint": glint }),
        }
        let json = serde_json::to_vec(&self.json).expect("a JSON value always serialises");
        // The input's buffer, padded: after it come the attributes added.
        let tail = if added || !self.bin.is_empty() {
            self.appended
        } else {
            Vec::new()
        };
        Written {
            head: glb::head(&json, self.bin.len() + tail.len()),
            bin: self.bin_range,
            tail,
        }
    }
}

/// A GLB in three parts: `head`, the bytes `bin` of the input GLB, `tail`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Written {
    pub head: Vec<u8>,
    /// A range of the input GLB's bytes.
    pub bin: std::ops::Range<usize>,
    pub tail: Vec<u8>,
}

impl Written {
    /// The GLB whole, its middle taken from `input`, the bytes that were
    /// read.
    pub fn to_vec(&self, input: &[u8]) -> Vec<u8> {
        [&self.head[..], &input[self.bin.clone()], &self.tail[..]].concat()
    }

    pub fn len(&self) -> usize {
        self.head.len() + self.bin.len() + self.tail.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The top-level array `name`, made when absent.
fn array<'v>(json: &'v mut Value, name: &str) -> &'v mut Vec<Value> {
    let slot = &mut json[name];
    if !slot.is_array() {
        *slot = Value::Array(Vec::new());
    }
    slot.as_array_mut().expect("made an array above")
}

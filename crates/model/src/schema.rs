//! The parts of glTF 2.0's JSON schema that glint reads, as serde types.
//! Fields glint does not read are not here: they stay in the model's JSON
//! as they came, and are written back untouched. Each object is read from
//! that JSON when it is needed, so a model's JSON is held once.

use std::collections::BTreeMap;

use serde::Deserialize;
use serde::de::IgnoredAny;

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Accessor {
    pub buffer_view: Option<usize>,
    #[serde(default)]
    pub byte_offset: u64,
    pub component_type: u32,
    #[serde(default)]
    pub normalized: bool,
    pub count: u64,
    #[serde(rename = "type")]
    pub kind: String,
    pub sparse: Option<Sparse>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Sparse {
    pub count: u64,
    pub indices: SparseIndices,
    pub values: SparseValues,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SparseIndices {
    pub buffer_view: usize,
    #[serde(default)]
    pub byte_offset: u64,
    pub component_type: u32,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct SparseValues {
    pub buffer_view: usize,
    #[serde(default)]
    pub byte_offset: u64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct BufferView {
    pub buffer: usize,
    #[serde(default)]
    pub byte_offset: u64,
    pub byte_length: u64,
    pub byte_stride: Option<u64>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Buffer {
    pub byte_length: u64,
    pub uri: Option<String>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Mesh {
    pub primitives: Vec<Primitive>,
}

/// `mode` 4.
pub const TRIANGLES: u32 = 4;

#[derive(Clone, Debug, Deserialize)]
pub struct Primitive {
    pub attributes: BTreeMap<String, usize>,
    pub indices: Option<usize>,
    pub material: Option<usize>,
    #[serde(default = "triangles")]
    pub mode: u32,
    pub targets: Option<IgnoredAny>,
}

fn triangles() -> u32 {
    TRIANGLES
}

#[derive(Clone, Debug, Default, Deserialize)]
pub struct Node {
    pub camera: Option<usize>,
    #[serde(default)]
    pub children: Vec<usize>,
    pub skin: Option<usize>,
    /// Column-major.
    pub matrix: Option<[f64; 16]>,
    pub mesh: Option<usize>,
    /// A unit quaternion, `[x, y, z, w]`.
    pub rotation: Option<[f64; 4]>,
    pub scale: Option<[f64; 3]>,
    pub translation: Option<[f64; 3]>,
    pub extensions: Option<NodeExtensions>,
}

#[derive(Clone, Debug, Default, Deserialize)]
pub struct NodeExtensions {
    #[serde(rename = "KHR_lights_punctual")]
    pub lights_punctual: Option<NodeLight>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct NodeLight {
    pub light: usize,
}

#[derive(Clone, Debug, Default, Deserialize)]
pub struct Scene {
    #[serde(default)]
    pub nodes: Vec<usize>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Material {
    pub name: Option<String>,
    pub pbr_metallic_roughness: Option<PbrMetallicRoughness>,
    pub emissive_factor: Option<[f64; 3]>,
    pub emissive_texture: Option<IgnoredAny>,
    pub normal_texture: Option<IgnoredAny>,
    pub occlusion_texture: Option<IgnoredAny>,
    #[serde(default)]
    pub double_sided: bool,
    /// The names of its extensions, with their objects.
    #[serde(default)]
    pub extensions: BTreeMap<String, serde_json::Value>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct PbrMetallicRoughness {
    pub base_color_factor: Option<[f64; 4]>,
    pub base_color_texture: Option<IgnoredAny>,
    pub metallic_factor: Option<f64>,
    pub roughness_factor: Option<f64>,
    pub metallic_roughness_texture: Option<IgnoredAny>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct Camera {
    #[serde(rename = "type")]
    pub kind: String,
    pub perspective: Option<Perspective>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Perspective {
    /// Radians.
    pub yfov: f64,
    pub aspect_ratio: Option<f64>,
}

/// A light of `KHR_lights_punctual`.
#[derive(Clone, Debug, Deserialize)]
pub struct Light {
    #[serde(rename = "type")]
    pub kind: String,
    pub color: Option<[f64; 3]>,
    pub intensity: Option<f64>,
    pub range: Option<f64>,
    pub spot: Option<LightSpot>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct LightSpot {
    pub inner_cone_angle: Option<f64>,
    pub outer_cone_angle: Option<f64>,
}

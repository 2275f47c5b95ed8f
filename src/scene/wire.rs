//! The request bodies as they arrive: serde types that mirror
//! `api/openapi.yaml` field by field. Every field a client may leave out is an
//! `Option` here, and gets its (GL) default in validation, so defaults live in
//! one place: the domain types' `Default`. Unknown fields are rejected.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use glint_lighting::MAX_LIGHTS;

use super::TermsDetail;

/// `precision`: the evaluator a request asks for, by its name on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    Reference,
    #[default]
    Accurate,
    Fast,
}

impl From<Precision> for glint_lighting::Precision {
    fn from(p: Precision) -> Self {
        match p {
            Precision::Reference => Self::Reference,
            Precision::Accurate => Self::Accurate,
            Precision::Fast => Self::Fast,
        }
    }
}

impl From<glint_lighting::Precision> for Precision {
    fn from(p: glint_lighting::Precision) -> Self {
        match p {
            glint_lighting::Precision::Reference => Self::Reference,
            glint_lighting::Precision::Accurate => Self::Accurate,
            glint_lighting::Precision::Fast => Self::Fast,
        }
    }
}

/// A colour: `[r, g, b]` (alpha 1) or `[r, g, b, a]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Color(pub [f64; 4]);

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        const EXPECTED: &str = "3 or 4 numbers ([r, g, b] or [r, g, b, a])";
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Color;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(EXPECTED)
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Color, A::Error> {
                let mut c = [0.0, 0.0, 0.0, 1.0];
                let mut len = 0;
                while let Some(v) = seq.next_element::<f64>()? {
                    if let Some(slot) = c.get_mut(len) {
                        *slot = v;
                    }
                    len += 1;
                }
                if !(3..=4).contains(&len) {
                    return Err(serde::de::Error::invalid_length(len, &EXPECTED));
                }
                Ok(Color(c))
            }
        }
        d.deserialize_seq(Visitor)
    }
}

/// A value that must be a JSON object. serde's derived structs also accept
/// an array of their fields in order, which the contract does not allow (and
/// whose errors could not name a field); every struct of a request is read
/// through this.
pub struct JsonObject<T>(pub T);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for JsonObject<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Visitor<T> {
            type Value = T;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object")
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
                T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
            }
        }
        d.deserialize_map(Visitor(std::marker::PhantomData))
            .map(JsonObject)
    }
}

fn object<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
    JsonObject::deserialize(d).map(|JsonObject(t)| t)
}

fn optional_object<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<JsonObject<T>>::deserialize(d).map(|o| o.map(|JsonObject(t)| t))
}

pub type Vec3 = [f64; 3];

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightModel {
    pub ambient: Option<Color>,
    pub local_viewer: Option<bool>,
    pub two_side: Option<bool>,
    pub color_control: Option<ColorControl>,
    pub specular_model: Option<SpecularModel>,
    pub attenuation_clamp: Option<bool>,
    pub normalize_normals: Option<bool>,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorControl {
    Single,
    SeparateSpecular,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpecularModel {
    BlinnPhong,
    Phong,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub ambient: Option<Color>,
    pub diffuse: Option<Color>,
    pub specular: Option<Color>,
    pub emission: Option<Color>,
    pub shininess: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Homogeneous, as glLightfv(GL_POSITION): w = 0 is directional.
    pub position: Option<[f64; 4]>,
    pub ambient: Option<Color>,
    pub diffuse: Option<Color>,
    pub specular: Option<Color>,
    pub attenuation: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "optional_object")]
    pub spot: Option<Spot>,
}

/// A list of which only the first `N + 1` entries are built, since no
/// server takes more; the rest are read as JSON and counted, so that the
/// limit can refuse them with their true count. A body of a million `{}`
/// lights or objects would otherwise become a million structs of a few
/// hundred bytes, a hundred times its size, before any limit is checked.
#[derive(Clone, Debug)]
pub struct Capped<T, const N: usize> {
    built: Vec<T>,
    count: usize,
}

impl<T, const N: usize> Capped<T, N> {
    /// How many entries the request lists.
    pub fn count(&self) -> usize {
        self.count
    }
}

impl<T, const N: usize> Default for Capped<T, N> {
    fn default() -> Self {
        Self {
            built: Vec::new(),
            count: 0,
        }
    }
}

impl<T, const N: usize> std::ops::Deref for Capped<T, N> {
    type Target = [T];

    /// The entries, complete when [`Capped::count`] is at most `N`.
    fn deref(&self) -> &[T] {
        &self.built
    }
}

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Capped<T, N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> serde::de::Visitor<'de> for Visitor<T, N> {
            type Value = Capped<T, N>;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an array")
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Capped<T, N>, A::Error> {
                let mut list = Capped::default();
                while list.built.len() <= N {
                    match seq.next_element::<JsonObject<T>>()? {
                        Some(JsonObject(entry)) => list.built.push(entry),
                        None => break,
                    }
                }
                list.count = list.built.len();
                while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    list.count += 1;
                }
                Ok(list)
            }
        }
        d.deserialize_seq(Visitor::<T, N>(std::marker::PhantomData))
    }
}

/// The `lights` of a request.
pub type Lights = Capped<Light, MAX_LIGHTS>;

/// The most objects in one render.
pub const MAX_OBJECTS: usize = 65_536;

/// The most named materials in one render.
pub const MAX_MATERIALS: usize = 4096;

/// The named materials of a render, capped as [`Capped`] is.
#[derive(Clone, Debug, Default)]
pub struct Materials {
    built: BTreeMap<String, Material>,
    count: usize,
}

impl Materials {
    /// How many materials the request names.
    pub fn count(&self) -> usize {
        self.count
    }
}

impl std::ops::Deref for Materials {
    type Target = BTreeMap<String, Material>;

    fn deref(&self) -> &Self::Target {
        &self.built
    }
}

impl<'de> Deserialize<'de> for Materials {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Materials;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map of named materials")
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Materials, A::Error> {
                let mut materials = Materials::default();
                while materials.built.len() <= MAX_MATERIALS {
                    match map.next_entry::<String, JsonObject<Material>>()? {
                        Some((name, JsonObject(material))) => {
                            materials.built.insert(name, material);
                        }
                        None => break,
                    }
                }
                materials.count = materials.built.len();
                while map
                    .next_entry::<serde::de::IgnoredAny, serde::de::IgnoredAny>()?
                    .is_some()
                {
                    materials.count += 1;
                }
                Ok(materials)
            }
        }
        d.deserialize_map(Visitor)
    }
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spot {
    pub direction: Option<Vec3>,
    pub exponent: Option<f64>,
    pub cutoff: Option<f64>,
}

/// The view of `/v1/shade`: world space, with the eye as the viewer.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct View {
    pub eye: Vec3,
    pub target: Vec3,
    /// Accepted for symmetry with the camera; lighting does not depend on it.
    pub up: Option<Vec3>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vertices {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// `POST /v1/shade`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadeRequest {
    #[serde(default, deserialize_with = "optional_object")]
    pub light_model: Option<LightModel>,
    #[serde(default, deserialize_with = "optional_object")]
    pub material: Option<Material>,
    #[serde(default, deserialize_with = "optional_object")]
    pub back_material: Option<Material>,
    pub lights: Option<Lights>,
    #[serde(default, deserialize_with = "optional_object")]
    pub view: Option<View>,
    #[serde(deserialize_with = "object")]
    pub vertices: Vertices,
    pub precision: Option<Precision>,
    pub terms: Option<TermsDetail>,
}

/// `POST /v1/render`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRequest {
    #[serde(default, deserialize_with = "optional_object")]
    pub light_model: Option<LightModel>,
    /// Named materials, referred to by the objects.
    pub materials: Materials,
    /// The back material of every object when two-sided; absent, each
    /// object's own material lights its back too.
    #[serde(default, deserialize_with = "optional_object")]
    pub back_material: Option<Material>,
    pub lights: Option<Lights>,
    #[serde(deserialize_with = "object")]
    pub camera: Camera,
    pub objects: Capped<Object, MAX_OBJECTS>,
    pub background: Option<Color>,
    pub shading: Option<ShadingMode>,
    pub samples: Option<u32>,
    pub shadows: Option<bool>,
    pub precision: Option<Precision>,
    #[serde(default, deserialize_with = "optional_object")]
    pub region: Option<Region>,
    pub probes: Option<Vec<[u32; 2]>>,
    pub encoding: Option<Encoding>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y: f64,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    #[serde(default, deserialize_with = "optional_object")]
    pub sphere: Option<Sphere>,
    #[serde(default, deserialize_with = "optional_object")]
    pub plane: Option<Plane>,
    #[serde(default, deserialize_with = "optional_object")]
    pub mesh: Option<Mesh>,
    pub material: String,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    pub point: Vec3,
    pub normal: Vec3,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<u32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ShadingMode {
    PerPixel,
    PerVertex,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Encoding {
    Linear,
    Srgb,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

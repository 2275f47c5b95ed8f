//! The request bodies as they arrive: serde types that mirror
//! `api/openapi.yaml` field by field. Every field a client may leave out is an
//! `Option` here, and gets its (GL) default in validation, so defaults live in
//! one place: the domain types' `Default`. Unknown fields are rejected, and so
//! is `null` in place of a field (`present`); integers are read as JSON
//! Schema counts them (`U32`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use glint_lighting::MAX_LIGHTS;

use super::model::{ColorFormat, ColorSpace};
use super::{RequestError, TermsDetail};

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

/// `precision` as a request gives it: a tier by its name, or an error
/// budget, `{"max_abs_error": E}`, for the cheapest tier whose documented
/// bound is at most `E`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PrecisionRequest {
    Tier(Precision),
    Budget(f64),
}

impl<'de> Deserialize<'de> for PrecisionRequest {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        /// The budget's object: that one field.
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Budget {
            max_abs_error: f64,
        }
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = PrecisionRequest;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("`reference`, `accurate`, `fast`, or {\"max_abs_error\": E}")
            }

            fn visit_str<E: serde::de::Error>(self, name: &str) -> Result<Self::Value, E> {
                let tier = Precision::deserialize(serde::de::value::StrDeserializer::new(name))?;
                Ok(PrecisionRequest::Tier(tier))
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Self::Value, A::Error> {
                let budget =
                    Budget::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(PrecisionRequest::Budget(budget.max_abs_error))
            }
        }
        d.deserialize_any(Visitor)
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

/// A field that may be left out, when it is there. No field of the contract
/// takes `null`: a field is absent (and gets its default) or of its type, so
/// `null` is refused as a wrong type (400) rather than read as absent, which
/// serde's `Option` would do. Every `Option` of a request is read through
/// this (with `#[serde(default)]` for the absent case) or [`present_object`].
fn present<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(d).map(Some)
}

/// [`present`] for a field whose value is an object.
fn present_object<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    object(d).map(Some)
}

/// A JSON Schema `integer` that fits a u32. JSON Schema counts a number
/// with a zero fraction as an integer (`3.0` is 3), and so does the contract;
/// serde's `u32` takes only the literal `3`.
#[derive(Clone, Copy)]
struct U32(u32);

impl<'de> Deserialize<'de> for U32 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{Error, Unexpected};
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = U32;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an integer from 0 to {}", u32::MAX)
            }

            fn visit_u64<E: Error>(self, v: u64) -> Result<U32, E> {
                u32::try_from(v)
                    .map(U32)
                    .map_err(|_| E::invalid_value(Unexpected::Unsigned(v), &self))
            }

            fn visit_i64<E: Error>(self, v: i64) -> Result<U32, E> {
                u32::try_from(v)
                    .map(U32)
                    .map_err(|_| E::invalid_value(Unexpected::Signed(v), &self))
            }

            fn visit_f64<E: Error>(self, v: f64) -> Result<U32, E> {
                if v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v) {
                    // Exact: a whole number within the range of u32.
                    Ok(U32(v as u32))
                } else {
                    Err(E::invalid_value(Unexpected::Float(v), &self))
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

fn integer<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    U32::deserialize(d).map(|U32(v)| v)
}

fn present_integer<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    integer(d).map(Some)
}

/// A render's `samples`: a count of samples in every pixel, or the object
/// of adaptive sampling.
#[derive(Clone, Copy, Debug)]
pub enum Samples {
    Count(u32),
    Adaptive(AdaptiveSamples),
}

/// `{"max": 64, "tolerance": T}`.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveSamples {
    #[serde(deserialize_with = "integer")]
    pub max: u32,
    pub tolerance: f64,
}

impl<'de> Deserialize<'de> for Samples {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::IntoDeserializer;
        use serde::de::value::MapAccessDeserializer;

        struct Visitor;

        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Samples;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a count of samples per pixel or {\"max\", \"tolerance\"}")
            }

            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Samples, E> {
                U32::deserialize(v.into_deserializer()).map(|U32(n)| Samples::Count(n))
            }

            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Samples, E> {
                U32::deserialize(v.into_deserializer()).map(|U32(n)| Samples::Count(n))
            }

            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Samples, E> {
                U32::deserialize(v.into_deserializer()).map(|U32(n)| Samples::Count(n))
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Samples, A::Error> {
                AdaptiveSamples::deserialize(MapAccessDeserializer::new(map)).map(Samples::Adaptive)
            }
        }

        d.deserialize_any(Visitor)
    }
}

fn integers<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<u32>, D::Error> {
    Vec::<U32>::deserialize(d).map(|v| v.into_iter().map(|U32(i)| i).collect())
}

fn present_pixels<'de, D>(d: D) -> Result<Option<Vec<[u32; 2]>>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    Vec::<[U32; 2]>::deserialize(d)
        .map(|v| Some(v.into_iter().map(|p| p.map(|U32(i)| i)).collect()))
}

pub type Vec3 = [f64; 3];

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightModel {
    #[serde(default, deserialize_with = "present")]
    pub ambient: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub local_viewer: Option<bool>,
    #[serde(default, deserialize_with = "present")]
    pub two_side: Option<bool>,
    #[serde(default, deserialize_with = "present")]
    pub color_control: Option<ColorControl>,
    #[serde(default, deserialize_with = "present")]
    pub specular_model: Option<SpecularModel>,
    #[serde(default, deserialize_with = "present")]
    pub attenuation_clamp: Option<bool>,
    #[serde(default, deserialize_with = "present")]
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
    #[serde(default, deserialize_with = "present")]
    pub ambient: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub diffuse: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub specular: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub emission: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub shininess: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Homogeneous, as glLightfv(GL_POSITION): w = 0 is directional.
    #[serde(default, deserialize_with = "present")]
    pub position: Option<[f64; 4]>,
    #[serde(default, deserialize_with = "present")]
    pub ambient: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub diffuse: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub specular: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub attenuation: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "present_object")]
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
    #[serde(default, deserialize_with = "present")]
    pub direction: Option<Vec3>,
    #[serde(default, deserialize_with = "present")]
    pub exponent: Option<f64>,
    #[serde(default, deserialize_with = "present")]
    pub cutoff: Option<f64>,
}

/// The view of `/v1/shade`: world space, with the eye as the viewer.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct View {
    pub eye: Vec3,
    pub target: Vec3,
    /// Accepted for symmetry with the camera; lighting does not depend on it.
    #[serde(default, deserialize_with = "present")]
    pub up: Option<Vec3>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vertices {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// `POST /v1/shade`: the JSON body, and the `request` part of a request
/// with a model, which differ in three ways that [`ShadeRequest::json_form`]
/// and [`ShadeRequest::model_form`] check: only the JSON body has
/// `vertices` (a model carries its own), and only the model's part has
/// `materials`, `color_space` and `color_format`. `POST /v1/compare` takes
/// the same request with what a compare adds (`candidate`, `worst`,
/// `tolerance`), which [`ShadeRequest::compare_form`] checks.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadeRequest {
    #[serde(default, deserialize_with = "present_object")]
    pub light_model: Option<LightModel>,
    /// The material of every vertex; with a model, of every primitive that
    /// `materials` does not name.
    #[serde(default, deserialize_with = "present_object")]
    pub material: Option<Material>,
    #[serde(default, deserialize_with = "present_object")]
    pub back_material: Option<Material>,
    #[serde(default, deserialize_with = "present")]
    pub lights: Option<Lights>,
    #[serde(default, deserialize_with = "present_object")]
    pub view: Option<View>,
    #[serde(default, deserialize_with = "present_object")]
    pub vertices: Option<Vertices>,
    #[serde(default, deserialize_with = "present")]
    pub precision: Option<PrecisionRequest>,
    #[serde(default, deserialize_with = "present")]
    pub terms: Option<TermsDetail>,
    /// With a model: GL materials by a glTF material's name, or `#<index>`.
    #[serde(default, deserialize_with = "present")]
    pub materials: Option<Materials>,
    #[serde(default, deserialize_with = "present")]
    pub color_space: Option<ColorSpace>,
    #[serde(default, deserialize_with = "present")]
    pub color_format: Option<ColorFormat>,
    /// A compare's candidate colours, in a JSON body.
    #[serde(default, deserialize_with = "present_object")]
    pub candidate: Option<CandidateColors>,
    /// A compare's number of worst vertices to report.
    #[serde(default, deserialize_with = "present")]
    pub worst: Option<usize>,
    /// A compare's largest error that a deviation may leave and explain.
    #[serde(default, deserialize_with = "present")]
    pub tolerance: Option<f64>,
}

/// The candidate of a compare: RGBA per vertex, in the order of the
/// vertices, and per vertex of the back side for a two-sided light model.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CandidateColors {
    pub colors: Vec<[f32; 4]>,
    #[serde(default, deserialize_with = "present")]
    pub back_colors: Option<Vec<[f32; 4]>>,
}

impl ShadeRequest {
    /// The vertices of the JSON body, which has them and none of the
    /// options of a model or a compare.
    pub fn json_form(&self) -> Result<&Vertices, RequestError> {
        refuse(&self.model_fields(), "only a request with a model takes it")?;
        refuse(&self.compare_fields(), "only /v1/compare takes it")?;
        self.vertices
            .as_ref()
            .ok_or_else(|| missing("", "vertices"))
    }

    /// Checks the `request` part of a request with a model, which has no
    /// vertices of its own; `compare` says whether it is a compare's, which
    /// takes `worst` and `tolerance` (its candidate is in the model).
    pub fn model_form(&self, compare: bool) -> Result<(), RequestError> {
        if self.vertices.is_some() {
            return Err(RequestError::malformed(
                "/vertices",
                "unknown field `vertices`: a request with a model lights the model's vertices",
            ));
        }
        if compare {
            refuse(
                &[("candidate", self.candidate.is_some())],
                "a compare with a model reads the candidate from the model's COLOR_0",
            )
        } else {
            refuse(&self.compare_fields(), "only /v1/compare takes it")
        }
    }

    /// The vertices and the candidate of a compare's JSON body.
    pub fn compare_form(&self) -> Result<(&Vertices, &CandidateColors), RequestError> {
        refuse(&self.model_fields(), "only a request with a model takes it")?;
        refuse(
            &[("terms", self.terms.is_some())],
            "a compare gives the breakdown of its worst vertices",
        )?;
        let vertices = self
            .vertices
            .as_ref()
            .ok_or_else(|| missing("", "vertices"))?;
        let candidate = self
            .candidate
            .as_ref()
            .ok_or_else(|| missing("", "candidate"))?;
        Ok((vertices, candidate))
    }

    fn model_fields(&self) -> [(&'static str, bool); 3] {
        [
            ("materials", self.materials.is_some()),
            ("color_space", self.color_space.is_some()),
            ("color_format", self.color_format.is_some()),
        ]
    }

    fn compare_fields(&self) -> [(&'static str, bool); 3] {
        [
            ("candidate", self.candidate.is_some()),
            ("worst", self.worst.is_some()),
            ("tolerance", self.tolerance.is_some()),
        ]
    }
}

/// A 400 at the first of `fields` present: a field of another form.
fn refuse(fields: &[(&str, bool)], why: &str) -> Result<(), RequestError> {
    match fields.iter().find(|(_, present)| *present) {
        Some((field, _)) => Err(RequestError::malformed(
            format!("/{field}"),
            format!("unknown field `{field}`: {why}"),
        )),
        None => Ok(()),
    }
}

/// The error of a field the schema requires, as serde words it.
pub fn missing(object: &str, field: &str) -> RequestError {
    RequestError::malformed(object, format!("missing field `{field}`"))
}

/// `POST /v1/render`: the JSON body, and the `request` part of a request
/// with a model. The JSON body must have `camera` (all of it), `materials`
/// and `objects` ([`RenderRequest::json_form`]); with a model, the camera
/// may come from the model and the objects are added to its triangles.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRequest {
    #[serde(default, deserialize_with = "present_object")]
    pub light_model: Option<LightModel>,
    /// Named materials, referred to by the objects (and, with a model, by a
    /// glTF material's name or `#<index>`).
    #[serde(default, deserialize_with = "present")]
    pub materials: Option<Materials>,
    /// The back material of every object when two-sided; absent, each
    /// object's own material lights its back too.
    #[serde(default, deserialize_with = "present_object")]
    pub back_material: Option<Material>,
    #[serde(default, deserialize_with = "present")]
    pub lights: Option<Lights>,
    #[serde(default, deserialize_with = "present_object")]
    pub camera: Option<Camera>,
    #[serde(default, deserialize_with = "present")]
    pub objects: Option<Capped<Object, MAX_OBJECTS>>,
    #[serde(default, deserialize_with = "present")]
    pub background: Option<Color>,
    #[serde(default, deserialize_with = "present")]
    pub shading: Option<ShadingMode>,
    #[serde(default, deserialize_with = "present")]
    pub samples: Option<Samples>,
    #[serde(default, deserialize_with = "present")]
    pub shadows: Option<bool>,
    #[serde(default, deserialize_with = "present")]
    pub precision: Option<PrecisionRequest>,
    #[serde(default, deserialize_with = "present_object")]
    pub region: Option<Region>,
    #[serde(default, deserialize_with = "present_pixels")]
    pub probes: Option<Vec<[u32; 2]>>,
    #[serde(default, deserialize_with = "present")]
    pub encoding: Option<Encoding>,
    /// An image compare's number of worst pixels to report.
    #[serde(default, deserialize_with = "present")]
    pub worst: Option<usize>,
    /// An image compare's largest error that a deviation may leave and
    /// explain.
    #[serde(default, deserialize_with = "present")]
    pub tolerance: Option<f64>,
}

impl RenderRequest {
    /// The camera of the JSON body, which has it, its materials and its
    /// objects, and none of the fields of a compare.
    pub fn json_form(&self) -> Result<&Camera, RequestError> {
        self.model_form()?;
        self.complete_form()
    }

    /// Checks the `request` part of a render with a model: none of the
    /// fields of a compare.
    pub fn model_form(&self) -> Result<(), RequestError> {
        refuse(
            &[
                ("worst", self.worst.is_some()),
                ("tolerance", self.tolerance.is_some()),
            ],
            "only /v1/compare takes it",
        )
    }

    /// The camera of an image compare's `request` part: the JSON body of a
    /// render, with `worst` and `tolerance` and without `probes` (the
    /// compare probes its worst pixels).
    pub fn compare_form(&self) -> Result<&Camera, RequestError> {
        refuse(
            &[("probes", self.probes.is_some())],
            "a compare gives the probes of its worst pixels",
        )?;
        self.complete_form()
    }

    /// The camera of a body that has it, its materials and its objects.
    fn complete_form(&self) -> Result<&Camera, RequestError> {
        let camera = self.camera.as_ref().ok_or_else(|| missing("", "camera"))?;
        camera.complete()?;
        if self.materials.is_none() {
            return Err(missing("", "materials"));
        }
        if self.objects.is_none() {
            return Err(missing("", "objects"));
        }
        Ok(camera)
    }
}

/// The pinhole camera. The JSON body gives every field; with a model, the
/// view (`eye`, `target`, `up`, `fov_y`) may come from the model's first
/// camera, and the size from its aspect ratio.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    #[serde(default, deserialize_with = "present")]
    pub eye: Option<Vec3>,
    #[serde(default, deserialize_with = "present")]
    pub target: Option<Vec3>,
    #[serde(default, deserialize_with = "present")]
    pub up: Option<Vec3>,
    #[serde(default, deserialize_with = "present")]
    pub fov_y: Option<f64>,
    #[serde(default, deserialize_with = "present_integer")]
    pub width: Option<u32>,
    #[serde(default, deserialize_with = "present_integer")]
    pub height: Option<u32>,
}

/// A camera's every field: eye, target, up, fov_y, width, height.
pub type CameraFields = (Vec3, Vec3, Vec3, f64, u32, u32);

impl Camera {
    /// Every field, or the error of the first one missing.
    pub fn complete(&self) -> Result<CameraFields, RequestError> {
        let required = |field: &str| missing("/camera", field);
        Ok((
            self.eye.ok_or_else(|| required("eye"))?,
            self.target.ok_or_else(|| required("target"))?,
            self.up.ok_or_else(|| required("up"))?,
            self.fov_y.ok_or_else(|| required("fov_y"))?,
            self.width.ok_or_else(|| required("width"))?,
            self.height.ok_or_else(|| required("height"))?,
        ))
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    #[serde(default, deserialize_with = "present_object")]
    pub sphere: Option<Sphere>,
    #[serde(default, deserialize_with = "present_object")]
    pub plane: Option<Plane>,
    #[serde(default, deserialize_with = "present_object")]
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
    #[serde(default, deserialize_with = "present")]
    pub normals: Option<Vec<Vec3>>,
    #[serde(deserialize_with = "integers")]
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
    #[serde(deserialize_with = "integer")]
    pub x: u32,
    #[serde(deserialize_with = "integer")]
    pub y: u32,
    #[serde(deserialize_with = "integer")]
    pub width: u32,
    #[serde(deserialize_with = "integer")]
    pub height: u32,
}
